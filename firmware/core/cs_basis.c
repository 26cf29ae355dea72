/* cs_basis: change of basis to cubic Bézier, G_B = (M_B^-1 . M) . G (seed 003). Every fixed
 * matrix below is written as an integer matrix K over a common divisor d, so a Bézier point is
 * round(sum_j K_ij G_j / d): one rounding, error <= 0.5 LSB. Sums are formed in int64
 * (|K_ij G_j| <= 6 * 2^31), so nothing can wrap before the final range check. */
#include "cs_basis.h"

/* out = (K . G) / d, degree-3 polynomial Bézier; every result checked against CS_POS_LIMIT. */
static cs_err_t basis_apply(const int8_t k[4][4], int64_t d, const cs_vec3_t *const g[4],
                            cs_bezier_t *out)
{
    cs_bezier_t b;
    for (unsigned i = 0; i < 4; i++) {
        int64_t r[3];
        for (unsigned axis = 0; axis < 3; axis++) {
            int64_t sum = 0;
            for (unsigned j = 0; j < 4; j++)
                sum += (int64_t)k[i][j] * cs_fixed_vec_get(g[j], axis);
            r[axis] = cs_fixed_div_round(sum, d);
            if (!cs_fixed_pos_ok(r[axis]))
                return CS_ERR_RANGE;
        }
        b.p[i].x = (cs_pos_t)r[0];
        b.p[i].y = (cs_pos_t)r[1];
        b.p[i].z = (cs_pos_t)r[2];
        b.w[i] = CS_WEIGHT_ONE;
    }
    for (unsigned i = 4; i < CS_BEZIER_MAX_POINTS; i++) {
        b.p[i] = cs_fixed_vec(0, 0, 0);
        b.w[i] = CS_WEIGHT_ONE;
    }
    b.degree = 3;
    b.rational = false;
    *out = b;
    return CS_OK;
}

static bool basis_pts_ok(const cs_vec3_t g[4])
{
    for (unsigned j = 0; j < 4; j++)
        if (!cs_fixed_vec_ok(&g[j]))
            return false;
    return true;
}

/* Hermite, G_H = [P1 P4 R1 R4]. Bézier tangents are Q'(0) = 3(B1 - B0), Q'(1) = 3(B3 - B2)
 * (seed 003, "Tangentes sur Bézier"), i.e. G_H = M_BH . G_B; its inverse is
 *   B0 = P1, B1 = P1 + R1/3, B2 = P4 - R4/3, B3 = P4  ->  K / 3 below. */
static const int8_t basis_k_hermite[4][4] = {
    {3, 0, 0, 0},
    {3, 0, 1, 0},
    {0, 3, 0, -1},
    {0, 3, 0, 0},
};

cs_err_t cs_basis_hermite(const cs_vec3_t *p1, const cs_vec3_t *p4, const cs_vec3_t *r1,
                          const cs_vec3_t *r4, cs_bezier_t *out)
{
    if (p1 == NULL || p4 == NULL || r1 == NULL || r4 == NULL || out == NULL)
        return CS_ERR_ARG;
    if (!cs_fixed_vec_ok(p1) || !cs_fixed_vec_ok(p4))
        return CS_ERR_RANGE;
    /* Tangents may exceed the coordinate range (fast curves); only the results are checked. */
    const cs_vec3_t *g[4] = {p1, p4, r1, r4};
    return basis_apply(basis_k_hermite, 3, g, out);
}

/* Uniform B-spline, M_Bs = 1/6 [-1 3 -3 1; 3 -6 3 0; -3 0 3 0; 1 4 1 0] (seed 003). The Bézier
 * points follow from Q(0), Q(1), Q'(0), Q'(1) as for Hermite:
 *   Q(0) = (G0 + 4 G1 + G2)/6, Q'(0) = (G2 - G0)/2 -> B1 = Q(0) + Q'(0)/3 = (4 G1 + 2 G2)/6,
 *   Q(1) = (G1 + 4 G2 + G3)/6, Q'(1) = (G3 - G1)/2 -> B2 = Q(1) - Q'(1)/3 = (2 G1 + 4 G2)/6. */
static const int8_t basis_k_bspline[4][4] = {
    {1, 4, 1, 0},
    {0, 4, 2, 0},
    {0, 2, 4, 0},
    {0, 1, 4, 1},
};

cs_err_t cs_basis_bspline(const cs_vec3_t g[4], cs_bezier_t *out)
{
    if (g == NULL || out == NULL)
        return CS_ERR_ARG;
    if (!basis_pts_ok(g))
        return CS_ERR_RANGE;
    const cs_vec3_t *gp[4] = {&g[0], &g[1], &g[2], &g[3]};
    return basis_apply(basis_k_bspline, 6, gp, out);
}

/* Catmull-Rom, M_CR = 1/2 [-1 3 -3 1; 2 -5 4 -1; -1 0 1 0; 0 2 0 0] (seed 003):
 *   Q(0) = G1, Q'(0) = (G2 - G0)/2, Q(1) = G2, Q'(1) = (G3 - G1)/2, so
 *   B1 = G1 + (G2 - G0)/6, B2 = G2 - (G3 - G1)/6  ->  K / 6 below. */
static const int8_t basis_k_catmull_rom[4][4] = {
    {0, 6, 0, 0},
    {-1, 6, 1, 0},
    {0, 1, 6, -1},
    {0, 0, 6, 0},
};

cs_err_t cs_basis_catmull_rom(const cs_vec3_t g[4], cs_bezier_t *out)
{
    if (g == NULL || out == NULL)
        return CS_ERR_ARG;
    if (!basis_pts_ok(g))
        return CS_ERR_RANGE;
    const cs_vec3_t *gp[4] = {&g[0], &g[1], &g[2], &g[3]};
    return basis_apply(basis_k_catmull_rom, 6, gp, out);
}

/* Beta-spline (Barsky; Foley-van Dam eq. 11.47): with d = delta,
 *   M_beta = 1/d [ -2b1^3   2(b2+b1^3+b1^2+b1)   -2(b2+b1^2+b1+1)  2 ;
 *                   6b1^3  -3(b2+2b1^3+2b1^2)      3(b2+2b1^2)      0 ;
 *                  -6b1^3   6(b1^3-b1)             6b1              0 ;
 *                   2b1^3   b2+4(b1^2+b1)          2                0 ].
 * Row sums of T.M at t = 0, 1 and of its derivative give
 *   Q(0)  = (2b1^3 G0 + (b2+4b1^2+4b1) G1 + 2 G2)/d,
 *   Q'(0) = 6(-b1^3 G0 + (b1^3-b1) G1 + b1 G2)/d,
 *   Q(1)  = (2b1^3 G1 + (b2+4b1^2+4b1) G2 + 2 G3)/d,
 *   Q'(1) = 6(-b1^2 G1 + (b1^2-1) G2 + G3)/d,
 * hence B1 = Q(0) + Q'(0)/3 = ((b2+2b1^3+4b1^2+2b1) G1 + (2+2b1) G2)/d and
 *       B2 = Q(1) - Q'(1)/3 = ((2b1^3+2b1^2) G1 + (b2+2b1^2+4b1+2) G2)/d.
 * Every coefficient is >= 0 and each row sums to d: the Bézier points are convex combinations.
 * With b1 = 1, b2 = 0 (d = 12) this is the uniform B-spline matrix above. */
cs_err_t cs_basis_beta_init(cs_basis_beta_mat_t *m, cs_basis_beta_t beta1, cs_basis_beta_t beta2)
{
    if (m == NULL)
        return CS_ERR_ARG;
    if (beta1 <= 0 || beta1 > CS_BASIS_BETA1_MAX || beta2 < 0 || beta2 > CS_BASIS_BETA2_MAX)
        return CS_ERR_RANGE;
    /* Everything scaled by 2^48 is an exact integer: b1 = a / 2^16, b2 = b / 2^16. */
    const int64_t a = beta1, one = (int64_t)1 << 48;
    const int64_t a3 = a * a * a;           /* b1^3 2^48 <= 2^60 */
    const int64_t a2 = (a * a) << 16;       /* b1^2 2^48 <= 2^56 */
    const int64_t a1 = a << 32;             /* b1   2^48 <= 2^52 */
    const int64_t b = (int64_t)beta2 << 32; /* b2   2^48 <= 2^58 */
    const int64_t delta = 2 * a3 + 4 * a2 + 4 * a1 + b + 2 * one;
    const int64_t c[4][4] = {
        {2 * a3, b + 4 * a2 + 4 * a1, 2 * one, 0},
        {0, b + 2 * a3 + 4 * a2 + 2 * a1, 2 * one + 2 * a1, 0},
        {0, 2 * a3 + 2 * a2, b + 2 * a2 + 4 * a1 + 2 * one, 0},
        {0, 2 * a3, b + 4 * a2 + 4 * a1, 2 * one},
    };
    for (unsigned i = 0; i < 4; i++) {
        for (unsigned j = 0; j < 4; j++) {
            int64_t w;
            /* 0 <= c <= delta, so the weight is in [0, 2^30]: cannot fail. */
            cs_err_t e = cs_fixed_muldiv64(c[i][j], (int64_t)1 << 30, delta, &w);
            if (e != CS_OK)
                return e;
            m->w[i][j] = (int32_t)w;
        }
    }
    return CS_OK;
}

cs_err_t cs_basis_beta(const cs_basis_beta_mat_t *m, const cs_vec3_t g[4], cs_bezier_t *out)
{
    if (m == NULL || g == NULL || out == NULL)
        return CS_ERR_ARG;
    if (!basis_pts_ok(g))
        return CS_ERR_RANGE;
    cs_bezier_t b;
    for (unsigned i = 0; i < 4; i++) {
        int64_t r[3];
        for (unsigned axis = 0; axis < 3; axis++) {
            /* |w| <= 2^30, |G| <= 2^28: four terms stay below 2^60. */
            int64_t sum = 0;
            for (unsigned j = 0; j < 4; j++)
                sum += (int64_t)m->w[i][j] * cs_fixed_vec_get(&g[j], axis);
            r[axis] = cs_fixed_round_shift64(sum, 30);
            if (!cs_fixed_pos_ok(r[axis]))
                return CS_ERR_RANGE;
        }
        b.p[i] = cs_fixed_vec((cs_pos_t)r[0], (cs_pos_t)r[1], (cs_pos_t)r[2]);
        b.w[i] = CS_WEIGHT_ONE;
    }
    for (unsigned i = 4; i < CS_BEZIER_MAX_POINTS; i++) {
        b.p[i] = cs_fixed_vec(0, 0, 0);
        b.w[i] = CS_WEIGHT_ONE;
    }
    b.degree = 3;
    b.rational = false;
    *out = b;
    return CS_OK;
}

static cs_err_t basis_seq_check(const cs_vec3_t *pts, size_t count, size_t min)
{
    if (count < min)
        return CS_ERR_DEGENERATE;
    for (size_t i = 0; i < count; i++)
        if (!cs_fixed_vec_ok(&pts[i]))
            return CS_ERR_RANGE;
    return CS_OK;
}

cs_err_t cs_basis_seq_init(cs_basis_seq_t *s, cs_basis_kind_t kind, const cs_vec3_t *pts,
                           const cs_vec3_t *tangents, size_t count)
{
    if (s == NULL || pts == NULL)
        return CS_ERR_ARG;
    cs_err_t e;
    switch (kind) {
    case CS_BASIS_HERMITE:
        if (tangents == NULL)
            return CS_ERR_ARG;
        e = basis_seq_check(pts, count, 2);
        break;
    case CS_BASIS_BSPLINE:
    case CS_BASIS_CATMULL_ROM:
        e = basis_seq_check(pts, count, 4);
        break;
    default: /* beta-splines need their parameters: cs_basis_seq_init_beta */
        return CS_ERR_ARG;
    }
    if (e != CS_OK)
        return e;
    s->kind = kind;
    s->pts = pts;
    s->tangents = kind == CS_BASIS_HERMITE ? tangents : NULL;
    s->count = count;
    return CS_OK;
}

cs_err_t cs_basis_seq_init_beta(cs_basis_seq_t *s, const cs_vec3_t *pts, size_t count,
                                cs_basis_beta_t beta1, cs_basis_beta_t beta2)
{
    if (s == NULL || pts == NULL)
        return CS_ERR_ARG;
    cs_err_t e = basis_seq_check(pts, count, 4);
    if (e != CS_OK)
        return e;
    e = cs_basis_beta_init(&s->beta, beta1, beta2);
    if (e != CS_OK)
        return e;
    s->kind = CS_BASIS_BETA;
    s->pts = pts;
    s->tangents = NULL;
    s->count = count;
    return CS_OK;
}

size_t cs_basis_seq_segments(const cs_basis_seq_t *s)
{
    if (s == NULL)
        return 0;
    if (s->kind == CS_BASIS_HERMITE)
        return s->count >= 2 ? s->count - 1 : 0;
    return s->count >= 4 ? s->count - 3 : 0;
}

cs_err_t cs_basis_seq_segment(const cs_basis_seq_t *s, size_t index, cs_bezier_t *out)
{
    if (s == NULL || out == NULL)
        return CS_ERR_ARG;
    if (index >= cs_basis_seq_segments(s))
        return CS_END;
    const cs_vec3_t *g = &s->pts[index];
    switch (s->kind) {
    case CS_BASIS_HERMITE:
        return cs_basis_hermite(&g[0], &g[1], &s->tangents[index], &s->tangents[index + 1], out);
    case CS_BASIS_BSPLINE:
        return cs_basis_bspline(g, out);
    case CS_BASIS_CATMULL_ROM:
        return cs_basis_catmull_rom(g, out);
    case CS_BASIS_BETA:
        return cs_basis_beta(&s->beta, g, out);
    default:
        return CS_ERR_ARG;
    }
}
