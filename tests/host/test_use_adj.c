/*
 * test_use_adj.c - format 4.5's edge uses named at their loop's vertex (cm_use_adj.h): the lists'
 * order and bound, a pyramid whose apex joins more edges than a list is walked coded in 4.5 and
 * 4.4 to the same loops, 4.5's FACE section smaller; uses sent past their candidates (as in 4.4)
 * read back; then FACE sections coded here as a hostile writer could: a candidate past the escape,
 * an escape past the edges, a loop broken, each refused by name in a file whose lengths and CRCs
 * are right.
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <stdlib.h>

#include "cm/cm_arith.h"
#include "cm/cm_decode.h"
#include "cm/cm_method.h"
#include "cm/cm_sections.h"
#include "cm/cm_use_adj.h"
#include "cmz_splice.h"
#include "encode/encode.h"
#include "igs_writer.h"
#include "model_load.h"

static cm_decoder dec;

static cm_err decode(const uint8_t *b, size_t len, cm_status *st)
{
    return cmz_decode(&dec, b, len, st);
}

static void load_pyramid(int n, loaded_model *lm)
{
    igw w;
    igw_init(&w);
    igw_pyramid_144(&w, n, 10.0, 8.0);
    cm_status st;
    assert_ok(igw_load(&w, "pyramid", lm, &st));
}

static void encode_minor(loaded_model *lm, int minor, encode_result *r)
{
    encode_opts o;
    encode_opts_default(&o);
    encode_opts_for_format(&o, 4, minor);
    cm_status st;
    cm_status_init(&st);
    memset(r, 0, sizeof *r);
    assert_ok(encode_model(lm, &o, r, &st));
}

/* A fan of 100 edges at vertex 0 (edge i from vertex 0 to vertex i + 1), referenced in order: the
   list is most recent first, the open edges (fewer than two uses) before the others, and only
   CM_USE_WALK entries are looked at in each pass. */
static void test_lists(void **state)
{
    (void)state;
    static cm_edge edges[100];
    static int32_t head[101], next[100][2];
    static uint8_t nuse[100];
    cm_use_adj a = {head, next, nuse};
    cm_use_adj_begin(&a, 101);
    for (uint32_t e = 0; e < 100; e++) {
        edges[e].v0 = 0;
        edges[e].v1 = (int32_t)e + 1;
        cm_use_adj_use(&a, edges, e, 1);
        if (e % 2 == 0) /* the even ones used twice */
            cm_use_adj_use(&a, edges, e, 0);
    }
    uint32_t c[CM_USE_CANDIDATES];
    int n = cm_use_adj_list(&a, edges, 0, c);
    /* the first 64 entries: edges 99 down to 36; the odd (open) ones first */
    assert_int_equal(n, CM_USE_WALK);
    assert_int_equal(c[0], 99);
    assert_int_equal(c[1], 97);
    assert_int_equal(c[31], 37);
    assert_int_equal(c[32], 98);
    assert_int_equal(c[63], 36);
    /* at the fan's other end: the one edge there */
    assert_int_equal(cm_use_adj_list(&a, edges, 40, c), 1);
    assert_int_equal(c[0], 39);
    assert_int_equal(cm_use_adj_rev(edges, 39, 40), 1);
    assert_int_equal(cm_use_adj_rev(edges, 39, 0), 0);
    /* a closed edge is in its vertex's list once */
    cm_use_adj_begin(&a, 2);
    edges[0].v0 = edges[0].v1 = 1;
    cm_use_adj_add(&a, edges, 0);
    assert_int_equal(cm_use_adj_list(&a, edges, 1, c), 1);
}

/* the decoded model's loops: every use's edge and direction, in order, as one array */
static int loops_of(const cm_model *m, uint32_t *out, int cap)
{
    int n = 0;
    for (uint32_t u = 0; u < m->nuses && n + 1 < cap; u++) {
        out[n++] = m->uses[u].edge;
        out[n++] = m->uses[u].rev;
    }
    return n;
}

/* how the FACE section below is spoilt */
typedef struct face_edit {
    int past;     /* the first use named among candidates: by an index this far past the escape */
    int far_back; /* the first escape: `back` as far as the edges referenced (one too far) */
    int swap_rev; /* the first loop's first use turned round: its loop no longer closes */
    int escape;   /* every use named among candidates sent past them instead, by `back` (as a writer
                     does for an edge beyond the walk): the same loops */
} face_edit;

/*
 * The FACE section of the model in `dec` (PLANE faces only, no copies), coded here as the writer
 * does (write_sections.c): every use after a loop's first at its vertex, with cm_use_adj; `ed`
 * spoils one field.
 */
static size_t face_section(uint8_t *buf, size_t cap, const face_edit *ed)
{
    const cm_model *m = &dec.model;
    cm_ac_enc e;
    cm_ac_enc_init(&e, buf, cap);
    cm_face_ctx c;
    cm_face_ctx_init(&c);
    static int32_t head[CM_MAX_VERTICES], next[CM_MAX_EDGES][2];
    static uint8_t nuse[CM_MAX_EDGES];
    cm_use_adj a = {head, next, nuse};
    cm_use_adj_begin(&a, m->nverts);
    int past = ed ? ed->past : 0, far = ed ? ed->far_back : 0, swap = ed ? ed->swap_rev : 0;
    int escape = ed ? ed->escape : 0;
    cm_ac_enc_uint(&e, &c.count, m->nfaces);
    uint32_t enext = 0;
    for (uint32_t f = 0; f < m->nfaces; f++) {
        const cm_face *F = &m->faces[f];
        assert_int_equal(F->method, CM_METHOD_PLANE);
        cm_ac_enc_uint(&e, &c.method, F->method);
        cm_ac_enc_bit(&e, &c.flip, F->flip);
        cm_ac_enc_uint(&e, &c.loops, F->nloops);
        for (uint32_t l = 0; l < F->nloops; l++) {
            const cm_loop *L = &m->loops[F->loop0 + l];
            cm_ac_enc_uint(&e, &c.uses, L->nuse);
            for (uint32_t k = 0; k < L->nuse; k++) {
                const cm_use *U = &m->uses[L->use0 + k];
                int fresh = U->edge == enext;
                if (k == 0) {
                    cm_ac_enc_bit(&e, &c.is_new, (unsigned)fresh);
                    if (fresh) {
                        cm_ac_enc_bit(&e, &c.rev_new, U->rev ^ (unsigned)swap);
                    } else {
                        cm_ac_enc_uint(&e, &c.back, enext - 1 - U->edge);
                        cm_ac_enc_bit(&e, &c.rev_old, U->rev ^ (unsigned)swap);
                    }
                    swap = 0;
                } else {
                    const cm_use *P = U - 1;
                    int32_t v = P->rev ? m->edges[P->edge].v0 : m->edges[P->edge].v1;
                    cm_ac_enc_bit(&e, &c.is_new, (unsigned)fresh);
                    if (!fresh) {
                        uint32_t cand[CM_USE_CANDIDATES];
                        int n = cm_use_adj_list(&a, m->edges, v, cand), i = 0;
                        while (i < n && cand[i] != U->edge)
                            i++;
                        if (past) {
                            cm_ac_enc_uint(&e, &c.cand, (uint64_t)n + (uint64_t)past);
                            past = 0;
                        } else if (far && i < n) {
                            cm_ac_enc_uint(&e, &c.cand, (uint64_t)n); /* the escape ... */
                            cm_ac_enc_uint(&e, &c.back, enext);       /* ... past every edge */
                            far = 0;
                        } else {
                            if (escape)
                                i = n;
                            cm_ac_enc_uint(&e, &c.cand, (uint64_t)i);
                            if (i == n)
                                cm_ac_enc_uint(&e, &c.back, enext - 1 - U->edge);
                        }
                    }
                    if (m->edges[U->edge].v0 == m->edges[U->edge].v1)
                        cm_ac_enc_bit(&e, &c.rev_closed, U->rev);
                }
                if (fresh)
                    enext++;
                cm_use_adj_use(&a, m->edges, U->edge, fresh);
            }
        }
    }
    cm_ac_enc_uint(&e, &c.place_n, 0);
    size_t n = cm_ac_enc_finish_trimmed(&e);
    assert_false(e.overflow);
    return n;
}

static void assert_refused(const encode_result *r, const face_edit *ed, cm_err code, const char *cause)
{
    static uint8_t sec[1 << 16];
    cm_status st;
    assert_ok(decode(r->bytes, r->len, &st));
    size_t n = face_section(sec, sizeof sec, ed);
    const char *why = cmz_section_refused(&dec, r, CM_SEC_FACE, sec, n, code, cause);
    if (why)
        fail_msg("%s", why);
}

/* A pyramid of 100 sides: the apex joins 100 edges, more than a list is walked. 4.5 and 4.4 decode
   to the same loops (the encoder checks its own file too), 4.5's FACE section in fewer bytes, the
   same bytes as coded here. */
static void test_pyramid(void **state)
{
    (void)state;
    loaded_model lm;
    load_pyramid(100, &lm);
    encode_result r5, r4;
    encode_minor(&lm, 5, &r5);
    encode_minor(&lm, 4, &r4);
    cm_status st;
    static uint32_t a[1 << 12], b[1 << 12];
    assert_ok(decode(r5.bytes, r5.len, &st));
    assert_int_equal(dec.version_minor, 5);
    assert_int_equal(dec.model.nfaces, 101);
    int na = loops_of(&dec.model, a, 1 << 12);
    /* coded here as the writer does: the same bytes */
    static uint8_t sec[1 << 16];
    assert_int_equal(face_section(sec, sizeof sec, NULL), r5.section_bytes[CM_SEC_FACE]);
    assert_ok(decode(r4.bytes, r4.len, &st));
    assert_int_equal(dec.version_minor, 4);
    int nb = loops_of(&dec.model, b, 1 << 12);
    assert_int_equal(na, 2 * 400);
    assert_int_equal(na, nb);
    assert_memory_equal(a, b, (size_t)na * sizeof *a);
    if (!(r5.section_bytes[CM_SEC_FACE] < r4.section_bytes[CM_SEC_FACE]))
        fail_msg("FACE: %zu bytes in 4.5, %zu in 4.4", r5.section_bytes[CM_SEC_FACE], r4.section_bytes[CM_SEC_FACE]);
    encode_result_free(&r5);
    encode_result_free(&r4);
    model_free(&lm);
}

/* A five-sided pyramid's FACE section coded here as the encoder means it decodes to the same loops,
   and so does one that sends every use past its candidates; then a candidate index past the escape, an escape past every referenced edge and a first use
   turned round (its loop no longer closes): each refused by name. */
static void test_hostile_face(void **state)
{
    (void)state;
    loaded_model lm;
    load_pyramid(5, &lm);
    encode_result r;
    encode_minor(&lm, 5, &r);
    cm_status st;
    static uint32_t a[1 << 10], b[1 << 10];
    assert_ok(decode(r.bytes, r.len, &st));
    int na = loops_of(&dec.model, a, 1 << 10);
    static uint8_t sec[1 << 16];
    size_t n = face_section(sec, sizeof sec, NULL), len;
    assert_int_equal(n, r.section_bytes[CM_SEC_FACE]); /* the writer's own bytes */
    uint8_t *f = cmz_with_section(&r, CM_SEC_FACE, sec, n, &len);
    assert_non_null(f);
    assert_ok(decode(f, len, &st));
    assert_int_equal(loops_of(&dec.model, b, 1 << 10), na);
    assert_memory_equal(a, b, (size_t)na * sizeof *a);
    free(f);
    face_edit escape = {0, 0, 0, 1};
    n = face_section(sec, sizeof sec, &escape);
    f = cmz_with_section(&r, CM_SEC_FACE, sec, n, &len);
    assert_non_null(f);
    assert_ok(decode(f, len, &st));
    assert_int_equal(loops_of(&dec.model, b, 1 << 10), na);
    assert_memory_equal(a, b, (size_t)na * sizeof *a);
    free(f);
    face_edit past = {2, 0, 0, 0}, far = {0, 1, 0, 0}, turned = {0, 0, 1, 0};
    assert_refused(&r, &past, CM_E_RANGE, "edge candidate at its vertex");
    assert_refused(&r, &far, CM_E_RANGE, "edge reference");
    assert_refused(&r, &turned, CM_E_FORMAT, "loop not closed");
    encode_result_free(&r);
    model_free(&lm);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lists),
        cmocka_unit_test(test_pyramid),
        cmocka_unit_test(test_hostile_face),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
