/* Tests of cs_daemon: the client's error when no daemon answers (it names the socket), and the
 * server's request protocol on a daemon run in a child process over a pseudo-terminal with no
 * device behind it (the queue is paused first, so no job starts): the socket's mode, STATUS,
 * SUBMIT of a good file (queued, sized as the planner sizes it) and of a bad one (refused with
 * file:line:col), CANCEL of a queued job, unknown requests, and a clean stop on SIGTERM; and a
 * machine file with [pen] mode = z: a G-code job's M3/M5 become Z moves in the daemon's plan as
 * in `curvestep plan` / `stream` (it is sized like that plan, not like the plan without pen). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "cs_daemon.h"
#include "cs_jobopts.h"
#include "cs_jobplan.h"
#include "cs_machine_ini.h"
#include "cs_motion.h"
#include "cs_serial.h"
#include "cs_trace.h"

/* Sends one request; returns the client's status and the reply in buf. */
/* Waits for the daemon's socket to appear: an event with a deadline in seconds (60, generous
 * for a loaded machine), never a count of tries. */
static void wait_for_socket(const char *sock, struct stat *st)
{
    struct timespec t0, t;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    do {
        if (stat(sock, st) == 0)
            return;
        usleep(10000);
        clock_gettime(CLOCK_MONOTONIC, &t);
    } while (t.tv_sec - t0.tv_sec < 60);
}

static int ask(const char *sock, const char *req, char *buf, size_t cap)
{
    char err[512];
    FILE *f = fmemopen(buf, cap, "w");
    assert_non_null(f);
    int rc = cs_daemon_request(sock, req, f, err, sizeof err);
    fclose(f);
    if (rc < 0)
        snprintf(buf, cap, "%s", err);
    return rc;
}

static void test_no_daemon_names_the_socket(void **state)
{
    (void)state;
    char buf[1024];
    int rc = ask("/nonexistent-dir/cs.sock", "STATUS", buf, sizeof buf);
    assert_int_equal(rc, -1);
    assert_non_null(strstr(buf, "no daemon answers on /nonexistent-dir/cs.sock"));
}

static void test_protocol(void **state)
{
    (void)state;
    int master, slave;
    char pty[128];
    assert_int_equal(cs_serial_openpty(&master, &slave, pty, sizeof pty), 0);
    char dir[] = "/tmp/cs-daemon-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char sock[256];
    snprintf(sock, sizeof sock, "%s/d.sock", dir);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        alarm(300); /* bounded whatever happens (generous: ASan on a loaded machine) */
        cs_daemon_cfg_t cfg = {
            .link = {.port = pty, .baud = 115200}, .socket_path = sock, .log = NULL};
        _exit(cs_daemon_serve(&cfg));
    }
    struct stat st;
    wait_for_socket(sock, &st);
    assert_int_equal(stat(sock, &st), 0);
    assert_true(S_ISSOCK(st.st_mode));
    assert_int_equal(st.st_mode & 0777, 0600);

    char buf[4096];
    assert_int_equal(ask(sock, "PAUSE", buf, sizeof buf), 0);
    assert_string_equal(buf, "OK paused\n");

    /* a good job: queued, with as many segments as the planner makes of it */
    const char *job = "tests/data/svg/resvg/M-L-Z-A.svg";
    char abs[PATH_MAX];
    assert_non_null(realpath(job, abs));
    cs_machine_t m;
    cs_machine_ini_default(&m);
    cs_path_t path;
    cs_path_init(&path);
    cs_path_diag_t diag;
    assert_int_equal(cs_motion_read_job(abs, &path, &diag), CS_OK);
    /* laid out as every job command does by default (the SVG page turned y-up, no merge) */
    cs_jobopts_t in;
    cs_jobopts_init(&in);
    assert_int_equal(cs_jobopts_prepare(&in, "test", &m, false, 0.01, &path, &diag, NULL), CS_OK);
    cs_motion_t mo;
    assert_int_equal(cs_motion_init(&mo, &m), CS_OK);
    assert_int_equal(cs_motion_plan_path(&mo, &path, m.tolerance, CS_TRACE_DEFAULT, 0, &diag),
                     CS_OK);
    char want[PATH_MAX + 400];
    snprintf(want, sizeof want, "OK job 1 queued: %s: %zu segments\n", abs, mo.segs.n);
    size_t nsegs = mo.segs.n;
    cs_motion_free(&mo);
    cs_path_free(&path);
    char req[PATH_MAX + 40];
    snprintf(req, sizeof req, "SUBMIT %s", abs);
    assert_int_equal(ask(sock, req, buf, sizeof buf), 0);
    assert_string_equal(buf, want);

    /* a bad job: refused with file:line:col, nothing queued */
    char bad[300];
    snprintf(bad, sizeof bad, "%s/bad.svg", dir);
    FILE *f = fopen(bad, "w");
    assert_non_null(f);
    fputs("M 0 0\nQ 1\n", f); /* nothing drawable before the error: it stays an error */
    fclose(f);
    snprintf(req, sizeof req, "SUBMIT %s", bad);
    assert_int_equal(ask(sock, req, buf, sizeof buf), 1);
    char prefix[400];
    snprintf(prefix, sizeof prefix, "ERR %s:", bad);
    assert_memory_equal(buf, prefix, strlen(prefix));
    unsigned line = 0, col = 0;
    assert_int_equal(sscanf(buf + strlen(prefix), "%u:%u:", &line, &col), 2);
    assert_true(line >= 1 && col >= 1);

    /* options, and a relative path refused */
    snprintf(req, sizeof req, "SUBMIT mode=curves tol=0.05 %s", abs);
    assert_int_equal(ask(sock, req, buf, sizeof buf), 0);
    assert_non_null(strstr(buf, "OK job 2 queued: "));
    assert_non_null(strstr(buf, " curves\n"));
    assert_int_equal(ask(sock, "SUBMIT mode=fast /x.svg", buf, sizeof buf), 1);
    assert_int_equal(ask(sock, "SUBMIT x.svg", buf, sizeof buf), 1);

    /* status: the paused queue, both jobs queued */
    assert_int_equal(ask(sock, "STATUS", buf, sizeof buf), 0);
    snprintf(want, sizeof want, "OK device %s, queue paused\njob 1 queued: %s: 0/%zu segments", pty,
             abs, nsegs);
    assert_memory_equal(buf, want, strlen(want));
    assert_non_null(strstr(buf, "\njob 2 queued: "));

    /* cancel a queued job; again is an error; an unknown job and request too */
    assert_int_equal(ask(sock, "CANCEL 1", buf, sizeof buf), 0);
    assert_string_equal(buf, "OK job 1 cancelled\n");
    assert_int_equal(ask(sock, "CANCEL 1", buf, sizeof buf), 1);
    assert_string_equal(buf, "ERR job 1 is cancelled\n");
    assert_int_equal(ask(sock, "CANCEL 9", buf, sizeof buf), 1);
    assert_int_equal(ask(sock, "CANCEL", buf, sizeof buf), 1); /* nothing runs */
    assert_int_equal(ask(sock, "FLY", buf, sizeof buf), 1);
    assert_int_equal(ask(sock, "STATUS", buf, sizeof buf), 0);
    assert_non_null(strstr(buf, "\njob 1 cancelled: "));

    /* SIGTERM: exit 0, socket removed */
    kill(pid, SIGTERM);
    int ws = 0;
    assert_int_equal(waitpid(pid, &ws, 0), pid);
    assert_true(WIFEXITED(ws));
    assert_int_equal(WEXITSTATUS(ws), 0);
    assert_int_not_equal(stat(sock, &st), 0);
    unlink(bad);
    rmdir(dir);
    close(master);
    close(slave);
}

/* Segments of file planned on the machine of ini with its [pen] (pen_z) or without (the plain
 * machine and no pen), as `curvestep plan` does. */
static size_t plan_count(const char *ini, const char *file, bool pen_z)
{
    cs_machine_t m;
    cs_machine_pen_t pen;
    char err[512];
    assert_int_equal(cs_machine_ini_load_pen(ini, &m, &pen, err, sizeof err), 0);
    cs_jobplan_t jp;
    cs_jobplan_init(&jp);
    assert_int_equal(cs_jobplan_read(&jp, file, pen_z ? &pen : NULL, false), CS_OK);
    assert_int_equal(cs_jobplan_plan(&jp, file, &m, NULL, m.tolerance, CS_TRACE_DEFAULT, 0), CS_OK);
    size_t n = jp.mo.segs.n;
    cs_jobplan_free(&jp);
    return n;
}

static void test_pen_machine(void **state)
{
    (void)state;
    int master, slave;
    char pty[128];
    assert_int_equal(cs_serial_openpty(&master, &slave, pty, sizeof pty), 0);
    char dir[] = "/tmp/cs-daemon-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char sock[256], ini[256], job[256];
    snprintf(sock, sizeof sock, "%s/d.sock", dir);
    snprintf(ini, sizeof ini, "%s/pen.ini", dir);
    snprintf(job, sizeof job, "%s/pen.nc", dir);
    FILE *f = fopen(ini, "w");
    assert_non_null(f);
    fputs("[pen]\nmode = z\nup_z = 5\ndown_z = 0\n", f);
    fclose(f);
    f = fopen(job, "w");
    assert_non_null(f);
    fputs("G21 G90\nG0 X10 Y10\nM3\nG1 X30 Y10 F1200\nM5\nG0 X40 Y20\nM3\nG1 X40 Y40\nM5\nM2\n", f);
    fclose(f);
    size_t with_pen = plan_count(ini, job, true), without = plan_count(ini, job, false);
    assert_true(with_pen != without); /* else this test could not tell the two apart */
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        alarm(300);
        cs_daemon_cfg_t cfg = {.link = {.port = pty, .baud = 115200},
                               .socket_path = sock,
                               .machine_file = ini,
                               .log = NULL};
        _exit(cs_daemon_serve(&cfg));
    }
    struct stat st;
    wait_for_socket(sock, &st);
    char buf[4096];
    assert_int_equal(ask(sock, "PAUSE", buf, sizeof buf), 0);
    char req[400], want[600];
    snprintf(req, sizeof req, "SUBMIT %s", job);
    assert_int_equal(ask(sock, req, buf, sizeof buf), 0);
    snprintf(want, sizeof want, "OK job 1 queued: %s: %zu segments\n", job, with_pen);
    assert_string_equal(buf, want);
    kill(pid, SIGTERM);
    int ws = 0;
    assert_int_equal(waitpid(pid, &ws, 0), pid);
    unlink(ini);
    unlink(job);
    rmdir(dir);
    close(master);
    close(slave);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_no_daemon_names_the_socket),
        cmocka_unit_test(test_protocol),
        cmocka_unit_test(test_pen_machine),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
