/*
 * test_mesh_spill.c - the streaming output mesh (cm_mesh.h, issue 15): a mesh whose arrays are a
 * small window, the rest spilled through an io callback, writes the same GLB, STL and OBJ bytes as
 * the same mesh held whole; a face rolled back past the window's start leaves nothing behind; a
 * failed write or read is CM_E_IO, a face larger than the window CM_E_LIMIT.
 *
 * The faces are synthetic (fans of 3 to 40 vertices on a wavy sheet, some coloured); the spill is
 * memory here (the terminal's is files: cm_decode_file.c, exercised by the corpus and the
 * bundled-model gates).
 */
#include <limits.h>
#include <stdio.h>

#include "test_util.h"
#include "test_mesh.h"

#include "cm/cm_mesh.h"
#include "cm/cm_out.h"
#include "cm/cm_place.h"

#define NFACES 60
#define MANY_FACES 400 /* test_read_fails: more than the cached pages hold */
#define WHOLE_V 16384
#define WHOLE_I 65536
#define WIN_V 48   /* the window: a few faces at a time */
#define WIN_I 160

static float w_pos[WHOLE_V][3], w_nrm[WHOLE_V][3];
static uint32_t w_idx[WHOLE_I];
static cm_mesh_face w_faces[MANY_FACES];

static float s_pos[WIN_V][3], s_nrm[WIN_V][3];
static uint32_t s_idx[WIN_I];
static cm_mesh_face s_faces[MANY_FACES];
static cm_mesh_spill spill;

/* the spill's store: three streams in memory; writes or reads fail from a chosen call on */
static uint8_t store[CM_SPILL_STREAMS][1 << 19];
static uint64_t store_len[CM_SPILL_STREAMS];
static long io_calls, fail_write_at = -1, fail_read_at = -1, writes, reads;

static int mem_io(void *ctx, int write, unsigned s, uint64_t off, void *buf, size_t n)
{
    (void)ctx;
    io_calls++;
    if (write ? (fail_write_at >= 0 && writes++ >= fail_write_at) : (fail_read_at >= 0 && reads++ >= fail_read_at))
        return -1;
    if (s >= CM_SPILL_STREAMS || off + n > sizeof store[0])
        return -1;
    if (write) {
        memcpy(store[s] + off, buf, n);
        if (off + n > store_len[s])
            store_len[s] = off + n;
    } else {
        if (off + n > store_len[s])
            return -1; /* only what was written is read */
        memcpy(buf, store[s] + off, n);
    }
    return 0;
}

/* an empty mesh over these arrays */
static cm_mesh mesh_over(float (*pos)[3], float (*nrm)[3], uint32_t *idx, cm_mesh_face *faces, uint32_t cap_v,
                         uint32_t cap_i)
{
    return test_mesh_on(pos, nrm, idx, faces, cap_v, cap_i, MANY_FACES);
}

static cm_mesh whole_mesh(void) { return mesh_over(w_pos, w_nrm, w_idx, w_faces, WHOLE_V, WHOLE_I); }

/* a window of WIN_V vertices and WIN_I indices over the memory store, up to WHOLE_V / WHOLE_I in all */
static cm_mesh spilled_mesh(void)
{
    cm_mesh m = mesh_over(s_pos, s_nrm, s_idx, s_faces, 0, 0);
    memset(&spill, 0, sizeof spill);
    spill.io = mem_io;
    memset(store_len, 0, sizeof store_len);
    io_calls = writes = reads = 0;
    fail_write_at = fail_read_at = -1;
    cm_mesh_set_spill(&m, &spill, WIN_V, WIN_I, WHOLE_V, WHOLE_I);
    return m;
}

/* face f: a fan of 3..40 vertices; through the window as the tessellation writes (make_room first) */
static cm_err add_face(cm_mesh *m, uint32_t f)
{
    uint32_t nv = 3u + (f * 7u) % 38u, nt = nv - 2u;
    cm_err e = cm_mesh_make_room(m, nv, 3u * nt, NULL);
    if (e != CM_OK)
        return e;
    cm_mesh_face *fc = &m->faces[m->nfaces];
    memset(fc, 0, sizeof *fc);
    fc->first_vert = m->nverts;
    fc->first_index = m->nindex;
    fc->source_face = f;
    fc->has_color = f % 3u == 0;
    fc->rgb = 0x102030u * (f % 5u);
    for (uint32_t i = 0; i < nv; i++) {
        float a = (float)i / (float)nv * 6.2831853f, x = (float)f + 0.4f * cosf(a), y = 0.4f * sinf(a);
        float *p = cm_mesh_wpos(m, m->nverts + i), *n = cm_mesh_wnrm(m, m->nverts + i);
        p[0] = x;
        p[1] = y;
        p[2] = 0.1f * sinf(x * 3.0f) * cosf(y * 2.0f);
        n[0] = 0.0f;
        n[1] = 0.6f;
        n[2] = 0.8f;
    }
    for (uint32_t t = 0; t < nt; t++) {
        uint32_t *ix = cm_mesh_widx(m, m->nindex + 3u * t);
        ix[0] = m->nverts;
        ix[1] = m->nverts + t + 1u;
        ix[2] = m->nverts + t + 2u;
    }
    m->nverts += nv;
    m->nindex += 3u * nt;
    fc->nverts = nv;
    fc->nindex = 3u * nt;
    m->nfaces++;
    return CM_OK;
}

/* the whole file of m in fmt into out; its length, or 0 on an error (code in *err) */
static size_t write_file(const cm_mesh *m, cm_out_format fmt, uint8_t *out, size_t cap, cm_err *err)
{
    static cm_out w;
    cm_status st;
    cm_status_init(&st);
    *err = cm_out_begin(&w, fmt, m, &st);
    if (*err != CM_OK)
        return 0;
    size_t len = 0;
    for (int done = 0; !done;) {
        size_t n = 0;
        if (len + 1000 > cap) {
            *err = CM_E_NOSPACE;
            return 0;
        }
        *err = cm_out_next(&w, out + len, 1000, &n, &done, &st); /* small pieces: many page turns */
        if (*err != CM_OK)
            return 0;
        len += n;
    }
    return len;
}

static uint8_t out_whole[1 << 22], out_spilled[1 << 22];

/* a and b write the same GLB, STL and OBJ bytes */
static void assert_same_files(const cm_mesh *a, const cm_mesh *b)
{
    const cm_out_format fmts[3] = {CM_OUT_GLB, CM_OUT_STL, CM_OUT_OBJ};
    for (int k = 0; k < 3; k++) {
        cm_err ea, eb;
        size_t na = write_file(a, fmts[k], out_whole, sizeof out_whole, &ea);
        size_t nb = write_file(b, fmts[k], out_spilled, sizeof out_spilled, &eb);
        assert_int_equal(ea, CM_OK);
        assert_int_equal(eb, CM_OK);
        assert_true(na > 0);
        assert_int_equal(na, nb);
        assert_memory_equal(out_whole, out_spilled, na);
    }
}

static void test_same_bytes_as_whole(void **state)
{
    (void)state;
    cm_mesh a = whole_mesh(), b = spilled_mesh();
    for (uint32_t f = 0; f < NFACES; f++) {
        assert_ok(add_face(&a, f));
        assert_ok(add_face(&b, f));
    }
    assert_true(b.win_vert > 0 && b.win_index > 0); /* it did spill */
    assert_true(b.nverts > 10u * WIN_V);
    assert_same_files(&a, &b);
    float lo[3], hi[3], lo2[3], hi2[3];
    assert_true(cm_mesh_bounds(&a, lo, hi) && cm_mesh_bounds(&b, lo2, hi2));
    assert_memory_equal(lo, lo2, sizeof lo);
    assert_memory_equal(hi, hi2, sizeof hi);
}

/* runs read back at once (cm_mesh_vecs, cm_mesh_idxs: the viewer's reads) give what one read per
   value gives, for runs across pages, and across the spill's end into the window */
static void test_runs_read_back(void **state)
{
    (void)state;
    cm_mesh m = spilled_mesh();
    for (uint32_t f = 0; f < NFACES; f++)
        assert_ok(add_face(&m, f));
    assert_true(m.win_vert > 0 && m.win_index > 0);
    static float run[WHOLE_V][3], one[3];
    static uint32_t irun[WHOLE_I];
    uint32_t starts[] = {0, 1, m.win_vert - 5u, m.win_vert, m.nverts - 3u};
    for (unsigned s = 0; s < 2; s++)
        for (size_t k = 0; k < sizeof starts / sizeof starts[0]; k++) {
            uint32_t first = starts[k], n = m.nverts - first;
            cm_mesh_vecs(&m, s == 0 ? CM_SPILL_POS : CM_SPILL_NRM, first, n, run);
            for (uint32_t i = 0; i < n; i++) {
                cm_mesh_vec(&m, s == 0 ? CM_SPILL_POS : CM_SPILL_NRM, first + i, one);
                assert_memory_equal(run[i], one, sizeof one);
            }
        }
    uint32_t istarts[] = {0, 2, m.win_index - 7u, m.win_index, m.nindex - 1u};
    for (size_t k = 0; k < sizeof istarts / sizeof istarts[0]; k++) {
        uint32_t first = istarts[k], n = m.nindex - first;
        cm_mesh_idxs(&m, first, n, irun);
        for (uint32_t i = 0; i < n; i++)
            assert_int_equal(irun[i], cm_mesh_idx(&m, first + i));
    }
    assert_false(cm_mesh_spill_failed(&m));
}

/* faces rolled back past the window's start (the window flushed while they were added) are gone */
static void test_rollback_past_window(void **state)
{
    (void)state;
    cm_mesh a = whole_mesh(), b = spilled_mesh();
    for (uint32_t f = 0; f < 20; f++) {
        assert_ok(add_face(&a, f));
        assert_ok(add_face(&b, f));
    }
    cm_mesh_mark mark = cm_mesh_save(&b);
    uint32_t win_before = b.win_vert;
    for (uint32_t f = 100; f < 110; f++) /* faces that fail later: enough to flush the window */
        assert_ok(add_face(&b, f));
    assert_true(b.win_vert > mark.nverts); /* the mark is in the spill now */
    cm_mesh_rollback(&b, &mark);
    assert_int_equal(b.nverts, mark.nverts);
    assert_true(b.win_vert <= mark.nverts && b.win_vert >= win_before);
    for (uint32_t f = 20; f < NFACES; f++) {
        assert_ok(add_face(&a, f));
        assert_ok(add_face(&b, f));
    }
    assert_same_files(&a, &b);
}

/* face 0 of 70 vertices, more than the window holds: written in two runs, as the tessellation
   writes a face of several patches (cm_mesh_make_room between them) */
static cm_err add_big_face(cm_mesh *m)
{
    const uint32_t nv = WIN_V + 22u, runs[2] = {WIN_V / 2u, nv - WIN_V / 2u};
    cm_mesh_face *fc = &m->faces[m->nfaces];
    memset(fc, 0, sizeof *fc);
    fc->first_vert = m->nverts;
    fc->first_index = m->nindex;
    for (int r = 0, v = 0; r < 2; r++) {
        uint32_t nt = runs[r] - (r == 0 ? 2u : 0u); /* a fan: one triangle a vertex past the first two */
        cm_err e = cm_mesh_make_room(m, runs[r], 3u * nt, NULL);
        if (e != CM_OK)
            return e;
        for (uint32_t i = 0; i < runs[r]; i++, v++) {
            float a = (float)v / (float)nv * 6.2831853f;
            float *p = cm_mesh_wpos(m, m->nverts + i), *n = cm_mesh_wnrm(m, m->nverts + i);
            p[0] = cosf(a);
            p[1] = sinf(a);
            p[2] = 0.05f * (float)v;
            n[0] = 0.0f;
            n[1] = 0.0f;
            n[2] = 1.0f;
        }
        for (uint32_t t = 0; t < nt; t++) { /* triangle (0, j - 1, j) for the run's vertices j */
            uint32_t j = m->nverts - fc->first_vert + t + (r == 0 ? 2u : 0u);
            uint32_t *ix = cm_mesh_widx(m, m->nindex + 3u * t);
            ix[0] = fc->first_vert;
            ix[1] = fc->first_vert + j - 1u;
            ix[2] = fc->first_vert + j;
        }
        m->nverts += runs[r];
        m->nindex += 3u * nt;
    }
    fc->nverts = m->nverts - fc->first_vert;
    fc->nindex = m->nindex - fc->first_index;
    m->nfaces++;
    return CM_OK;
}

/* a part with a face larger than the window, placed once more (format 4.3): copied in runs that fit
   the window, the same files as the mesh held whole (it was refused as over MAX_TESS_POINTS) */
static cm_model model;

static void test_place_face_over_window(void **state)
{
    (void)state;
    cm_mesh a = whole_mesh(), b = spilled_mesh();
    assert_ok(add_big_face(&a));
    assert_ok(add_big_face(&b));
    for (uint32_t f = 1; f < 6; f++) {
        assert_ok(add_face(&a, f));
        assert_ok(add_face(&b, f));
    }
    model.nplacements = 1; /* all cm_mesh_place reads of the model (the workstation profile's model is
                              hundreds of MiB of untouched storage: not cleared) */
    model.placements[0].first = 0;
    model.placements[0].count = 3;
    const double tr[12] = {0, -1, 0, 5, 1, 0, 0, 0, 0, 0, 1, 2}; /* a quarter turn and a shift */
    memcpy(model.placements[0].m, tr, sizeof tr);
    cm_status st;
    cm_status_init(&st);
    assert_ok(cm_mesh_place(&model, &a, &st));
    assert_ok(cm_mesh_place(&model, &b, &st));
    assert_int_equal(a.nverts, b.nverts);
    assert_same_files(&a, &b);
}

static void test_write_fails(void **state)
{
    (void)state;
    cm_mesh b = spilled_mesh();
    fail_write_at = 0;
    cm_err e = CM_OK;
    for (uint32_t f = 0; f < NFACES && e == CM_OK; f++)
        e = add_face(&b, f);
    assert_int_equal(e, CM_E_IO);
    assert_true(cm_mesh_spill_failed(&b));
    assert_int_equal(add_face(&b, 0), CM_E_IO); /* and it stays failed */
}

static void test_read_fails(void **state)
{
    (void)state;
    /* a dry run counts the reads: cm_out_begin's checks, then the writing */
    cm_mesh b = spilled_mesh();
    for (uint32_t f = 0; f < MANY_FACES; f++)
        assert_ok(add_face(&b, f));
    static cm_out w;
    cm_status st;
    cm_status_init(&st);
    fail_read_at = LONG_MAX; /* counts, never fails */
    assert_ok(cm_out_begin(&w, CM_OUT_STL, &b, &st));
    long in_begin = reads;
    cm_err e;
    assert_true(write_file(&b, CM_OUT_STL, out_spilled, sizeof out_spilled, &e) > 0);
    long in_all = reads - in_begin;
    /* write_file reads in its cm_out_begin (in_begin), then in its writing: more pages than cached */
    assert_true(in_begin > 0 && in_all > in_begin);
    const long at[3] = {0, in_begin, in_all - 1}; /* in the checks, the writing's first read, its last */
    for (int k = 0; k < 3; k++) {
        b = spilled_mesh();
        for (uint32_t f = 0; f < MANY_FACES; f++)
            assert_ok(add_face(&b, f));
        fail_read_at = at[k];
        size_t n = write_file(&b, CM_OUT_STL, out_spilled, sizeof out_spilled, &e);
        assert_int_equal(e, CM_E_IO);
        assert_int_equal(n, 0);
    }
}

static void test_face_larger_than_window(void **state)
{
    (void)state;
    cm_mesh b = spilled_mesh();
    cm_status st;
    cm_status_init(&st);
    assert_int_equal(cm_mesh_make_room(&b, WIN_V + 1u, 3u, &st), CM_E_LIMIT);
    assert_int_equal(cm_mesh_make_room(&b, 3u, WIN_I + 1u, &st), CM_E_LIMIT);
    assert_ok(cm_mesh_make_room(&b, WIN_V, WIN_I, &st)); /* exactly the window fits */
}

/* without a spill make_room never refuses: the arrays are the whole mesh (the callers' capacity
   checks decide, as before streaming) */
static void test_no_spill(void **state)
{
    (void)state;
    cm_mesh a = whole_mesh();
    assert_ok(cm_mesh_make_room(&a, WHOLE_V + 1u, WHOLE_I + 1u, NULL));
    assert_int_equal(a.win_vert, 0);
    assert_false(cm_mesh_spill_failed(&a));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_same_bytes_as_whole), cmocka_unit_test(test_rollback_past_window),
        cmocka_unit_test(test_write_fails),         cmocka_unit_test(test_read_fails),
        cmocka_unit_test(test_face_larger_than_window), cmocka_unit_test(test_no_spill),
        cmocka_unit_test(test_place_face_over_window), cmocka_unit_test(test_runs_read_back),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
