/* cs_stream_report: the one place where a link's run becomes what `stream` says: the exit
 * status of an outcome (cs_stream_cmd.h's CS_EXIT_*) and the summary lines "stream: LINK:
 * outcome", "stream: N of M ... executed ...", the link's counters, and the resume hint. Every
 * link reaches it through cs_joblink_report (serial, Modbus TCP/RTU, GPIO). Host only. */
#ifndef CS_STREAM_REPORT_H
#define CS_STREAM_REPORT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "cs_stream.h"

/* The exit status of an outcome: 0 done, CS_EXIT_NO_DEVICE, _RESET, _CLOSED, _DEV_ERROR,
 * _INTERRUPTED. */
int cs_stream_exit_code(cs_stream_outcome_t oc);
/* The link's own counters line(s), printed between the counts and the resume hint. */
typedef void (*cs_stream_report_fn)(void *ctx, FILE *out, const cs_stream_result_t *r);
/* Prints the summary of run r of a job of n messages (over link `where`, from resume_from + 1,
 * curves or segments) on out and returns cs_stream_exit_code(r->outcome). counters (NULL: the
 * byte and retransmission counters of the serial and Modbus links, cs_stream_report_bytes)
 * prints the link's own counters. */
int cs_stream_report(FILE *out, const char *where, size_t n, const cs_stream_result_t *r,
                     size_t resume_from, bool curves, cs_stream_report_fn counters, void *ctx);
/* "stream: B bytes sent, R received in S s; N retransmissions (...); M WHAT/s": the serial and
 * Modbus links' counters (the rate over the messages executed after resume_from). */
void cs_stream_report_bytes(FILE *out, const cs_stream_result_t *r, size_t resume_from,
                            bool curves);
/* "stream: E of N WHAT executed, D delivered, S sent; last executed: E". */
void cs_stream_report_counts(FILE *out, size_t executed, size_t n, size_t delivered, size_t sent,
                             const char *what);
/* "stream: to continue once the machine is where ONE no. E left it: ..." (one: "segment" or
 * "curve"): the hint of links whose device does not number the job (Modbus, GPIO); a serial
 * run the device numbered gets cs_stream_resume_hint instead. */
void cs_stream_report_resume(FILE *out, const char *one, size_t executed);

#endif
