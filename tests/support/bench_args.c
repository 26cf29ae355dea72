/* bench_args: see bench_args.h. */
#include "bench_args.h"

#include <stdio.h>
#include <string.h>

int bench_args_check(int argc, char **argv, const char *usage, int max_args)
{
    int positional = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            fputs(usage, stdout);
            return 0;
        }
        if (a[0] == '-') {
            fprintf(stderr, "%s: unknown option '%s'\n%s", argv[0], a, usage);
            return 2;
        }
        positional++;
    }
    if (max_args >= 0 && positional > max_args) {
        fprintf(stderr, "%s: too many arguments\n%s", argv[0], usage);
        return 2;
    }
    return -1;
}
