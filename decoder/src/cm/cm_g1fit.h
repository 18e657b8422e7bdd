/*
 * cm_g1fit.h - method G1FIT's surface (spec §9, Muraki's fitting that keeps
 * G1 with the neighbours): a bicubic B-spline whose four borders are the
 * face's own edges, whose second row of control points lies in the tangent
 * planes along them, and whose interior is faired.
 *
 * Pipeline, all from the curve mesh (no frame, no rays):
 *   corners   the face's four sharpest corners (all of them on a four-sided
 *             face; on 5..12 sides the four that turn most, ties to the
 *             lower index): they cut the loop into four chains of edges;
 *   sides     each chain sampled CM_FMT_SEG_PER_EDGE times per edge, with
 *             the edge's basis normals (spec 5.4) interpolated along it,
 *             parameterised by chord length and fitted by a clamped cubic
 *             with its ends on the corners (K6): the net's border;
 *   Coons     the bilinearly blended Coons net of the four sides (exact for
 *             ruled faces: a cylinder or cone band between two arcs);
 *   G1 row    every point of the second ring moved into the tangent plane
 *             of its side at its Greville abscissa (spec 9.4 stage 2; two
 *             sides at a corner: both planes, by their 2x2 Gram system);
 *   interior  the Coons points, or (mode 1) the net of least thin-plate
 *             energy with the two outer rings fixed: one banded Cholesky.
 * The record carries nu, nv and the mode (the compressor's search), so the
 * decoder builds exactly one net.
 *
 * Deviations from spec §9, and why (evidence in docs/METHODS.md):
 *   - the parameter domain is the face's own four edge chains, not a
 *     rectangle in the K11 frame with the G1 edges fitted with extensions:
 *     the corpus faces that lose G1 are mostly four-sided bands whose
 *     edges turn by up to half a circle (no height field in any frame, and
 *     the Gregory patch's cubic cross derivative cannot follow them: 50 to
 *     90 degrees off mid-edge on asitus__Pieza1); the chains are sampled,
 *     so arcs and multi-span edges are fine, and G1 edges are exact
 *     boundary curves up to the side fit, as §9 wants;
 *   - every side's second row is restricted, G1 or not: the basis normals
 *     are the curve mesh's best estimate of the tangent plane on any edge
 *     (the Gregory patches use them on every edge too);
 *   - no knots are inserted (9.3): the chains are the sides, so a G1 part
 *     ends at a corner of the net.
 *
 * Contract: pure function of its inputs; no heap, no VLA, no recursion;
 * + - * / sqrt and comparisons in fixed orders (spec §2 rules 3-4), so
 * the encoder and every decoder build bit-identical nets.  Every buffer is
 * sized by fixedcfg (CM_MAX_FIT_CTRL, CM_MAX_LSQ_UNKNOWNS, CM_MAX_LSQ_BAND).
 */
#ifndef CM_G1FIT_H
#define CM_G1FIT_H

#include "cm/cm_nfill.h"

/** Edges of the loop G1FIT takes (format rule: 4..12; the loop input's capacity). */
#define CM_G1FIT_MIN_EDGES 4
#define CM_G1FIT_MAX_EDGES CM_GREG_MAX_INPUT
/** Samples of one chain: CM_FMT_SEG_PER_EDGE per edge and its end. */
#define CM_G1FIT_MAX_CHAIN (CM_G1FIT_MAX_EDGES * CM_FMT_SEG_PER_EDGE + 1)
/** Interiors the record's mode names: 0 the Coons net's, 1 the faired net's. */
#define CM_G1FIT_MODES 2
/** cm_face.fill_phi's bit for a G1FIT face with twists (format 4.2; its bit 0 is the mode). */
#define CM_G1FIT_TWISTED 2u

/** Scratch of one build. */
typedef struct cm_g1fit_ws {
    cm_vec3 p[CM_G1FIT_MAX_CHAIN];     /* one chain's samples ... */
    cm_vec3 N[CM_G1FIT_MAX_CHAIN];     /* ... their unit basis normals ... */
    double t[CM_G1FIT_MAX_CHAIN];      /* ... and chord parameters */
    cm_vec3 side[4][CM_MAX_FIT_CTRL];  /* the four sides' control points (spec 8.5 order) */
    cm_vec3 sn[4][CM_MAX_FIT_CTRL];    /* the tangent-plane normal at each Greville abscissa */
    double knots[CM_MAX_FIT_CTRL + 4];
    cm_fit_curve_ws fit;
    double band[CM_MAX_LSQ_UNKNOWNS * (CM_MAX_LSQ_BAND + 1)];
    cm_vec3 rhs[CM_MAX_LSQ_UNKNOWNS];
} cm_g1fit_ws;

/**
 * The unit normals along side gs at its samples u = j / CM_FMT_SEG_PER_EDGE, j = 0..CM_FMT_SEG_PER_EDGE
 * (face direction): the basis normal at each end (spec 5.4) carried along the edge by a rotation-
 * minimising frame (double reflection: Wang, Juettler, Zheng, Liu 2008), the two carried fields
 * blended linearly.  Not spec 5.4's linear blend of the end normals: along an edge that turns the
 * normal turns with it (half a circle round the end of a slot: N_e = -N_s, and the blend vanishes
 * mid-edge: 30 to 90 degrees off on asitus__Pieza1), which the frame follows exactly on arcs and
 * keeps constant along a plane.  Only + - * / sqrt (spec §2 rule 3).

 * @return CM_E_DEGENERATE where a normal lies along the edge
 */
CM_NODISCARD cm_err cm_g1fit_edge_normals(const cm_greg_side *gs, cm_vec3 *N, cm_status *st);

/**
 * The four corners of loop `in` (cm_greg_input_build with exact = 1), as side indices in increasing
 * order: corner k is the start vertex of side corner[k].
 * @return CM_E_RANGE outside 4..CM_G1FIT_MAX_EDGES sides, CM_E_DEGENERATE on a zero tangent
 */
CM_NODISCARD cm_err cm_g1fit_corners(const cm_greg_input *in, int corner[4], cm_status *st);

/**
 * The surface of the face whose outer loop is `in`.
 * @param nu, nv  control points per direction, CM_NFILL_MIN_CTRL..CM_MAX_FIT_CTRL
 * @param mode    0: Coons interior, 1: faired interior
 * @param twist   NULL, or per side k of the loop 3 points holding the sines s_j (j = 1..9, in x y z
 *                order) by which the carried normal N at the side's inner sample j is turned about
 *                the edge's unit tangent T: sqrt(1 - s^2) N + s unit(T x N) (format 4.2: the
 *                surface's normal twists along an edge where the carried one cannot)
 * @return CM_E_LIMIT over fixedcfg's limits, CM_E_DEGENERATE on a chain of no length,
 *         CM_E_SINGULAR when a fit or the solve fails
 */
CM_NODISCARD cm_err cm_g1fit_build(const cm_greg_input *in, int nu, int nv, int mode, const cm_vec3 *twist,
                                   cm_nfill_surface *out, cm_g1fit_ws *ws, cm_status *st);

#endif /* CM_G1FIT_H */
