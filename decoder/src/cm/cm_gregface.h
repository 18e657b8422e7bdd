/*
 * cm_gregface.h - the GREGORY method's surface construction (spec §5.4,
 * §6.2-§6.5): from a face's outer loop of cubic edges and the basis
 * normals at their ends, 1..CM_MAX_GREG bicubic Gregory patches that
 * interpolate the loop with the cross-boundary tangent planes of §5.4.
 *
 * Contract: pure functions of their explicit inputs; no heap, no VLA, no
 * recursion, no I/O; only + - * / sqrt fabs and comparisons, fixed loop
 * orders (spec §2 rules 3-4), so encoder and decoder rebuild bit-identical
 * surfaces under -ffp-contract=off.  Over-limit counts return CM_E_LIMIT.
 *
 * ---- patch layouts (what the tessellator needs) ----------------------
 * Every patch is a cm_gregory on [0,1]^2; P[i][j] has i along u, j along v.
 * "side k" is in->side[k] (E_k: V_k -> V_{k+1}, indices mod n).
 *
 * layout 0 (QUAD, n = 4, npatch = 1), spec §6.3:
 *     S(u,0) = E_0(u)      S(1,v) = E_1(v)
 *     S(u,1) = E_2(1-u)    S(0,v) = E_3(1-v)
 *   corners (0,0)=V_0, (1,0)=V_1, (1,1)=V_2, (0,1)=V_3.
 *
 * layout 2 (DEGEN, n = 3, npatch = 1, vertex j), spec §6.5: the loop is
 *   re-indexed so that it starts at V_j; with E'_m = side (j+m) mod 3:
 *     S(u,0) = E'_0(u)     S(1,v) = E'_1(v)
 *     S(u,1) = E'_2(1-u)   S(0,v) = V_j for every v (collapsed side)
 *   corners (0,0)=(0,1)=V_j, (1,0)=V_{j+1}, (1,1)=V_{j+2}.
 *
 * layout 1 (SPLIT, n = 3..CM_MAX_SIDES, npatch = n), spec §6.4: E_k is split
 *   at t = CM_GREG_SPLIT_T (= 1/2) into H_k^a (V_k -> M_k) and H_k^b
 *   (M_k -> V_{k+1}); inner[k] = I_k runs M_k -> C (C = centre).
 *   Patch k is the quad around V_k, loop [H_k^a, I_k, rev(I_{k-1}), H_{k-1}^b]:
 *     S_k(u,0) = H_k^a(u)     = E_k(u/2)
 *     S_k(1,v) = I_k(v)
 *     S_k(u,1) = I_{k-1}(u)                   (I_{k-1} in its own direction)
 *     S_k(0,v) = H_{k-1}^b(1-v) = E_{k-1}(1 - v/2)
 *   corners (0,0)=V_k, (1,0)=M_k, (1,1)=C, (0,1)=M_{k-1}.
 *   So the point E_k(t) lies on patch k at (2t, 0) for t <= 1/2 and on
 *   patch k+1 at (0, 2-2t) for t >= 1/2 (power-of-two scalings: the
 *   parameter maps are exact), and the internal curve I_k(t) is patch k at
 *   (1,t) and patch k+1 at (t,1): sample inner[k] once and use it for both.
 *   The patch boundaries equal these curves up to rounding only (the halves
 *   are de Casteljau splits): a tessellator that must not crack samples the
 *   edge curves and inner[] themselves, and maps parameters as above.
 *
 * layout 3 (JOINED, n = 5..CM_GREG_JOINED_MAX_EDGES, at most
 *   CM_GREG_JOINED_MAX_PIECES edges per side, npatch = 1, exact patches only,
 *   format 2.3): one four-sided patch whose corners are the four loop
 *   vertices V_c0 < V_c1 < V_c2 < V_c3 named by the bits of j (bit k: V_k);
 *   the others are T-vertices inside a side, whose edges are joined into a
 *   CHAIN side (cm_egreg.h).  Side m runs V_cm -> V_c(m+1) (indices mod 4)
 *   in layout 0's places: side 0 v=0, side 1 u=1, side 2 v=1 backwards, side
 *   3 u=0 backwards.  The edge of use u, the i-th of its side, covers
 *   [piece[i].s0, piece[i].s1] of that side's parameter, linearly in the
 *   edge's own parameter.  The joints are placed so that the side's speed
 *   is continuous where its edges meet tangentially: a quad one of whose
 *   sides an exporter cut in two (a T-vertex where a neighbour's edge ends)
 *   is rebuilt as the quad it is, not as an N-split pentagon.
 *
 * ---- checksum (spec §2 rule 6) ----------------------------------------
 * FNV-1a 32 over the bytes of the doubles x, y, z of, for patch
 * k = 0..npatch-1 in turn: the 12 boundary points P[i][j] (i = 0..3 outer,
 * j = 0..3 inner, skipping i,j both in {1,2}), then the 8 interior points
 * I[a][b][c] (a, b, c = 0..1, a outermost).  Each double is serialised as
 * its IEEE-754 bit pattern, least significant byte first, on every host.
 */
#ifndef CM_GREGFACE_H
#define CM_GREGFACE_H

#include <stdint.h>

#include "cm/cm_bezier.h"
#include "cm/cm_bspline.h"
#include "cm/cm_egreg.h"
#include "cm/cm_error.h"
#include "cm/cm_gregory.h"
#include "cm/cm_patchfit.h"
#include "cm/cm_vec.h"
#include "cm_limits.h"

enum { CM_GREG_LAYOUT_QUAD = 0, CM_GREG_LAYOUT_SPLIT = 1, CM_GREG_LAYOUT_DEGEN = 2, CM_GREG_LAYOUT_JOINED = 3 };

/** Layout 3: the patch corners a record names (a bit per loop vertex). */
#define CM_GREG_JOINED_CORNERS 4
/** Layout 3: at most this many edges in the loop, and in one side (format rules, 2.3). */
#define CM_GREG_JOINED_MAX_EDGES 12
#define CM_GREG_JOINED_MAX_PIECES 4

/** The sides cm_greg_input holds: a build that can do layout 3 (CM_MAX_SIDES >= 5) takes its loops
    of up to CM_GREG_JOINED_MAX_EDGES edges; the other layouts stop at CM_MAX_SIDES. */
#if CM_MAX_SIDES >= 5
#  define CM_GREG_MAX_INPUT CM_GREG_JOINED_MAX_EDGES
#else
#  define CM_GREG_MAX_INPUT CM_MAX_SIDES
#endif

/** Layout 1 splits every edge at this parameter (spec 6.4 step 1). */
#define CM_GREG_SPLIT_T 0.5

/* Spec 6.4 step 2: the centroid's position along a median of the regular
 * N-gon for odd N, written as the spec writes them (format constants). */
#define CM_GREG_SPOKE_R3 0.3333333333333334
#define CM_GREG_SPOKE_R5 0.4472135954999579
#define CM_GREG_SPOKE_R7 0.47395245819915655

/* A product of two unit vectors shorter than this is "parallel" (dimensionless). */
#define CM_GREG_EPS_DIR 1e-12

/*
 * One side of the face's outer loop, in the face's direction (material on
 * the left when the face normal points at the viewer); side k runs
 * V_k -> V_{k+1}.
 */
typedef struct cm_greg_side {
    cm_cubic c;     /* the K7 cubic of the edge, in face direction (zero when not asked for) */
    cm_curve curve; /* the edge's own curve (into the model) in its stored direction */
    uint32_t edge;  /* its number */
    int rev;        /* 1: the face runs it from t = 1 to t = 0 */
    cm_vec3 Ns, Ne; /* basis normals at its start and end vertex (spec 5.4; the caller applies the G1 symmetric rule) */
} cm_greg_side;

typedef struct cm_greg_input {
    int n;                               /* number of sides, 3..CM_MAX_SIDES (layout 3: edges, 5..CM_GREG_MAX_INPUT) */
    cm_greg_side side[CM_GREG_MAX_INPUT];
    cm_vec3 corner_normal[CM_GREG_MAX_INPUT]; /* N(F, V_k) of spec 5.3 at V_k (start of side k); odd-N spoke rule */
    cm_vec3 nF;                          /* face reference normal n_F (unit) */
    double eps_len;                      /* spec EPS_LEN: lengths <= this are zero */
    int turning;                         /* exact sides: the turning basis (cm_egreg.h; format 2.6) */
} cm_greg_input;

/*
 * The rebuilt surface (layouts: see the top of this file).  Patches
 * g[npatch..CM_MAX_GREG-1] are never read (cm_greg_surface_reset clears
 * only the patches a layout can use); the unused P[1..2][1..2] of every
 * patch are zero.  inner/centre are set for layout 1 only (zero otherwise).
 */
typedef struct cm_greg_surface {
    int layout;                  /* CM_GREG_LAYOUT_* */
    int j;                       /* layout 2: the collapsed vertex V_j (original index); layout 3: the
                                    corner bits; else 0 */
    int n;                       /* sides of the face */
    int npatch;                  /* 1 (layouts 0, 2) or n (layout 1) */
    double t_split;              /* layout 1: CM_GREG_SPLIT_T; else 0 */
    int exact;                   /* 1: the patches are e[] (cm_egreg_build), 0: g[] (cm_greg_build) */
    union {                      /* one or the other: a board's decoder state holds one surface */
        cm_gregory g[CM_MAX_GREG];
        cm_egreg e[CM_MAX_GREG]; /* exact: the patches over the edges themselves (same layouts) */
    };
    cm_cubic inner[CM_MAX_SIDES]; /* layout 1: I_k, M_k -> C (inner[k].c[0] = M_k) */
    cm_vec3 centre;              /* layout 1: C */
    cm_vec3 centre_normal;       /* layout 1: n_C (spec 6.4 step 2) */
    /* GREGORY-FIT: fit coefficients per direction of each patch's interior correction (0: none) and
       the coefficients, patch k's corr[k][i*fit + j] (cm_patchfit.h); evaluation adds them */
    int fit;
    cm_vec3 corr[CM_MAX_GREG][CM_FIT_MAX_COEF];
} cm_greg_surface;

/*
 * A side of a 4-sided patch given by its basis vectors directly (spec 6.4
 * step 4 uses this for sub-patches; 6.3 derives A_s, A_e from normals).
 */
typedef struct cm_greg_quad_side {
    cm_cubic c;     /* in the patch loop's direction */
    cm_vec3 As, Ae; /* cross-boundary basis at the start and the end, pointing into the patch */
} cm_greg_quad_side;

/**
 * Spec 5.4 basis vectors of one edge use: A_s = unit(N_s x ĉ_s),
 * A_e = unit(N_e x ĉ_e), with ĉ the unit end tangents of the cubic (c0 at
 * the start, c2 at the end; if that control vector is <= eps_len long,
 * c1 instead).
 * @return CM_E_DEGENERATE if a tangent is still zero or N is parallel to it
 */
CM_NODISCARD cm_err cm_greg_edge_basis(const cm_cubic *c, cm_vec3 Ns, cm_vec3 Ne, double eps_len, cm_vec3 *As,
                                       cm_vec3 *Ae, cm_status *st);

/**
 * Spec 6.2: the inner control points X1 = C1 + b1, X2 = C2 + b2 of the
 * cross-boundary derivative k(t)A(t) + h(t)c(t) along cubic c, with
 * A(t) = (1-t)As + t Ae, fitted to the corner vectors b0 (at C0) and b3
 * (at C3).  A corner vector <= eps_len long gives k = h = 0 at that end;
 * a control vector c0 (c2) <= eps_len long gives h = 0 and k = A.b/|A|^2
 * there (the 2x2 system is rank one).
 * @param[out] kh  k0, h0, k1, h1 (may be NULL)
 * @return CM_E_DEGENERATE when |A|^2|c|^2 - (A.c)^2 < 1e-20 |A|^2 |c|^2
 *         (the edge is tangent to its basis vector: "method fails")
 */
CM_NODISCARD cm_err cm_greg_cross(const cm_cubic *c, cm_vec3 As, cm_vec3 Ae, cm_vec3 b0, cm_vec3 b3, double eps_len,
                                  cm_vec3 *X1, cm_vec3 *X2, double kh[4], cm_status *st);

/**
 * The 4-sided Gregory patch of spec 6.3 for the loop s[0..3] with the given
 * bases: boundary P from the cubics (side 0 v=0, 1 u=1, 2 v=1 reversed,
 * 3 u=0 reversed; where loop ends disagree, the later side in that order
 * wins), corner vectors from the neighbouring sides, interior pairs by
 * cm_greg_cross.  No orientation check (see cm_greg_build).
 * @param skip_side3  1: leave side 3's pair (I[0][*][1]) untouched (layout 2 fills it)
 */
CM_NODISCARD cm_err cm_greg_quad(const cm_greg_quad_side s[4], int skip_side3, double eps_len, cm_gregory *g,
                                 cm_status *st);

/**
 * (k,h) = argmin |b - k A - h c|^2 (spec 6.2): b <= eps_len long gives k = h = 0; c <= eps_len long
 * gives h = 0, k = A.b/|A|^2.  CM_E_DEGENERATE for a zero A or c (nearly) along A.
 */
CM_NODISCARD cm_err cm_greg_fit_kh(cm_vec3 A, cm_vec3 c, cm_vec3 b, double eps_len, double *k, double *h,
                                   cm_status *st);

/**
 * Spec 6.4 steps 2-3, shared by both constructions: the centre C (spoke rule) and its normal n_C
 * into out->centre and out->centre_normal, the internal cubics I_k into out->inner, and U_k.
 * M[k]: the midpoint of side k; T[k], nmid[k]: the unit mid cross vector and mid normal; V[k]: the
 * start vertex of side k; corner_normal[k]: N(F, V_k).
 */
CM_NODISCARD cm_err cm_greg_spoke_centre(int n, const cm_vec3 *M, const cm_vec3 *T, const cm_vec3 *nmid,
                                         const cm_vec3 *V, const cm_vec3 *corner_normal, double eps,
                                         cm_vec3 *U, cm_greg_surface *out, cm_status *st);

/**
 * What both constructions do first: *out zeroed but for layout, n, j and exact; the arguments and
 * the layout checked as cm_greg_build() documents (return codes as there; `exact` 1: the cubics
 * are not looked at).
 */
CM_NODISCARD cm_err cm_greg_begin(const cm_greg_input *in, int layout, int j, int exact, cm_greg_surface *out,
                                  cm_status *st);

/**
 * Layout 3's corner bits for a loop of n edges: exactly CM_GREG_JOINED_CORNERS of them, none at or
 * above bit n, no side of more than CM_GREG_JOINED_MAX_PIECES edges, 5 <= n <=
 * CM_GREG_JOINED_MAX_EDGES.  1 when they are.
 */
int cm_greg_joined_ok(unsigned bits, int n);

/** *out zeroed but for layout, n, j (layout 2 only) and exact: what a failed construction leaves. */
void cm_greg_surface_reset(cm_greg_surface *out, int layout, int n, int j, int exact);

/**
 * Spec 6.5's circular fan at a collapsed vertex: from the edge vectors e0 and e2 leaving it, the
 * inner vectors f1, f2 (linear when e0, e2 are within 1e-12 of parallel).  CM_E_DEGENERATE for an
 * edge vector <= eps long or a flat collapsed corner.
 */
CM_NODISCARD cm_err cm_greg_fan(cm_vec3 e0, cm_vec3 e2, double eps, cm_vec3 *f1, cm_vec3 *f2, cm_status *st);

/**
 * The same layouts over the exact edges (cm_egreg.h): sides from in->side[k].curve/edge/rev, the
 * basis normals Ns, Ne, the corner normals and nF as for cm_greg_build (the cubics are not used).
 * Same return codes as cm_greg_build.
 */
CM_NODISCARD cm_err cm_egreg_build(const cm_greg_input *in, int layout, int j, cm_greg_surface *out,
                                   cm_status *st);

/** arc_handle of spec 6.4: (2/3)|Q-P| / (1 + sqrt((1 + clamp(t0.t1,-1,1))/2)). */
double cm_greg_arc_handle(cm_vec3 P, cm_vec3 t0, cm_vec3 Q, cm_vec3 t1);

/**
 * Build the surface of spec §6 for the given layout (and j for layout 2).
 * Each patch must pass the orientation check of 6.3: (Su x Sv)(1/2,1/2) . nF > 0.
 * @return CM_OK;
 *         CM_E_ARG for NULL pointers or a negative / non-finite eps_len;
 *         CM_E_NONFINITE for NaN or infinity in the input;
 *         CM_E_LIMIT when n > CM_MAX_SIDES, or layout 1 needs n > CM_MAX_GREG patches;
 *         CM_E_RANGE for n < 3, an unknown layout, layout 0 with n != 4,
 *                    layout 2 with n != 3 or j outside 0..2;
 *         CM_E_DEGENERATE when the construction fails as the spec says (zero
 *                    tangents, basis parallel to the edge, short projections,
 *                    |M_k - C| <= eps_len, the orientation check).
 *         On failure *out is zeroed except layout/n/j.
 */
CM_NODISCARD cm_err cm_greg_build(const cm_greg_input *in, int layout, int j, cm_greg_surface *out, cm_status *st);

/**
 * Nearest point of the surface to p (spec K9 per patch: best of a 17x17
 * grid, then Levenberg-Marquardt with clamping, cm_patch_project), minimum
 * over patches 0..npatch-1 (the first patch wins a tie).
 * @param[out] patch, u, v  foot point (any may be NULL); -1, 0, 0 if npatch == 0
 * @return the distance; HUGE_VAL if there is no patch
 */
double cm_greg_surface_project(const cm_greg_surface *s, cm_vec3 p, int *patch, double *u, double *v);

/** Evaluate patch k at (u,v) (clamped to [0,1]^2): point and first partials (Su, Sv may be NULL).
 *  A k outside 0..npatch-1 gives zero vectors; an exact patch may fail (CM_E_NONFINITE, curve errors;
 *  the vectors are then zero too). */
cm_err cm_greg_surface_eval(const cm_greg_surface *s, int k, double u, double v, cm_vec3 *S, cm_vec3 *Su, cm_vec3 *Sv);
/** cm_greg_surface_eval with an exact patch's side evaluations through memo (cm_egreg_eval_memo; NULL:
    none; reset it when k or s changes); the same bits as without. */
cm_err cm_greg_surface_eval_memo(const cm_greg_surface *s, int k, double u, double v, cm_vec3 *S, cm_vec3 *Su,
                                 cm_vec3 *Sv, cm_egreg_memo *memo);

/** FNV-1a 32 of the rebuilt control data (order: top of this file; spec §2 rule 6). */
uint32_t cm_greg_surface_checksum(const cm_greg_surface *s);

/** 1 if an exact patch of s has a side (or a chain's edge) on the turning basis (cm_egreg.h): the
    surface then needs a file of format 2.6; 0 for cubic patches. */
int cm_greg_surface_turns(const cm_greg_surface *s);

#endif /* CM_GREGFACE_H */
