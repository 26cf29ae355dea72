/* cs_stream_resume: the stated position and the job's position after n messages (see
 * cs_stream_resume.h). */
#include "cs_stream_resume.h"

#include <stdlib.h>
#include <string.h>

#include "cs_conv.h"
#include "cs_fixed.h"

cs_err_t cs_stream_resume_position(const char *text, const cs_machine_t *m,
                                   int32_t steps[CS_AXES])
{
    char buf[128];
    if (text == NULL || strlen(text) >= sizeof buf)
        return CS_ERR_PARSE;
    strcpy(buf, text);
    memset(steps, 0, CS_AXES * sizeof steps[0]);
    unsigned n = 0;
    char *save = NULL;
    for (char *tok = strtok_r(buf, ",", &save); tok != NULL; tok = strtok_r(NULL, ",", &save)) {
        double mm;
        cs_pos_t p;
        if (n >= m->n_axes || !cs_conv_number(tok, &mm))
            return CS_ERR_PARSE;
        if (cs_conv_mm_to_pos(mm, &p) != CS_OK)
            return CS_ERR_RANGE;
        /* round(pos * steps_per_mm): Q16 x Q16 = Q32, as the planner (cs_planner.c) */
        steps[n] = (int32_t)cs_fixed_round_shift64((int64_t)p * m->axis[n].steps_per_mm, 32);
        n++;
    }
    return n == m->n_axes ? CS_OK : CS_ERR_PARSE;
}

void cs_stream_resume_steps_after(const cs_stream_job_t *job, size_t n, int64_t steps[CS_AXES])
{
    for (unsigned i = 0; i < CS_AXES; i++)
        steps[i] = 0;
    for (size_t k = 0; k < n && k < job->n; k++)
        if (job->v[k].type == CS_PROTO_SEGMENT)
            for (unsigned i = 0; i < CS_AXES; i++)
                steps[i] += job->v[k].u.segment.steps[i];
}

/* Where message n leaves the machine, mm: the segments' sum (segments mode, from the origin)
 * or curve n's end point (curves mode). */
static void where_after(const cs_stream_job_t *job, size_t n, const cs_machine_t *m, double mm[3])
{
    mm[0] = mm[1] = mm[2] = 0;
    if (job->mode == CS_STREAM_CURVES) {
        for (size_t k = n; k > 0; k--)
            if (job->v[k - 1].type == CS_PROTO_CURVE) {
                const cs_vec3_t *p = &job->v[k - 1].u.curve.p[3];
                mm[0] = cs_conv_pos_to_mm(p->x);
                mm[1] = cs_conv_pos_to_mm(p->y);
                mm[2] = cs_conv_pos_to_mm(p->z);
                return;
            }
        return;
    }
    int64_t st[CS_AXES];
    cs_stream_resume_steps_after(job, n, st);
    for (unsigned i = 0; i < 3 && i < m->n_axes; i++)
        mm[i] = (double)st[i] * CS_MOTION_ONE / m->axis[i].steps_per_mm;
}

void cs_stream_resume_hint(FILE *out, const cs_stream_job_t *job, const cs_stream_result_t *r,
                           const cs_machine_t *m, const char *file)
{
    if (!r->numbered || r->outcome == CS_STREAM_DONE || r->executed >= job->n)
        return;
    const char *one = job->mode == CS_STREAM_CURVES ? "curve" : "segment";
    size_t k = r->executed, top = r->sent;
    fprintf(out, "stream: confirmed by the device: %s no. %zu finished", one, k);
    if (top > k)
        fprintf(out, "; it may have executed up to no. %zu (sent; it had reported %zu received)",
                top, r->dev_recv);
    fprintf(out, "\n");
    double mm[3];
    where_after(job, k, m, mm);
    fprintf(out, "stream: %s no. %zu leaves the machine at %.4f,%.4f,%.4f mm\n", one, k, mm[0],
            mm[1], mm[2]);
    if (r->outcome != CS_STREAM_RESET)
        fprintf(out,
                "stream: if the device did not reset (still powered, same boot), it knows "
                "exactly: curvestep stream --port DEV --resume %s\n",
                file);
    fprintf(out,
            "stream: if it reset, its position is unknown: home the machine and run the job "
            "again, or put it where %s no. N left it (N = the last it finished, %zu..%zu) and "
            "state it: curvestep stream --port DEV --resume-from N --position X,Y,Z %s\n",
            one, k, top, file);
}
