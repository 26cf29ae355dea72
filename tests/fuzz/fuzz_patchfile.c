/* libFuzzer target: arbitrary bytes as a patch file (Newell's indexed format or the .bpt format,
 * host/cs_patchfile.c). Asserts (abort = finding): no out-of-bounds access or undefined
 * behaviour (ASan, UBSan); a diagnostic has the file's name, a line >= 1 and a reason; a file
 * read without error holds at least one patch, each of degree 1..7 in u and v with every index
 * inside the vertex table; reading is deterministic (the same patches twice). With
 * -DCS_FUZZ_SEED_MAIN it writes a seed corpus into argv[1]: the forms below plus the files of
 * ../shared/data/bezier_patches and tests/data/teapot. */
#define _DEFAULT_SOURCE
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <string.h>

#define FUZZ_NAME "fuzz_patchfile"
#include "fuzz_common.h"

#include "../../host/cs_conv.c"
#include "../../host/cs_err_text.c"
#include "../../host/cs_path.c"
#include "../../host/cs_patchfile.c"
#include "../../host/cs_readall.c"

static void check_diag(cs_err_t e, const cs_path_diag_t *d)
{
    if (e == CS_OK || e == CS_ERR_FULL)
        return;
    FUZZ_CHECK(d->loc.file != NULL && d->loc.line >= 1 && d->reason[0] != '\0');
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    cs_patchfile_t a, b;
    cs_path_diag_t d, d2;
    memset(&d, 0, sizeof d);
    memset(&d2, 0, sizeof d2);
    cs_err_t e = cs_patchfile_parse((const char *)data, size, "fuzz", &a, &d);
    check_diag(e, &d);
    cs_err_t e2 = cs_patchfile_parse((const char *)data, size, "fuzz", &b, &d2);
    FUZZ_CHECK(e == e2);
    if (e == CS_OK) {
        FUZZ_CHECK(a.npatches >= 1 && a.npatches == b.npatches && a.nverts == b.nverts);
        FUZZ_CHECK(memcmp(a.vert, b.vert, a.nverts * sizeof *a.vert) == 0);
        for (size_t i = 0; i < a.npatches; i++) {
            FUZZ_CHECK(a.deg[i][0] >= 1 && a.deg[i][0] <= 7 && a.deg[i][1] >= 1 &&
                       a.deg[i][1] <= 7);
            for (size_t k = 0; k < (size_t)(a.deg[i][0] + 1) * (a.deg[i][1] + 1); k++)
                FUZZ_CHECK(a.idx[i][k] < a.nverts);
        }
    } else {
        FUZZ_CHECK(d.loc.line == d2.loc.line && d.loc.col == d2.loc.col);
    }
    cs_patchfile_free(&a);
    cs_patchfile_free(&b);
    return 0;
}

#ifdef CS_FUZZ_SEED_MAIN
static const char *const seeds[] = {
    "1\n1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16\n16\n"
    "0,0,0\n1,0,0\n2,0,0\n3,0,0\n0,1,0\n1,1,1\n2,1,1\n3,1,0\n"
    "0,2,0\n1,2,1\n2,2,1\n3,2,0\n0,3,0\n1,3,0\n2,3,0\n3,3,0\n",
    "1\n3 3\n0 0 0\n1 0 0\n2 0 0\n3 0 0\n0 1 0\n1 1 1\n2 1 1\n3 1 0\n"
    "0 2 0\n1 2 1\n2 2 1\n3 2 0\n0 3 0\n1 3 0\n2 3 0\n3 3 0\n",
    "1\n1 2\n0 0 0\n0 1 0\n0 2 1\n1 0 0\n1 1 2\n1 2 0\n",
    "\xef\xbb\xbf" "1\n1 1\n0 0 0\n0 1 0\n1 0 0\n1 1 0\n",
    "2\n1 1\n0 0 0\n0 1 0\n1 0 0\n1 1 0\n",
    "",
};

int main(int argc, char **argv)
{
    static const char *const dirs[] = {"../shared/data/bezier_patches", "tests/data/teapot", NULL};
    return fuzz_seed_main(argc, argv, seeds, sizeof seeds / sizeof seeds[0], dirs);
}
#endif
