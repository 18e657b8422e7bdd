/*
 * g1fit.c - G1FIT (spec §9 as built here, docs/METHODS.md): a bicubic
 * B-spline whose borders are the face's four edge chains, its second row in
 * their tangent planes, its interior the Coons net's or faired (kernel:
 * cm_g1fit.c).  Edges are sampled, so arcs and multi-span edges are fine;
 * it rebuilds four- to twelve-sided faces whose Gregory patch strays from
 * the tangent planes along edges that turn.  The record holds what the
 * compressor searched (nu, nv, mode) and the checksum of the net.
 * Format 2.5.
 */
#include "cm_method_impl.h"

#include "cm/cm_corner.h"
#include "cm/cm_g1fit.h"
#include "cm/cm_limits_info.h"

/*
 * Format 4.2: the twists along the outer loop's edges (cm_g1fit.h).  A bit: any; then the count of
 * uses (the loop follows the record: its length is checked against it in cm_g1fit_check_loops), and
 * per use a bit and, when set, each inner sample's quantised sine as its change from the sample
 * before (0 before the first).  In the model's pool after the correction's coefficients, three
 * samples a point (zeros for a use without); F->fill_phi's bit 1 says so, F->corner holds the count.
 */
static cm_err read_twists(cm_ac_dec *ac, cm_face_ctx *ctx, cm_model *m, cm_face *F, cm_method_fault *why)
{
    if (!cm_ac_dec_bit(ac, &ctx->twist_on))
        return ac->overrun ? (why->what = "face record", CM_E_TRUNCATED) : CM_OK;
    uint64_t n = cm_ac_dec_uint(ac, &ctx->twist_n);
    if (ac->overrun) {
        why->what = "face record";
        return CM_E_TRUNCATED;
    }
    if (n < CM_G1FIT_MIN_EDGES || n > CM_GREG_JOINED_MAX_EDGES) {
        why->what = "G1FIT twists' count";
        return CM_E_RANGE;
    }
    uint32_t need = 3u * (uint32_t)n;
    if (need > CM_MAX_MODEL_CTRL - m->nctrl) {
        why->what = "G1FIT twists";
        why->limit = CM_LIMIT_MAX_MODEL_CTRL;
        why->need = (uint64_t)m->nctrl + need;
        return CM_E_LIMIT;
    }
    if (!F->fit)
        F->surf = m->nctrl;
    for (uint32_t k = 0; k < n; k++) {
        double s[CM_TWIST_N] = {0};
        if (cm_ac_dec_bit(ac, &ctx->twist_use)) {
            int64_t q = 0;
            for (int j = 0; j < CM_TWIST_N; j++) {
                q += cm_ac_dec_sint(ac, &ctx->twist);
                if (ac->overrun) {
                    why->what = "face record";
                    return CM_E_TRUNCATED;
                }
                if (q < -CM_TWIST_MAX || q > CM_TWIST_MAX) {
                    why->what = "G1FIT twist";
                    return CM_E_RANGE;
                }
                s[j] = (double)q / (double)CM_TWIST_ONE;
            }
        }
        for (int i = 0; i < 3; i++) {
            m->ctrl[m->nctrl] = cm_v3(s[3 * i], s[3 * i + 1], s[3 * i + 2]);
            m->w[m->nctrl] = 1.0;
            m->nctrl++;
        }
    }
    if (ac->overrun) {
        why->what = "face record";
        return CM_E_TRUNCATED;
    }
    F->fill_phi |= CM_G1FIT_TWISTED;
    F->corner = (uint16_t)n;
    return CM_OK;
}

static void write_twists(cm_ac_enc *ac, cm_face_ctx *ctx, const cm_fit_q *fit)
{
    int n = fit ? fit->ntwist : 0;
    cm_ac_enc_bit(ac, &ctx->twist_on, n > 0);
    if (n == 0)
        return;
    cm_ac_enc_uint(ac, &ctx->twist_n, (uint64_t)n);
    for (int k = 0; k < n; k++) {
        int any = 0;
        for (int j = 0; j < CM_TWIST_N; j++)
            any |= fit->twist[k][j] != 0;
        cm_ac_enc_bit(ac, &ctx->twist_use, (unsigned)any);
        for (int j = 0; any && j < CM_TWIST_N; j++)
            cm_ac_enc_sint(ac, &ctx->twist, (int64_t)fit->twist[k][j] - (j ? fit->twist[k][j - 1] : 0));
    }
}

cm_err cm_g1fit_read_record(cm_ac_dec *ac, cm_face_ctx *ctx, cm_model *m, cm_face *F, cm_method_fault *why)
{
    uint64_t nu = cm_ac_dec_direct(ac, 5) + CM_NFILL_MIN_CTRL;
    uint64_t nv = cm_ac_dec_direct(ac, 5) + CM_NFILL_MIN_CTRL;
    uint64_t mode = cm_ac_dec_direct(ac, 1);
    F->checksum = cm_ac_dec_direct(ac, 16);
    F->checksum |= cm_ac_dec_direct(ac, 16) << 16;
    if (ac->overrun) {
        why->what = "face record";
        return CM_E_TRUNCATED;
    }
    F->fill_nu = (uint8_t)nu;
    F->fill_nv = (uint8_t)nv;
    F->fill_phi = (uint8_t)mode;
    cm_err e = cm_fit_net_read_record(ac, ctx, m, F, why);
    if (e != CM_OK || !ctx->net_fit)
        return e;
    return read_twists(ac, ctx, m, F, why);
}

void cm_g1fit_write_record(cm_ac_enc *ac, cm_face_ctx *ctx, const cm_face *F, const cm_fit_q *fit)
{
    cm_ac_enc_direct(ac, (uint32_t)(F->fill_nu - CM_NFILL_MIN_CTRL), 5);
    cm_ac_enc_direct(ac, (uint32_t)(F->fill_nv - CM_NFILL_MIN_CTRL), 5);
    cm_ac_enc_direct(ac, F->fill_phi & 1u, 1);
    cm_ac_enc_direct(ac, F->checksum & 0xffffu, 16);
    cm_ac_enc_direct(ac, F->checksum >> 16, 16);
    cm_fit_net_write_record(ac, ctx, fit);
    if (ctx->net_fit)
        write_twists(ac, ctx, fit);
}

/* what the face's net and loop ask of a build: control points, the faired interior, loop input */
static void g1fit_need(const cm_model *m, const cm_face *F, uint32_t need[CM_LIMIT_COUNT])
{
    uint32_t n = m->loops[F->loop0].nuse, nu = F->fill_nu, nv = F->fill_nv;
    need[CM_LIMIT_MAX_FIT_CTRL] = nu > nv ? nu : nv;
    if ((F->fill_phi & 1u) == 1) {
        uint32_t K = (nu - 4u) * (nv - 4u), w = 2u * (nv - 4u);
        need[CM_LIMIT_MAX_LSQ_UNKNOWNS] = K;
        need[CM_LIMIT_MAX_LSQ_BAND] = K == 0 ? 0 : (w < K - 1u ? w : K - 1u);
    }
    /* a build that can join edges (CM_MAX_SIDES >= 5) takes loops of up to 12 (cm_gregface.h) */
    need[CM_LIMIT_MAX_SIDES] = n > 4u ? 5u : n;
}

/* an outer loop of 4..12 edges (holes are trimmed away, not built: the error check decides); the
   net within the build's limits */
cm_err cm_g1fit_check_loops(const cm_model *m, const cm_face *F, cm_method_fault *why)
{
    uint32_t n = m->loops[F->loop0].nuse;
    why->what = NULL;
    if (n < CM_G1FIT_MIN_EDGES)
        why->what = "G1FIT face with fewer than 4 edges";
    else if (n > CM_GREG_JOINED_MAX_EDGES)
        why->what = "G1FIT loop of more than 12 edges";
    else if ((F->fill_phi & CM_G1FIT_TWISTED) && F->corner != n)
        why->what = "G1FIT twists do not fit the loop";
    if (why->what)
        return CM_E_FORMAT;
    uint32_t need[CM_LIMIT_COUNT] = {0};
    g1fit_need(m, F, need);
    static const char *const what[4] = {"G1FIT control points", "G1FIT unknowns", "G1FIT band", "G1FIT edges"};
    return cm_fit_net_check_needs(need, what, why);
}

cm_err cm_g1fit_rebuild(const cm_model *m, uint32_t f, int check, cm_rebuilt *out, cm_rebuild_ws *ws, cm_status *st)
{
    const cm_face *F = &m->faces[f];
    cm_err e = cm_greg_input_build(m, f, 1, &ws->gin, &ws->corner, st);
    if (e != CM_OK)
        return e;
    /* the twists follow the correction's coefficients in the pool (read_twists) */
    const cm_vec3 *twist = NULL;
    if (F->fill_phi & CM_G1FIT_TWISTED) {
        uint32_t at = F->surf + (F->fit ? cm_face_fit_m(F) * cm_face_fit_m(F) : 0u);
        if ((int)F->corner != ws->gin.n || at > m->nctrl || 3u * F->corner > m->nctrl - at)
            return cm_fail(st, CM_E_FORMAT, "G1FIT twists");
        twist = &m->ctrl[at];
    }
    if ((e = cm_g1fit_build(&ws->gin, F->fill_nu, F->fill_nv, F->fill_phi & 1u, twist, &ws->nfill, &ws->g1fit_ws,
                            st)) != CM_OK)
        return e;
    /* Su x Sv is the loop's turning direction at its corners (side 0 leaves corner 0 along the loop,
       side 3 leaves it against): the face normal n_F when the loop runs counter-clockwise about it */
    return cm_fit_net_result(m, &ws->nfill, F, check, out, "G1FIT face rebuilt differently from the encoder", st);
}

void cm_g1fit_needs(const cm_model *m, const cm_face *F, uint32_t *need)
{
    uint32_t mine[CM_LIMIT_COUNT] = {0};
    g1fit_need(m, F, mine);
    cm_needs_merge(mine, need);
}

const cm_method cm_method_g1fit = {
    .name = "g1fit",
    .counted = "g1fit",
    .id = CM_METHOD_G1FIT,
    .since_major = 2,
    .since_minor = 5,
    .has_record = 1,
    .too_new = "G1FIT face in a file older than format 2.5",
};
