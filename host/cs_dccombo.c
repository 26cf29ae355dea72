/* cs_dccombo: raster on shallow ground, waterline on steep ground (cs_dccombo.h). */
#include "cs_dccombo.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cs_dcwater.h"

#define DCC_D         0.05    /* mm: the step of the fine slope test */
#define DCC_MAX_NODES 4000000 /* region grid nodes, at most */

typedef struct {
    double x0, y0, g;
    size_t nx, ny;
    unsigned char *steep; /* per node: 1 steep */
    unsigned char *keep[2]; /* per node: 0 raster, 1 waterline keeps its points there */
} dcc_grid_t;

static double top_or(cs_dropcut_mesh_t *ms, double x, double y, double floor_z)
{
    double z;
    return cs_dropcut_top(ms, x, y, &z) ? fmax(z, floor_z) : floor_z;
}

/* The fine slope test at one node: the top over DCC_D in x and y (the floor where no surface). */
static bool fine_steep(cs_dropcut_mesh_t *ms, double x, double y, double zc, double floor_z)
{
    static const double dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
    for (int i = 0; i < 4; i++)
        if (fabs(top_or(ms, x + DCC_D * dx[i], y + DCC_D * dy[i], floor_z) - zc) > DCC_STEEP * DCC_D)
            return true;
    return false;
}

static cs_err_t classify(dcc_grid_t *gr, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                         const cs_dcpath_opts_t *o)
{
    const double *b = o->box;
    gr->g = fmax(t->r_mm / 4, o->tol_mm);
    gr->nx = (size_t)ceil((b[2] - b[0]) / gr->g) + 1;
    gr->ny = (size_t)ceil((b[3] - b[1]) / gr->g) + 1;
    if (gr->nx * gr->ny > DCC_MAX_NODES)
        return CS_ERR_RANGE;
    gr->x0 = b[0], gr->y0 = b[1];
    size_t nn = gr->nx * gr->ny;
    double *z = malloc(nn * sizeof *z);
    gr->steep = calloc(nn, 1);
    gr->keep[0] = calloc(nn, 1);
    gr->keep[1] = calloc(nn, 1);
    if (!z || !gr->steep || !gr->keep[0] || !gr->keep[1]) {
        free(z);
        return CS_ERR_FULL;
    }
    for (size_t j = 0; j < gr->ny; j++)
        for (size_t i = 0; i < gr->nx; i++) {
            double x = gr->x0 + (double)i * gr->g, y = gr->y0 + (double)j * gr->g;
            z[j * gr->nx + i] = top_or(ms, x, y, o->min_z);
            gr->steep[j * gr->nx + i] = fine_steep(ms, x, y, z[j * gr->nx + i], o->min_z);
        }
    /* A wall between two nodes marks both. */
    for (size_t j = 0; j < gr->ny; j++)
        for (size_t i = 0; i < gr->nx; i++) {
            size_t k = j * gr->nx + i;
            size_t nb[2] = {i + 1 < gr->nx ? k + 1 : k, j + 1 < gr->ny ? k + gr->nx : k};
            for (int q = 0; q < 2; q++)
                if (fabs(z[nb[q]] - z[k]) > DCC_STEEP * gr->g)
                    gr->steep[k] = gr->steep[nb[q]] = 1;
        }
    free(z);
    return CS_OK;
}

/* keep[1]: within rho of a steep node; keep[0]: within rho of a shallow node. */
static bool dilate(dcc_grid_t *gr, double rho)
{
    size_t nn = gr->nx * gr->ny;
    unsigned char *shallow = malloc(nn);
    if (!shallow)
        return false;
    for (size_t k = 0; k < nn; k++)
        shallow[k] = !gr->steep[k];
    cs_dcwater_dilate(gr->steep, gr->keep[1], gr->nx, gr->ny, gr->g, gr->g, rho);
    cs_dcwater_dilate(shallow, gr->keep[0], gr->nx, gr->ny, gr->g, gr->g, rho);
    free(shallow);
    return true;
}

/* Appends to out the runs of in's passes that lie in region `which` (cs_dcwater_clip). */
static cs_err_t clip_into(cs_dcpath_t *out, const cs_dcpath_t *in, const dcc_grid_t *gr, int which)
{
    cs_dcwater_mask_t m = {gr->x0, gr->y0, gr->g, gr->g, gr->nx, gr->ny, gr->keep[which]};
    return cs_dcwater_clip(out, in, &m);
}

cs_err_t cs_dccombo_plan(cs_dcpath_t *p, cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t,
                         const cs_dcpath_opts_t *o)
{
    dcc_grid_t gr;
    memset(&gr, 0, sizeof gr);
    cs_dcpath_t ra, wl;
    cs_dcpath_init(&ra);
    cs_dcpath_init(&wl);
    cs_dcpath_opts_t ro = *o, wo = *o;
    ro.max_slope = DCC_STEEP;
    if (o->step_mm <= 0) {
        /* the level step on the shallowest ground the waterline serves (header) */
        double h = fmax(o->scallop_mm - ms->eps - o->tol_mm / 2, o->scallop_mm / 4);
        wo.step_mm = cs_dcwater_zstep(t, h) * (t->c_mm > 0 ? sin(atan(DCC_STEEP)) : 1);
    }
    cs_err_t e = classify(&gr, ms, t, o);
    if (e == CS_OK)
        e = dilate(&gr, t->r_mm + 2 * gr.g) ? CS_OK : CS_ERR_FULL;
    if (e == CS_OK)
        e = cs_dcpath_raster(&ra, ms, t, &ro);
    if (e == CS_OK)
        e = cs_dcwater_contours(&wl, ms, t, &wo);
    if (e == CS_OK)
        e = clip_into(p, &ra, &gr, 0);
    if (e == CS_OK)
        e = clip_into(p, &wl, &gr, 1);
    p->drops = ra.drops + wl.drops;
    p->refined = ra.refined;
    p->capped = ra.capped;
    p->max_left = ra.max_left;
    p->max_stuck = ra.max_stuck;
    cs_dcpath_free(&ra);
    cs_dcpath_free(&wl);
    free(gr.steep), free(gr.keep[0]), free(gr.keep[1]);
    return e;
}
