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

typedef struct cm_limit_info {
    const char *name;  /* "MAX_FACES" */
    const char *macro; /* "CM_MAX_FACES" */
    uint32_t value;    /* this build's value */
    uint32_t hard_max; /* format/type ceiling */
    const char *unit;  /* "faces" */
    const char *doc;   /* one line */
} cm_limit_info;

extern const cm_limit_info cm_limit_table[CM_LIMIT_COUNT];

/** Name of the profile this code was compiled with ("terminal", "host", "tiny"). */
extern const char cm_profile_name[];

/** Row of limit `id`, or NULL if `id` is out of range. */
const cm_limit_info *cm_limit_get(unsigned id);

#endif /* CM_LIMITS_INFO_H */
