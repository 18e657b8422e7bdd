/*
 * profile_table.c - the limits table of one board profile, compiled once
 * per profile (-DCM_PROFILE=... -DPROFILE_TABLE=cm_profile_table_<name>)
 * and linked into the workstation tools, so `cmz encode --profile terminal`
 * checks a file against the terminal's real limits, from the same X-macro
 * list the terminal is built from.
 */
#include "cm/cm_limits_info.h"

#ifndef PROFILE_TABLE
#error "compile with -DPROFILE_TABLE=cm_profile_table_<profile>"
#endif

extern const cm_limit_info PROFILE_TABLE[CM_LIMIT_COUNT];
const cm_limit_info PROFILE_TABLE[CM_LIMIT_COUNT] = {CM_LIMITS(CM_LIMIT_INFO_ROW)};
