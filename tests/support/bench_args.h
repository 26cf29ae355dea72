/* bench_args: the command line every benchmark (tests/bench/bench_*.c) shares: --help or -h
 * prints its usage and exits 0; an option it does not know, or more arguments than it takes,
 * is refused (usage on stderr, exit 2) before anything runs or any file is written. Benchmarks
 * and tests only. */
#ifndef BENCH_ARGS_H
#define BENCH_ARGS_H

/* The exit status main must return now (0 after --help, 2 after a bad command line), or -1 to
 * go on. usage: the whole usage text (printed as is); max_args: positional arguments taken at
 * most, -1 for any number. Not thread-safe (prints). */
int bench_args_check(int argc, char **argv, const char *usage, int max_args);

#endif
