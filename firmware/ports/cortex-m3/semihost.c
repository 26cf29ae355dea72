/* semihost: see semihost.h. Operation numbers from the semihosting specification. */
#include "semihost.h"

#define SYS_WRITE0                   0x04u
#define SYS_TIME                     0x11u
#define SYS_GET_CMDLINE              0x15u
#define SYS_EXIT_EXTENDED            0x20u
#define ADP_STOPPED_APPLICATION_EXIT 0x20026u

static int32_t semihost_call(uint32_t op, const void *arg)
{
    register uint32_t r0 __asm("r0") = op;
    register const void *r1 __asm("r1") = arg;
    __asm volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return (int32_t)r0;
}

void semihost_write0(const char *s)
{
    (void)semihost_call(SYS_WRITE0, s);
}

bool semihost_cmdline(char *buf, size_t cap)
{
    if (cap == 0)
        return false;
    volatile uint32_t block[2] = {(uint32_t)(uintptr_t)buf, (uint32_t)cap};
    buf[0] = '\0';
    if (semihost_call(SYS_GET_CMDLINE, (const void *)block) != 0)
        return false;
    buf[cap - 1] = '\0';
    return true;
}

uint32_t semihost_time(void)
{
    int32_t t = semihost_call(SYS_TIME, NULL);
    return t < 0 ? 0u : (uint32_t)t;
}

void semihost_exit(uint32_t code)
{
    volatile uint32_t block[2] = {ADP_STOPPED_APPLICATION_EXIT, code};
    (void)semihost_call(SYS_EXIT_EXTENDED, (const void *)block);
}

void semihost_fmt_str(char *buf, size_t cap, size_t *len, const char *s)
{
    while (*s != '\0' && *len + 1 < cap)
        buf[(*len)++] = *s++;
    buf[*len] = '\0';
}

void semihost_fmt_uint(char *buf, size_t cap, size_t *len, uint32_t v)
{
    char d[11];
    unsigned n = 0;
    do {
        d[n++] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v != 0);
    while (n > 0 && *len + 1 < cap)
        buf[(*len)++] = d[--n];
    buf[*len] = '\0';
}

void semihost_fmt_int(char *buf, size_t cap, size_t *len, int32_t v)
{
    if (v < 0) {
        semihost_fmt_str(buf, cap, len, "-");
        semihost_fmt_uint(buf, cap, len, (uint32_t)0 - (uint32_t)v);
    } else {
        semihost_fmt_uint(buf, cap, len, (uint32_t)v);
    }
}
