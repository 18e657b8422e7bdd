/*
 * test_encode_jobs.c - `cmz encode -j N` (encode_opts.jobs): the surfaces built, the methods chosen
 * and the tessellation's needs measured on N processes give the bytes and the per-face report of
 * one process, and when workers die holding a face the encoder takes their faces over and still
 * gives them.  The bundled models: as1_pe_203 has faces whose
 * G1FIT trial asks which faces before them keep their surfaces (choose_methods.c chooses them
 * again in order), geo_example has G1FIT faces.
 */
#include "../unit/test_util.h"

#include <stdio.h>
#include <stdlib.h>

#include "encode/encode.h"
#include "model_load.h"

static const char *const models[2] = {"tests/data/as1_pe_203.igs", "tests/data/geo_example.igs"};

/* the model encoded with `jobs` workers, each dying after `die_after` faces (0: never) */
static encode_result encode_with(const char *path, int jobs, int die_after)
{
    loaded_model lm;
    cm_status st;
    cm_status_init(&st);
    cm_err e = model_load(path, &lm, NULL, NULL, &st);
    if (e != CM_OK)
        fail_msg("%s: %s (%s): run the tests from the top of the checkout", path, cm_err_name(e),
                 st.where ? st.where : "?");
    encode_opts o;
    encode_opts_default(&o);
    o.jobs = jobs;
    o.jobs_die_after = die_after;
    o.measure_mesh = 1; /* the --report's per-face mesh measure, made by the workers too */
    encode_result r;
    cm_status_init(&st);
    e = encode_model(&lm, &o, &r, &st);
    if (e != CM_OK)
        fail_msg("%s with %d jobs: %s (%s)", path, jobs, cm_err_name(e), st.where ? st.where : "?");
    model_free(&lm);
    return r;
}

static void assert_same_file(const encode_result *ref, const encode_result *r, const char *path, const char *how)
{
    if (r->len != ref->len || memcmp(r->bytes, ref->bytes, ref->len) != 0)
        fail_msg("%s %s: %zu bytes, other than the %zu of one process", path, how, r->len, ref->len);
    for (int m = 0; m < CM_METHOD_COUNT; m++)
        assert_int_equal(r->faces_by_method[m], ref->faces_by_method[m]);
    /* the report too (cmz encode --report), face by face: a worker's numbers are the encoder's */
    int nf = 0;
    for (int m = 0; m < CM_METHOD_COUNT; m++)
        nf += (int)ref->faces_by_method[m];
    for (int f = 0; f < nf; f++) {
        const face_report *a = &ref->faces[f], *b = &r->faces[f];
        if (a->method != b->method || a->layout != b->layout || a->corner != b->corner || a->why != b->why ||
            memcmp(&a->rebuild_max, &b->rebuild_max, sizeof a->rebuild_max) != 0 ||
            memcmp(&a->rebuild_avg, &b->rebuild_avg, sizeof a->rebuild_avg) != 0 ||
            memcmp(&a->g1_cos, &b->g1_cos, sizeof a->g1_cos) != 0 ||
            memcmp(&a->mesh_dev, &b->mesh_dev, sizeof a->mesh_dev) != 0 || a->fit_m != b->fit_m)
            fail_msg("%s %s: face %d's report differs (mesh %.9g / %.9g mm, error %.9g / %.9g mm)", path, how, f,
                     a->mesh_dev, b->mesh_dev, a->rebuild_max, b->rebuild_max);
    }
    assert_true(nf > 0 && ref->faces[0].mesh_dev >= 0.0); /* measured */
}

static void test_any_job_count_gives_the_same_file(void **state)
{
    (void)state;
    for (int k = 0; k < 2; k++) {
        encode_result ref = encode_with(models[k], 1, 0);
        encode_result r = encode_with(models[k], 2, 0);
        assert_same_file(&ref, &r, models[k], "with -j 2");
        encode_result_free(&r);
        /* three workers on two cores, each dying with its second face */
        r = encode_with(models[k], 3, 2);
        assert_same_file(&ref, &r, models[k], "with -j 3, the workers dying with their second face");
        encode_result_free(&r);
        encode_result_free(&ref);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_any_job_count_gives_the_same_file),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
