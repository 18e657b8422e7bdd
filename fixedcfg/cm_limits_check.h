/*
 * cm_limits_check.h - compile-time validation of the limits in cm_limits.h.
 * Included last by cm_limits.h; do not include it directly.
 *
 * Every message names the macro and the range it must lie in, so a profile
 * author sees what to change (nanopb's FIELDINFO_DOES_NOT_FIT is the
 * counter-example).
 */
#ifndef CM_LIMITS_H
#  error "include cm_limits.h, not cm_limits_check.h"
#endif
#ifndef CM_LIMITS_CHECK_H
#define CM_LIMITS_CHECK_H

#include <float.h>
#include <stdint.h>

_Static_assert(1, "static assert works");
_Static_assert(sizeof(double) == 8 && FLT_RADIX == 2 && DBL_MANT_DIG == 53,
               "IEEE-754 binary64 double required");

/* ranges */
_Static_assert(CM_MAX_DEGREE >= 3 && CM_MAX_DEGREE <= CM_HARD_MAX_DEGREE,
               "CM_MAX_DEGREE must be in [3,15] (cubic edges and patches need 3)");
_Static_assert(CM_MAX_EDGE_CTRL >= CM_MAX_DEGREE + 1 && CM_MAX_EDGE_CTRL <= CM_HARD_MAX_COUNT16,
               "CM_MAX_EDGE_CTRL must be in [CM_MAX_DEGREE+1, 65535]");
_Static_assert(CM_MAX_SURF_CTRL_DIR >= CM_MAX_DEGREE + 1 && CM_MAX_SURF_CTRL_DIR <= CM_HARD_MAX_COUNT16,
               "CM_MAX_SURF_CTRL_DIR must be in [CM_MAX_DEGREE+1, 65535]");
_Static_assert(CM_MAX_SURF_CTRL >= (CM_MAX_DEGREE + 1) * (CM_MAX_DEGREE + 1) &&
                   CM_MAX_SURF_CTRL <= CM_HARD_MAX_COUNT24,
               "CM_MAX_SURF_CTRL must be in [(CM_MAX_DEGREE+1)^2, 16777215]");
_Static_assert(CM_MAX_FIT_CTRL >= 4 && CM_MAX_FIT_CTRL <= CM_HARD_MAX_FIT_CTRL,
               "CM_MAX_FIT_CTRL must be in [4,35]");
_Static_assert(CM_MAX_FIT_CTRL <= CM_MAX_SURF_CTRL_DIR,
               "CM_MAX_FIT_CTRL must be <= CM_MAX_SURF_CTRL_DIR (a fitted surface is a surface)");
_Static_assert(CM_MAX_LOOPS >= 1 && CM_MAX_LOOPS <= CM_HARD_MAX_COUNT16,
               "CM_MAX_LOOPS must be in [1,65535]");
_Static_assert(CM_MAX_LOOP_EDGES >= 3 && CM_MAX_LOOP_EDGES <= CM_HARD_MAX_COUNT16,
               "CM_MAX_LOOP_EDGES must be in [3,65535]");
_Static_assert(CM_MAX_FACE_EDGES >= CM_MAX_LOOP_EDGES && CM_MAX_FACE_EDGES <= CM_HARD_MAX_COUNT16,
               "CM_MAX_FACE_EDGES must be in [CM_MAX_LOOP_EDGES, 65535]");
_Static_assert(CM_MAX_SIDES >= 3 && CM_MAX_SIDES <= CM_HARD_MAX_SIDES,
               "CM_MAX_SIDES must be in [3,8]");
_Static_assert(CM_MAX_SIDES <= CM_MAX_LOOP_EDGES,
               "CM_MAX_SIDES must be <= CM_MAX_LOOP_EDGES");
_Static_assert(CM_MAX_GREG >= CM_MAX_SIDES && CM_MAX_GREG <= CM_HARD_MAX_GREG,
               "CM_MAX_GREG must be in [CM_MAX_SIDES,16] (an N-split face needs N patches)");
_Static_assert(CM_MAX_LSQ_UNKNOWNS >= 4 && CM_MAX_LSQ_UNKNOWNS <= CM_HARD_MAX_LSQ_UNKNOWNS,
               "CM_MAX_LSQ_UNKNOWNS must be in [4,1089]");
_Static_assert(CM_MAX_LSQ_BAND >= 6 && CM_MAX_LSQ_BAND <= CM_HARD_MAX_LSQ_BAND,
               "CM_MAX_LSQ_BAND must be in [6,102]");
_Static_assert(CM_MAX_LSQ_BAND >= 3 * (CM_MAX_FIT_CTRL - 2) + 3,
               "CM_MAX_LSQ_BAND must be >= 3*(CM_MAX_FIT_CTRL-2)+3 (spec 8.7 band of the widest fit)");
_Static_assert(CM_MAX_LSQ_UNKNOWNS >= (CM_MAX_FIT_CTRL - 2) * (CM_MAX_FIT_CTRL - 2),
               "CM_MAX_LSQ_UNKNOWNS must be >= (CM_MAX_FIT_CTRL-2)^2 (unknowns of the largest fit)");
_Static_assert(CM_MAX_FACES >= 1 && CM_MAX_FACES <= CM_HARD_MAX_COUNT24,
               "CM_MAX_FACES must be in [1,16777215]");
_Static_assert(CM_MAX_EDGES >= 1 && CM_MAX_EDGES <= CM_HARD_MAX_COUNT24,
               "CM_MAX_EDGES must be in [1,16777215]");
_Static_assert(CM_MAX_VERTICES >= 1 && CM_MAX_VERTICES <= CM_HARD_MAX_COUNT24,
               "CM_MAX_VERTICES must be in [1,16777215]");
_Static_assert(CM_MAX_TRIS >= 1 && CM_MAX_TRIS <= CM_HARD_MAX_TRIS,
               "CM_MAX_TRIS must be in [1,1431655765] (3*tris indices must fit uint32)");
_Static_assert(CM_MAX_TESS_POINTS >= 16 && CM_MAX_TESS_POINTS <= CM_HARD_MAX_COUNT24,
               "CM_MAX_TESS_POINTS must be in [16,16777215]");
_Static_assert(CM_MAX_FILE_BYTES >= 256 && CM_MAX_FILE_BYTES <= 2147483647,
               "CM_MAX_FILE_BYTES must be in [256, 2^31-1]");
_Static_assert(CM_MAX_MODEL_CTRL >= CM_MAX_EDGE_CTRL && CM_MAX_MODEL_CTRL <= CM_HARD_MAX_COUNT24,
               "CM_MAX_MODEL_CTRL must be in [CM_MAX_EDGE_CTRL, 16777215]");
_Static_assert(CM_MAX_MODEL_KNOTS >= CM_MAX_EDGE_KNOTS && CM_MAX_MODEL_KNOTS <= CM_HARD_MAX_COUNT24,
               "CM_MAX_MODEL_KNOTS must be in [CM_MAX_EDGE_KNOTS, 16777215]");
_Static_assert(CM_MAX_MODEL_LOOPS >= CM_MAX_LOOPS && CM_MAX_MODEL_LOOPS <= CM_HARD_MAX_COUNT24,
               "CM_MAX_MODEL_LOOPS must be in [CM_MAX_LOOPS, 16777215]");
_Static_assert(CM_MAX_MODEL_USES >= CM_MAX_FACE_EDGES && CM_MAX_MODEL_USES <= CM_HARD_MAX_COUNT24,
               "CM_MAX_MODEL_USES must be in [CM_MAX_FACE_EDGES, 16777215]");
_Static_assert(CM_TESS_PASS_SLOTS >= 2 && CM_TESS_PASS_SLOTS <= (1 << 24) &&
                   (CM_TESS_PASS_SLOTS & (CM_TESS_PASS_SLOTS - 1)) == 0,
               "CM_TESS_PASS_SLOTS must be a power of two in [2, 2^24]");
_Static_assert(CM_MAX_TESS_POINTS < (1 << 21), "the refinement's pass keys hold a point index in 21 bits");
_Static_assert(CM_MAX_EDGE_SAMPLES >= 2 && CM_MAX_EDGE_SAMPLES <= CM_HARD_MAX_COUNT16,
               "CM_MAX_EDGE_SAMPLES must be in [2, 65535]");
_Static_assert(CM_MAX_PLACEMENTS >= 0 && CM_MAX_PLACEMENTS <= CM_HARD_MAX_COUNT24,
               "CM_MAX_PLACEMENTS must be in [0, 16777215]");
_Static_assert(CM_STACK_FN_MAX >= 1024 && CM_STACK_FN_MAX <= CM_STACK_BUDGET,
               "CM_STACK_FN_MAX must be in [1024, CM_STACK_BUDGET]");
_Static_assert(CM_STACK_BUDGET <= CM_HARD_MAX_STACK,
               "CM_STACK_BUDGET must be <= 1048576");
_Static_assert(CM_FILE_WINDOW_BYTES >= 4096 && CM_FILE_WINDOW_BYTES <= CM_MAX_FILE_BYTES,
               "CM_FILE_WINDOW_BYTES must be in [4096 (a header, held whole), CM_MAX_FILE_BYTES]");
_Static_assert(CM_SPILL_PAGE_BYTES >= 12, "CM_SPILL_PAGE_BYTES must hold a vertex (12 bytes)");
_Static_assert(CM_SPILL_PAGES >= 1 && CM_SPILL_PAGES <= 64, "CM_SPILL_PAGES must be in [1, 64]");

/* storage products must not overflow size_t on a 32-bit board */
_Static_assert((unsigned long long)CM_MAX_LSQ_UNKNOWNS * (CM_MAX_LSQ_BAND + 1) * sizeof(double) <= SIZE_MAX / 4,
               "CM_MAX_LSQ_UNKNOWNS*(CM_MAX_LSQ_BAND+1) doubles overflow size_t");
_Static_assert((unsigned long long)CM_MAX_SURF_CTRL * 4 * sizeof(double) <= SIZE_MAX / 4,
               "CM_MAX_SURF_CTRL homogeneous control points overflow size_t");

#endif /* CM_LIMITS_CHECK_H */
