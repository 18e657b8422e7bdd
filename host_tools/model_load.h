/*
 * model_load.h - the workstation's import pipeline in one call:
 * IGES or STEP file -> B-rep -> face parameter domains (loops oriented) ->
 * curve mesh.  Shared by `cmz info`, `cmz sample` and the encoder.  The
 * format is told by content (a STEP file begins with ISO-10303-21;), not
 * by the file's name.
 */
#ifndef MODEL_LOAD_H
#define MODEL_LOAD_H

#include "brep/brep.h"
#include "brep/face_domain.h"
#include "iges/iges_brep.h"
#include "iges/iges_file.h"
#include "mesh/cmesh.h"
#include "step/step_brep.h"
#include "step/step_file.h"

typedef struct loaded_model {
    iges_file iges;      /* an IGES model's file; for either format its path, warnings (iges.warn) and error (iges.err) */
    int is_step;         /* the file is STEP (ISO 10303-21, detected by content): step and step_stats hold it */
    step_file step;
    step_import_stats step_stats;
    brep_model brep;
    brep_import_stats stats;
    face_domain *fds;    /* one per face; a face whose domain failed has fds[f].uv == NULL */
    int domains_failed;
    int loops_reversed;  /* faces whose loops were re-oriented (spec §1) */
    int outer_reordered; /* faces whose outer loop was not listed first */
    int seam_joined;     /* faces bounded by loops winding around a closed surface */
    int seams_cut;       /* of those, bands cut open along their surface (brep_seam.h) */
    double max_gap;      /* largest boundary-to-surface distance seen */
    int *left_out;       /* indices into iges.warn: one warning per face left out of the model */
    int nleft_out;       /* (import, parameter domain or encoder: each names the face's entity) */
    int load_flags;      /* MODEL_LOAD_* it was loaded with */
    int instances_folded; /* placed copies folded out (MODEL_LOAD_FOLD; lm->brep.placements) */
    cmesh mesh;
    double seconds_read, seconds_brep, seconds_domains, seconds_mesh;
} loaded_model;

/** 1 if the file at path begins like a STEP file (its first 4 KB: blanks, a BOM or comments may come first). */
int model_file_is_step(const char *path);

/** Progress callback: stage name, done, total (may be NULL). */
typedef void (*model_progress)(const char *stage, int done, int total, void *ctx);

/**
 * Load a model.  On failure returns the error; lm->iges.err holds a
 * "line N: ..." message for IGES errors.  lm is always freeable.
 */
CM_NODISCARD cm_err model_load(const char *path, loaded_model *lm, model_progress progress, void *ctx,
                               cm_status *st);
/** model_load_ex flags: import blanked (hidden) entities too (model_load leaves them out) ... */
#define MODEL_LOAD_BLANKED 1
/** ... fold an assembly's placed copies out (brep_fold_instances: format 4.3 sends a part once) */
#define MODEL_LOAD_FOLD 2

/** The same, with MODEL_LOAD_* flags. */
CM_NODISCARD cm_err model_load_ex(const char *path, loaded_model *lm, int flags, model_progress progress, void *ctx,
                                  cm_status *st);

/** The same from a file already in memory, IGES or STEP (`name` is used in messages; the fuzzers use this). */
CM_NODISCARD cm_err model_load_data(const char *name, const char *data, size_t len, loaded_model *lm,
                                    model_progress progress, void *ctx, cm_status *st);

/**
 * Leave B-rep face bf out of the model: warned ("face of entity 144 (DE d): left out: why"),
 * counted in lm->left_out, removed from the B-rep (later faces move down by one) and the curve
 * mesh built again without it.  The B-rep's face orientations must be
 * the ones the face domains were built with (the encoder undoes its own turns first).
 */
CM_NODISCARD cm_err model_leave_out_face(loaded_model *lm, int bf, const char *why, cm_status *st);

/** model_load_data with MODEL_LOAD_* flags. */
CM_NODISCARD cm_err model_load_data_ex(const char *name, const char *data, size_t len, loaded_model *lm, int flags,
                                       model_progress progress, void *ctx, cm_status *st);

void model_free(loaded_model *lm);

#endif /* MODEL_LOAD_H */
