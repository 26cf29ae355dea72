/* cs_grbl_cmd: `curvestep grbl`, the command line of the Grbl front end (cs_grbl). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_cmd.h"
#include "cs_grbl.h"
#include "cs_joblink.h"
#include "cs_machine_ini.h"

static void usage(FILE *f)
{
    fputs("usage: curvestep grbl --port DEV [--baud N] [--line-rate BPS]\n"
          "                      | --modbus-tcp HOST:PORT [--unit ID]\n"
          "                      | --modbus-rtu DEV [--baud N] [--parity P] [--unit ID]\n"
          "                      | --gpio CHIP\n"
          "                      [--machine FILE.ini] [--tol MM] [--feed MM/S]\n"
          "                      [--pty [--link PATH] | --listen [ADDR:]PORT] [--state FILE]\n"
          "Speaks Grbl 1.1's serial protocol to a G-code sender (Universal G-code Sender,\n"
          "cncjs, bCNC, a streaming script) and drives a curvestep device over any of the\n"
          "links of `curvestep stream`: its wire protocol on a serial line (or the pty printed\n"
          "by `curvestep-sim --pty`), Modbus TCP or RTU, or GPIO step/dir lines.\n"
          "  --pty              (default) create a pseudo-terminal; its path is the first line\n"
          "                     on standard output: open it in the sender as a serial port\n"
          "  --link PATH        also make PATH a symlink to that pty (e.g. /tmp/ttyCURVESTEP);\n"
          "                     removed on exit\n"
          "  --listen [ADDR:]PORT  serve one TCP client at a time instead, on ADDR (default\n"
          "                     127.0.0.1: loopback only); PORT 0 picks one; ADDR:PORT is\n"
          "                     the first line on standard output\n"
          "  --port DEV         the device's serial line; --baud N its speed (default 115200);\n"
          "                     --line-rate BPS paces the writes as a line of BPS bits/s would\n"
          "  --modbus-tcp HOST:PORT  a Modbus TCP device (docs/modbus.md); --unit ID its unit\n"
          "                     id (default 1)\n"
          "  --modbus-rtu DEV   a Modbus RTU device on serial line DEV; --baud N (default\n"
          "                     115200), --parity none|even|odd (default even), --unit ID\n"
          "                     --modbus-timeout MS: one try's wait for an answer (default 200)\n"
          "  --gpio CHIP        step/dir lines of GPIO chip CHIP, wired as the machine file's\n"
          "                     [gpio] section says (requested for each chunk); --gpio\n"
          "                     record:FILE runs on no hardware and writes the last chunk's\n"
          "                     edges to FILE (docs/gpio.md)\n"
          "  --machine FILE     machine description (default: the built-in plotter); $$ shows\n"
          "                     it as Grbl settings, read-only ($10 alone can be set)\n"
          "  --state FILE       keep the work offsets (G54..G59.3, set by G10) and the G28/G30\n"
          "                     homes in FILE: read at start, written on exit (as G-code)\n"
          "  --tol MM           chord tolerance (default: the machine's); --feed MM/S the feed\n"
          "                     where the program gives no F (default: the machine's)\n"
          "Each line is answered ok when it is read into the queue (error:N, with a [MSG:...]\n"
          "saying why, when it is refused: the stream goes on). Lines are planned in chunks:\n"
          "a chunk ends when the sender pauses 30 ms, after 400 moves, at a G4 dwell or at\n"
          "M2/M30, and each chunk ends at rest (no look-ahead across chunks).\n"
          "Lines are LinuxCNC G-code read a line at a time: parameters, work offsets (G10,\n"
          "G54-G59.3, G92, G28/G30, G53) and O-word subroutines carry from line to line.\n"
          "Real-time bytes: ? status, ! feed hold, ~ resume, Ctrl-X reset, 0x85 jog cancel,\n"
          "0x90-0x9D feed/rapid/spindle overrides (feed and spindle also on the chunk a\n"
          "serial device runs, within its acceleration; over Modbus and GPIO from the next\n"
          "chunk; Ov: in the status). $$ $# $G $I $N $C $X $J= $H work. On the device: $H\n"
          "homes the axes of the machine file's [homing], $X unlocks, G38.2-G38.5 probe\n"
          "([PRB:] reported), M3/M4/M5 S drive the spindle ([spindle] laser = true: Grbl's\n"
          "laser mode); its alarms come as ALARM:N, its switches as Pn: in the status. Over\n"
          "GPIO the host runs $H, G38.x and the hard limits on its step thread with the\n"
          "[gpio] inputs; Modbus carries motion only: there $H is error:5 and G38.x, M3, M4\n"
          "error:20 (GPIO: M3, M4), each with a [MSG:] saying why. See docs/controller.md.\n"
          "SIGINT or SIGTERM: the running chunk is held, aborted, and the command ends.\n"
          "Exit status: 0 stopped by a signal, 1 bad machine file, 2 bad command line,\n"
          "3 internal error (pty, socket), 4 the device cannot be opened.\n",
          f);
}

int cs_cmd_grbl(int argc, char **argv)
{
    cs_grbl_cfg_t c;
    memset(&c, 0, sizeof c);
    c.dev.baud = 115200;
    c.dev.unit = 1;
    cs_jobplan_opts_init(&c.job);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        bool has = i + 1 < argc;
        int r = cs_jobplan_option("grbl", argc, argv, &i, &c.job);
        if (r == 0) /* --port, --modbus-tcp, --modbus-rtu, --gpio and their settings */
            r = cs_joblink_option("grbl", argc, argv, &i, &c.dev);
        if (r < 0)
            return CS_EXIT_USAGE;
        if (r > 0)
            continue;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return CS_EXIT_OK;
        } else if (strcmp(a, "--pty") == 0) {
            c.listen = NULL;
        } else if (strcmp(a, "--listen") == 0 && has) {
            c.listen = argv[++i];
        } else if (strcmp(a, "--link") == 0 && has) {
            c.link = argv[++i];
        } else if (strcmp(a, "--state") == 0 && has) {
            c.state = argv[++i];
        } else {
            fprintf(stderr, "curvestep grbl: unknown or incomplete option '%s'\n", a);
            usage(stderr);
            return CS_EXIT_USAGE;
        }
    }
    cs_joblink_t pick;
    if (cs_joblink_select(&pick, &c.dev) != CS_EXIT_OK) {
        fprintf(stderr, "curvestep grbl: %s (the device's link)\n", pick.why);
        return CS_EXIT_USAGE;
    }
    if (c.dev.line_rate != 0 && c.dev.port == NULL) {
        fprintf(stderr, "curvestep grbl: --line-rate applies to --port only\n");
        return CS_EXIT_USAGE;
    }
    if (c.dev.mb_timeout_ms != 0 && c.dev.modbus_tcp == NULL && c.dev.modbus_rtu == NULL) {
        fprintf(stderr, "curvestep grbl: --modbus-timeout applies to a Modbus link only\n");
        return CS_EXIT_USAGE;
    }
    static char found[4096];
    if (c.dev.port == NULL && c.job.machine_file == NULL &&
        cs_machine_ini_find(found, sizeof found))
        c.job.machine_file = found;          /* as `curvestep stream` finds it */
    c.dev.machine_file = c.job.machine_file; /* the GPIO link's [gpio] section */
    struct sockaddr_in sa;
    if (c.listen != NULL && !cs_grbl_listen_parse(c.listen, &sa)) {
        fprintf(stderr, "curvestep grbl: --listen wants [ADDR:]PORT (an IPv4 address), got '%s'\n",
                c.listen);
        return CS_EXIT_USAGE;
    }
    if (c.link != NULL && c.listen != NULL) {
        fprintf(stderr, "curvestep grbl: --link goes with a pty, not with --listen\n");
        return CS_EXIT_USAGE;
    }
    return cs_grbl_serve(&c);
}
