/*
 * enc_method.h - the encoder's half of a face method (the decoder's half is
 * its module in decoder/methods/, cm_method.h): the trial that decides
 * whether face f may be sent by the method, and what the report says about
 * a face that keeps its surface.  One file per method (enc_plane.c,
 * enc_gregory.c, enc_keep.c), one row in choose_methods.c.
 */
#ifndef ENC_METHOD_H
#define ENC_METHOD_H

#include "encode_internal.h"
#include "verify.h"

typedef struct enc_method {
    unsigned id; /* CM_METHOD_*: the row of cm_method_table it belongs to */
    /**
     * Try the method on face f of the decoded model t->w->dec.model: rebuild it with the decoder's
     * code (enc_trial_rebuild) and verify it against the source surface (spec §12).  1 when it
     * passes: its surface in fs[f], its record in t, its numbers in rep; 0 with rep->why otherwise.
     * NULL: the method always applies (the fallback).
     */
    int (*trial)(tx *t, const loaded_model *lm, int f, const encode_opts *o, face_report *rep, face_surface *fs);
    /** For a face that ends with this method and keeps its surface: its report's numbers (NULL: none). */
    void (*measure_kept)(enc_work *w, const loaded_model *lm, int f, face_report *rep);
} enc_method;

extern const enc_method enc_method_plane, enc_method_gregory, enc_method_gregory_exact, enc_method_gregory_fit,
    enc_method_g1fit, enc_method_nfill, enc_method_keep;

/**
 * Rebuild face f of the decoded model with a trial record (decoder code, no checksum check); fit:
 * GREGORY-FIT's correction (else NULL), placed in the model as the terminal's reader places it.
 */
cm_err enc_trial_rebuild(enc_work *w, int f, int method, int layout, int corner, const cm_fit_q *fit, cm_rebuilt *rb);

/**
 * Face f with a trial record (fit: its correction, or NULL; its rebuild's checksum) tessellated as the terminal will, at the file's
 * chordal tolerance, and measured against its source surface both ways (verify_mesh_face, `expect`
 * its expected distance): what the trimmed mesh the viewer gets strays, which §12 on the untrimmed
 * surface does not see.  HUGE_VAL when the face does not tessellate or its triangles fold.
 */
double enc_trial_mesh_dev(enc_work *w, const loaded_model *lm, int f, int method, int layout, int corner,
                          const cm_fit_q *fit, uint32_t checksum, double expect);
struct fit_record;
/** Format 4.2: a net over the tolerance by itself, a candidate for a correction. */
typedef struct enc_net_near {
    int c, variant; /* its size, and its mode (G1FIT) or fairing weight (NFILL) */
    double err;     /* §12's error without a correction */
} enc_net_near;
/* the correction is tried on the nets over the tolerance by at most ENC_NET_REACH times it (at most
   5 x 5 coefficients mend a face that is nearly right, not a wrong one), the ENC_NET_TRIED closest */
#define ENC_NET_REACH 4.0
#define ENC_NET_TRIED 3
/** The candidates, closest first. */
void enc_net_near_sort(enc_net_near *near, int n);
/**
 * A corrected net passed (rb, fe): sent unless its record costs as much as the kept surface (spec §14
 * step 6: then 0, fr freed, rep->why says so); else fr goes to t->fit[f] and the record to t.
 */
int enc_net_take(tx *t, int f, struct fit_record *fr, int layout, int corner, int shown, const cm_rebuilt *rb,
                 const face_error *fe, face_report *rep);
/**
 * Format 4.2: face f's net (method NFILL or G1FIT, record layout and corner), over the tolerance by
 * itself, with an interior correction fitted to the source surface (fit_net_correction, at most as
 * many coefficients per direction as the net has interior rows).  1 when the corrected rebuild
 * passes §12 within tol: the record in *fr, the numbers in *fe, the rebuild in *rb (the smallest m
 * that passes).  base: G1FIT's twists (a record of m = 0; NULL: none), in every record tried.  The
 * method's own checks are the caller's.
 */
int enc_net_corrected(enc_work *w, const loaded_model *lm, int f, int method, int layout, int corner, double tol,
                      const struct fit_record *base, struct fit_record *fr, face_error *fe, cm_rebuilt *rb);
/**
 * A candidate passed (GREGORY family, NFILL, G1FIT): its record fields (layout, corner:
 * enc_record_fields) and checksum to t, its measures to rep (rep->corner shows `shown`: the corner,
 * or the fairing or mode index).
 */
void enc_fit_accept(tx *t, int f, int layout, int corner, int shown, const cm_rebuilt *rb, const face_error *fe,
                    face_report *rep);

#endif /* ENC_METHOD_H */
