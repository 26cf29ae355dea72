/* bench_curves: see bench_curves.h. */
#include "bench_curves.h"

#include <glob.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cs_svgdoc.h"

void bench_set_add(bench_set_t *s, const cs_bezier_t *c)
{
    if (s->n == s->cap) {
        s->cap = s->cap ? 2 * s->cap : 64;
        s->c = realloc(s->c, s->cap * sizeof *s->c);
        if (!s->c)
            abort();
    }
    s->c[s->n++] = *c;
}

double bench_rng_unit(bench_rng_t *g)
{
    g->s ^= g->s << 13;
    g->s ^= g->s >> 7;
    g->s ^= g->s << 17;
    return (double)(g->s >> 11) * (1.0 / 9007199254740992.0);
}

double bench_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

size_t bench_svg_curves(bench_set_t *s, char *const *files, size_t nfiles,
                        bool (*keep)(const cs_bezier_t *in, cs_bezier_t *out))
{
    glob_t g;
    memset(&g, 0, sizeof g);
    bool globbed = false;
    /* ../shared is the shared data beside the repository; the copies in tests/data/svg stand
     * in when it is absent. */
    if (nfiles == 0 && (glob("../shared/data/svg/*/*.svg", 0, NULL, &g) == 0 ||
                        glob("tests/data/svg/*/*.svg", 0, NULL, &g) == 0)) {
        files = g.gl_pathv;
        nfiles = g.gl_pathc;
        globbed = true;
    }
    size_t left_out = 0;
    for (size_t i = 0; i < nfiles; i++) {
        cs_path_t path;
        cs_path_init(&path);
        cs_svgdoc_opts_t o;
        cs_svgdoc_opts_init(&o);
        o.warn = NULL;
        cs_path_diag_t d;
        if (cs_svgdoc_read_file(files[i], &o, &path, &d, NULL) == CS_OK) {
            for (size_t j = 0; j < path.n; j++) {
                const cs_bezier_t *c = &path.elems[j].curve;
                cs_bezier_t k;
                if (c->degree < 2)
                    continue;
                if (keep == NULL)
                    bench_set_add(s, c);
                else if (keep(c, &k))
                    bench_set_add(s, &k);
                else
                    left_out++;
            }
        } else {
            cs_path_diag_print(stderr, &d);
        }
        cs_path_free(&path);
    }
    if (globbed)
        globfree(&g);
    return left_out;
}
