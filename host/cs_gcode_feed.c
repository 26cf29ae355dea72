/* cs_gcode_feed: the G-code reader a line at a time (see cs_gcode.h, "line at a time"). The
 * reader's own state (gc_t) lives on between lines, so parameters, work offsets, modal state and
 * an open NURBS block carry over as they do in a file. O-word control flow needs the lines of a
 * block together (a loop runs its body again), so the lines of an open block are held and run,
 * with every sub definition seen so far in front of them, when the block closes (LinuxCNC runs
 * MDI O-word blocks the same way: "O-word ... in MDI: the block is run once it is complete"). */
#include <stdlib.h>
#include <string.h>

#include "cs_gcode_int.h"

/* Lines of G-code text kept with the client's line number of each. */
typedef struct {
    char *text;
    size_t len;
    unsigned *no;
    size_t n, cap;
} held_t;

typedef struct {
    char label[CS_GFLOW_LABEL_MAX];
    cs_gflow_kind_t kind;
} open_t;

struct cs_gcode_session {
    cs_gcode_opts_t o;
    char *name;
    gc_t g;      /* the reader's state */
    gc_t saved;  /* the state before the last line (undo) */
    bool has_saved;
    held_t defs; /* every complete sub ... endsub so far */
    held_t held; /* the open block's lines */
    open_t open[CS_GFLOW_MAX_OPEN];
    size_t nopen;
};

static void held_free(held_t *h)
{
    free(h->text);
    free(h->no);
    memset(h, 0, sizeof *h);
}

/* Appends line s[0..n) numbered lineno. False without memory. */
static bool held_add(held_t *h, const char *s, size_t n, unsigned lineno)
{
    char *t = realloc(h->text, h->len + n + 2);
    if (!t)
        return false;
    h->text = t;
    memcpy(t + h->len, s, n);
    t[h->len + n] = '\n';
    t[h->len + n + 1] = '\0';
    h->len += n + 1;
    void *no = h->no;
    if (!cs_path_grow(&no, &h->cap, h->n + 1, sizeof *h->no))
        return false;
    h->no = no;
    h->no[h->n++] = lineno;
    return true;
}

/* The state without its heap parts' owners changing: g's parameters and NURBS block freed. */
static void gc_release(gc_t *g)
{
    cs_gexpr_free(&g->st);
    cs_gnurbs_free(&g->nb);
}

static bool gc_copy(gc_t *dst, const gc_t *src)
{
    *dst = *src;
    if (cs_gexpr_copy(&dst->st, &src->st) != CS_OK)
        return false;
    if (cs_gnurbs_copy(&dst->nb, &src->nb) != CS_OK) {
        cs_gexpr_free(&dst->st);
        return false;
    }
    return true;
}

cs_gcode_session_t *cs_gcode_session_new(const char *name, const cs_gcode_opts_t *o)
{
    cs_gcode_session_t *s = calloc(1, sizeof *s);
    if (!s)
        return NULL;
    if (o)
        s->o = *o;
    else
        cs_gcode_opts_init(&s->o);
    s->name = strdup(name ? name : "<input>");
    cs_path_t tmp;
    cs_path_diag_t d;
    cs_path_init(&tmp);
    bool ok = s->name && cs_gcode_begin(&s->g, s->name, &s->o, &tmp, &d) == CS_OK;
    cs_path_free(&tmp);
    s->g.name = NULL; /* interned in tmp: set again on each line */
    if (!ok) {
        cs_gcode_session_free(s);
        return NULL;
    }
    return s;
}

void cs_gcode_session_free(cs_gcode_session_t *s)
{
    if (!s)
        return;
    gc_release(&s->g);
    if (s->has_saved)
        gc_release(&s->saved);
    held_free(&s->defs);
    held_free(&s->held);
    free(s->name);
    free(s);
}

bool cs_gcode_undo(cs_gcode_session_t *s)
{
    if (!s->has_saved)
        return false;
    gc_release(&s->g);
    s->g = s->saved;
    s->has_saved = false;
    return true;
}

/* The client's line number of line k (1-based) of defs + held. */
static unsigned client_line(const cs_gcode_session_t *s, unsigned k, unsigned fallback)
{
    if (k >= 1 && k <= s->defs.n)
        return s->defs.no[k - 1];
    if (k > s->defs.n && k - s->defs.n <= s->held.n)
        return s->held.no[k - s->defs.n - 1];
    return fallback;
}

/* Runs the held block (or, when none is held, line) behind the sub definitions. */
static cs_err_t run_flow(cs_gcode_session_t *s, const char *line, size_t len, unsigned lineno,
                         size_t n0)
{
    held_t text = {0};
    bool ok = (!s->defs.n || held_add(&text, s->defs.text, s->defs.len - 1, 0)) &&
              (s->held.n ? held_add(&text, s->held.text, s->held.len - 1, 0)
                         : held_add(&text, line, len, 0));
    cs_err_t e = CS_ERR_FULL;
    cs_gflow_t fl;
    memset(&fl, 0, sizeof fl);
    if (!ok)
        cs_path_diag_set(s->g.diag, e, cs_gcode_loc(&s->g, 1), "out of memory");
    else
        e = cs_gflow_init(&fl, s->g.name, text.text, text.len, true, s->o.max_loops, s->g.diag);
    if (e == CS_OK)
        e = cs_gcode_run_lines(&s->g, &fl, text.text);
    cs_gflow_free(&fl);
    held_free(&text);
    if (!s->held.n && !held_add(&s->held, line, len, lineno))
        e = CS_ERR_FULL; /* only for the numbering below */
    for (size_t k = n0; k < s->g.path->n; k++)
        s->g.path->elems[k].loc.line = client_line(s, s->g.path->elems[k].loc.line, lineno);
    if (e != CS_OK)
        s->g.diag->loc.line = client_line(s, s->g.diag->loc.line, lineno);
    return e;
}

/* Keeps track of the O-word blocks a line opens and closes. *run: the line completes what is
 * to run now (a block closed, or an O-word line alone such as a call); false: the line is held. */
static void track_block(cs_gcode_session_t *s, const cs_gflow_line_t *l, bool bad, bool *run)
{
    cs_gflow_kind_t k = l->kind;
    open_t *top = s->nopen ? &s->open[s->nopen - 1] : NULL;
    bool closes_do = k == CS_GFLOW_WHILE && top && top->kind == CS_GFLOW_DO &&
                     strcmp(top->label, l->label) == 0;
    bool opens = !bad && !closes_do &&
                 (k == CS_GFLOW_SUB || k == CS_GFLOW_IF || k == CS_GFLOW_WHILE ||
                  k == CS_GFLOW_DO || k == CS_GFLOW_REPEAT);
    bool closes = closes_do || k == CS_GFLOW_ENDSUB || k == CS_GFLOW_ENDIF ||
                  k == CS_GFLOW_ENDWHILE || k == CS_GFLOW_ENDREPEAT;
    if (opens && s->nopen < CS_GFLOW_MAX_OPEN) {
        strcpy(s->open[s->nopen].label, l->label);
        s->open[s->nopen++].kind = k;
    } else if (closes && s->nopen > 0) {
        s->nopen--;
    }
    *run = s->nopen == 0;
}

/* Runs one line with the state saved first (restored on an error). */
static cs_err_t run_line(cs_gcode_session_t *s, const char *line, size_t len, unsigned lineno,
                         bool flow)
{
    gc_t *g = &s->g;
    if (s->has_saved)
        gc_release(&s->saved);
    s->has_saved = gc_copy(&s->saved, g);
    if (!s->has_saved)
        return cs_path_diag_set(g->diag, CS_ERR_FULL, cs_gcode_loc(g, 1), "out of memory");
    size_t n0 = g->path->n;
    g->line = lineno;
    cs_err_t e = flow ? run_flow(s, line, len, lineno, n0) : cs_gcode_line(g, line, len);
    if (e != CS_OK) {
        g->path->n = n0;
        cs_gcode_undo(s);
    }
    return e;
}

cs_err_t cs_gcode_feed(cs_gcode_session_t *s, const char *line, size_t len, unsigned lineno,
                       cs_path_t *out, cs_path_diag_t *diag, bool *ended)
{
    gc_t *g = &s->g;
    *ended = false;
    memset(diag, 0, sizeof *diag);
    g->path = out;
    g->diag = diag;
    g->line = lineno;
    g->name = cs_path_intern(out, s->name);
    cs_path_loc_t loc = {s->name, lineno, 1};
    if (!g->name)
        return cs_path_diag_set(diag, CS_ERR_FULL, loc, "out of memory");
    cs_gflow_line_t l;
    memset(&l, 0, sizeof l);
    bool bad = s->o.dialect != CS_GCODE_GRBL && cs_gflow_line_parse(line, len, &l) != CS_OK;
    bool flow = bad || l.kind != CS_GFLOW_NONE || s->nopen > 0, run = true;
    if (flow)
        track_block(s, &l, bad, &run);
    if (!run) {
        if (!held_add(&s->held, line, len, lineno))
            return cs_path_diag_set(diag, CS_ERR_FULL, loc, "out of memory");
        return CS_OK;
    }
    if (s->held.n && !held_add(&s->held, line, len, lineno))
        return cs_path_diag_set(diag, CS_ERR_FULL, loc, "out of memory");
    bool def = s->held.n && l.kind == CS_GFLOW_ENDSUB && s->held.text[0] != '\0' &&
               cs_gflow_line_parse(s->held.text, strcspn(s->held.text, "\n"), &l) == CS_OK &&
               l.kind == CS_GFLOW_SUB;
    cs_err_t e = run_line(s, line, len, lineno, flow);
    if (e == CS_OK && def) { /* a definition: kept for the calls that follow */
        for (size_t k = 0; k < s->held.n && e == CS_OK; k++) {
            const char *t = s->held.text;
            size_t at = 0;
            for (size_t j = 0; j < k; j++)
                at += strcspn(t + at, "\n") + 1;
            if (!held_add(&s->defs, t + at, strcspn(t + at, "\n"), s->held.no[k]))
                e = cs_path_diag_set(diag, CS_ERR_FULL, loc, "out of memory");
        }
    }
    held_free(&s->held);
    if (e == CS_OK && g->ended) {
        cs_gcode_reset(s, false);
        *ended = true;
    }
    return e;
}

void cs_gcode_state(const cs_gcode_session_t *s, cs_gcode_state_t *st)
{
    const gc_t *g = &s->g;
    memset(st, 0, sizeof *st);
    memcpy(st->pos, g->pos, sizeof st->pos);
    for (int a = 0; a < 3; a++)
        st->off[a] = cs_gcode_offset(g, a);
    st->wcs = (int)g->st.num[GC_P_WCS];
    st->inch = g->unit != 1.0;
    st->incr = g->incr;
    st->ijk_abs = g->ijk_abs;
    st->plane = g->plane;
    st->motion = g->motion >= 0 ? g->motion : -1;
    st->feed = g->feed;
    st->spindle = g->spindle;
    st->speed = g->speed;
    st->holding = s->nopen > 0 || g->nurbs != 0;
}

double cs_gcode_param(const cs_gcode_session_t *s, int index)
{
    return index >= 1 && index < CS_GEXPR_NUM_PARAMS ? s->g.st.num[index] : 0.0;
}

void cs_gcode_set_pos(cs_gcode_session_t *s, const double mm[3])
{
    memcpy(s->g.pos, mm, sizeof s->g.pos);
}

void cs_gcode_reset(cs_gcode_session_t *s, bool clear_g92)
{
    gc_t *g = &s->g;
    cs_gcode_start_modes(g);
    g->ended = false;
    g->nurbs = 0;
    cs_gnurbs_free(&g->nb);
    cs_gexpr_discard(&g->st);
    held_free(&s->held);
    s->nopen = 0;
    /* Program end and Grbl's reset go back to G54 (LinuxCNC "M2, M30": "origin offsets are set
     * to the default (like G54)"); a reset also drops the G92 offsets (Grbl keeps none). */
    g->st.num[GC_P_WCS] = 1;
    if (clear_g92)
        cs_gcode_wcs_set(g, GC_G92_1);
}
