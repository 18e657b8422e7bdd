/*
 * test_corpus.c - every IGES model in ../shared/models imports, its face
 * count matches CATALOG.tsv (distinct 144/143/510 face entities; untrimmed
 * patches are reported separately) and every closed solid pairs all its
 * edges.  Skipped, with a message, when ../shared/models is absent (set
 * CM_SHARED_MODELS to another checkout of it).
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <stdio.h>
#include <stdlib.h>

#include "cm/cm_format.h"
#include "encode/encode.h"
#include "model_load.h"

static const char *models_dir(void)
{
    const char *d = getenv("CM_SHARED_MODELS");
    return d ? d : "../shared/models";
}

/* the shared corpus's file `rel` (path[cap] gets its path), open; the test is skipped, with a
   message, when it is not there */
static FILE *open_shared(char *path, size_t cap, const char *rel, const char *mode)
{
    snprintf(path, cap, "%s/%s", models_dir(), rel);
    FILE *f = fopen(path, mode);
    if (!f) {
        print_message("SKIP: %s not found (the shared corpus is not beside this checkout)\n", path);
        skip();
    }
    return f;
}

/* count of entity `type` in a catalog "entity_counts" field like "102:24 110:48 144:10" */
static int catalog_count(const char *counts, int type)
{
    char key[16];
    snprintf(key, sizeof key, "%d:", type);
    for (const char *p = counts; (p = strstr(p, key)) != NULL; p++)
        if (p == counts || p[-1] == ' ')
            return atoi(p + strlen(key));
    return 0;
}

/*
 * Format 4.1 re-approximates a kept net with its boundary up to a quarter of the tolerance off the
 * face's edges; one of occt__bug22869_Spring's coil nets then folds 54 triangles over their
 * neighbours where the coil meets its end cap: the encoder's fold check finds it and sends that net
 * whole.  For a 4.0 terminal (the boundary held to a sixteenth where the face's edges run, since its
 * tessellation tests the loop against the edges) no net folds.
 */
static void test_folding_nets_go_whole(void **state)
{
    (void)state;
    char path[1024];
    fclose(open_shared(path, sizeof path, "iges/occt__bug22869_Spring.igs", "rb"));
    loaded_model lm;
    cm_status st;
    cm_status_init(&st);
    assert_int_equal(model_load(path, &lm, NULL, NULL, &st), CM_OK);
    for (int minor = 0; minor < 2; minor++) {
        encode_opts o;
        encode_opts_default(&o);
        encode_opts_for_format(&o, 4, minor);
        encode_result r;
        memset(&r, 0, sizeof r);
        cm_status_init(&st);
        assert_int_equal(encode_model(&lm, &o, &r, &st), CM_OK);
        print_message("  format 4.%d: %d nets re-approximated, %d sent whole, %zu bytes\n", minor, r.surfs_reapproximated,
                      r.nets_whole, r.len);
        assert_true(r.surfs_reapproximated >= 1);
        assert_int_equal(r.bytes[CM_HDR_MINOR], minor);
        assert_int_equal(r.nets_whole, minor);
        assert_int_equal(r.faces_left_out, 0);
        encode_result_free(&r);
    }
    model_free(&lm);
}

static void test_every_corpus_model(void **state)
{
    (void)state;
    char path[1024];
    FILE *cat = open_shared(path, sizeof path, "CATALOG.tsv", "r");
    char line[8192];
    int n = 0;
    while (fgets(line, sizeof line, cat)) {
        if (strncmp(line, "iges/", 5) != 0)
            continue;
        char *file = strtok(line, "\t");
        for (int i = 0; i < 6; i++)
            strtok(NULL, "\t");
        char *counts = strtok(NULL, "\t");
        assert_non_null(counts);
        int expect = catalog_count(counts, 144) + catalog_count(counts, 143) + catalog_count(counts, 510);
        snprintf(path, sizeof path, "%s/%s", models_dir(), file);
        loaded_model lm;
        cm_status st;
        cm_status_init(&st);
        /* blanked entities included: every face entity the catalog counts must import (by default
           Shelt_channel_5's 190 entities placed only by blanked subfigure instances are left out) */
        cm_err e = model_load_ex(path, &lm, MODEL_LOAD_BLANKED, NULL, NULL, &st);
        if (e != CM_OK)
            fail_msg("%s: %s (%s)", file, lm.iges.err, cm_err_name(e));
        if (lm.stats.face_entities != expect || lm.brep.faces_failed != 0 || lm.domains_failed != 0)
            fail_msg("%s: %d face entities imported (%d failed, %d without a domain), catalog says %d", file,
                     lm.stats.face_entities, lm.brep.faces_failed, lm.domains_failed, expect);
        /* a part whose faces form a closed shell: no edge may stay unpaired */
        int *comp = malloc((size_t)lm.mesh.nfaces * sizeof *comp), *freec = calloc((size_t)lm.mesh.nfaces, sizeof(int));
        assert_non_null(comp);
        assert_non_null(freec);
        int nc = cmesh_components(&lm.mesh, comp);
        for (int k = 0; k < lm.mesh.nedges; k++)
            if (lm.mesh.edges[k].kind == CMESH_FREE)
                freec[comp[lm.mesh.edges[k].face[0]]]++;
        int closed = 0;
        for (int c = 0; c < nc; c++)
            closed += freec[c] == 0;
        print_message("  %-40s %6d faces (%d entities, %d untrimmed) %6d edges, %d/%d parts closed\n", file,
                      lm.brep.nfaces, lm.stats.face_entities, lm.stats.faces_untrimmed, lm.mesh.nedges, closed, nc);
        free(comp);
        free(freec);
        model_free(&lm);
        n++;
    }
    fclose(cat);
    assert_true(n >= 24);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_corpus_model),
        cmocka_unit_test(test_folding_nets_go_whole),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
