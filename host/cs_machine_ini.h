/* cs_machine_ini: the machine file. Reads an INI file (libinih) into the core's cs_machine_t
 * (x, y, z and optional a axis: steps/mm, rate, acceleration, travel, DIR inversion, pulse
 * width; tolerance, junction deviation, tick rate, segment time, default feed, profile) and
 * owns the built-in default, a generic 3-axis pen plotter at 80 steps/mm. Also reads the host-only
 * [pen] section (how pen up / down, G-code M3/M4/M5, is carried out). A [gpio] section is
 * accepted and skipped here (host/cs_gpio_cfg.h reads it). Keys: docs/motion.md, docs/gpio.md. */
#ifndef CS_MACHINE_INI_H
#define CS_MACHINE_INI_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_machine.h"

/* How the pen (or spindle) is raised and lowered. Mode z is host-only (Z moves); mode servo
 * becomes pen events in the step segments (cs_motion_segs_t.pens). */
typedef enum {
    CS_MACHINE_PEN_NONE = 0,  /* no pen axis: pen up / down only split the job into subpaths */
    CS_MACHINE_PEN_Z = 1,     /* pen up / down are rapid moves of Z to up_z_mm / down_z_mm */
    CS_MACHINE_PEN_SERVO = 2, /* pen up / down set an RC servo's pulse width, then wait settle_ms */
} cs_machine_pen_mode_t;

typedef struct {
    cs_machine_pen_mode_t mode;
    double up_z_mm;   /* machine Z of the raised pen (mode z), inside [z] travel */
    double down_z_mm; /* machine Z of the lowered pen (mode z), inside [z] travel */
    double z_feed_mm_s;      /* speed of the pen's Z moves (mode z), mm/s; 0: rapid (the default) */
    unsigned up_us, down_us; /* servo pulse widths of the raised / lowered pen (mode servo), us */
    double settle_ms;        /* wait after each servo move before the motion goes on (mode servo) */
} cs_machine_pen_t;

/* RC servo pulse range (the common 1..2 ms with margin) and the longest settle wait. */
#define CS_MACHINE_SERVO_MIN_US        400
#define CS_MACHINE_SERVO_MAX_US        2600
#define CS_MACHINE_SERVO_MAX_SETTLE_MS 5000

/* The default [pen]: mode none (heights 0). */
void cs_machine_ini_pen_default(cs_machine_pen_t *pen);

/* The built-in machine: 3 axes, 80 steps/mm, x/y 200 mm/s and 1000 mm/s^2 over -1000..1000 mm,
 * z 50 mm/s and 500 mm/s^2 over -100..100 mm, 100 kHz ticks, 5 ms segments, tolerance and
 * junction deviation 0.01 mm, default feed 50 mm/s, trapezoid profile. */
void cs_machine_ini_default(cs_machine_t *m);
/* Reads file `path` over the default (keys absent keep their default value; an [a] section adds
 * the a axis) and validates the result with the core's own checks. Returns 0 on success;
 * otherwise writes "file:line: reason" (line 0 when the file cannot be read or the error is
 * about the whole machine) to err and returns -1. */
int cs_machine_ini_load(const char *path, cs_machine_t *m, char *err, size_t errlen);
/* Same, from a string (file name `name` used in messages). */
int cs_machine_ini_parse(const char *text, const char *name, cs_machine_t *m, char *err,
                         size_t errlen);
/* As cs_machine_ini_load / cs_machine_ini_parse, also filling *pen from the [pen] section
 * (cs_machine_ini_pen_default when absent). mode = z needs up_z and down_z, different, both
 * inside the z axis travel; mode = servo needs up_us and down_us (CS_MACHINE_SERVO_MIN_US ..
 * _MAX_US, different), settle_ms (0 .. CS_MACHINE_SERVO_MAX_SETTLE_MS) defaults to 150. (The plain
 * functions read and check [pen] too, and drop it.) */
int cs_machine_ini_load_pen(const char *path, cs_machine_t *m, cs_machine_pen_t *pen, char *err,
                            size_t errlen);
int cs_machine_ini_parse_pen(const char *text, const char *name, cs_machine_t *m,
                             cs_machine_pen_t *pen, char *err, size_t errlen);
/* The machine file used when none is given: the first that exists of
 * $XDG_CONFIG_HOME/curvestep/machine.ini, $HOME/.config/curvestep/machine.ini and
 * CS_SYSCONFDIR/curvestep/machine.ini (/etc by default), written to out; false when none does
 * (the built-in machine). */
bool cs_machine_ini_find(char *out, size_t outlen);
/* The machine of file `given`, or else of cs_machine_ini_find, or else the built-in one, with its
 * [pen] (pen may be NULL); says on stderr which ("WHO: machine: FILE" / "WHO: machine: the
 * built-in machine ...", who e.g. "curvestep plan").
 * Returns 0, or -1 with "file:line: reason" in err (as cs_machine_ini_load_pen). */
int cs_machine_ini_open(const char *who, const char *given, cs_machine_t *m, cs_machine_pen_t *pen,
                        char *err, size_t errlen);
/* A decimal number of the machine file (no hex, inf or nan; blanks after it allowed): true and
 * *out. A boolean: 1 for true / 1 / yes, 0 for false / 0 / no, -1 otherwise. */
bool cs_machine_ini_number(const char *v, double *out);
int cs_machine_ini_bool(const char *v);
/* mm/s (double) <-> the core's Q15.16 motion format. */
double cs_machine_ini_to_double(int32_t q16);

#endif
