/*
 * gregory_exact.c - GREGORY-EXACT (docs/METHODS.md, format 2.1): GREGORY's
 * layouts and record, but every patch side on the face's loop is the edge
 * itself (cm_egreg.h, cm_egregface.c) instead of a cubic within K7 of it.
 * Full and half circles and multi-span B-spline edges no longer keep a face
 * (issue 13: they kept 11314 of 12152 kept faces), and a face whose true
 * surface is linear in one direction between two curved edges (cylinder,
 * cone band, extrusion) comes back exactly.  The record is GREGORY's:
 * layout, corner, and the checksum of the rebuilt patches.
 */
#include "cm/cm_limits_info.h"
#include "cm_method_impl.h"

cm_err cm_gregory_exact_rebuild(const cm_model *m, uint32_t f, int check, cm_rebuilt *out, cm_rebuild_ws *ws,
                                cm_status *st)
{
    return cm_gregory_family_rebuild(m, f, check, 1, 0, out, ws, st);
}

const cm_method cm_method_gregory_exact = {
    .name = "gregory-exact",
    .counted = "gregory-exact",
    .id = CM_METHOD_GREGORY_EXACT,
    .since_major = 2,
    .since_minor = 1,
    .has_record = 1,
    .layouts = 4,
    .too_new = "GREGORY-EXACT face in a file older than format 2.1",
};
