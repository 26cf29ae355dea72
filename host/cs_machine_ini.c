/* cs_machine_ini: INI machine file -> cs_machine_t, every value range-checked. */
#include "cs_machine_ini.h"

#include "cs_ctlcfg.h"

#include <errno.h>
#include <ini.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "cs_conv.h"
#include "cs_err_text.h"
#include "cs_planner.h"
#include "cs_readall.h"

/* A machine file is a few dozen lines: 1 MiB is far above any (cs_readall's limit). */
#define CS_MACHINE_INI_MAX_BYTES ((size_t)1 << 20)

typedef struct {
    cs_machine_t *m;
    double pulse_us[CS_AXES];
    double segment_ms;
    bool has_a;
    cs_machine_pen_t pen;
    bool has_up_z, has_down_z, has_up_us, has_down_us;
    char reason[200];
    int bad_line;     /* the line reason is about (the first key the handler refused) */
    int lineno;       /* lines read so far (text_reader): the line the handler is given */
    const char *text; /* the rest of the file (text_reader) */
} ini_ctx_t;

static const char *const axis_names[CS_AXES] = {"x", "y", "z", "a"};

void cs_machine_ini_default(cs_machine_t *m)
{
    memset(m, 0, sizeof *m);
    m->n_axes = 3;
    for (unsigned i = 0; i < CS_AXES; i++) {
        cs_axis_cfg_t *a = &m->axis[i];
        a->steps_per_mm = 80 * CS_MOTION_ONE;
        a->max_rate = (i == CS_AXIS_Z ? 50 : 200) * CS_MOTION_ONE;
        a->max_accel = (i == CS_AXIS_Z ? 500 : 1000) * CS_MOTION_ONE;
        a->travel_min = (i == CS_AXIS_Z ? -100 : -1000) * CS_POS_ONE_MM;
        a->travel_max = (i == CS_AXIS_Z ? 100 : 1000) * CS_POS_ONE_MM;
        a->invert_dir = false;
        a->pulse_ticks = 1;
    }
    m->tick_hz = 100000;
    m->segment_ticks = 500;
    m->tolerance = CS_POS_ONE_MM / 100;
    m->junction_deviation = CS_POS_ONE_MM / 100;
    m->default_feed = 50 * CS_MOTION_ONE;
    m->profile = CS_PROFILE_TRAPEZOID;
    m->max_jerk = 100000;
}

double cs_machine_ini_to_double(int32_t q16)
{
    return (double)q16 / CS_MOTION_ONE;
}

static bool parse_num(const char *v, double *out)
{
    /* decimal only: strtod would also take "0x10" (16), "inf" and "nan" */
    for (const char *p = v; *p != '\0'; p++)
        if (strchr("0123456789+-.eE \t", *p) == NULL)
            return false;
    char *end;
    errno = 0;
    double d = strtod(v, &end);
    while (*end == ' ' || *end == '\t')
        end++;
    if (end == v || *end != '\0' || errno != 0 || !isfinite(d))
        return false;
    *out = d;
    return true;
}

bool cs_machine_ini_number(const char *v, double *out)
{
    return parse_num(v, out);
}

int cs_machine_ini_bool(const char *v)
{
    if (strcasecmp(v, "true") == 0 || strcmp(v, "1") == 0 || strcasecmp(v, "yes") == 0)
        return 1;
    if (strcasecmp(v, "false") == 0 || strcmp(v, "0") == 0 || strcasecmp(v, "no") == 0)
        return 0;
    return -1;
}

/* Positive Q15.16 value in (0, 32768). */
static bool to_q16_pos(double d, int32_t *out)
{
    double q = d * CS_MOTION_ONE;
    if (!(d > 0) || q >= 2147483647.0)
        return false;
    *out = (int32_t)llround(q);
    if (*out < 1)
        *out = 1;
    return true;
}

static int fail(ini_ctx_t *c, const char *fmt, const char *section, const char *name)
{
    if (c->reason[0] == '\0') { /* libinih reports the first bad line: keep its reason */
        snprintf(c->reason, sizeof c->reason, fmt, section, name);
        c->bad_line = c->lineno;
    }
    return 0;
}

static int handler(void *user, const char *section, const char *name, const char *value);

/* ini_reader over c->text (fgets-like: at most num - 1 bytes, up to a newline), counting lines so
 * the handler knows which line it is given (libinih passes no line number to it). */
static char *text_reader(char *str, int num, void *stream)
{
    ini_ctx_t *c = stream;
    if (*c->text == '\0' || num < 2)
        return NULL;
    int k = 0;
    while (k < num - 1 && c->text[k] != '\0' && (k == 0 || c->text[k - 1] != '\n'))
        k++;
    memcpy(str, c->text, (size_t)k);
    str[k] = '\0';
    c->text += k;
    if (str[k - 1] == '\n' || *c->text == '\0')
        c->lineno++; /* a line longer than num - 1 is one line read in pieces */
    return str;
}

/* ini_parse_string with line numbers for the handler's errors. */
static int parse_text(ini_ctx_t *c, const char *text)
{
    c->text = text;
    c->lineno = 0;
    return ini_parse_stream(text_reader, c, handler, c);
}

void cs_machine_ini_pen_default(cs_machine_pen_t *pen)
{
    memset(pen, 0, sizeof *pen);
    pen->mode = CS_MACHINE_PEN_NONE;
    pen->settle_ms = 150; /* a hobby servo's 60-degree move at 0.1-0.15 s, plus margin */
}

/* [pen] servo keys: up_us, down_us (pulse widths), settle_ms. -1: not one of them. */
static int servo_key(ini_ctx_t *c, const char *section, const char *name, const char *value)
{
    double d;
    bool up = strcasecmp(name, "up_us") == 0, down = strcasecmp(name, "down_us") == 0;
    if (up || down) {
        if (!parse_num(value, &d) || d < CS_MACHINE_SERVO_MIN_US || d > CS_MACHINE_SERVO_MAX_US ||
            d != floor(d))
            return fail(c, "[%s] %s: must be a whole number of microseconds in [400, 2600]",
                        section, name);
        *(up ? &c->pen.up_us : &c->pen.down_us) = (unsigned)d;
        *(up ? &c->has_up_us : &c->has_down_us) = true;
        return 1;
    }
    if (strcasecmp(name, "settle_ms") == 0) {
        if (!parse_num(value, &d) || !(d >= 0) || d > CS_MACHINE_SERVO_MAX_SETTLE_MS)
            return fail(c, "[%s] %s: must be a time in [0, 5000] ms", section, name);
        c->pen.settle_ms = d;
        return 1;
    }
    return -1;
}

/* [pen]: mode = none | z | servo, up_z, down_z (mm), z_feed (mm/s), servo keys above. */
static int pen_key(ini_ctx_t *c, const char *section, const char *name, const char *value)
{
    double d;
    cs_pos_t q;
    if (strcasecmp(name, "mode") == 0) {
        if (strcasecmp(value, "none") == 0)
            c->pen.mode = CS_MACHINE_PEN_NONE;
        else if (strcasecmp(value, "z") == 0)
            c->pen.mode = CS_MACHINE_PEN_Z;
        else if (strcasecmp(value, "servo") == 0)
            c->pen.mode = CS_MACHINE_PEN_SERVO;
        else
            return fail(c, "[%s] %s: expected none, z or servo", section, name);
        return 1;
    }
    int servo = servo_key(c, section, name, value);
    if (servo >= 0)
        return servo;
    if (strcasecmp(name, "z_feed") == 0) {
        /* 32768 mm/s: the Q15.16 speed's range (cs_motion_speed), as --feed */
        if (!parse_num(value, &d) || !(d >= 0) || d >= 32768)
            return fail(c, "[%s] %s: must be a speed in [0, 32768) mm/s (0: rapid)", section, name);
        c->pen.z_feed_mm_s = d;
        return 1;
    }
    bool up = strcasecmp(name, "up_z") == 0;
    if (!up && strcasecmp(name, "down_z") != 0)
        return fail(c,
                    "[%s] %s: unknown key (expected mode, up_z, down_z, z_feed, up_us, down_us "
                    "or settle_ms)",
                    section, name);
    if (!parse_num(value, &d) || cs_conv_mm_to_pos(d, &q) != CS_OK)
        return fail(c, "[%s] %s: must be a number in [-4096, 4096] mm", section, name);
    if (up) {
        c->pen.up_z_mm = d;
        c->has_up_z = true;
    } else {
        c->pen.down_z_mm = d;
        c->has_down_z = true;
    }
    return 1;
}

/* A key of [machine]. */
static int machine_key(ini_ctx_t *c, const char *section, const char *name, const char *value)
{
    cs_machine_t *m = c->m;
    double d;
    if (strcasecmp(name, "profile") == 0) {
        if (strcasecmp(value, "trapezoid") == 0)
            m->profile = CS_PROFILE_TRAPEZOID;
        else if (strcasecmp(value, "scurve") == 0)
            m->profile = CS_PROFILE_SCURVE;
        else
            return fail(c, "[%s] %s: expected trapezoid or scurve", section, name);
        return 1;
    }
    if (!parse_num(value, &d))
        return fail(c, "[%s] %s: not a number", section, name);
    if (strcasecmp(name, "axes") == 0) {
        if (d != 3 && d != 4)
            return fail(c, "[%s] %s: must be 3 or 4", section, name);
        m->n_axes = (uint8_t)d;
        c->has_a = d == 4;
    } else if (strcasecmp(name, "tick_hz") == 0) {
        if (d < 1000 || d > 16e6 || d != floor(d))
            return fail(c, "[%s] %s: must be an integer in 1000..16000000", section, name);
        m->tick_hz = (uint32_t)d;
    } else if (strcasecmp(name, "segment_ms") == 0) {
        if (!(d > 0) || d > 1000)
            return fail(c, "[%s] %s: must be in (0, 1000] ms", section, name);
        c->segment_ms = d;
    } else if (strcasecmp(name, "tolerance") == 0) {
        if (cs_conv_tol_to_pos(d, &m->tolerance) != CS_OK)
            return fail(c, "[%s] %s: must be in [1/65536, 4096] mm", section, name);
    } else if (strcasecmp(name, "junction_deviation") == 0) {
        if (!(d >= 0) || cs_conv_mm_to_pos(d, &m->junction_deviation) != CS_OK)
            return fail(c, "[%s] %s: must be in [0, 4096] mm", section, name);
    } else if (strcasecmp(name, "default_feed") == 0) {
        if (!to_q16_pos(d, &m->default_feed))
            return fail(c, "[%s] %s: must be in (0, 32768) mm/s", section, name);
    } else if (strcasecmp(name, "max_jerk") == 0) {
        if (!(d >= 1) || d > 2e9)
            return fail(c, "[%s] %s: must be in [1, 2e9] mm/s^3", section, name);
        m->max_jerk = (int32_t)d;
    } else {
        return fail(c, "[%s] %s: unknown key", section, name);
    }
    return 1;
}

/* A key of axis section ax ([x], [y], [z], [a]). */
static int axis_key(ini_ctx_t *c, int ax, const char *section, const char *name,
                    const char *value)
{
    double d;
    cs_axis_cfg_t *a = &c->m->axis[ax];
    if (strcasecmp(name, "invert_dir") == 0) {
        if (strcasecmp(value, "true") == 0 || strcmp(value, "1") == 0 ||
            strcasecmp(value, "yes") == 0)
            a->invert_dir = true;
        else if (strcasecmp(value, "false") == 0 || strcmp(value, "0") == 0 ||
                 strcasecmp(value, "no") == 0)
            a->invert_dir = false;
        else
            return fail(c, "[%s] %s: expected true or false", section, name);
        return 1;
    }
    if (!parse_num(value, &d))
        return fail(c, "[%s] %s: not a number", section, name);
    if (strcasecmp(name, "steps_per_mm") == 0) {
        if (!(d >= 1.0 / 16) || d > 4096 || !to_q16_pos(d, &a->steps_per_mm))
            return fail(c, "[%s] %s: must be in [1/16, 4096]", section, name);
    } else if (strcasecmp(name, "max_rate") == 0) {
        if (!to_q16_pos(d, &a->max_rate))
            return fail(c, "[%s] %s: must be in (0, 32768) mm/s", section, name);
    } else if (strcasecmp(name, "max_accel") == 0) {
        if (!to_q16_pos(d, &a->max_accel))
            return fail(c, "[%s] %s: must be in (0, 32768) mm/s^2", section, name);
    } else if (strcasecmp(name, "travel_min") == 0) {
        if (cs_conv_mm_to_pos(d, &a->travel_min) != CS_OK)
            return fail(c, "[%s] %s: must be in [-4096, 4096] mm", section, name);
    } else if (strcasecmp(name, "travel_max") == 0) {
        if (cs_conv_mm_to_pos(d, &a->travel_max) != CS_OK)
            return fail(c, "[%s] %s: must be in [-4096, 4096] mm", section, name);
    } else if (strcasecmp(name, "pulse_us") == 0) {
        if (!(d > 0) || d > 10000)
            return fail(c, "[%s] %s: must be in (0, 10000] us", section, name);
        c->pulse_us[ax] = d;
    } else {
        return fail(c, "[%s] %s: unknown key", section, name);
    }
    return 1;
}

static int handler(void *user, const char *section, const char *name, const char *value)
{
    ini_ctx_t *c = user;
    cs_machine_t *m = c->m;
    if (strcasecmp(section, "pen") == 0)
        return pen_key(c, section, name, value);
    /* [gpio] (pins of the GPIO link) is read and checked by cs_gpio_cfg in a second pass over
     * the file; the machine itself does not depend on it. */
    if (strcasecmp(section, "gpio") == 0)
        return 1;
    /* [homing], [limits], [probe], [spindle]: machine control, read by cs_ctlcfg likewise */
    if (cs_ctlcfg_section(section))
        return 1;
    if (strcasecmp(section, "machine") == 0)
        return machine_key(c, section, name, value);
    int ax = -1;
    for (int i = 0; i < CS_AXES; i++)
        if (strcasecmp(section, axis_names[i]) == 0)
            ax = i;
    if (ax < 0)
        return fail(c,
                    "[%s]%s: unknown section (expected machine, x, y, z, a, pen, gpio, homing, "
                    "limits, probe or spindle)",
                    section, "");
    if (ax == CS_AXIS_A) {
        c->has_a = true;
        m->n_axes = 4;
    }
    return axis_key(c, ax, section, name, value);
}

static int finish(ini_ctx_t *c, int rc, const char *name, char *err, size_t errlen)
{
    cs_machine_t *m = c->m;
    if (rc < 0) {
        snprintf(err, errlen, "%s:0: cannot read the machine file", name);
        return -1;
    }
    if (rc > 0) { /* rc: the first bad line; the handler's reason only when it is that line's */
        snprintf(err, errlen, "%s:%d: %s", name, rc,
                 c->reason[0] && c->bad_line == rc
                     ? c->reason
                     : "syntax error (expected [section] or key = value)");
        return -1;
    }
    m->segment_ticks = (uint32_t)llround(c->segment_ms * m->tick_hz / 1000.0);
    if (m->segment_ticks < 1)
        m->segment_ticks = 1;
    for (unsigned i = 0; i < CS_AXES; i++) {
        double t = ceil(c->pulse_us[i] * m->tick_hz / 1e6 - 1e-9);
        m->axis[i].pulse_ticks = (uint16_t)(t < 1 ? 1 : t > 65535 ? 65535 : t);
        if (m->axis[i].travel_min > m->axis[i].travel_max) {
            snprintf(err, errlen, "%s:0: [%s] travel_min is above travel_max", name, axis_names[i]);
            return -1;
        }
    }
    if (c->pen.mode == CS_MACHINE_PEN_Z) {
        /* No default heights: a guessed down_z could drive the pen (or a tool) into the bed. */
        if (!c->has_up_z || !c->has_down_z) {
            snprintf(err, errlen, "%s:0: [pen] mode = z needs both up_z and down_z", name);
            return -1;
        }
        if (c->pen.up_z_mm == c->pen.down_z_mm) {
            snprintf(err, errlen, "%s:0: [pen] up_z and down_z are equal: the pen would not move",
                     name);
            return -1;
        }
        double zmin = (double)m->axis[CS_AXIS_Z].travel_min / CS_POS_ONE_MM;
        double zmax = (double)m->axis[CS_AXIS_Z].travel_max / CS_POS_ONE_MM;
        const double zs[2] = {c->pen.up_z_mm, c->pen.down_z_mm};
        for (int k = 0; k < 2; k++)
            if (zs[k] < zmin || zs[k] > zmax) {
                snprintf(err, errlen, "%s:0: [pen] %s = %g mm is outside the z travel [%g, %g] mm",
                         name, k == 0 ? "up_z" : "down_z", zs[k], zmin, zmax);
                return -1;
            }
    }
    if (c->pen.mode == CS_MACHINE_PEN_SERVO) {
        /* No default pulse widths: the wrong one could drive the pen into the paper. */
        if (!c->has_up_us || !c->has_down_us || c->pen.up_us == c->pen.down_us) {
            snprintf(err, errlen, "%s:0: [pen] mode = servo needs up_us and down_us, different",
                     name);
            return -1;
        }
    }
    cs_planner_t pl;
    cs_err_t e = cs_planner_init(&pl, m);
    if (e != CS_OK) {
        snprintf(err, errlen,
                 "%s:0: machine rejected: %s (each axis needs max_rate * steps_per_mm <= "
                 "tick_hz / 2 and a pulse that fits half a step period)",
                 name, cs_err_text(e));
        return -1;
    }
    return 0;
}

static void ctx_init(ini_ctx_t *c, cs_machine_t *m)
{
    memset(c, 0, sizeof *c);
    c->m = m;
    cs_machine_ini_default(m);
    c->segment_ms = 5.0;
    cs_machine_ini_pen_default(&c->pen);
    for (unsigned i = 0; i < CS_AXES; i++)
        c->pulse_us[i] = 2.0;
}

int cs_machine_ini_load_pen(const char *path, cs_machine_t *m, cs_machine_pen_t *pen, char *err,
                            size_t errlen)
{
    /* read whole first (cs_readall: bounded, and a directory is an error, not an empty file
     * that would leave the built-in machine in place) */
    char *text = NULL;
    size_t len = 0;
    cs_path_diag_t d;
    if (cs_readall(path, CS_MACHINE_INI_MAX_BYTES, false, &text, &len, &d) != CS_OK) {
        char file[512];
        cs_path_escape(file, sizeof file, path);
        snprintf(err, errlen, "%s:0: cannot read the machine file: %s", file, d.reason);
        return -1;
    }
    int rc = cs_machine_ini_parse_pen(text, path, m, pen, err, errlen);
    free(text);
    return rc;
}

int cs_machine_ini_parse_pen(const char *text, const char *name, cs_machine_t *m,
                             cs_machine_pen_t *pen, char *err, size_t errlen)
{
    ini_ctx_t c;
    ctx_init(&c, m);
    int rc = finish(&c, parse_text(&c, text), name, err, errlen);
    if (rc == 0 && pen)
        *pen = c.pen;
    return rc;
}

int cs_machine_ini_load(const char *path, cs_machine_t *m, char *err, size_t errlen)
{
    return cs_machine_ini_load_pen(path, m, NULL, err, errlen);
}

int cs_machine_ini_parse(const char *text, const char *name, cs_machine_t *m, char *err,
                         size_t errlen)
{
    return cs_machine_ini_parse_pen(text, name, m, NULL, err, errlen);
}

#ifndef CS_SYSCONFDIR
#define CS_SYSCONFDIR "/etc"
#endif

/* dir/rest into out when dir is set and the file is there. */
static bool found_in(const char *dir, const char *rest, char *out, size_t outlen)
{
    if (dir == NULL || dir[0] == '\0')
        return false;
    int n = snprintf(out, outlen, "%s/%s", dir, rest);
    return n > 0 && (size_t)n < outlen && access(out, R_OK) == 0;
}

bool cs_machine_ini_find(char *out, size_t outlen)
{
    /* XDG Base Directory Specification: $XDG_CONFIG_HOME, else $HOME/.config */
    return found_in(getenv("XDG_CONFIG_HOME"), "curvestep/machine.ini", out, outlen) ||
           found_in(getenv("HOME"), ".config/curvestep/machine.ini", out, outlen) ||
           found_in(CS_SYSCONFDIR, "curvestep/machine.ini", out, outlen);
}

int cs_machine_ini_open(const char *who, const char *given, cs_machine_t *m, cs_machine_pen_t *pen,
                        char *err, size_t errlen)
{
    char found[4096];
    const char *file = given;
    if (file == NULL && cs_machine_ini_find(found, sizeof found))
        file = found;
    if (file == NULL) {
        fprintf(stderr,
                "%s: machine: the built-in machine (no --machine, no machine.ini found; "
                "see docs/plotting.md)\n",
                who);
        cs_machine_ini_default(m);
        if (pen)
            cs_machine_ini_pen_default(pen);
        return 0;
    }
    fprintf(stderr, "%s: machine: %s%s\n", who, file, given ? "" : " (found)");
    return cs_machine_ini_load_pen(file, m, pen, err, errlen);
}
