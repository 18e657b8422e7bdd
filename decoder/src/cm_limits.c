/* cm_limits.c - the run-time limits table, generated from cm_limits_list.h. */
#include "cm/cm_limits_info.h"

#include <stddef.h>

const cm_limit_info cm_limit_table[CM_LIMIT_COUNT] = {CM_LIMITS(CM_LIMIT_INFO_ROW)};
/* each text with its 0 byte within its array (a literal exactly as long as the array would lose it) */
#define CM_LIMIT_FITS_(id, value, hard, unit, doc)                                                         \
    _Static_assert(sizeof(#id) <= CM_LIMIT_NAME_CHARS && sizeof(unit) <= CM_LIMIT_UNIT_CHARS &&            \
                       sizeof(doc) <= CM_LIMIT_DOC_CHARS,                                                  \
                   "limit " #id ": a text longer than cm_limit_info holds");
CM_LIMITS(CM_LIMIT_FITS_)
#undef CM_LIMIT_FITS_

const char cm_profile_name[] = CM_PROFILE_NAME;

const cm_limit_info *cm_limit_get(unsigned id)
{
    return id < (unsigned)CM_LIMIT_COUNT ? &cm_limit_table[id] : NULL;
}
