/* cs_grbl_gc: G-code one line at a time (see cs_grbl_gc.h). cs_gcode has no line-at-a-time entry
 * point, so each line is read as a tiny program: a preamble that puts cs_gcode's modal state
 * where the previous lines left it, then the line. The preamble's own move (to the current
 * position) is dropped by its line number. The modal words are tracked here with the meaning
 * cs_gcode gives them (LinuxCNC G-code reference: G20/G21, G90/G91, G90.1/G91.1, G17-G19, G92,
 * G92.1, G80, modal group 1). */
#include "cs_grbl_gc.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_err_text.h"

#define MM_PER_INCH 25.4
#define SCAN_G_MAX 16

/* The words of one line that change the modal state. */
typedef struct {
    int g[SCAN_G_MAX]; /* G words x10 */
    int ng;
    bool has[26];
    double v[26];
    bool end; /* M2 or M30 */
} scan_t;

void cs_grbl_gc_init(cs_grbl_gc_t *g)
{
    memset(g, 0, sizeof *g);
    cs_grbl_gc_reset_modal(g);
}

void cs_grbl_gc_free(cs_grbl_gc_t *g)
{
    free(g->block);
    g->block = NULL;
    g->block_len = g->block_lines = 0;
}

void cs_grbl_gc_reset_modal(cs_grbl_gc_t *g)
{
    cs_grbl_gc_free(g);
    g->inch = false;
    g->incr = false;
    g->ijk_abs = false;
    g->plane = 17;
    g->motion = -1;
    g->feed = 0;
}

double cs_grbl_gc_work(const cs_grbl_gc_t *g, int a)
{
    return (g->pos[a] - g->off[a]) / (g->inch ? MM_PER_INCH : 1.0);
}

/* Letters and numbers of a line; comments "(...)" and after ';' skipped. Only what the modal
 * tracking needs: the line was (or will be) checked by cs_gcode. */
static void scan(const char *s, scan_t *t)
{
    memset(t, 0, sizeof *t);
    while (*s != '\0' && *s != ';') {
        if (*s == '(') {
            while (*s != '\0' && *s != ')')
                s++;
            if (*s == ')')
                s++;
            continue;
        }
        int c = toupper((unsigned char)*s);
        if (c < 'A' || c > 'Z') {
            s++;
            continue;
        }
        s++;
        while (*s == ' ' || *s == '\t')
            s++;
        char *e;
        double v = strtod(s, &e);
        if (e == s)
            continue;
        s = e;
        if (c == 'G' && t->ng < SCAN_G_MAX)
            t->g[t->ng++] = (int)lround(v * 10);
        if (c == 'M' && (lround(v) == 2 || lround(v) == 30))
            t->end = true;
        t->has[c - 'A'] = true;
        t->v[c - 'A'] = v;
    }
}

static bool scan_has_g(const scan_t *t, int gx10)
{
    for (int i = 0; i < t->ng; i++)
        if (t->g[i] == gx10)
            return true;
    return false;
}

/* The preamble: cs_gcode starts at 0,0,0 in G17 G21 G90 G91.1 with no offsets. Returns its line
 * count. Numbers printed with 17 significant digits round-trip exactly. */
static unsigned preamble(const cs_grbl_gc_t *g, FILE *f)
{
    fprintf(f, "G21 G90 G0 X%.17g Y%.17g Z%.17g\n", g->pos[0], g->pos[1], g->pos[2]);
    unsigned n = 1;
    if (g->off[0] != 0 || g->off[1] != 0 || g->off[2] != 0) {
        fprintf(f, "G92 X%.17g Y%.17g Z%.17g\n", g->pos[0] - g->off[0], g->pos[1] - g->off[1],
                g->pos[2] - g->off[2]);
        n++;
    }
    fprintf(f, "%s %s %s G%d\n", g->inch ? "G20" : "G21", g->incr ? "G91" : "G90",
            g->ijk_abs ? "G90.1" : "G91.1", g->plane);
    n++;
    if (g->feed > 0) {
        fprintf(f, "F%.17g\n", g->feed);
        n++;
    }
    if (g->motion >= 0) {
        if (g->motion % 10)
            fprintf(f, "G%d.%d\n", g->motion / 10, g->motion % 10);
        else
            fprintf(f, "G%d\n", g->motion / 10);
        n++;
    }
    return n;
}

/* After cs_gcode accepted the line: the modal words it changed, in cs_gcode's order (modal
 * words first, then G92 with the line's units, from the position before the line). */
static void apply(cs_grbl_gc_t *g, const scan_t *t, const double before[3])
{
    bool g92 = false;
    for (int i = 0; i < t->ng; i++) {
        int v = t->g[i];
        if (v == 0 || v == 10 || v == 20 || v == 30 || v == 50 || v == 51)
            g->motion = v;
        else if (v == 800 || v == 53)
            g->motion = -1;
        else if (v == 170 || v == 180 || v == 190)
            g->plane = v / 10;
        else if (v == 200 || v == 210)
            g->inch = v == 200;
        else if (v == 900 || v == 910)
            g->incr = v == 910;
        else if (v == 901 || v == 911)
            g->ijk_abs = v == 901;
        else if (v == 921)
            memset(g->off, 0, sizeof g->off);
        else if (v == 920)
            g92 = true;
    }
    if (t->has['F' - 'A'])
        g->feed = t->v['F' - 'A'];
    for (int a = 0; g92 && a < 3; a++)
        if (t->has['X' - 'A' + a])
            g->off[a] = before[a] - t->v['X' - 'A' + a] * (g->inch ? MM_PER_INCH : 1.0);
}

/* Holds a line of an open G5.2 block. */
static cs_err_t hold(cs_grbl_gc_t *g, const char *line, cs_path_diag_t *diag, unsigned lineno)
{
    size_t n = strlen(line);
    cs_path_loc_t loc = {"grbl", lineno, 1};
    if (g->block_lines >= CS_GRBL_GC_BLOCK_MAX)
        return cs_path_diag_set(diag, CS_ERR_FULL, loc, "G5.2 block longer than %d lines",
                                CS_GRBL_GC_BLOCK_MAX);
    char *b = realloc(g->block, g->block_len + n + 2);
    if (b == NULL)
        return cs_path_diag_set(diag, CS_ERR_FULL, loc, "out of memory");
    memcpy(b + g->block_len, line, n);
    b[g->block_len + n] = '\n';
    b[g->block_len + n + 1] = '\0';
    g->block = b;
    g->block_len += n + 1;
    g->block_lines++;
    return CS_OK;
}

/* Reads preamble + held block + line; appends the elements after the preamble to out. */
static cs_err_t read_text(const cs_grbl_gc_t *g, const char *line, unsigned lineno,
                          cs_path_t *out, cs_path_diag_t *diag)
{
    char *text = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&text, &len);
    cs_path_loc_t loc = {"grbl", lineno, 1};
    if (f == NULL)
        return cs_path_diag_set(diag, CS_ERR_FULL, loc, "out of memory");
    unsigned npre = preamble(g, f);
    if (g->block != NULL)
        fputs(g->block, f);
    fprintf(f, "%s\n", line);
    if (fclose(f) != 0) {
        free(text);
        return cs_path_diag_set(diag, CS_ERR_FULL, loc, "out of memory");
    }
    cs_gcode_opts_t o;
    cs_gcode_opts_init(&o);
    cs_path_t tmp;
    cs_path_init(&tmp);
    cs_err_t e = cs_gcode_read("grbl", text, len, &o, &tmp, diag, NULL);
    if (e != CS_OK) {
        /* the line's own column when the error is on it; else (a preamble or block line) col 1 */
        diag->loc.col = diag->loc.line == npre + g->block_lines + 1 ? diag->loc.col : 1;
        diag->loc.line = lineno;
    }
    diag->loc.file = "grbl"; /* tmp's interned name is freed below */
    for (size_t k = 0; e == CS_OK && k < tmp.n; k++) {
        if (tmp.elems[k].loc.line <= npre)
            continue;
        if (!cs_path_grow((void **)&out->elems, &out->cap, out->n + 1, sizeof *out->elems)) {
            e = cs_path_diag_set(diag, CS_ERR_FULL, loc, "out of memory");
            break;
        }
        cs_path_elem_t el = tmp.elems[k];
        el.loc = loc;
        el.subpath = 0;
        out->elems[out->n++] = el;
    }
    cs_path_free(&tmp);
    free(text);
    return e;
}

cs_err_t cs_grbl_gc_line(cs_grbl_gc_t *g, const char *line, unsigned lineno, cs_path_t *out,
                         cs_path_diag_t *diag, bool *end)
{
    scan_t t;
    scan(line, &t);
    *end = false;
    memset(diag, 0, sizeof *diag);
    bool opens = scan_has_g(&t, 52), closes = scan_has_g(&t, 53);
    if ((g->block != NULL && !closes) || (g->block == NULL && opens && !closes))
        return hold(g, line, diag, lineno); /* read whole at its G5.3 */
    size_t n0 = out->n;
    cs_err_t e = read_text(g, line, lineno, out, diag);
    cs_grbl_gc_free(g); /* a block is read (or refused) with its G5.3 */
    if (e != CS_OK) {
        out->n = n0;
        return e;
    }
    double before[3];
    memcpy(before, g->pos, sizeof before);
    if (out->n > n0)
        cs_path_eval_mm(&out->elems[out->n - 1].curve, 1.0, g->pos);
    apply(g, &t, before);
    *end = t.end;
    return CS_OK;
}
