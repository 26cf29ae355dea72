/* cs_lensub: seed 003's length-based recursive subdivision ("Subdivision récursive basée sur la
 * longueur: si la distance entre Q(t) et Q(t + dt) est plus grande que le seuil désiré,
 * subdivise dt"), as a pull iterator with no recursion and no stack: dyadic parameter steps
 * dt = 2^-k (k <= CS_LENSUB_MAX_DEPTH) halved while the chord is longer than the threshold and,
 * after each accepted chord, grown back to the largest dyadic step the position allows (the
 * same points, in the same order, as the recursion). Points by de Casteljau
 * (cs_bezier_eval) or Horner (cs_horner). Owns the iterator state.
 * What it promises: every chord at most max_len long. Not a deviation from the curve (a chord
 * whose ends are close may skip a loop between them); `flatten --stats` measures that. */
#ifndef CS_LENSUB_H
#define CS_LENSUB_H

#include <stdbool.h>
#include <stdint.h>

#include "cs_bezier.h"
#include "cs_horner.h"

/* Finest step 2^-24 of the parameter. */
#define CS_LENSUB_MAX_DEPTH 24

typedef struct {
    cs_bezier_t c;
    cs_horner_t h;
    bool horner;
    uint64_t max2;    /* max_len^2, LSB^2 */
    uint32_t t, step; /* position and step, units of 2^-CS_LENSUB_MAX_DEPTH */
    cs_vec3_t cur;    /* the point at t */
} cs_lensub_t;

/* Starts at c's first point; chords at most max_len (LSB, >= 1, else CS_ERR_TOLERANCE);
 * horner: evaluate by cs_horner (polynomial segments only, CS_ERR_UNSUPPORTED otherwise).
 * cs_bezier errors for a malformed segment. Not for ISRs (copies the segment). */
cs_err_t cs_lensub_begin(cs_lensub_t *s, const cs_bezier_t *c, cs_pos_t max_len, bool horner);
/* Next chord's end point into *out; CS_END after the last (which is c's last point exactly);
 * CS_ERR_DEPTH when a step of 2^-CS_LENSUB_MAX_DEPTH is still longer than max_len. Bounded:
 * at most CS_LENSUB_MAX_DEPTH + 1 evaluations per point. */
cs_err_t cs_lensub_next(cs_lensub_t *s, cs_vec3_t *out);

#endif
