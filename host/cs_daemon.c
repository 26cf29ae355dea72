/* cs_daemon: a single-threaded server (poll on the listening socket, the clients and the running
 * job's progress pipe). A job runs in a child process that inherits the open port (or opens its
 * link itself) and runs the job through cs_joblink: SIGUSR1 holds it (pause), SIGUSR2 resumes
 * it, SIGTERM cancels it (hold, then abort). The child writes the link's progress lines (and
 * "stream: device held ..." once a pause's hold is confirmed) and a final RESULT line to a
 * pipe. */
#include "cs_daemon.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "cs_cmd.h"
#include "cs_conv.h"
#include "cs_dsock.h"
#include "cs_err_text.h"
#include "cs_joblink.h"
#include "cs_jobplan.h"
#include "cs_machine_ini.h"
#include "cs_motion.h"
#include "cs_serial.h"
#include "cs_stream.h"
#include "cs_stream_pen.h"
#include "cs_trace.h"

#define MAX_CLIENTS 16
/* A client that has not sent its whole request line this long after connecting is closed: a
 * real client sends it at once (cs_daemon_request), so only a silent or stalled one waits. */
#define CLIENT_IDLE_MS 5000

typedef enum { JOB_QUEUED, JOB_RUNNING, JOB_DONE, JOB_FAILED, JOB_CANCELLED } job_state_t;

static const char *const state_names[] = {"queued", "running", "done", "failed", "cancelled"};

typedef struct {
    unsigned id;
    char *path;
    cs_stream_job_t job; /* freed once the job ended */
    cs_jobplan_t jp;     /* the job as read at submit (its path; the file is never read again) */
    bool curves;         /* what SUBMIT asked, to plan it again from the device's position */
    double tol_mm, feed;
    cs_jobopts_t in; /* the shared input and layout options SUBMIT gave */
    job_state_t state;
    size_t executed;
    size_t n;
    bool held;     /* the link confirmed the pause's hold (a "device held" line) */
    char end[200]; /* how it ended */
} djob_t;

typedef struct {
    int fd;
    char buf[CS_DAEMON_LINE_MAX];
    size_t len;
    struct timespec since; /* accepted at (CLOCK_MONOTONIC): idle clients are closed */
} client_t;

typedef struct {
    const cs_daemon_cfg_t *cfg;
    cs_machine_t m;
    cs_machine_pen_t pen; /* [pen]: G-code M3/M4/M5 as Z moves, as `stream` does */
    cs_joblink_t link;    /* a keep_open link (serial) is open while serving */
    djob_t *jobs;
    size_t njobs, cap;
    unsigned next_id;
    bool paused;
    size_t running; /* index in jobs, or SIZE_MAX */
    pid_t child;
    int pipe_fd;
    char pbuf[512];
    size_t plen;
    bool cancel_running;
    bool have_pos;                      /* the device reported its position (last job) */
    int32_t dev_pos[CS_PROTO_AXES_MAX]; /* steps */
    client_t clients[MAX_CLIENTS];
    int listen_fd;
} daemon_t;

static volatile sig_atomic_t stop_serving;
static volatile sig_atomic_t child_interrupt, child_pause;

static void on_stop(int sig)
{
    (void)sig;
    stop_serving = 1;
}
static void on_child_cancel(int sig)
{
    (void)sig;
    if (child_interrupt < 1)
        child_interrupt = 1;
}
static void on_child_pause(int sig)
{
    child_pause = sig == SIGUSR1;
}

static void dlog(daemon_t *d, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void dlog(daemon_t *d, const char *fmt, ...)
{
    if (d->cfg->log == NULL)
        return;
    va_list ap;
    va_start(ap, fmt);
    fputs("serve: ", d->cfg->log);
    vfprintf(d->cfg->log, fmt, ap);
    fputc('\n', d->cfg->log);
    fflush(d->cfg->log);
    va_end(ap);
}

char *cs_daemon_default_socket(char *buf, size_t cap)
{
    return cs_dsock_default(buf, cap);
}

static int unix_addr(struct sockaddr_un *a, const char *path)
{
    memset(a, 0, sizeof *a);
    a->sun_family = AF_UNIX;
    if (strlen(path) >= sizeof a->sun_path) {
        errno = ENAMETOOLONG;
        return -1;
    }
    memcpy(a->sun_path, path, strlen(path) + 1);
    return 0;
}

int cs_daemon_request(const char *socket_path, const char *request, FILE *out, char *err,
                      size_t errcap)
{
    struct sockaddr_un a;
    int fd = socket(AF_UNIX, SOCK_STREAM, 0);
    if (fd < 0 || unix_addr(&a, socket_path) != 0 ||
        connect(fd, (struct sockaddr *)&a, sizeof a) != 0) {
        snprintf(err, errcap, "no daemon answers on %s (%s); start one with `curvestep serve`",
                 socket_path, strerror(errno));
        if (fd >= 0)
            close(fd);
        return -1;
    }
    uid_t peer;
    if (!cs_dsock_peer_uid(fd, &peer) || !cs_dsock_uid_trusted(peer)) {
        snprintf(err, errcap,
                 "%s: the process answering there is not run by this user or root: "
                 "nothing sent (docs/streaming.md)",
                 socket_path);
        close(fd);
        return -1;
    }
    size_t len = strlen(request);
    char *line = malloc(len + 2);
    if (line == NULL) {
        close(fd);
        snprintf(err, errcap, "out of memory");
        return -1;
    }
    memcpy(line, request, len);
    line[len] = '\n';
    size_t off = 0;
    int werr = 0;
    while (off < len + 1 && werr == 0) {
        ssize_t w = send(fd, line + off, len + 1 - off, MSG_NOSIGNAL);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            werr = w < 0 ? errno : EPIPE; /* the daemon may have said why: read it below */
        else
            off += (size_t)w;
    }
    free(line);
    shutdown(fd, SHUT_WR);
    /* a daemon that never answers (hung, or not ours) must not hang the client: a deadline far
     * above the longest submit (planning a job at the input size limit) */
    struct timeval tv = {CS_DAEMON_REPLY_S, 0};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    char buf[4096];
    int rc = -1;
    bool first = true;
    for (;;) {
        ssize_t r = read(fd, buf, sizeof buf);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            break;
        if (first) {
            rc = strncmp(buf, "OK", 2) == 0 ? 0 : 1;
            first = false;
        }
        fwrite(buf, 1, (size_t)r, out);
    }
    close(fd);
    if (first && werr != 0) {
        snprintf(err, errcap, "%s: write failed (%s)", socket_path, strerror(werr));
        return -1;
    }
    if (first) {
        snprintf(err, errcap, "%s: the daemon closed the connection without a reply", socket_path);
        return -1;
    }
    return rc;
}

/* ---- the job queue ---- */

static void job_release(djob_t *j)
{
    cs_stream_job_free(&j->job);
    cs_jobplan_free(&j->jp);
}

/* jp->diag (or e's sentence) as one line in err. */
static void diag_text(const cs_jobplan_t *jp, const char *file, cs_err_t e, char *err,
                      size_t errcap)
{
    char *s = NULL;
    size_t slen = 0;
    FILE *f = open_memstream(&s, &slen);
    if (f != NULL) {
        cs_path_diag_print(f, &jp->diag);
        fclose(f);
    }
    if (s != NULL) {
        while (slen > 0 && (s[slen - 1] == '\n'))
            s[--slen] = '\0';
        for (size_t i = 0; i < slen; i++)
            if (s[i] == '\n')
                s[i] = ' ';
        snprintf(err, errcap, "%s", slen ? s : cs_err_text(e));
    } else {
        snprintf(err, errcap, "%s: %s", file, cs_err_text(e));
    }
    free(s);
}

/* Reads the job file once (a regular file only: a FIFO or a device would block the daemon) into
 * jp->path, laid out, ordered and pen-lifted by in (the SUBMIT words) with merge distance tol_mm;
 * on error a "file:line:col: reason" in err. */
static bool read_job(daemon_t *d, const char *file, const cs_jobopts_t *in, const char *font,
                     double tol_mm, cs_jobplan_t *jp, char *err, size_t errcap)
{
    cs_jobplan_init(jp);
    jp->font_file = font; /* NULL: the shipped font */
    jp->regular_only = true;
    jp->max_bytes = d->cfg->max_input_bytes;
    cs_pos_t tol;
    if (!cs_jobplan_tol(&d->m, tol_mm, &tol)) {
        snprintf(err, errcap, "tol %g mm is outside the accepted range", tol_mm);
        return false;
    }
    cs_err_t e = cs_jobplan_read_opts(jp, file, &d->pen, in);
    if (e == CS_OK) /* layout, merge and sort (the SUBMIT words), then the pen lifts */
        e = cs_jobplan_prepare(jp, "serve", in, &d->m, &d->pen, tol, d->cfg->log);
    if (e == CS_OK)
        return true;
    diag_text(jp, file, e, err, errcap);
    cs_jobplan_free(jp);
    return false;
}

/* Plans jp's path (read at submit, never re-read) whole as `curvestep stream` does, from
 * start_steps (NULL: the origin), into *job; on error a "file:line:col: reason" in err. */
static bool plan_job(daemon_t *d, cs_jobplan_t *jp, const char *file, bool curves, double tol_mm,
                     double feed, const int32_t *start_steps, cs_stream_job_t *job, char *err,
                     size_t errcap)
{
    cs_pos_t tol;
    if (!cs_jobplan_tol(&d->m, tol_mm, &tol)) {
        snprintf(err, errcap, "tol %g mm is outside the accepted range", tol_mm);
        return false;
    }
    cs_stream_job_init(job, curves ? CS_STREAM_CURVES : CS_STREAM_SEGMENTS);
    /* step segments are relative: plan them from where the device is (the position the
     * previous job left it at), rounded to the nearest LSB (far below half a step) */
    cs_pos_t start[CS_AXES] = {0};
    if (start_steps != NULL)
        for (unsigned i = 0; i < d->m.n_axes && i < CS_PROTO_AXES_MAX; i++)
            start[i] = (cs_pos_t)llround((double)start_steps[i] * 65536.0 * 65536.0 /
                                         (double)d->m.axis[i].steps_per_mm);
    int32_t feed_q = cs_motion_speed(feed);
    if (jp->have_mo) { /* planned before (at submit): plan the same path again */
        cs_motion_free(&jp->mo);
        jp->have_mo = false;
    }
    cs_err_t e = cs_jobplan_plan(jp, file, &d->m, start_steps != NULL ? start : NULL, tol,
                                 CS_TRACE_DEFAULT, feed_q);
    if (e == CS_OK && curves && !d->link.ops->curves) {
        snprintf(err, errcap, "mode=curves: the %s link runs the step segments planned here",
                 d->link.ops->kind);
        cs_stream_job_free(job);
        return false;
    }
    if (e == CS_OK)
        e = cs_jobplan_linkable(jp, file, d->link.ops->pens, curves);
    if (e == CS_OK)
        e = curves ? cs_stream_job_add_path_pen(
                         job, &jp->path, feed_q > 0 ? feed_q : d->m.default_feed, tol, &jp->pen,
                         d->m.tick_hz, &(cs_vec3_t){start[0], start[1], start[2]}, &jp->diag)
                   : cs_stream_job_add_motion(job, &jp->mo.segs);
    if (jp->have_mo) { /* the job holds its own copy of the segments */
        cs_motion_free(&jp->mo);
        jp->have_mo = false;
    }
    if (e == CS_OK)
        return true;
    cs_stream_job_free(job);
    diag_text(jp, file, e, err, errcap);
    return false;
}

/* "SUBMIT [mode=segments|curves] [tol=MM] [feed=MM/S] [font=/ABS/FONT] [shared option words]
 * /ABS/PATH"
 * (the shared words: cs_jobopts_word, e.g. lenient, dialect=grbl, fit, rotate=90) */
static void req_submit(daemon_t *d, char *args, FILE *out)
{
    bool curves = false;
    double tol = 0, feed = 0;
    const char *font = NULL;
    cs_jobopts_t in;
    cs_jobopts_init(&in);
    while (*args == ' ')
        args++;
    while (*args != '\0' && *args != '/') {
        char *sp = strchr(args, ' ');
        if (sp == NULL) {
            fprintf(out, "ERR no absolute job path\n");
            return;
        }
        *sp = '\0';
        char *end = NULL;
        if (strcmp(args, "mode=curves") == 0)
            curves = true;
        else if (strcmp(args, "mode=segments") == 0)
            curves = false;
        else if (strncmp(args, "tol=", 4) == 0 &&
                 ((tol = strtod(args + 4, &end)), *end == '\0' && tol > 0))
            ;
        else if (strncmp(args, "feed=", 5) == 0 &&
                 ((feed = strtod(args + 5, &end)), *end == '\0' && feed > 0 && feed < 32768))
            ;
        else if (strncmp(args, "font=/", 6) == 0)
            font = args + 5; /* within args, which outlives the read */
        else if (cs_jobopts_word(args, &in))
            ;
        else {
            fprintf(out, "ERR bad option %s\n", args);
            return;
        }
        args = sp + 1;
        while (*args == ' ')
            args++;
    }
    if (*args != '/') {
        fprintf(out, "ERR no absolute job path\n");
        return;
    }
    char err[600];
    cs_stream_job_t job;
    cs_jobplan_t jp;
    if (!read_job(d, args, &in, font, tol, &jp, err, sizeof err)) {
        fprintf(out, "ERR %s\n", err);
        dlog(d, "refused %s: %s", args, err);
        return;
    }
    if (!plan_job(d, &jp, args, curves, tol, feed, NULL, &job, err, sizeof err)) {
        fprintf(out, "ERR %s\n", err);
        dlog(d, "refused %s: %s", args, err);
        cs_jobplan_free(&jp);
        return;
    }
    if (d->njobs == d->cap) {
        size_t cap = d->cap ? 2 * d->cap : 16;
        djob_t *v = realloc(d->jobs, cap * sizeof *v);
        if (v == NULL) {
            cs_stream_job_free(&job);
            cs_jobplan_free(&jp);
            fprintf(out, "ERR out of memory\n");
            return;
        }
        d->jobs = v;
        d->cap = cap;
    }
    djob_t *j = &d->jobs[d->njobs];
    memset(j, 0, sizeof *j);
    j->path = strdup(args);
    if (j->path == NULL) {
        cs_stream_job_free(&job);
        cs_jobplan_free(&jp);
        fprintf(out, "ERR out of memory\n");
        return;
    }
    j->id = ++d->next_id;
    j->job = job;
    j->jp = jp;
    j->n = job.n;
    j->curves = curves;
    j->tol_mm = tol;
    j->feed = feed;
    j->in = in;
    j->state = JOB_QUEUED;
    d->njobs++;
    const char *what = curves ? "curves" : "segments";
    fprintf(out, "OK job %u queued: %s: %zu %s\n", j->id, j->path, j->n, what);
    dlog(d, "job %u queued: %s: %zu %s", j->id, j->path, j->n, what);
}

static void req_status(daemon_t *d, FILE *out)
{
    fprintf(out, "OK device %s, queue %s\n", d->link.name, d->paused ? "paused" : "running");
    for (size_t i = 0; i < d->njobs; i++) {
        const djob_t *j = &d->jobs[i];
        const char *what = j->job.mode == CS_STREAM_CURVES ? "curves" : "segments";
        fprintf(out, "job %u %s: %s: %zu/%zu %s executed", j->id, state_names[j->state], j->path,
                j->executed, j->n, what);
        if (j->state == JOB_RUNNING && d->paused)
            fprintf(out, j->held ? " (held)" : " (holding)");
        if (j->end[0] != '\0')
            fprintf(out, " (%s)", j->end);
        fputc('\n', out);
    }
}

static void req_cancel(daemon_t *d, const char *arg, FILE *out)
{
    unsigned id = 0;
    if (*arg != '\0') {
        char *end;
        unsigned long v = strtoul(arg, &end, 10);
        if (*end != '\0' || v == 0 || v > UINT_MAX) {
            fprintf(out, "ERR CANCEL wants a job number\n");
            return;
        }
        id = (unsigned)v;
    } else if (d->running != SIZE_MAX) {
        id = d->jobs[d->running].id;
    } else {
        fprintf(out, "ERR no job is running\n");
        return;
    }
    for (size_t i = 0; i < d->njobs; i++) {
        djob_t *j = &d->jobs[i];
        if (j->id != id)
            continue;
        if (j->state == JOB_QUEUED) {
            j->state = JOB_CANCELLED;
            snprintf(j->end, sizeof j->end, "cancelled before it started");
            job_release(j);
            fprintf(out, "OK job %u cancelled\n", id);
            dlog(d, "job %u cancelled (queued)", id);
        } else if (j->state == JOB_RUNNING) {
            d->cancel_running = true;
            kill(d->child, SIGTERM);
            fprintf(out, "OK job %u cancelling (hold, then abort)\n", id);
            dlog(d, "job %u cancelling", id);
        } else {
            fprintf(out, "ERR job %u is %s\n", id, state_names[j->state]);
        }
        return;
    }
    fprintf(out, "ERR no job %u\n", id);
}

static void handle_request(daemon_t *d, char *line, FILE *out)
{
    size_t len = strlen(line);
    while (len > 0 && (line[len - 1] == '\r' || line[len - 1] == ' '))
        line[--len] = '\0';
    if (strncmp(line, "SUBMIT ", 7) == 0) {
        req_submit(d, line + 7, out);
    } else if (strcmp(line, "STATUS") == 0) {
        req_status(d, out);
    } else if (strcmp(line, "PAUSE") == 0) {
        d->paused = true;
        if (d->running != SIZE_MAX)
            kill(d->child, SIGUSR1);
        fprintf(out, "OK paused%s\n", d->running != SIZE_MAX ? " (device held)" : "");
        dlog(d, "paused");
    } else if (strcmp(line, "RESUME") == 0) {
        d->paused = false;
        if (d->running != SIZE_MAX) {
            kill(d->child, SIGUSR2);
            d->jobs[d->running].held = false;
        }
        fprintf(out, "OK resumed\n");
        dlog(d, "resumed");
    } else if (strcmp(line, "CANCEL") == 0 || strncmp(line, "CANCEL ", 7) == 0) {
        req_cancel(d, line[6] ? line + 7 : "", out);
    } else {
        fprintf(out, "ERR unknown request (SUBMIT, STATUS, PAUSE, RESUME, CANCEL)\n");
    }
}

/* ---- running a job ---- */

/* The job's process: the signals as the link's controls, the link opened (unless the daemon
 * keeps it open), the job run from the device's position, the RESULT line. Never returns. */
static void child_run(daemon_t *d, djob_t *j, int wfd)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_child_cancel;
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    sa.sa_handler = on_child_pause;
    sigaction(SIGUSR1, &sa, NULL);
    sigaction(SIGUSR2, &sa, NULL);
    child_pause = d->paused;
    sigset_t set;
    sigemptyset(&set);
    sigprocmask(SIG_SETMASK, &set, NULL);
    FILE *f = fdopen(wfd, "w");
    if (f == NULL)
        _exit(3);
    cs_stream_result_t r;
    memset(&r, 0, sizeof r);
    cs_joblink_job_t jj = {
        .m = &d->m, .job = &j->job, .start_pos = d->have_pos ? d->dev_pos : NULL};
    cs_joblink_ctl_t c = {&child_interrupt, &child_pause, f, false};
    cs_err_t e = CS_OK;
    int orc = d->link.ops->keep_open ? CS_EXIT_OK : cs_joblink_open(&d->link, &jj);
    if (orc != CS_EXIT_OK) { /* the device is not there: as a link that never answered */
        r.outcome = CS_STREAM_NO_DEVICE;
        r.dev_state = 0xFF;
        snprintf(r.why, sizeof r.why, "%.159s", d->link.why);
    } else {
        e = cs_joblink_run(&d->link, &jj, &c, &r);
    }
    if (!d->link.ops->keep_open)
        cs_joblink_close(&d->link, 0);
    if (e != CS_OK)
        fprintf(f, "RESULT -1 %zu %s\n", r.executed, cs_err_text(e));
    else
        fprintf(f, "RESULT %d %zu %d %ld %ld %ld %ld %s%s%s%s\n", (int)r.outcome, r.executed,
                r.dev_state != 0xFF, (long)r.dev_pos[0], (long)r.dev_pos[1], (long)r.dev_pos[2],
                (long)r.dev_pos[3], cs_stream_result_text(&r), r.why[0] ? " (" : "", r.why,
                r.why[0] ? ")" : "");
    fflush(f);
    _exit(0);
}

static void start_next(daemon_t *d)
{
    if (d->running != SIZE_MAX || d->paused || stop_serving)
        return;
    size_t i = 0;
    while (i < d->njobs && d->jobs[i].state != JOB_QUEUED)
        i++;
    if (i == d->njobs)
        return;
    djob_t *j = &d->jobs[i];
    bool moved = false;
    for (int k = 0; k < CS_PROTO_AXES_MAX; k++)
        moved = moved || (d->have_pos && d->dev_pos[k] != 0);
    if (!j->curves && moved) {
        char err[600];
        cs_stream_job_t job;
        if (!plan_job(d, &j->jp, j->path, false, j->tol_mm, j->feed, d->dev_pos, &job, err,
                      sizeof err)) {
            j->state = JOB_FAILED;
            snprintf(j->end, sizeof j->end, "planning from the device's position: %.160s", err);
            dlog(d, "job %u failed: %s", j->id, j->end);
            job_release(j);
            return;
        }
        cs_stream_job_free(&j->job);
        j->job = job;
        j->n = job.n;
    }
    int p[2];
    if (pipe(p) != 0) {
        j->state = JOB_FAILED;
        snprintf(j->end, sizeof j->end, "pipe: %s", strerror(errno));
        job_release(j);
        return;
    }
    sigset_t set, old;
    sigemptyset(&set);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGUSR1);
    sigaddset(&set, SIGUSR2);
    sigprocmask(SIG_BLOCK, &set, &old);
    fflush(NULL);
    pid_t pid = fork();
    if (pid == 0) {
        close(p[0]);
        close(d->listen_fd);
        for (int k = 0; k < MAX_CLIENTS; k++)
            if (d->clients[k].fd >= 0)
                close(d->clients[k].fd);
        child_run(d, j, p[1]);
    }
    sigprocmask(SIG_SETMASK, &old, NULL);
    close(p[1]);
    if (pid < 0) {
        close(p[0]);
        j->state = JOB_FAILED;
        snprintf(j->end, sizeof j->end, "fork: %s", strerror(errno));
        job_release(j);
        return;
    }
    fcntl(p[0], F_SETFL, fcntl(p[0], F_GETFL) | O_NONBLOCK);
    d->child = pid;
    d->pipe_fd = p[0];
    d->plen = 0;
    d->running = i;
    d->cancel_running = false;
    j->state = JOB_RUNNING;
    dlog(d, "job %u started: %s", j->id, j->path);
}

static void child_line(daemon_t *d, const char *line)
{
    djob_t *j = &d->jobs[d->running];
    size_t ex, n;
    int oc, have;
    long p[4];
    int pos = 0;
    if (sscanf(line, "stream: %zu/%zu", &ex, &n) == 2) {
        j->executed = ex;
    } else if (sscanf(line, "stream: device held at %zu of %zu", &ex, &n) == 2) {
        j->executed = ex;
        j->held = d->paused;
    } else if (sscanf(line, "RESULT %d %zu %d %ld %ld %ld %ld %n", &oc, &ex, &have, &p[0], &p[1],
                      &p[2], &p[3], &pos) == 7) {
        j->executed = ex;
        if (have) {
            d->have_pos = true;
            for (int i = 0; i < 4; i++)
                d->dev_pos[i] = (int32_t)p[i];
        }
        snprintf(j->end, sizeof j->end, "%s", line + pos);
        j->state = oc == CS_STREAM_DONE                               ? JOB_DONE
                   : oc == CS_STREAM_INTERRUPTED && d->cancel_running ? JOB_CANCELLED
                                                                      : JOB_FAILED;
    }
}

/* Reads the child's pipe; at its end, reaps the child and closes the job. */
static void child_pump(daemon_t *d)
{
    for (;;) {
        ssize_t r = read(d->pipe_fd, d->pbuf + d->plen, sizeof d->pbuf - 1 - d->plen);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0 && errno == EAGAIN)
            return;
        if (r <= 0)
            break;
        d->plen += (size_t)r;
        d->pbuf[d->plen] = '\0';
        char *nl;
        while ((nl = strchr(d->pbuf, '\n')) != NULL) {
            *nl = '\0';
            child_line(d, d->pbuf);
            size_t used = (size_t)(nl + 1 - d->pbuf);
            memmove(d->pbuf, nl + 1, d->plen - used + 1);
            d->plen -= used;
        }
        if (d->plen == sizeof d->pbuf - 1)
            d->plen = 0; /* an overlong line: dropped */
    }
    close(d->pipe_fd);
    d->pipe_fd = -1;
    int st = 0;
    while (waitpid(d->child, &st, 0) < 0 && errno == EINTR)
        ;
    djob_t *j = &d->jobs[d->running];
    if (j->state == JOB_RUNNING) {
        j->state = JOB_FAILED;
        snprintf(j->end, sizeof j->end, "the streaming process died (status %d)", st);
    }
    dlog(d, "job %u %s: %zu/%zu executed (%s)", j->id, state_names[j->state], j->executed, j->n,
         j->end);
    job_release(j);
    d->running = SIZE_MAX;
    d->child = 0;
}

/* ---- the server ---- */

static int open_socket(const char *path)
{
    struct sockaddr_un a;
    char err[600];
    if (unix_addr(&a, path) != 0) {
        fprintf(stderr, "curvestep serve: %s: socket path too long\n", path);
        return -1;
    }
    if (!cs_dsock_dir_ok(path, err, sizeof err) || !cs_dsock_clear_stale(path, err, sizeof err)) {
        fprintf(stderr, "curvestep serve: %s\n", err);
        return -1;
    }
    int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    mode_t old = umask(077);
    int rc = fd < 0 ? -1 : bind(fd, (struct sockaddr *)&a, sizeof a);
    umask(old);
    if (rc != 0 || chmod(path, 0600) != 0 || listen(fd, 8) != 0) {
        fprintf(stderr, "curvestep serve: %s: %s\n", path, strerror(errno));
        if (fd >= 0)
            close(fd);
        return -1;
    }
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
    return fd;
}

static long long now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (long long)t.tv_sec * 1000 + t.tv_nsec / 1000000;
}

static long long client_age_ms(const client_t *c, long long now)
{
    return now - ((long long)c->since.tv_sec * 1000 + c->since.tv_nsec / 1000000);
}

static void client_close(client_t *c)
{
    close(c->fd);
    c->fd = -1;
    c->len = 0;
}

static void client_reply(daemon_t *d, client_t *c)
{
    char *s = NULL;
    size_t slen = 0;
    FILE *out = open_memstream(&s, &slen);
    if (out != NULL) {
        c->buf[c->len] = '\0';
        handle_request(d, c->buf, out);
        fclose(out);
        /* short replies to a local peer: a blocking send with a bound on the time */
        int fl = fcntl(c->fd, F_GETFL);
        fcntl(c->fd, F_SETFL, fl & ~O_NONBLOCK);
        struct timeval tv = {1, 0};
        setsockopt(c->fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
        size_t off = 0;
        while (off < slen) {
            ssize_t w = send(c->fd, s + off, slen - off, MSG_NOSIGNAL);
            if (w < 0 && errno == EINTR)
                continue;
            if (w <= 0)
                break;
            off += (size_t)w;
        }
    }
    free(s);
    client_close(c);
}

static void client_read(daemon_t *d, client_t *c)
{
    ssize_t r = read(c->fd, c->buf + c->len, sizeof c->buf - 1 - c->len);
    if (r < 0 && (errno == EINTR || errno == EAGAIN))
        return;
    if (r <= 0) {
        if (c->len > 0)
            client_reply(d, c); /* a last line without a newline */
        else
            client_close(c);
        return;
    }
    c->len += (size_t)r;
    char *nl = memchr(c->buf, '\n', c->len);
    if (nl != NULL) {
        c->len = (size_t)(nl - c->buf);
        client_reply(d, c);
    } else if (c->len == sizeof c->buf - 1) {
        static const char msg[] = "ERR request line too long\n";
        ssize_t w = send(c->fd, msg, sizeof msg - 1, MSG_NOSIGNAL);
        (void)w;
        client_close(c);
    }
}

/* Sends a one-line refusal (best effort, never blocking) and closes fd. */
static void refuse(int fd, const char *msg)
{
    ssize_t w = send(fd, msg, strlen(msg), MSG_NOSIGNAL | MSG_DONTWAIT);
    (void)w;
    close(fd);
}

/* Accepts one connection: only from this user or root (SO_PEERCRED). When every slot is taken,
 * the oldest client gets one last read (its request, if it came, is answered) and is closed:
 * silent clients can never lock out status, pause or cancel. */
static void accept_client(daemon_t *d)
{
    int cfd = accept(d->listen_fd, NULL, NULL);
    if (cfd < 0)
        return;
    uid_t uid;
    if (!cs_dsock_peer_uid(cfd, &uid) || !cs_dsock_uid_trusted(uid)) {
        dlog(d, "refused a client of uid %ld (not this user or root)", (long)uid);
        refuse(cfd, "ERR permission denied: not this daemon's user\n");
        return;
    }
    int k = 0;
    while (k < MAX_CLIENTS && d->clients[k].fd >= 0)
        k++;
    if (k == MAX_CLIENTS) {
        long long now = now_ms();
        k = 0;
        for (int q = 1; q < MAX_CLIENTS; q++)
            if (client_age_ms(&d->clients[q], now) > client_age_ms(&d->clients[k], now))
                k = q;
        client_read(d, &d->clients[k]);
        if (d->clients[k].fd >= 0) {
            refuse(d->clients[k].fd, "ERR too many clients: the oldest silent one is closed\n");
            d->clients[k].fd = -1;
            d->clients[k].len = 0;
        }
    }
    fcntl(cfd, F_SETFL, fcntl(cfd, F_GETFL) | O_NONBLOCK);
    d->clients[k].fd = cfd;
    d->clients[k].len = 0;
    clock_gettime(CLOCK_MONOTONIC, &d->clients[k].since);
}

/* Closes the clients that sent no whole request within CLIENT_IDLE_MS. */
static void reap_idle(daemon_t *d)
{
    long long now = now_ms();
    for (int k = 0; k < MAX_CLIENTS; k++)
        if (d->clients[k].fd >= 0 && client_age_ms(&d->clients[k], now) > CLIENT_IDLE_MS) {
            refuse(d->clients[k].fd, "ERR idle too long: no request line\n");
            d->clients[k].fd = -1;
            d->clients[k].len = 0;
        }
}

/* The machine, the port and the socket, in that order. Returns 0, or the exit status after a
 * message on stderr (what was opened is closed again). */
static int serve_setup(daemon_t *d)
{
    const cs_daemon_cfg_t *cfg = d->cfg;
    char err[512];
    if (cs_machine_ini_open("curvestep serve", cfg->machine_file, &d->m, &d->pen, err,
                            sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    if (cs_joblink_select(&d->link, &cfg->link) != CS_EXIT_OK) {
        fprintf(stderr, "curvestep serve: %s\n", d->link.why);
        return CS_EXIT_USAGE;
    }
    d->link.cfg.machine_file = cfg->machine_file;
    int orc = d->link.ops->check ? d->link.ops->check(&d->link, &d->m) : CS_EXIT_OK;
    if (orc == CS_EXIT_OK && d->link.ops->keep_open)
        orc = cs_joblink_open(&d->link, NULL);
    if (orc != CS_EXIT_OK) { /* "file:line: reason" as it is */
        fprintf(stderr, "%s%s\n", orc == CS_EXIT_INPUT ? "" : "curvestep serve: ", d->link.why);
        return orc;
    }
    d->listen_fd = open_socket(cfg->socket_path);
    if (d->listen_fd < 0) {
        if (d->link.ops->keep_open)
            cs_joblink_close(&d->link, 0);
        return 3;
    }
    return 0;
}

int cs_daemon_serve(const cs_daemon_cfg_t *cfg)
{
    daemon_t *d = calloc(1, sizeof *d);
    if (d == NULL)
        return 3;
    d->cfg = cfg;
    d->running = SIZE_MAX;
    d->pipe_fd = -1;
    for (int k = 0; k < MAX_CLIENTS; k++)
        d->clients[k].fd = -1;
    int rc = serve_setup(d);
    if (rc != 0) {
        free(d);
        return rc;
    }
    int lfd = d->listen_fd;
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop;
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);
    stop_serving = 0;
    dlog(d, "serving %s on %s", d->link.name, cfg->socket_path);
    bool told_child = false;
    while (!(stop_serving && d->running == SIZE_MAX)) {
        if (stop_serving && d->running != SIZE_MAX && !told_child) {
            d->cancel_running = true;
            kill(d->child, SIGTERM);
            told_child = true;
        }
        start_next(d);
        struct pollfd pf[2 + MAX_CLIENTS];
        int map[2 + MAX_CLIENTS];
        nfds_t n = 0;
        if (!stop_serving) {
            pf[n] = (struct pollfd){.fd = lfd, .events = POLLIN};
            map[n++] = -1;
        }
        if (d->pipe_fd >= 0) {
            pf[n] = (struct pollfd){.fd = d->pipe_fd, .events = POLLIN};
            map[n++] = -2;
        }
        for (int k = 0; k < MAX_CLIENTS; k++)
            if (d->clients[k].fd >= 0) {
                pf[n] = (struct pollfd){.fd = d->clients[k].fd, .events = POLLIN};
                map[n++] = k;
            }
        int pr = poll(pf, n, 200);
        reap_idle(d);
        if (pr < 0 && errno != EINTR) {
            fprintf(stderr, "curvestep serve: poll: %s\n", strerror(errno));
            rc = 3;
            break;
        }
        if (pr <= 0)
            continue;
        for (nfds_t i = 0; i < n; i++) {
            if (pf[i].revents == 0)
                continue;
            if (map[i] == -1) {
                accept_client(d);
            } else if (map[i] == -2) {
                if (d->pipe_fd >= 0)
                    child_pump(d);
            } else if (d->clients[map[i]].fd >= 0) {
                client_read(d, &d->clients[map[i]]);
            }
        }
    }
    if (d->running != SIZE_MAX) { /* poll failed: do not leave the child behind */
        kill(d->child, SIGTERM);
        while (d->pipe_fd >= 0) {
            child_pump(d);
            if (d->pipe_fd >= 0)
                usleep(10000);
        }
    }
    dlog(d, "stopped");
    for (int k = 0; k < MAX_CLIENTS; k++)
        if (d->clients[k].fd >= 0)
            client_close(&d->clients[k]);
    close(lfd);
    unlink(cfg->socket_path);
    if (d->link.ops->keep_open)
        cs_joblink_close(&d->link, 0);
    for (size_t i = 0; i < d->njobs; i++) {
        if (d->jobs[i].state == JOB_QUEUED)
            job_release(&d->jobs[i]);
        free(d->jobs[i].path);
    }
    free(d->jobs);
    free(d);
    return rc;
}
