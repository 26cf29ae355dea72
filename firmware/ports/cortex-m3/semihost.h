/* semihost: ARM semihosting calls (the "Semihosting for AArch32 and AArch64" specification,
 * BKPT 0xAB on M-profile): text out, the command line, the host's clock, and SYS_EXIT_EXTENDED
 * so a test image ends qemu with a status code. Safe without a debugger: startup_m3.c's HardFault
 * handler turns a semihosting BKPT nobody serves into a call that returns -1. */
#ifndef SEMIHOST_H
#define SEMIHOST_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Writes the NUL-terminated string s to the debugger's console (qemu: its standard output with
 * -semihosting-config enable=on,target=native). */
void semihost_write0(const char *s);
/* Copies the command line (qemu: -semihosting-config ...,arg=A,arg=B gives "A B") into buf
 * (NUL-terminated); false when there is none or no debugger answers. */
bool semihost_cmdline(char *buf, size_t cap);
/* Seconds since 1970 on the host (SYS_TIME), 0 when no debugger answers. */
uint32_t semihost_time(void);
/* Ends the session with status code (SYS_EXIT_EXTENDED, reason ADP_Stopped_ApplicationExit);
 * returns only when no debugger answers. */
void semihost_exit(uint32_t code);
/* Appends the decimal form of v to buf at *len (cap includes the NUL). */
void semihost_fmt_int(char *buf, size_t cap, size_t *len, int32_t v);
void semihost_fmt_uint(char *buf, size_t cap, size_t *len, uint32_t v);
void semihost_fmt_str(char *buf, size_t cap, size_t *len, const char *s);

#endif
