/* curvestep: the host program. Dispatches `curvestep COMMAND [ARGS]` through the table below;
 * each command lives in its own host/cs_*_cmd.c and is declared in cs_cmd.h. */
#include <stdio.h>
#include <string.h>

#include "cs_cmd.h"

static int cmd_help(int argc, char **argv);

/* The commands. Add one line here and a prototype in cs_cmd.h. */
static const struct {
    const char *name;
    cs_cmd_fn fn;
    const char *summary;
} commands[] = {
    {"flatten", cs_cmd_flatten, "print a job's chords (SVG, G-code, HP-GL, DXF), within a tolerance"},
    {"plan", cs_cmd_plan, "plan a job into step segments (ticks dx dy dz) for a machine"},
    {"inspect", cs_cmd_inspect, "describe a job or surfaces file: elements, lengths, continuity"},
    {"toolpath", cs_cmd_toolpath, "surface patches: projected wireframe or ball-end finishing"},
    {"stream", cs_cmd_stream, "stream a job to a device on a serial port (segments or curves)"},
    {"grbl", cs_cmd_grbl, "speak Grbl 1.1 to a G-code sender (pty or TCP), drive a device"},
    {"serve", cs_cmd_serve, "the daemon: keep a device open, stream queued jobs one by one"},
    {"submit", cs_cmd_submit, "queue a job on the daemon (planned whole, refused if bad)"},
    {"status", cs_cmd_status, "the daemon's queue and the running job's progress"},
    {"pause", cs_cmd_pause, "hold the daemon's running job and its queue"},
    {"resume", cs_cmd_resume, "resume the daemon's held job and queue"},
    {"cancel", cs_cmd_cancel, "cancel a queued job, or the running one (hold, then abort)"},
    {"home", cs_cmd_home, "home the machine on its switches ([homing] of the machine file)"},
    {"jog", cs_cmd_jog, "move the device to a machine position (Ctrl-C decelerates, stops)"},
    {"probe", cs_cmd_probe, "probe towards a position, print the contact (G38.2..G38.5)"},
    {"unlock", cs_cmd_unlock, "leave the device's alarm state (Grbl's $X)"},
    {"spindle", cs_cmd_spindle, "set the spindle or laser output (M3/M4/M5 S; laser mode)"},
    {"help", cmd_help, "show this help, or a command's help: curvestep help COMMAND"},
};

#define NCOMMANDS (sizeof commands / sizeof commands[0])

static void usage(FILE *f)
{
    fprintf(f, "Usage: curvestep COMMAND [OPTIONS] [ARGS]\n"
               "       curvestep COMMAND --help | --help | --version\n\n"
               "curvestep turns curves into chords and motor steps in fixed point.\n\n"
               "Commands:\n");
    for (size_t i = 0; i < NCOMMANDS; i++)
        fprintf(f, "  %-10s %s\n", commands[i].name, commands[i].summary);
    fprintf(f, "\nExit status: 0 success, 1 bad input (file:line:col: reason), 2 usage error,\n"
               "3 internal error (overflow, out of memory, I/O).\n");
}

static int find_command(const char *name)
{
    for (size_t i = 0; i < NCOMMANDS; i++)
        if (strcmp(commands[i].name, name) == 0)
            return (int)i;
    return -1;
}

static int cmd_help(int argc, char **argv)
{
    if (argc < 2 || strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0) {
        usage(stdout);
        return CS_EXIT_OK;
    }
    int k = find_command(argv[1]);
    if (k < 0 || commands[k].fn == cmd_help) {
        if (k < 0) {
            fprintf(stderr, "curvestep: unknown command '%s'\n", argv[1]);
            usage(stderr);
            return CS_EXIT_USAGE;
        }
        usage(stdout);
        return CS_EXIT_OK;
    }
    static char help_opt[] = "--help";
    char *sub[3] = {argv[1], help_opt, NULL};
    return commands[k].fn(2, sub);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return CS_EXIT_USAGE;
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0) {
        usage(stdout);
        return CS_EXIT_OK;
    }
    if (strcmp(argv[1], "--version") == 0) {
        printf("curvestep %s\n", CS_VERSION);
        return CS_EXIT_OK;
    }
    int k = find_command(argv[1]);
    if (k < 0) {
        fprintf(stderr, "curvestep: unknown command '%s' (try 'curvestep --help')\n", argv[1]);
        return CS_EXIT_USAGE;
    }
    return commands[k].fn(argc - 1, argv + 1);
}
