/* main_m3: the Cortex-M3 image's main loop: the application (firmware/app) over the port, sleeping
 * (WFI) whenever a pass leaves nothing to do. Under a debugger or qemu (semihosting), the image
 * also prints a report each time a job ends (the device goes idle after executing something) and,
 * when its command line says exit-idle=MS, ends the session with SYS_EXIT_EXTENDED once it has
 * executed something and heard nothing for MS milliseconds: status 0, or 1 after an ERROR or a
 * fault. qemu: -semihosting-config enable=on,target=native,arg=curvestep,arg=exit-idle=500. */
#include "cs_fw_app.h"
#include "port_m3.h"
#include "semihost.h"

static cs_machine_t machine;
static cs_fw_app_t app;
static uint32_t exit_idle_ms; /* 0: never exit */
/* power-up SRAM contents: noise on a real chip, mixed into the boot id */
__attribute__((section(".noinit"))) static uint32_t noise[32];

static const char axis_name[4] = {'x', 'y', 'z', 'a'};

/* "KEY=N" (N signed decimal) anywhere on the command line: true and *v. */
static bool parse_int(const char *cmd, const char *key, int32_t *v)
{
    for (const char *s = cmd; *s != '\0'; s++) {
        unsigned k = 0;
        while (key[k] != '\0' && s[k] == key[k])
            k++;
        if (key[k] != '\0' || (s != cmd && s[-1] != ' ')) /* a whole word only */
            continue;
        s += k;
        bool neg = *s == '-';
        if (neg)
            s++;
        int32_t n = 0;
        for (; *s >= '0' && *s <= '9' && n < 100000000; s++)
            n = n * 10 + (int32_t)(*s - '0');
        *v = neg ? -n : n;
        return true;
    }
    return false;
}

/* "exit-idle=MS" on the command line (0: none). */
static uint32_t parse_exit_idle(const char *cmd)
{
    int32_t v;
    return parse_int(cmd, "exit-idle=", &v) && v > 0 ? (uint32_t)v : 0u;
}

/* Simulated switches and probe for qemu (its board has none to press): "x_min=STEPS" ...
 * "a_max=STEPS", "probe_z=STEPS" in STEP/DIR pin positions (port_m3_sim_switch). */
static void sim_switches(const char *cmd)
{
    static const char *const keys[8] = {"x_min=", "y_min=", "z_min=", "a_min=",
                                        "x_max=", "y_max=", "z_max=", "a_max="};
    int32_t v;
    for (unsigned i = 0; i < 8u; i++)
        if (parse_int(cmd, keys[i], &v))
            port_m3_sim_switch((uint16_t)(1u << i), (uint8_t)(i & 3u), v, i >= 4u);
    if (parse_int(cmd, "probe_z=", &v))
        port_m3_sim_switch(CS_PROTO_IN_PROBE, 2, v, false);
}

static void line_axes(const char *label, const int32_t *v, bool is_signed)
{
    char b[160];
    size_t n = 0;
    semihost_fmt_str(b, sizeof b, &n, label);
    for (unsigned i = 0; i < machine.n_axes; i++) {
        char nm[4] = {' ', axis_name[i], '=', '\0'};
        semihost_fmt_str(b, sizeof b, &n, nm);
        if (is_signed)
            semihost_fmt_int(b, sizeof b, &n, v[i]);
        else
            semihost_fmt_uint(b, sizeof b, &n, (uint32_t)v[i]);
    }
    semihost_fmt_str(b, sizeof b, &n, "\n");
    semihost_write0(b);
}

/* The report a test compares with the simulator; one fact per line, "key: values". */
/* The pen servo's train as the port measured it (port_m3_servo.c), in core cycles (50 per us). */
static void report_servo(void)
{
    port_m3_servo_t sv;
    port_m3_servo(&sv);
    char b[240];
    size_t n = 0;
    semihost_fmt_str(b, sizeof b, &n, "fw: servo: PG1 ");
    semihost_fmt_uint(b, sizeof b, &n, sv.periods);
    semihost_fmt_str(b, sizeof b, &n, " periods, mean ");
    semihost_fmt_uint(b, sizeof b, &n, sv.periods ? (uint32_t)(sv.span_cyc / sv.periods) : 0);
    semihost_fmt_str(b, sizeof b, &n, " cycles (min ");
    semihost_fmt_uint(b, sizeof b, &n, sv.min_cyc);
    semihost_fmt_str(b, sizeof b, &n, " max ");
    semihost_fmt_uint(b, sizeof b, &n, sv.max_cyc);
    semihost_fmt_str(b, sizeof b, &n, "), last width ");
    semihost_fmt_uint(b, sizeof b, &n, sv.high_n);
    semihost_fmt_str(b, sizeof b, &n, " pulses of ");
    semihost_fmt_uint(b, sizeof b, &n, sv.high_sum);
    semihost_fmt_str(b, sizeof b, &n, " cycles; registers: period ");
    semihost_fmt_uint(b, sizeof b, &n, sv.period_reg);
    semihost_fmt_str(b, sizeof b, &n, " width ");
    semihost_fmt_uint(b, sizeof b, &n, sv.width_reg);
    semihost_fmt_str(b, sizeof b, &n, " cycles\n");
    semihost_write0(b);
}

static void report(void)
{
    cs_fw_report_t r;
    cs_fw_app_report(&app, &r);
    uint32_t pulses[4];
    int32_t pins[4];
    port_m3_pins(pulses, pins);
    char b[200];
    size_t n = 0;
    semihost_fmt_str(b, sizeof b, &n, "fw: executed ");
    semihost_fmt_uint(b, sizeof b, &n, r.stats.executed);
    semihost_fmt_str(b, sizeof b, &n, " messages, ");
    semihost_fmt_uint(b, sizeof b, &n, r.stats.segments);
    semihost_fmt_str(b, sizeof b, &n, " step segments, ");
    semihost_fmt_uint(b, sizeof b, &n, r.stats.curves);
    semihost_fmt_str(b, sizeof b, &n, " curves, ");
    semihost_fmt_uint(b, sizeof b, &n, r.stats.errors);
    semihost_fmt_str(b, sizeof b, &n, " errors, ");
    semihost_fmt_uint(b, sizeof b, &n, r.stats.holds);
    semihost_fmt_str(b, sizeof b, &n, " holds, ");
    semihost_fmt_uint(b, sizeof b, &n, r.stats.aborts);
    semihost_fmt_str(b, sizeof b, &n, " aborts\n");
    semihost_write0(b);
    n = 0;
    semihost_fmt_str(b, sizeof b, &n, "fw: pen: ");
    semihost_fmt_uint(b, sizeof b, &n, r.stats.pens);
    semihost_fmt_str(b, sizeof b, &n, " settings, last ");
    semihost_fmt_uint(b, sizeof b, &n, r.stats.pen_us);
    semihost_fmt_str(b, sizeof b, &n, " us\n");
    semihost_write0(b);
    uint32_t sp_n;
    uint16_t sp_duty;
    uint8_t sp_mode;
    port_m3_spindle(&sp_n, &sp_duty, &sp_mode);
    const cs_fw_ctl_t *c = &app.mo.ctl;
    n = 0;
    semihost_fmt_str(b, sizeof b, &n, "fw: control: ");
    semihost_fmt_uint(b, sizeof b, &n, c->homings);
    semihost_fmt_str(b, sizeof b, &n, " axes homed, ");
    semihost_fmt_uint(b, sizeof b, &n, c->alarms);
    semihost_fmt_str(b, sizeof b, &n, " alarms (now ");
    semihost_fmt_uint(b, sizeof b, &n, c->alarm);
    semihost_fmt_str(b, sizeof b, &n, "), ");
    semihost_fmt_uint(b, sizeof b, &n, c->probes);
    semihost_fmt_str(b, sizeof b, &n, " probe cycles; spindle: ");
    semihost_fmt_uint(b, sizeof b, &n, sp_n);
    semihost_fmt_str(b, sizeof b, &n, " settings, last duty ");
    semihost_fmt_uint(b, sizeof b, &n, sp_duty);
    semihost_fmt_str(b, sizeof b, &n, " mode ");
    semihost_fmt_uint(b, sizeof b, &n, sp_mode);
    semihost_fmt_str(b, sizeof b, &n, "\n");
    semihost_write0(b);
    report_servo();
    line_axes("fw: position (executor):", r.pos, true);
    line_axes("fw: position (STEP/DIR pins):", pins, true);
    line_axes("fw: step pulses:", (const int32_t *)pulses, false);
    n = 0;
    semihost_fmt_str(b, sizeof b, &n, "fw: steps total ");
    semihost_fmt_uint(b, sizeof b, &n, r.steps);
    semihost_fmt_str(b, sizeof b, &n, " in ");
    semihost_fmt_uint(b, sizeof b, &n, port_m3_step_irqs());
    semihost_fmt_str(b, sizeof b, &n, " step interrupts");
    semihost_fmt_str(b, sizeof b, &n, "; link: ");
    semihost_fmt_uint(b, sizeof b, &n, r.stats.rx_bytes);
    semihost_fmt_str(b, sizeof b, &n, " bytes in, ");
    semihost_fmt_uint(b, sizeof b, &n, r.rx.frames);
    semihost_fmt_str(b, sizeof b, &n, " frames, ");
    semihost_fmt_uint(b, sizeof b, &n, r.rx.crc_errs);
    semihost_fmt_str(b, sizeof b, &n, " CRC errors, ");
    semihost_fmt_uint(b, sizeof b, &n, r.link.duplicates);
    semihost_fmt_str(b, sizeof b, &n, " duplicates, ");
    semihost_fmt_uint(b, sizeof b, &n, r.link.retransmits);
    semihost_fmt_str(b, sizeof b, &n, " resent, ");
    semihost_fmt_uint(b, sizeof b, &n, port_m3_rx_overruns());
    semihost_fmt_str(b, sizeof b, &n, " UART overruns\n");
    semihost_write0(b);
    /* the execution log (cs_exlog), printed as the simulator prints it (sim/cs_sim_device.c) */
    cs_exlog_edges_t ed;
    port_m3_edges(&ed);
    n = 0;
    semihost_fmt_str(b, sizeof b, &n, "fw: log: ");
    semihost_fmt_uint(b, sizeof b, &n, r.log.n);
    semihost_fmt_str(b, sizeof b, &n, " segments hash ");
    semihost_fmt_uint(b, sizeof b, &n, r.log.hash);
    semihost_fmt_str(b, sizeof b, &n, ", ");
    semihost_fmt_uint(b, sizeof b, &n, ed.n);
    semihost_fmt_str(b, sizeof b, &n, " step edges hash ");
    semihost_fmt_uint(b, sizeof b, &n, ed.hash);
    semihost_fmt_str(b, sizeof b, &n, " at executor tick ");
    semihost_fmt_uint(b, sizeof b, &n, ed.clock);
    semihost_fmt_str(b, sizeof b, &n, "\n");
    semihost_write0(b);
}

void port_m3_on_fault(cs_err_t code)
{
    char b[64];
    size_t n = 0;
    semihost_fmt_str(b, sizeof b, &n, "fw: fault, code ");
    semihost_fmt_uint(b, sizeof b, &n, (uint32_t)code);
    semihost_fmt_str(b, sizeof b, &n, "\n");
    semihost_write0(b);
    report();
    semihost_exit(1);
    for (;;) /* no debugger: stay safe, drivers off, until reset */
        __asm volatile("wfi");
}

int main(void)
{
    port_init();
    char cmd[96];
    if (semihost_cmdline(cmd, sizeof cmd)) {
        exit_idle_ms = parse_exit_idle(cmd);
        sim_switches(cmd);
    }
    /* boot id: the host's clock (semihosting), the power-up noise of SRAM, the cycle counter */
    uint32_t boot = semihost_time() * 2654435761u;
    for (unsigned i = 0; i < sizeof noise / sizeof noise[0]; i++)
        boot = (boot ^ noise[i]) * 16777619u;
    boot ^= port_m3_cycles();
    noise[0] = boot; /* a warm reset keeps SRAM: the next boot id differs */
    cs_fw_machine_default(&machine, port_tick_hz());
    if (cs_fw_app_init(&app, &machine, boot) != CS_OK)
        port_fault(CS_ERR_ARG);
    uint32_t reported = 0;
    uint32_t hz_ms = port_tick_hz() / 1000u;
    for (;;) {
        cs_fw_app_poll(&app);
        if (cs_fw_app_idle(&app) && app.mo.stats.executed != reported) {
            reported = app.mo.stats.executed;
            report();
        }
        if (exit_idle_ms != 0 && reported != 0 && cs_fw_app_idle(&app) &&
            port_ticks_now() - cs_fw_app_last_rx(&app) >= exit_idle_ms * hz_ms) {
            report();
            semihost_exit(app.mo.stats.errors != 0 ? 1u : 0u);
            exit_idle_ms = 0; /* no debugger took the exit: go on serving */
        }
        /* nothing to do until an interrupt: sleep while no motion runs, spin while it does.
         * Under qemu each wake-up from WFI costs about 0.1 ms of host time, so sleeping between
         * step interrupts would make a job several times slower than real time, and the spin
         * touches no register (docs/firmware.md, "Running under qemu") */
        if (cs_fw_app_can_sleep(&app)) {
            if (cs_fw_app_idle(&app))
                port_m3_sleep();
            else
                port_m3_spin();
        }
    }
}
