/* cs_stream_report: outcome -> exit status and the summary lines of every link (see
 * cs_stream_report.h; the lines are documented in docs/streaming.md). */
#include "cs_stream_report.h"

#include "cs_cmd.h"
#include "cs_ctlcfg.h"
#include "cs_err_text.h"
#include "cs_stream_cmd.h"

int cs_stream_exit_code(cs_stream_outcome_t oc)
{
    switch (oc) {
    case CS_STREAM_DONE:
        return CS_EXIT_OK;
    case CS_STREAM_NO_DEVICE:
    case CS_STREAM_INCOMPATIBLE:
        return CS_EXIT_NO_DEVICE;
    case CS_STREAM_RESET:
        return CS_EXIT_RESET;
    case CS_STREAM_CLOSED:
        return CS_EXIT_CLOSED;
    case CS_STREAM_DEVICE_ERROR:
        return CS_EXIT_DEV_ERROR;
    case CS_STREAM_INTERRUPTED:
        return CS_EXIT_INTERRUPTED;
    }
    return CS_EXIT_INTERNAL;
}

void cs_stream_report_counts(FILE *out, size_t executed, size_t n, size_t delivered, size_t sent,
                             const char *what)
{
    fprintf(out, "stream: %zu of %zu %s executed, %zu delivered, %zu sent; last executed: %zu\n",
            executed, n, what, delivered, sent, executed);
}

void cs_stream_report_resume(FILE *out, const char *one, size_t executed)
{
    fprintf(out,
            "stream: to continue once the machine is where %s no. %zu left it: "
            "curvestep stream --resume-from %zu ...\n",
            one, executed, executed);
}

/* "stream: LINK: outcome (why)" with the reset's boot ids or the device's error. */
static void outcome_line(FILE *out, const char *where, const cs_stream_result_t *r, const char *one)
{
    fprintf(out, "stream: %s: %s", where, cs_stream_result_text(r));
    if (r->why[0] && r->outcome != CS_STREAM_DEVICE_ERROR)
        fprintf(out, " (%s)", r->why);
    if (r->outcome == CS_STREAM_RESET && !r->refused)
        fprintf(out, " (boot id %08x -> %08x; %u messages were in flight)", (unsigned)r->old_boot,
                (unsigned)r->new_boot, (unsigned)r->unacked);
    if (r->outcome == CS_STREAM_DEVICE_ERROR)
        fprintf(out, " (%s%s%s, about %s no. %zu)", r->why, r->why[0] ? ": " : "",
                cs_err_text((cs_err_t)r->dev_error.code), one, r->dev_error_msg);
    fprintf(out, "\n");
}

/* "stream: ALARM:N (what): WHICH, during SEGMENT no. K; stopped at P steps": the device's
 * alarm EVENT located in the job (the message executing) and on the machine (the inputs that
 * tripped, the position). */
static void alarm_line(FILE *out, const cs_stream_result_t *r, const char *one)
{
    static const char axes[] = "xyza";
    const cs_proto_event_t *e = &r->alarm_ev;
    fprintf(out, "stream: ALARM:%u (%s):", (unsigned)e->code, cs_ctlcfg_alarm_text(e->code));
    unsigned shown = 0;
    for (unsigned i = 0; i < CS_PROTO_AXES_MAX; i++) {
        if (e->inputs & CS_PROTO_IN_MIN(i))
            fprintf(out, "%s %c min switch", shown++ ? "," : "", axes[i]);
        if (e->inputs & CS_PROTO_IN_MAX(i))
            fprintf(out, "%s %c max switch", shown++ ? "," : "", axes[i]);
    }
    if (e->inputs & CS_PROTO_IN_ESTOP)
        fprintf(out, "%s e-stop", shown++ ? "," : "");
    if (e->inputs & CS_PROTO_IN_PROBE)
        fprintf(out, "%s probe", shown++ ? "," : "");
    if (shown == 0)
        fprintf(out, " no input active");
    size_t at = r->outcome == CS_STREAM_DEVICE_ERROR && r->dev_error_msg ? r->dev_error_msg
                                                                         : r->alarm_msg;
    fprintf(out, ", during %s no. %zu; stopped at", one, at);
    for (unsigned i = 0; i < e->axes && i < CS_PROTO_AXES_MAX; i++)
        fprintf(out, " %c %ld", axes[i], (long)e->pos[i]);
    fprintf(out, " steps\n");
}

void cs_stream_report_bytes(FILE *out, const cs_stream_result_t *r, size_t resume_from, bool curves)
{
    fprintf(out,
            "stream: %llu bytes sent, %llu received in %.2f s; %u retransmissions (%u timeouts, "
            "%u NAKs); %.0f %s/s\n",
            (unsigned long long)r->bytes_out, (unsigned long long)r->bytes_in, r->wall_s,
            (unsigned)r->link.retransmits, (unsigned)r->link.timeouts, (unsigned)r->link.naks,
            r->stream_s > 0 ? (double)(r->executed - resume_from) / r->stream_s : 0.0,
            curves ? "curves" : "segments");
}

int cs_stream_report(FILE *out, const char *where, size_t n, const cs_stream_result_t *r,
                     size_t resume_from, bool curves, cs_stream_report_fn counters, void *ctx)
{
    const char *what = curves ? "curves" : "segments", *one = curves ? "curve" : "segment";
    int rc = cs_stream_exit_code(r->outcome);
    outcome_line(out, where, r, one);
    if (r->alarm)
        alarm_line(out, r, one);
    cs_stream_report_counts(out, r->executed, n, r->delivered, r->sent, what);
    if (counters != NULL)
        counters(ctx, out, r);
    else
        cs_stream_report_bytes(out, r, resume_from, curves);
    /* a device that numbers the job (serial link) gets the confirmed / in-flight lines and the
     * resume rules from the command (cs_stream_resume_hint); a refusal at the start said why */
    if (rc != CS_EXIT_OK && r->executed < n && !r->mid_message &&
        r->outcome != CS_STREAM_NO_DEVICE && r->outcome != CS_STREAM_INCOMPATIBLE &&
        !r->numbered && !r->refused)
        cs_stream_report_resume(out, one, r->executed);
    fflush(out);
    return rc;
}
