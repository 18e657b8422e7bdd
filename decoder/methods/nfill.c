/*
 * nfill.c - NFILL (spec §8, docs/METHODS.md): a bicubic B-spline fitted to
 * the face's outer loop and to its tangent planes along outward rays, on a
 * rectangle that contains the face (kernel: cm_nfill.c).  Its loop may be
 * concave and of any edges (they are sampled, not converted to cubics), so
 * it rebuilds faces the Gregory patches cannot: reflex corners, loops of
 * more sides than the N-split takes, holes.  The record holds what the
 * compressor searched (nu, nv, phi) and the checksum of the net.
 * Format 2.4.
 */
#include "cm_method_impl.h"

#include "cm/cm_corner.h"
#include "cm/cm_limits_info.h"

cm_err cm_nfill_read_record(cm_ac_dec *ac, cm_face_ctx *ctx, cm_model *m, cm_face *F, cm_method_fault *why)
{
    uint64_t nu = cm_ac_dec_direct(ac, 5) + CM_NFILL_MIN_CTRL;
    uint64_t nv = cm_ac_dec_direct(ac, 5) + CM_NFILL_MIN_CTRL;
    uint64_t phi = cm_ac_dec_direct(ac, 3);
    F->checksum = cm_ac_dec_direct(ac, 16);
    F->checksum |= cm_ac_dec_direct(ac, 16) << 16;
    if (ac->overrun) {
        why->what = "face record";
        return CM_E_TRUNCATED;
    }
    if (phi >= CM_NFILL_PHI_COUNT) {
        why->what = "NFILL phi";
        return CM_E_RANGE;
    }
    F->fill_nu = (uint8_t)nu;
    F->fill_nv = (uint8_t)nv;
    F->fill_phi = (uint8_t)phi;
    return cm_fit_net_read_record(ac, ctx, m, F, why);
}

void cm_nfill_write_record(cm_ac_enc *ac, cm_face_ctx *ctx, const cm_face *F, const cm_fit_q *fit)
{
    cm_ac_enc_direct(ac, (uint32_t)(F->fill_nu - CM_NFILL_MIN_CTRL), 5);
    cm_ac_enc_direct(ac, (uint32_t)(F->fill_nv - CM_NFILL_MIN_CTRL), 5);
    cm_ac_enc_direct(ac, F->fill_phi, 3);
    cm_ac_enc_direct(ac, F->checksum & 0xffffu, 16);
    cm_ac_enc_direct(ac, F->checksum >> 16, 16);
    cm_fit_net_write_record(ac, ctx, fit);
}

/* From format 4.2 a net's record ends with its interior correction: m (0: none), then as
   GREGORY-FIT's of one patch (cm_fit_read_coefs) */
cm_err cm_fit_net_read_record(cm_ac_dec *ac, cm_face_ctx *ctx, cm_model *m, cm_face *F, cm_method_fault *why)
{
    if (!ctx->net_fit)
        return CM_OK;
    uint64_t fm = cm_ac_dec_uint(ac, &ctx->fit_m);
    if (ac->overrun) {
        why->what = "face record";
        return CM_E_TRUNCATED;
    }
    if (fm == 0)
        return CM_OK;
    if (fm > CM_FIT_MAX_M) {
        why->what = "net correction's coefficients per direction";
        return CM_E_RANGE;
    }
    uint64_t ex = cm_ac_dec_uint(ac, &ctx->fit_exp);
    if (ac->overrun) {
        why->what = "face record";
        return CM_E_TRUNCATED;
    }
    return cm_fit_read_coefs(ac, ctx, m, F, (unsigned)fm, 1u, ex, why);
}

void cm_fit_net_write_record(cm_ac_enc *ac, cm_face_ctx *ctx, const cm_fit_q *fit)
{
    if (!ctx->net_fit)
        return;
    uint64_t fm = fit ? (uint64_t)fit->m : 0u; /* G1FIT's twists alone: m = 0 */
    cm_ac_enc_uint(ac, &ctx->fit_m, fm);
    if (fm > 0)
        cm_fit_write_coefs(ac, ctx, fit);
}

/* what the face's net and loop ask of a build: control points, unknowns, band, loop input */
static void nfill_need(const cm_model *m, const cm_face *F, uint32_t need[CM_LIMIT_COUNT])
{
    uint32_t n = m->loops[F->loop0].nuse, nu = F->fill_nu, nv = F->fill_nv;
    uint32_t K = (nu - 2u) * (nv - 2u), w = 3u * (nv - 2u) + 3u;
    need[CM_LIMIT_MAX_FIT_CTRL] = nu > nv ? nu : nv;
    need[CM_LIMIT_MAX_LSQ_UNKNOWNS] = K;
    need[CM_LIMIT_MAX_LSQ_BAND] = w < K - 1u ? w : K - 1u;
    /* a build that can join edges (CM_MAX_SIDES >= 5) takes loops of up to 12 (cm_gregface.h) */
    need[CM_LIMIT_MAX_SIDES] = n > 4u ? 5u : n;
}

/* an outer loop of 3..CM_GREG_JOINED_MAX_EDGES edges, at most 64 edges in all its loops; the net
   within the build's limits */
cm_err cm_nfill_check_loops(const cm_model *m, const cm_face *F, cm_method_fault *why)
{
    uint32_t n = m->loops[F->loop0].nuse, all = 0;
    for (uint32_t l = 0; l < F->nloops; l++)
        all += m->loops[F->loop0 + l].nuse;
    why->what = NULL;
    if (all > CM_NFILL_FMT_ALL_EDGES)
        why->what = "NFILL face of more than 64 edges";
    else if (n < 3)
        why->what = "NFILL face with fewer than 3 edges";
    else if (n > CM_GREG_JOINED_MAX_EDGES)
        why->what = "NFILL loop of more than 12 edges";
    if (why->what)
        return CM_E_FORMAT;
    uint32_t need[CM_LIMIT_COUNT] = {0};
    nfill_need(m, F, need);
    static const char *const what[4] = {"NFILL control points", "NFILL unknowns", "NFILL band", "NFILL edges"};
    return cm_fit_net_check_needs(need, what, why);
}

cm_err cm_fit_net_check_needs(const uint32_t need[CM_LIMIT_COUNT], const char *const what[4], cm_method_fault *why)
{
    static const unsigned ids[4] = {CM_LIMIT_MAX_FIT_CTRL, CM_LIMIT_MAX_LSQ_UNKNOWNS, CM_LIMIT_MAX_LSQ_BAND,
                                    CM_LIMIT_MAX_SIDES};
    static const uint32_t have[4] = {CM_MAX_FIT_CTRL, CM_MAX_LSQ_UNKNOWNS, CM_MAX_LSQ_BAND, CM_MAX_SIDES};
    for (int i = 0; i < 4; i++)
        if (need[ids[i]] > have[i]) {
            why->what = what[i];
            why->limit = ids[i];
            why->need = need[ids[i]];
            return CM_E_LIMIT;
        }
    return CM_OK;
}

cm_err cm_nfill_rebuild(const cm_model *m, uint32_t f, int check, int n, int n_outer, cm_rebuilt *out,
                        cm_rebuild_ws *ws, cm_status *st)
{
    (void)n;
    const cm_face *F = &m->faces[f];
    cm_err e = cm_greg_input_build(m, f, 1, &ws->gin, &ws->corner, st);
    if (e != CM_OK)
        return e;
    /* the holes: the samples the caller took after the outer loop's (cm_rebuild_face_ex: 10 per edge,
       n - n_outer in all), loop by loop (cm_nfill_check_loops bounded their count) */
    cm_nfill_holes *H = &ws->nfill_holes;
    H->n = 0;
    H->start[0] = 0;
    H->pts = ws->samples + n_outer;
    for (uint32_t l = 1; l < F->nloops && H->n < CM_NFILL_MAX_HOLES; l++) {
        H->start[H->n + 1] = H->start[H->n] + (int)m->loops[F->loop0 + l].nuse * CM_FMT_SEG_PER_EDGE;
        H->n++;
    }
    if ((e = cm_nfill_build(&ws->gin, H, F->fill_nu, F->fill_nv, F->fill_phi, &out->frame, &ws->nfill,
                            &ws->nfill_ws, st)) != CM_OK)
        return e;
    /* u along the frame's x, v along its y: Su x Sv along ez, the face normal */
    return cm_fit_net_result(m, &ws->nfill, F, check, out, "NFILL face rebuilt differently from the encoder", st);
}

cm_err cm_fit_net_result(const cm_model *m, cm_nfill_surface *net, const cm_face *F, int check, cm_rebuilt *out,
                         const char *mismatch, cm_status *st)
{
    if (F->fit) {
        unsigned fm = cm_face_fit_m(F);
        if (fm < 1 || fm > CM_FIT_MAX_M || cm_face_fit_patches(F) != 1u || F->surf > m->nctrl ||
            fm * fm > m->nctrl - F->surf)
            return cm_fail(st, CM_E_FORMAT, "net correction");
        cm_fit_net_add(net->ctrl, net->nu, net->nv, net->U, net->V, &m->ctrl[F->surf], (int)fm);
    }
    out->repr = CM_REPR_NURBS;
    out->surf = net->surf;
    out->sign = 1.0;
    out->checksum = cm_nfill_checksum(net);
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
    check = 0; /* as with the CRCs: mutated records must reach the tessellation */
#endif
    if (check && out->checksum != F->checksum)
        return cm_fail(st, CM_E_CHECKSUM, mismatch);
    return CM_OK;
}

void cm_nfill_needs(const cm_model *m, const cm_face *F, uint32_t *need)
{
    uint32_t mine[CM_LIMIT_COUNT] = {0};
    nfill_need(m, F, mine);
    cm_needs_merge(mine, need);
}

void cm_needs_merge(const uint32_t mine[CM_LIMIT_COUNT], uint32_t *need)
{
    for (int i = 0; i < CM_LIMIT_COUNT; i++)
        if (mine[i] > need[i])
            need[i] = mine[i];
}

const cm_method cm_method_nfill = {
    .name = "nfill",
    .counted = "nfill",
    .id = CM_METHOD_NFILL,
    .since_major = 2,
    .since_minor = 4,
    .has_record = 1,
    .too_new = "NFILL face in a file older than format 2.4",
};
