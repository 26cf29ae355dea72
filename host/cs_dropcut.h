/* cs_dropcut: drop-cutter for 3-axis finishing from above (issue 20). Owns a triangle mesh of a
 * set of surface patches, with a proven bound eps on its distance from the exact patches, a
 * uniform xy grid over the triangles, and the query "how low can the cutter's tip go at (x, y)
 * without entering the mesh". The cutter is a torus of radius R and corner radius r: r = 0 a
 * flat end mill, r = R a ball, 0 < r < R a bull-nose. Its solid is the disk of radius R - r
 * swept by a ball of radius r (a Minkowski sum), with a cylindrical shank above.
 *
 * Gouge-free by construction: every point S(u, v) of a patch is within eps of the point L(u, v)
 * of the mesh (cs_dropcut_grid_eps). The query drops the cutter enlarged by eps (R + eps,
 * r + eps: K + B(eps)) onto the mesh and raises the result by eps, the difference of the two
 * tips. If a surface point s were inside the real cutter K, the mesh point l with |s - l| <= eps
 * would be inside K + B(eps), which the drop forbids. So the real cutter never enters any patch;
 * it stands at most 2 eps above the exact drop height.
 *
 * Per triangle the drop height is the maximum over its points p (within R of the axis) of
 * f(p) = p.z - h(d(p)), h the cutter's profile at horizontal distance d from the axis. h is
 * convex and non-decreasing in d and d is convex in p, so f is concave over the triangle: its
 * maximum is the facet contact (the tangent plane touching the cutter, closed form) when that
 * contact lies inside the triangle, else on an edge, where the 1-D concave maximum is closed-form
 * for a ball and a flat end and the root of f' for a bull-nose (OpenCAMLib's facet / edge /
 * vertex split, derived here from concavity). The index is a grid with a pyramid of cell tops
 * above it, searched by branch and bound (cs_dropcut.c). Host only, double precision. */
#ifndef CS_DROPCUT_H
#define CS_DROPCUT_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_err.h"
#include "cs_surffile.h"

/* A cutter: radius r_mm > 0, corner radius 0 <= c_mm <= r_mm (0 flat, r_mm ball). */
typedef struct {
    double r_mm;
    double c_mm;
} cs_dropcut_tool_t;

typedef struct {
    double v[3][3]; /* vertices, mm */
} cs_dropcut_tri_t;

/* Levels of the index's pyramid at most: enough for 2^15 cells a side. */
#define CS_DROPCUT_LEVELS 16

/* The mesh and its index. */
typedef struct {
    cs_dropcut_tri_t *tri;
    size_t ntri, cap;
    double eps;       /* largest bound of any patch's mesh from the patch, mm */
    double box[6];    /* x0 y0 z0 x1 y1 z1 of the mesh, mm */
    double cell;      /* grid cell size, mm */
    size_t gx, gy;    /* grid cells in x and y */
    size_t *start;    /* gx * gy + 1 offsets into ent */
    struct cs_dropcut_ent *ent; /* each cell's triangles with their boxes and tops, highest first */
    unsigned *stamp;  /* per triangle: the query that last visited it */
    unsigned query;   /* the current query's number */
    double (*pl)[4];  /* per triangle: its plane's unit normal, nz >= 0 (all 0 when degenerate or
                       * vertical), and n . v0 (mm) */
    double *top;      /* per node of the pyramid: the highest z of the triangles listed under it,
                       * mm (level 0 the cells, a node above the 2 x 2 nodes below it) */
    size_t lev;       /* levels; the last has one node */
    size_t lgx[CS_DROPCUT_LEVELS], lgy[CS_DROPCUT_LEVELS]; /* nodes in x and y, by level */
    size_t loff[CS_DROPCUT_LEVELS]; /* a level's first node in top */
    struct cs_dropcut_cq *cq; /* scratch: the heap of one query's nodes, by bound */
    size_t cqcap;
} cs_dropcut_mesh_t;

/* Height of the profile of tool t at horizontal distance d (0 <= d <= R) above its tip, mm. */
double cs_dropcut_profile(const cs_dropcut_tool_t *t, double d);

/* Bound (mm) on |S - L| for a Bézier patch p (control points in mm, degree m x n, stored as
 * p[(m + 1) * ... ] row-major [i][j]) triangulated on an nu x nv grid, two triangles a cell:
 * (1/8) ((Muu + Muv) / nu^2 + (Mvv + Muv) / nv^2), Muu = m (m - 1) max |Δ²u P| etc. (the
 * second derivative patches' control points bound them: convex hull), from the Taylor remainder
 * of linear interpolation on a triangle (docs/surfaces.md, "Drop-cutter"). */
double cs_dropcut_grid_eps(const double *p, int m, int n, int nu, int nv);

/* Empty mesh. */
void cs_dropcut_init(cs_dropcut_mesh_t *ms);
/* Triangulates every item of sf (quads directly, triangles as their collapsed tensor form,
 * n-sided patches as their bicubic cells fitted within fit_mm, whose fit adds to eps, spheres on
 * a latitude-longitude grid bounded by the caps of its triangles) on grids fine enough that each
 * item's bound is <= eps_mm (at most 512 x 512 a patch), then builds the index for tools up to
 * radius rmax_mm. CS_ERR_FULL out of memory, CS_ERR_DEGENERATE when sf holds no surface, a
 * patch constructor's code otherwise. */
cs_err_t cs_dropcut_build(cs_dropcut_mesh_t *ms, const cs_surffile_t *sf, double eps_mm,
                          double fit_mm, double rmax_mm);
/* Adds one triangle (before cs_dropcut_index; the tests build meshes by hand). */
cs_err_t cs_dropcut_add(cs_dropcut_mesh_t *ms, const double a[3], const double b[3],
                        const double c[3]);
/* Builds the xy grid for tools up to radius rmax_mm (after the last add). */
cs_err_t cs_dropcut_index(cs_dropcut_mesh_t *ms, double rmax_mm);
/* The tip height (mm) of tool t dropped at (x, y) onto the mesh, raised by ms->eps through the
 * enlarged cutter (see above); *hit false (and -HUGE_VAL) when no triangle is under the cutter. */
double cs_dropcut_drop(cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t, double x, double y,
                       bool *hit);
/* The same against the bare mesh: tool t exactly, no eps (the tests' facet/edge/vertex cases). */
double cs_dropcut_drop_exact(cs_dropcut_mesh_t *ms, const cs_dropcut_tool_t *t, double x,
                             double y, bool *hit);
/* Highest mesh point straight above or below (x, y), mm; false when none (a needle's drop). */
bool cs_dropcut_top(cs_dropcut_mesh_t *ms, double x, double y, double *z);
void cs_dropcut_free(cs_dropcut_mesh_t *ms);

#endif
