/* cs_surffile: the surface inputs of `curvestep toolpath`. Reads either Newell's patch format
 * (cs_patchfile) or curvestep's native surface text format, which can say every surface type
 * the core builds (docs/surfaces.md, "Native surface format"):
 *
 *   curvestep-surfaces 1            header (first token of the file)
 *   bezier DU DV  P...              (DU+1)(DV+1) points x y z, p[i][j] with j fastest
 *   tri N  P...                     (N+1)(N+2)/2 points, cs_tripatch order
 *   hermite  V x 16                 P00 P10 P01 P11 Pu.. Pv.. Puv.. (index: u corner, v corner)
 *   power  V x 16                   a[i][j] (coefficient of u^i v^j), i-major
 *   coons-bilinear C C C C          boundaries p1 (v=0), p2 (v=1), q1 (u=0), q2 (u=1)
 *   coons-bicubic C C C C [derivatives C C C C] [twists V V V V]
 *                                   same with Hermite blends; derivative curves and twists
 *                                   default to the corner tangents and zero
 *   coons-blend F G C C C C         generalised Coons (seed 002), blends linear | hermite |
 *                                   bernstein 1 b1 b2 0 (cs_gcoons)
 *   ruled C C                       (1 - v) C1(u) + v C2(u)
 *   extrude C V                     C(u) + v V
 *   revolve O A R SWEEP C           profile C (x = radius, y = height) about the axis through O
 *                                   along A, from the direction R, SWEEP degrees
 *   varady N C x N                  n-sided transfinite patch (seed 002) bounded by a loop
 *   varady-scheme B P [domain D] N C x N [tangents C x N] [twists V x N]
 *                                   same with blend B (mu, lambda-kappa), parametrisation
 *                                   P (side, radial, centre, biquadratic), domain D (arc,
 *                                   chords, angles, least-squares); varady = "varady-scheme mu
 *                                   side" (it takes the tangents and twists too)
 *   sphere C R                      the exact sphere of centre C, radius R (seed 000)
 * where C = "N P0 .. PN" (a Bézier curve of degree N = 1..3), P and V = three numbers, '#'
 * starts a comment; numbers are free-form across lines. Every item becomes core patches
 * (cs_patch_t or cs_tripatch_t) with the line of its keyword. Bad input: file:line:col. */
#ifndef CS_SURFFILE_H
#define CS_SURFFILE_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_patch.h"
#include "cs_path.h"
#include "cs_sphere.h"
#include "cs_tripatch.h"
#include "cs_varady.h"

typedef struct {
    bool tri;    /* triangular: trip is set */
    bool varady; /* n-sided: nside is set (else quad) */
    bool sphere; /* the exact sphere: sph is set (else quad) */
    cs_sphere_t sph;
    cs_patch_t quad;
    cs_tripatch_t trip;
    cs_varady_t nside;
    unsigned line; /* line of the statement (Newell: of the patch's index line) */
} cs_surf_item_t;

typedef struct {
    char *file; /* name used by diagnostics (owned) */
    bool native;
    cs_surf_item_t *items;
    size_t n, cap;
} cs_surffile_t;

/* Reads filename ("-" = standard input) in either format (native when its first token is
 * "curvestep-surfaces"), every coordinate times scale (mm per file unit). Surfaces of
 * revolution are approximated within rev_tol_mm. CS_ERR_PARSE / CS_ERR_RANGE / CS_ERR_IO /
 * a constructor's code with *diag (file:line:col: reason); CS_ERR_FULL when out of memory.
 * Call cs_surffile_free in every case (the diagnostic's file name lives in *sf). */
cs_err_t cs_surffile_read(const char *filename, double scale, double rev_tol_mm, cs_surffile_t *sf,
                          cs_path_diag_t *diag);
/* cs_surffile_read for a command: on error "file:line:col: reason" (or "WHO: out of memory") on
 * stderr and sf freed. Returns 0 (CS_EXIT_OK), 1 (bad input) or 3 (out of memory). */
int cs_surffile_load(const char *who, const char *filename, double scale, double rev_tol_mm,
                     cs_surffile_t *sf);
/* Same from memory. */
cs_err_t cs_surffile_parse(const char *text, size_t len, const char *name, double scale,
                           double rev_tol_mm, cs_surffile_t *sf, cs_path_diag_t *diag);
/* Frees everything (fine on an empty or failed one). */
void cs_surffile_free(cs_surffile_t *sf);
/* The keywords the native format accepts, in the order docs/surfaces.md lists them: keyword i,
 * or NULL past the last (the one table the parser, toolpath --help and the docs test share). */
const char *cs_surffile_keyword(size_t i);
/* All keywords joined by ", " into buf (cut to cap - 1 characters, always terminated). */
void cs_surffile_keyword_list(char *buf, size_t cap);

#endif
