/* cs_ctlcfg: [homing], [limits], [probe], [spindle] -> cs_ctlcfg_t, every value range-checked. */
#include "cs_ctlcfg.h"

#include <ini.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "cs_conv.h"
#include "cs_machine_ini.h"

static const char *const axis_names[CS_AXES] = {"x", "y", "z", "a"};

typedef struct {
    cs_ctlcfg_t *c;
    const cs_machine_t *m;
    char reason[200];
} ctx_t;

void cs_ctlcfg_default(cs_ctlcfg_t *c)
{
    memset(c, 0, sizeof *c);
    c->seek = 20;
    c->latch = 2;
    c->pulloff = 1;
    c->s_max = 1000;
}

bool cs_ctlcfg_section(const char *section)
{
    return strcasecmp(section, "homing") == 0 || strcasecmp(section, "limits") == 0 ||
           strcasecmp(section, "probe") == 0 || strcasecmp(section, "spindle") == 0;
}

static int fail(ctx_t *x, const char *section, const char *name, const char *what)
{
    if (x->reason[0] == '\0')
        snprintf(x->reason, sizeof x->reason, "[%s] %s: %s", section, name, what);
    return 0;
}

/* The axis a key names ("x", "x_pos", "x_min": prefix then suffix), or -1. */
static int axis_of(const char *name, const char *suffix)
{
    for (int i = 0; i < CS_AXES; i++) {
        size_t n = strlen(axis_names[i]);
        if (strncasecmp(name, axis_names[i], n) == 0 && strcasecmp(name + n, suffix) == 0)
            return i;
    }
    return -1;
}

static int order_key(ctx_t *x, const char *sec, const char *name, const char *v)
{
    cs_ctlcfg_t *c = x->c;
    c->n_order = 0;
    for (const char *p = v; *p; p++) {
        if (*p == ' ' || *p == ',')
            continue;
        int ax = -1;
        for (int i = 0; i < CS_AXES; i++)
            if (*p == axis_names[i][0] || *p == axis_names[i][0] - 'a' + 'A')
                ax = i;
        if (ax < 0 || ax >= x->m->n_axes || ax > 2)
            return fail(x, sec, name, "expected axis letters among x, y, z (e.g. zxy)");
        for (unsigned k = 0; k < c->n_order; k++)
            if (c->order[k] == ax)
                return fail(x, sec, name, "an axis is named twice");
        c->order[c->n_order++] = (uint8_t)ax;
    }
    return c->n_order > 0 ? 1 : fail(x, sec, name, "expected axis letters (e.g. zxy)");
}

static int homing_key(ctx_t *x, const char *sec, const char *name, const char *v)
{
    cs_ctlcfg_t *c = x->c;
    if (strcasecmp(name, "order") == 0)
        return order_key(x, sec, name, v);
    int ax = axis_of(name, "");
    if (ax >= 0) {
        if (strcasecmp(v, "min") != 0 && strcasecmp(v, "max") != 0)
            return fail(x, sec, name, "expected min or max");
        c->at_max[ax] = strcasecmp(v, "max") == 0;
        return 1;
    }
    double d;
    if (!cs_machine_ini_number(v, &d))
        return fail(x, sec, name, "not a number");
    if ((ax = axis_of(name, "_pos")) >= 0) {
        if (fabs(d) > CS_POS_LIMIT_MM)
            return fail(x, sec, name, "must be in [-4096, 4096] mm");
        c->has_pos[ax] = true;
        c->pos[ax] = d;
        return 1;
    }
    double *dst = strcasecmp(name, "seek") == 0      ? &c->seek
                  : strcasecmp(name, "latch") == 0   ? &c->latch
                  : strcasecmp(name, "pulloff") == 0 ? &c->pulloff
                  : strcasecmp(name, "search") == 0  ? &c->search
                                                     : NULL;
    if (dst == NULL)
        return fail(x, sec, name,
                    "unknown key (expected order, seek, latch, pulloff, search, x, x_pos, ...)");
    bool speed = dst == &c->seek || dst == &c->latch;
    if (speed ? !(d > 0 && d <= 4096) : !(d >= 0 && d <= 1000))
        return fail(x, sec, name, speed ? "must be in (0, 4096] mm/s" : "must be in [0, 1000] mm");
    *dst = d;
    return 1;
}

static int limits_key(ctx_t *x, const char *sec, const char *name, const char *v)
{
    cs_ctlcfg_t *c = x->c;
    int lo = axis_of(name, "_min"), hi = axis_of(name, "_max");
    double d;
    if (lo < 0 && hi < 0)
        return fail(x, sec, name, "unknown key (expected x_min, x_max, y_min, ... a_max)");
    if (!cs_machine_ini_number(v, &d) || fabs(d) > CS_POS_LIMIT_MM)
        return fail(x, sec, name, "must be a position in [-4096, 4096] mm");
    if (lo >= 0) {
        c->has_min[lo] = true;
        c->min_mm[lo] = d;
    } else {
        c->has_max[hi] = true;
        c->max_mm[hi] = d;
    }
    return 1;
}

static int handler(void *user, const char *section, const char *name, const char *value)
{
    ctx_t *x = user;
    cs_ctlcfg_t *c = x->c;
    double d;
    if (strcasecmp(section, "homing") == 0)
        return homing_key(x, section, name, value);
    if (strcasecmp(section, "limits") == 0)
        return limits_key(x, section, name, value);
    if (strcasecmp(section, "probe") == 0) {
        if (strcasecmp(name, "z") != 0)
            return fail(x, section, name, "unknown key (expected z)");
        if (!cs_machine_ini_number(value, &d) || fabs(d) > CS_POS_LIMIT_MM)
            return fail(x, section, name, "must be a position in [-4096, 4096] mm");
        c->has_probe = true;
        c->probe_z = d;
        return 1;
    }
    if (strcasecmp(section, "spindle") == 0) {
        if (strcasecmp(name, "laser") == 0) {
            int b = cs_machine_ini_bool(value);
            if (b < 0)
                return fail(x, section, name, "expected true or false");
            c->laser = b == 1;
            return 1;
        }
        if (strcasecmp(name, "s_max") != 0)
            return fail(x, section, name, "unknown key (expected laser, s_max)");
        if (!cs_machine_ini_number(value, &d) || !(d > 0 && d <= 1e6))
            return fail(x, section, name, "must be in (0, 1000000]");
        c->s_max = d;
        return 1;
    }
    return 1; /* the machine's own sections: cs_machine_ini's business */
}

static int finish(ctx_t *x, int r, const char *name, char *err, size_t errlen)
{
    if (r == 0)
        return 0;
    if (r < 0)
        snprintf(err, errlen, "%s:0: cannot read the file", name);
    else
        snprintf(err, errlen, "%s:%d: %s", name, r, x->reason[0] ? x->reason : "syntax error");
    return -1;
}

int cs_ctlcfg_load(const char *path, const cs_machine_t *m, cs_ctlcfg_t *c, char *err,
                   size_t errlen)
{
    cs_ctlcfg_default(c);
    if (path == NULL)
        return 0;
    ctx_t x = {c, m, {0}};
    return finish(&x, ini_parse(path, handler, &x), path, err, errlen);
}

int cs_ctlcfg_parse(const char *text, const char *name, const cs_machine_t *m, cs_ctlcfg_t *c,
                    char *err, size_t errlen)
{
    cs_ctlcfg_default(c);
    ctx_t x = {c, m, {0}};
    return finish(&x, ini_parse_string(text, handler, &x), name, err, errlen);
}

cs_err_t cs_ctlcfg_home_msg(const cs_ctlcfg_t *c, const cs_machine_t *m, unsigned k,
                            cs_proto_msg_t *out)
{
    if (k >= c->n_order)
        return CS_ERR_ARG;
    unsigned ax = c->order[k];
    const cs_axis_cfg_t *a = &m->axis[ax];
    double lo = (double)a->travel_min / CS_POS_ONE_MM, hi = (double)a->travel_max / CS_POS_ONE_MM;
    double search = c->search > 0 ? c->search : 1.5 * (hi - lo);
    if (search > CS_POS_LIMIT_MM)
        search = CS_POS_LIMIT_MM;
    double pos = c->has_pos[ax] ? c->pos[ax] : c->at_max[ax] ? hi : lo;
    memset(out, 0, sizeof *out);
    out->type = CS_PROTO_HOME;
    cs_proto_home_t *h = &out->u.home;
    h->axis = (uint8_t)ax;
    h->flags = c->at_max[ax] ? CS_PROTO_HOME_MAX : 0;
    /* mm and mm/s are both Q15.16 (CS_MOTION_ONE = CS_POS_ONE_MM) */
    if (cs_conv_mm_to_pos(c->seek, &h->seek) != CS_OK ||
        cs_conv_mm_to_pos(c->latch, &h->latch) != CS_OK ||
        cs_conv_mm_to_pos(c->pulloff, &h->pulloff) != CS_OK ||
        cs_conv_mm_to_pos(search, &h->search) != CS_OK ||
        cs_conv_mm_to_pos(pos, &h->home_pos) != CS_OK)
        return CS_ERR_RANGE;
    uint8_t buf[CS_PROTO_LEN_MAX];
    size_t n;
    return cs_proto_encode(out, buf, sizeof buf, &n); /* the protocol's own range checks */
}

uint16_t cs_ctlcfg_inputs(const cs_ctlcfg_t *c, const double mm[CS_AXES])
{
    uint16_t b = 0;
    for (unsigned i = 0; i < CS_AXES; i++) {
        if (c->has_min[i] && mm[i] <= c->min_mm[i])
            b |= CS_PROTO_IN_MIN(i);
        if (c->has_max[i] && mm[i] >= c->max_mm[i])
            b |= CS_PROTO_IN_MAX(i);
    }
    if (c->has_probe && mm[CS_AXIS_Z] <= c->probe_z)
        b |= CS_PROTO_IN_PROBE;
    return b;
}

bool cs_ctlcfg_has_inputs(const cs_ctlcfg_t *c)
{
    for (unsigned i = 0; i < CS_AXES; i++)
        if (c->has_min[i] || c->has_max[i])
            return true;
    return c->has_probe;
}

const char *cs_ctlcfg_alarm_text(uint8_t code)
{
    static const char *const t[] = {
        "?",
        "hard limit: a limit switch tripped",
        "soft limit: a target outside the machine's travel",
        "aborted during a cycle",
        "probe: already in the state sought at the start",
        "probe: no contact within the move",
        "homing: reset during the cycle",
        "homing: door open",
        "homing: the switch still active after the pull-off",
        "homing: the switch not found within the search distance",
        "e-stop pressed",
    };
    return code < sizeof t / sizeof t[0] ? t[code] : "?";
}
