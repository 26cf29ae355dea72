/* cs_sim_exlog: the executed log on disk (see cs_sim_exlog.h). */
#include "cs_sim_exlog.h"

#include <fcntl.h>
#include <stdio.h>
#include <unistd.h>

/* the firmware's hook: a segment handed to the executor, in order */
static void on_pushed(void *ctx, const cs_segment_t *s, uint32_t job_no)
{
    cs_sim_exlog_t *x = ctx;
    if (x->count == CS_SIM_EXLOG_FIFO) /* cannot happen: the ring is smaller (asserted) */
        return;
    uint32_t k = (x->head + x->count) % CS_SIM_EXLOG_FIFO;
    x->q[k].job_no = job_no;
    x->q[k].seg = *s;
    x->count++;
}

cs_err_t cs_sim_exlog_open(cs_sim_exlog_t *x, const char *path, cs_fw_motion_t *mo)
{
    x->fd = open(path, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (x->fd < 0)
        return CS_ERR_IO;
    x->head = x->count = 0;
    x->done = mo->completed;
    mo->pushed_hook = on_pushed;
    mo->hook_ctx = x;
    return CS_OK;
}

cs_err_t cs_sim_exlog_flush(cs_sim_exlog_t *x, const cs_fw_motion_t *mo)
{
    char buf[8192];
    size_t n = 0;
    while (x->done != mo->completed && x->count > 0) {
        const cs_segment_t *s = &x->q[x->head].seg;
        int w = snprintf(buf + n, sizeof buf - n, "%lu %lu %ld %ld %ld %ld\n",
                         (unsigned long)x->q[x->head].job_no, (unsigned long)s->ticks,
                         (long)s->steps[0], (long)s->steps[1], (long)s->steps[2],
                         (long)s->steps[3]);
        if (w < 0 || (size_t)w >= sizeof buf - n)
            break; /* the buffer is full: the rest goes out on the next call */
        n += (size_t)w;
        x->head = (x->head + 1u) % CS_SIM_EXLOG_FIFO;
        x->count--;
        x->done++;
    }
    /* one write a pass: a kill leaves whole lines (O_APPEND, regular file) */
    if (n > 0 && write(x->fd, buf, n) != (ssize_t)n)
        return CS_ERR_IO;
    return CS_OK;
}

void cs_sim_exlog_close(cs_sim_exlog_t *x, cs_fw_motion_t *mo)
{
    mo->pushed_hook = NULL;
    mo->hook_ctx = NULL;
    if (x->fd >= 0)
        close(x->fd);
    x->fd = -1;
}
