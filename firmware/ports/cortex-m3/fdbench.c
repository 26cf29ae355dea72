/* fdbench: the Cortex-M3 benchmark image (build/fw/cortex-m3/fdbench.elf, not the firmware).
 * Times the curve code on the LM3S6965 under qemu with -icount shift=0, where the virtual clock
 * advances exactly 1 ns per guest instruction, so SysTick cycles (20 ns each at 50 MHz) count
 * instructions: instructions = cycles * 20 / 2^shift. Measures, on one cubic Bezier:
 *   fd      cs_fd_next per point (uniform forward differences, the inner loop)
 *   fd3     cs_fd3_next per point (the planar polynomial FD path: 3 adds per coordinate)
 *   trace   cs_trace_next per chord for each tracer (FD, AFD, subdivision)
 *   arc     cs_trace per chord of a 50 mm quarter circle (cs_arc, one conic piece) by the
 *           default (the arc tracer cs_ellarc) and by the conic predictor (cs_predict)
 *   planner cs_planner_line3 + cs_segment_next per chord: what the device does with each chord
 *           of a CURVE message (the look-ahead plan and its step segments)
 * Prints one line per figure over semihosting ("bench: NAME calls N cycles C") and exits with
 * status 0 (1 when a call failed). scripts/bench.sh runs it. */
#include <stdint.h>

#include "cs_arc.h"
#include "cs_fd.h"
#include "cs_fd3.h"
#include "cs_planner.h"
#include "cs_segment.h"
#include "cs_trace.h"
#include "lm3s6965.h"
#include "semihost.h"

static volatile uint32_t wraps;
static bool failed;

void SysTick_Handler(void);
void SysTick_Handler(void)
{
    wraps++;
}

/* Core cycles since start: SysTick counts down from 2^24 - 1, its interrupt counts wraps. */
static uint32_t cycles(void)
{
    uint32_t w = wraps, v = SYST_CVR;
    if (SCB_ICSR & SCB_ICSR_PENDSTSET) { /* wrapped, interrupt not taken yet */
        w++;
        v = SYST_CVR;
    }
    return (w << 24) + (0xFFFFFFu - v);
}

static void print(const char *name, uint32_t calls, uint32_t cyc)
{
    char b[96];
    size_t n = 0;
    semihost_fmt_str(b, sizeof b, &n, "bench: ");
    semihost_fmt_str(b, sizeof b, &n, name);
    semihost_fmt_str(b, sizeof b, &n, " calls ");
    semihost_fmt_uint(b, sizeof b, &n, calls);
    semihost_fmt_str(b, sizeof b, &n, " cycles ");
    semihost_fmt_uint(b, sizeof b, &n, cyc);
    semihost_fmt_str(b, sizeof b, &n, "\n");
    semihost_write0(b);
}

#define MM(v) ((cs_pos_t)((v)*65536))

/* A 100 mm S-shaped cubic (mm): control polygon (0,0) (30,80) (70,-40) (100,20). */
static const cs_vec3_t ctrl[4] = {
    {MM(0), MM(0), 0}, {MM(30), MM(80), 0}, {MM(70), MM(-40), 0}, {MM(100), MM(20), 0}};

static void bench_fd(const cs_bezier_t *c, cs_pos_t tol, const char *name)
{
    static cs_fd_t f;
    cs_vec3_t p;
    uint32_t t0 = cycles();
    if (cs_fd_begin(&f, c, tol) != CS_OK)
        failed = true;
    uint32_t t1 = cycles();
    uint32_t n = 0;
    while (cs_fd_next(&f, &p) == CS_OK)
        n++;
    uint32_t t2 = cycles();
    print("fd_begin", 1, t1 - t0);
    print(name, n, t2 - t1);
}

static void bench_trace(const cs_bezier_t *c, cs_trace_method_t m, const char *name)
{
    static cs_trace_t tr;
    cs_vec3_t p;
    uint32_t t0 = cycles();
    if (cs_trace_begin(&tr, c, CS_POS_ONE_MM / 100, m) != CS_OK)
        failed = true;
    uint32_t n = 0;
    cs_err_t e;
    while ((e = cs_trace_next(&tr, &p)) == CS_OK)
        n++;
    uint32_t t1 = cycles();
    if (e != CS_END)
        failed = true;
    print(name, n, t1 - t0);
}

/* A 50 mm quarter circle at 0.01 mm: the default (cs_ellarc) and the conic predictor. */
static void bench_arc(void)
{
    static const cs_vec3_t cen = {0, 0, 0}, u = {50 * CS_POS_ONE_MM, 0, 0},
                           v = {0, 50 * CS_POS_ONE_MM, 0};
    cs_bezier_t seg[CS_ARC_MAX_SEGMENTS];
    unsigned n = 0;
    if (cs_arc_build(&cen, &u, &v, CS_PARAM_ONE, 0, 0, CS_PARAM_ONE, true, seg, &n) != CS_OK ||
        n != 1) {
        failed = true;
        return;
    }
    bench_trace(&seg[0], CS_TRACE_PREDICT, "trace_arc_chord");
    static cs_predict_t p;
    cs_vec3_t pt;
    uint32_t t0 = cycles(), k = 0;
    if (cs_predict_begin_conic(&p, &seg[0], CS_POS_ONE_MM / 100) != CS_OK)
        failed = true;
    while (cs_predict_next(&p, &pt) == CS_OK)
        k++;
    print("trace_conic_chord", k, cycles() - t0);
}

static void bench_fd3(const cs_bezier_t *c, cs_pos_t tol)
{
    static cs_fd3_t f;
    cs_vec3_t p;
    uint32_t t0 = cycles();
    if (cs_fd3_begin(&f, c, tol) != CS_OK)
        failed = true;
    uint32_t t1 = cycles();
    uint32_t n = 0;
    while (cs_fd3_next(&f, &p) == CS_OK)
        n++;
    uint32_t t2 = cycles();
    print("fd3_begin", 1, t1 - t0);
    print("fd3_point", n, t2 - t1);
    /* The block loop (cs_fd3_fill, 64 vertices a call) */
    static cs_vec3_t buf[64];
    if (cs_fd3_begin(&f, c, tol) != CS_OK)
        failed = true;
    uint32_t t3 = cycles();
    uint32_t m = 0, k;
    while ((k = (uint32_t)cs_fd3_fill(&f, buf, 64)) != 0)
        m += k;
    uint32_t t4 = cycles();
    print("fd3_fill_point", m, t4 - t3);
    /* The loop alone: the first piece's steps but its last (no piece start in the timing) */
    if (cs_fd3_begin(&f, c, tol) != CS_OK)
        failed = true;
    size_t inner = f.left - 1u < 64u ? f.left - 1u : 64u;
    uint32_t t5 = cycles();
    k = (uint32_t)cs_fd3_fill(&f, buf, inner);
    uint32_t t6 = cycles();
    print("fd3_loop_point", k, t6 - t5);
}

/* The device's work per chord of a CURVE: plan it, cut the plan into step segments. */
static void bench_planner(const cs_bezier_t *c)
{
    static cs_machine_t m;
    static cs_planner_t pl;
    static cs_segment_gen_t gen;
    static cs_trace_t tr;
    m.n_axes = 3;
    for (unsigned i = 0; i < CS_AXES; i++) {
        m.axis[i].steps_per_mm = 80 * CS_MOTION_ONE;
        m.axis[i].max_rate = 500 * CS_MOTION_ONE;
        m.axis[i].max_accel = 5000 * CS_MOTION_ONE;
        m.axis[i].travel_min = -1000 * CS_POS_ONE_MM;
        m.axis[i].travel_max = 1000 * CS_POS_ONE_MM;
        m.axis[i].pulse_ticks = 1;
    }
    m.tick_hz = 100000;
    m.segment_ticks = 500;
    m.tolerance = CS_POS_ONE_MM / 100;
    m.junction_deviation = CS_POS_ONE_MM / 100;
    m.default_feed = 50 * CS_MOTION_ONE;
    m.profile = CS_PROFILE_TRAPEZOID;
    m.max_jerk = 100000;
    if (cs_planner_init(&pl, &m) != CS_OK || cs_segment_init(&gen, &m) != CS_OK ||
        cs_trace_begin(&tr, c, m.tolerance, CS_TRACE_SUBDIV) != CS_OK) {
        failed = true;
        return;
    }
    /* the chords first (not timed), then plan and cut them in a loop like the device's */
    static cs_vec3_t pts[1024];
    uint32_t n = 0;
    while (n < 1024u && cs_trace_next(&tr, &pts[n]) == CS_OK)
        n++;
    uint32_t segs = 0;
    cs_segment_t s;
    uint32_t t0 = cycles();
    for (uint32_t i = 0; i < n; i++) {
        while (cs_planner_full(&pl)) {
            if (cs_segment_next(&gen, &pl, &s) != CS_OK) {
                failed = true;
                return;
            }
            segs++;
        }
        if (cs_planner_line3(&pl, &pts[i], 300 * CS_MOTION_ONE, i) != CS_OK)
            failed = true;
    }
    while (cs_segment_next(&gen, &pl, &s) == CS_OK)
        segs++;
    uint32_t t1 = cycles();
    print("planner_chord", n, t1 - t0);
    print("planner_segments", segs, 0);
}

int main(void)
{
    /* 50 MHz as in the firmware (PLL, SYSDIV 4): one SysTick cycle = 20 ns */
    uint32_t rcc = SYSCTL_RCC;
    rcc = (rcc | SYSCTL_RCC_BYPASS) & ~SYSCTL_RCC_USESYSDIV;
    SYSCTL_RCC = rcc;
    rcc = (rcc & ~(SYSCTL_RCC_XTAL_M | SYSCTL_RCC_OSCSRC_M | SYSCTL_RCC_PWRDN)) |
          SYSCTL_RCC_XTAL_8MHZ;
    SYSCTL_RCC = rcc;
    rcc = (rcc & ~SYSCTL_RCC_SYSDIV_M) | (3u << SYSCTL_RCC_SYSDIV_S) | SYSCTL_RCC_USESYSDIV;
    SYSCTL_RCC = rcc;
    for (uint32_t k = 0; k < 100000u && !(SYSCTL_RIS & SYSCTL_RIS_PLLLRIS); k++)
        ;
    SYSCTL_RCC = rcc & ~SYSCTL_RCC_BYPASS;
    SYST_RVR = 0xFFFFFFu;
    SYST_CVR = 0;
    SYST_CSR = SYST_CSR_CLKSOURCE | SYST_CSR_TICKINT | SYST_CSR_ENABLE;
    __asm volatile("cpsie i" ::: "memory");

    cs_bezier_t c;
    if (cs_bezier_init(&c, 3, ctrl) != CS_OK)
        failed = true;
    uint32_t t0 = cycles();
    uint32_t t1 = cycles();
    print("overhead", 1, t1 - t0);
    bench_fd(&c, CS_POS_ONE_MM / 1000, "fd_point"); /* 1 um: many points */
    bench_fd3(&c, CS_POS_ONE_MM / 1000);
    bench_trace(&c, CS_TRACE_FD, "trace_fd_chord");
    bench_trace(&c, CS_TRACE_AFD, "trace_afd_chord");
    bench_trace(&c, CS_TRACE_SUBDIV, "trace_subdiv_chord");
    bench_trace(&c, CS_TRACE_PREDICT, "trace_predict_chord");
    bench_arc();
    bench_planner(&c);
    semihost_exit(failed ? 1u : 0u);
    for (;;)
        ;
}
