/*
 * profiles.h - every board profile's limits table inside the workstation
 * tools (see profile_table.c), to check files against a target board.
 */
#ifndef PROFILES_H
#define PROFILES_H

#include "cm/cm_limits_info.h"

extern const cm_limit_info cm_profile_table_terminal[CM_LIMIT_COUNT];
extern const cm_limit_info cm_profile_table_host[CM_LIMIT_COUNT];
extern const cm_limit_info cm_profile_table_tiny[CM_LIMIT_COUNT];

/** The table of a profile by name ("terminal", "host", "tiny"), or NULL. */
static inline const cm_limit_info *cm_profile_limits(const char *name)
{
    if (!name)
        return 0;
    if (name[0] == 't' && name[1] == 'e')
        return cm_profile_table_terminal;
    if (name[0] == 'h')
        return cm_profile_table_host;
    if (name[0] == 't' && name[1] == 'i')
        return cm_profile_table_tiny;
    return 0;
}

#endif /* PROFILES_H */
