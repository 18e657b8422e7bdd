/* test_limits.c - the profile named by the build took effect, and the limits table is consistent. */
#include "test_util.h"

#include "cm/cm_error.h"
#include "cm/cm_limits_info.h"

/* The Makefile compiles this file once per profile with CM_EXPECT_PROFILE set
 * to the profile it asked for; a mismatch means the -DCM_PROFILE plumbing broke. */
static void test_profile_name_matches_build(void **state)
{
    (void)state;
    assert_string_equal(cm_profile_name, CM_EXPECT_PROFILE);
    assert_string_equal(CM_PROFILE_NAME, CM_EXPECT_PROFILE);
}

/* Values that differ between profiles: each profile's own header set them. */
static void test_profile_values(void **state)
{
    (void)state;
    if (strcmp(cm_profile_name, "tiny") == 0) {
        assert_int_equal(CM_MAX_DEGREE, 3);
        assert_int_equal(CM_MAX_LOOP_EDGES, 4);
        assert_int_equal(CM_MAX_FACES, 8);
        assert_int_equal(CM_MAX_TRIS, 512);
    } else if (strcmp(cm_profile_name, "host") == 0) {
        assert_int_equal(CM_MAX_DEGREE, 15);
        assert_int_equal(CM_MAX_FACES, 1048576);
    } else if (strcmp(cm_profile_name, "terminal") == 0) {
        /* the terminal uses cm_limits.h's documented defaults */
        assert_int_equal(CM_MAX_DEGREE, 9);
        assert_int_equal(CM_MAX_FACES, 4096);
        assert_int_equal(CM_MAX_TRIS, 524288);
        /* issue 15: a decode in 3.5 MiB of static storage, the program's own in 0.5 MiB */
        assert_true(CM_DECODE_STATE_BUDGET + CM_PROGRAM_STATIC_BUDGET <= 4u * 1048576u);
    } else {
        fail_msg("unknown profile %s", cm_profile_name);
    }
}

/* The run-time table equals the macros and respects every hard bound. */
static void test_table_matches_macros(void **state)
{
    (void)state;
    assert_int_equal(cm_limit_table[CM_LIMIT_MAX_DEGREE].value, CM_MAX_DEGREE);
    assert_int_equal(cm_limit_table[CM_LIMIT_MAX_FACES].value, CM_MAX_FACES);
    assert_int_equal(cm_limit_table[CM_LIMIT_MAX_LSQ_BAND].value, CM_MAX_LSQ_BAND);
    assert_int_equal(cm_limit_table[CM_LIMIT_STACK_BUDGET].value, CM_STACK_BUDGET);
    for (unsigned i = 0; i < CM_LIMIT_COUNT; i++) {
        const cm_limit_info *l = &cm_limit_table[i];
        assert_true(strlen(l->name) > 3 && strlen(l->unit) > 0);
        assert_true(strlen(l->doc) > 10);
        assert_true(l->value >= 1 && l->value <= l->hard_max);
    }
    assert_ptr_equal(cm_limit_get(0), &cm_limit_table[0]);
    assert_null(cm_limit_get(CM_LIMIT_COUNT));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_profile_name_matches_build),
        cmocka_unit_test(test_profile_values),
        cmocka_unit_test(test_table_matches_macros),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
