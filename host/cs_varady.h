/* cs_varady: transfinite n-sided patches after Várady, Rockwood and Salvi (seed 002), built on
 * the host in double precision; what reaches the fixed-point core is cubic Bézier curves (the
 * images of straight domain segments) fitted within a tolerance. Owns the domain polygon
 * (seed 002 "Solution 1": vertices on a circle at angles proportional to the boundary arc
 * lengths), the side-based parametrisation (d_i = distance to domain side i,
 * s_i = d_{i-1} / (d_{i-1} + d_{i+1})), linear ribbons R_i(s, d) = P_i(s) + d T_i(s) and the
 * seed's special side blends mu_i = D_i / sum D_j, D_i = prod_{j != i} d_j^2:
 * S = sum R_i(s_i, d_i) mu_i (the default). Also the seed's side / corner blends
 * S = sum lambda_i R_i(s_i, d_i) - sum kappa_i Q_i (corner correction patches Q_i), and its
 * radial (Charrot-Gregory) and central-line-sweep parametrisations (cs_varady_set_scheme). */
#ifndef CS_VARADY_H
#define CS_VARADY_H

#include <stdbool.h>
#include <stddef.h>

#include "cs_bezier.h"
#include "cs_patch.h"

#define CS_VARADY_MAX_SIDES 8

/* Blending of the ribbons (seed 002, "Fonctions de mélange"). */
typedef enum {
    CS_VARADY_MU = 0,       /* S = sum mu_i R_i */
    CS_VARADY_LAMBDA_KAPPA, /* S = sum lambda_i R_i - sum kappa_i Q_i */
} cs_varady_blend_t;

/* Local coordinates (s_i, d_i) of a domain point for side i (seed 002, "Choix de la
 * paramétrisation"). Each gives s_i = 0 on side i - 1, s_i = 1 on side i + 1, d_i = 0 on side
 * i, s_i linear along side i except for CS_VARADY_SIDE. */
typedef enum {
    CS_VARADY_SIDE = 0, /* d_i = distance to side i's line, s_i = d_{i-1} / (d_{i-1} + d_{i+1}) */
    CS_VARADY_RADIAL,   /* rays from where the lines of sides i - 1 and i + 1 meet: e_i where
                         * the ray through the point crosses side i, s_i = |e_i - p_i| / side
                         * length, d_i = |point - e_i| */
    CS_VARADY_CENTRE,   /* central-line sweep: r(s, d) = p_i + (p_{i+1} - p_i) s + [w1 (1 - s)^2
                         * + 2 w12 (1 - s) s + w2 s^2] d, w1 and w2 the unit directions of the
                         * neighbouring sides, w12 chosen so that r(1/2, d_c) is the domain
                         * centre; (s_i, d_i) = r^-1(point) */
    CS_VARADY_BIQUADRATIC, /* seed 002's biquadratic mapping: (x, y) = sum C_ab B2_a(s) B2_b(t)
                            * with rows t = 0: p_i, (p_i + p_(i+1)) / 2, p_(i+1); t = 2:
                            * p_(i-1), c, p_(i+2) (c the vertices' centroid; for n = 3 the
                            * apex p_(i-1) = p_(i+2) itself); t = 1: the
                            * midpoints of those columns, so lines s = const are straight and
                            * the map is linear on side i; (s, t) by Newton-Raphson from the
                            * side-based values, d_i = t h_i (h_i: distance from c to side i) */
} cs_varady_param_t;

/* The domain polygon (seed 002, "Choix du domaine"): p_i starts side i, counter-clockwise;
 * L_i the boundary curves' arc lengths, phi_i the 3D angle between the two boundaries at corner
 * i, c_angle = (n - 2) pi / sum phi_j. */
typedef enum {
    CS_VARADY_DOMAIN_ARC = 0, /* solution 1: on a circle of circumference sum L, at angles
                               * 2 pi (L_1 + .. + L_(i-1)) / sum L */
    CS_VARADY_DOMAIN_CHORDS,  /* solution 2: on a circle, |p_i p_(i+1)| = L_i */
    CS_VARADY_DOMAIN_ANGLES,  /* solution 3: sides L_i, interior angles alpha_i = c_angle phi_i,
                               * the closing gap e = p_(n+1) -> p_1 spread as (i / n) e */
    CS_VARADY_DOMAIN_LSQ,     /* the least-squares domain: sides l_i and angles alpha_i
                               * minimising sum (l_i - L_i)^2 + sum (alpha_i - c_angle phi_i)^2
                               * over closed polygons (Gauss-Newton on the constraints) */
} cs_varady_domain_t;

typedef struct {
    size_t n;
    cs_varady_domain_t domain;
    cs_varady_blend_t blend;
    cs_varady_param_t param;
    cs_bezier_t side[CS_VARADY_MAX_SIDES]; /* P_i(s), s in [0, 1], P_i(1) = P_{i+1}(0) */
    double len[CS_VARADY_MAX_SIDES];       /* arc length of each side, mm */
    double vert[CS_VARADY_MAX_SIDES][2];   /* domain polygon, vertex i starts side i */
    double t0[CS_VARADY_MAX_SIDES][3];     /* cross-boundary tangent of side i at s = 0 */
    double t1[CS_VARADY_MAX_SIDES][3];     /* ... at s = 1 (unit vectors into the patch) */
    /* Per side i, in its local frame (origin p_i, u along side i, v into the domain): */
    double len_d[CS_VARADY_MAX_SIDES];    /* domain side length |p_{i+1} - p_i| */
    double w1[CS_VARADY_MAX_SIDES][2];    /* unit direction p_i -> p_{i-1} */
    double w2[CS_VARADY_MAX_SIDES][2];    /* unit direction p_{i+1} -> p_{i+2} */
    double w12u[CS_VARADY_MAX_SIDES];     /* central line: u of w12 (its v is (w1v + w2v) / 2) */
    double rc[CS_VARADY_MAX_SIDES][2];    /* radial: where the lines of sides i - 1, i + 1 meet */
    int rpar[CS_VARADY_MAX_SIDES];        /* radial: those lines are parallel (rays along w1) */
    bool user_tan;                        /* tan[] replaces the linear t0 -> t1 blend */
    cs_bezier_t tan[CS_VARADY_MAX_SIDES]; /* T_i(s), mm per domain unit (cs_varady_set_tangents) */
    double twist[CS_VARADY_MAX_SIDES][3]; /* W_i at corner i (start of side i), zero by default */
} cs_varady_t;

/* n (3..CS_VARADY_MAX_SIDES) polynomial boundary curves of degree 1..3 forming a loop (the end
 * of side i is exactly the start of side i + 1, and of the last the start of the first):
 * CS_ERR_ARG / CS_ERR_DEGREE / CS_ERR_UNSUPPORTED (rational) / CS_ERR_DEGENERATE (loop not
 * closed, a zero-length side or zero tangent at a corner). Cross-boundary tangents: at each
 * corner the unit tangent of the neighbouring side leading away from it, blended linearly
 * along the side (1 mm per domain mm). */
cs_err_t cs_varady_init(cs_varady_t *v, const cs_bezier_t *sides, size_t n);
/* Places the domain polygon by one of seed 002's constructions (cs_varady_init uses
 * CS_VARADY_DOMAIN_ARC). CS_ERR_ARG for an unknown value; CS_ERR_DEGENERATE when the
 * construction has no convex counter-clockwise solution (solution 2: a side longer than the
 * others allow on one circle; 3 and least squares: an angle outside (0, pi), or no closing).
 * On error the previous domain stays. */
cs_err_t cs_varady_set_domain(cs_varady_t *v, cs_varady_domain_t domain);
/* The 3D angle phi_i (radians) between the boundaries meeting at corner i (the start of side
 * i): between -P_(i-1)'(1) and P_i'(0). */
double cs_varady_corner_angle(const cs_varady_t *v, size_t i);
/* The cross-boundary tangents given by the user (seed 002: "contrainte tangentielle T_i(s_i)"):
 * tan[i] is T_i(s), s in [0, 1], in mm per domain unit (degree 1..3, any direction pointing
 * into the patch), replacing the default unit tangents blended linearly along the side; NULL
 * goes back to the defaults. Ribbons R_i(s, d) = P_i(s) + d T_i(s); the corner patches use
 * T_(i-1)(1) and T_i(0). CS_ERR_DEGREE / CS_ERR_UNSUPPORTED (rational). */
cs_err_t cs_varady_set_tangents(cs_varady_t *v, const cs_bezier_t *tan);
/* The twists W_i (mm per domain unit squared) at the corners (corner i starts side i; NULL:
 * zero, the default): the corner patches become Q_i = P_i(0) + d_(i-1) T_(i-1)(1) + d_i T_i(0)
 * + d_(i-1) d_i W_i (seed 002's corner cross derivatives W_i(0)), which is 0 on sides i - 1 and
 * i, so the boundaries are still interpolated. Only the lambda / kappa blending has corner
 * patches; mu ignores them. */
void cs_varady_set_twists(cs_varady_t *v, const double (*twist)[3]);
/* Chooses the blending and the parametrisation (cs_varady_init sets CS_VARADY_MU,
 * CS_VARADY_SIDE). CS_ERR_ARG for unknown values. */
cs_err_t cs_varady_set_scheme(cs_varady_t *v, cs_varady_blend_t blend, cs_varady_param_t param);
/* The parametrisation's (s_i, d_i) of domain point (x, y) for every side (d in domain units,
 * >= 0 inside the polygon). */
void cs_varady_params(const cs_varady_t *v, double x, double y, double s[], double d[]);
/* The seed's blends of n distances d[0..n-1] (any array may be NULL): with
 * D_{a..} = prod_{j not in a..} d_j^2, lambda_i = (D_{i-1,i} + D_{i,i+1}) / sum_j D_{j-1,j}
 * (sum 2), kappa_i = D_{i-1,i} / sum_j D_{j-1,j} (sum 1; corner i is the start of side i),
 * mu_i = D_i / sum_j D_j (sum 1). Where a denominator vanishes (two or more distances zero for
 * mu, more for lambda / kappa) that family is set to 0. */
void cs_varady_blends(size_t n, const double d[], double lambda[], double kappa[], double mu[]);
/* Surface point (mm) at domain point (x, y) inside the polygon (outside: extrapolated). On a
 * domain side it is that boundary curve; at a vertex, the corner. Lambda / kappa:
 * S = sum lambda_i R_i(s_i, d_i) - sum kappa_i Q_i with the corner patch
 * Q_i = P_i(0) + d_{i-1} T_{i-1}(1) + d_i T_i(0) (zero twist), which equals R_{i-1} on side i and
 * R_i on side i - 1, so the corrections cancel the neighbouring ribbons on every side. */
void cs_varady_eval(const cs_varady_t *v, double x, double y, double out[3]);
/* Domain polygon vertex i (i < n), in domain units. */
void cs_varady_vertex(const cs_varady_t *v, size_t i, double out[2]);
/* The image of the domain segment a -> b as cubic Béziers (Hermite pieces through the surface
 * with derivatives by central differences), each within tol_mm of the surface curve at 33
 * samples per piece, split in halves until they are (at most 64 pieces). Writes *count curves
 * to out[0..max-1]. CS_ERR_TOLERANCE when 64 pieces do not reach tol_mm, CS_ERR_FULL when max is
 * too small, CS_ERR_RANGE when a point leaves the coordinate range. */
cs_err_t cs_varady_curve(const cs_varady_t *v, const double a[2], const double b[2], double tol_mm,
                         cs_bezier_t *out, size_t max, size_t *count);

/* Room the toolpath gives cs_varady_patches, and the deepest split (cells down to 2^-10 of a
 * quad's side). */
#define CS_VARADY_MAX_PATCHES 4096
#define CS_VARADY_MAX_DEPTH   10

/* A cell of cs_varady_patches. */
typedef struct {
    size_t quad;    /* which quad (side / vertex index) */
    double a, b, w; /* the cell [a, a + w] x [b, b + w] of the quad's unit square */
} cs_varady_cell_t;

/* Bicubic patches covering the n-sided surface, for tools that need tensor patches (ball-end
 * finishing): the domain is split into n quads (the centre of the vertices, the midpoint of side
 * i - 1, vertex i, the midpoint of side i: counter-clockwise, so Pu x Pv points like the
 * surface's Sx x Sy), each mapped bilinearly from the unit square (cs_varady_quad_point). A cell
 * of the square becomes the Hermite bicubic of the surface's corner points, tangents and twists
 * (central differences in the square's parameters); a cell whose patch is farther than tol_mm
 * from the surface at the same parameters (9 x 9 samples) is split in four (quadtree, down to
 * 2^-CS_VARADY_MAX_DEPTH). Neighbouring cells of different sizes meet within about tol_mm, not
 * exactly. Writes *count patches to out[0 .. max - 1], quad by quad, and (cells may be NULL)
 * the cell each covers, patch parameters (u, v) = ((a' - a) / w, (b' - b) / w); *err_mm (may be
 * NULL) gets the largest sampled distance. CS_ERR_TOLERANCE when the deepest cells miss tol_mm,
 * CS_ERR_FULL when max is too small, CS_ERR_RANGE when a point leaves the coordinate range. */
cs_err_t cs_varady_patches(const cs_varady_t *v, double tol_mm, cs_patch_t *out,
                           cs_varady_cell_t *cells, size_t max, size_t *count, double *err_mm);
/* The domain point of quad i's parameters (a, b) in [0, 1]^2 used by cs_varady_patches. */
void cs_varady_quad_point(const cs_varady_t *v, size_t i, double a, double b, double out[2]);

#endif
