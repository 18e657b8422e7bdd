/* cm_methods.c - the table of face methods and the dispatch of their operations (see cm_method.h). */
#include "cm_method_impl.h"

#include <stddef.h>

/* spec §14: PLANE first (exact and free when it applies), then the GREGORY patches (the cubic ones
   first: files that do without the exact ones stay readable by format 2.0), then G1FIT (the edges as
   borders, their tangent planes kept: a record of 43 bits), then GREGORY-FIT (a sent correction,
   tens of bytes: only where nothing before passes; G1FIT first made every corpus model that has
   GREGORY-FIT faces smaller, asitus__Tightening_screw 12664 -> 12377 bytes), NFILL (sampled edges,
   any loop shape), KEEP last */
const cm_method *const cm_method_table[CM_METHOD_COUNT] = {&cm_method_plane,        &cm_method_gregory,
                                                           &cm_method_gregory_exact, &cm_method_g1fit,
                                                           &cm_method_gregory_fit,  &cm_method_nfill,
                                                           &cm_method_keep};

const cm_method *cm_method_of(unsigned id)
{
    for (int i = 0; i < CM_METHOD_COUNT; i++)
        if (cm_method_table[i]->id == id)
            return cm_method_table[i];
    return NULL;
}

const char *cm_method_name(unsigned id)
{
    const cm_method *m = cm_method_of(id);
    return m ? m->name : "?";
}

/* One switch per operation: a method without the operation falls to the default (nothing to do). */

cm_err cm_method_read_record(const cm_method *M, cm_ac_dec *ac, cm_face_ctx *ctx, cm_model *m, cm_face *F,
                             cm_method_fault *why)
{
    switch (M->id) {
    case CM_METHOD_GREGORY:
    case CM_METHOD_GREGORY_EXACT:
    case CM_METHOD_GREGORY_FIT: {
        cm_err e = M->id == CM_METHOD_GREGORY_FIT ? cm_gregory_fit_read_record(ac, ctx, m, F, why)
                                                  : cm_gregory_read_record(ac, ctx, F, why);
        return e != CM_OK ? e : cm_gregory_read_hints(ac, ctx, m, F, why);
    }
    case CM_METHOD_NFILL:
        return cm_nfill_read_record(ac, ctx, m, F, why);
    case CM_METHOD_G1FIT:
        return cm_g1fit_read_record(ac, ctx, m, F, why);
    default:
        return CM_OK;
    }
}

void cm_method_write_record(const cm_method *M, cm_ac_enc *ac, cm_face_ctx *ctx, const cm_face *F,
                            const cm_fit_q *fit)
{
    switch (M->id) {
    case CM_METHOD_GREGORY:
    case CM_METHOD_GREGORY_EXACT:
        cm_gregory_write_record(ac, ctx, F);
        cm_gregory_write_hints(ac, ctx, fit);
        break;
    case CM_METHOD_GREGORY_FIT:
        cm_gregory_fit_write_record(ac, ctx, F, fit);
        cm_gregory_write_hints(ac, ctx, fit);
        break;
    case CM_METHOD_NFILL:
        cm_nfill_write_record(ac, ctx, F, fit);
        break;
    case CM_METHOD_G1FIT:
        cm_g1fit_write_record(ac, ctx, F, fit);
        break;
    default:
        break;
    }
}

cm_err cm_method_check_loops(const cm_method *M, const cm_model *m, const cm_face *F, cm_method_fault *why)
{
    switch (M->id) {
    case CM_METHOD_GREGORY:
    case CM_METHOD_GREGORY_EXACT:
        return cm_gregory_check_loops(m, F, why);
    case CM_METHOD_GREGORY_FIT:
        return cm_gregory_fit_check_loops(m, F, why);
    case CM_METHOD_NFILL:
        return cm_nfill_check_loops(m, F, why);
    case CM_METHOD_G1FIT:
        return cm_g1fit_check_loops(m, F, why);
    default:
        return CM_OK;
    }
}

int cm_method_needs_midpoints(const cm_method *M, const cm_face *F)
{
    switch (M->id) {
    case CM_METHOD_GREGORY:
    case CM_METHOD_GREGORY_EXACT:
    case CM_METHOD_GREGORY_FIT:
        return cm_gregory_needs_midpoints(F);
    default:
        return 0;
    }
}

cm_err cm_method_rebuild(const cm_method *M, const cm_model *m, uint32_t f, int check, int n, int n_outer,
                         cm_rebuilt *out, cm_rebuild_ws *ws, cm_status *st)
{
    switch (M->id) {
    case CM_METHOD_KEEP:
        return cm_keep_rebuild(m, f, check, n, n_outer, out, ws, st);
    case CM_METHOD_PLANE:
        return cm_plane_rebuild(m, f, check, n, n_outer, out, ws, st);
    case CM_METHOD_GREGORY:
        return cm_gregory_rebuild(m, f, check, n, n_outer, out, ws, st);
    case CM_METHOD_GREGORY_EXACT:
        return cm_gregory_exact_rebuild(m, f, check, out, ws, st);
    case CM_METHOD_GREGORY_FIT:
        return cm_gregory_fit_rebuild(m, f, check, out, ws, st);
    case CM_METHOD_NFILL:
        return cm_nfill_rebuild(m, f, check, n, n_outer, out, ws, st);
    case CM_METHOD_G1FIT:
        return cm_g1fit_rebuild(m, f, check, out, ws, st);
    default:
        return cm_fail(st, CM_E_UNSUPPORTED, "face method");
    }
}

void cm_method_needs(const cm_method *M, const cm_model *m, const cm_face *F, uint32_t *need)
{
    switch (M->id) {
    case CM_METHOD_GREGORY:
    case CM_METHOD_GREGORY_EXACT:
    case CM_METHOD_GREGORY_FIT:
        cm_gregory_needs(m, F, need);
        break;
    case CM_METHOD_NFILL:
        cm_nfill_needs(m, F, need);
        break;
    case CM_METHOD_G1FIT:
        cm_g1fit_needs(m, F, need);
        break;
    default:
        break;
    }
}
