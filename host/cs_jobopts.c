/* cs_jobopts: the shared input options and the preparation of a read job (see cs_jobopts.h). */
#include "cs_jobopts.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cs_conv.h"
#include "cs_order.h"

static bool set_lenient(cs_jobopts_t *o, const char *v)
{
    (void)v;
    o->lenient = true;
    return true;
}

static bool set_dialect(cs_jobopts_t *o, const char *v)
{
    o->dialect = strcmp(v, "grbl") == 0 ? CS_DIALECT_GRBL : CS_DIALECT_LINUXCNC;
    return strcmp(v, "grbl") == 0 || strcmp(v, "linuxcnc") == 0;
}

static bool set_units(cs_jobopts_t *o, const char *v)
{
    o->units = strcmp(v, "inch") == 0 ? CS_UNITS_INCH : CS_UNITS_MM;
    return strcmp(v, "inch") == 0 || strcmp(v, "mm") == 0;
}

static bool set_scale(cs_jobopts_t *o, const char *v)
{
    double f;
    o->layout.scale = 1.0;
    if (!cs_conv_number(v, &f) || !(f >= CS_LAYOUT_SCALE_MIN && f <= CS_LAYOUT_SCALE_MAX))
        return false;
    o->layout.scale = f;
    return true;
}

static bool set_fit(cs_jobopts_t *o, const char *v)
{
    (void)v;
    o->layout.fit = true;
    return true;
}

static bool set_page(cs_jobopts_t *o, const char *v)
{
    o->layout.fit = true; /* a page is only used to fit the drawing on */
    return cs_layout_parse_page(v, &o->layout.page_w_mm, &o->layout.page_h_mm);
}

static bool set_margin(cs_jobopts_t *o, const char *v)
{
    return cs_conv_number(v, &o->layout.margin_mm) && o->layout.margin_mm >= 0 &&
           o->layout.margin_mm <= CS_POS_LIMIT_MM;
}

static bool set_translate(cs_jobopts_t *o, const char *v)
{
    const char *comma = strchr(v, ',');
    if (comma == NULL || (size_t)(comma - v) >= 64)
        return false;
    char x[64];
    memcpy(x, v, (size_t)(comma - v));
    x[comma - v] = '\0';
    return cs_conv_number(x, &o->layout.tx_mm) && cs_conv_number(comma + 1, &o->layout.ty_mm) &&
           fabs(o->layout.tx_mm) <= CS_POS_LIMIT_MM && fabs(o->layout.ty_mm) <= CS_POS_LIMIT_MM;
}

static bool set_rotate(cs_jobopts_t *o, const char *v)
{
    static const char *const ok[] = {"0", "90", "180", "270"};
    for (int k = 0; k < 4; k++)
        if (strcmp(v, ok[k]) == 0) {
            o->layout.rotate_deg = 90 * k;
            return true;
        }
    return false;
}

static bool set_flip_y(cs_jobopts_t *o, const char *v)
{
    (void)v;
    o->layout.flip_y = true;
    return true;
}

static bool set_merge(cs_jobopts_t *o, const char *v)
{
    o->merge = v[0] == '1';
    return true;
}

static bool set_sort(cs_jobopts_t *o, const char *v)
{
    o->sort = v[0] == '1';
    return true;
}

/* The table: name, value's name (NULL: a flag; flags pass `flag` to set), what a bad value
 * wants, help. */
static const struct {
    const char *name, *arg, *flag, *want, *help;
    bool (*set)(cs_jobopts_t *o, const char *v);
} table[] = {
    {"lenient", NULL, "", NULL, "G-code: an unsupported word is a warning, not an error",
     set_lenient},
    {"dialect", "D", NULL, "linuxcnc or grbl",
     "G-code dialect: linuxcnc (default) or grbl (docs/inputs.md)", set_dialect},
    {"units", "U", NULL, "mm or inch",
     "units a G-code program starts in: mm (default) or inch;\nfor DXF, the drawing's unit "
     "(overrides $INSUNITS)",
     set_units},
    {"scale", "F", NULL, "a factor in [0.0001, 10000]",
     "scale the drawing by F about the origin (control points,\nexactly)", set_scale},
    {"fit", NULL, "", NULL,
     "scale and centre the drawing's box in the machine's x y\n"
     "travel (or --page), keeping aspect",
     set_fit},
    {"page", "P", NULL, "A3, A4, A5, letter or WxH[mm]",
     "--fit onto a page at the origin: A3 A4 A5 letter (portrait)\nor WxHmm", set_page},
    {"margin", "MM", NULL, "a length in mm, >= 0", "free border kept by --fit (default 0)",
     set_margin},
    {"translate", "X,Y", NULL, "two lengths in mm, X,Y", "move the drawing by X,Y mm (last)",
     set_translate},
    {"rotate", "DEG", NULL, "90, 180 or 270",
     "turn the drawing counter-clockwise, keeping its lower-left\ncorner", set_rotate},
    {"flip-y", NULL, "", NULL,
     "mirror the drawing top to bottom (SVG pages are already\nturned y-up)", set_flip_y},
    {"merge", NULL, "1", NULL,
     "join lines whose ends meet within the tolerance (default: on\n"
     "for a machine with a [pen] mode, docs/plotting.md)",
     set_merge},
    {"no-merge", NULL, "0", NULL, "keep the lines as drawn", set_merge},
    {"sort", NULL, "1", NULL,
     "reorder (and reverse) lines to shorten pen-up travel\n(default as --merge)", set_sort},
    {"no-sort", NULL, "0", NULL, "keep the file's order", set_sort},
};

#define NTABLE (sizeof table / sizeof table[0])

void cs_jobopts_init(cs_jobopts_t *o)
{
    memset(o, 0, sizeof *o);
    o->dialect = CS_DIALECT_LINUXCNC;
    o->units = CS_UNITS_DEFAULT;
    cs_layout_opts_init(&o->layout);
    o->merge = o->sort = -1;
}

static int find(const char *name, size_t len)
{
    for (size_t k = 0; k < NTABLE; k++)
        if (strlen(table[k].name) == len && strncmp(table[k].name, name, len) == 0)
            return (int)k;
    return -1;
}

/* Records " name[=value]" for SUBMIT; false when it does not fit or the value has a blank. */
static bool record(cs_jobopts_t *o, const char *name, const char *v)
{
    size_t len = strlen(o->words);
    int k =
        snprintf(o->words + len, sizeof o->words - len, " %s%s%s", name, v ? "=" : "", v ? v : "");
    return k > 0 && (size_t)k < sizeof o->words - len && (v == NULL || strpbrk(v, " \t\n") == NULL);
}

int cs_jobopts_option(const char *cmd, int argc, char **argv, int *i, cs_jobopts_t *o)
{
    const char *a = argv[*i];
    if (strncmp(a, "--", 2) != 0)
        return 0;
    int k = find(a + 2, strlen(a + 2));
    if (k < 0 || (table[k].arg != NULL && *i + 1 >= argc))
        return 0;
    const char *v = table[k].arg ? argv[++*i] : NULL;
    if (!table[k].set(o, v ? v : table[k].flag) || !record(o, table[k].name, v)) {
        fprintf(stderr, "curvestep %s: --%s wants %s\n", cmd, table[k].name,
                table[k].want ? table[k].want : "no value");
        return -1;
    }
    return 1;
}

bool cs_jobopts_word(const char *word, cs_jobopts_t *o)
{
    const char *eq = strchr(word, '=');
    int k = find(word, eq ? (size_t)(eq - word) : strlen(word));
    if (k < 0 || (table[k].arg != NULL) != (eq != NULL))
        return false;
    return table[k].set(o, eq ? eq + 1 : table[k].flag) &&
           record(o, table[k].name, eq ? eq + 1 : NULL);
}

int cs_jobopts_check(const char *cmd, const cs_jobopts_t *o)
{
    if (o->layout.fit && o->layout.scale != 1.0) {
        fprintf(stderr, "curvestep %s: --fit (or --page) and --scale exclude each other\n", cmd);
        return -1;
    }
    return 0;
}

void cs_jobopts_help(FILE *f)
{
    fputs("Input and layout options (the same on flatten, plan, stream, submit and\n"
          "curvestep-sim --reference; docs/inputs.md, docs/plotting.md):\n",
          f);
    for (size_t k = 0; k < NTABLE; k++) {
        char head[40];
        snprintf(head, sizeof head, "--%s%s%s", table[k].name, table[k].arg ? " " : "",
                 table[k].arg ? table[k].arg : "");
        fprintf(f, "  %-17s ", head);
        for (const char *h = table[k].help; *h; h++) {
            fputc(*h, f);
            if (*h == '\n')
                fprintf(f, "  %-17s ", "");
        }
        fputc('\n', f);
    }
}

void cs_jobopts_input(const cs_jobopts_t *o, cs_input_opts_t *io)
{
    io->lenient = o->lenient;
    io->dialect = o->dialect;
    io->units = o->units;
}

bool cs_jobopts_merge(const cs_jobopts_t *o, bool plotter)
{
    return o->merge < 0 ? plotter : o->merge == 1;
}

bool cs_jobopts_sort(const cs_jobopts_t *o, bool plotter)
{
    return o->sort < 0 ? plotter : o->sort == 1;
}

cs_err_t cs_jobopts_prepare(const cs_jobopts_t *o, const char *cmd, const cs_machine_t *m,
                            bool plotter, double tol_mm, cs_path_t *p, cs_path_diag_t *diag,
                            FILE *report)
{
    cs_layout_area_t area = {{0, 0}, {o->layout.page_w_mm, o->layout.page_h_mm}};
    if (o->layout.page_w_mm == 0)
        for (int a = 0; a < 2; a++) {
            area.min[a] = cs_conv_pos_to_mm(m->axis[a].travel_min);
            area.max[a] = cs_conv_pos_to_mm(m->axis[a].travel_max);
        }
    cs_err_t e = cs_layout_apply(&o->layout, &area, p, diag);
    cs_order_opts_t oo = {cs_jobopts_merge(o, plotter), cs_jobopts_sort(o, plotter), tol_mm};
    cs_order_stats_t st;
    if (e != CS_OK || (!oo.merge && !oo.sort))
        return e;
    if ((e = cs_order_apply(p, &oo, &st)) != CS_OK) {
        cs_path_loc_t loc = {p->n ? p->elems[0].loc.file : "job", 0, 0};
        return cs_path_diag_set(diag, e, loc, "merge/sort: out of memory");
    }
    if (report != NULL && st.skipped)
        fprintf(report, "%s: merge/sort skipped: the job has travel moves of its own (G0)\n", cmd);
    else if (report != NULL)
        fprintf(report, "%s: %zu pen lifts -> %zu, pen-up travel %.1f mm -> %.1f mm (%s%s%s)\n",
                cmd, st.lifts_before, st.lifts_after, st.travel_before_mm, st.travel_after_mm,
                oo.merge ? "merge" : "", oo.merge && oo.sort ? ", " : "", oo.sort ? "sort" : "");
    return CS_OK;
}
