/* cs_input: format detection and dispatch to the readers (see cs_input.h). */
#include "cs_input.h"

#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cs_curvefile.h"
#include "cs_dxf.h"
#include "cs_gcode.h"
#include "cs_hpgl.h"
#include "cs_readall.h"
#include "cs_svgdoc.h"

void cs_input_opts_init(cs_input_opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->helix_tol_mm = CS_GCODE_HELIX_TOL_MM;
}

const char *cs_input_format_name(cs_input_format_t f)
{
    switch (f) {
    case CS_INPUT_SVG:
        return "svg";
    case CS_INPUT_GCODE:
        return "gcode";
    case CS_INPUT_HPGL:
        return "hpgl";
    case CS_INPUT_CURVES:
        return "curves";
    case CS_INPUT_DXF:
        return "dxf";
    default:
        return "auto";
    }
}

static cs_input_format_t by_extension(const char *filename)
{
    static const struct {
        const char *ext;
        cs_input_format_t f;
    } exts[] = {
        {"svg", CS_INPUT_SVG},  {"txt", CS_INPUT_SVG},       {"d", CS_INPUT_SVG},
        {"nc", CS_INPUT_GCODE}, {"gcode", CS_INPUT_GCODE},   {"ngc", CS_INPUT_GCODE},
        {"g", CS_INPUT_GCODE},  {"tap", CS_INPUT_GCODE},     {"cnc", CS_INPUT_GCODE},
        {"plt", CS_INPUT_HPGL}, {"hpgl", CS_INPUT_HPGL},     {"hgl", CS_INPUT_HPGL},
        {"hpg", CS_INPUT_HPGL}, {"curves", CS_INPUT_CURVES}, {"dxf", CS_INPUT_DXF},
    };
    if (!filename || strcmp(filename, "-") == 0)
        return CS_INPUT_AUTO;
    const char *slash = strrchr(filename, '/');
    const char *base = slash ? slash + 1 : filename;
    const char *dot = strrchr(base, '.');
    if (!dot || dot == base)
        return CS_INPUT_AUTO;
    for (size_t i = 0; i < sizeof exts / sizeof exts[0]; i++)
        if (strcasecmp(dot + 1, exts[i].ext) == 0)
            return exts[i].f;
    return CS_INPUT_AUTO;
}

static bool is_upper(char c)
{
    return c >= 'A' && c <= 'Z';
}

static bool is_digit(char c)
{
    return c >= '0' && c <= '9';
}

/* Content: '<' first -> SVG; two capital letters then ';', a digit, a sign or the end
 * (IN; PU0,0; SP1) -> HP-GL; '%', '(', ';', '/', a G N T F S X Y word, an O program number or
 * an M word with fewer than two numbers on its line -> G-code; anything else -> bare SVG path
 * data (M 0 0 L ...). */
cs_input_format_t cs_input_detect(const char *filename, const char *buf, size_t len)
{
    cs_input_format_t f = by_extension(filename);
    if (f != CS_INPUT_AUTO)
        return f;
    if (cs_curvefile_is(buf, len))
        return CS_INPUT_CURVES;
    if (cs_dxf_is(buf, len))
        return CS_INPUT_DXF;
    size_t i = cs_readall_bom(buf, len);
    while (i < len && (buf[i] == ' ' || buf[i] == '\t' || buf[i] == '\r' || buf[i] == '\n'))
        i++;
    if (i == len)
        return CS_INPUT_SVG;
    char c = buf[i];
    if (c == '<')
        return CS_INPUT_SVG;
    if (c == '%' || c == '(' || c == ';' || c == '/')
        return CS_INPUT_GCODE;
    if (i + 1 < len && is_upper(c) && is_upper(buf[i + 1]) &&
        (i + 2 == len || buf[i + 2] == ';' || is_digit(buf[i + 2]) || buf[i + 2] == '-' ||
         buf[i + 2] == '+' || buf[i + 2] == '\n' || buf[i + 2] == '\r' || is_upper(buf[i + 2])))
        return CS_INPUT_HPGL;
    /* A G-code word (letter, optional blanks, number) that path data never starts with: path
     * data begins with a moveto (M or m) and then two coordinates. */
    char u = (char)(c & ~0x20);
    if (u == 'G' || u == 'N' || u == 'T' || u == 'F' || u == 'S' || u == 'X' || u == 'Y')
        return CS_INPUT_GCODE;
    if (u == 'O' && i + 1 < len && is_digit(buf[i + 1]))
        return CS_INPUT_GCODE; /* a program number, O1000 */
    if (u == 'M') {
        /* "M3", "M30", "M2 (end)" are G-code; "M 0 0", "M0,0", "M0 0" are path data: count the
         * numbers on the first line before any other letter. */
        size_t j = i + 1;
        unsigned nums = 0;
        while (j < len && buf[j] != '\n' && buf[j] != '\r') {
            if (is_digit(buf[j]) || buf[j] == '.') {
                /* One number: digits, then at most one '.' and its digits (".5.5" is two). */
                nums++;
                while (j < len && is_digit(buf[j]))
                    j++;
                if (j < len && buf[j] == '.')
                    j++;
                while (j < len && is_digit(buf[j]))
                    j++;
                continue;
            }
            if ((buf[j] & ~0x20) >= 'A' && (buf[j] & ~0x20) <= 'Z')
                break;
            j++;
        }
        return nums >= 2 ? CS_INPUT_SVG : CS_INPUT_GCODE;
    }
    return CS_INPUT_SVG;
}

/* The stroke font for text: --font FILE (an error when it is not a font), else the shipped
 * default when found (else none: text is skipped with a warning). *have: f was loaded. */
static cs_err_t load_font(const cs_input_opts_t *o, cs_hershey_font_t *f, bool *have,
                          cs_path_diag_t *diag)
{
    char def[4096];
    *have = false;
    if (o->font_file != NULL) {
        cs_err_t e = cs_hershey_load(o->font_file, f, diag);
        *have = e == CS_OK;
        return e;
    }
    *have = cs_hershey_default_path(def, sizeof def) && cs_hershey_load(def, f, diag) == CS_OK;
    return CS_OK;
}

/* SVG, HP-GL and DXF: the drawing readers, with the stroke font for their text. */
static cs_err_t parse_drawing(cs_input_format_t fmt, const char *name, const char *buf, size_t len,
                              const cs_input_opts_t *o, cs_path_t *path, cs_path_diag_t *diag)
{
    cs_hershey_font_t font;
    bool have;
    cs_err_t e = load_font(o, &font, &have, diag);
    if (e != CS_OK)
        return e;
    if (fmt == CS_INPUT_HPGL) {
        cs_hpgl_opts_t ho;
        cs_hpgl_opts_init(&ho);
        ho.warn = o->warn;
        ho.warn_ctx = o->warn_ctx;
        ho.font = have ? &font : NULL;
        e = cs_hpgl_read(name, buf, len, &ho, path, diag);
    } else if (fmt == CS_INPUT_DXF) {
        cs_dxf_opts_t xo;
        cs_dxf_opts_init(&xo);
        xo.warn = o->warn;
        xo.warn_ctx = o->warn_ctx;
        xo.font = have ? &font : NULL;
        xo.unit_mm = o->units == CS_UNITS_INCH ? 25.4 : o->units == CS_UNITS_MM ? 1.0 : 0.0;
        e = cs_dxf_read(name, buf, len, &xo, path, diag);
    } else {
        cs_svgdoc_opts_t so;
        cs_svgdoc_opts_init(&so);
        so.warn = o->warn;
        so.warn_ctx = o->warn_ctx;
        so.font = have ? &font : NULL;
        e = cs_svgdoc_read(buf, len, name, &so, path, diag, NULL);
    }
    if (have)
        cs_hershey_free(&font);
    return e;
}

static cs_err_t parse_format(const char *name, const char *buf, size_t len,
                             const cs_input_opts_t *o, cs_path_t *path, cs_path_diag_t *diag)
{
    cs_input_opts_t dflt;
    if (!o) {
        cs_input_opts_init(&dflt);
        o = &dflt;
    }
    cs_input_format_t f = o->format != CS_INPUT_AUTO ? o->format : cs_input_detect(name, buf, len);
    if (o->detected != NULL)
        *o->detected = f;
    switch (f) {
    case CS_INPUT_GCODE: {
        cs_gcode_opts_t go;
        cs_gcode_opts_init(&go);
        go.lenient = o->lenient;
        if (o->helix_tol_mm > 0)
            go.helix_tol_mm = o->helix_tol_mm;
        go.pen_z = o->pen_z;
        go.pen_down_z_mm = o->pen_down_z_mm;
        go.pen_up_z_mm = o->pen_up_z_mm;
        go.pen_z_feed_mm_s = o->pen_z_feed_mm_s;
        go.dialect = o->dialect == CS_DIALECT_GRBL ? CS_GCODE_GRBL : CS_GCODE_LINUXCNC;
        go.start_inch = o->units == CS_UNITS_INCH;
        go.warn = o->warn;
        go.warn_ctx = o->warn_ctx;
        return cs_gcode_read(name, buf, len, &go, path, diag, NULL);
    }
    case CS_INPUT_CURVES:
        return cs_curvefile_parse(name, buf, len, path, diag);
    case CS_INPUT_HPGL:
    default:
        return parse_drawing(f, name, buf, len, o, path, diag);
    }
}

cs_err_t cs_input_parse(const char *name, const char *buf, size_t len, const cs_input_opts_t *o,
                        cs_path_t *path, cs_path_diag_t *diag)
{
    size_t before = path->n;
    cs_err_t e = parse_format(name, buf, len, o, path, diag);
    if (cs_path_over_limit(path, diag)) /* whatever the reader said about the refused element */
        return CS_ERR_RANGE;
    if (e == CS_OK && path->n == before) { /* empty, BOM only, comments only: never silence */
        cs_path_loc_t loc = {name ? name : "-", 1, 1};
        return cs_path_diag_set(diag, CS_ERR_EMPTY, loc,
                                "no drawable geometry (the %s input is empty or holds nothing "
                                "curvestep draws)",
                                cs_input_format_name(o && o->format != CS_INPUT_AUTO
                                                         ? o->format
                                                         : cs_input_detect(name, buf, len)));
    }
    return e;
}

cs_err_t cs_input_load(const char *filename, const cs_input_opts_t *o, cs_path_t *path,
                       cs_path_diag_t *diag)
{
    char *buf = NULL;
    size_t len = 0;
    cs_err_t e = cs_readall(filename, o ? o->max_bytes : 0, o && o->regular_only, &buf, &len, diag);
    if (e != CS_OK)
        return e;
    bool is_stdin = strcmp(filename, "-") == 0;
    cs_input_opts_t oo;
    if (o)
        oo = *o;
    else
        cs_input_opts_init(&oo);
    if (oo.format == CS_INPUT_AUTO)
        oo.format = cs_input_detect(is_stdin ? NULL : filename, buf, len);
    e = cs_input_parse(is_stdin ? "<stdin>" : filename, buf, len, &oo, path, diag);
    free(buf);
    return e;
}
