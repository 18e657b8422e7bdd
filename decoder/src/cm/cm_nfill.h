/*
 * cm_nfill.h - method NFILL's surface (spec §8, Tokuyama-Konno N-side
 * filling): a bicubic B-spline on a rectangle that contains the face,
 * fitted by least squares to the face's boundary and to its tangent
 * planes extended outwards along rays, with a thin-plate fairing term.
 * The face is the part of it that its boundary loop trims.
 *
 * Pipeline (spec 8.1-8.8), all in the K11 frame of the boundary:
 *   samples   CM_FMT_SEG_PER_EDGE points per edge of the outer loop, with
 *             a unit inward direction d from the edge's basis normals (5.4);
 *   rectangle the box of the samples' (x, y), enlarged by 0.1 max(w, h);
 *   rays      from each sample outwards along -d, cut where they cross the
 *             loop again, else ending on a side of the rectangle (a hit);
 *   sides     a cubic B-spline per side through its hits, corners from the
 *             sides' linear extensions (8.4); they fix the net's border;
 *   solve     the interior control points by weighted least squares over
 *             the boundary samples (weight 10) and the rays' samples at
 *             1/4, 2/4, 3/4 (weight falling off with distance), plus
 *             phi * trace / K times the thin-plate energy of the net:
 *             one banded Cholesky, three right-hand sides (K8c).
 * The record carries nu, nv and the index of phi (the compressor's search,
 * spec 8.9), so the decoder runs exactly one solve.
 *
 * Deviations from the spec, and why:
 *   - holes give boundary samples but no rays (8.3 sends rays half way
 *     across each hole): a hole's corners are mostly flat (a circle of two
 *     arcs), where 5.3 falls back to the face's mean normal, and rays in the
 *     mean plane would pull the surface flat around the hole; the fairing
 *     fills the hole instead (it is trimmed away);
 *   - the inward direction is unit(N(t) x T(t)) from the interpolated
 *     basis normals, not perp(A(t), T(t)): see loop_samples in cm_nfill.c;
 *   - data parameters are the start values of 8.6 ((x-X0)/(X1-X0),
 *     (y-Y0)/(Y1-Y0)): for NFILL without G1 sides 8.6 says they are the
 *     answer up to rounding, and skipping the Newton keeps them exact.
 *
 * Contract: pure function of its inputs; no heap, no VLA, no recursion;
 * + - * / sqrt and comparisons in fixed orders (spec §2 rules 3-4), so
 * the encoder and every decoder build bit-identical nets.  Every buffer is
 * sized by fixedcfg (CM_MAX_FIT_CTRL, CM_MAX_LSQ_UNKNOWNS, CM_MAX_LSQ_BAND).
 */
#ifndef CM_NFILL_H
#define CM_NFILL_H

#include <stdint.h>

#include "cm/cm_bspline.h"
#include "cm/cm_error.h"
#include "cm/cm_format.h"
#include "cm/cm_geom.h"
#include "cm/cm_gregface.h"
#include "cm/cm_lsq.h"
#include "cm/cm_vec.h"
#include "cm_limits.h"

/** Ray subdivisions (spec §3 RAY_SUB): samples at 1/4, 2/4, 3/4 of each ray. */
#define CM_NFILL_RAY_SUB 4
/** Edges of the outer loop NFILL takes (format rule; the loop input's capacity). */
#define CM_NFILL_MAX_EDGES CM_GREG_MAX_INPUT
/** Edges of all its loops (format rule: the spec's MAX_FACE_EDGES, 64, or the build's if smaller). */
#define CM_NFILL_FMT_ALL_EDGES 64
#if CM_MAX_FACE_EDGES < CM_NFILL_FMT_ALL_EDGES
#  define CM_NFILL_MAX_ALL_EDGES CM_MAX_FACE_EDGES
#else
#  define CM_NFILL_MAX_ALL_EDGES CM_NFILL_FMT_ALL_EDGES
#endif
/** Holes (inner loops) of one face: at most one per edge of it. */
#define CM_NFILL_MAX_HOLES (CM_NFILL_MAX_ALL_EDGES - 1)
/** Boundary samples of one face, all loops (spec §3 MAX_BSAMP). */
#define CM_NFILL_MAX_BSAMP (CM_NFILL_MAX_ALL_EDGES * CM_FMT_SEG_PER_EDGE)

/** The face's inner loops as the caller sampled them (cm_face_samples: CM_FMT_SEG_PER_EDGE per edge,
    spec 8.1): hole l is pts[start[l] .. start[l+1]). */
typedef struct cm_nfill_holes {
    int n;
    int start[CM_NFILL_MAX_HOLES + 1];
    const cm_vec3 *pts;
} cm_nfill_holes;
/** Control points per direction the record can name: 4 + a 5-bit field. */
#define CM_NFILL_MIN_CTRL 4
#define CM_NFILL_MAX_CTRL_FIELD 35
/** Fairing weights the record's 3-bit index names (spec 8.7): phi = cm_nfill_phi[index]. */
#define CM_NFILL_PHI_COUNT 5
extern const double cm_nfill_phi[CM_NFILL_PHI_COUNT];

/** The rebuilt surface: a clamped uniform bicubic B-spline, net row-major in u (ctrl[i*nv + j]). */
typedef struct cm_nfill_surface {
    int nu, nv;
    double U[CM_MAX_FIT_CTRL + 4], V[CM_MAX_FIT_CTRL + 4];
    cm_vec3 ctrl[CM_MAX_FIT_CTRL * CM_MAX_FIT_CTRL];
    cm_surf surf; /* the view of the above (p = q = 3, w = NULL) */
} cm_nfill_surface;

/** Scratch of one build: samples, rays' ends, hits, the side fits and the normal equations. */
typedef struct cm_nfill_ws {
    cm_vec3 p[CM_NFILL_MAX_BSAMP];   /* boundary samples (local), outer loop first */
    int loop_start[CM_NFILL_MAX_HOLES + 2]; /* loop l's samples: p[loop_start[l] .. loop_start[l+1]) */
    cm_vec3 d[CM_NFILL_MAX_BSAMP];   /* unit inward directions (local) */
    double lam[CM_NFILL_MAX_BSAMP];  /* each ray's end (0: no ray) */
    cm_vec3 hit[CM_NFILL_MAX_BSAMP]; /* hit points ... */
    double hit_t[CM_NFILL_MAX_BSAMP]; /* ... their side parameter ... */
    int8_t hit_side[CM_NFILL_MAX_BSAMP]; /* ... and side (-1: none) */
    cm_vec3 q[CM_NFILL_MAX_BSAMP];   /* one side's hits, sorted */
    double t[CM_NFILL_MAX_BSAMP];
    cm_vec3 first[4][CM_MAX_FIT_CTRL]; /* free-end fit of each side (8.4 step 1) */
    int nfirst[4];
    double tmin[4], tmax[4];
    double knots[CM_MAX_FIT_CTRL + 4];
    cm_fit_curve_ws fit;
    double band[CM_MAX_LSQ_UNKNOWNS * (CM_MAX_LSQ_BAND + 1)];
    cm_vec3 rhs[CM_MAX_LSQ_UNKNOWNS];
} cm_nfill_ws;

/** The normal equations of a net's free points: those at least `margin` rows from its border (the
    rest are fixed: ctrl), banded with half bandwidth w; shared by NFILL and G1FIT. */
typedef struct cm_net_lsq {
    int nu, nv, margin, w;
    double *band;
    cm_vec3 *rhs;
    const cm_vec3 *ctrl; /* row-major in u: ctrl[i * nv + j] */
} cm_net_lsq;

/** The unknown number of net point (i, j), -1 when it is fixed. */
int cm_net_unknown(const cm_net_lsq *L, int i, int j);

/** Add weight * (sum_t c_t P_t - Q)^2 (pts[t] = i * nv + j; Q NULL: 0) to the normal equations; fixed
    points go to the right-hand side. */
void cm_net_accumulate(cm_net_lsq *L, const int *pts, const double *c, int np, double weight, const cm_vec3 *Q);

/** lf times the net's thin-plate energy (spec 8.7: every stencil inside the net, row-major, second
    differences in u, in v, then 2 lf times the twist). */
void cm_net_fairing(cm_net_lsq *L, double lf);

/**
 * Spec §8 for the outer loop `in` (cm_greg_input_build with exact = 1: edges, rev, basis normals)
 * and the holes (NULL: none).
 * @param nu, nv  control points per direction, CM_NFILL_MIN_CTRL..CM_MAX_FIT_CTRL
 * @param phi     index into cm_nfill_phi
 * @param frame   out: the K11 frame the surface was built in (its ez is the face normal)
 * @return CM_E_LIMIT over fixedcfg's limits, CM_E_DEGENERATE when a side of the rectangle gets fewer
 *         than 4 hits or the loop is degenerate, CM_E_SINGULAR when the solve fails
 */
CM_NODISCARD cm_err cm_nfill_build(const cm_greg_input *in, const cm_nfill_holes *holes, int nu, int nv, int phi,
                                   cm_frame *frame, cm_nfill_surface *out, cm_nfill_ws *ws, cm_status *st);

/** s->surf made the view of s's net (bicubic, non-rational). */
void cm_nfill_surface_view(cm_nfill_surface *s);

/** FNV-1a 32 over the net's doubles x, y, z in row-major order, each as its IEEE-754 bytes, least
    significant first (spec §2 rule 6). */
uint32_t cm_nfill_checksum(const cm_nfill_surface *s);

#endif /* CM_NFILL_H */
