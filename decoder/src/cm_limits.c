/* cm_limits.c - the run-time limits table, generated from cm_limits_list.h. */
#include "cm/cm_limits_info.h"

#include <stddef.h>

#define CM_LIMIT_ROW_(id, value, hard, unit, doc) {#id, "CM_" #id, (uint32_t)(value), (uint32_t)(hard), unit, doc},
const cm_limit_info cm_limit_table[CM_LIMIT_COUNT] = {CM_LIMITS(CM_LIMIT_ROW_)};
#undef CM_LIMIT_ROW_

const char cm_profile_name[] = CM_PROFILE_NAME;

const cm_limit_info *cm_limit_get(unsigned id)
{
    return id < (unsigned)CM_LIMIT_COUNT ? &cm_limit_table[id] : NULL;
}
