/* What every libFuzzer target in tests/fuzz shares: the check that aborts on a finding, and the
 * seed writer that a target compiled with -DCS_FUZZ_SEED_MAIN runs instead of the fuzzer
 * (scripts/fuzz.sh runs it once with the corpus folder as argv[1]). Header only, included by
 * each target before its own code: scripts/fuzz.sh builds one target source plus the core, and
 * treats every tests/fuzz/fuzz_*.c as a target, so this is not a .c file.
 * The target defines FUZZ_NAME (its name, for the messages) before including this. */
#ifndef FUZZ_COMMON_H
#define FUZZ_COMMON_H

#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef FUZZ_NAME
#error "define FUZZ_NAME (the target's name) before including fuzz_common.h"
#endif

/* A failed check is a finding: say which and abort, so libFuzzer keeps the input. */
#define FUZZ_CHECK(c)                                                                              \
    do {                                                                                           \
        if (!(c)) {                                                                                \
            fprintf(stderr, FUZZ_NAME ": check failed: %s (line %d)\n", #c, __LINE__);             \
            abort();                                                                               \
        }                                                                                          \
    } while (0)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#ifdef CS_FUZZ_SEED_MAIN
/* Writes n bytes to dir/name; exits 1 (the seed run fails) when it cannot. */
static inline void fuzz_write_file(const char *dir, const char *name, const void *data, size_t n)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *fp = fopen(path, "wb");
    if (fp == NULL || fwrite(data, 1, n, fp) != n || fclose(fp) != 0) {
        perror(path);
        exit(1);
    }
}

/* Copies every file of src (when the folder is there: ../shared/data may be missing) into out
 * as data-NNN, numbered on from *k, and runs each through the target once. */
static inline void fuzz_seed_dir(const char *src, const char *out, int *k)
{
    DIR *dp = opendir(src);
    if (dp == NULL)
        return;
    static char buf[1 << 20];
    char name[4096];
    struct dirent *de;
    while ((de = readdir(dp)) != NULL) {
        if (de->d_name[0] == '.')
            continue;
        snprintf(name, sizeof name, "%s/%s", src, de->d_name);
        FILE *f = fopen(name, "rb");
        if (f == NULL)
            continue;
        size_t n = fread(buf, 1, sizeof buf, f);
        fclose(f);
        snprintf(name, sizeof name, "data-%03d", (*k)++);
        fuzz_write_file(out, name, buf, n);
        LLVMFuzzerTestOneInput((const uint8_t *)buf, n);
    }
    closedir(dp);
}

/* The whole seed program of a text-input target: argv[1] is the corpus folder; writes each
 * string of seeds as seed-NN and each file of the folders in dirs (NULL-terminated, may be
 * NULL) as data-NNN, running every one through the target once. Returns main's exit code. */
static inline int fuzz_seed_main(int argc, char **argv, const char *const *seeds, size_t nseeds,
                                 const char *const *dirs)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s corpus-dir\n", argv[0]);
        return 2;
    }
    char name[32];
    for (size_t i = 0; i < nseeds; i++) {
        snprintf(name, sizeof name, "seed-%02zu", i);
        fuzz_write_file(argv[1], name, seeds[i], strlen(seeds[i]));
        LLVMFuzzerTestOneInput((const uint8_t *)seeds[i], strlen(seeds[i]));
    }
    int k = 0;
    for (size_t i = 0; dirs != NULL && dirs[i] != NULL; i++)
        fuzz_seed_dir(dirs[i], argv[1], &k);
    return 0;
}
#endif /* CS_FUZZ_SEED_MAIN */

#endif /* FUZZ_COMMON_H */
