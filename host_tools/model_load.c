/* model_load.c - IGES -> B-rep -> face domains -> curve mesh (see model_load.h). */
#define _POSIX_C_SOURCE 200809L
#include "model_load.h"

#include "brep/brep_seam.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cm_clock.h"

static double now(void)
{
    return cm_clock_s();
}

int model_file_is_step(const char *path)
{
    char head[4096];
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return 0; /* the IGES reader reports why it cannot be opened */
    size_t n = fread(head, 1, sizeof head, fp);
    fclose(fp);
    return step_sniff(head, n);
}

/* remember warning w as one about a face left out of the model */
static cm_err note_left_out(loaded_model *lm, int w)
{
    int *p = realloc(lm->left_out, (size_t)(lm->nleft_out + 1) * sizeof *p);
    if (!p)
        return CM_E_NOMEM;
    lm->left_out = p;
    lm->left_out[lm->nleft_out++] = w;
    return CM_OK;
}

/* a STEP file read into lm->step: its faces into the B-rep, its warnings and error where IGES's go */
static cm_err step_import(loaded_model *lm, cm_status *st)
{
    cm_err e = step_to_brep(&lm->step, &lm->brep, &lm->step_stats, st);
    for (int w = 0; w < lm->step.nwarn; w++)
        iges_warn(&lm->iges, lm->step.warn[w].line, "%s", lm->step.warn[w].msg);
    if (lm->step.warnings_dropped)
        iges_warn(&lm->iges, lm->step.nlines, "... and %d more warnings not kept", lm->step.warnings_dropped);
    if (lm->step.err[0]) {
        snprintf(lm->iges.err, sizeof lm->iges.err, "%s", lm->step.err);
        lm->iges.err_line = lm->step.err_line;
    }
    return e;
}

/* everything after the file is read (into lm->iges or lm->step) */
static cm_err load_rest(loaded_model *lm, int flags, model_progress progress, void *ctx, cm_status *st)
{
    double t = now();
    cm_err e;
    lm->load_flags = flags;
    if (lm->is_step)
        e = step_import(lm, st);
    else
        e = iges_to_brep(&lm->iges, &lm->brep, &lm->stats, (flags & MODEL_LOAD_BLANKED) != 0, st);
    if (e == CM_OK && (flags & MODEL_LOAD_FOLD))
        e = brep_fold_instances(&lm->brep, &lm->instances_folded, st);
    lm->seconds_brep = now() - t;
    if (e != CM_OK)
        return e;
    /* the import's own skipped faces (iges_brep.c face_failed: "face N (TYPE, DE d) skipped: ...") */
    for (int w = 0, n = lm->iges.nwarn; w < n; w++)
        if (strncmp(lm->iges.warn[w].msg, "face ", 5) == 0 && strstr(lm->iges.warn[w].msg, ") skipped: ") &&
            note_left_out(lm, w) != CM_OK)
            return cm_fail(st, CM_E_NOMEM, "out of memory");
    t = now();
    brep_model *m = &lm->brep;
    lm->fds = calloc((size_t)m->nfaces, sizeof *lm->fds);
    if (!lm->fds)
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    double tol = brep_tolerance(m);
    for (int f = 0; f < m->nfaces; f++) {
        if (progress)
            progress("face domains", f, m->nfaces, ctx);
        cm_status fst;
        cm_status_init(&fst);
        if (face_domain_build(m, f, tol, &lm->fds[f], &fst) != CM_OK) {
            if (fst.code == CM_E_NOMEM)
                return cm_fail(st, CM_E_NOMEM, "out of memory");
            char src[64];
            iges_warn(&lm->iges, 0, "face %d (%s): left out: no parameter domain: %s", f,
                      brep_face_source(&m->faces[f], src, sizeof src), cm_strerror(fst.code));
            face_domain_free(&lm->fds[f]);
            if (note_left_out(lm, lm->iges.nwarn - 1) != CM_OK)
                return cm_fail(st, CM_E_NOMEM, "out of memory");
            lm->domains_failed++;
            continue;
        }
        lm->loops_reversed += lm->fds[f].reversed;
        lm->outer_reordered += lm->fds[f].reordered;
        lm->seam_joined += lm->fds[f].joined_seam;
        if (lm->fds[f].max_gap > lm->max_gap)
            lm->max_gap = lm->fds[f].max_gap;
        /* a band between two loops winding round its surface, cut open along it (brep_seam.h) */
        int cut = 0;
        if ((e = brep_cut_seam(m, f, &lm->fds[f], tol, &cut, st)) != CM_OK)
            return e; /* (only memory: st says so) */
        lm->seams_cut += cut;
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
    return model_load_ex(path, lm, 0, progress, ctx, st);
}

cm_err model_load_ex(const char *path, loaded_model *lm, int flags, model_progress progress, void *ctx, cm_status *st)
{
    memset(lm, 0, sizeof *lm);
    double t = now();
    cm_err e;
    lm->is_step = model_file_is_step(path);
    if (lm->is_step) {
        e = step_read(path, &lm->step, st);
        lm->iges.path = strdup(path);
        if (e != CM_OK)
            snprintf(lm->iges.err, sizeof lm->iges.err, "%s", lm->step.err), lm->iges.err_line = lm->step.err_line;
        if (e == CM_OK && !lm->iges.path)
            e = cm_fail(st, CM_E_NOMEM, "out of memory");
    } else {
        e = iges_read(path, &lm->iges, st);
    }
    lm->seconds_read = now() - t;
    if (e != CM_OK)
        return e;
    return load_rest(lm, flags, progress, ctx, st);
}

cm_err model_load_data(const char *name, const char *data, size_t len, loaded_model *lm, model_progress progress,
                       void *ctx, cm_status *st)
{
    return model_load_data_ex(name, data, len, lm, 0, progress, ctx, st);
}

cm_err model_load_data_ex(const char *name, const char *data, size_t len, loaded_model *lm, int flags,
                          model_progress progress, void *ctx, cm_status *st)
{
    memset(lm, 0, sizeof *lm);
    double t = now();
    cm_err e;
    lm->is_step = step_sniff(data, len);
    if (lm->is_step) {
        e = step_parse(data, len, &lm->step, st);
        if (e != CM_OK)
            snprintf(lm->iges.err, sizeof lm->iges.err, "%s", lm->step.err), lm->iges.err_line = lm->step.err_line;
    } else {
        e = iges_parse(data, len, &lm->iges, st);
    }
    lm->iges.path = strdup(name);
    lm->seconds_read = now() - t;
    if (e != CM_OK)
        return e;
    return load_rest(lm, flags, progress, ctx, st);
}

cm_err model_leave_out_face(loaded_model *lm, int bf, const char *why, cm_status *st)
{
    brep_model *m = &lm->brep;
    if (bf < 0 || bf >= m->nfaces)
        return cm_fail(st, CM_E_ARG, __func__);
    unsigned char *drop = calloc((size_t)m->nfaces + 1, 1);
    if (!drop)
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    drop[bf] = 1;
    char src[64];
    iges_warn(&lm->iges, 0, "face of %s: left out: %s", brep_face_source(&m->faces[bf], src, sizeof src), why);
    cm_err e = note_left_out(lm, lm->iges.nwarn - 1) == CM_OK ? CM_OK : cm_fail(st, CM_E_NOMEM, "out of memory");
    if (e == CM_OK)
        e = brep_remove_faces(m, drop, st);
    free(drop);
    if (e != CM_OK)
        return e;
    /* the face domains follow their faces down; the box is what remains */
    face_domain_free(&lm->fds[bf]);
    memmove(&lm->fds[bf], &lm->fds[bf + 1], (size_t)(m->nfaces - bf) * sizeof *lm->fds);
    memset(&lm->fds[m->nfaces], 0, sizeof lm->fds[m->nfaces]);
    for (int f = bf; f < m->nfaces; f++)
        if (lm->fds[f].uv)
            lm->fds[f].face = f;
    m->box = hbox_empty();
    for (int s = 0; s < m->nsegs; s++)
        hbox_add_curve(&m->box, &m->segs[s]);
    /* (the placed copies' box, m->placed_box, stays: the model's diagonal is the whole's) */
    cmesh_free(&lm->mesh);
    return cmesh_build(m, lm->fds, &lm->mesh, st);
}

void model_free(loaded_model *lm)
{
    free(lm->left_out);
    cmesh_free(&lm->mesh);
    if (lm->fds)
        for (int f = 0; f < lm->brep.nfaces; f++)
            face_domain_free(&lm->fds[f]);
    free(lm->fds);
    brep_free(&lm->brep);
    iges_free(&lm->iges);
    step_free(&lm->step);
    memset(lm, 0, sizeof *lm);
}
