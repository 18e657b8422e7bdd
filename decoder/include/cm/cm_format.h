/*
 * cm_format.h - constants, the header layout and the decoded model of the .cmz format
 * (docs/FORMAT.md is the specification; this header is its C view).
 *
 * The model is what the terminal rebuilds surfaces from: vertices, edges
 * (the transmitted curves, clamped on [0,1], ends exactly at their
 * vertices), faces with loops of edge uses and a reconstruction method,
 * kept surfaces, colours.  All storage is static and sized by fixedcfg
 * limits; nothing here allocates.
 */
#ifndef CM_FORMAT_H
#define CM_FORMAT_H

#include <stdint.h>

#include "cm/cm_error.h"
#include "cm/cm_vec.h"
#include "cm_limits.h"

#define CM_FMT_MAGIC0 0x89u
#define CM_FMT_MAGIC1 'C'
#define CM_FMT_MAGIC2 'M'
#define CM_FMT_MAGIC3 'Z'
#define CM_FMT_VERSION_MAJOR 4     /* the newest this reader knows (4: the compact header) */
#define CM_FMT_VERSION_MINOR 14    /* the newest minor of CM_FMT_VERSION_MAJOR */
#define CM_FMT_V2_MINOR 6          /* the last minor of format 2: 1 GREGORY-EXACT, 2 GREGORY-FIT, 3 layout 3,
                                      4 NFILL, 5 G1FIT, 6 the exact patches' turning basis */
#define CM_FMT_TURNING_MINOR 6     /* files of 2.6 on rebuild exact sides with the turning basis */
#define CM_FMT_PREDICT_MAJOR 3     /* files of 3.0 on code curves and knots predicted (cm_predict.h) */
#define CM_FMT_COMPACT_MAJOR 4     /* files of 4.0 on have the compact header (cm_fmt_compact_pack) */
#define CM_FMT_VERSION_MIN_MAJOR 1 /* oldest major version this reader accepts */

#define CM_FMT_FIXED_HEADER 60u   /* bytes before the need table */
/* need-table entries every writer since format 1.0 emits (the limit list of 1.0 had 25): a shorter
   table is malformed, since the decoder bounds its tessellation work by what the file declares */
#define CM_FMT_MIN_NEEDS 25u
#define CM_FMT_SECTION_ENTRY 16u  /* tag, 3 reserved, offset, length, crc */

/* Byte offsets of the fixed header's fields (docs/FORMAT.md), named once for the reader, the writer
   and the tests: the header is the need table (4 bytes per limit) and the section table after them,
   then its CRC-32 */
enum cm_fmt_header_at {
    CM_HDR_MAGIC = 0,         /* 4 bytes: 0x89 'C' 'M' 'Z' */
    CM_HDR_MAJOR = 4,         /* u8 */
    CM_HDR_MINOR = 5,         /* u8 */
    CM_HDR_FLAGS = 6,         /* u16: bit 0 = a COLR palette is present */
    CM_HDR_LENGTH = 8,        /* u32: header bytes, its CRC included */
    CM_HDR_FILE_LENGTH = 12,  /* u32: the whole file, its trailing CRC included */
    CM_HDR_NLIMITS = 16,      /* u8: entries of the need table */
    CM_HDR_NSECTIONS = 17,    /* u8: entries of the section table */
    CM_HDR_QEXP = 18,         /* s8: the grid step is 2^e mm */
    CM_HDR_RESERVED = 19,     /* u8: 0 */
    CM_HDR_ORIGIN = 20,       /* 3 x f64: the grid origin (mm) */
    CM_HDR_TESS_TOL = 44,     /* f64: recommended chordal tolerance (mm) */
    CM_HDR_REL_TOL = 52,      /* f64: the encoder's rebuild tolerance (fraction of a face's size) */
    CM_HDR_NEEDS = 60         /* u32 per limit, then the section table */
};
/* Byte offsets within one section table entry. */
enum cm_fmt_entry_at { CM_ENT_TAG = 0, CM_ENT_RESERVED = 1 /* 3 bytes, 0 */, CM_ENT_OFFSET = 4, CM_ENT_LENGTH = 8,
                       CM_ENT_CRC = 12 };

/** The fixed header's fields (the tables after it are addressed with cm_fmt_need_at/cm_fmt_entry_at). */
typedef struct cm_fmt_header {
    uint8_t major, minor;
    uint16_t flags;
    uint32_t header_len, file_len;
    uint8_t nlimits, nsections;
    int8_t q_exp;
    double origin[3], tess_tol, rel_tol;
} cm_fmt_header;

/** Write the fixed header (magic included) into b[0..CM_FMT_FIXED_HEADER). */
void cm_fmt_header_pack(uint8_t *b, const cm_fmt_header *h);
/** Read the fixed header from b[0..CM_FMT_FIXED_HEADER) (nothing checked: the reader does that). */
void cm_fmt_header_unpack(const uint8_t *b, cm_fmt_header *h);
/*
 * Format 4's compact header (docs/FORMAT.md, "Header, format 4"): magic, major, minor as above, then
 * unsigned LEB128 varints (signed ones zigzag-mapped): H (the header's length, its CRC included), flags,
 * N and the N needs, S and the S section lengths (the sections back to back after the header, so
 * their offsets and the file's length follow; no CRC per section: the file's CRC, checked before
 * any section is read, covers them), the grid exponent e, the grid origin as three multiples of the
 * grid step q = 2^e, the chordal tolerance as a multiple m >= 1 of q, the rebuild tolerance as a
 * multiple of 2^-24; then the u32 CRC of the bytes before it.  A 10 mm cube's header: 58 bytes
 * where format 3's fixed one takes 248.
 */
#define CM_FMT_COMPACT_AT_H 6u   /* offset of the varint H */
#define CM_FMT_VARINT_MAX 10u    /* bytes of the longest varint (64 bits) */
#define CM_FMT_REL_TOL_ONE (1u << 24) /* the rebuild tolerance's unit in format 4: 2^-24 */
/* format 4.1: the origin as multiples of a coarser power-of-two step (its exponent over the grid's
   first), the rebuild tolerance as its difference from the default 1 % (167772 / 2^24) */
#define CM_FMT_SHORT_ORIGIN_MINOR 1u
#define CM_FMT_KEPT_OFF_EDGES_MINOR 1u /* 4.1: kept nets re-approximated (cm_model.kept_off_edges) */
#define CM_FMT_NET_FIT_MINOR 2u        /* 4.2: NFILL and G1FIT records may carry an interior correction */
#define CM_FMT_PLACE_MINOR 3u          /* 4.3: the FACE section ends with the placed copies (cm_placement) */
#define CM_FMT_ARC_MINOR 4u            /* 4.4: a curve may be sent as an arc through its middle point (cm_arc.h) */
#define CM_FMT_USE_ADJ_MINOR 5u        /* 4.5: an edge use named among the edges at its loop's vertex (cm_use_adj.h) */
#define CM_FMT_ONE_STREAM_MINOR 6u     /* 4.6: the header's fields range-coded, the five sections one stream */
#define CM_FMT_REFINE_MINOR 7u         /* 4.7: the bytes of 4.6; the tessellation's refinement continues its
                                          triangulation and tests less (cm_model.refine_47) */
#define CM_FMT_PREDICT_FLAT_MINOR 8u   /* 4.8: the bytes of 4.7; the refinement passes untested a piece its
                                          corners' normals predict flat, a kept face's loop starts from its
                                          control net (cm_model.refine_48) */
#define CM_FMT_RULED_MINOR 9u          /* 4.9: the bytes of 4.8; a kept face is triangulated in a plane squeezed
                                          along its flatter direction, a ruled one (degree 1) in strips
                                          along its rulings (cm_model.refine_49) */
#define CM_FMT_PATCH_SCALE_MINOR 10u   /* 4.10: the bytes of 4.9; a GREGORY patch's plane of triangulation is
                                          scaled by its boundary's lengths (cm_model.refine_410) */
#define CM_FMT_PARTS_MINOR 11u         /* 4.11: the COLR section ends with the model's parts, in the order of
                                          the terminal's assembly steps (cm_face.part, cm_placement.part) */
#define CM_FMT_PART_NAMES_MINOR 12u    /* 4.12: and with their names (cm_model.part_names) */
#define CM_FMT_MAX_PART_NAME 255u      /* 4.12: bytes of one part's name */
#define CM_FMT_HINTS_MINOR 13u         /* 4.13: GREGORY-family records end with corner hint normals (spec 15.3,
                                          cm_face_hint_mask) */
#define CM_FMT_HINT_ONE 32767          /* 4.13: a hint's octahedral coordinates in units of 1/this */
#define CM_FMT_CONIC_CUBIC_MINOR 14u   /* 4.14: the bytes of 4.13; a GREGORY side along a one-span conic (an arc
                                          up to a half circle) is its closed-form cubic, not K7's fit
                                          (cm_model.conic_cubic, cm_edge_cubic) */
/* 4.3: a placement's linear part within this of 1 per entry, its translation within this many mm */
#define CM_FMT_PLACE_MAX_LINEAR 1e3
#define CM_FMT_PLACE_MAX_SHIFT 1e9
#define CM_FMT_PLACE_MIN_DET 1e-9 /* |det M|: a copy scaled by less than 1e-3 is no copy */
#define CM_FMT_PLACE_MAX_STEPS (1ll << 32) /* a copy's displacement of the grid origin, in grid steps (the
                                              writer's bound: the coder carries up to 2^33 - 1) */
#define CM_FMT_REL_TOL_DEFAULT 167772u
#define CM_FMT_MAX_ORIGIN_SHIFT 62u
/** Append v as an unsigned LEB128 varint at b; returns its bytes (1..CM_FMT_VARINT_MAX). */
uint32_t cm_fmt_put_varint(uint8_t *b, uint64_t v);
/** Read a varint from b[*at..end) into *v, advancing *at; 0 when it does not end before `end` or
    runs past 64 bits (then *at is where it failed). */
int cm_fmt_get_varint(const uint8_t *b, uint32_t end, uint32_t *at, uint64_t *v);
/** Format 4.1 on: the rebuild tolerance whose difference from the default (167772 / 2^24) is d;
    -1 below zero (the reader refuses it); in double, so that no d overflows. */
static inline double cm_fmt_rel_tol(int64_t d)
{
    return d < -(int64_t)CM_FMT_REL_TOL_DEFAULT ? -1.0
                                                : ((double)d + (double)CM_FMT_REL_TOL_DEFAULT) / (double)CM_FMT_REL_TOL_ONE;
}
static inline uint64_t cm_fmt_zigzag(int64_t v) { return v < 0 ? ((uint64_t)(-(v + 1)) << 1) | 1u : (uint64_t)v << 1; }
static inline int64_t cm_fmt_unzigzag(uint64_t u) { return (u & 1u) ? -(int64_t)(u >> 1) - 1 : (int64_t)(u >> 1); }
/** The grid step 2^e mm (e in -60..20, exact). */
double cm_fmt_grid_step(int q_exp);
/**
 * Write format 4's header into b (room for CM_FMT_MAX_HEADER bytes) for h (its header_len and
 * file_len are set here), nneeds needs and h->nsections section lengths; the origin must be a
 * multiple of the grid step and the chordal tolerance a positive one (cm_fmt_compact_tess).
 * Returns the header's length, CRC included, or 0 when it would pass CM_FMT_MAX_HEADER.
 */
uint32_t cm_fmt_compact_pack(uint8_t *b, cm_fmt_header *h, const uint32_t *need, const uint32_t *sec_len);
/*
 * Format 4.6's header (docs/FORMAT.md, "Header, format 4.6"): magic, major, minor, the varint H, then
 * one trimmed range-coded stream of the fields up to the CRC at H - 4: flags, N - 25, the body's
 * length B (the file is H + B + 4 bytes), the needs but MAX_FILE_BYTES (which is the file's length),
 * each as its difference from what the ones before it predict (cm_fmt_need_pred), the grid exponent,
 * the origin's step and multiples, the chordal and the rebuild tolerance.  The 10 mm cube's header:
 * 52 bytes in 4.5, 27 here.
 */
#define CM_FMT_STREAM_MIN_HEADER 12u /* magic, version, H, at least one byte of fields, the CRC */
/** What the needs before limit i predict of it (0: nothing; the Euler formula of a closed shell, two
    uses per edge, a loop per face, ...): the writer sends the difference. */
int64_t cm_fmt_need_pred(uint32_t i, const uint32_t *need);
/** Write format 4.6's header into b (room for CM_FMT_MAX_HEADER bytes) for h (its header_len and
    file_len are set here), h->nlimits needs (need[MAX_FILE_BYTES] is not sent: it is the file's
    length) and a body of body_len bytes.  Returns the header's length, or 0 past CM_FMT_MAX_HEADER. */
uint32_t cm_fmt_stream_pack(uint8_t *b, cm_fmt_header *h, const uint32_t *need, uint32_t body_len);
/**
 * Read format 4.6's header from b[0..H) (H from its varint; the CRC is the caller's): its fields into
 * h, the first `cap` needs into need (need[MAX_FILE_BYTES] = the file's length), the first need at or
 * past `cap` that is not 0 into *unknown (else UINT32_MAX).  Returns NULL, or the field that is
 * malformed (past the CRC, out of its range).  Nothing else is checked: the reader does that.
 */
const char *cm_fmt_stream_unpack(const uint8_t *b, uint32_t H, cm_fmt_header *h, uint32_t *need, uint32_t cap,
                                 uint32_t *unknown);

/** The needs a header of any format in b[0..n) declares (nothing checked but that they are in b):
    the first min(count, cap) of them into need, their number into *count; 0 when they are not in b. */
int cm_fmt_header_needs(const uint8_t *b, uint32_t n, uint32_t *need, uint32_t cap, uint32_t *count);
/** The chordal tolerance format 4 can say nearest to tess: a multiple m >= 1 of the grid step. */
double cm_fmt_compact_tess(double tess, int q_exp);

/**
 * Format 4.3: what is wrong with a placement's transform m (cm_placement.m), or NULL when the format
 * can say it: its linear part finite, within CM_FMT_PLACE_MAX_LINEAR per entry and invertible (|det|
 * at least CM_FMT_PLACE_MIN_DET), its translation within CM_FMT_PLACE_MAX_SHIFT mm.  The reader and
 * the writer apply the same rule.
 */
const char *cm_fmt_placement_fault(const double m[12]);

/** Offset of limit i's need, and of section entry s, in a header with nlimits needs (formats 1-3). */
static inline uint32_t cm_fmt_need_at(uint32_t i) { return CM_HDR_NEEDS + 4u * i; }
static inline uint32_t cm_fmt_entry_at(uint32_t nlimits, uint32_t s)
{
    return CM_HDR_NEEDS + 4u * nlimits + CM_FMT_SECTION_ENTRY * s;
}
/** Header length with nlimits needs and nsections entries: the tables and the CRC. */
static inline uint32_t cm_fmt_header_len(uint32_t nlimits, uint32_t nsections)
{
    return cm_fmt_entry_at(nlimits, nsections) + 4u;
}
#define CM_FMT_MAX_HEADER 4096u   /* a header larger than this is malformed */
#define CM_FMT_KNOT_BITS 30       /* knots quantised to 2^-30 of [0,1] */
#define CM_FMT_WEIGHT_BITS 24     /* weights quantised to 2^-24 of the first weight */
#define CM_FMT_COORD_MAX (1ll << 40)  /* |grid coordinate| beyond this is refused (hostile) */
#define CM_FMT_WEIGHT_MAX (1ll << 48) /* quantised weight beyond this is refused */
#define CM_FMT_MAX_STEP 24        /* format 3: a curve's or net's own step is at most 2^24 grid steps */
#define CM_FMT_MAX_PALETTE 255    /* colours (index 0 = none) */
#define CM_FMT_SEG_PER_EDGE 10    /* boundary samples per edge use (spec 8.1 / 5A) */
/** Boundary samples of a face: CM_FMT_SEG_PER_EDGE per edge use (spec 8.1), all loops. */
#define CM_MAX_FACE_SAMPLES (CM_MAX_FACE_EDGES * CM_FMT_SEG_PER_EDGE)

enum cm_fmt_section {
    CM_SEC_VERT = 1,
    CM_SEC_EDGE = 2,
    CM_SEC_SURF = 3,
    CM_SEC_FACE = 4,
    CM_SEC_COLR = 5,
    CM_SEC_COUNT = 5
};

enum cm_fmt_method {
    CM_METHOD_KEEP = 0,   /* the original surface travels in the SURF section */
    CM_METHOD_PLANE = 1,  /* spec 5A: rebuilt from the boundary */
    CM_METHOD_GREGORY = 2, /* spec §6: Gregory patches from the boundary curves (format 2) */
    CM_METHOD_GREGORY_EXACT = 3, /* GREGORY's layouts over the exact edges (format 2.1) */
    CM_METHOD_GREGORY_FIT = 4, /* GREGORY-EXACT's patches plus a sent interior correction (format 2.2) */
    CM_METHOD_NFILL = 5,  /* spec §8: a B-spline fitted to the boundary and its tangent planes (format 2.4) */
    CM_METHOD_G1FIT = 6,  /* spec §9 over the face's own edges: their tangent planes kept (format 2.5) */
    CM_METHOD_COUNT = 7   /* methods this version knows */
};

enum cm_fmt_edge_kind {
    CM_EDGE_LINE = 0,     /* degree 1 between its vertices: no curve data */
    CM_EDGE_CURVE = 1     /* a clamped NURBS on [0,1] */
};

typedef struct cm_edge {
    int32_t v0, v1;       /* vertices at t = 0 and t = 1 */
    uint32_t ctrl0;       /* first control point in the pool (ctrl[ctrl0] is v0) */
    uint32_t knot0;       /* first knot in the pool (n + p + 1 knots) */
    uint16_t nctrl;
    uint8_t p, rational, g1, kind;
} cm_edge;

typedef struct cm_ksurf {
    uint32_t ctrl0, uknot0, vknot0; /* pools; net row-major in u */
    uint16_t nu, nv;
    uint8_t p, q, rational;
} cm_ksurf;

typedef struct cm_use {
    uint32_t edge;
    uint8_t rev;          /* 1: the loop runs v1 -> v0 */
} cm_use;

typedef struct cm_loop {
    uint32_t use0;
    uint16_t nuse;
} cm_loop;

typedef struct cm_face {
    uint32_t loop0;       /* loop0 is the outer loop */
    uint16_t nloops;
    uint8_t method, flip, color; /* color: palette index, 0 = none */
    uint8_t layout;       /* GREGORY record (spec 15.2): layout 0..3 */
    uint16_t corner;      /* and layout 2's vertex j, or layout 3's corner bits (up to 12 edges) */
    uint8_t fit;          /* GREGORY-FIT, and NFILL and G1FIT from format 4.2: coefficients per
                             direction m (bits 0-2) and patches (bits 3-7; a net: 1) of its
                             correction (cm_face_fit_m, cm_face_fit_patches); else 0 */
    uint8_t fill_nu, fill_nv, fill_phi; /* NFILL, G1FIT record (spec 15.2): control points per direction
                             and NFILL's fairing weight's index (cm_nfill_phi) or G1FIT's mode; the
                             GREGORY family's hinted corners (cm_face_hint_mask); else 0 */
    uint32_t surf;        /* KEEP: index of its kept surface; a face with a correction (fit != 0):
                             index in ctrl[] of its first coefficient (patch k's (i,j) at
                             surf + (k m + i) m + j) */
    uint32_t checksum;    /* GREGORY: FNV-1a of the encoder's rebuilt patches (spec §2 rule 6) */
    uint32_t rec_off;     /* byte offset in the file where the face's record starts (the range
                             coder's read position then): errors about the face name it */
    uint32_t part;        /* format 4.11: its part, 1..cm_model.nparts, the assembly step that adds
                             it; 0 when the file names no parts */
} cm_face;

static inline uint8_t cm_face_fit_pack(unsigned m, unsigned patches) { return (uint8_t)((m & 7u) | (patches << 3)); }
static inline unsigned cm_face_fit_m(const cm_face *F) { return F->fit & 7u; }
static inline unsigned cm_face_fit_patches(const cm_face *F) { return (unsigned)F->fit >> 3; }
/* GREGORY family, format 4.13: the outer loop's corners that carry a hint normal (spec 15.3), bit k for
   the corner where use k starts, in fill_nu (bits 0-7) and fill_nv (bits 8-11), which only NFILL and
   G1FIT use otherwise (no room taken from the model's faces); the unit normals follow the face's
   correction in ctrl[] (from cm_face_hint_first), one per bit in corner order */
static inline int cm_method_takes_hints(unsigned method)
{
    return method >= CM_METHOD_GREGORY && method <= CM_METHOD_GREGORY_FIT;
}
static inline unsigned cm_face_hint_mask(const cm_face *F)
{
    return cm_method_takes_hints(F->method) ? (unsigned)F->fill_nu | (unsigned)F->fill_nv << 8 : 0u;
}
static inline uint32_t cm_face_hint_first(const cm_face *F)
{
    return F->surf + cm_face_fit_patches(F) * cm_face_fit_m(F) * cm_face_fit_m(F);
}

#define CM_NO_FACE (-1)   /* edge_face: no face on that side */
#define CM_MANY_FACES (-2) /* edge_face[e][1]: a third face uses the edge (non-manifold) */

/**
 * Format 4.3: a copy of faces [first, first + count) (a part placed once more: its faces travel
 * once), placed by x -> M x + t, m = {M11, M12, M13, t1, M21, ..., t3} (millimetres).  The decoder
 * rebuilds and tessellates the part once and appends the placed triangles (cm_place.h).
 */
typedef struct cm_placement {
    uint32_t first, count;
    double m[12];
    uint32_t part;        /* format 4.11: the copy's part (as cm_face.part) */
} cm_placement;

/** The decoded model: everything the reconstruction reads (spec §2 rule 5). */
typedef struct cm_model {
    double origin[3], q;  /* quantisation grid: p = origin + q * integer */
    double tess_tol;      /* chordal tolerance recommended by the encoder (mm) */
    double rel_tol;       /* the encoder's rebuild tolerance (fraction of a face's size) */
    int turning_basis;    /* format 2.6 on: GREGORY-EXACT/-FIT sides use the turning basis (cm_egreg.h) */
    int kept_off_edges;   /* format 4.1 on: a kept net may be re-approximated, its boundary up to a
                             quarter of its face's tolerance off the face's edges: the tessellation's
                             flatness tests along a kept face's loop take the surface's points */
    int predicted;        /* format 3 on: edges and knots coded with cm_predict.h's predictions */
    int refine_47;        /* format 4.7 on: the tessellation's refinement inserts each round's points
                             into the last round's triangulation, tests a triangle at its centre only
                             and a side's quarter points only where it may be S-shaped
                             (cm_tessellate.c); the encoder measured the needs that way */
    int refine_48;        /* format 4.8 on: a piece whose corners' normals predict it within a quarter
                             of the tolerance passes untested, and a kept face's loop finds its first
                             (u,v) from the surface's control net before any grid (cm_tessellate.c,
                             cm_param.c); the encoder measured the needs that way */
    int refine_49;        /* format 4.9 on: a kept face is triangulated in a plane squeezed along the
                             direction whose grid cells are longer (by at most 4; a ruled direction,
                             degree 1, without limit and with a grid column per knot span), so that
                             its triangles run along the flatter direction (cm_tessellate.c) */
    int conic_cubic;      /* format 4.14 on: a GREGORY side along a one-span conic is the cubic through
                             its ends and middle point with its end tangents (cm_edge_cubic), not K7's
                             least-squares fit; the encoder's checksums are of those patches */
    int refine_410;       /* format 4.10 on: a GREGORY patch is triangulated in (u,v) scaled by the
                             lengths of its boundary's sides, not by its mean speeds at 5 x 5 interior
                             points (cm_tessellate.c); the encoder measured the needs that way */
    /* what the header declares the tessellation at tess_tol needs (0: not declared): points of one
       face (MAX_TESS_POINTS), samples of one edge (MAX_EDGE_SAMPLES) and triangles of the whole
       model (MAX_TRIS).  The tessellation's work on a face, and on the model, is bounded by these
       (cm_tessellate.h), not only by the build's limits */
    uint32_t need_tess_points, need_edge_samples, need_tris;
    uint32_t nverts, nedges, nfaces, nloops, nuses, nsurfs, nctrl, nknots, npalette;
    cm_vec3 verts[CM_MAX_VERTICES];
    cm_edge edges[CM_MAX_EDGES];
    /* derived when the faces are read: the (up to) two faces that use each edge, and whether an
       N-split GREGORY face uses it (its tessellation then needs the edge's midpoint, t = 1/2) */
    int32_t edge_face[CM_MAX_EDGES][2];
    uint8_t edge_split[CM_MAX_EDGES];
    cm_ksurf surfs[CM_MAX_FACES];
    cm_face faces[CM_MAX_FACES];
    cm_loop loops[CM_MAX_MODEL_LOOPS];
    cm_use uses[CM_MAX_MODEL_USES];
    cm_vec3 ctrl[CM_MAX_MODEL_CTRL];
    double w[CM_MAX_MODEL_CTRL];
    double knots[CM_MAX_MODEL_KNOTS];
    uint32_t palette[CM_FMT_MAX_PALETTE + 1];
    uint32_t nplacements; /* format 4.3 */
    uint32_t nparts;      /* format 4.11: the parts the workstation named (0: none; the viewer then takes
                             the faces' connected pieces, cm_view_parts) */
    /* format 4.12: the parts' names, each ended by a 0 byte, part 1's first (cm_model_part_name);
       part_names_len 0: none sent, or (part_names_left_out) more than this build holds */
    char part_names[CM_MAX_PART_NAME_BYTES];
    uint32_t part_names_len;
    int part_names_left_out;
    cm_placement placements[CM_MAX_PLACEMENTS > 0 ? CM_MAX_PLACEMENTS : 1];
} cm_model;

/** Little-endian loads and stores (no host-endianness assumption). */
static inline uint32_t cm_get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static inline uint16_t cm_get_u16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }
static inline void cm_put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}
static inline void cm_put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}
/** IEEE-754 binary64 through its bit pattern (little-endian on the wire). */
double cm_get_f64(const uint8_t *p);
void cm_put_f64(uint8_t *p, double v);

/** Views of a model edge / kept surface for the kernels (pointing into the model's pools). */
struct cm_curve;
struct cm_surf;
void cm_model_edge_curve(const cm_model *m, uint32_t e, struct cm_curve *out);

/** Part part's name (format 4.12; parts from 1), or NULL where the file sent none (or the build
    left the names out: cm_model.part_names_left_out). */
const char *cm_model_part_name(const cm_model *m, uint32_t part);
void cm_model_surface(const cm_model *m, uint32_t s, struct cm_surf *out);

/** Fill edge_face and edge_split from the faces' loops (the decoder calls it after FACE). */
void cm_model_adjacency(cm_model *m);
/** The other face of edge e seen from face f, or CM_NO_FACE (free, non-manifold, a seam of f). */
int32_t cm_model_partner(const cm_model *m, uint32_t e, uint32_t f);

#endif /* CM_FORMAT_H */
