/* test_error.c - error names and texts, first-failure-wins status, human messages. */
#include "test_util.h"

#include "cm/cm_error.h"
#include "cm/cm_limits_info.h"
#include "cm_report.h"

static void test_names_and_texts(void **state)
{
    (void)state;
    assert_string_equal(cm_err_name(CM_OK), "CM_OK");
    assert_string_equal(cm_err_name(CM_E_LIMIT), "CM_E_LIMIT");
    assert_string_equal(cm_strerror(CM_E_NOSPACE), "output buffer too small");
    assert_string_equal(cm_err_name((cm_err)CM_ERR_COUNT), "CM_E_UNKNOWN");
    assert_string_equal(cm_strerror((cm_err)-1), "unknown error");
    /* every code has a distinct name; the numbers of dropped codes (link protocol 2 carries codes:
       they are never reused) name nothing */
    for (int a = 0; a < (int)CM_ERR_COUNT; a++)
        for (int b = a + 1; b < (int)CM_ERR_COUNT; b++)
            if (cm_err_defined(a) && cm_err_defined(b))
                assert_true(strcmp(cm_err_name((cm_err)a), cm_err_name((cm_err)b)) != 0);
    /* (each from its own place in the pools: a name that is not its code's, a text cut or run
       into the next, reads wrong here) */
    assert_string_equal(cm_err_name(CM_E_STEP), "CM_E_STEP");
    assert_string_equal(cm_strerror(CM_E_STEP), "malformed STEP file");
    assert_string_equal(cm_strerror(CM_OK), "ok");
    for (int code = 0; code < (int)CM_ERR_COUNT; code++)
        if (cm_err_defined(code))
            assert_true(strncmp(cm_err_name((cm_err)code), "CM_", 3) == 0 && strlen(cm_strerror((cm_err)code)) > 1);
    for (int dropped = 18; dropped <= 21; dropped++) {
        assert_false(cm_err_defined(dropped));
        assert_string_equal(cm_err_name((cm_err)dropped), "CM_E_UNKNOWN");
    }
    /* numbers on the wire stay what protocol 2 peers know */
    assert_int_equal(CM_E_IO, 17);
    assert_int_equal(CM_E_PROTOCOL, 22);
    assert_int_equal(CM_E_NOMEM, 23);
}

/* The innermost failure is kept: a caller's later, vaguer failure does not overwrite it. */
static void test_first_failure_wins(void **state)
{
    (void)state;
    cm_status st;
    cm_status_init(&st);
    assert_int_equal(st.code, CM_OK);
    assert_int_equal(cm_fail_limit(&st, CM_LIMIT_MAX_FACES, 20000, 16384, "inner"), CM_E_LIMIT);
    assert_int_equal(cm_fail_at(&st, CM_E_FORMAT, 99, "outer"), CM_E_FORMAT);
    assert_int_equal(st.code, CM_E_LIMIT);
    assert_int_equal(st.limit, CM_LIMIT_MAX_FACES);
    assert_int_equal(st.need, 20000);
    assert_int_equal(st.have, 16384);
    assert_string_equal(st.where, "inner");
    assert_int_equal(st.offset, CM_NO_OFFSET);
    /* a NULL status is allowed everywhere */
    assert_int_equal(cm_fail(NULL, CM_E_RANGE, "x"), CM_E_RANGE);
    cm_status_init(NULL);
}

static void test_format_limit_message(void **state)
{
    (void)state;
    cm_status st;
    char buf[256];
    cm_status_init(&st);
    cm_fail_limit(&st, CM_LIMIT_MAX_FACES, 20000, CM_MAX_FACES, "header");
    cm_fail_at(&st, CM_E_LIMIT, 12, "ignored");
    cm_format_status(buf, sizeof buf, &st);
    char expect[160];
    snprintf(expect, sizeof expect, "needs MAX_FACES=20000, this build (profile %s) has %d", cm_profile_name,
             CM_MAX_FACES);
    if (!strstr(buf, expect))
        fail_msg("message '%s' lacks '%s'", buf, expect);
    /* truncation keeps the buffer terminated */
    cm_format_status(buf, 8, &st);
    assert_int_equal(strlen(buf), 7);
}

static void test_format_offset_message(void **state)
{
    (void)state;
    cm_status st;
    char buf[256];
    cm_status_init(&st);
    cm_fail_at(&st, CM_E_CRC, 4242, "faces");
    cm_format_status(buf, sizeof buf, &st);
    assert_non_null(strstr(buf, "byte 4242: "));
    assert_non_null(strstr(buf, "CM_E_CRC"));
    assert_non_null(strstr(buf, "[in faces]"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_names_and_texts),
        cmocka_unit_test(test_first_failure_wins),
        cmocka_unit_test(test_format_limit_message),
        cmocka_unit_test(test_format_offset_message),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
