/*
 * cm_tess.h - triangulation of a face's trimmed region in its 2D
 * parameter domain: a polygon with holes, plus interior points.
 *
 * This is the heap-free core of tessellation.  The caller (the decoder)
 * samples every edge once, maps the samples into the face's (u,v) domain,
 * adds interior points where the surface curves, and calls
 * cm_triangulate(); the boundary segments come out exactly as given, so two
 * faces sharing an edge share its vertices and the mesh is watertight.
 *
 * Input points, all in one array:
 *   [0, loop_start[1])              loop 0: the outer boundary, counter-clockwise
 *   [loop_start[l], loop_start[l+1]) loop l >= 1: holes, clockwise
 *   [loop_start[nloops], npts)      interior (Steiner) points, any order
 * Each loop is closed implicitly (last point to first).
 *
 * Output: triangles as index triples into the input array, counter-clockwise,
 * covering exactly the region inside the outer loop and outside the holes;
 * every boundary segment is a side of exactly one triangle; interior points
 * that fall outside the region, on the boundary, or within `min_dist` of
 * another point are left unused.  Among valid triangulations the result is
 * Delaunay except across boundary segments (Lawson flips), so triangles are
 * as well shaped as the points allow.
 *
 * Degenerate input, as sampled CAD boundaries produce it once rounded to a
 * grid (tolerances are relative to the boundary's larger extent):
 *   - a point that repeats its predecessor in a loop (within 1e-14, e.g. the
 *     first point repeated at the end) is dropped: it is in no triangle;
 *   - loops that touch at a point: points of different loops within 1e-10
 *     are taken to be at one position (a vertex mapped twice with different
 *     rounding); around such a point a triangle may use either loop's point
 *     (both stand for the same vertex), so there a boundary segment may come
 *     out with the other loop's index at its end;
 *   - collinear boundary points, slivers (aspect 1e-6 and beyond), points
 *     1e-13 apart: handled, every triangle has positive area;
 *   - a loop through one point more than once (lobes touching there), a
 *     vertex on another segment (of its loop or another, within 1e-10), a
 *     hole sharing vertices or a run of segments with the outer loop or
 *     another hole, spikes (a loop running out along a line and back),
 *     slits: triangulated; the only flat triangles are those a vertex lying
 *     on a boundary segment forces: all three corners on that segment, so
 *     that the segment stays a side of a triangle;
 *   - a hole without area (fewer than 3 distinct points, or all on a line)
 *     or outside the outer loop takes nothing away: it is left out, its
 *     points are in no triangle;
 *   - loops that overlap by rounding (up to ~1e-11): triangulated, but a
 *     triangle there may have a tiny negative area (|2 area| < 1e-8 of the
 *     product of two side lengths); a part that the loops go round twice
 *     (touching, not crossing) may come out covered twice;
 *   - a loop given in the wrong orientation is reversed (its segments then
 *     appear reversed in the triangles).
 * The region is that of winding number >= 1 of the loops (the outer one
 * counter-clockwise, the holes clockwise).  Ear clipping triangulates it;
 * where that cannot finish or leaves a flat triangle the input does not
 * force, a constrained Delaunay triangulation of the boundary points does
 * (cm_tess.c).
 *
 * Contract: no allocation, no recursion, no I/O; every loop is bounded by
 * the point count; only + - * /, sqrt, floor and comparisons on doubles
 * (bit-identical on every architecture); stack below CM_STACK_FN_MAX.
 */
#ifndef CM_TESS_H
#define CM_TESS_H

#include "cm/cm_error.h"
#include "cm/cm_vec.h"
#include "cm_limits.h"

/** Nodes of the ear-clipping polygon: every boundary point once, plus two per bridged hole. */
#define CM_TESS_MAX_NODES (2 * CM_MAX_TESS_POINTS)

/**
 * Workspace of cm_triangulate: everything it needs, sized by CM_MAX_TESS_POINTS
 * (about 150 bytes per point: 1.2 MiB for the terminal profile).  Its contents
 * between calls mean nothing.
 */
typedef struct cm_tri_ws {
    cm_vec2 p[CM_MAX_TESS_POINTS + 3];      /* points, scaled by a power of two to an extent of ~1;
                                               the last 3: an enclosing triangle (cm_tess.c fallback) */
    int tri[CM_MAX_TESS_TRIS][3];           /* triangle corners, counter-clockwise */
    int adj[CM_MAX_TESS_TRIS][3];           /* across side i (corner i -> i+1): 3*u + j for side j of
                                               triangle u, -1 if none */
    unsigned char flag[CM_MAX_TESS_TRIS];   /* bit i: side i is fixed (a boundary segment, never
                                               flipped); bit 3+i: side i is in the flip queue */
    int mark[CM_MAX_TESS_TRIS];             /* visit stamps of the near-point search */
    int stack[3 * CM_MAX_TESS_TRIS];        /* flip queue, search queue; sort scratch */
    int cell[CM_MAX_TESS_POINTS];           /* point location grid: a triangle meeting each cell */
    /* ear clipping: the outer loop with the holes bridged in, a ring of nodes */
    int node_pt[CM_TESS_MAX_NODES];         /* the point of node k */
    int next[CM_TESS_MAX_NODES];            /* ring links */
    int prev[CM_TESS_MAX_NODES];
    int side[CM_TESS_MAX_NODES];            /* ring edge k -> next[k]: -1 boundary segment, 3*t + i
                                               the triangle side across it, -2 - w its bridge twin
                                               (the edge w -> next[w]) not yet cut */
    uint32_t zkey[CM_TESS_MAX_NODES];       /* Morton code of the node's position */
    int znext[CM_TESS_MAX_NODES];           /* live nodes in z-order (for the ear tests) */
    int zprev[CM_TESS_MAX_NODES];
    unsigned char nflag[CM_TESS_MAX_NODES]; /* node flags (cm_tess.c) */
    long ear_tests;                         /* ear tests the last call spent (cm_tess.c bounds them by
                                               the ring's length; tests read it) */
    long cdt_work;                          /* the fallback's steps in the last call (flips and fan
                                               walks; bounded likewise) */
    long flips;                             /* Delaunay flips the last call made (tests read it: a
                                               long boundary must not cost a quadratic number) */
    /* what cm_triangulate_more continues from: the last successful call's triangulation */
    struct {
        int valid;                          /* 1 after a successful call, 0 after a failed one */
        int npts, nb, ntri, last;           /* points taken, boundary points, triangles, walk start */
        double scale, ox, oy, box[4];       /* normalise()'s map and the boundary's box */
        int grid, grid_ntri;                /* the location grid's cells per side, and the triangles
                                               it was built for (0: none built) */
        double ghx, ghy;                    /* its cell size */
    } done;
} cm_tri_ws;

/**
 * Triangulate the region.
 * @param pts        npts points (boundary loops first, then interior points)
 * @param loop_start nloops + 1 offsets (loop_start[0] = 0, increasing: no empty loop,
 *                   loop_start[nloops] = boundary count <= npts)
 * @param min_dist   interior points closer than this to a used point or a boundary segment are
 *                   skipped (>= 0; even with 0, points within 1e-10 of the extent are)
 * @param[out] tris  up to cap triangles (may be NULL if cap is 0)
 * @param[out] ntris triangles written (0 on any error)
 * @param[out] nused interior points used (may be NULL)
 * @param ws         workspace (its contents on entry do not matter)
 * @return CM_E_LIMIT if npts > CM_MAX_TESS_POINTS (the limit is named);
 *         CM_E_NOSPACE if cap is too small (st->need: the triangle count);
 *         CM_E_DEGENERATE if the boundary cannot be triangulated: an outer
 *         loop with fewer than 3 distinct points or no area, loops that
 *         cross themselves or each other (with cm_triangulate_folds: by
 *         more than fold_tol), no region left (holes covering the outer
 *         loop: loops in the wrong order); st->where says which;
 *         CM_E_NONFINITE if a coordinate is NaN or infinite;
 *         CM_E_ARG on NULL pointers, nloops < 1, npts < 0, cap < 0, min_dist
 *         negative or NaN, or inconsistent offsets
 */
CM_NODISCARD cm_err cm_triangulate(const cm_vec2 *pts, int npts, const int *loop_start, int nloops, double min_dist,
                                   int (*tris)[3], int cap, int *ntris, int *nused, cm_tri_ws *ws, cm_status *st);

/**
 * cm_triangulate for boundaries that may cross by rounding: where no ear is
 * left but one that turns the wrong way, that triangle is cut anyway if its
 * height (over its longest side) is at most fold_tol, in the units of pts.
 * The decoder passes a fraction of the chordal tolerance: two boundary runs
 * closer than that which cross (the sliver where a spring's coil is ground
 * flat) then give a triangle folded over by less than the tolerance instead
 * of a failed face.  In the fallback, a boundary segment passing within
 * fold_tol / 2 of a vertex is bent through it (a hole poking out of the
 * outer loop by less, a thin finger whose sides cross); no triangle comes
 * out folded by more than fold_tol.  fold_tol = 0 is cm_triangulate.
 */
CM_NODISCARD cm_err cm_triangulate_folds(const cm_vec2 *pts, int npts, const int *loop_start, int nloops,
                                         double min_dist, double fold_tol, int (*tris)[3], int cap, int *ntris,
                                         int *nused, cm_tri_ws *ws, cm_status *st);

/**
 * cm_triangulate_folds with boundaries of `cdt_first` points or more (<= 0: 1024) triangulated
 * by the constrained Delaunay path first (inserted coarse to fine, the segments forced in), the
 * ear clipping only where that does not give a plain triangulation.  The result is the same
 * constrained Delaunay triangulation up to ties of cocircular points; for rings of a few hundred
 * points the ear clipping's fans cost more flips than the insertion (format 4.7 passes 64).
 */
CM_NODISCARD cm_err cm_triangulate_cdt(const cm_vec2 *pts, int npts, const int *loop_start, int nloops,
                                       double min_dist, double fold_tol, int cdt_first, int (*tris)[3], int cap,
                                       int *ntris, int *nused, cm_tri_ws *ws, cm_status *st);

/**
 * Insert the interior points pts[ws->done.npts, npts) into the triangulation
 * the last successful call on `ws` left (cm_triangulate, cm_triangulate_folds
 * or this), whose points pts[0, ws->done.npts) must be unchanged: the
 * decoder's refinement adds a few points a round, and rebuilding the region
 * from its boundary each round cost a quarter of a decode (issue 15).  The
 * points are inserted in order as cm_triangulate inserts interior points
 * (skipped when outside the region or within `min_dist` of a used point or
 * a boundary segment; points skipped before are not tried again), with the
 * Lawson flips about each point but no final pass over the region; the
 * triangles come out as from cm_triangulate, the unchanged ones in their places.  The result is the constrained Delaunay
 * triangulation of the same points, up to the ties of cocircular points and
 * the points min_dist skipped, which may differ from one call on all points.
 * @return CM_E_ARG (no triangulation to continue, fewer points than it has,
 *         min_dist negative or NaN), CM_E_LIMIT, CM_E_NONFINITE, CM_E_NOSPACE
 *         and CM_E_RANGE as cm_triangulate; after a failure nothing is left
 *         to continue.
 */
CM_NODISCARD cm_err cm_triangulate_more(const cm_vec2 *pts, int npts, double min_dist, int (*tris)[3], int cap,
                                        int *ntris, cm_tri_ws *ws, cm_status *st);

#endif /* CM_TESS_H */
