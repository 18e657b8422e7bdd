/* encode.c - loaded model -> .cmz (see encode.h and docs/FORMAT.md): the passes over the model, and
   the faces that cannot be sent settled between them. */
#include "encode.h"

#include "brep/brep_seam.h"
#include "encode_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_method.h"
#include "cm/cm_place.h"


void encode_opts_for_format(encode_opts *o, int major, int minor)
{
    if (major < 2) {
        o->gregory = 0; /* format 1: planes only */
        o->g1fit = 0;
        o->nfill = 0;
    }
    if (major < CM_FMT_COMPACT_MAJOR)
        o->compact_header = 0;
    if (major == CM_FMT_COMPACT_MAJOR && minor < o->compact_minor)
        o->compact_minor = minor < 0 ? 0 : minor; /* 4.0: the long origin; 4.1: no net corrections */
    if (major < CM_FMT_PREDICT_MAJOR)
        o->predicted = o->budget_steps = 0;
    if (major > 2)
        return;
    if (minor < 1)
        o->gregory_exact = 0;
    if (minor < 2)
        o->gregory_fit = 0;
    if (minor < 4)
        o->nfill = 0;
    if (minor < 5)
        o->g1fit = 0;
    if (minor < CM_FMT_TURNING_MINOR)
        o->turning_basis = 0;
}

void encode_opts_default(encode_opts *o)
{
    o->rel_tol = 0.01;    /* spec §1 RATIO_TOL: 1 % of the face's bounding box */
    o->quant_rel = 1e-6;  /* grid step: 1e-6 of the diagonal, far below any rebuild tolerance */
    o->tess_rel = 5e-4;   /* chordal tolerance for viewers: 0.05 % of the diagonal */
    o->target = NULL;
    o->steps = NULL;
    o->test_parts = NULL;
    o->target_name = NULL;
    o->gregory = 1;
    o->gregory_exact = 1;
    o->gregory_fit = 1;
    o->g1fit = 1;
    o->nfill = 1;
    o->turning_basis = 1;
    o->predicted = 1;
    o->compact_header = 1;
    o->compact_minor = CM_FMT_VERSION_MINOR;
    /* precision from the tolerance budget (tx_coarsen.c): 422 k instead of 502 k bytes over the
       corpus for a third more encode time (a second choice of methods where a face is kept) */
    o->budget_steps = 1;
    o->instances = 1;
    o->strict = 0;
    o->measure_mesh = 0;
    o->abs_tol = 0;
    o->rel_set = 0;
    /* model-level accuracy: 1 % of a large face's box lets it drift far (as1_pe_203's 5 m face was
       rebuilt 48 mm off, 0.75 % of the diagonal, where a mesh at 1e-3 of it stays within 0.1 %) */
    o->model_tol_rel = 1e-3;
    o->progress = NULL;
    o->progress_ctx = NULL;
    o->jobs = 1;
    o->jobs_die_after = 0;
}

int encode_places(const encode_opts *o)
{
    return o->instances && o->predicted && o->compact_header && o->compact_minor >= (int)CM_FMT_PLACE_MINOR;
}

double encode_face_tol(double rel_tol, int rel_set, double abs_tol, double bbox)
{
    if (!(abs_tol > 0))
        return rel_tol * bbox;
    return rel_set && rel_tol * bbox < abs_tol ? rel_tol * bbox : abs_tol;
}

void encode_opts_for_model(encode_opts *o, double diag)
{
    if (o->model_tol_rel > 0 && !o->rel_set && !(o->abs_tol > 0) && diag > 0) {
        o->abs_tol = o->model_tol_rel * diag;
        o->rel_set = 1;
    }
}

void encode_result_free(encode_result *r)
{
    free(r->bytes);
    free(r->faces);
    memset(r, 0, sizeof *r);
}

/*
 * One try at the whole file.  Faces that cannot be sent as they are come back in fault[] (per curve
 * mesh face, *nfaults of them) with CM_OK and no file; anything else that fails is the model's.
 */
/* a tessellation need over the target's limit */
static int tess_over(const cm_limit_info *target, const uint32_t *need)
{
    static const int ids[] = {CM_LIMIT_MAX_TESS_POINTS, CM_LIMIT_MAX_EDGE_SAMPLES, CM_LIMIT_MAX_TRIS};
    for (int i = 0; i < 3; i++)
        if (need[ids[i]] > target[ids[i]].value)
            return 1;
    return 0;
}

static cm_err encode_pass(enc_work *w, loaded_model *lm, const encode_opts *asked, const unsigned char *keep_only,
                          const unsigned char *net_whole, const char **fault, int *nfaults, encode_result *r, cm_status *st)
{
    encode_opts model_opts = *asked;
    const encode_opts *o = &model_opts;
    encode_opts_for_model(&model_opts, brep_diag(&lm->brep));
    memset(r, 0, sizeof *r);
    *nfaults = 0;
    tx t;
    memset(&t, 0, sizeof t);
    t.keep_only = keep_only;
    t.net_whole = net_whole;
    t.w = w;
    cm_err e = CM_OK;
    double diag = brep_diag(&lm->brep);
    if (!(diag > 0))
        return cm_fail(st, CM_E_DEGENERATE, "empty model");
    if (!isfinite(diag) || !isfinite(log2(o->quant_rel * diag)))
        return cm_fail(st, CM_E_NONFINITE, "the model's extent is not finite");
    /* every part's faces one way, closed parts outwards: before anything is built on the loops'
       direction (edge numbering, Gregory patches, method choice) */
    r->faces_flipped = enc_orient_parts(lm);
    r->faces_flipped += enc_outward_parts(lm);
    /* the grid: the largest power of two not above quant_rel * diagonal */
    t.q_exp = (int)floor(log2(o->quant_rel * diag));
    if (t.q_exp < -60)
        t.q_exp = -60;
    if (t.q_exp > 20) /* the decoder's bound (cm_decode.c, check_header): a grid step over 1 km */
        return cm_fail(st, CM_E_RANGE, "the model is too large for the format's coordinate grid");
    t.q = ldexp(1.0, t.q_exp);
    r->q = t.q;
    t.origin[0] = lm->brep.box.lo.x;
    t.origin[1] = lm->brep.box.lo.y;
    t.origin[2] = lm->brep.box.lo.z;
    /* format 4 sends the origin as a multiple of the grid step (a few bytes, not 24); 4.1 as a
       multiple of a coarser power-of-two step, the largest within a sixteenth of the diagonal: one
       byte a coordinate for a model near its own origin (the coordinates, on the same grid, gain a
       step at most) */
    if (enc_compact_header(o)) {
        double step = t.q;
        while (o->compact_minor >= (int)CM_FMT_SHORT_ORIGIN_MINOR && step * 2.0 <= diag / 16.0 &&
               step * 2.0 <= ldexp(t.q, (int)CM_FMT_MAX_ORIGIN_SHIFT))
            step *= 2.0;
        for (int k = 0; k < 3; k++)
            t.origin[k] = floor(t.origin[k] / step) * step;
    }
    t.nfaces = lm->mesh.nfaces;
    t.method = calloc((size_t)t.nfaces + 1, sizeof(int));
    t.layout = calloc((size_t)t.nfaces + 1, sizeof(int));
    t.corner = calloc((size_t)t.nfaces + 1, sizeof(int));
    t.checksum = calloc((size_t)t.nfaces + 1, sizeof(uint32_t));
    t.turning = calloc((size_t)t.nfaces + 1, 1);
    t.color = calloc((size_t)t.nfaces + 1, sizeof(int));
    t.surfs = calloc((size_t)t.nfaces + 1, sizeof *t.surfs);
    t.fault = calloc((size_t)t.nfaces + 1, sizeof *t.fault);
    t.fit = calloc((size_t)t.nfaces + 1, sizeof *t.fit);
    r->faces = calloc((size_t)t.nfaces + 1, sizeof *r->faces);
    if (!t.method || !t.layout || !t.corner || !t.checksum || !t.turning || !t.color || !t.surfs || !t.fault ||
        !t.fit || !r->faces) {
        tx_free(&t);
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    }
    t.o = o;
    if ((e = tx_build_edges(lm, &t, st)) != CM_OK) {
        tx_free(&t);
        return e;
    }
    for (int f = 0; f < t.nfaces; f++)
        t.method[f] = CM_METHOD_FALLBACK;
    e = tx_build_surfaces(&t, lm, st); /* a face whose surface cannot be built is a fault, below */
    for (int f = 0; f < t.nfaces && e == CM_OK; f++) {
        const brep_face *bf = &lm->brep.faces[lm->mesh.faces[f].brep_face];
        if (bf->has_color) {
            int k = 1;
            while (k <= t.npalette && t.palette[k] != bf->rgb)
                k++;
            if (k > t.npalette && t.npalette < CM_FMT_MAX_PALETTE)
                t.palette[++t.npalette] = bf->rgb;
            t.color[f] = k <= t.npalette ? k : 0;
        }
    }
    /* pass 1: everything kept, decoded back to have exactly the transmitted edges; the methods;
       pass 2: the final methods, decoded again, needs taken from what the terminal will see */
    if (e == CM_OK && t.nfaults == 0)
        e = enc_choose_and_write(lm, &t, o, r, st);
    /* format 3: kept faces' edges (and the vertices, when a face is kept) back on the grid, the
       methods chosen again on them (tx_coarsen.c, enc_keep_fine_edges); the fourth round puts every
       edge back */
    for (int round = 0; e == CM_OK && t.nfaults == 0 && o->predicted && o->budget_steps && round < 4; round++) {
        if (!enc_keep_fine_edges(lm, &t, round == 3))
            break;
        for (int f = 0; f < t.nfaces; f++) {
            free(t.fit[f]);
            t.fit[f] = NULL;
        }
        tx_free_edges(&t);
        t.edges_refit = t.edges_reapproximated = t.edges_arcs = 0;
        if ((e = tx_build_edges(lm, &t, st)) == CM_OK && t.nfaults == 0)
            e = enc_choose_and_write(lm, &t, o, r, st);
    }
    if (e == CM_OK) {
        for (int i = 0; i < t.nedges; i++) {
            r->edges_line += t.edges[i].kind == CM_EDGE_LINE;
            r->edges_curve += t.edges[i].kind == CM_EDGE_CURVE;
        }
    }
    if (e == CM_OK && t.nfaults == 0) {
        enc_compute_needs(t.w, r, r->need);
        e = enc_tessellation_needs(&t, r->need, o, o->measure_mesh ? lm : NULL, r, st);
    }
    /* fit the board (issue 14.5): what the tessellation needs (points of a face, samples of an edge,
       triangles) follows the recommended chordal tolerance, the one setting the encoder may change
       without changing the model.  Past a target profile's tessellation limits it is made coarser,
       twice at a time, at most 16 times (occt__bug22869_Spring: a face of 16329 points, where the
       terminal has 8192); the summary says so.  Beyond that the profile refuses, as before */
    r->tess_asked = r->tess_used = enc_file_tess(&t, o->tess_rel * diag); /* as the file can say it */
    r->edges_refit = t.edges_refit;
    r->edges_reapproximated = t.edges_reapproximated;
    r->edges_arcs = t.edges_arcs;
    r->surfs_refit = t.surfs_refit;
    r->surfs_reapproximated = t.surfs_reapproximated;
    for (int k = 0; e == CM_OK && t.nfaults == 0 && o->target && k < 4 && tess_over(o->target, r->need); k++) {
        model_opts.tess_rel *= 2;
        t.w->dec.model.tess_tol = enc_file_tess(&t, model_opts.tess_rel * diag);
        r->tess_used = t.w->dec.model.tess_tol;
        r->need[CM_LIMIT_MAX_TESS_POINTS] = r->need[CM_LIMIT_MAX_EDGE_SAMPLES] = r->need[CM_LIMIT_MAX_TRIS] = 0;
        e = enc_tessellation_needs(&t, r->need, o, o->measure_mesh ? lm : NULL, r, st);
    }
    if (e == CM_OK && t.nfaults > 0) {
        /* faces that cannot be sent: encode_model settles them and calls again */
        for (int f = 0; f < t.nfaces; f++)
            if (t.fault[f])
                fault[f] = t.fault[f];
        *nfaults = t.nfaults;
        tx_free(&t);
        return CM_OK;
    }
    if (e == CM_OK) {
        e = enc_write_file(&t, lm, o, r->need, r, st);
        r->need[CM_LIMIT_MAX_FILE_BYTES] = (uint32_t)r->len;
    }
    if (e == CM_OK)
        e = enc_decode_back(t.w, r, st); /* the final bytes must decode: any inconsistency is ours */
    if (e == CM_OK)
        e = enc_placements_decoded(&t, lm, &t.w->dec.model, st); /* and say the copies it meant */
    if (e == CM_OK) {
        const cm_model *dm = &t.w->dec.model;
        uint64_t no_tris, placed;
        cm_place_counts(dm, NULL, &no_tris, &placed);
        r->placements = dm->nplacements;
        r->placed_faces = (uint32_t)placed;
    }
    tx_free(&t);
    if (e != CM_OK)
        return e;
    if (o->target) {
        for (int i = 0; i < CM_LIMIT_COUNT; i++)
            if (r->need[i] > o->target[i].value) {
                snprintf(r->refusal, sizeof r->refusal,
                         "the model needs %s=%u, profile %s has %u: it cannot be loaded there", o->target[i].name,
                         r->need[i], o->target_name ? o->target_name : "?", o->target[i].value);
                return cm_fail_limit(st, (unsigned)i, r->need[i], o->target[i].value, "target profile");
            }
    }
    return CM_OK;
}

/* bands cut open (brep_seam.h) back as imported: the faces' orientations first back to those their
   domains were built with (flip0), then, with rebuild_mesh, the curve mesh anew; nothing for n 0 */
static cm_err uncut_faces(loaded_model *lm, const int *faces, int n, const unsigned char *flip0, int rebuild_mesh,
                          cm_status *st)
{
    if (n == 0)
        return CM_OK;
    for (int b = 0; b < lm->brep.nfaces; b++)
        lm->brep.faces[b].flip = flip0[b];
    cm_err e = CM_OK;
    for (int i = 0; e == CM_OK && i < n; i++)
        e = brep_uncut_seam(&lm->brep, faces[i], &lm->fds[faces[i]], brep_tolerance(&lm->brep), st);
    lm->seams_cut -= n;
    if (e == CM_OK && rebuild_mesh) {
        cmesh_free(&lm->mesh);
        e = cmesh_build(&lm->brep, lm->fds, &lm->mesh, st);
    }
    return e;
}

/*
 * One bad face never sinks a model.  A face that cannot be sent as it is (an edge or its surface off
 * the grid, a surface that does not tessellate) is settled and the file made again: a rebuilt face
 * that did not tessellate is tried once more as KEEP; a face that fails as KEEP is left out of the
 * model with a warning naming its entity (o->strict: the model fails instead).  Every round settles
 * at least one face for good, so the rounds end.
 */
cm_err encode_model(loaded_model *lm, const encode_opts *o, encode_result *r, cm_status *st)
{
    if (lm->brep.nplacements > 0 && !encode_places(o)) {
        memset(r, 0, sizeof *r);
        return cm_fail(st, CM_E_ARG, "a model loaded with its placed copies folded out needs format 4.3");
    }
    if (o->steps) { /* a steps file that names no part fails before the long work, not after */
        memset(r, 0, sizeof *r);
        enc_parts p;
        cm_err pe = enc_parts_build(lm, o->steps, &p, r->refusal, sizeof r->refusal, st);
        if (pe != CM_OK)
            return pe;
        enc_parts_free(&p);
    }
    int nb = lm->brep.nfaces;
    unsigned char *keep_only = calloc((size_t)nb + 1, 1), *flip0 = malloc((size_t)nb + 1);
    unsigned char *net_whole = calloc((size_t)nb + 1, 1);
    /* why a face cut open (brep_seam.h) kept its surface all the same: its report says that, not the
       uncut face's "fewer than 3 sides" (a cone's cap, one circle) or "holes" (a band) */
    const char **cut_why = calloc((size_t)nb + 1, sizeof *cut_why);
    enc_work *w = calloc(1, sizeof *w);
    if (!keep_only || !flip0 || !w || !net_whole || !cut_why) {
        free(keep_only);
        free(net_whole);
        free(cut_why);
        free(flip0);
        free(w);
        memset(r, 0, sizeof *r);
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    }
    for (int b = 0; b < nb; b++)
        flip0[b] = (unsigned char)lm->brep.faces[b].flip;
    int left_out = 0, nets_whole = 0;
    cm_err e;
    for (;;) {
        int nf = lm->mesh.nfaces, nfaults = 0;
        const char **fault = calloc((size_t)nf + 1, sizeof *fault);
        if (!fault) {
            e = cm_fail(st, CM_E_NOMEM, "out of memory");
            break;
        }
        e = encode_pass(w, lm, o, keep_only, net_whole, fault, &nfaults, r, st);
        if (e == CM_OK && nfaults == 0 && r->faces) {
            /* a band cut open whose surface is still sent: the cut only cost its edge (brep_seam.h);
               the face as it was, the curve mesh anew, and the file once more */
            int *kept_cut = malloc((size_t)nf * sizeof *kept_cut + 1), uncut = 0;
            for (int f = 0; kept_cut && f < nf; f++) {
                int b = lm->mesh.faces[f].brep_face;
                if (enc_kept(r->faces[f].method) && lm->brep.faces[b].cut_from_nloops > 0) {
                    cut_why[b] = r->faces[f].why;
                    kept_cut[uncut++] = b;
                }
            }
            e = kept_cut ? uncut_faces(lm, kept_cut, uncut, flip0, 1, st) : cm_fail(st, CM_E_NOMEM, "out of memory");
            free(kept_cut);
            if (e != CM_OK || uncut > 0) {
                encode_result_free(r);
                free(fault);
                if (e != CM_OK)
                    break;
                continue;
            }
        }
        if (e != CM_OK || nfaults == 0) {
            free(fault);
            break;
        }
        /* settle the faulty faces: a band cut open as it was imported (brep_seam.h), KEEP once
           more where a rebuilt surface failed, else leave out */
        int *out = malloc((size_t)nfaults * sizeof *out), nout = 0, retried = 0, nuncut = 0;
        int *uncut = malloc((size_t)nfaults * sizeof *uncut);
        if (!out || !uncut) {
            free(out);
            free(uncut);
            free(fault);
            e = cm_fail(st, CM_E_NOMEM, "out of memory");
            break;
        }
        for (int f = 0; f < nf; f++) {
            if (!fault[f])
                continue;
            int b = lm->mesh.faces[f].brep_face;
            if (lm->brep.faces[b].cut_from_nloops > 0) {
                uncut[nuncut++] = b;
                retried++;
            } else if (fault[f] == enc_net_folds && !net_whole[b]) {
                net_whole[b] = 1; /* its net whole, as the source has it */
                nets_whole++;
                retried++;
            } else if (r->faces && !enc_kept(r->faces[f].method) && !keep_only[b]) {
                keep_only[b] = 1;
                retried++;
            } else {
                out[nout++] = f;
            }
        }
        char refusal[sizeof r->refusal] = "";
        if (nout > 0 && o->strict) {
            const brep_face *F = &lm->brep.faces[lm->mesh.faces[out[0]].brep_face];
            char src[64];
            snprintf(refusal, sizeof refusal, "face of %s cannot be sent: %s (--strict)",
                     brep_face_source(F, src, sizeof src), fault[out[0]]);
            e = cm_fail(st, CM_E_DEGENERATE, "a face cannot be sent (--strict)");
        }
        if (e == CM_OK) /* (a face left out builds the curve mesh anew below) */
            e = uncut_faces(lm, uncut, nuncut, flip0, nout == 0, st);
        free(uncut);
        if (e == CM_OK && nout > 0) {
            /* back to the orientation the face domains were built with, then the curve mesh anew */
            int *bad = malloc((size_t)nout * sizeof *bad);
            char (*why)[160] = malloc((size_t)nout * sizeof *why);
            if (!bad || !why)
                e = cm_fail(st, CM_E_NOMEM, "out of memory");
            for (int i = 0; e == CM_OK && i < nout; i++) {
                bad[i] = lm->mesh.faces[out[i]].brep_face;
                snprintf(why[i], sizeof why[i], "%s", fault[out[i]]);
            }
            for (int b = 0; e == CM_OK && b < lm->brep.nfaces; b++)
                lm->brep.faces[b].flip = flip0[b];
            /* from the last: a face left out moves the later ones down, and what is kept per face
               with them (until 2026-12-07 a second round read a moved face's neighbour's) */
            for (int i = nout - 1; e == CM_OK && i >= 0; i--) {
                e = model_leave_out_face(lm, bad[i], why[i], st);
                if (e == CM_OK) {
                    size_t after = (size_t)(lm->brep.nfaces - bad[i]);
                    memmove(&flip0[bad[i]], &flip0[bad[i] + 1], after);
                    memmove(&keep_only[bad[i]], &keep_only[bad[i] + 1], after);
                    memmove(&net_whole[bad[i]], &net_whole[bad[i] + 1], after);
                    memmove(&cut_why[bad[i]], &cut_why[bad[i] + 1], after * sizeof *cut_why);
                }
                left_out++;
            }
            free(bad);
            free(why);
        }
        free(out);
        free(fault);
        encode_result_free(r);
        memcpy(r->refusal, refusal, sizeof refusal);
        if (e != CM_OK)
            break;
        if (lm->mesh.nfaces == 0) {
            e = cm_fail(st, CM_E_DEGENERATE, "no face of the model can be sent (see warnings)");
            break;
        }
    }
    r->faces_left_out = left_out;
    r->nets_whole = nets_whole;
    for (int f = 0; e == CM_OK && r->faces && f < lm->mesh.nfaces; f++) {
        int b = lm->mesh.faces[f].brep_face;
        if (cut_why[b] && enc_kept(r->faces[f].method))
            r->faces[f].why = cut_why[b];
    }
    free(cut_why);
    if (e == CM_OK && enc_compact_header(o) && o->compact_minor >= (int)CM_FMT_PARTS_MINOR) {
        /* what write_parts sent (the same numbering on the same faces) */
        enc_parts p;
        char why[256];
        cm_status pst;
        cm_status_init(&pst);
        if (enc_parts_build(lm, o->steps, &p, why, sizeof why, &pst) == CM_OK) {
            r->parts = p.nparts >= 2 && (p.held > 0 || o->steps) ? p.nparts : 0;
            r->parts_stepped = r->parts ? p.stepped : 0;
            enc_parts_free(&p);
        }
    }
    free(keep_only);
    free(net_whole);
    free(flip0);
    free(w);
    return e;
}
