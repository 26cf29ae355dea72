/* cs_machine_ini: the machine file. Reads an INI file (libinih) into the core's cs_machine_t
 * (x, y, z and optional a axis: steps/mm, rate, acceleration, travel, DIR inversion, pulse
 * width; tolerance, junction deviation, tick rate, segment time, default feed, profile) and
 * owns the built-in default, a generic 3-axis pen plotter at 80 steps/mm. Also reads the host-only
 * [pen] section (how pen up / down, G-code M3/M4/M5, is carried out). A [gpio] section is
 * accepted and skipped here (host/cs_gpio_cfg.h reads it). Keys: docs/motion.md, docs/gpio.md. */
#ifndef CS_MACHINE_INI_H
#define CS_MACHINE_INI_H

#include <stddef.h>

#include "cs_machine.h"

/* How the pen (or spindle) is raised and lowered; host-only, the firmware never sees it. */
typedef enum {
    CS_MACHINE_PEN_NONE = 0, /* no pen axis: pen up / down only split the job into subpaths */
    CS_MACHINE_PEN_Z = 1,    /* pen up / down are rapid moves of Z to up_z_mm / down_z_mm */
} cs_machine_pen_mode_t;

typedef struct {
    cs_machine_pen_mode_t mode;
    double up_z_mm;   /* machine Z of the raised pen (mode z), inside [z] travel */
    double down_z_mm; /* machine Z of the lowered pen (mode z), inside [z] travel */
    double z_feed_mm_s; /* speed of the pen's Z moves (mode z), mm/s; 0: rapid (the default) */
} cs_machine_pen_t;

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
 * inside the z axis travel. (The plain functions read and check [pen] too, and drop it.) */
int cs_machine_ini_load_pen(const char *path, cs_machine_t *m, cs_machine_pen_t *pen, char *err,
                            size_t errlen);
int cs_machine_ini_parse_pen(const char *text, const char *name, cs_machine_t *m,
                             cs_machine_pen_t *pen, char *err, size_t errlen);
/* mm/s (double) <-> the core's Q15.16 motion format. */
double cs_machine_ini_to_double(int32_t q16);

#endif
