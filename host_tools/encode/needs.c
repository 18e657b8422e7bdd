/* needs.c - what the terminal will need, measured with its own tessellation (see encode_internal.h). */
#include "encode_internal.h"
#include "enc_workers.h"
#include "verify.h"
#include "mesh/mesh_topo.h"

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_const.h"
#include "cm/cm_corner.h"
#include "cm/cm_crc32.h"
#include "cm/cm_cubic_convert.h"
#include "cm/cm_method.h"
#include "cm/cm_place.h"
#include "cm/cm_sections.h"

/* ---- needs ---- */


/* why a face does not tessellate, for its warning */
static const char *tess_fault(cm_err e)
{
    switch (e) {
    case CM_E_DEGENERATE: return "its boundary cannot be triangulated (loops cross, or are degenerate)";
    case CM_E_LIMIT: return "its tessellation exceeds a limit of every profile";
    case CM_E_NONFINITE: return "its surface gives non-finite points";
    default: return "it cannot be tessellated";
    }
}

const char enc_net_folds[] = "its re-approximated surface folds its triangles";

int enc_face_folds(const cm_mesh *m)
{
    mesh_topo topo;
    if (mesh_topo_analyse(m, &topo) != 0)
        return -1;
    mesh_topo_free(&topo);
    return topo.duplicate > 0;
}

/* what the terminal's tessellation of one face needs, and what is wrong with it */
typedef struct face_need {
    atomic_int done;    /* 1: filled in by a worker (cmz encode -j) */
    cm_err e;           /* CM_E_NOMEM: the end of memory (the model fails); else the face's own */
    const char *fault;  /* why it cannot be sent as it is (a static string), or NULL */
    double mesh_dev;    /* with `measure`: its triangles against its source (-1: not measured) */
    int measured;
    uint32_t triangles, points, edge_samples;
} face_need;

/* face f tessellated as the terminal will (issue 14.6: measured against its source with `measure`) */
static void need_of_face(const tx *t, const loaded_model *measure, const encode_result *r, uint32_t f, face_need *out)
{
    enc_work *w = t->w;
    const cm_model *m = &w->dec.model;
    cm_mesh_face mf;
    cm_mesh mesh = {w->face_pos, w->face_nrm, w->face_idx, &mf, 0, CM_MAX_TESS_POINTS, 0, 3 * CM_MAX_TESS_TRIS, 0, 1, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    cm_tess_info info;
    cm_status fst;
    cm_status_init(&fst);
    cm_err e = cm_tessellate_face(m, f, m->tess_tol, &mesh, &w->tess_ws, &info, &fst);
    out->e = e == CM_E_NOMEM ? e : CM_OK;
    out->fault = NULL;
    out->measured = measure && (int)f < t->nfaces;
    out->mesh_dev = -1.0;
    out->triangles = out->points = out->edge_samples = 0;
    if (e == CM_E_NOMEM)
        return;
    if (out->measured && e == CM_OK)
        out->mesh_dev = verify_mesh_face(measure, (int)f, (const float(*)[3])mesh.pos, mesh.nverts, mesh.idx,
                                         mesh.nindex, r->faces[f].rebuild_max + m->tess_tol);
    if (e != CM_OK) {
        out->fault = tess_fault(e); /* a fault of that face (see encode_model), not of the model */
        return;
    }
    if ((int)f < t->nfaces && t->surfs[f].reapproximated && enc_kept(t->method[f])) {
        int folds = enc_face_folds(&mesh);
        if (folds < 0) {
            out->e = CM_E_NOMEM;
            return;
        }
        if (folds) {
            out->fault = enc_net_folds;
            return;
        }
    }
    out->triangles = (uint32_t)info.triangles;
    out->points = (uint32_t)info.points;
    out->edge_samples = (uint32_t)info.max_edge_samples;
}

/* on -j N processes: the faces in shared memory */
typedef struct need_board {
    atomic_int next;
    face_need face[];
} need_board;

typedef struct need_job {
    tx *t;
    const loaded_model *measure;
    const encode_result *r;
    need_board *b;
} need_job;

static void need_item(void *ctx, int f, int self)
{
    const need_job *J = ctx;
    face_need *F = &J->b->face[f];
    need_of_face(J->t, J->measure, J->r, (uint32_t)f, F);
    atomic_store(&F->done, self ? 2 : 1);
}

/* the terminal's tessellation of every face: triangles, points, edge samples (on t->o->jobs
   processes, the same answer); with `measure`, each face's triangles against its source too
   (issue 14.6: r->faces[f].mesh_dev) */
cm_err enc_tessellation_needs(tx *t, uint32_t *need, const encode_opts *o, const loaded_model *measure,
                              encode_result *r, cm_status *st)
{
    const cm_model *m = &t->w->dec.model;
    uint32_t nf = m->nfaces;
    uint64_t tris = 0;
    /* per face its triangles: the placed copies' (format 4.3) are the same again */
    uint32_t *face_tris = calloc((size_t)nf + 1, sizeof *face_tris);
    if (!face_tris)
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    size_t size = sizeof(need_board) + (size_t)nf * sizeof(face_need);
    need_board *b = o->jobs > 1 && nf > 1 ? enc_shared_alloc(size) : NULL;
    if (b) {
        need_job J = {t, measure, r, b};
        enc_workers_run(o->jobs, (int)nf, &b->next, need_item, &J, o->jobs_die_after);
    }
    cm_err err = CM_OK;
    for (uint32_t f = 0; f < nf && err == CM_OK; f++) {
        face_need one, *F = b && atomic_load(&b->face[f].done) ? &b->face[f] : &one;
        if (F == &one) { /* in order, with one process; else a worker's that died */
            if (o->progress)
                o->progress("tessellating", (int)f + 1, (int)nf, o->progress_ctx);
            need_of_face(t, measure, r, f, &one);
        }
        if (F->e == CM_E_NOMEM) {
            err = cm_fail(st, CM_E_NOMEM, "out of memory");
            break;
        }
        if (F->measured)
            r->faces[f].mesh_dev = F->mesh_dev;
        if (F->fault) {
            tx_face_fault(t, (int)f, F->fault);
            continue;
        }
        tris += F->triangles;
        face_tris[f] = F->triangles;
        if (F->points > need[CM_LIMIT_MAX_TESS_POINTS])
            need[CM_LIMIT_MAX_TESS_POINTS] = F->points;
        if (F->edge_samples > need[CM_LIMIT_MAX_EDGE_SAMPLES])
            need[CM_LIMIT_MAX_EDGE_SAMPLES] = F->edge_samples;
    }
    enc_shared_free(b, size);
    if (err != CM_OK) {
        free(face_tris);
        return err;
    }
    uint64_t copy_tris = 0, copy_faces = 0;
    cm_place_counts(m, face_tris, &copy_tris, &copy_faces);
    free(face_tris);
    tris += copy_tris;
    need[CM_LIMIT_MAX_TRIS] = tris > UINT32_MAX ? UINT32_MAX : (uint32_t)tris;
    return CM_OK;
}

void enc_compute_needs(const enc_work *w, const encode_result *r, uint32_t *need)
{
    const cm_model *m = &w->dec.model;
    memset(need, 0, sizeof(uint32_t) * CM_LIMIT_COUNT);
#define NEED(id, v)                                                                                                    \
    do {                                                                                                               \
        uint64_t v_ = (uint64_t)(v);                                                                                   \
        if (v_ > need[CM_LIMIT_##id])                                                                                  \
            need[CM_LIMIT_##id] = (uint32_t)v_;                                                                        \
    } while (0)
    for (uint32_t e = 0; e < m->nedges; e++) {
        NEED(MAX_DEGREE, m->edges[e].p);
        NEED(MAX_EDGE_CTRL, m->edges[e].nctrl);
    }
    for (uint32_t s = 0; s < m->nsurfs; s++) {
        const cm_ksurf *S = &m->surfs[s];
        NEED(MAX_DEGREE, S->p);
        NEED(MAX_DEGREE, S->q);
        NEED(MAX_SURF_CTRL_DIR, S->nu);
        NEED(MAX_SURF_CTRL_DIR, S->nv);
        NEED(MAX_SURF_CTRL, (uint32_t)S->nu * S->nv);
    }
    for (uint32_t f = 0; f < m->nfaces; f++) {
        const cm_face *F = &m->faces[f];
        uint32_t uses = 0;
        NEED(MAX_LOOPS, F->nloops);
        const cm_method *M = cm_method_of(F->method);
        cm_method_needs(M, m, F, need);
        for (uint32_t l = 0; l < F->nloops; l++) {
            NEED(MAX_LOOP_EDGES, m->loops[F->loop0 + l].nuse);
            uses += m->loops[F->loop0 + l].nuse;
        }
        NEED(MAX_FACE_EDGES, uses);
    }
    /* the mesh holds the placed copies' faces too (format 4.3) */
    uint64_t no_tris, copies;
    cm_place_counts(m, NULL, &no_tris, &copies);
    NEED(MAX_FACES, m->nfaces + copies);
    NEED(MAX_PLACEMENTS, m->nplacements);
    NEED(MAX_EDGES, m->nedges);
    NEED(MAX_VERTICES, m->nverts);
    NEED(MAX_FILE_BYTES, r->len);
    NEED(MAX_MODEL_CTRL, m->nctrl);
    NEED(MAX_MODEL_KNOTS, m->nknots);
    NEED(MAX_MODEL_LOOPS, m->nloops);
    NEED(MAX_MODEL_USES, m->nuses);
#undef NEED
}
