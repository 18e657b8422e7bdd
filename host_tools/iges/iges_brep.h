/*
 * iges_brep.h - an IGES file's faces into the format-neutral B-rep
 * (brep.h): trimmed surfaces (144), bounded surfaces (143) and the B-rep
 * solids' faces (510), subfigure instances (408) expanded.
 */
#ifndef IGES_BREP_H
#define IGES_BREP_H

#include "brep/brep.h"
#include "iges/iges_file.h"

/** Counts per kind of IGES input, for `cmz info`. */
typedef struct brep_import_stats {
    int faces_144, faces_143, faces_510, faces_untrimmed;
    int instances;        /* expanded 408 subfigure instances */
    int face_entities;    /* distinct 144/143/510 entities imported (instances place some several times) */
    int blanked_entities; /* blanked (hidden) entities not imported, that would have placed faces ... */
    long long blanked_faces; /* ... this many */
} brep_import_stats;

/**
 * Import every face of an IGES file into m (model space, millimetres).
 * A face that cannot be built is skipped with a warning in f->warn naming
 * its entity and line; the import fails only on errors that leave no
 * usable model (none of the file's faces could be read).  Blanked (hidden)
 * entities are left out, each with a warning, unless include_blanked (or
 * unless every face of the file is blanked).
 */
CM_NODISCARD cm_err iges_to_brep(iges_file *f, brep_model *m, brep_import_stats *stats, int include_blanked,
                                 cm_status *st);

#endif /* IGES_BREP_H */
