/*
 * cm_kill_point.h - fault injection for cmz-terminal's storing of a model.
 *
 * cm_kill_point("glb-written") ends the process with SIGKILL, as a power
 * cut or `kill -9` would, when the environment variable CM_TERM_KILL_AT
 * names that step; otherwise it does nothing.  tests/link/check_store_kill.sh
 * stops the terminal at every step in turn and checks what a restart finds,
 * so that no step is left where a kill leaves the directory inconsistent.
 *
 * It is in every build, not only in test builds: the binary that is tested
 * is the one that ships.  It costs a getenv per step of storing a model, and
 * nothing but this variable triggers it.  The steps, in order
 * (docs/LINK.md "On the terminal"):
 *   part-created        .incoming.part created for a new transfer (empty)
 *   incoming-mid-write  half of the file received into .incoming.part
 *   incoming-renamed    the verified file is .incoming.cmz, DONE "stored" sent
 *   gen-created         the next generation directory .gen-N exists (empty)
 *   stl-created, stl-written, stl-closed    model.stl in .gen-N (--stl only):
 *                       created, its first bytes written, synced and closed
 *   glb-created, glb-written, glb-closed    the same for model.glb
 *   cmz-linked          .incoming.cmz hard-linked as .gen-N/model.cmz
 *   gen-synced          .gen-N complete and synced, not yet shown
 *   link-created        the symlink .current.new -> .gen-N created
 *   swapped             .current.new renamed over `current`: the new model shows
 *   incoming-removed    .incoming.cmz unlinked
 *   old-removing        the old generation half removed
 *   old-removed         the old generation gone
 */
#ifndef CM_KILL_POINT_H
#define CM_KILL_POINT_H

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static inline void cm_kill_point(const char *step)
{
    const char *at = getenv("CM_TERM_KILL_AT");
    if (!at || strcmp(at, step) != 0)
        return;
    fprintf(stderr, "cmz-terminal: level=warn event=kill-point step=%s\n", step);
    fflush(stderr);
    raise(SIGKILL);
}

#endif /* CM_KILL_POINT_H */
