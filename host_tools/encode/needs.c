/* needs.c - what the terminal will need, measured with its own tessellation (see encode_internal.h). */
#include "encode_internal.h"
#include "verify.h"
#include "mesh/mesh_topo.h"

#include <math.h>
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

/* a face that does not tessellate is a fault of that face (see encode_model), not of the model */
/* the terminal's tessellation of every face, one face at a time: triangles, points, edge samples;
   with `measure`, each face's triangles against its source too (issue 14.6: r->faces[f].mesh_dev) */
cm_err enc_tessellation_needs(tx *t, uint32_t *need, const encode_opts *o, const loaded_model *measure,
                              encode_result *r, cm_status *st)
{
    enc_work *w = t->w;
    const cm_model *m = &w->dec.model;
    cm_mesh_face mf;
    cm_mesh mesh = {w->face_pos, w->face_nrm, w->face_idx, &mf, 0, CM_MAX_TESS_POINTS, 0, 3 * CM_MAX_TESS_TRIS, 0, 1, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    uint64_t tris = 0;
    /* per face its triangles: the placed copies' (format 4.3) are the same again */
    uint32_t *face_tris = calloc((size_t)m->nfaces + 1, sizeof *face_tris);
    if (!face_tris)
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    for (uint32_t f = 0; f < m->nfaces; f++) {
        if (o->progress)
            o->progress("tessellating", (int)f + 1, (int)m->nfaces, o->progress_ctx);
        cm_tess_info info;
        cm_mesh_clear(&mesh);
        cm_status fst;
        cm_status_init(&fst);
        cm_err e = cm_tessellate_face(m, f, m->tess_tol, &mesh, &w->tess_ws, &info, &fst);
        if (e == CM_E_NOMEM) {
            *st = fst;
            free(face_tris);
            return e;
        }
        if (measure && (int)f < t->nfaces)
            r->faces[f].mesh_dev = e != CM_OK ? -1.0
                                              : verify_mesh_face(measure, (int)f, (const float(*)[3])mesh.pos,
                                                                 mesh.nverts, mesh.idx, mesh.nindex,
                                                                 r->faces[f].rebuild_max + m->tess_tol);
        if (e != CM_OK) {
            tx_face_fault(t, (int)f, tess_fault(e));
            continue;
        }
        if ((int)f < t->nfaces && t->surfs[f].reapproximated && enc_kept(t->method[f])) {
            int folds = enc_face_folds(&mesh);
            if (folds < 0) {
                free(face_tris);
                return cm_fail(st, CM_E_NOMEM, "out of memory");
            }
            if (folds) {
                tx_face_fault(t, (int)f, enc_net_folds);
                continue;
            }
        }
        tris += (uint64_t)info.triangles;
        face_tris[f] = (uint32_t)info.triangles;
        if ((uint32_t)info.points > need[CM_LIMIT_MAX_TESS_POINTS])
            need[CM_LIMIT_MAX_TESS_POINTS] = (uint32_t)info.points;
        if ((uint32_t)info.max_edge_samples > need[CM_LIMIT_MAX_EDGE_SAMPLES])
            need[CM_LIMIT_MAX_EDGE_SAMPLES] = (uint32_t)info.max_edge_samples;
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
