/*
 * test_encode_reentrant.c - encode_model keeps no state between calls or
 * across threads: two bundled models encoded one after the other, again in
 * the other order, and side by side in two threads all give the bytes the
 * first encode of each gave in a fresh process.  (A later `cmz encode -j N`
 * encodes faces or files in parallel; before the encoder held its work in
 * one allocated struct, its decoder and workspaces were file-static and two
 * threads wrote into each other's.)
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>

#include "encode/encode.h"
#include "model_load.h"

static const char *const models[2] = {"tests/data/as1_pe_203.igs", "tests/data/geo_example.igs"};

typedef struct job {
    const char *path;
    loaded_model lm;
    encode_result r;
    cm_err e;
} job;

static void load(job *j, const char *path)
{
    memset(j, 0, sizeof *j);
    j->path = path;
    cm_status st;
    cm_status_init(&st);
    cm_err e = model_load(path, &j->lm, NULL, NULL, &st);
    if (e != CM_OK)
        fail_msg("%s: %s (%s): run the tests from the top of the checkout", path, cm_err_name(e),
                 st.where ? st.where : "?");
}

static void *encode_job(void *arg)
{
    job *j = arg;
    encode_opts o;
    encode_opts_default(&o);
    cm_status st;
    cm_status_init(&st);
    j->e = encode_model(&j->lm, &o, &j->r, &st);
    return NULL;
}

static void release(job *j)
{
    encode_result_free(&j->r);
    model_free(&j->lm);
}

static void assert_same_bytes(const job *j, const uint8_t *ref, size_t len, const char *how)
{
    assert_int_equal(j->e, CM_OK);
    if (j->r.len != len || memcmp(j->r.bytes, ref, len) != 0)
        fail_msg("%s encoded %s: %zu bytes, the first encode gave %zu other bytes", j->path, how, j->r.len, len);
}

static void test_sequential_and_parallel_encodes_agree(void **state)
{
    (void)state;
    uint8_t *ref[2];
    size_t ref_len[2];
    /* the first encode of each model in this process: the reference (a fresh process's bytes) */
    for (int m = 0; m < 2; m++) {
        job j;
        load(&j, models[m]);
        encode_job(&j);
        assert_int_equal(j.e, CM_OK);
        ref_len[m] = j.r.len;
        ref[m] = malloc(j.r.len);
        assert_non_null(ref[m]);
        memcpy(ref[m], j.r.bytes, j.r.len);
        release(&j);
    }
    /* the other order, one after the other */
    for (int m = 1; m >= 0; m--) {
        job j;
        load(&j, models[m]);
        encode_job(&j);
        assert_same_bytes(&j, ref[m], ref_len[m], "after the other model");
        release(&j);
    }
    /* side by side: both models at once, twice */
    for (int round = 0; round < 2; round++) {
        static job jobs[2];
        pthread_t th[2];
        for (int m = 0; m < 2; m++)
            load(&jobs[m], models[m]);
        for (int m = 0; m < 2; m++)
            assert_int_equal(pthread_create(&th[m], NULL, encode_job, &jobs[m]), 0);
        for (int m = 0; m < 2; m++)
            assert_int_equal(pthread_join(th[m], NULL), 0);
        for (int m = 0; m < 2; m++) {
            assert_same_bytes(&jobs[m], ref[m], ref_len[m], "in a thread beside the other");
            release(&jobs[m]);
        }
    }
    free(ref[0]);
    free(ref[1]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sequential_and_parallel_encodes_agree),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
