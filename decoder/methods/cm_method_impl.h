/*
 * cm_method_impl.h - the operations each method module implements (see
 * cm_method.h); only the modules and the dispatch in cm_methods.c include it.
 */
#ifndef CM_METHOD_IMPL_H
#define CM_METHOD_IMPL_H

#include "cm/cm_limits_info.h"
#include "cm/cm_method.h"

/* KEEP (keep.c) */
cm_err cm_keep_rebuild(const cm_model *m, uint32_t f, int check, int n, int n_outer, cm_rebuilt *out, cm_rebuild_ws *ws,
                       cm_status *st);

/* PLANE (plane.c) */
cm_err cm_plane_rebuild(const cm_model *m, uint32_t f, int check, int n, int n_outer, cm_rebuilt *out,
                        cm_rebuild_ws *ws, cm_status *st);

/* GREGORY (gregory.c) */
cm_err cm_gregory_read_record(cm_ac_dec *ac, cm_face_ctx *ctx, cm_face *F, cm_method_fault *why);
void cm_gregory_write_record(cm_ac_enc *ac, cm_face_ctx *ctx, const cm_face *F);
cm_err cm_gregory_check_loops(const cm_model *m, const cm_face *F, cm_method_fault *why);
int cm_gregory_needs_midpoints(const cm_face *F);
cm_err cm_gregory_rebuild(const cm_model *m, uint32_t f, int check, int n, int n_outer, cm_rebuilt *out,
                          cm_rebuild_ws *ws, cm_status *st);
void cm_gregory_needs(const cm_model *m, const cm_face *F, uint32_t *need);
/* format 4.13: the corner hints that end a GREGORY-family record (after GREGORY-FIT's correction),
   their normals into the model's pool; written from fit (NULL: none) */
cm_err cm_gregory_read_hints(cm_ac_dec *ac, cm_face_ctx *ctx, cm_model *m, cm_face *F, cm_method_fault *why);
void cm_gregory_write_hints(cm_ac_enc *ac, cm_face_ctx *ctx, const cm_fit_q *fit);

/* GREGORY, GREGORY-EXACT and GREGORY-FIT: the rebuild they share (gregory.c), exact 1 over the edges
   themselves, fit 1 with the record's correction added (cm_gregory_fit_apply) */
cm_err cm_gregory_family_rebuild(const cm_model *m, uint32_t f, int check, int exact, int fit, cm_rebuilt *out,
                                 cm_rebuild_ws *ws, cm_status *st);

/* GREGORY-EXACT (gregory_exact.c): GREGORY's record, loops and needs; its own rebuild */
cm_err cm_gregory_exact_rebuild(const cm_model *m, uint32_t f, int check, cm_rebuilt *out, cm_rebuild_ws *ws,
                                cm_status *st);

/* GREGORY-FIT (gregory_fit.c): GREGORY's record and a correction; GREGORY-EXACT's patches plus it */
cm_err cm_gregory_fit_read_record(cm_ac_dec *ac, cm_face_ctx *ctx, cm_model *m, cm_face *F, cm_method_fault *why);
void cm_gregory_fit_write_record(cm_ac_enc *ac, cm_face_ctx *ctx, const cm_face *F, const cm_fit_q *fit);
cm_err cm_gregory_fit_check_loops(const cm_model *m, const cm_face *F, cm_method_fault *why);
cm_err cm_gregory_fit_rebuild(const cm_model *m, uint32_t f, int check, cm_rebuilt *out, cm_rebuild_ws *ws,
                              cm_status *st);
/* face F's correction from the model's pool into the patches s built for it */
cm_err cm_gregory_fit_apply(const cm_model *m, const cm_face *F, cm_greg_surface *s, cm_status *st);
/* a correction's step and coefficients (np patches of fm x fm), read into the model's pool (F->fit,
   F->surf set), and written; GREGORY-FIT's and, from format 4.2, the nets' */
cm_err cm_fit_read_coefs(cm_ac_dec *ac, cm_face_ctx *ctx, cm_model *m, cm_face *F, unsigned fm, unsigned np,
                         uint64_t ex, cm_method_fault *why);
void cm_fit_write_coefs(cm_ac_enc *ac, cm_face_ctx *ctx, const cm_fit_q *fit);

/* NFILL (nfill.c): nu, nv, phi and a checksum; one loop; a B-spline fitted to it (cm_nfill.h) */
cm_err cm_nfill_read_record(cm_ac_dec *ac, cm_face_ctx *ctx, cm_model *m, cm_face *F, cm_method_fault *why);
void cm_nfill_write_record(cm_ac_enc *ac, cm_face_ctx *ctx, const cm_face *F, const cm_fit_q *fit);
cm_err cm_nfill_check_loops(const cm_model *m, const cm_face *F, cm_method_fault *why);
cm_err cm_nfill_rebuild(const cm_model *m, uint32_t f, int check, int n, int n_outer, cm_rebuilt *out,
                        cm_rebuild_ws *ws, cm_status *st);
void cm_nfill_needs(const cm_model *m, const cm_face *F, uint32_t *need);

/* the fitted nets' shared parts (nfill.c): the four limits a net asks of a build (need[] by limit id,
   what[] names them in the order MAX_FIT_CTRL, MAX_LSQ_UNKNOWNS, MAX_LSQ_BAND, MAX_SIDES); the
   rebuilt net as the face's surface, with its interior correction (format 4.2, cm_fit_net_add) when
   the record has one, its checksum compared with the record's (`mismatch` names it); the
   correction's field of a net's record (ctx->net_fit: absent before 4.2; fit NULL: none); a
   method's needs folded into the model's */
cm_err cm_fit_net_check_needs(const uint32_t need[CM_LIMIT_COUNT], const char *const what[4], cm_method_fault *why);
cm_err cm_fit_net_result(const cm_model *m, cm_nfill_surface *net, const cm_face *F, int check, cm_rebuilt *out,
                         const char *mismatch, cm_status *st);
cm_err cm_fit_net_read_record(cm_ac_dec *ac, cm_face_ctx *ctx, cm_model *m, cm_face *F, cm_method_fault *why);
void cm_fit_net_write_record(cm_ac_enc *ac, cm_face_ctx *ctx, const cm_fit_q *fit);
void cm_needs_merge(const uint32_t mine[CM_LIMIT_COUNT], uint32_t *need);

/* G1FIT (g1fit.c): nu, nv, mode and a checksum; a B-spline over the face's four edge chains (cm_g1fit.h) */
cm_err cm_g1fit_read_record(cm_ac_dec *ac, cm_face_ctx *ctx, cm_model *m, cm_face *F, cm_method_fault *why);
void cm_g1fit_write_record(cm_ac_enc *ac, cm_face_ctx *ctx, const cm_face *F, const cm_fit_q *fit);
cm_err cm_g1fit_check_loops(const cm_model *m, const cm_face *F, cm_method_fault *why);
cm_err cm_g1fit_rebuild(const cm_model *m, uint32_t f, int check, cm_rebuilt *out, cm_rebuild_ws *ws, cm_status *st);
void cm_g1fit_needs(const cm_model *m, const cm_face *F, uint32_t *need);

#endif /* CM_METHOD_IMPL_H */
