/* cs_grbl_gc: G-code one line at a time for the Grbl front end (see cs_grbl_gc.h): a cs_gcode
 * session named "grbl", and its state copied out after each call. */
#include "cs_grbl_gc.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cs_readall.h"

#define MM_PER_INCH 25.4

/* The copy the reports read. */
static void mirror(cs_grbl_gc_t *g)
{
    if (g->s == NULL)
        return;
    cs_gcode_state_t st;
    cs_gcode_state(g->s, &st);
    memcpy(g->pos, st.pos, sizeof g->pos);
    memcpy(g->off, st.off, sizeof g->off);
    g->wcs = st.wcs;
    g->inch = st.inch;
    g->incr = st.incr;
    g->ijk_abs = st.ijk_abs;
    g->plane = st.plane;
    g->motion = st.motion;
    g->feed = st.feed;
    g->spindle = st.spindle;
    g->speed = st.speed;
}

cs_err_t cs_grbl_gc_init(cs_grbl_gc_t *g, const cs_gcode_opts_t *o)
{
    memset(g, 0, sizeof *g);
    g->s = cs_gcode_session_new("grbl", o);
    mirror(g);
    return g->s ? CS_OK : CS_ERR_FULL;
}

void cs_grbl_gc_free(cs_grbl_gc_t *g)
{
    cs_gcode_session_free(g->s);
    g->s = NULL;
}

void cs_grbl_gc_reset_modal(cs_grbl_gc_t *g, bool clear_g92)
{
    if (g->s)
        cs_gcode_reset(g->s, clear_g92);
    mirror(g);
}

cs_err_t cs_grbl_gc_line(cs_grbl_gc_t *g, const char *line, unsigned lineno, cs_path_t *out,
                         cs_path_diag_t *diag, bool *end)
{
    *end = false;
    if (g->s == NULL) {
        cs_path_loc_t loc = {"grbl", lineno, 1};
        return cs_path_diag_set(diag, CS_ERR_FULL, loc, "out of memory");
    }
    cs_err_t e = cs_gcode_feed(g->s, line, strlen(line), lineno, out, diag, end);
    mirror(g);
    return e;
}

bool cs_grbl_gc_undo(cs_grbl_gc_t *g)
{
    bool ok = g->s && cs_gcode_undo(g->s);
    mirror(g);
    return ok;
}

void cs_grbl_gc_set_pos(cs_grbl_gc_t *g, const double mm[3])
{
    if (g->s)
        cs_gcode_set_pos(g->s, mm);
    mirror(g);
}

double cs_grbl_gc_work(const cs_grbl_gc_t *g, int a)
{
    return (g->pos[a] - g->off[a]) / (g->inch ? MM_PER_INCH : 1.0);
}

double cs_grbl_gc_param(const cs_grbl_gc_t *g, int index)
{
    return g->s ? cs_gcode_param(g->s, index) : 0.0;
}

cs_err_t cs_grbl_gc_save(const cs_grbl_gc_t *g, const char *path)
{
    char tmp[4096];
    if (snprintf(tmp, sizeof tmp, "%s.tmp", path) >= (int)sizeof tmp)
        return CS_ERR_IO;
    FILE *f = fopen(tmp, "w");
    if (f == NULL)
        return CS_ERR_IO;
    /* %.17g: every double reads back exactly */
    fprintf(f, "(curvestep grbl --state: work offsets and homes, mm; written on exit)\nG21\n");
    for (int n = 1; n <= 9; n++) {
        int b = 5221 + 20 * (n - 1); /* LinuxCNC: system n's X at #5221 + 20 (n - 1) */
        fprintf(f, "G10 L2 P%d X%.17g Y%.17g Z%.17g\n", n, cs_grbl_gc_param(g, b),
                cs_grbl_gc_param(g, b + 1), cs_grbl_gc_param(g, b + 2));
    }
    for (int p = 5161; p <= 5183; p += 20) /* G28 and G30 homes */
        fprintf(f, "#%d=%.17g #%d=%.17g #%d=%.17g\n", p, cs_grbl_gc_param(g, p), p + 1,
                cs_grbl_gc_param(g, p + 1), p + 2, cs_grbl_gc_param(g, p + 2));
    bool ok = fclose(f) == 0;
    if (!ok || rename(tmp, path) != 0) {
        remove(tmp);
        return CS_ERR_IO;
    }
    return CS_OK;
}

cs_err_t cs_grbl_gc_load(cs_grbl_gc_t *g, const char *path, cs_path_diag_t *diag)
{
    cs_path_loc_t loc = {path, 0, 0};
    char *buf = NULL;
    size_t len = 0;
    FILE *probe = fopen(path, "r");
    if (probe == NULL && errno == ENOENT)
        return CS_OK; /* nothing stored yet */
    if (probe != NULL)
        fclose(probe);
    cs_err_t e = cs_readall(path, 0, true, &buf, &len, diag);
    if (e != CS_OK)
        return e;
    cs_path_t out;
    cs_path_init(&out);
    unsigned no = 0;
    for (size_t i = 0; i < len && e == CS_OK;) {
        size_t n = 0;
        while (i + n < len && buf[i + n] != '\n')
            n++;
        char line[CS_GRBL_GC_LINE_MAX];
        bool end;
        no++;
        if (n >= sizeof line) {
            loc.line = no;
            e = cs_path_diag_set(diag, CS_ERR_PARSE, loc, "line too long");
            break;
        }
        memcpy(line, buf + i, n);
        line[n] = '\0';
        e = cs_grbl_gc_line(g, line, no, &out, diag, &end);
        i += n + 1;
    }
    if (e != CS_OK)
        diag->loc.file = path;
    cs_path_free(&out);
    free(buf);
    return e;
}
