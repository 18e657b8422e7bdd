/*
 * Profile `terminal`: the smallest board curvemesh ships on, a Cortex-A7
 * class ARM Linux terminal with 256 MiB of RAM shared with the viewer.
 * Its limits are exactly the defaults written (once, with their reasons)
 * in cm_limits.h; this file only names the profile.  Since issue 15 a decode
 * takes 4 MiB of static storage in all (the file and the output mesh
 * streamed, the pools sized to the corpus's largest model with room to
 * spare), so that the terminal leaves its RAM to the viewer.  `make print-limits
 * PROFILE=terminal` shows the effective table.
 */
#ifndef CM_PROFILE_TERMINAL_H
#define CM_PROFILE_TERMINAL_H
#define CM_PROFILE_NAME "terminal"
#endif
