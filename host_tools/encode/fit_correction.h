/*
 * fit_correction.h - the encoder's half of GREGORY-FIT: the least-squares
 * fit of each patch's interior correction (decoder/src/cm/cm_patchfit.h)
 * to the face's source surface, and its quantisation as the record sends it.
 */
#ifndef FIT_CORRECTION_H
#define FIT_CORRECTION_H

#include <stdint.h>

#include "cm/cm_gregface.h"
#include "cm/cm_method.h"
#include "model_load.h"

/** A fitted correction as the record carries it: coefficient = q * 2^exp * grid mm. */
struct fit_record {
    int m;                                          /* coefficients per direction, 1..CM_FIT_MAX_M */
    int npatch;                                     /* patches of the surface it was fitted to */
    int exp;                                        /* the step's power of two above the model grid */
    int32_t q[CM_MAX_GREG * CM_FIT_MAX_COEF][3];    /* patch k's coefficient (i,j) at (k m + i) m + j */
    int ntwist;                                     /* G1FIT (format 4.2): uses with a twist field (0: none) */
    int16_t twist[CM_GREG_MAX_INPUT][CM_TWIST_N];   /* ... each use's quantised sines (cm_fit_q) */
    unsigned hint_mask;                             /* GREGORY family (format 4.13): hinted corners, */
    int16_t hint[CM_GREG_MAX_INPUT][2];             /* ... their normals in corner order (cm_fit_q) */
};
typedef struct fit_record fit_record;

/** The record's view for the FACE section writer (cm_method_write_record). */
static inline cm_fit_q fit_record_view(const fit_record *r)
{
    cm_fit_q v = {r->m,         r->npatch, r->exp, (const int32_t(*)[3])r->q, r->ntwist,
                  (const int16_t(*)[CM_TWIST_N])r->twist, r->hint_mask, (const int16_t(*)[2])r->hint};
    return v;
}

/**
 * Fit face f's correction with m coefficients per direction to the patches gs (built without one)
 * and quantise it with a step of the model grid (`grid` mm) times a power of two at most tol/256.
 * Returns 1 and the record; 0 when the face has no source domain, or the fitted patches still miss
 * a point of the source grid by tol or more (the measure then fails: not worth a rebuild).
 */
int fit_correction(const loaded_model *lm, int bface, const cm_greg_surface *gs, int m, double tol, double grid,
                   fit_record *out);

/**
 * Whether a correction could bring the patches gs of face `bface` within tol at all: it vanishes with
 * its slopes on every side of every patch, so each side stays where GREGORY-EXACT put it.  Returns 0
 * when a point of a side (t = 1/4, 1/2, 3/4) is tol or more off the source surface: the N-split's
 * inner curves cutting across a surface they do not follow (the outer sides are the curve mesh's
 * edges, on the surface).  1 otherwise, or when the face has no source domain (no verdict).
 */
/**
 * A fitted net's interior correction (NFILL, G1FIT from format 4.2; cm_fit_net_add): m per
 * direction, fitted to face `bface`'s source surface for the bicubic net `net` (rebuilt without
 * one; m at most its interior rows, nu - 4 and nv - 4), quantised as fit_correction does.  Returns 1
 * and the record (one patch); 0 when the face has no source domain or the corrected net still
 * misses a point of the source grid by tol or more.  fit_net.c.
 */
int fit_net_correction(const loaded_model *lm, int bface, const cm_surf *net, int m, double tol, double grid,
                       fit_record *out);

/** The coefficients c (npatch * m * m) as the record sends them: a step of the model grid (`grid`
    mm) times the largest power of two at most tol/256.  0 when one is beyond CM_FIT_MAX_INT. */
int fit_record_quantise(fit_record *out, const cm_vec3 *c, int m, int npatch, double tol, double grid);

int fit_sides_within(const loaded_model *lm, int bface, const cm_greg_surface *gs, double tol);

#endif /* FIT_CORRECTION_H */
