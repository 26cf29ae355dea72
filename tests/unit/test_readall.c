/* test_readall: the bounded reader (host/cs_readall) and the message escaping of host/cs_path
 * (issue 17 items 4 and 5). Expected values written by hand: sizes around the limit, the kinds
 * of file refused by regular_only, and each control character's "\xHH" form. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cs_path.h"
#include "cs_readall.h"

static char dir[64];

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/cs-readall-XXXXXX");
    return mkdtemp(dir) ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    return system(cmd) == 0 ? 0 : -1;
}

static void write_file(const char *name, size_t n)
{
    FILE *f = fopen(name, "wb");
    assert_non_null(f);
    for (size_t i = 0; i < n; i++)
        fputc('a' + (int)(i % 26), f);
    fclose(f);
}

/* Exactly the limit reads; one byte more is refused with CS_ERR_RANGE naming the file. */
static void test_limit(void **state)
{
    (void)state;
    char name[128];
    snprintf(name, sizeof name, "%s/f.txt", dir);
    write_file(name, 1000);
    char *buf = NULL;
    size_t len = 0;
    cs_path_diag_t d;
    assert_int_equal(cs_readall(name, 1000, false, &buf, &len, &d), CS_OK);
    assert_int_equal(len, 1000);
    assert_int_equal(buf[999], 'a' + 999 % 26);
    assert_int_equal(buf[1000], '\0');
    free(buf);
    assert_int_equal(cs_readall(name, 999, false, &buf, &len, &d), CS_ERR_RANGE);
    assert_string_equal(d.loc.file, name);
    assert_non_null(strstr(d.reason, "larger than the input limit"));
    /* /dev/zero (endless) stops at the limit too */
    assert_int_equal(cs_readall("/dev/zero", 4096, false, &buf, &len, &d), CS_ERR_RANGE);
}

/* regular_only: a FIFO (opened without blocking), a device and a directory are refused. */
static void test_regular_only(void **state)
{
    (void)state;
    char fifo[128];
    snprintf(fifo, sizeof fifo, "%s/p", dir);
    assert_int_equal(mkfifo(fifo, 0600), 0);
    char *buf = NULL;
    size_t len = 0;
    cs_path_diag_t d;
    assert_int_equal(cs_readall(fifo, 0, true, &buf, &len, &d), CS_ERR_IO);
    assert_non_null(strstr(d.reason, "a FIFO, not a regular file"));
    assert_int_equal(cs_readall("/dev/null", 0, true, &buf, &len, &d), CS_ERR_IO);
    assert_non_null(strstr(d.reason, "a character device"));
    assert_int_equal(cs_readall(dir, 0, true, &buf, &len, &d), CS_ERR_IO);
    assert_non_null(strstr(d.reason, "a directory"));
    assert_true(cs_readall_parse_mb("64", &len) && len == (size_t)64 << 20);
    assert_false(cs_readall_parse_mb("0", &len));
    assert_false(cs_readall_parse_mb("-1", &len));
    assert_false(cs_readall_parse_mb("1e3", &len));
    assert_false(cs_readall_parse_mb("4097", &len));
}

/* Every control character (0x01..0x1f, 0x7f) comes out as \xHH; other bytes as they are. */
static void test_escape(void **state)
{
    (void)state;
    char out[64];
    cs_path_escape(out, sizeof out, "a\x1b]0;t\x07z\x7f\t\n");
    assert_string_equal(out, "a\\x1b]0;t\\x07z\\x7f\\x09\\x0a");
    /* no room for a whole escape: cut before it, never half of one */
    cs_path_escape(out, 5, "ab\x1b");
    assert_string_equal(out, "ab");
    cs_path_diag_t d;
    cs_path_loc_t l = {"f", 1, 2};
    cs_path_diag_set(&d, CS_ERR_PARSE, l, "'%s'", "\x1b[2J");
    assert_string_equal(d.reason, "'\\x1b[2J'");
    char *s = NULL;
    size_t n = 0;
    FILE *f = open_memstream(&s, &n);
    cs_path_loc_t l2 = {"a\x1b"
                        "b",
                        3, 4};
    d.loc = l2;
    cs_path_diag_print(f, &d);
    fclose(f);
    assert_string_equal(s, "a\\x1bb:3:4: '\\x1b[2J'\n");
    free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_limit, setup, teardown),
        cmocka_unit_test_setup_teardown(test_regular_only, setup, teardown),
        cmocka_unit_test(test_escape),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
