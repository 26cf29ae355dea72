/* test_gexpr: LinuxCNC real values and parameters (host/cs_gexpr.c) against values worked out by
 * hand from LinuxCNC's G-code reference ("Overview": Parameter Value, Expressions and Binary
 * Operations, Unary Operation Value, Parameter Setting; "O Codes": call arguments). Each sentence
 * that decides a case is quoted beside it. Tolerance: 1e-12 on values that double computes
 * exactly or to its last bits. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "cs_gexpr.h"

#define EPS 1e-12

static cs_gexpr_store_t ST;
static cs_gexpr_fail_t F;

/* The whole of text as one real value; *end = bytes read. */
static cs_err_t val(const char *text, double *v, size_t *end)
{
    size_t i = 0;
    memset(&F, 0, sizeof F);
    cs_err_t e = cs_gexpr_real(&ST, text, strlen(text), &i, v, &F);
    if (end)
        *end = i;
    return e;
}

static void expect_val(const char *text, double want)
{
    double v = NAN;
    size_t end;
    cs_err_t e = val(text, &v, &end);
    if (e != CS_OK || fabs(v - want) > EPS || end != strlen(text))
        print_error("%s: got %d %.15g (read %zu) '%s', want %.15g\n", text, e, v, end, F.reason,
                    want);
    assert_int_equal(e, CS_OK);
    assert_true(fabs(v - want) <= EPS);
    assert_int_equal(end, strlen(text));
}

static void expect_fail(const char *text, cs_err_t code, size_t at)
{
    double v;
    cs_err_t e = val(text, &v, NULL);
    if (e != code || F.at != at)
        print_error("%s: got %d at %zu '%s', want %d at %zu\n", text, e, F.at, F.reason, code, at);
    assert_int_equal(e, code);
    assert_int_equal(F.at, at);
    assert_true(strlen(F.reason) > 0);
}

static int setup(void **state)
{
    (void)state;
    return cs_gexpr_init(&ST) == CS_OK ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    cs_gexpr_free(&ST);
    return 0;
}

/* "A number consists of (1) an optional plus or minus sign, followed by (2) zero to many digits,
 * followed, possibly, by (3) one decimal point, followed by (4) zero to many digits - provided
 * that there is at least one digit somewhere in the number." */
static void test_numbers(void **state)
{
    (void)state;
    expect_val("341", 341);
    expect_val("-0.8807", -0.8807);
    expect_val("+.5", 0.5);
    expect_val("7.", 7);
    expect_fail(".", CS_ERR_PARSE, 0);
    /* No exponent form in G-code. */
    expect_fail("1e3", CS_ERR_PARSE, 1);
    expect_fail("2.5E-2", CS_ERR_PARSE, 3);
}

/* "[2.0 / 3 * 1.5 - 5.5 / 11.0] is equivalent to [[[2.0 / 3] * 1.5] - [5.5 / 11.0]] which is
 * equivalent to [1.0 - 0.5] which is 0.5"; precedence, highest first: "** / * / MOD / + - /
 * EQ NE GT GE LT LE / AND OR XOR". */
static void test_precedence(void **state)
{
    (void)state;
    expect_val("[2.0 / 3 * 1.5 - 5.5 / 11.0]", 0.5);
    expect_val("[2 + 3 * 2 ** 2]", 14);                 /* 2 + (3 * 4) */
    expect_val("[2 ** 3 ** 2]", 64);                    /* left first: (2**3)**2 */
    expect_val("[10 - 4 - 3]", 3);                      /* left first */
    expect_val("[1 + 1 EQ 2]", 1);                      /* (1 + 1) EQ 2 */
    expect_val("[1 LT 2 AND 3 GT 4]", 0);               /* (1 < 2) AND (3 > 4) */
    expect_val("[0 OR 2 XOR 1]", 0);                    /* (0 OR 2) = 1, 1 XOR 1 = 0 */
    expect_val("[7 MOD 3 * 2]", 2);                     /* MOD and * share a level: (7 MOD 3) * 2 */
    expect_val("[ 1 + acos[0] - [#3 ** [4.0/2]]]", 91); /* #3 = 0 */
}

/* "The logical operations and modulus are to be performed on any real numbers, not just on
 * integers. The number zero is equivalent to logical false, and any non-zero number is
 * equivalent to logical true." MOD's result is made non-negative (LinuxCNC's interpreter). */
static void test_logic_and_mod(void **state)
{
    (void)state;
    expect_val("[0.5 AND 2]", 1);
    expect_val("[0 AND 2]", 0);
    expect_val("[5.5 MOD 2]", 1.5);
    expect_val("[-1 MOD 3]", 2);
    expect_val("[1 EQ 1.00005]", 1); /* EQ within 0.0001 */
    expect_val("[1 NE 1.0002]", 1);
    expect_val("[2 GE 2]", 1);
    expect_val("[2 LE 1]", 0);
}

/* "Arguments to unary operations which take angle measures (COS, SIN, and TAN) are in degrees.
 * Values returned by unary operations which return angle measures (ACOS, ASIN, and ATAN) are also
 * in degrees." "FIX[2.8] = 2 and FIX[-2.8] = -3"; "FUP[2.8] = 3 and FUP[-2.8] = -2". */
static void test_functions(void **state)
{
    (void)state;
    expect_val("SIN[90]", 1);
    expect_val("COS[180]", -1);
    expect_val("TAN[45]", tan(M_PI / 4));
    expect_val("ASIN[1]", 90);
    expect_val("ACOS[0]", 90);
    expect_val("ATAN[2]/[1+3]", atan2(2, 4) * 180 / M_PI);
    expect_val("ATAN[1]/[-1]", 135);
    expect_val("FIX[2.8]", 2);
    expect_val("FIX[-2.8]", -3);
    expect_val("FUP[2.8]", 3);
    expect_val("FUP[-2.8]", -2);
    expect_val("ROUND[2.5]", 3);
    expect_val("ROUND[-2.5]", -3);
    expect_val("ABS[-4]", 4);
    expect_val("SQRT[16]", 4);
    expect_val("EXP[1]", exp(1));
    expect_val("LN[EXP[2]]", 2);
    expect_val("-SIN[30]", -0.5);
    expect_val("sin[30]", 0.5); /* "Input is case insensitive" */
    expect_fail("ASIN[2]", CS_ERR_RANGE, 0);
    expect_fail("LN[0]", CS_ERR_RANGE, 0);
    expect_fail("SQRT[-1]", CS_ERR_RANGE, 0);
    expect_fail("[1/0]", CS_ERR_RANGE, 2);
    expect_fail("[-8 ** 0.5]", CS_ERR_RANGE, 4);
    expect_fail("ATAN[1]", CS_ERR_PARSE, 7);
    expect_fail("FOO[1]", CS_ERR_PARSE, 0);
    expect_fail("[1 + ]", CS_ERR_PARSE, 5);
    expect_fail("[1 2]", CS_ERR_PARSE, 3);
}

/* "The # character takes precedence over other operations, so that, for example, #1+2 means the
 * number found by adding 2 to the value of parameter 1, not the value found in parameter 3. Of
 * course, #[1+2] does mean the value found in parameter 3. The # character may be repeated; for
 * example ##2 means the value of the parameter whose index is the (integer) value of parameter
 * 2." */
static void test_parameters(void **state)
{
    (void)state;
    ST.num[1] = 10;
    ST.num[2] = 3;
    ST.num[3] = 7;
    expect_val("[#1+2]", 12);
    expect_val("#[1+2]", 7);
    expect_val("##2", 7);
    expect_val("-#1", -10);
    expect_fail("#5400", CS_ERR_PARSE, 1);
    expect_fail("#1.5", CS_ERR_PARSE, 1);
    expect_fail("#<missing>", CS_ERR_PARSE, 0);
    /* A deep nest is refused, not a stack overflow. */
    char deep[4 * CS_GEXPR_MAX_NEST + 8];
    size_t k = 0;
    for (int i = 0; i < CS_GEXPR_MAX_NEST + 2; i++)
        deep[k++] = '[';
    deep[k++] = '1';
    for (int i = 0; i < CS_GEXPR_MAX_NEST + 2; i++)
        deep[k++] = ']';
    deep[k] = '\0';
    double v;
    assert_int_equal(val(deep, &v, NULL), CS_ERR_PARSE);
}

/* Settings wait for the end of the line; named parameters are lower-cased with blanks removed;
 * "#<_name>" is global, "#<name>" local to the call level that set it. */
static void test_settings_and_scope(void **state)
{
    (void)state;
    const char *line = "#3 = [#3 + 1] #<My Var> = 2.5 #<_g> = #3";
    size_t n = strlen(line), i = 0;
    ST.num[3] = 15;
    for (int k = 0; k < 3; k++) {
        while (line[i] == ' ')
            i++;
        assert_int_equal(cs_gexpr_assign(&ST, line, n, &i, &F), CS_OK);
    }
    assert_true(ST.num[3] == 15); /* not yet */
    assert_int_equal(cs_gexpr_commit(&ST), CS_OK);
    expect_val("#3", 16);
    expect_val("#<myvar>", 2.5);
    expect_val("#<_g>", 15); /* read with the line's old #3 */
    /* A call: #1.. set, the rest of #1..#30 kept; locals of the caller hidden, globals seen. */
    ST.num[1] = 1;
    ST.num[2] = 2;
    double args[1] = {9};
    assert_int_equal(cs_gexpr_call(&ST, args, 1), CS_OK);
    expect_val("[#1 * 10 + #2]", 92);
    expect_fail("#<myvar>", CS_ERR_PARSE, 0);
    expect_val("#<_g>", 15);
    assert_int_equal(cs_gexpr_set_named(&ST, "myvar", 4), CS_OK);
    ST.num[1] = 100;
    cs_gexpr_return(&ST);
    expect_val("[#1 + #<myvar>]", 3.5); /* #1 restored; the caller's own myvar */
    /* "The maximum subroutine nesting level is 10." */
    for (int k = 0; k < CS_GEXPR_MAX_CALLS; k++)
        assert_int_equal(cs_gexpr_call(&ST, args, 1), CS_OK);
    assert_int_equal(cs_gexpr_call(&ST, args, 1), CS_ERR_FULL);
    for (int k = 0; k < CS_GEXPR_MAX_CALLS; k++)
        cs_gexpr_return(&ST);
    expect_val("#1", 1);
    /* "#1 = " alone, "#1 2", a setting without '=' */
    i = 0;
    assert_int_equal(cs_gexpr_assign(&ST, "#1 2", 4, &i, &F), CS_ERR_PARSE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_numbers),       cmocka_unit_test(test_precedence),
        cmocka_unit_test(test_logic_and_mod), cmocka_unit_test(test_functions),
        cmocka_unit_test(test_parameters),    cmocka_unit_test(test_settings_and_scope),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
