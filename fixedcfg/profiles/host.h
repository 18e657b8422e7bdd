/*
 * Profile `host`: the workstation tools (import, compression, verification,
 * host-side decode).  Large limits so any real model can be read; the
 * encoder still checks every file it writes against the target profile
 * (`cmz encode --profile terminal`).
 */
#ifndef CM_PROFILE_HOST_H
#define CM_PROFILE_HOST_H
#define CM_PROFILE_NAME "host"
#define CM_MAX_DEGREE 15
#define CM_MAX_EDGE_CTRL 8192
#define CM_MAX_SURF_CTRL_DIR 4096
#define CM_MAX_SURF_CTRL 1048576
#define CM_MAX_FIT_CTRL 24
#define CM_MAX_LOOPS 4096
#define CM_MAX_LOOP_EDGES 4096
#define CM_MAX_FACE_EDGES 16384
#define CM_MAX_SIDES 8
#define CM_MAX_GREG 8
#define CM_MAX_LSQ_UNKNOWNS 484
#define CM_MAX_LSQ_BAND 69
#define CM_MAX_FACES 1048576
#define CM_MAX_EDGES 2097152
#define CM_MAX_VERTICES 2097152
#define CM_MAX_TRIS 67108864
#define CM_VIEW_MAX_W 3840
#define CM_VIEW_MAX_H 2160
#define CM_TESS_PASS_SLOTS 131072
#define CM_MAX_TESS_POINTS 65536
#define CM_MAX_FILE_BYTES 268435456
#define CM_FILE_WINDOW_BYTES CM_MAX_FILE_BYTES /* the workstation holds the file: its decoders are fed from memory */
#define CM_MAX_MODEL_CTRL 4194304
#define CM_MAX_MODEL_KNOTS 4194304
#define CM_MAX_MODEL_LOOPS 4194304
#define CM_MAX_MODEL_USES 4194304
#define CM_MAX_EDGE_SAMPLES 4096
#define CM_MAX_PLACEMENTS 65536
#define CM_STACK_FN_MAX 8192
#define CM_STACK_BUDGET 131072
/* 3.25 GiB for 3.05 GiB on x86-64 (beyond a 32-bit address space: see cm_decode_state.h) */
#define CM_DECODE_STATE_BUDGET 3489660928
#endif
