/* cs_patchfile: reads bicubic Bézier patch sets in Newell's indexed text format (the Utah
 * teapot's): a patch count; one line of 16 one-based vertex indices per patch (k = 4 i + j:
 * i runs along u, j along v); a vertex count; one "x,y,z" line per vertex. Commas and blanks
 * both separate numbers; blank lines are skipped. Owns the parsed file and its conversion to
 * the core's cs_patch_t (with a scale, range-checked); bad input is "file:line:col: reason". */
#ifndef CS_PATCHFILE_H
#define CS_PATCHFILE_H

#include <stddef.h>
#include <stdio.h>

#include "cs_patch.h"
#include "cs_path.h"

typedef struct {
    char *file;          /* the name diagnostics use (owned) */
    size_t npatches;     /* patches read */
    size_t (*idx)[16];   /* 0-based vertex index of each control point */
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
/* Patch i as a bicubic cs_patch_t with every coordinate multiplied by scale (mm per file
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
