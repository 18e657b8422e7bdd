/*
 * encode_internal.h - what the encoder's files share (see encode.h for the
 * order of work): the transmitted model (tx_build.c), the section writers
 * (write_sections.c), the method choice (choose_methods.c) and the needs
 * and orientation measured on the terminal's tessellation (needs.c);
 * encode.c runs them.  Not for use outside host_tools/encode/.
 */
#ifndef ENCODE_INTERNAL_H
#define ENCODE_INTERNAL_H

#include <math.h>
#include <stdint.h>

#include "cm/cm_arith.h"
#include "cm/cm_decode.h"
#include "cm/cm_format.h"
#include "cm/cm_method.h"
#include "cm/cm_predict.h"
#include "cm/cm_rebuild.h"
#include "cm/cm_tessellate.h"
#include "encode.h"
#include "model_load.h"

#define WEIGHT_ONE (1ll << CM_FMT_WEIGHT_BITS)
#define KNOT_ONE (1ll << CM_FMT_KNOT_BITS)
/* what the decoder accepts: a value beyond cannot be sent */
#define GRID_MAX CM_FMT_COORD_MAX
#define WEIGHT_MAX CM_FMT_WEIGHT_MAX

/*
 * Everything one encode works in besides the model: a decoder like the terminal's, the rebuild's and
 * the tessellation's workspaces (tens of MB: allocated once per encode_model, never file-static, so
 * two encodes in one process do not share state).
 */
typedef struct enc_work {
    cm_decoder dec;
    cm_rebuild_ws rbws;
    cm_tess_ws tess_ws;
    float face_pos[CM_MAX_TESS_POINTS][3], face_nrm[CM_MAX_TESS_POINTS][3];
    uint32_t face_idx[3 * CM_MAX_TESS_TRIS];
} enc_work;

/* ---- the transmitted model (quantised, in transmission order) ---- */

typedef struct tx_edge {
    int v0, v1;       /* transmitted vertex numbers */
    int g1, kind, p, n, rational, uniform;
    int64_t *kq;      /* n - p - 1 interior knots */
    int64_t (*cq)[3]; /* n control points on the grid (ends = vertices) */
    int64_t *wq;      /* n weights */
    int linear, step; /* format 3: the predictor and the step 2^step of the interior points
                         (tx_coarsen.c; 0, 0 in format 2); of an arc, its middle point's */
    int arc;          /* format 4.4: sent as the arc through its vertices and qa (tx_arc.c); p, n and
                         rational are then the decoded curve's, cq, wq and kq NULL */
    int64_t qa[3];    /* ... the arc's middle point on the grid; of a closed edge's circle, the point
                         across from its vertex */
    int64_t ra[3];    /* ... and then the circle's point halfway to it */
} tx_edge;

typedef struct tx_surf {
    int p, q, nu, nv, rational, uniform_u, uniform_v;
    int64_t *ku, *kv;
    int64_t (*cq)[3];
    int64_t *wq;
    int quadratic;      /* format 3: the net's predictor (tx_net_predictor); its step is always 0 */
    int reapproximated; /* the net is the budget's re-approximation, not the source's (tx_coarsen.c) */
    int ruled;          /* format 4.4: sent ruled between two arcs (tx_arc.c, tx_ruled_surface) ... */
    int ruled_closed;   /* ... full circles */
    int ruled_along_v;  /* ... the arcs along v (the net's columns) */
    int64_t rp[2][3][3]; /* ... each row's first point, end (a circle's far point) and middle point */
} tx_surf;

/* a check a trial made that reads which faces before it keep their surfaces (G1FIT's normals
   along its edges: verify_g1_self), as it can be answered again once those are known */
#define TX_MAX_MATTER 16 /* faces before it one check depends on */
#define TX_MAX_CHECKS 48 /* checks of one face's trials */
typedef struct tx_check {
    unsigned char ok;   /* its answer with no face before counted as kept */
    double need_rebuilt, need_kept; /* passed: the worst |cos| toward faces that are rebuilt at least
                                       the first, toward kept faces the second */
    double other;       /* the worst |cos| toward faces that are not before it (never kept yet) */
    int n;              /* faces before it across a G1 edge: the worst |cos| toward each */
    int face[TX_MAX_MATTER];
    double worst[TX_MAX_MATTER];
} tx_check;

/*
 * What the trials of the face being chosen asked of the faces before it (t->nchosen): with several
 * workers each face is chosen as if none before it kept its surface, and then, in order, its checks
 * are answered again with the faces before it final; where an answer changes, the face is chosen
 * again from `row` (choose_methods.c).
 */
typedef struct tx_asked {
    int row;            /* the table row whose trial made the first check (-1: none) */
    face_report rep;    /* the face's report before that trial */
    int n;              /* checks made */
    int all;            /* more checks, or faces in one, than the record holds: chosen again whenever
                           a face before it across an edge keeps its surface */
    tx_check check[TX_MAX_CHECKS];
} tx_asked;

typedef struct tx {
    double origin[3], q;
    int q_exp;
    int vstep;          /* format 3: the vertices' step exponent (tx_coarsen_vertices; 0 in format 2) */
    unsigned char *fine; /* per curve mesh edge: 1 keeps it on the grid (it bounds a kept face;
                            enc_keep_fine_edges); NULL: none */
    int no_vstep;       /* 1: the vertices stay on the grid (a face is kept) */
    int edges_reapproximated; /* curves sent as fewer cubic points within their budget (tx_coarsen.c) */
    int edges_arcs;     /* curves sent as arcs (format 4.4, tx_arc.c) */
    int nverts, nedges, nfaces, nsurfs;
    int64_t (*vq)[3];   /* vertices in transmission order */
    tx_edge *edges;     /* in transmission order */
    int *edge_tx;       /* cmesh edge -> transmission number */
    int *vert_tx;       /* cmesh vertex -> transmission number */
    tx_surf *surfs;     /* one per face (used for KEEP faces) */
    int *method;        /* per face */
    int nchosen;        /* faces 0..nchosen-1 have their method (choose_methods: in order, then all) */
    tx_asked asked;     /* of the face being chosen (choose_methods.c) */
    int *layout, *corner; /* per GREGORY or NFILL face: its record (spec 15.2; enc_record_fields) */
    uint32_t *checksum;
    unsigned char *turning; /* per face: its exact patches turn a basis (the file is then format 2.6) */
    struct fit_record **fit; /* per GREGORY-FIT face: its correction (malloc'd; NULL otherwise) */
    uint32_t palette[CM_FMT_MAX_PALETTE + 1];
    int npalette;
    int *color;         /* per face palette index */
    const unsigned char *keep_only; /* per B-rep face: KEEP, a rebuilt surface did not tessellate */
    const unsigned char *net_whole; /* per B-rep face: its kept net sent whole (re-approximated, it folded) */
    const char **fault; /* per face: why it cannot be sent (NULL: it can); see encode_model */
    int nfaults;
    enc_work *w;        /* the decoder and tessellation storage this encode works in */
    const encode_opts *o; /* the options, as they apply to this model (encode_opts_for_model) */
    int edges_refit;    /* edges re-approximated to fit the target profile (fit_board.c) */
    int surfs_refit;    /* kept surfaces likewise */
    int surfs_reapproximated; /* kept surfaces sent as fewer cubic points within their budget */
} tx;

/* a check of the face being chosen that reads the kept faces before it (choose_methods.c): c->face
   and c->worst, its answer and thresholds; only where no face counted as kept (the record is then
   exact) */
void tx_note_check(tx *t, const tx_check *c);

/*
 * Replace curve c by a clamped B-spline of degree min(3, max_degree) with max_ctrl control points,
 * its ends kept, fitted to the original by least squares; only when it stays within tol (mm) of it
 * (fit_board.c).  Returns 1 if c was replaced, 0 if not (c unchanged).
 */
int enc_edge_refit(hcurve *c, int max_degree, int max_ctrl, double tol, cm_status *st);
/* ... by_length: the samples and the checks at equal steps of the curve's length (tx_coarsen.c) */
int enc_edge_refit_ex(hcurve *c, int max_degree, int max_ctrl, double tol, int by_length, cm_status *st);

/*
 * Replace polynomial surface s by one of degree at most min(3, max_degree) per direction, at most
 * max_dir control points per direction and max_total in all, within tol (mm) of it (fit_board.c).
 * Returns 1 if s was replaced, 0 if not (s unchanged).
 */
int enc_surf_refit(hsurf *s, int max_degree, int max_dir, int max_total, double tol, cm_status *st);
/* whether the interior knots of a degree-p B-spline of n control points (K: n + p + 1 knots) are
   not equally spaced over its domain */
static inline int enc_knots_uneven(const double *K, int p, int n)
{
    double a = K[p], b = K[n];
    for (int j = 1; j < n - p; j++)
        if (fabs(K[p + j] - (a + (b - a) * j / (n - p))) > 1e-9 * (b - a))
            return 1;
    return 0;
}
/* Replace surface s by a uniform cubic one with the fewest control points per direction (searched as
   tx_reapproximate_curve searches a curve's, the rows within tol / 2, then the columns) that stays
   within tol (mm) of it at the same parameters; 1 if s was replaced (fit_board.c). */
int enc_surf_reduce(hsurf *s, double tol, double rim_tol, cm_status *st);

/*
 * A face's record fields from tx's per-face layout and corner: GREGORY's as they are; NFILL's and
 * G1FIT's nu = layout, nv = corner & 0xff, phi or mode = corner >> 8 (one pair of arrays for every
 * method's record).
 */
static inline void enc_record_fields(cm_face *F, int method, int layout, int corner)
{
    F->method = (uint8_t)method;
    F->layout = (uint8_t)layout;
    F->corner = (uint16_t)corner;
    F->fill_nu = F->fill_nv = F->fill_phi = 0;
    if (method == CM_METHOD_NFILL || method == CM_METHOD_G1FIT) {
        F->layout = 0;
        F->corner = 0;
        F->fill_nu = (uint8_t)layout;
        F->fill_nv = (uint8_t)(corner & 0xff);
        F->fill_phi = (uint8_t)(corner >> 8);
    }
}

/* face f cannot be sent as it is; the first reason stays */
void tx_face_fault(tx *t, int f, const char *why);

/* 1 if faces of this method carry their surface (cm_method.h) */
static inline int enc_kept(int method)
{
    return cm_method_of((unsigned)method)->kept_surface;
}

/* drop the transmitted edges and vertices (tx_build_edges makes them again) */
void tx_free_edges(tx *t);

void tx_free(tx *t);

/* ---- orientation (orient.c): every part's faces agree on shared edges (they run both ways), and
   every closed part faces outwards ---- */
void enc_flip_face(loaded_model *lm, int f);

/* turn faces so that each part's faces agree with its first; returns faces turned */
int enc_orient_parts(loaded_model *lm);

/* turn every closed part (no free edges) whose faces enclose a negative volume, measured on the
   B-rep's own surfaces; returns faces turned */
int enc_outward_parts(loaded_model *lm);

cm_err tx_build_edges(loaded_model *lm, tx *t, cm_status *st);

/* S: face f's surface orig on the grid, as the source has it or re-approximated within its budget
   (tx_reapproximate_surface; not when t->net_whole says the face's net goes whole), its predictor
   chosen (tx_net_predictor) */
cm_err tx_build_surface(tx *t, const hsurf *orig, tx_surf *S, const cmesh *cm, int f, cm_status *st);
/* every face's tx_build_surface, on t->o->jobs processes (the same surfaces, faults and counters as
   in order); a face whose surface cannot be built gets its fault (tx_face_fault): only the end of
   memory fails */
cm_err tx_build_surfaces(tx *t, const loaded_model *lm, cm_status *st);
void tx_surf_free(tx_surf *S);
/* the fault a kept face whose re-approximated net folds its triangles gets (needs.c): encode_model
   sends that face's net whole and makes the file again */
extern const char enc_net_folds[];
/* whether one face's triangles, welded by position, use a directed side twice (two triangles on one
   side of it: a fold; mesh_topo's census, as mesh_check judges the decoded model).  A kept face's
   triangles meet its edges' points, the inner ones the surface's: a re-approximated surface a
   little off its edges may fold them there (needs.c).  Returns -1 when out of memory. */
int enc_face_folds(const cm_mesh *m);

/* format 4's compact header, trimmed streams and recent vertex values: the options say format 4 */
static inline int enc_compact_header(const encode_opts *o)
{
    return o->predicted && o->compact_header;
}
/* format 4.3 on: the FACE section ends with the placed copies (their count, 0 without) */
static inline int enc_placement_tail(const encode_opts *o)
{
    return enc_compact_header(o) && o->compact_minor >= (int)CM_FMT_PLACE_MINOR;
}
/* the placed copies' faces must travel together (write_sections.c); CM_E_FORMAT when not */
cm_err enc_check_placements(const tx *t, const loaded_model *lm, cm_status *st);
/* the decoded file's copies are lm's (faces, linear part exactly, translation within half a grid
   step): CM_E_FORMAT naming the copy when not (an encoder bug) */
cm_err enc_placements_decoded(const tx *t, const loaded_model *lm, const cm_model *dm, cm_status *st);
/* format 4.5 on: an edge use after the first of its loop is named among the edges at its vertex
   (cm_use_adj.h) */
static inline int enc_use_adj(const encode_opts *o)
{
    return enc_compact_header(o) && o->compact_minor >= (int)CM_FMT_USE_ADJ_MINOR;
}
/* format 4.4 on: curves may be sent as arcs (tx_arc.c) */
static inline int enc_arcs(const encode_opts *o)
{
    return enc_compact_header(o) && o->compact_minor >= (int)CM_FMT_ARC_MINOR;
}
/* format 4.2 on: NFILL and G1FIT nets may carry an interior correction (cm_fit_net_add) */
static inline int enc_net_fit(const encode_opts *o)
{
    return enc_compact_header(o) && o->compact_minor >= (int)CM_FMT_NET_FIT_MINOR;
}
/* format 4.13 on: GREGORY-family records may carry corner hints (spec 15.3) */
static inline int enc_hints(const encode_opts *o)
{
    return enc_compact_header(o) && o->compact_minor >= (int)CM_FMT_HINTS_MINOR;
}
/* the chordal tolerance the file can say nearest to tess (format 4: a multiple of the grid step), so
   that what the encoder measures the tessellation with is what the terminal reads */
double enc_file_tess(const tx *t, double tess);
/* assemble header + sections + trailer; needs may be NULL (all zero) */
cm_err enc_write_file(const tx *t, const loaded_model *lm, const encode_opts *o, const uint32_t *need,
                         encode_result *r, cm_status *st);

/* Spec §14 step 6, estimated: the bits a kept surface and a GREGORY-FIT record cost in the file
   (write_sections.c says how; the same estimate for both, so they compare) */
/* the bytes kept net S codes in, alone in a fresh stream (write_sections.c) */
size_t enc_net_bytes(const tx *t, const tx_surf *S);
double enc_kept_surface_bits(const tx_surf *S, int predicted);
/* control point j's prediction in edge X, coordinate k, on predictor `linear` (cm_predict.h; format 2:
   linear = 0, the previous point) */
static inline int64_t tx_edge_pred(const tx_edge *X, int linear, int j, int k)
{
    return cm_pred_ctrl(linear, j, X->n, X->cq[0][k], X->cq[X->n - 1][k], X->cq[j - 1][k], j >= 2 ? X->cq[j - 2][k] : 0);
}

/* the estimate of what one sint costs once the models have learnt (write_sections.c) */
double enc_sint_bits(int64_t v);
/* ... and of what curve X costs in EDGE, as sec_edge writes it (write_sections.c) */
double enc_edge_bits(const tx *t, const tx_edge *X, int predicted);
/* the numbers an arc edge sends: its middle point less the chord's midpoint (3); a closed edge's
   circle its far point less its vertex, then its middle point less their midpoint (6) */
static inline int tx_arc_fields(const tx_edge *X)
{
    return X->v0 == X->v1 ? 6 : 3;
}
/* ... field k of them, in steps */
static inline int64_t tx_arc_residual(const tx *t, const tx_edge *X, int k)
{
    const int64_t *a = t->vq[X->v0], *b = t->vq[X->v1];
    int64_t v = X->v0 != X->v1 ? X->qa[k] - cm_pred_arc_mid(a[k], b[k])
                               : (k < 3 ? X->qa[k] - a[k] : X->ra[k - 3] - cm_pred_arc_mid(a[k - 3], X->qa[k - 3]));
    return v / ((int64_t)1 << X->step);
}

/*
 * Format 3's precision from the tolerance budget (tx_coarsen.c): the interior control points of
 * curve X, or the net of kept surface S, moved onto a coarser step of their own, as coarse as the
 * budget allows: tol_mm is the tolerance of the faces the curve bounds, or of the face the surface
 * is kept for.  Chooses the predictor too.  Nothing changes unless the options say format 3.
 */
void tx_coarsen_edge(const tx *t, tx_edge *X, int fine, double tol_mm);
/* Before that (with the budget steps, off the grid's edges): curve c replaced by the uniform cubic
   B-spline with the fewest control points (fewer than it has; as many where its degree differs; up
   to half as many more where it is rational or on uneven knots) that stays within a sixteenth of the
   tolerance of a face its size, matched at equal steps of length; 1 if it was replaced. */
int tx_reapproximate_curve(const tx *t, hcurve *c);
/* p on the grid; 0 when it is not finite or beyond what the decoder accepts (out is then 0) */
int tx_quantise(const tx *t, cm_vec3 p, int64_t out[3]);
/* of the faces' tolerance, for the points of a curve or net (tx_coarsen.c) and an arc (tx_arc.c) */
#define ENC_CURVE_SHARE (1.0 / 16.0)
/* Format 4.4 (tx_arc.c): 1 and A an arc edge (its vertices and G1 flag as set) when curve c, from A's
   vertex v0 to v1, is the arc through them and its middle point within a sixteenth of the tolerance
   of a face its size, as the terminal will build it (cm_arc_nurbs), its middle point on the largest
   step the budget allows (`fine`: on the grid, within two grid steps); else 0 and A as it was. */
int tx_arc_edge(const tx *t, const hcurve *c, int fine, tx_edge *A);
/* ... and a kept surface s (on [0,1] both ways) linear in v whose two rows are arcs (or full circles)
   of as many pieces within two grid steps, corresponding as s's, or linear in u whose two columns
   are: 1 and S->ruled set with the rows' points, else 0 and S as it was */
int tx_ruled_surface(const tx *t, const hsurf *s, tx_surf *S);
/* the step exponent for points whose shortest leg is h_min mm, within tol_mm's share (tx_coarsen.c) */
int tx_choose_step(const tx *t, double tol_mm, double h_min);
/* v / 2^s rounded to the nearest integer, halves away from zero */
int64_t tx_div_step(int64_t v, int s);
/* the tolerance (mm) of a face the size of curve c (the box of its control points holds it): no
   face it bounds is held to less */
double curve_face_tol(const tx *t, const hcurve *c);
/* ... and of a face the size of surface s's net */
double surf_face_tol(const tx *t, const hsurf *s);
/* Likewise face f's kept net s (its parameters on [0,1] both ways): replaced by the uniform cubic one
   with the fewest control points within a quarter of the tolerance of a face its size (for a
   terminal older than 4.1, its boundary within a sixteenth where the face's edges run along it),
   when that has fewer; 1 if it was replaced (its net then stays on the grid as every kept net; the
   caller keeps it where it codes in fewer bytes). */
int tx_reapproximate_surface(const tx *t, hsurf *s, const cmesh *cm, int f);
/* After the methods are chosen: the edges of kept faces that were moved are marked to stay on the
   grid (every edge when `all`), the vertices too when a face is kept and they were moved.  Returns
   1 if anything is to change (the edges are then made again and the methods chosen again). */
int enc_keep_fine_edges(const loaded_model *lm, tx *t, int all);
/* the vertices likewise, one step for all of them: the smallest face's budget and the shortest
   edge's (their grid numbers in t->vq, transmission numbers in vert_tx) */
void tx_coarsen_vertices(tx *t, const cmesh *cm);
/* the diagonal (mm) of the box of n grid points (tx_build.c) */
double ctrl_box_diag(const tx *t, const int64_t (*cq)[3], long n);
void tx_net_predictor(const tx *t, tx_surf *S);
double enc_fit_record_bits(const struct fit_record *fr);

/* ---- decoding what we wrote, with the terminal's code ---- */
cm_err enc_decode_back(enc_work *w, const encode_result *r, cm_status *st);

/*
 * The file with every face kept (so that every face can be measured against a decoded model that
 * has all surfaces), decoded; the methods chosen on it; the file with those, decoded again.
 */
cm_err enc_choose_and_write(loaded_model *lm, tx *t, const encode_opts *o, encode_result *r, cm_status *st);

/* the terminal's tessellation of every face, one face at a time: triangles, points, edge samples */
/* measure (may be NULL): also each face's triangles against its source surface, both ways, into
   r->faces[f].mesh_dev (issue 14.6, --report) */
cm_err enc_tessellation_needs(tx *t, uint32_t *need, const encode_opts *o, const loaded_model *measure,
                              encode_result *r, cm_status *st);

void enc_compute_needs(const enc_work *w, const encode_result *r, uint32_t *need);

#endif /* ENCODE_INTERNAL_H */
