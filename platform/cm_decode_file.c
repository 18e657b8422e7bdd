/* cm_decode_file.c - .cmz -> mesh -> file with POSIX I/O and no heap (see cm_decode_file.h). */
#define _POSIX_C_SOURCE 200809L
#include "cm_decode_file.h"
#include "cm_report.h"

#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

static int ends_with(const char *s, const char *suffix)
{
    size_t a = strlen(s), b = strlen(suffix);
    if (a < b)
        return 0;
    for (size_t i = 0; i < b; i++) {
        char c = s[a - b + i];
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
        if (c != suffix[i])
            return 0;
    }
    return 1;
}

int cm_out_format_of(const char *path)
{
    if (ends_with(path, ".glb"))
        return CM_OUT_GLB;
    if (ends_with(path, ".stl"))
        return CM_OUT_STL;
    if (ends_with(path, ".obj"))
        return CM_OUT_OBJ;
    return -1;
}


/* The file's bytes on their way to the decoder, and the serialiser's on their way to a file: static,
 * not on the stack, so that a terminal program's deepest call path stays within
 * CM_STACK_PROGRAM_BUDGET (make check-stack-programs).  A program reads or writes one file at a
 * time (the terminal, cmz decode and cmz eval are single-threaded). */
static uint8_t read_chunk[16384];
static uint8_t write_chunk[65536];

/* all n bytes at off, read (or written); 0, or -1 on an error or an early end */
static int full_io(int fd, int write, uint64_t off, uint8_t *p, size_t n)
{
    if (off > (uint64_t)INT64_MAX - n)
        return -1;
    while (n > 0) {
        ssize_t k = write ? pwrite(fd, p, n, (off_t)off) : pread(fd, p, n, (off_t)off);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0)
            return -1;
        p += k;
        off += (uint64_t)k;
        n -= (size_t)k;
    }
    return 0;
}

/* cm_dec_read_fn over a file descriptor (ctx points at it): a long file's sections read again */
int cm_decode_pread(void *ctx, uint32_t off, uint8_t *buf, size_t n)
{
    return full_io(*(const int *)ctx, 0, off, buf, n);
}

cm_err cm_decode_read(const char *in_path, cm_decoder *dec, cm_status *st)
{
    cm_dec_init(dec);
    static int fd; /* the source's context: the decoder reads the file again through it */
    fd = open(in_path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return cm_fail_errno(st, "open");
    cm_dec_set_source(dec, cm_decode_pread, &fd);
    cm_err e = CM_OK;
    for (;;) {
        ssize_t n = read(fd, read_chunk, sizeof read_chunk);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            e = cm_fail_errno(st, "read");
            break;
        }
        if (n == 0)
            break;
        if ((e = cm_dec_feed(dec, read_chunk, (size_t)n, st)) != CM_OK)
            break;
    }
    if (e == CM_OK)
        e = cm_dec_finish(dec, st);
    close(fd);
    return e;
}

/* ---- the output mesh's spill (issue 15): three unlinked files in the output's directory ---- */

typedef struct spill_files {
    char dir[4096];            /* where the files go: the output's directory */
    int fd[CM_SPILL_STREAMS];  /* opened at the first spill; -1 before */
} spill_files;

static spill_files spill_fs = {"", {-1, -1, -1}};

/* an unlinked read-write file in spill_fs.dir: O_TMPFILE where the file system has it, else a named
   file removed at once (nothing is left behind when the program dies) */
static int open_spill_file(void)
{
    int dirfd = open(spill_fs.dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dirfd < 0)
        return -1;
    int fd = -1;
#ifdef O_TMPFILE
    fd = openat(dirfd, ".", O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
#endif
    for (int k = 0; fd < 0 && k < 64; k++) {
        char name[64];
        snprintf(name, sizeof name, ".cmz-spill-%ld-%d", (long)getpid(), k);
        fd = openat(dirfd, name, O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
        if (fd >= 0)
            unlinkat(dirfd, name, 0);
        else if (errno != EEXIST)
            break;
    }
    close(dirfd);
    return fd;
}

static int spill_file_io(void *ctx, int write, unsigned s, uint64_t off, void *buf, size_t n)
{
    spill_files *sf = ctx;
    if (s >= CM_SPILL_STREAMS)
        return -1;
    if (sf->fd[s] < 0 && (!write || (sf->fd[s] = open_spill_file()) < 0))
        return -1;
    return full_io(sf->fd[s], write, off, buf, n);
}

cm_mesh cm_decode_stream_mesh(cm_decode_state *s, const char *out_path, int is_dir)
{
    cm_decode_spill_close();
    size_t n = strlen(out_path);
    if (!is_dir) { /* the output file's directory */
        while (n > 0 && out_path[n - 1] != '/')
            n--;
        while (n > 1 && out_path[n - 1] == '/')
            n--;
    }
    if (n == 0)
        snprintf(spill_fs.dir, sizeof spill_fs.dir, ".");
    else
        snprintf(spill_fs.dir, sizeof spill_fs.dir, "%.*s", (int)n, out_path);
    return cm_decode_state_mesh(s, spill_file_io, &spill_fs);
}

size_t cm_decode_file_static_bytes(void)
{
    return sizeof read_chunk + sizeof write_chunk + sizeof spill_fs;
}

size_t cm_decode_file_read_static_bytes(void)
{
    return sizeof read_chunk + sizeof spill_fs;
}

void cm_decode_spill_close(void)
{
    for (int k = 0; k < CM_SPILL_STREAMS; k++) {
        if (spill_fs.fd[k] >= 0)
            close(spill_fs.fd[k]);
        spill_fs.fd[k] = -1;
    }
}

/* a face's output must be finite (the writers refuse the whole mesh otherwise, naming no face) */
static cm_err check_face_finite(const cm_mesh *mesh, const cm_mesh_mark *from, cm_status *st)
{
    for (uint32_t i = from->nverts; i < mesh->nverts; i++) {
        float p[3], q[3];
        cm_mesh_pos(mesh, i, p);
        cm_mesh_nrm(mesh, i, q);
        for (int k = 0; k < 3; k++)
            if (!isfinite(p[k]) || !isfinite(q[k]))
                return cm_fail(st, CM_E_NONFINITE, "tessellation: a vertex beyond float range");
    }
    if (cm_mesh_spill_failed(mesh))
        return cm_fail(st, CM_E_IO, "mesh spill");
    return CM_OK;
}

static cm_err decode_faces(const cm_model *m, uint32_t tri_cap, cm_mesh *mesh, cm_tess_ws *ws, cm_decode_summary *sum,
                           cm_status *st);

cm_err cm_decode_mesh(const cm_decoder *dec, double tol, cm_mesh *mesh, cm_tess_ws *ws, cm_decode_summary *sum,
                      cm_status *st)
{
    const cm_model *m = &dec->model;
    cm_mesh_clear(mesh);
    memset(sum, 0, sizeof *sum);
    sum->tess_tol = tol > 0 ? tol : m->tess_tol;
    const uint32_t tri_cap = (uint32_t)cm_tess_triangle_cap(m, sum->tess_tol);
    cm_corner_cache_begin(&ws->rb.corner, m); /* the model stays as it is until the last face */
    cm_err e = decode_faces(m, tri_cap, mesh, ws, sum, st);
    cm_corner_cache_end(&ws->rb.corner);
    return e;
}

/* cm_decode_mesh's loop over the faces */
static cm_err decode_faces(const cm_model *m, uint32_t tri_cap, cm_mesh *mesh, cm_tess_ws *ws, cm_decode_summary *sum,
                           cm_status *st)
{
    for (uint32_t f = 0; f < m->nfaces; f++) {
        cm_tess_info info;
        cm_status fst;
        cm_status_init(&fst);
        cm_mesh_mark mark = cm_mesh_save(mesh);
        cm_err e = cm_tessellate_face(m, f, sum->tess_tol, mesh, ws, &info, &fst);
        if (e == CM_OK && (e = check_face_finite(mesh, &mark, &fst)) != CM_OK)
            cm_status_at_face(&fst, f, m->faces[f].rec_off);
        if (e != CM_OK) {
            if (fst.where == NULL)
                fst.where = "tessellation";
            cm_mesh_rollback(mesh, &mark); /* nothing of the failed face stays in the mesh */
            if (e == CM_E_LIMIT || e == CM_E_NOMEM || e == CM_E_IO) {
                if (st && st->code == CM_OK)
                    *st = fst;
                return e;
            }
            /* this face only: say why, go on */
            if (sum->faces_left_out < CM_DECODE_LEFT_OUT_LIST)
                sum->left_out[sum->faces_left_out] = fst;
            sum->faces_left_out++;
            continue;
        }
        if (mesh->nindex / 3 > tri_cap) {
            /* a valid file never gets here (the encoder counted the triangles with this code):
               a damaged header, whose tolerance no longer matches its needs, stops here */
            if (st && st->code == CM_OK) {
                st->need = mesh->nindex / 3;
                st->have = (uint64_t)tri_cap;
            }
            cm_err over = cm_fail(st, CM_E_RANGE, "tessellation: the model needs more triangles than the header "
                                                  "declares (MAX_TRIS)");
            cm_status_at_face(st, f, m->faces[f].rec_off);
            return over;
        }
        if (info.max_gap > sum->max_gap)
            sum->max_gap = info.max_gap;
        if (m->faces[f].method < CM_METHOD_COUNT)
            sum->faces_by_method[m->faces[f].method]++;
    }
    /* format 4.3: each placed copy of a part, from the part's triangles */
    cm_err pe = cm_mesh_place(m, mesh, st);
    if (pe != CM_OK)
        return pe;
    sum->faces = m->nfaces;
    sum->placed_faces = mesh->nfaces;
    sum->triangles = mesh->nindex / 3;
    sum->vertices = mesh->nverts;
    if (sum->faces_left_out > 0 && mesh->nindex == 0) {
        /* nothing to show (every face left out, or the rest without a triangle): the model fails,
           with its first face's reason and place (the writer would only say "empty mesh") */
        if (st && st->code == CM_OK)
            *st = sum->left_out[0];
        return sum->left_out[0].code;
    }
    return CM_OK;
}

/* the serialiser's bytes into fd; step(ctx, "written") after the first chunk */
static cm_err write_all(cm_out *w, int fd, uint64_t *total, cm_write_step *step, void *ctx, cm_status *st)
{
    cm_err e = CM_OK;
    *total = 0;
    for (;;) {
        size_t n = 0;
        int done = 0;
        if ((e = cm_out_next(w, write_chunk, sizeof write_chunk, &n, &done, st)) != CM_OK)
            return e;
        for (size_t off = 0; off < n;) {
            ssize_t k = write(fd, write_chunk + off, n - off);
            if (k < 0 && errno == EINTR)
                continue;
            if (k <= 0)
                return cm_fail_errno(st, "write");
            off += (size_t)k;
        }
        if (*total == 0 && step)
            step(ctx, "written");
        *total += n;
        if (done)
            return CM_OK;
    }
}

cm_err cm_write_mesh(const cm_mesh *mesh, cm_out_format fmt, const char *out_path, int sync, uint64_t *bytes,
                     cm_status *st)
{
    char tmp[4096];
    if (strlen(out_path) + 16 > sizeof tmp)
        return cm_fail(st, CM_E_ARG, "output path too long");
    snprintf(tmp, sizeof tmp, "%s.part%ld", out_path, (long)getpid());
    static cm_out w; /* serialiser state: static, like everything on the decode path */
    cm_err e = cm_out_begin(&w, fmt, mesh, st);
    if (e != CM_OK)
        return e;
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0)
        return cm_fail_errno(st, "create");
    uint64_t total = 0;
    e = write_all(&w, fd, &total, NULL, NULL, st);
    if (e == CM_OK && sync && fsync(fd) != 0)
        e = cm_fail_errno(st, "fsync");
    if (close(fd) != 0 && e == CM_OK)
        e = cm_fail_errno(st, "close");
    if (e == CM_OK && rename(tmp, out_path) != 0)
        e = cm_fail_errno(st, "rename");
    if (e != CM_OK)
        unlink(tmp);
    else if (bytes)
        *bytes = total;
    return e;
}

cm_err cm_write_mesh_at(const cm_mesh *mesh, cm_out_format fmt, int dirfd, const char *name, uint64_t *bytes,
                        cm_write_step *step, void *ctx, cm_status *st)
{
    static cm_out w;
    cm_err e = cm_out_begin(&w, fmt, mesh, st);
    if (e != CM_OK)
        return e;
    int fd = openat(dirfd, name, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0)
        return cm_fail_errno(st, "create");
    if (step)
        step(ctx, "created");
    uint64_t total = 0;
    e = write_all(&w, fd, &total, step, ctx, st);
    if (e == CM_OK && fsync(fd) != 0)
        e = cm_fail_errno(st, "fsync");
    if (close(fd) != 0 && e == CM_OK)
        e = cm_fail_errno(st, "close");
    if (e != CM_OK) {
        unlinkat(dirfd, name, 0);
        return e;
    }
    if (step)
        step(ctx, "closed");
    if (bytes)
        *bytes = total;
    return CM_OK;
}
