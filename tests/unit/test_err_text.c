/* test_err_text: host/cs_err_text.c gives every code of the table (firmware/core/cs_err.h) its
 * own sentence and name, and a fixed answer for values outside the table. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "cs_err_text.h"

typedef struct {
    cs_err_t code;
    const char *name, *text;
} row_t;

#define ROW_(name, value, text) {name, #name, text},
static const row_t rows[] = {CS_ERR_TABLE(ROW_)};
#undef ROW_
#define NROWS (sizeof rows / sizeof rows[0])

static void test_every_code(void **state)
{
    (void)state;
    assert_int_equal(NROWS, CS_ERR_COUNT_);
    for (size_t i = 0; i < NROWS; i++) {
        assert_int_equal(rows[i].code, (cs_err_t)i); /* values are 0..n-1, in order */
        assert_string_equal(cs_err_text(rows[i].code), rows[i].text);
        assert_string_equal(cs_err_name(rows[i].code), rows[i].name);
        assert_true(strlen(cs_err_text(rows[i].code)) > 3);
        for (size_t j = 0; j < i; j++)
            assert_string_not_equal(cs_err_text(rows[i].code), cs_err_text(rows[j].code));
    }
    assert_string_equal(cs_err_text(CS_ERR_RANGE),
                        "value outside the fixed-point format's accepted range");
}

static void test_unknown(void **state)
{
    (void)state;
    assert_string_equal(cs_err_text((cs_err_t)999), "unknown status code");
    assert_string_equal(cs_err_name((cs_err_t)999), "CS_ERR_?");
    assert_string_equal(cs_err_text(CS_ERR_COUNT_), "unknown status code");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_code),
        cmocka_unit_test(test_unknown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
