/* cm_term_store.c - the displayed model in generations behind one symlink (see cm_term_store.h). */
#define _GNU_SOURCE /* getdents64: reading a directory without opendir's heap */
#include "cm_term_store.h"
#include "cm_report.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cm_decode_file.h"
#include "cm_kill_point.h"

#define GEN_PREFIX ".gen-"
#define CURRENT "current"
#define CURRENT_NEW ".current.new"

/* the files of a generation, and the fixed symlinks DIR/NAME -> current/NAME of the same names */
static const char *const outputs[] = {"model.glb", "model.cmz", "model.stl"};
#define STL_OUTPUT 2


static void gen_name(char *out, size_t cap, uint64_t n)
{
    snprintf(out, cap, GEN_PREFIX "%llu", (unsigned long long)n);
}

/* n of ".gen-<n>" (n >= 1, plain decimal), 0 for any other name */
static uint64_t gen_number(const char *name)
{
    if (strncmp(name, GEN_PREFIX, strlen(GEN_PREFIX)) != 0)
        return 0;
    const char *p = name + strlen(GEN_PREFIX);
    uint64_t n = 0;
    size_t len = strlen(p);
    if (len == 0 || len > 19 || p[0] == '0')
        return 0;
    for (; *p; p++) {
        if (*p < '0' || *p > '9')
            return 0;
        n = n * 10u + (uint64_t)(*p - '0');
    }
    return n;
}

/* the generation `current` names, if it is a directory; 0 otherwise */
static uint64_t read_current(int dirfd)
{
    char target[64];
    ssize_t r = readlinkat(dirfd, CURRENT, target, sizeof target);
    if (r <= 0 || (size_t)r >= sizeof target)
        return 0;
    target[r] = '\0';
    uint64_t n = gen_number(target);
    struct stat s;
    if (n == 0 || fstatat(dirfd, target, &s, AT_SYMLINK_NOFOLLOW) != 0 || !S_ISDIR(s.st_mode))
        return 0;
    return n;
}

/*
 * A directory read entry by entry (getdents64, no heap).  Entries unlinked while a directory is
 * read may make the reader skip others, so a caller that removes entries reads it again until a
 * whole pass removes nothing (at most DIR_PASSES).  No callback: the walks nest (the store's walk
 * removes a generation, whose own walk removes its files), and a call through a pointer would hide
 * that bound from the stack gate (make check-stack-programs).
 */
enum { DIR_PASSES = 64 };

typedef struct dir_reader {
    int fd;
    ssize_t n, at; /* bytes in buf, and the next entry's offset */
    _Alignas(struct dirent64) char buf[4096];
} dir_reader;

/* start a pass over fd's entries; false if the directory cannot be read again */
static bool dir_rewind(dir_reader *r, int fd)
{
    r->fd = fd;
    r->n = r->at = 0;
    return lseek(fd, 0, SEEK_SET) == 0;
}

/* the pass's next entry but . and .. (its type in *type), or NULL at its end */
static const char *dir_next(dir_reader *r, unsigned char *type)
{
    for (;;) {
        if (r->at >= r->n) {
            r->n = getdents64(r->fd, r->buf, sizeof r->buf);
            r->at = 0;
            if (r->n <= 0)
                return NULL;
        }
        const struct dirent64 *d = (const struct dirent64 *)(const void *)(r->buf + r->at);
        r->at += d->d_reclen;
        if (strcmp(d->d_name, ".") != 0 && strcmp(d->d_name, "..") != 0) {
            *type = d->d_type;
            return d->d_name;
        }
    }
}

typedef struct gen_removal {
    int fd;
    bool kill_steps; /* the old generation after a swap: a kill point midway */
    unsigned removed;
} gen_removal;

static bool unlink_in_gen(gen_removal *g, const char *name, unsigned char type)
{
    (void)type;
    if (unlinkat(g->fd, name, 0) != 0)
        return false;
    if (g->removed++ == 0 && g->kill_steps)
        cm_kill_point("old-removing");
    return true;
}

/* remove generation directory `name` and its files (best effort: what stays is removed at the next start) */
static void remove_gen(int dirfd, const char *name, bool kill_steps)
{
    gen_removal g = {openat(dirfd, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC), kill_steps, 0};
    if (g.fd >= 0) {
        dir_reader r;
        for (int pass = 0; pass < DIR_PASSES && dir_rewind(&r, g.fd); pass++) {
            bool removed = false;
            unsigned char type;
            for (const char *entry; (entry = dir_next(&r, &type));)
                removed |= unlink_in_gen(&g, entry, type);
            if (!removed)
                break;
        }
        close(g.fd);
    }
    unlinkat(dirfd, name, AT_REMOVEDIR);
}

/* "model.glb.part1234": cm_write_mesh's temporary file, left by an earlier version killed while writing */
static bool is_writer_part(const char *name)
{
    if (strncmp(name, "model.", 6) != 0)
        return false;
    const char *p = strstr(name, ".part");
    if (!p || !p[5])
        return false;
    for (p += 5; *p; p++)
        if (*p < '0' || *p > '9')
            return false;
    return true;
}

/* ".current.new", ".model.glb.new": a symlink made to be renamed into place */
static bool is_temp_link(const char *name)
{
    size_t n = strlen(name);
    return strcmp(name, CURRENT_NEW) == 0 ||
           (strncmp(name, ".model.", 7) == 0 && n > 4 && strcmp(name + n - 4, ".new") == 0);
}

static bool clean_entry(cm_term_store *s, const char *name, unsigned char type)
{
    if (strncmp(name, GEN_PREFIX, strlen(GEN_PREFIX)) == 0) {
        if (gen_number(name) == s->gen && s->gen != 0)
            return false;
        if (type == DT_DIR || type == DT_UNKNOWN)
            remove_gen(s->dirfd, name, false);
        if (type != DT_DIR)
            unlinkat(s->dirfd, name, 0);
        struct stat gone;
        return fstatat(s->dirfd, name, &gone, AT_SYMLINK_NOFOLLOW) != 0;
    }
    if (is_writer_part(name) || is_temp_link(name))
        return unlinkat(s->dirfd, name, 0) == 0;
    return false;
}

/* symlink `target` at `name`, replacing what is there in one rename */
static int replace_link(int dirfd, const char *target, const char *name, const char *tmp)
{
    unlinkat(dirfd, tmp, 0);
    if (symlinkat(target, dirfd, tmp) != 0)
        return -1;
    if (renameat(dirfd, tmp, dirfd, name) != 0) {
        unlinkat(dirfd, tmp, 0);
        return -1;
    }
    return 0;
}

/* DIR/NAME -> current/NAME for each output (model.stl only with --stl); dangling until a first model */
static int ensure_links(cm_term_store *s)
{
    bool changed = false;
    for (int i = 0; i < 3; i++) {
        char want[32], have[64], tmp[32];
        snprintf(want, sizeof want, CURRENT "/%s", outputs[i]);
        ssize_t r = readlinkat(s->dirfd, outputs[i], have, sizeof have - 1);
        bool ours = r > 0 && (size_t)r == strlen(want) && memcmp(have, want, (size_t)r) == 0;
        if (i == STL_OUTPUT && !s->stl) {
            /* without --stl new generations have no model.stl: the link would name nothing */
            if (ours && unlinkat(s->dirfd, outputs[i], 0) == 0)
                changed = true;
            continue;
        }
        if (ours)
            continue;
        snprintf(tmp, sizeof tmp, ".%s.new", outputs[i]);
        if (replace_link(s->dirfd, want, outputs[i], tmp) != 0) {
            snprintf(s->why, sizeof s->why, "cannot make the symlink %s -> %s: %s", outputs[i], want, strerror(errno));
            return -1;
        }
        changed = true;
    }
    return changed ? fsync(s->dirfd) : 0;
}

/* make generation n what `current` names: the one atomic step */
static cm_err swap(cm_term_store *s, uint64_t n, cm_status *st)
{
    char target[32];
    gen_name(target, sizeof target, n);
    unlinkat(s->dirfd, CURRENT_NEW, 0);
    if (symlinkat(target, s->dirfd, CURRENT_NEW) != 0)
        return cm_fail_errno(st, "store: symlink " CURRENT_NEW);
    cm_kill_point("link-created");
    if (renameat(s->dirfd, CURRENT_NEW, s->dirfd, CURRENT) != 0) {
        cm_err e = cm_fail_errno(st, "store: rename " CURRENT_NEW " over " CURRENT);
        unlinkat(s->dirfd, CURRENT_NEW, 0);
        return e;
    }
    cm_kill_point("swapped");
    s->gen = n;
    /* the rename is done and the viewer sees the new model: a failed sync of the directory only
       means a power cut may bring the old one back, which is still one whole model */
    (void)fsync(s->dirfd);
    return CM_OK;
}

/* a model kept by an earlier version as plain files DIR/model.*: into generation 1 (hard links) */
static int migrate(cm_term_store *s)
{
    struct stat st;
    if (fstatat(s->dirfd, "model.glb", &st, AT_SYMLINK_NOFOLLOW) != 0 || !S_ISREG(st.st_mode))
        return 0;
    uint64_t n = s->gen + 1;
    char name[32];
    gen_name(name, sizeof name, n);
    remove_gen(s->dirfd, name, false);
    int g = -1;
    if (mkdirat(s->dirfd, name, 0755) != 0 || (g = openat(s->dirfd, name, O_RDONLY | O_DIRECTORY | O_CLOEXEC)) < 0)
        goto fail;
    for (int i = 0; i < 3; i++) {
        if (i == STL_OUTPUT && !s->stl)
            continue;
        /* AT_SYMLINK_FOLLOW: a name that is already our symlink contributes the file it shows */
        if (linkat(s->dirfd, outputs[i], g, outputs[i], AT_SYMLINK_FOLLOW) != 0 && errno != ENOENT)
            goto fail;
    }
    if (fsync(g) != 0)
        goto fail;
    close(g);
    g = -1;
    uint64_t old = s->gen;
    cm_status cs;
    cm_status_init(&cs);
    if (swap(s, n, &cs) != CM_OK) {
        errno = cs.sys_errno;
        goto fail;
    }
    if (old != 0) { /* the generation a newer version had shown before an older one wrote plain files */
        char old_name[32];
        gen_name(old_name, sizeof old_name, old);
        remove_gen(s->dirfd, old_name, false);
    }
    return 0;
fail:
    snprintf(s->why, sizeof s->why, "cannot move the model into %s: %s", name, strerror(errno));
    if (g >= 0)
        close(g);
    if (s->gen != n)
        remove_gen(s->dirfd, name, false);
    return -1;
}

int cm_term_store_open(cm_term_store *s, const char *dir, bool stl)
{
    memset(s, 0, sizeof *s);
    s->stl = stl;
    s->dirfd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (s->dirfd < 0) {
        snprintf(s->why, sizeof s->why, "cannot open %s: %s", dir, strerror(errno));
        return -1;
    }
    s->gen = read_current(s->dirfd);
    dir_reader r;
    for (int pass = 0; pass < DIR_PASSES && dir_rewind(&r, s->dirfd); pass++) {
        bool removed = false;
        unsigned char type;
        for (const char *entry; (entry = dir_next(&r, &type));)
            removed |= clean_entry(s, entry, type);
        if (!removed)
            break;
    }
    if (migrate(s) != 0 || ensure_links(s) != 0) {
        close(s->dirfd);
        s->dirfd = -1;
        return -1;
    }
    if (fsync(s->dirfd) != 0) {
        snprintf(s->why, sizeof s->why, "cannot sync %s: %s", dir, strerror(errno));
        close(s->dirfd);
        s->dirfd = -1;
        return -1;
    }
    return 0;
}

/* cm_write_mesh_at's progress as kill points: "glb-created", "stl-written", ... */
static void write_step(void *ctx, const char *step)
{
    char name[32];
    snprintf(name, sizeof name, "%s-%s", (const char *)ctx, step);
    cm_kill_point(name);
}

cm_err cm_term_store_install(cm_term_store *s, const cm_mesh *mesh, const char *cmz_path, uint64_t *glb_bytes,
                             cm_status *st)
{
    uint64_t old = s->gen, n = s->gen + 1;
    char name[32], old_name[32];
    gen_name(name, sizeof name, n);
    gen_name(old_name, sizeof old_name, old);
    remove_gen(s->dirfd, name, false); /* an earlier install that failed midway */
    if (mkdirat(s->dirfd, name, 0755) != 0)
        return cm_fail_errno(st, "store: create the generation directory");
    cm_kill_point("gen-created");
    cm_err e = CM_OK;
    int g = openat(s->dirfd, name, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (g < 0)
        e = cm_fail_errno(st, "store: open the generation directory");
    if (e == CM_OK && s->stl)
        e = cm_write_mesh_at(mesh, CM_OUT_STL, g, "model.stl", NULL, write_step, "stl", st);
    if (e == CM_OK)
        e = cm_write_mesh_at(mesh, CM_OUT_GLB, g, "model.glb", glb_bytes, write_step, "glb", st);
    /* a hard link, not a copy: no second copy of the bytes to write, and until the swap the
       received file stays at cmz_path for a restart to finish */
    if (e == CM_OK && linkat(AT_FDCWD, cmz_path, g, "model.cmz", 0) != 0)
        e = cm_fail_errno(st, "store: link the received file into the generation");
    if (e == CM_OK)
        cm_kill_point("cmz-linked");
    if (e == CM_OK && fsync(g) != 0)
        e = cm_fail_errno(st, "store: sync the generation directory");
    if (e == CM_OK)
        cm_kill_point("gen-synced");
    if (g >= 0)
        close(g);
    if (e == CM_OK)
        e = swap(s, n, st);
    if (s->gen != n) {
        remove_gen(s->dirfd, name, false);
        return e;
    }
    /* shown: the rest is tidying up, and what a kill leaves of it cm_term_store_open removes */
    unlink(cmz_path);
    cm_kill_point("incoming-removed");
    if (old != 0) {
        remove_gen(s->dirfd, old_name, true);
        cm_kill_point("old-removed");
    }
    (void)fsync(s->dirfd);
    return CM_OK;
}

void cm_term_store_close(cm_term_store *s)
{
    if (s->dirfd >= 0)
        close(s->dirfd);
    s->dirfd = -1;
}
