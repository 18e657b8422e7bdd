/* choose_methods.c - spec §14: per face the first method of the table whose rebuild passes the
   verification against the source surface, then the G1 fix-point (see encode_internal.h). */
#include "encode_internal.h"
#include "enc_method.h"
#include "enc_workers.h"
#include "fit_correction.h"
#include "verify.h"

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_const.h"
#include "cm/cm_corner.h"
#include "cm/cm_crc32.h"
#include "cm/cm_cubic_convert.h"
#include "cm/cm_g1fit.h"
#include "cm/cm_method.h"
#include "cm/cm_sections.h"

/* ---- decoding what we wrote, with the terminal's code ---- */

cm_err enc_decode_back(enc_work *w, const encode_result *r, cm_status *st)
{
    cm_dec_init(&w->dec);
    cm_err e = cm_dec_feed(&w->dec, r->bytes, r->len, st);
    if (e == CM_OK)
        e = cm_dec_finish(&w->dec, st);
    /* the encoder measures the tessellation's needs (needs.c): nothing declared bounds it, whatever
       the header it wrote so far says (a declared 0 would cap every face at the slack) */
    w->dec.model.need_tess_points = w->dec.model.need_edge_samples = w->dec.model.need_tris = 0;
    if (e != CM_OK && st && e != CM_E_NOMEM) {
        /* a byte of a file the user never sees names nothing: the fault is the encoder's; what the
           terminal's reader refused goes into the report (a process encodes one model at a time:
           its workers are processes) */
        static char why[320];
        snprintf(why, sizeof why, "the encoder's check of its own file, whose %s the terminal's reader refused (an "
                 "encoder bug: please report it with the model)", st->where ? st->where : "?");
        st->offset = CM_NO_OFFSET;
        st->where = why;
    }
    return e;
}

/* ---- method choice per face ---- */

/* rebuild face f of the decoded model with a trial record (decoder code, no checksum yet) */
/* face f's record replaced by a trial one, the correction (fit, or none) where the terminal's reader
   puts it: the control-point pool, here past its end, dequantised as the reader does
   (cm_fit_dequantise); trial_restore puts the face back */
static cm_err trial_place(cm_model *m, int f, int method, int layout, int corner, const cm_fit_q *fit)
{
    cm_face *F = &m->faces[f];
    enc_record_fields(F, method, layout, corner);
    F->fit = 0;
    if (fit && fit->ntwist > 0) {
        /* G1FIT's twists after the correction's coefficients, as read_twists places them */
        if (fit->ntwist > CM_GREG_MAX_INPUT || 3u * (uint32_t)fit->ntwist + CM_FIT_MAX_COEF > CM_MAX_MODEL_CTRL - m->nctrl)
            return CM_E_LIMIT;
    }
    if (fit && fit->m > 0) {
        uint32_t n = (uint32_t)(fit->patches * fit->m * fit->m);
        if (fit->m > CM_FIT_MAX_M || fit->patches < 1 || fit->patches > CM_MAX_GREG ||
            n > CM_MAX_MODEL_CTRL - m->nctrl)
            return CM_E_LIMIT;
        F->fit = cm_face_fit_pack((unsigned)fit->m, (unsigned)fit->patches);
        F->surf = m->nctrl;
        for (uint32_t i = 0; i < n; i++)
            m->ctrl[m->nctrl + i] = cm_v3(cm_fit_dequantise(fit->q[i][0], m->q, fit->exp),
                                          cm_fit_dequantise(fit->q[i][1], m->q, fit->exp),
                                          cm_fit_dequantise(fit->q[i][2], m->q, fit->exp));
        m->nctrl += n;
    }
    if (fit && fit->ntwist > 0) {
        if (!F->fit)
            F->surf = m->nctrl;
        for (int k = 0; k < fit->ntwist; k++)
            for (int i = 0; i < 3; i++)
                m->ctrl[m->nctrl++] = cm_v3((double)fit->twist[k][3 * i] / CM_TWIST_ONE,
                                            (double)fit->twist[k][3 * i + 1] / CM_TWIST_ONE,
                                            (double)fit->twist[k][3 * i + 2] / CM_TWIST_ONE);
        F->fill_phi |= CM_G1FIT_TWISTED;
        F->corner = (uint16_t)fit->ntwist;
    }
    /* the corner hints after the correction, as the reader places them */
    if (fit && fit->hint_mask && cm_method_takes_hints((unsigned)method))
        return cm_gregory_place_hints(m, F, fit->hint_mask, fit->hint);
    return CM_OK;
}

static void trial_restore(cm_model *m, int f, const cm_face *saved, uint32_t nctrl)
{
    m->faces[f] = *saved;
    m->nctrl = nctrl;
}

cm_err enc_trial_rebuild(enc_work *w, int f, int method, int layout, int corner, const cm_fit_q *fit, cm_rebuilt *rb)
{
    cm_model *m = &w->dec.model;
    cm_face saved = m->faces[f];
    uint32_t nctrl = m->nctrl;
    cm_err e = trial_place(m, f, method, layout, corner, fit);
    if (e == CM_OK)
        e = cm_rebuild_face_ex(m, (uint32_t)f, 0, rb, &w->rbws, NULL);
    trial_restore(m, f, &saved, nctrl);
    return e;
}

/* the terminal's mesh of face f with a trial record, measured against the source surface both ways
   (verify_mesh_face); HUGE_VAL when it does not tessellate or its triangles fold */
double enc_trial_mesh_dev(enc_work *w, const loaded_model *lm, int f, int method, int layout, int corner,
                          const cm_fit_q *fit, uint32_t checksum, double expect)
{
    cm_model *m = &w->dec.model;
    cm_face saved = m->faces[f];
    uint32_t nctrl = m->nctrl;
    if (trial_place(m, f, method, layout, corner, fit) != CM_OK) {
        trial_restore(m, f, &saved, nctrl);
        return HUGE_VAL;
    }
    m->faces[f].checksum = checksum;
    cm_mesh_face mf;
    cm_mesh mesh = {w->face_pos, w->face_nrm, w->face_idx, &mf, 0, CM_MAX_TESS_POINTS, 0, 3 * CM_MAX_TESS_TRIS, 0, 1, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    cm_tess_info info;
    cm_status st;
    cm_status_init(&st);
    cm_err e = cm_tessellate_face(m, (uint32_t)f, m->tess_tol, &mesh, &w->tess_ws, &info, &st);
    trial_restore(m, f, &saved, nctrl);
    if (e != CM_OK || enc_face_folds(&mesh) != 0)
        return HUGE_VAL;
    double d = verify_mesh_face(lm, f, (const float(*)[3])mesh.pos, mesh.nverts, mesh.idx, mesh.nindex, expect);
    return d < 0 ? HUGE_VAL : d;
}

void enc_fit_accept(tx *t, int f, int layout, int corner, int shown, const cm_rebuilt *rb, const face_error *fe,
                    face_report *rep)
{
    t->layout[f] = layout;
    t->corner[f] = corner;
    t->checksum[f] = rb->checksum;
    t->turning[f] = (unsigned char)(rb->repr == CM_REPR_PATCHES && cm_greg_surface_turns(rb->greg));
    rep->layout = layout;
    rep->corner = shown;
    rep->rebuild_max = fe->max;
    rep->rebuild_avg = fe->avg;
    rep->ratio = fe->ratio;
    rep->why = NULL;
}

/* the encoder's half of each method (enc_method.h), found by the decoder table's number */
static const enc_method *const enc_methods[] = {&enc_method_plane, &enc_method_gregory, &enc_method_gregory_exact,
                                                &enc_method_gregory_fit, &enc_method_g1fit, &enc_method_nfill,
                                                &enc_method_keep};

static const enc_method *enc_method_of(unsigned id)
{
    for (size_t i = 0; i < sizeof enc_methods / sizeof enc_methods[0]; i++)
        if (enc_methods[i]->id == id)
            return enc_methods[i];
    return NULL;
}

/* spec §14: the methods of the table from row `from` on, the first that passes wins (KEEP always does) */
static int first_passing(tx *t, const loaded_model *lm, int f, const encode_opts *o, face_report *rep,
                         face_surface *fs, int from)
{
    for (int i = from; i < CM_METHOD_COUNT; i++) {
        const enc_method *E = enc_method_of(cm_method_table[i]->id);
        /* a correction is the record of the method that fitted it (a face turned back from
           GREGORY-FIT by the G1 fix-point must not carry its correction on) */
        free(t->fit[f]);
        t->fit[f] = NULL;
        face_report before = *rep;
        int noted = t->asked.n + t->asked.all;
        int passed = E && E->trial && E->trial(t, lm, f, o, rep, fs);
        if (t->asked.row < 0 && t->asked.n + t->asked.all > noted) {
            t->asked.row = i;
            t->asked.rep = before;
        }
        if (passed)
            return cm_method_table[i]->id;
    }
    return CM_METHOD_FALLBACK;
}

void tx_note_check(tx *t, const tx_check *c)
{
    tx_asked *a = &t->asked;
    if (a->n < TX_MAX_CHECKS)
        a->check[a->n++] = *c;
    else
        a->all = 1;
}

static int table_row(int method)
{
    for (int i = 0; i < CM_METHOD_COUNT; i++)
        if (cm_method_table[i]->id == method)
            return i;
    return CM_METHOD_COUNT;
}

/*
 * Face f's method: the first row of the table that passes (the first pass of choose_methods), with
 * faces 0..chosen-1 counted as chosen (t->method) where a trial asks (t->asked says what it asked).
 */
static void choose_face(const loaded_model *lm, tx *t, const encode_opts *o, encode_result *r, face_surface *fs, int f,
                        int chosen)
{
    face_report *rep = &r->faces[f];
    memset(rep, 0, sizeof *rep);
    rep->g1_cos = 1.0;
    rep->layout = -1;
    t->method[f] = CM_METHOD_FALLBACK;
    t->layout[f] = t->corner[f] = 0;
    t->checksum[f] = 0;
    t->turning[f] = 0;
    free(t->fit[f]);
    t->fit[f] = NULL;
    face_surface_free(&fs[f]);
    memset(&t->asked, 0, sizeof t->asked);
    t->asked.row = -1;
    if (t->keep_only[lm->mesh.faces[f].brep_face]) {
        rep->why = "rebuilt surface did not tessellate";
        return;
    }
    t->nchosen = chosen;
    t->method[f] = first_passing(t, lm, f, o, rep, fs, 0);
    if (enc_kept(t->method[f]))
        face_surface_free(&fs[f]);
}

/* ---- the first pass in worker processes (cmz encode -j N) ---- */

/* what a worker found for one face, in memory it shares with the encoder: what every face has (the
   larger parts, a correction and the checks, are in the board's arrays and touched only where a
   face has them: a model of 100 000 faces touches a few pages per thousand faces here) */
typedef struct face_found {
    atomic_int done; /* 0: not yet; 1: by a worker, the rest filled in; 2: by the encoder itself */
    int method, layout, corner, has_fit;
    unsigned char turning;
    uint32_t checksum;
    face_report rep; /* its `why` points at a string of the program, the same in every process */
    int row, n, all; /* what its trials asked of the faces before it (tx_asked; checks in board->check) */
    face_report rep_asked;
} face_found;

typedef struct found_board {
    atomic_int next;  /* the next face a worker takes */
    atomic_int ndone; /* faces done, for the progress line */
    face_found *face; /* per face (the arrays follow the board in the same shared memory) */
    fit_record *fit;  /* per face: its correction, where has_fit */
    tx_check (*check)[TX_MAX_CHECKS]; /* per face: its checks, n of them */
} found_board;

typedef struct choose_job {
    const loaded_model *lm;
    tx *t;
    const encode_opts *o;
    encode_result *r;
    face_surface *fs;
    found_board *b;
} choose_job;

/* face f's record of what its trials asked (t->asked) onto the board, only as much as it holds */
static void copy_asked(found_board *b, int f, const tx_asked *from)
{
    face_found *F = &b->face[f];
    F->row = from->row;
    F->rep_asked = from->rep;
    F->n = from->n;
    F->all = from->all;
    memcpy(b->check[f], from->check, (size_t)from->n * sizeof *from->check);
}

/* face f chosen by a worker (its answer on the board) or by the encoder itself (`self`: it stays in
   t, r and fs) */
static void choose_item(void *ctx, int f, int self)
{
    const choose_job *J = ctx;
    tx *t = J->t;
    choose_face(J->lm, t, J->o, J->r, J->fs, f, 0); /* no face counts as chosen: see choose_in_workers */
    face_found *F = &J->b->face[f];
    if (!self) {
        F->method = t->method[f];
        F->layout = t->layout[f];
        F->corner = t->corner[f];
        F->turning = t->turning[f];
        F->checksum = t->checksum[f];
        F->rep = J->r->faces[f];
        F->has_fit = t->fit[f] != NULL;
        if (t->fit[f])
            J->b->fit[f] = *t->fit[f];
    }
    copy_asked(J->b, f, &t->asked);
    atomic_store(&F->done, self ? 2 : 1);
    int n = atomic_fetch_add(&J->b->ndone, 1) + 1;
    if (self && J->o->progress)
        J->o->progress("choosing methods", n, t->nfaces, J->o->progress_ctx);
}

/* a worker's answer for face f taken into t, r and fs: its surface rebuilt from the record (one
   rebuild, where the worker made many trials); 0 when that does not give the worker's surface (its
   checksum; a method without one, PLANE, leaves 0) */
static int take_found(tx *t, encode_result *r, face_surface *fs, int f, const found_board *b)
{
    const face_found *F = &b->face[f];
    t->method[f] = F->method;
    t->layout[f] = F->layout;
    t->corner[f] = F->corner;
    t->turning[f] = F->turning;
    t->checksum[f] = F->checksum;
    r->faces[f] = F->rep;
    free(t->fit[f]);
    t->fit[f] = NULL;
    face_surface_free(&fs[f]);
    if (F->has_fit) {
        if (!(t->fit[f] = malloc(sizeof *t->fit[f])))
            return 0;
        *t->fit[f] = b->fit[f];
    }
    if (enc_kept(F->method))
        return 1;
    cm_fit_q view;
    if (t->fit[f])
        view = fit_record_view(t->fit[f]);
    cm_rebuilt rb;
    return enc_trial_rebuild(t->w, f, F->method, F->layout, F->corner, t->fit[f] ? &view : NULL, &rb) == CM_OK &&
           (rb.checksum == F->checksum || F->checksum == 0) && face_surface_set(&fs[f], &rb);
}

/* 1 where a face before f across one of its edges keeps its surface */
static int kept_before(const cm_model *m, const tx *t, int f)
{
    const cm_face *F = &m->faces[f];
    for (uint32_t l = 0; l < F->nloops; l++) {
        const cm_loop *L = &m->loops[F->loop0 + l];
        for (uint32_t u = 0; u < L->nuse; u++) {
            uint32_t e = m->uses[L->use0 + u].edge;
            int32_t a = m->edge_face[e][0], b = m->edge_face[e][1];
            int32_t g = a == f ? b : a;
            if (a >= 0 && b >= 0 && a != b && g < f && enc_kept(t->method[g]))
                return 1;
        }
    }
    return 0;
}

/* 1 where a check of face f's trials (its record on the board) answers otherwise with the faces
   before it as chosen */
static int answer_changes(const cm_model *m, const tx *t, int f, const found_board *b)
{
    const face_found *F = &b->face[f];
    if (F->all)
        return kept_before(m, t, f);
    for (int k = 0; k < F->n; k++) {
        const tx_check *c = &b->check[f][k];
        double rebuilt = c->other, kept = 1.0;
        for (int i = 0; i < c->n; i++) {
            double *w = enc_kept(t->method[c->face[i]]) ? &kept : &rebuilt;
            *w = c->worst[i] < *w ? c->worst[i] : *w;
        }
        if ((rebuilt >= c->need_rebuilt && kept >= c->need_kept) != c->ok)
            return 1;
    }
    return 0;
}

/* face f chosen again from the row whose trial made its first check, with every face before it
   chosen: the rows above answered as they would have in order (they asked nothing) */
static void choose_again(const loaded_model *lm, tx *t, const encode_opts *o, encode_result *r, face_surface *fs,
                         int f, const face_found *F)
{
    r->faces[f] = F->rep_asked;
    t->method[f] = CM_METHOD_FALLBACK;
    t->layout[f] = t->corner[f] = 0;
    t->checksum[f] = 0;
    t->turning[f] = 0;
    face_surface_free(&fs[f]);
    memset(&t->asked, 0, sizeof t->asked);
    t->asked.row = -1;
    t->nchosen = f;
    t->method[f] = first_passing(t, lm, f, o, &r->faces[f], fs, F->row);
    if (enc_kept(t->method[f]))
        face_surface_free(&fs[f]);
}

/*
 * The first pass on `jobs` processes (the encoder and jobs - 1 forked workers, sharing the decoded
 * model copy-on-write), with the same answer as in order.  Face f's trials read nothing of the other
 * faces' choices but G1FIT's question which faces before f keep their surfaces (t->nchosen): a
 * worker answers "none" and records each such check with what it measured toward each of those
 * faces (t->asked); then, in order, the checks are answered again with the faces before it final,
 * and a face whose answer changes is chosen again from that trial on.  A worker that cannot start or
 * dies leaves its faces to the encoder.  0 when no memory can be shared (nothing done: choose in
 * order).
 */
static int choose_in_workers(const loaded_model *lm, tx *t, const encode_opts *o, encode_result *r,
                              face_surface *fs, int jobs)
{
    int nf = t->nfaces;
    size_t at_fit = sizeof(found_board) + (size_t)nf * sizeof(face_found);
    at_fit = (at_fit + 63) / 64 * 64;
    size_t at_check = at_fit + (size_t)nf * sizeof(fit_record);
    at_check = (at_check + 63) / 64 * 64;
    size_t size = at_check + (size_t)nf * sizeof(tx_check[TX_MAX_CHECKS]);
    found_board *b = enc_shared_alloc(size);
    if (b) {
        b->face = (face_found *)(void *)(b + 1);
        b->fit = (fit_record *)(void *)((unsigned char *)b + at_fit);
        b->check = (tx_check(*)[TX_MAX_CHECKS])(void *)((unsigned char *)b + at_check);
    }
    if (!b)
        return 0;
    choose_job J = {lm, t, o, r, fs, b};
    enc_workers_run(jobs, nf, &b->next, choose_item, &J, o->jobs_die_after);
    for (int f = 0; f < nf; f++) {
        face_found *F = &b->face[f];
        int done = atomic_load(&F->done);
        if (done == 1 && !take_found(t, r, fs, f, b))
            done = 0;
        if (done == 0) { /* its worker died, or its answer does not rebuild: the encoder's own */
            choose_face(lm, t, o, r, fs, f, 0);
            copy_asked(b, f, &t->asked);
        }
    }
    const cm_model *m = &t->w->dec.model;
    for (int f = 0; f < nf; f++)
        if (b->face[f].row >= 0 && answer_changes(m, t, f, b))
            choose_again(lm, t, o, r, fs, f, &b->face[f]);
    enc_shared_free(b, size);
    return 1;
}

/*
 * Spec §14 steps 3-4 on the decoded model (the transmitted edges): per face PLANE, then the
 * GREGORY candidates, else KEEP; then the G1 fix-point: every G1 edge next to a rebuilt face is
 * checked on the final surfaces (§13), and where it fails the rebuilt face with the larger error
 * moves on to the next method of the table that passes (spec: back to KEEP; a GREGORY face next to
 * a GREGORY-EXACT one meets it G1 when it too takes its edges as they are), until nothing changes.
 * Faces only move down the table: at most #faces x #methods rounds.
 */
static cm_err choose_methods(const loaded_model *lm, tx *t, const encode_opts *o, encode_result *r, cm_status *st)
{
    enc_work *w = t->w;
    const cm_model *m = &w->dec.model;
    int nf = t->nfaces;
    face_surface *fs = calloc((size_t)nf + 1, sizeof *fs);
    if (!fs)
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    if (!(o->jobs > 1 && nf > 1 && choose_in_workers(lm, t, o, r, fs, o->jobs)))
        for (int f = 0; f < nf; f++) {
            if (o->progress)
                o->progress("choosing methods", f + 1, nf, o->progress_ctx);
            choose_face(lm, t, o, r, fs, f, f);
        }
    t->nchosen = nf;
    /* each G1 edge is measured once, and again only when one of its faces went back to KEEP */
    double *ecos = malloc(((size_t)m->nedges + 1) * sizeof *ecos);
    int *eworse = malloc(((size_t)m->nedges + 1) * sizeof *eworse);
    unsigned char *dirty = malloc((size_t)m->nedges + 1);
    if (!ecos || !eworse || !dirty) {
        free(ecos);
        free(eworse);
        free(dirty);
        for (int f = 0; f < nf; f++)
            face_surface_free(&fs[f]);
        free(fs);
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    }
    memset(dirty, 1, (size_t)m->nedges + 1);
    for (int round = 0; round <= nf * CM_METHOD_COUNT; round++) {
        int changed = 0;
        for (int f = 0; f < nf; f++)
            r->faces[f].g1_cos = 1.0;
        for (uint32_t e = 0; e < m->nedges; e++) {
            int32_t a = m->edge_face[e][0], b = m->edge_face[e][1];
            if (!m->edges[e].g1 || a < 0 || b < 0 || a == b)
                continue;
            if (enc_kept(t->method[a]) && enc_kept(t->method[b]))
                continue;
            if (dirty[e])
                ecos[e] = verify_g1_edge(lm, m, e, fs, &eworse[e]);
            dirty[e] = 0;
            double c = ecos[e];
            for (int s = 0; s < 2; s++) {
                face_report *rep = &r->faces[s ? b : a];
                rep->g1_cos = c < rep->g1_cos ? c : rep->g1_cos;
            }
            if (c >= CM_COS_G1)
                continue;
            /* spec §14 step 4 reverts the rebuilt face with the larger Max error; on the corpus that often
               turned back an exact PLANE next to a Gregory face whose error is smaller in millimetres
               but whose normal is the one that strays.  The face whose normal is farther from its own
               source surface goes back (a KEEP face's is exact, so a rebuilt one is always picked). */
            int pick = enc_kept(t->method[a]) ? b : a;
            if (!enc_kept(t->method[a]) && !enc_kept(t->method[b]))
                pick = eworse[e] ? b : a;
            face_surface_free(&fs[pick]);
            face_report *prep = &r->faces[pick];
            t->method[pick] = first_passing(t, lm, pick, o, prep, fs, table_row(t->method[pick]) + 1);
            if (enc_kept(t->method[pick])) {
                face_surface_free(&fs[pick]);
                prep->why = "G1";
            }
            changed = 1;
            /* its edges are measured again next round (this one included: now against a KEEP face) */
            const cm_face *F = &m->faces[pick];
            for (uint32_t l = 0; l < F->nloops; l++) {
                const cm_loop *L = &m->loops[F->loop0 + l];
                for (uint32_t u = 0; u < L->nuse; u++)
                    dirty[m->uses[L->use0 + u].edge] = 1;
            }
        }
        if (!changed)
            break;
    }
    free(ecos);
    free(eworse);
    free(dirty);
    memset(r->faces_by_method, 0, sizeof r->faces_by_method);
    for (int f = 0; f < nf; f++) {
        face_report *rep = &r->faces[f];
        rep->method = t->method[f];
        r->faces_by_method[t->method[f]]++;
        if (enc_kept(t->method[f])) {
            t->layout[f] = t->corner[f] = 0;
            t->checksum[f] = 0;
            t->turning[f] = 0;
            rep->layout = -1;
            rep->fit_m = 0;
            enc_method_of((unsigned)t->method[f])->measure_kept(w, lm, f, rep);
        }
        face_surface_free(&fs[f]);
    }
    free(fs);
    return CM_OK;
}

/*
 * The file with every face kept (so that every face can be measured against a decoded model that
 * has all surfaces), decoded; the methods chosen on it; the file with those, decoded again.
 */
cm_err enc_choose_and_write(loaded_model *lm, tx *t, const encode_opts *o, encode_result *r, cm_status *st)
{
    for (int f = 0; f < t->nfaces; f++)
        t->method[f] = CM_METHOD_FALLBACK;
    cm_err e = enc_write_file(t, lm, o, NULL, r, st);
    if (e == CM_OK)
        e = enc_decode_back(t->w, r, st);
    /* that file has no exact patch, so it says format 1.0 or 2.0; the trials rebuild them as the
       file with them will say (write_sections.c: 2.6 where a side turns) */
    t->w->dec.model.turning_basis = o->turning_basis;
    if (e == CM_OK)
        e = choose_methods(lm, t, o, r, st);
    if (e == CM_OK)
        e = enc_write_file(t, lm, o, NULL, r, st);
    if (e == CM_OK)
        e = enc_decode_back(t->w, r, st);
    return e;
}
