/*
 * cm_limits_info.h - the run-time view of fixedcfg/cm_limits.h.
 *
 * cm_limit_info[] holds one row per limit of cm_limits_list.h, in list
 * order (the order is the limit id, also on the wire).  Binaries print it
 * for `--limits`; the file header and the link HELLO carry values indexed
 * by these ids.
 */
#ifndef CM_LIMITS_INFO_H
#define CM_LIMITS_INFO_H

#include <stdint.h>

#include "cm_limits_list.h"

#define CM_LIMIT_ENUM_(id, value, hard, unit, doc) CM_LIMIT_##id,
typedef enum cm_limit_id { CM_LIMITS(CM_LIMIT_ENUM_) CM_LIMIT_COUNT } cm_limit_id;
#undef CM_LIMIT_ENUM_

/* The texts are arrays in the row, not pointers: a pointer in a position-independent program is
   a relocation the loader applies (24 bytes each on aarch64, 104 here: 2.5 KB of the terminal's
   read-only 256 KiB).  cm_limits.c refuses a text that does not fit with its 0 byte. */
#define CM_LIMIT_NAME_CHARS 18 /* name and its 0 (the longest now: MAX_SURF_CTRL_DIR) */
#define CM_LIMIT_UNIT_CHARS 10
#define CM_LIMIT_DOC_CHARS 64
typedef struct cm_limit_info {
    uint32_t value;                 /* this build's value */
    uint32_t hard_max;              /* format/type ceiling */
    char name[CM_LIMIT_NAME_CHARS]; /* "MAX_FACES" (its macro: "CM_" and the name) */
    char unit[CM_LIMIT_UNIT_CHARS]; /* "faces" */
    char doc[CM_LIMIT_DOC_CHARS];   /* one line */
} cm_limit_info;

/* one row of a limits table from a CM_LIMITS entry (this build's cm_limit_table and the
   workstation's per-profile copies, host_tools/profile_table.c: one layout for both) */
#define CM_LIMIT_INFO_ROW(id, value, hard, unit, doc) {(uint32_t)(value), (uint32_t)(hard), #id, unit, doc},

extern const cm_limit_info cm_limit_table[CM_LIMIT_COUNT];

/** Name of the profile this code was compiled with ("terminal", "host", "tiny"). */
extern const char cm_profile_name[];

/** Row of limit `id`, or NULL if `id` is out of range. */
const cm_limit_info *cm_limit_get(unsigned id);

#endif /* CM_LIMITS_INFO_H */
