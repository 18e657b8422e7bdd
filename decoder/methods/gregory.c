/*
 * gregory.c - GREGORY (spec §6, docs/METHODS.md): a face of one loop of 3
 * to CM_MAX_SIDES edges rebuilt as Gregory patches from its boundary
 * curves and the cross-boundary tangents of its G1 neighbours.  The record
 * holds the layout (0: one four-sided patch, 1: N-split into one patch per
 * side, 2: one patch degenerate at corner `corner` of a three-sided face,
 * 3 (format 2.3, GREGORY-EXACT and -FIT only): one four-sided patch whose
 * corners are the loop vertices named by the bits of `corner`, the edges
 * between them joined into its sides)
 * and the FNV-1a checksum of the encoder's patches (spec §2 rule 6): a
 * terminal that rebuilds them differently says so instead of showing it.
 */
#include "cm/cm_limits_info.h"
#include "cm_method_impl.h"

#include <math.h>

cm_err cm_gregory_read_record(cm_ac_dec *ac, cm_face_ctx *ctx, cm_face *F, cm_method_fault *why)
{
    uint64_t layout = cm_ac_dec_uint(ac, &ctx->layout);
    uint64_t corner = cm_ac_dec_uint(ac, &ctx->corner);
    F->checksum = cm_ac_dec_direct(ac, 16);
    F->checksum |= cm_ac_dec_direct(ac, 16) << 16;
    if (ac->overrun) {
        why->what = "face record";
        return CM_E_TRUNCATED;
    }
    if (layout > CM_GREG_LAYOUT_JOINED) {
        why->what = "GREGORY layout";
        return CM_E_RANGE;
    }
    if (layout == CM_GREG_LAYOUT_JOINED ? corner >= (1u << CM_GREG_JOINED_MAX_EDGES)
                                        : corner >= CM_MAX_SIDES || (layout != CM_GREG_LAYOUT_DEGEN && corner != 0)) {
        why->what = "GREGORY corner";
        return CM_E_RANGE;
    }
    F->layout = (uint8_t)layout;
    F->corner = (uint16_t)corner;
    return CM_OK;
}

void cm_gregory_write_record(cm_ac_enc *ac, cm_face_ctx *ctx, const cm_face *F)
{
    cm_ac_enc_uint(ac, &ctx->layout, F->layout);
    cm_ac_enc_uint(ac, &ctx->corner, F->corner);
    cm_ac_enc_direct(ac, F->checksum & 0xffffu, 16);
    cm_ac_enc_direct(ac, F->checksum >> 16, 16);
}

/* spec 15.3's octahedral map: v = n / (|x| + |y| + |z|), the lower half folded over the diagonals */
void cm_hint_encode(cm_vec3 n, int16_t q[2])
{
    double s = fabs(n.x) + fabs(n.y) + fabs(n.z);
    double x = s > 0 ? n.x / s : 0, y = s > 0 ? n.y / s : 0;
    if (s > 0 && n.z < 0) {
        double fx = (1 - fabs(y)) * (x < 0 ? -1 : 1), fy = (1 - fabs(x)) * (y < 0 ? -1 : 1);
        x = fx, y = fy;
    }
    /* (rounded half away from zero, |x|, |y| <= 1; written out: the decoder links no libm rounding) */
    double qx = x * CM_FMT_HINT_ONE, qy = y * CM_FMT_HINT_ONE;
    q[0] = (int16_t)(qx < 0 ? -(int32_t)(0.5 - qx) : (int32_t)(qx + 0.5));
    q[1] = (int16_t)(qy < 0 ? -(int32_t)(0.5 - qy) : (int32_t)(qy + 0.5));
}

cm_vec3 cm_hint_decode(int32_t qx, int32_t qy)
{
    double x = (double)qx / CM_FMT_HINT_ONE, y = (double)qy / CM_FMT_HINT_ONE, z = 1 - fabs(x) - fabs(y);
    if (z < 0) {
        double fx = (1 - fabs(y)) * (x < 0 ? -1 : 1), fy = (1 - fabs(x)) * (y < 0 ? -1 : 1);
        x = fx, y = fy;
    }
    return cm_unit(cm_v3(x, y, z));
}

cm_err cm_gregory_place_hints(cm_model *m, cm_face *F, unsigned mask, const int16_t (*q)[2])
{
    unsigned count = 0;
    for (unsigned b = mask; b; b &= b - 1)
        count++;
    if (count > CM_MAX_MODEL_CTRL - m->nctrl)
        return CM_E_LIMIT;
    if (mask && !F->fit)
        F->surf = m->nctrl; /* (GREGORY-FIT's follow its correction: cm_face_hint_first) */
    for (unsigned i = 0; i < count; i++) {
        m->ctrl[m->nctrl] = cm_hint_decode(q[i][0], q[i][1]);
        m->w[m->nctrl++] = 1.0;
    }
    F->fill_nu = (uint8_t)(mask & 0xffu);
    F->fill_nv = (uint8_t)(mask >> 8);
    return CM_OK;
}

cm_err cm_gregory_read_hints(cm_ac_dec *ac, cm_face_ctx *ctx, cm_model *m, cm_face *F, cm_method_fault *why)
{
    int16_t q[CM_GREG_JOINED_MAX_EDGES][2];
    unsigned count = 0;
    F->fill_nu = F->fill_nv = 0;
    uint64_t mask = ctx->hints && cm_ac_dec_bit(ac, &ctx->hint_any) ? cm_ac_dec_uint(ac, &ctx->hint_mask) : 0;
    if (mask >= 1u << CM_GREG_JOINED_MAX_EDGES) {
        why->what = "GREGORY hints";
        return CM_E_RANGE;
    }
    for (uint64_t b = mask; b && !ac->overrun; b &= b - 1, count++) {
        int64_t qx = cm_ac_dec_sint(ac, &ctx->hint_oct), qy = cm_ac_dec_sint(ac, &ctx->hint_oct);
        if (qx < -CM_FMT_HINT_ONE || qx > CM_FMT_HINT_ONE || qy < -CM_FMT_HINT_ONE || qy > CM_FMT_HINT_ONE) {
            why->what = ac->overrun ? "face record" : "GREGORY hint normal";
            return ac->overrun ? CM_E_TRUNCATED : CM_E_RANGE;
        }
        q[count][0] = (int16_t)qx, q[count][1] = (int16_t)qy;
    }
    if (ac->overrun) {
        why->what = "face record";
        return CM_E_TRUNCATED;
    }
    if (cm_gregory_place_hints(m, F, (unsigned)mask, (const int16_t(*)[2])q) != CM_OK) {
        why->what = "GREGORY hints";
        why->limit = CM_LIMIT_MAX_MODEL_CTRL;
        why->need = (uint64_t)m->nctrl + count;
        return CM_E_LIMIT;
    }
    return CM_OK;
}

void cm_gregory_write_hints(cm_ac_enc *ac, cm_face_ctx *ctx, const cm_fit_q *fit)
{
    unsigned mask = fit ? fit->hint_mask : 0u;
    if (!ctx->hints)
        return;
    cm_ac_enc_bit(ac, &ctx->hint_any, mask != 0);
    if (mask)
        cm_ac_enc_uint(ac, &ctx->hint_mask, mask);
    for (unsigned k = 0, i = 0; k < CM_GREG_JOINED_MAX_EDGES; k++)
        if ((mask >> k) & 1u) {
            cm_ac_enc_sint(ac, &ctx->hint_oct, fit->hint[i][0]);
            cm_ac_enc_sint(ac, &ctx->hint_oct, fit->hint[i][1]);
            i++;
        }
}

/* one loop of 3..CM_MAX_SIDES edges; layout 0 only for 4, layout 2 only for 3, layout 3 for 5 to 12
   with four corners named */
cm_err cm_gregory_check_loops(const cm_model *m, const cm_face *F, cm_method_fault *why)
{
    uint32_t n = m->loops[F->loop0].nuse;
    why->what = NULL;
    if (F->nloops != 1)
        why->what = "GREGORY face with holes";
    else if (n < 3)
        why->what = "GREGORY face with fewer than 3 sides";
    else if ((F->layout == 0 && n != 4) || (F->layout == 2 && n != 3) || (F->layout == CM_GREG_LAYOUT_JOINED && n < 5))
        why->what = "GREGORY sides do not fit the layout";
    else if (F->layout == 2 && F->corner >= n)
        why->what = "GREGORY corner beyond the loop";
    else if (F->layout == CM_GREG_LAYOUT_JOINED && F->method == CM_METHOD_GREGORY)
        why->what = "GREGORY layout 3 on cubic patches"; /* it joins the exact edges */
    else if (F->layout == CM_GREG_LAYOUT_JOINED && !cm_greg_joined_ok(F->corner, (int)n))
        why->what = "GREGORY layout 3 corners";
    else if (cm_face_hint_mask(F) >> n)
        why->what = "GREGORY hint beyond the loop";
    if (why->what)
        return CM_E_FORMAT;
    /* layout 3 takes up to 12 edges in any build that can do it at all (CM_MAX_SIDES >= 5) */
    uint32_t need = F->layout == CM_GREG_LAYOUT_JOINED ? 5u : n;
    if (need > CM_MAX_SIDES) {
        why->what = "GREGORY sides";
        why->limit = CM_LIMIT_MAX_SIDES;
        why->need = need;
        return CM_E_LIMIT;
    }
    return CM_OK;
}

/* the N-split's inner curves start at each side's midpoint */
int cm_gregory_needs_midpoints(const cm_face *F)
{
    return F->layout == CM_GREG_LAYOUT_SPLIT;
}

cm_err cm_gregory_family_rebuild(const cm_model *m, uint32_t f, int check, int exact, int fit, cm_rebuilt *out,
                                 cm_rebuild_ws *ws, cm_status *st)
{
    const cm_face *F = &m->faces[f];
    cm_err e = cm_greg_input_build(m, f, exact, &ws->gin, &ws->corner, st);
    if (e != CM_OK)
        return e;
    e = exact ? cm_egreg_build(&ws->gin, F->layout, F->corner, &ws->greg, st)
              : cm_greg_build(&ws->gin, F->layout, F->corner, &ws->greg, st);
    if (e != CM_OK)
        return e;
    if (fit && (e = cm_gregory_fit_apply(m, F, &ws->greg, st)) != CM_OK)
        return e;
    out->repr = CM_REPR_PATCHES;
    out->greg = &ws->greg;
    out->checksum = cm_greg_surface_checksum(&ws->greg);
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
    check = 0; /* as with the CRCs: mutated records must reach the tessellation */
#endif
    if (check && out->checksum != F->checksum)
        return cm_fail(st, CM_E_CHECKSUM, fit     ? "GREGORY-FIT face rebuilt differently from the encoder"
                                          : exact ? "GREGORY-EXACT face rebuilt differently from the encoder"
                                                  : "GREGORY face rebuilt differently from the encoder");
    return CM_OK;
}

cm_err cm_gregory_rebuild(const cm_model *m, uint32_t f, int check, int n, int n_outer, cm_rebuilt *out,
                          cm_rebuild_ws *ws, cm_status *st)
{
    (void)n;
    (void)n_outer;
    return cm_gregory_family_rebuild(m, f, check, 0, 0, out, ws, st);
}

/* sides of the outer loop; N-split: one patch per side */
void cm_gregory_needs(const cm_model *m, const cm_face *F, uint32_t *need)
{
    uint32_t sides = m->loops[F->loop0].nuse;
    uint32_t patches = F->layout == CM_GREG_LAYOUT_SPLIT ? sides : 1u;
    if (F->layout == CM_GREG_LAYOUT_JOINED)
        sides = 5; /* what a build needs for layout 3 (cm_gregory_check_loops) */
    if (sides > need[CM_LIMIT_MAX_SIDES])
        need[CM_LIMIT_MAX_SIDES] = sides;
    if (patches > need[CM_LIMIT_MAX_GREG])
        need[CM_LIMIT_MAX_GREG] = patches;
}

const cm_method cm_method_gregory = {
    .name = "gregory",
    .counted = "gregory",
    .id = CM_METHOD_GREGORY,
    .since_major = 2,
    .has_record = 1,
    .layouts = 3,
    .too_new = "GREGORY face in a format 1 file",
};
