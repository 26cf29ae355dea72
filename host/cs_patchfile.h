/* cs_patchfile: reads Bézier patch sets in two text formats, told apart by the line after the
 * patch count:
 *  - Newell's indexed format (the Utah teapot's): a patch count; one line of 16 one-based vertex
 *    indices per patch (k = 4 i + j: i runs along u, j along v); a vertex count; one "x,y,z"
 *    line per vertex (bicubic patches);
 *  - the .bpt format: a patch count; per patch a line "degu degv" (each 1..CS_PATCH_MAX_DEGREE)
 *    then (degu + 1)(degv + 1) lines "x y z", point k = i (degv + 1) + j (i along u).
 * Commas and blanks both separate numbers; blank lines are skipped. Owns the parsed file and
 * its conversion to the core's cs_patch_t (with a scale, range-checked); bad input is
 * "file:line:col: reason", and a file of neither shape says what each format expected. */
#ifndef CS_PATCHFILE_H
#define CS_PATCHFILE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "cs_patch.h"
#include "cs_path.h"

/* Most control points of one patch (either format). */
#define CS_PATCHFILE_MAX_POINTS (CS_PATCH_MAX_POINTS * CS_PATCH_MAX_POINTS)

typedef struct {
    char *file;                             /* the name diagnostics use (owned) */
    bool bpt;                               /* read as .bpt (else Newell's format) */
    size_t npatches;                        /* patches read */
    size_t (*idx)[CS_PATCHFILE_MAX_POINTS]; /* 0-based vertex index of each control point */
    uint8_t (*deg)[2];   /* degrees in u and v of each patch (3, 3 in Newell's format) */
    unsigned *line;      /* source line of each patch */
    size_t nverts;       /* vertices read */
    double (*vert)[3];   /* x, y, z as written */
    unsigned *vert_line; /* source line of each vertex */
} cs_patchfile_t;

/* Reads filename ("-" = standard input, named <stdin>). On CS_ERR_PARSE / CS_ERR_RANGE (a
 * count or an index out of range, a number not finite) / CS_ERR_IO, *diag says where and why
 * and *pf holds only the file name *diag points to; CS_ERR_FULL when out of memory. Call
 * cs_patchfile_free in every case (after printing the diagnostic). */
cs_err_t cs_patchfile_read(const char *filename, cs_patchfile_t *pf, cs_path_diag_t *diag);
/* Same, from a string already in memory (name used in diagnostics). */
cs_err_t cs_patchfile_parse(const char *text, size_t len, const char *name, cs_patchfile_t *pf,
                            cs_path_diag_t *diag);
/* Patch i as a cs_patch_t of its degrees with every coordinate multiplied by scale (mm per file
 * unit). CS_ERR_RANGE with *diag (at the offending vertex's line) when a coordinate leaves
 * +/-CS_POS_LIMIT_MM; CS_ERR_ARG for i out of range. */
cs_err_t cs_patchfile_patch(const cs_patchfile_t *pf, size_t i, double scale, cs_patch_t *out,
                            cs_path_diag_t *diag);
/* Writes n bicubic patches (deg 3 x 3, else CS_ERR_DEGREE) to f in Newell's format, one vertex
 * per control point (16 per patch, no sharing), coordinates in mm with 6 decimals (exact for
 * the 2^-16 mm grid up to rounding of the last digit). CS_ERR_IO when writing fails. */
cs_err_t cs_patchfile_write(FILE *f, const cs_patch_t *patches, size_t n);
/* Frees everything; *pf is empty afterwards (free on an empty one is fine). */
void cs_patchfile_free(cs_patchfile_t *pf);

#endif
