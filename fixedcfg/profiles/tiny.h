/*
 * Profile `tiny`: not a board.  Limits so small that tests reach every one
 * of them with hand-sized inputs (each limit is tested at MAX, MAX+1 and 0).
 */
#ifndef CM_PROFILE_TINY_H
#define CM_PROFILE_TINY_H
#define CM_PROFILE_NAME "tiny"
#define CM_MAX_DEGREE 3
#define CM_MAX_EDGE_CTRL 8
#define CM_MAX_SURF_CTRL_DIR 8
#define CM_MAX_SURF_CTRL 32
#define CM_MAX_FIT_CTRL 6
#define CM_MAX_LOOPS 2
#define CM_MAX_LOOP_EDGES 4
#define CM_MAX_FACE_EDGES 8
#define CM_MAX_SIDES 4
#define CM_MAX_GREG 4
#define CM_MAX_LSQ_UNKNOWNS 16
#define CM_MAX_LSQ_BAND 15
#define CM_MAX_FACES 8
#define CM_MAX_EDGES 16
#define CM_MAX_VERTICES 16
#define CM_MAX_TRIS 512
#define CM_VIEW_MAX_W 160
#define CM_VIEW_MAX_H 120
#define CM_TESS_PASS_SLOTS 128
#define CM_PARAM_GRID_CACHE 0 /* the global searches' grids (47 KiB) do not fit the budget: searched as before */
#define CM_EGREG_MEMO_BITS 0  /* an exact patch's memo of side evaluations (17 KiB): the last one a side */
#define CM_MAX_TESS_POINTS 64
#define CM_MAX_FILE_BYTES 4096
#define CM_FILE_WINDOW_BYTES CM_MAX_FILE_BYTES
#define CM_SPILL_PAGE_BYTES 192u
#define CM_SPILL_PAGES 2
#define CM_MAX_MODEL_CTRL 64
#define CM_MAX_MODEL_KNOTS 64
#define CM_MAX_MODEL_LOOPS 16
#define CM_MAX_MODEL_USES 64
#define CM_MAX_EDGE_SAMPLES 32
#define CM_MAX_PLACEMENTS 4
#define CM_MAX_PART_NAME_BYTES 64
#define CM_STACK_FN_MAX 8192
#define CM_STACK_BUDGET 65536
/* 72 KiB for 57.7 KiB on x86-64 (65 KiB before issue 15's mesh window; GREGORY-FIT's corrections
   had added 2 x 2.4 KiB: MAX_GREG patches of 25 coefficients in the rebuild's and the
   tessellation's patch sets) */
#define CM_DECODE_STATE_BUDGET 73728
#endif
