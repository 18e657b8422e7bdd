/*
 * cm_limits.h - THE list of compile-time limits of a curvemesh build.
 *
 * Every buffer of the decoder and of the shared kernels is sized from the
 * macros below; nothing is allocated at run time.  A board profile
 * (fixedcfg/profiles/<name>.h, selected by -DCM_PROFILE='"profiles/x.h"')
 * may set any CM_MAX_* before the defaults here apply.  The defaults are the
 * `terminal` profile's values, so a build without a profile is a terminal
 * build.
 *
 * Each limit states its unit, its hard bound (a format or type ceiling that
 * no profile may exceed, checked in cm_limits_check.h) and why it exists.
 * The run-time table printed by `--limits` and `make print-limits` is
 * generated from cm_limits_list.h, so the numbers live only here and in the
 * profiles.
 */
#ifndef CM_LIMITS_H
#define CM_LIMITS_H

#ifdef CM_PROFILE
#  include CM_PROFILE /* profile first: it may set any CM_MAX_* below */
#endif

#ifndef CM_PROFILE_NAME
#  define CM_PROFILE_NAME "default"
#endif

/* ---- hard bounds: format field widths and type ceilings; never change ---- */
#define CM_HARD_MAX_DEGREE 15u          /* 4-bit degree field of the format */
#define CM_HARD_MAX_COUNT16 65535u      /* counts stored in 16-bit fields */
#define CM_HARD_MAX_COUNT24 16777215u   /* model-wide indices (24-bit, fits int32 and size_t on 32-bit ARM) */
#define CM_HARD_MAX_SIDES 8u            /* N-split record: at most 8 sub-patches (spec 6.4) */
#define CM_HARD_MAX_GREG 16u            /* Gregory patches per face: SUBDIV needs 7, N-split 8 */
#define CM_HARD_MAX_FIT_CTRL 35u        /* record field nu-4 is 5 bits (spec 15.2) */
#define CM_HARD_MAX_LSQ_UNKNOWNS 1089u  /* (CM_HARD_MAX_FIT_CTRL-2)^2 */
#define CM_HARD_MAX_LSQ_BAND 102u       /* 3*(CM_HARD_MAX_FIT_CTRL-2)+3 */
#define CM_HARD_MAX_TRIS 1431655765u    /* 3*tris must fit uint32 glTF indices */
#define CM_HARD_MAX_STACK 1048576u      /* 1 MiB: more than any board gives a thread */

/* ---- curves and surfaces ---- */

/* Polynomial degree of a curve, or of a surface in one direction.
 * Unit: degree.  Hard bound 15.  Sizes every basis-function workspace
 * (CM_MAX_ORDER doubles per row).  CAD exporters use 1..7 in practice. */
#ifndef CM_MAX_DEGREE
#  define CM_MAX_DEGREE 9
#endif

/* Control points of one edge curve (the transmitted boundary curves).
 * Unit: control points.  Hard bound 65535.  Sizes per-edge scratch such as
 * knot insertion and cubic conversion inputs; intersection curves from CAD
 * exporters reach a few hundred. */
#ifndef CM_MAX_EDGE_CTRL
#  define CM_MAX_EDGE_CTRL 256
#endif

/* Control points of one surface in one direction (kept or fitted).
 * Unit: control points.  Hard bound 65535.  Sizes knot vectors of a surface. */
#ifndef CM_MAX_SURF_CTRL_DIR
#  define CM_MAX_SURF_CTRL_DIR 128
#endif

/* Control points of one surface in total (nu*nv).  Unit: control points.
 * Hard bound 2^24-1.  Sizes the control net buffer of a kept surface. */
#ifndef CM_MAX_SURF_CTRL
#  define CM_MAX_SURF_CTRL 4096
#endif

/* Control points per direction of a surface fitted by NFILL/G1FIT (spec 8.9
 * tries c = 4..24).  Unit: control points.  Hard bound 35 (5-bit record
 * field).  Sizes the side-curve least squares. */
#ifndef CM_MAX_FIT_CTRL
#  define CM_MAX_FIT_CTRL 24
#endif

/* ---- faces and loops ---- */

/* Loops of one face: the outer loop plus holes.  Unit: loops.  Hard bound
 * 65535.  Sizes the per-face topology record. */
#ifndef CM_MAX_LOOPS
#  define CM_MAX_LOOPS 64
#endif

/* Edge uses in one loop.  Unit: edges.  Hard bound 65535. */
#ifndef CM_MAX_LOOP_EDGES
#  define CM_MAX_LOOP_EDGES 128
#endif

/* Edge uses in one face, all loops together.  Unit: edges.  Hard bound
 * 65535.  Sizes boundary sampling (CM_MAX_FACE_EDGES*CM_SEG_PER_EDGE points):
 * a face's and a partner's samples, 720 bytes an edge.  Terminal 256 (512
 * before issue 15's 4 MiB); the corpus needs at most 150. */
#ifndef CM_MAX_FACE_EDGES
#  define CM_MAX_FACE_EDGES 256
#endif

/* Sides of a face rebuilt by Gregory N-split (spec 6.4).  Unit: sides.
 * Hard bound 8. */
#ifndef CM_MAX_SIDES
#  define CM_MAX_SIDES 8
#endif

/* Bicubic Gregory patches of one rebuilt face.  Unit: patches.  Hard bound
 * 16; SUBDIV needs 7 and N-split CM_MAX_SIDES. */
#ifndef CM_MAX_GREG
#  define CM_MAX_GREG 8
#endif

/* ---- least squares (spec 8.7, 16) ---- */

/* Unknown control points of a fitted surface, K = (nu-2)(nv-2).  Unit:
 * unknowns.  Hard bound 1089.  Banded storage is K*(band+1) doubles. */
#ifndef CM_MAX_LSQ_UNKNOWNS
#  define CM_MAX_LSQ_UNKNOWNS 484
#endif

/* Half bandwidth of the surface normal equations, w = 3(nv-2)+3.
 * Unit: columns.  Hard bound 102. */
#ifndef CM_MAX_LSQ_BAND
#  define CM_MAX_LSQ_BAND 69
#endif

/* ---- whole model ---- */

/* Faces of one model.  Unit: faces.  Hard bound 2^24-1. */
#ifndef CM_MAX_FACES
#  define CM_MAX_FACES 4096
#endif

/* Edges of one model's curve mesh (a shared edge counts once).
 * Unit: edges.  Hard bound 2^24-1. */
#ifndef CM_MAX_EDGES
#  define CM_MAX_EDGES 4096
#endif

/* Vertices of one model's curve mesh.  Unit: vertices.  Hard bound 2^24-1. */
#ifndef CM_MAX_VERTICES
#  define CM_MAX_VERTICES 4096
#endif

/* Triangles of the decoded mesh.  Unit: triangles.  Hard bound
 * 1431655765 (3 indices each must fit uint32 glTF indices). */
#ifndef CM_MAX_TRIS
#  define CM_MAX_TRIS 524288
#endif

/* Points triangulated for one face (boundary samples of all its loops plus
 * interior points).  Unit: points.  Hard bound 2^24-1.  Sizes the
 * tessellation workspace (about 2 triangles per point). */
#ifndef CM_MAX_TESS_POINTS
#  define CM_MAX_TESS_POINTS 3072
#endif

/* Slots of each of the two tables in which the tessellation's refinement remembers the triangles
 * and sides that passed its deviation test in the last round, so that it does not test them again
 * (the test of a piece depends only on its corners).  A lossy cache: when a table is half full the
 * rest are tested again, so a smaller size costs speed, never output.  Unit: slots of 8 bytes, two
 * tables.  A power of two.  Not a limit of the format (cm-limits does not list it). */
#ifndef CM_TESS_PASS_SLOTS
#  define CM_TESS_PASS_SLOTS 8192
#endif

/* The viewer's frame (cm_view.h, cmz-view): at most this many pixels across and down.  Its
 * static RAM is 7 bytes a pixel (RGB and a float depth): 800 x 480, a common 7-inch panel, is
 * 2.6 MiB, within issue 17's 4 MiB for the viewer on top of the decoder's budget.  Unit: pixels.
 * Not a limit of the format (cm-limits does not list it). */
#ifndef CM_VIEW_MAX_W
#  define CM_VIEW_MAX_W 800
#endif
#ifndef CM_VIEW_MAX_H
#  define CM_VIEW_MAX_H 480
#endif

/* Vertices of one mesh face the viewer projects once for all its triangles (33 bytes each); a
 * larger face's are projected at each triangle corner, the same pixels more slowly.  Unit:
 * vertices.  Not a limit of the format. */
#ifndef CM_VIEW_FACE_VERTS
#  define CM_VIEW_FACE_VERTS CM_MAX_TESS_POINTS
#endif

/* The names of a model's parts (format 4.12: what the terminal's status line says at each assembly
 * step), each with a 0 byte after it.  A file whose names need more decodes without them, with a
 * warning (cm_model.part_names_left_out): names are for the operator's eyes, not worth refusing a
 * model for.  Unit: bytes.  Not a limit of the format (cm-limits does not list it). */
#ifndef CM_MAX_PART_NAME_BYTES
#  define CM_MAX_PART_NAME_BYTES 8192
#endif

/* Straight pieces the viewer draws each edge curve with (its points are the curve's own, at even
 * parameter steps).  Unit: segments per edge.  Not a limit of the format. */
#ifndef CM_VIEW_EDGE_SEGMENTS
#  define CM_VIEW_EDGE_SEGMENTS 32
#endif

/* The viewer's glTF input (cmz-view MODEL.glb, cm_glb_read.h): accessors, primitives (each mesh's
 * list counted again for every mesh), nodes and materials a .glb may have.  `cmz decode`'s own GLB of
 * a model of CM_MAX_FACES faces has three accessors a face and each face a primitive of the model's
 * mesh and at most once more of a placed copies' mesh, a node per placement.  Over them the file is
 * refused by name (CM_E_LIMIT, what it needs and what the build has).  Each accessor takes 16
 * bytes, a primitive 20, a node 176.  Units: items.  Not limits of the format. */
#ifndef CM_GLB_MAX_ACCESSORS
#  define CM_GLB_MAX_ACCESSORS (3 * CM_MAX_FACES + 16)
#endif
#ifndef CM_GLB_MAX_PRIMS
#  define CM_GLB_MAX_PRIMS (2 * CM_MAX_FACES)
#endif
#ifndef CM_GLB_MAX_NODES
#  define CM_GLB_MAX_NODES (CM_MAX_PLACEMENTS + 64)
#endif
#ifndef CM_GLB_MAX_MATERIALS
#  define CM_GLB_MAX_MATERIALS 256
#endif
#ifndef CM_GLB_MAX_VIEWS
#  define CM_GLB_MAX_VIEWS 64
#endif

/* Bytes of each cached page (CM_SPILL_PAGES for each of positions, normals, indices) through
 * which a streaming terminal reads its spilled output mesh back (cm_mesh.h): a page is a read
 * call.  Unit: bytes, at least 12.  Not a limit of the format (cm-limits does not list it). */
#ifndef CM_SPILL_PAGE_BYTES
#  define CM_SPILL_PAGE_BYTES 8192u
#endif

/* Cached pages per stream of the spilled mesh (above): STL reads a face's positions by its
 * indices, which jump within the face; with one page it re-read a page nearly every triangle.
 * Unit: pages.  Not a limit of the format. */
#ifndef CM_SPILL_PAGES
#  define CM_SPILL_PAGES 4
#endif

/* Size of one .cmz file.  Unit: bytes.  Hard bound 2^31-1.  The decoder
 * holds only CM_FILE_WINDOW_BYTES of it (below); what stays is the link's
 * and the store's room for a file (the corpus's largest: 28 KB). */
#ifndef CM_MAX_FILE_BYTES
#  define CM_MAX_FILE_BYTES 8388608
#endif

/* Bytes of the .cmz file the decoder holds (issue 15: stream, don't hold): the header is read in
 * them as it arrives, the body only checked (its CRC) as it passes; the sections are then read
 * again through them from where the file is stored (cm_dec_set_source), a window at a time.  A file
 * no longer than this is simply held.  Unit: bytes, at least CM_FMT_MAX_HEADER (4096: a header is
 * held whole).  Not a limit of the format (cm-limits does not list it): a smaller window reads
 * more often.  Terminal: 8 KiB, so that most corpus files are read through it (tested). */
#ifndef CM_FILE_WINDOW_BYTES
#  define CM_FILE_WINDOW_BYTES 8192
#endif

/* Control points of all curves and kept surfaces of one model (one pool).
 * Unit: control points.  Hard bound 2^24-1.  32 bytes each (point and weight). */
#ifndef CM_MAX_MODEL_CTRL
#  define CM_MAX_MODEL_CTRL 16384
#endif

/* Knots of all curves and kept surfaces of one model (one pool).
 * Unit: knots.  Hard bound 2^24-1. */
#ifndef CM_MAX_MODEL_KNOTS
#  define CM_MAX_MODEL_KNOTS 16384
#endif

/* Loops of all faces of one model.  Unit: loops.  Hard bound 2^24-1. */
#ifndef CM_MAX_MODEL_LOOPS
#  define CM_MAX_MODEL_LOOPS 4096
#endif

/* Edge uses of all loops of one model (about twice the edges).
 * Unit: uses.  Hard bound 2^24-1. */
#ifndef CM_MAX_MODEL_USES
#  define CM_MAX_MODEL_USES 8192
#endif

/* Points sampled on one edge for tessellation.  Unit: points.  Hard bound
 * 65535.  The chordal tolerance decides; this caps a wild curve. */
#ifndef CM_MAX_EDGE_SAMPLES
#  define CM_MAX_EDGE_SAMPLES 1024
#endif

/* Placed copies of a model's parts (format 4.3: a part placed several times travels once, with a
 * transform per further placement).  Unit: copies.  Hard bound 2^24-1.  104 bytes each in the
 * decoder's model; the corpus's assemblies place 3 to 14 copies, a large vault assembly (fasteners
 * placed one by one) a few hundred. */
#ifndef CM_MAX_PLACEMENTS
#  define CM_MAX_PLACEMENTS 512
#endif

/* ---- stack (checked from -fstack-usage / -fcallgraph-info=su) ---- */

/* Stack frame of one decoder or kernel function.  Unit: bytes.  Hard bound
 * 1 MiB.  Enforced at compile time by -Wstack-usage. */
#ifndef CM_STACK_FN_MAX
#  define CM_STACK_FN_MAX 8192
#endif

/* Deepest call path through decoder and kernels, summed frames.
 * Unit: bytes.  Hard bound 1 MiB.  Checked by `make check-stack`. */
#ifndef CM_STACK_BUDGET
#  define CM_STACK_BUDGET 65536
#endif

/* Deepest call path of a whole terminal program (cmz-decode, cmz-terminal:
 * main, the link, the store, the writers, then the decoder), summed frames;
 * every function of it also within CM_STACK_FN_MAX.  Unit: bytes.  32 KiB:
 * a board's daemon thread may get as little as 64 KiB of stack, and the
 * libraries below (libc, libusb, libgpiod), whose frames the gate cannot
 * see, keep the other half.  Checked by `make check-stack-programs`. */
#ifndef CM_STACK_PROGRAM_BUDGET
#  define CM_STACK_PROGRAM_BUDGET 32768
#endif

/* ---- memory of one decode ---- */

/* Static storage of one decode, sizeof(cm_decode_state) (cm_decode_state.h):
 * the decoder (the file's window and the model's pools), the triangulator's
 * workspace and the output mesh's window at this profile's limits.
 * Unit: bytes.  A budget, not a limit of a model: it is not in
 * cm_limits_list.h (whose order is the limit id on the wire) and no file
 * needs it.  A _Static_assert fails the build when the state outgrows it, so
 * the board's RAM changes only on purpose; `--limits` prints both.  Terminal:
 * 3.5 MiB for 3.35 MiB on x86-64 and aarch64 (issue 15: 4 MiB in all with the
 * program's own below; 44.6 MiB before the file and the output mesh were
 * streamed and the model's pools sized to the corpus: its largest model needs
 * 3358 faces, 1580 edges, 6133 control points, 9859 knots, 3160 edge uses,
 * 5898 points on one face at the workstation's tolerance). */
#ifndef CM_DECODE_STATE_BUDGET
#  define CM_DECODE_STATE_BUDGET 3670016
#endif

/* Static storage of a terminal program besides its decode state (cmz-decode,
 * cmz-terminal: the link's frames and file, the transports, the writer's and
 * reader's chunks, the store).  Unit: bytes.  A budget like the one above:
 * `make check-ram` fails when a program's data + bss exceeds
 * CM_DECODE_STATE_BUDGET + CM_PROGRAM_STATIC_BUDGET (x86-64 and aarch64), so
 * the board's RAM grows only on purpose.  Terminal: 512 KiB for about 290 KiB
 * (the two budgets: issue 15's 4 MiB). */
#ifndef CM_PROGRAM_STATIC_BUDGET
#  define CM_PROGRAM_STATIC_BUDGET 524288
#endif

/* Static storage of the viewer on top of a program's other budgets (cmz-view; issue 17: at most
 * 4 MiB at 800 x 480): its frame and depth buffer (CM_VIEW_MAX_W x CM_VIEW_MAX_H, 7 bytes a
 * pixel).  Unit: bytes.  `make check-ram` holds cmz-view's data + bss within
 * CM_DECODE_STATE_BUDGET + CM_PROGRAM_STATIC_BUDGET + this.  Terminal: 4 MiB for 2.6 MiB. */
#ifndef CM_VIEW_STATIC_BUDGET
#  define CM_VIEW_STATIC_BUDGET 4194304
#endif

/* Code and read-only data of a terminal program (text: what `size` counts
 * as such, the unwind and relocation tables included) built for aarch64, the
 * board's architecture; Unit: bytes.  A budget like the two above, for the
 * flash and page cache of a small board (issue 15: 256 KiB): `make check-ram`
 * with CROSS_COMPILE=aarch64-linux-gnu- fails when cmz-decode or cmz-terminal
 * is over it (x86-64 code is another size: not checked there).  Terminal:
 * 256 KiB for about 250 KiB (cmz-terminal; cmz-decode about 196 KiB). */
#ifndef CM_PROGRAM_TEXT_BUDGET
#  define CM_PROGRAM_TEXT_BUDGET 262144
#endif

/* ---- derived sizes: never set directly ---- */
#define CM_MAX_ORDER (CM_MAX_DEGREE + 1)                      /* order = degree + 1 */
#define CM_MAX_DERS 2                                         /* derivatives evaluated: S, S', S'' */
#define CM_MAX_EDGE_KNOTS (CM_MAX_EDGE_CTRL + CM_MAX_ORDER)   /* n + p + 1 */
#define CM_MAX_SURF_KNOTS_DIR (CM_MAX_SURF_CTRL_DIR + CM_MAX_ORDER)
#define CM_MAX_DENSE CM_MAX_FIT_CTRL                          /* dense Cholesky dimension */
#define CM_MAX_TESS_TRIS (2 * CM_MAX_TESS_POINTS)             /* a triangulation of n points has < 2n triangles */

#include "cm_limits_check.h"

#endif /* CM_LIMITS_H */
