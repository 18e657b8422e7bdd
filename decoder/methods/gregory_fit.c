/*
 * gregory_fit.c - GREGORY-FIT (docs/METHODS.md, format 2.2): GREGORY-EXACT's
 * patches plus an interior correction per patch that the encoder fitted to
 * the face's true surface and sends (cm_patchfit.h).
 *
 * Why: the papers rebuild a face from its boundary alone, and on real models
 * many faces then come back just over the tolerance (fillets of revolution,
 * saddles: 2555 of 4826 kept faces of a corpus run were measured over it),
 * and at a tolerance of 0.1 % most curved faces do.  Keeping such a face
 * sends its whole surface (hundreds of bytes and more); a correction of one
 * to 25 vectors per patch, quantised at 1/256 of the tolerance, costs tens.
 * The correction vanishes with its first derivatives on every patch side, so
 * the boundary and the G1 conditions are GREGORY-EXACT's.
 *
 * Record: GREGORY's (layout, corner, checksum), then m (coefficients per
 * direction, 1..CM_FIT_MAX_M), the number of patches (which the loops must
 * then match), exp, and per patch, per coefficient (i,j) row-major, x y z as
 * signed integers: coefficient = integer * 2^exp * the model's grid step.
 * The coefficients go to the model's control-point pool (MAX_MODEL_CTRL).
 * The checksum covers the patches and the correction as dequantised.
 */
#include "cm/cm_limits_info.h"
#include "cm/cm_patchfit.h"
#include "cm_method_impl.h"

cm_err cm_gregory_fit_read_record(cm_ac_dec *ac, cm_face_ctx *ctx, cm_model *m, cm_face *F, cm_method_fault *why)
{
    cm_err e = cm_gregory_read_record(ac, ctx, F, why);
    if (e != CM_OK)
        return e;
    uint64_t fm = cm_ac_dec_uint(ac, &ctx->fit_m);
    uint64_t np = cm_ac_dec_uint(ac, &ctx->fit_patches);
    uint64_t ex = cm_ac_dec_uint(ac, &ctx->fit_exp);
    if (ac->overrun) {
        why->what = "face record";
        return CM_E_TRUNCATED;
    }
    if (fm < 1 || fm > CM_FIT_MAX_M) {
        why->what = "GREGORY-FIT coefficients per direction";
        return CM_E_RANGE;
    }
    if (np < 1 || np > CM_HARD_MAX_GREG) {
        why->what = "GREGORY-FIT patches";
        return CM_E_RANGE;
    }
    if (np > CM_MAX_GREG) {
        why->what = "GREGORY-FIT patches";
        why->limit = CM_LIMIT_MAX_GREG;
        why->need = np;
        return CM_E_LIMIT;
    }
    return cm_fit_read_coefs(ac, ctx, m, F, (unsigned)fm, (unsigned)np, ex, why);
}

cm_err cm_fit_read_coefs(cm_ac_dec *ac, cm_face_ctx *ctx, cm_model *m, cm_face *F, unsigned fm, unsigned np,
                         uint64_t ex, cm_method_fault *why)
{
    int net = F->method != CM_METHOD_GREGORY_FIT; /* a net's correction (the faults name it) */
    if (ex > CM_FIT_MAX_EXP) {
        why->what = net ? "net correction step" : "GREGORY-FIT step";
        return CM_E_RANGE;
    }
    uint32_t n = np * fm * fm;
    if (n > CM_MAX_MODEL_CTRL - m->nctrl) {
        why->what = net ? "net correction coefficients" : "GREGORY-FIT coefficients";
        why->limit = CM_LIMIT_MAX_MODEL_CTRL;
        why->need = (uint64_t)m->nctrl + n;
        return CM_E_LIMIT;
    }
    F->fit = cm_face_fit_pack(fm, np);
    F->surf = m->nctrl;
    for (uint32_t i = 0; i < n; i++) {
        double c[3];
        for (int a = 0; a < 3; a++) {
            int64_t q = cm_ac_dec_sint(ac, &ctx->fit_coef);
            if (ac->overrun) {
                why->what = "face record";
                return CM_E_TRUNCATED;
            }
            if (q < -(int64_t)CM_FIT_MAX_INT || q > (int64_t)CM_FIT_MAX_INT) {
                why->what = net ? "net correction coefficient" : "GREGORY-FIT coefficient";
                return CM_E_RANGE;
            }
            c[a] = cm_fit_dequantise((int32_t)q, m->q, (int)ex);
        }
        m->ctrl[m->nctrl] = cm_v3(c[0], c[1], c[2]);
        m->w[m->nctrl] = 1.0;
        m->nctrl++;
    }
    return CM_OK;
}

void cm_fit_write_coefs(cm_ac_enc *ac, cm_face_ctx *ctx, const cm_fit_q *fit)
{
    cm_ac_enc_uint(ac, &ctx->fit_exp, (uint64_t)fit->exp);
    for (int i = 0; i < fit->patches * fit->m * fit->m; i++)
        for (int a = 0; a < 3; a++)
            cm_ac_enc_sint(ac, &ctx->fit_coef, fit->q[i][a]);
}

void cm_gregory_fit_write_record(cm_ac_enc *ac, cm_face_ctx *ctx, const cm_face *F, const cm_fit_q *fit)
{
    cm_gregory_write_record(ac, ctx, F);
    cm_ac_enc_uint(ac, &ctx->fit_m, (uint64_t)fit->m);
    cm_ac_enc_uint(ac, &ctx->fit_patches, (uint64_t)fit->patches);
    cm_fit_write_coefs(ac, ctx, fit);
}

/* GREGORY's rules, and as many corrections as the layout has patches */
cm_err cm_gregory_fit_check_loops(const cm_model *m, const cm_face *F, cm_method_fault *why)
{
    cm_err e = cm_gregory_check_loops(m, F, why);
    if (e != CM_OK)
        return e;
    uint32_t sides = m->loops[F->loop0].nuse;
    uint32_t patches = F->layout == CM_GREG_LAYOUT_SPLIT ? sides : 1u;
    if (cm_face_fit_patches(F) != patches) {
        why->what = "GREGORY-FIT corrections do not fit the layout";
        return CM_E_FORMAT;
    }
    return CM_OK;
}

cm_err cm_gregory_fit_apply(const cm_model *m, const cm_face *F, cm_greg_surface *s, cm_status *st)
{
    unsigned fm = cm_face_fit_m(F), np = cm_face_fit_patches(F);
    if (fm < 1 || fm > CM_FIT_MAX_M || np != (unsigned)s->npatch || np > CM_MAX_GREG ||
        F->surf > m->nctrl || np * fm * fm > m->nctrl - F->surf)
        return cm_fail(st, CM_E_FORMAT, "GREGORY-FIT correction");
    s->fit = (int)fm;
    for (unsigned k = 0; k < np; k++)
        for (unsigned i = 0; i < fm * fm; i++)
            s->corr[k][i] = m->ctrl[F->surf + k * fm * fm + i];
    return CM_OK;
}

cm_err cm_gregory_fit_rebuild(const cm_model *m, uint32_t f, int check, cm_rebuilt *out, cm_rebuild_ws *ws,
                              cm_status *st)
{
    return cm_gregory_family_rebuild(m, f, check, 1, 1, out, ws, st);
}

const cm_method cm_method_gregory_fit = {
    .name = "gregory-fit",
    .counted = "gregory-fit",
    .id = CM_METHOD_GREGORY_FIT,
    .since_major = 2,
    .since_minor = 2,
    .has_record = 1,
    .layouts = 4,
    .too_new = "GREGORY-FIT face in a file older than format 2.2",
};
