/* cs_cmd: the subcommands of the curvestep program. host/main.c dispatches through one table;
 * adding a command is one line there plus its prototype here. Every command takes its own
 * argv (argv[0] = the command's name), handles its own --help, and returns an exit status. */
#ifndef CS_CMD_H
#define CS_CMD_H

#define CS_VERSION "0.1.0"

/* Exit statuses shared by every command (documented in each --help). */
enum {
    CS_EXIT_OK = 0,       /* success */
    CS_EXIT_INPUT = 1,    /* bad input: "file:line:col: reason" on stderr */
    CS_EXIT_USAGE = 2,    /* bad command line */
    CS_EXIT_INTERNAL = 3, /* internal error, arithmetic overflow, out of memory, I/O */
};

/* A command: argc/argv start at the command's name; returns a CS_EXIT_* status. */
typedef int (*cs_cmd_fn)(int argc, char **argv);

/* curvestep flatten [--tol MM] [--method fd|afd|subdiv] [--stats] [--svg OUT.svg] [JOBOPTS] FILE
 * (JOBOPTS: the input and layout options every job command shares, host/cs_jobopts.h) */
int cs_cmd_flatten(int argc, char **argv);

/* curvestep plan [--machine FILE.ini] [--tol MM] [--method M] [--feed MM/S] [JOBOPTS] [-o OUT]
 * FILE */
int cs_cmd_plan(int argc, char **argv);

/* curvestep toolpath --patches FILE [--view V] [--lines N] [--tol MM] [--svg OUT.svg]
 *                    [--ball R --scallop H [--safe-z Z]] */
int cs_cmd_toolpath(int argc, char **argv);
/* curvestep toolpath --cutter ball:R|flat:R|bull:R:r ...: drop-cutter finishing (cs_toolpath
 * hands over any command line with --cutter; the options are in toolpath's --help). */
int cs_cmd_toolpath_drop(int argc, char **argv);

/* curvestep stream --port DEV [--baud N] [--machine FILE.ini] [--mode segments|curves]
 * [--tol MM] [--feed MM/S] [--resume-from N] [--line-rate BPS] [--quiet] [JOBOPTS] FILE */
int cs_cmd_stream(int argc, char **argv);

/* curvestep inspect [--json] [--tol MM] [--rel R] [--patches] FILE */
int cs_cmd_inspect(int argc, char **argv);
/* curvestep grbl --port DEV [--baud N] [--machine FILE.ini] [--tol MM] [--feed MM/S]
 *                [--pty [--link PATH] | --listen [ADDR:]PORT] */
int cs_cmd_grbl(int argc, char **argv);

/* curvestep serve --port DEV [--baud N] [--machine FILE.ini] [--socket PATH] */
int cs_cmd_serve(int argc, char **argv);
/* curvestep submit [--socket PATH] [--mode M] [--tol MM] [--feed MM/S] [JOBOPTS] FILE */
int cs_cmd_submit(int argc, char **argv);
/* curvestep status | pause | resume [--socket PATH]; curvestep cancel [--socket PATH] [JOB] */
int cs_cmd_status(int argc, char **argv);
int cs_cmd_pause(int argc, char **argv);
int cs_cmd_resume(int argc, char **argv);
int cs_cmd_cancel(int argc, char **argv);

/* curvestep home | jog | probe | unlock --port DEV [--baud N] [--machine FILE.ini] ...: the
 * machine-control commands (host/cs_ctl_cmd.c) */
int cs_cmd_home(int argc, char **argv);
int cs_cmd_jog(int argc, char **argv);
int cs_cmd_probe(int argc, char **argv);
int cs_cmd_unlock(int argc, char **argv);
int cs_cmd_spindle(int argc, char **argv);

#endif
