/*
 * cm_term_store.h - the terminal's displayed model, replaced in one atomic
 * step (docs/LINK.md "On the terminal").
 *
 * The viewer's files and the .cmz they came from must change together: a
 * power cut between two renames once left model.glb new and model.cmz old.
 * So each decoded model is built in a generation directory no viewer looks
 * at, and one rename of a symlink shows it:
 *
 *   DIR/.gen-N/model.glb, model.cmz (a hard link of the received file),
 *              model.stl (with --stl)          each synced, then the directory
 *   DIR/current -> .gen-N                      replaced by rename(2): the step
 *   DIR/model.glb -> current/model.glb         fixed symlinks: the paths the
 *   DIR/model.cmz -> current/model.cmz         viewer opens never change
 *   DIR/model.stl -> current/model.stl         (--stl)
 *
 * Whatever instant a kill or a power cut hits, `current` names a complete
 * generation (the old one until the rename, the new one after it), and so
 * every DIR/model.* resolves to files of one model.  Rename(2) cannot swap a
 * non-empty directory, and swapping files one by one is what failed: the
 * symlink is the one name whose replacement changes them all.
 *
 * The old generation is removed after the swap.  A viewer that has a file
 * open keeps reading it (its inode lives until closed); one that resolves
 * the path at that moment may see ENOENT once and should open again.
 * Needs a file system with symlinks and hard links (ext4, f2fs, btrfs, xfs;
 * not FAT).  No heap: directories are read with getdents64.
 */
#ifndef CM_TERM_STORE_H
#define CM_TERM_STORE_H

#include <stdbool.h>
#include <stdint.h>

#include "cm/cm_error.h"
#include "cm/cm_mesh.h"

#define CM_STORE_WHY 256

typedef struct cm_term_store {
    int dirfd;     /* the output directory, for the *at() calls */
    uint64_t gen;  /* the generation `current` names, 0 while there is none */
    bool stl;      /* model.stl is part of a generation */
    char why[CM_STORE_WHY]; /* what cm_term_store_open could not do */
} cm_term_store;

/**
 * Open the store in `dir` and finish what a kill left: remove generations that `current` does not
 * name (half built, or old ones not removed yet), temporary symlinks, and the part files of
 * earlier versions' writers (model.glb.part<pid>); move a model kept as plain files by an earlier
 * version (DIR/model.glb a regular file) into a generation; make the fixed symlinks.
 * @return 0, or -1 with s->why set (the directory cannot hold the layout)
 */
int cm_term_store_open(cm_term_store *s, const char *dir, bool stl);

/**
 * Show a new model: write mesh as .gen-N/model.glb (and model.stl), hard-link cmz_path (the
 * verified received file) as .gen-N/model.cmz, sync, swap `current`, then unlink cmz_path and
 * remove the old generation.  On failure nothing shown changes, the new generation is removed and
 * cmz_path stays for the caller.  *glb_bytes: the GLB's size.
 */
CM_NODISCARD cm_err cm_term_store_install(cm_term_store *s, const cm_mesh *mesh, const char *cmz_path,
                                          uint64_t *glb_bytes, cm_status *st);

void cm_term_store_close(cm_term_store *s);

#endif /* CM_TERM_STORE_H */
