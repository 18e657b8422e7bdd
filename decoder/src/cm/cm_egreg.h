/*
 * cm_egreg.h - the Gregory patch over exact boundaries (method GREGORY-EXACT,
 * docs/METHODS.md): a four-sided patch whose sides are the curve mesh's own
 * edges (or parts of them, or cubics inside the face), not cubic stand-ins.
 *
 * Why: the bicubic Gregory patch (cm_gregory.h, spec §6) needs every edge to
 * be one cubic within a quarter of the tolerance (K7).  Real models are full
 * of full and half circles and multi-span B-spline edges: 11314 of 12152
 * kept faces of a corpus run were kept for that reason alone (issue 13).
 * This patch interpolates the edges exactly, so no edge blocks it, and it
 * reproduces a surface that is linear in one direction (cylinder, cone
 * band, extrusion between two arcs and two lines) exactly.
 *
 * The surface is Gregory's compatibility-corrected Coons patch (J. A.
 * Gregory, "Smooth interpolation without twist constraints", 1974) with
 * cubic Hermite blending:
 *
 *   S = P_u S + P_v S - P_u P_v S
 *   P_u S = H0(u) a0(v) + H1(u) s0(v) + H2(u) s1(v) + H3(u) a1(v)
 *   P_v S = H0(v) b0(u) + H1(v) t0(u) + H2(v) t2(u) + H3(v) b2(u)
 *   P_u P_v S = sum_ij H_i(u) H_j(v) M_ij
 *
 * with H0 = 1-3s^2+2s^3, H1 = s-2s^2+s^3, H2 = s^3-s^2, H3 = 3s^2-2s^3, the
 * boundaries a0 = S(0,.), a1 = S(1,.), b0 = S(.,0), b2 = S(.,1), the cross
 * derivatives s0 = S_u(0,.), s1 = S_u(1,.), t0 = S_v(.,0), t2 = S_v(.,1),
 * and in M the corners' points, the cross derivatives at the corners (so
 * that the boundary points are interpolated exactly even where a cross
 * derivative does not quite match its neighbour side's tangent) and the
 * rational twists, e.g. at (0,0): (u s0'(0) + v t0'(0)) / (u + v), whose
 * value follows the side being approached.
 *
 * Sides are given in the loop order of cm_gregory (side 0 v=0 along +u,
 * side 1 u=1 along +v, side 2 v=1 along -u, side 3 u=0 along -v).  Each side
 * carries its cross-boundary derivative into the patch, per unit of its own
 * parameter s in [0,1]: X(s) = k(s) A(s) + h(s) B'(s) with k, h, A linear
 * (spec 6.2 with the exact tangent B' instead of the cubic's), so two
 * faces of an edge that use opposite bases have cross derivatives in the
 * same plane span(A(s), B'(s)) and meet G1; or, on a side collapsed into
 * a vertex, an explicit cubic (Bezier) cross derivative (the fan of 6.5).
 * A CHAIN side is several edges end to end (a quad side split at a
 * T-vertex): A(s) is then linear on each edge, from that edge's own basis,
 * while k and h stay linear over the whole side.
 *
 * The turning basis (format 2.6): the exact edges turn, which the papers'
 * cubic edges barely do.  Along a flat face's half circle B'(1) = -B'(0),
 * so A_e = -A_s and the linear A passes through zero at the middle: the
 * patch is singular there (Pieza1: the G1 check read 70-90 degrees at 54
 * mid-edge samples; a cross derivative fell from 0.285 to 0.000138 between
 * s = 0.4 and 0.5).  So a side along an edge whose end bases turn by more
 * than a right angle (A_s.A_e < 0) takes, from format 2.6 on:
 *  - on a plane curve (normal P), the normals carried along it without
 *    twist (rotation-minimising: each end normal N = alpha P + beta m with
 *    m = P x t keeps its alpha and beta as t turns) and blended:
 *    A = unit(alpha(s) m(s) - beta(s) P), alpha, beta linear between the
 *    ends' (CM_EGREG_TURN_PLANE).  Exact on a surface of revolution about
 *    the circle's axis (a dome's rim), a flat face's arc (A = m) and a half
 *    cylinder's (A = the axis);
 *  - on a space curve, where the end normals agree better than the bases
 *    (N_s.N_e > A_s.A_e): A = unit(N(s) x B'(s)), N(s) blended linearly
 *    from N_s to N_e (CM_EGREG_TURN_BLEND).
 * Either A is square to the edge at every s and of unit length.  Both faces
 * of an edge make the same choice from the same edge and normals (equal up
 * to one sign), so they still share span(A(s), B'(s)) and meet G1.  Edges
 * that turn less keep the linear basis, which is what a cubic GREGORY face
 * beside them has.  Sides inside the face (the N-split's cubics) keep it too.
 *
 * Contract: pure functions of their inputs; no heap, no VLA, no recursion;
 * + - * / and comparisons only, fixed orders (spec §2 rules 3-4).
 */
#ifndef CM_EGREG_H
#define CM_EGREG_H

#include <stdint.h>

#include "cm/cm_bezier.h"
#include "cm/cm_bspline.h"
#include "cm/cm_error.h"
#include "cm/cm_vec.h"
#include "cm_limits.h"

enum { CM_EGREG_SIDE_EDGE = 0, CM_EGREG_SIDE_CUBIC = 1, CM_EGREG_SIDE_CHAIN = 2 };

/** Edges one side of a patch may join (layout 3, format 2.3): a side of a quad split by up to 3
    T-vertices (a profile of four sides never joins any: its decoder state does not pay for it). */
#if CM_MAX_SIDES >= 5
#  define CM_EGREG_MAX_PIECES 4 /* = CM_GREG_JOINED_MAX_PIECES (cm_gregface.h) */
#else
#  define CM_EGREG_MAX_PIECES 1
#endif

enum { CM_EGREG_TURN_NONE = 0, CM_EGREG_TURN_BLEND = 1, CM_EGREG_TURN_PLANE = 2 };

/** The turning basis of a side along an edge (or of a chain's edge), over the fraction r of it. */
typedef struct cm_egreg_turn {
    int mode;               /* CM_EGREG_TURN_*: NONE, the linear basis of spec 5.4 */
    union {                 /* (one or the other: a board's decoder state holds a few hundred) */
        struct {
            cm_vec3 N0, N1; /* BLEND: the normals at r = 0 and 1 */
        };
        struct {
            cm_vec3 P;      /* PLANE: the curve's plane normal */
            double a0, a1, b0, b1; /* PLANE: alpha and beta at r = 0 and 1 */
        };
    };
} cm_egreg_turn;

/**
 * One edge of a CHAIN side: on [s0, s1] of the side, B(s) = curve(t0 + (t1 - t0) (s - s0) / (s1 - s0)),
 * with its own linear cross basis from As (at s0) to Ae (at s1): the basis of that edge alone
 * (spec 5.4), so a neighbour across it that uses the whole edge sees the same tangent planes.
 */
typedef struct cm_egreg_piece {
    cm_curve curve;
    uint32_t edge;
    double t0, t1, s0, s1;
    cm_vec3 As, Ae;
    cm_egreg_turn tb;   /* its turning basis (mode 0: the linear one from As to Ae) */
} cm_egreg_piece;

/** One side of an exact-boundary patch. */
typedef struct cm_egreg_side {
    int kind;           /* CM_EGREG_SIDE_* */
    int npiece;         /* CHAIN: 2..CM_EGREG_MAX_PIECES edges in piece[] (As, Ae below: the first's
                           start and the last's end, as the corner fits see them) */
    cm_egreg_piece piece[CM_EGREG_MAX_PIECES];
    uint32_t edge;      /* EDGE: the model edge (checksum only) */
    double t0, t1;      /* EDGE: B(s) = curve(t0 + (t1 - t0) s); t1 < t0 runs it backwards */
    union {
        cm_curve curve; /* EDGE: its curve, points into the model */
        cm_cubic cub;   /* CUBIC: B(s) = cub(s) */
    };
    int fan;            /* 1: X(s) is the Bezier cubic fx[] (a collapsed side), not the basis form */
    cm_vec3 As, Ae;     /* cross basis at s = 0 and 1, into the patch */
    cm_egreg_turn tb;   /* EDGE: its turning basis over s (CHAIN: each piece's own) */
    double k0, h0, k1, h1; /* k(s) = k0 + (k1-k0)s, h(s) likewise */
    cm_vec3 fx[4];
} cm_egreg_side;

/** A patch on [0,1]^2; corner data are filled by cm_egreg_finish(). */
typedef struct cm_egreg {
    cm_egreg_side side[4];
    cm_vec3 M[4][4];       /* corner data (positions, cross derivatives); the twists' places unused */
    cm_vec3 tw_a[2][2];    /* twist at corner (u=a, v=b) along the u-side: s_a'(b) */
    cm_vec3 tw_b[2][2];    /* twist at corner (a, b) along the v-side: t_b'(a) */
} cm_egreg;

/**
 * The turning basis for the EDGE side sd (its curve and range set; sd->As, sd->Ae its end bases
 * from the normals Ns, Ne): mode NONE when the bases turn by a right angle or less, else PLANE on a
 * plane curve (within 1e-3 of its chord), else BLEND where Ns.Ne > As.Ae, else NONE.  Curve errors
 * pass through.
 */
CM_NODISCARD cm_err cm_egreg_choose_turn(const cm_egreg_side *sd, cm_vec3 Ns, cm_vec3 Ne, cm_egreg_turn *tb,
                                         cm_status *st);

/** The cross basis A of an EDGE or CHAIN side at s: linear, or its turning basis (clamped to [0,1]). */
CM_NODISCARD cm_err cm_egreg_side_basis(const cm_egreg_side *sd, double s, cm_vec3 *A, cm_status *st);

/** The turning basis tb restricted to the fraction [r0, r1] of its edge (an N-split's half edge). */
cm_egreg_turn cm_egreg_turn_part(const cm_egreg_turn *tb, double r0, double r1);


/**
 * Side at s (clamped to [0,1]): d[0] = B, d[1] = B', d[2] = B'' (per unit s),
 * x[0] = X, x[1] = X' (either array may be NULL).
 */
CM_NODISCARD cm_err cm_egreg_side_eval(const cm_egreg_side *sd, double s, cm_vec3 d[3], cm_vec3 x[2], cm_status *st);

/** Fill the corner data M, tw_a, tw_b from the four sides (after their cross derivatives are set). */
CM_NODISCARD cm_err cm_egreg_finish(cm_egreg *g, cm_status *st);

/**
 * Point and first partials at (u,v), clamped to [0,1]^2 (Su, Sv may be NULL).
 * CM_E_NONFINITE if the result is not finite; curve errors pass through.
 */
CM_NODISCARD cm_err cm_egreg_eval(const cm_egreg *g, double u, double v, cm_vec3 *S, cm_vec3 *Su, cm_vec3 *Sv,
                                  cm_status *st);

/*
 * A memo of one patch's side evaluations.  A point of the patch costs its four sides (each an exact
 * edge's point with two derivatives and its cross derivative: about 500 instructions), and the
 * tessellation asks for the same side parameters again and again: a grid's rows and columns share
 * them, and a refinement's points fall on the same parameters (a side's evaluations repeat 46 % to
 * 74 % of the time over the corpus models' GREGORY-EXACT faces, as1_pe_203's 68 %).  Each side keeps
 * its last CM_EGREG_MEMO results, placed by a hash of s; the same s gives the same bits as
 * cm_egreg_side_eval (a pure function of its side and s), so nothing the decoder outputs changes.
 * Valid for one patch: cm_egreg_memo_reset before another (or the same one rebuilt).
 */
#ifndef CM_EGREG_MEMO_BITS
#  define CM_EGREG_MEMO_BITS 5 /* 2^5 entries per side: 17 KB in all, in the tessellation's workspace (4 bits
                                  gave 1 % more instructions on as1_pe_203, 6 did not fit the terminal's budget) */
#endif
#define CM_EGREG_MEMO (1 << CM_EGREG_MEMO_BITS) /* a profile's 0: one entry a side, the last s */
typedef struct cm_egreg_memo_entry {
    double s;
    uint32_t gen; /* the memo's generation it was written in (0: never) */
    cm_vec3 d[3], x[2];
} cm_egreg_memo_entry;
typedef struct cm_egreg_memo {
    uint32_t gen;
    cm_egreg_memo_entry e[4][CM_EGREG_MEMO];
} cm_egreg_memo;

/** Forget every entry (a new patch). */
void cm_egreg_memo_reset(cm_egreg_memo *m);

/** The entry of a side that s takes: a hash of its bits (the tiny profile: the one entry). */
int cm_egreg_memo_slot(double s);

/** cm_egreg_eval with its side evaluations through memo (NULL: none); the same bits as without. */
CM_NODISCARD cm_err cm_egreg_eval_memo(const cm_egreg *g, double u, double v, cm_vec3 *S, cm_vec3 *Su, cm_vec3 *Sv,
                                       cm_egreg_memo *memo, cm_status *st);

#endif /* CM_EGREG_H */
