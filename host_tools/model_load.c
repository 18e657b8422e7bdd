/* model_load.c - IGES -> B-rep -> face domains -> curve mesh (see model_load.h). */
#define _POSIX_C_SOURCE 200809L
#include "model_load.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* everything after the IGES file is in lm->iges */
static cm_err load_rest(loaded_model *lm, model_progress progress, void *ctx, cm_status *st)
{
    double t = now();
    cm_err e;
    e = iges_to_brep(&lm->iges, &lm->brep, &lm->stats, st);
    lm->seconds_brep = now() - t;
    if (e != CM_OK)
        return e;
    t = now();
    brep_model *m = &lm->brep;
    lm->fds = calloc((size_t)m->nfaces, sizeof *lm->fds);
    if (!lm->fds)
        return cm_fail(st, CM_E_IO, "out of memory");
    double tol = brep_tolerance(m);
    for (int f = 0; f < m->nfaces; f++) {
        if (progress)
            progress("face domains", f, m->nfaces, ctx);
        cm_status fst;
        cm_status_init(&fst);
        if (face_domain_build(m, f, tol, &lm->fds[f], &fst) != CM_OK) {
            if (fst.code == CM_E_IO)
                return cm_fail(st, CM_E_IO, "out of memory");
            iges_warn(&lm->iges, 0, "face %d (DE %d): no parameter domain: %s", f, m->faces[f].src_de,
                      cm_strerror(fst.code));
            face_domain_free(&lm->fds[f]);
            lm->domains_failed++;
            continue;
        }
        lm->loops_reversed += lm->fds[f].reversed;
        lm->outer_reordered += lm->fds[f].reordered;
        lm->seam_joined += lm->fds[f].joined_seam;
        if (lm->fds[f].max_gap > lm->max_gap)
            lm->max_gap = lm->fds[f].max_gap;
    }
    lm->seconds_domains = now() - t;
    if (progress)
        progress("curve mesh", 0, 1, ctx);
    t = now();
    e = cmesh_build(m, lm->fds, &lm->mesh, st);
    lm->seconds_mesh = now() - t;
    return e;
}

cm_err model_load(const char *path, loaded_model *lm, model_progress progress, void *ctx, cm_status *st)
{
    memset(lm, 0, sizeof *lm);
    double t = now();
    cm_err e = iges_read(path, &lm->iges, st);
    lm->seconds_read = now() - t;
    if (e != CM_OK)
        return e;
    return load_rest(lm, progress, ctx, st);
}

cm_err model_load_data(const char *name, const char *data, size_t len, loaded_model *lm, model_progress progress,
                       void *ctx, cm_status *st)
{
    memset(lm, 0, sizeof *lm);
    double t = now();
    cm_err e = iges_parse(data, len, &lm->iges, st);
    lm->iges.path = strdup(name);
    lm->seconds_read = now() - t;
    if (e != CM_OK)
        return e;
    return load_rest(lm, progress, ctx, st);
}

void model_free(loaded_model *lm)
{
    cmesh_free(&lm->mesh);
    if (lm->fds)
        for (int f = 0; f < lm->brep.nfaces; f++)
            face_domain_free(&lm->fds[f]);
    free(lm->fds);
    brep_free(&lm->brep);
    iges_free(&lm->iges);
    memset(lm, 0, sizeof *lm);
}
