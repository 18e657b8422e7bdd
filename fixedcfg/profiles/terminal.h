/*
 * Profile `terminal`: the smallest board curvemesh ships on, a Cortex-A7
 * class ARM Linux terminal with 256 MiB of RAM shared with the viewer.
 * Its limits are exactly the defaults written (once, with their reasons)
 * in cm_limits.h; this file only names the profile.  `make print-limits
 * PROFILE=terminal` shows the effective table.
 */
#ifndef CM_PROFILE_TERMINAL_H
#define CM_PROFILE_TERMINAL_H
#define CM_PROFILE_NAME "terminal"
#endif
