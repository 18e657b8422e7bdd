/*
 * test_parts.c - the model's parts, the terminal's assembly steps (format 4.11, issue 17): what the
 * CAD system made one (an outermost subfigure instance, a 402 associativity group) is one part, each
 * placed copy one, loose faces joined by their edges; in file order, or in the order of `cmz encode
 * --steps` (names a part answers to, "#N"); the terminal's decoder reads them and its viewer steps
 * through them; a steps file that names nothing is refused by line; a broken writer's part records
 * are refused by name; format 4.10 and a model of loose faces alone send none.
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cm/cm_decode.h"
#include "cm/cm_view.h"
#include "cm_report.h"
#include "encode/encode.h"
#include "igs_writer.h"
#include "model_load.h"

static cm_decoder dec;
static cm_view view;

/* three boxes, copies of one subfigure "BOX" (the second and third placed again as transforms),
   two loose squares apart, and two squares one associativity group holds */
static const double xf[3][12] = {
    {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0},
    {1, 0, 0, 100, 0, 1, 0, 0, 0, 0, 1, 0},
    {1, 0, 0, 200, 0, 1, 0, 0, 0, 0, 1, 0},
};

static void load_assembly(loaded_model *lm)
{
    igw w;
    igw_init(&w);
    igw_placed_boxes(&w, 3, xf);
    igw_square_144(&w, 5, 100, 0);
    igw_square_144(&w, 5, 110, 0);
    int g1 = igw_square_144(&w, 5, 120, 0), g2 = igw_square_144(&w, 5, 130, 0);
    igw_add(&w, 402, 7, "2,%d,%d", g1, g2);
    size_t len = 0;
    char *text = igw_text(&w, &len);
    cm_status st;
    cm_status_init(&st);
    assert_ok(model_load_data_ex("assembly", text, len, lm, MODEL_LOAD_FOLD, NULL, NULL, &st));
    free(text);
    igw_free(&w);
}

static cm_err encode_with(loaded_model *lm, const char *steps, void (*hook)(enc_parts *), int minor, encode_result *r,
                          cm_status *st)
{
    encode_opts o;
    encode_opts_default(&o);
    if (minor >= 0)
        encode_opts_for_format(&o, 4, minor);
    o.steps = steps;
    o.test_parts = hook;
    cm_status_init(st);
    memset(r, 0, sizeof *r);
    return encode_model(lm, &o, r, st);
}

static cm_err decode(const encode_result *r, cm_status *st)
{
    cm_status_init(st);
    cm_dec_init(&dec);
    cm_err e = cm_dec_feed(&dec, r->bytes, r->len, st);
    return e != CM_OK ? e : cm_dec_finish(&dec, st);
}

/* the part of each face in file order, then of each copy, as the terminal read them */
static void decoded_parts(uint32_t *got, uint32_t *n)
{
    *n = 0;
    for (uint32_t f = 0; f < dec.model.nfaces; f++)
        got[(*n)++] = dec.model.faces[f].part;
    for (uint32_t k = 0; k < dec.model.nplacements; k++)
        got[(*n)++] = dec.model.placements[k].part;
}

static char steps_path[64];

static const char *steps_file(const char *text)
{
    snprintf(steps_path, sizeof steps_path, "/tmp/cm_test_steps_%d.txt", (int)getpid());
    FILE *f = fopen(steps_path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    return steps_path;
}

/*
 * In file order, each part where its top-level entity is: the first box (its 7 faces the model's
 * own), its two copies (their 408 instances come before the squares in the file, though the file
 * sends their transforms after every face), the two loose squares, the group's two squares as one
 * part; the viewer steps through them.
 */
static void test_parts_in_file_order(void **state)
{
    (void)state;
    loaded_model lm;
    load_assembly(&lm);
    assert_int_equal(lm.mesh.nfaces, 11);
    assert_int_equal(lm.brep.nplacements, 2);
    encode_result r;
    cm_status st;
    assert_ok(encode_with(&lm, NULL, NULL, -1, &r, &st));
    assert_true(r.bytes[CM_HDR_MINOR] >= CM_FMT_PART_NAMES_MINOR); /* (the default: the newest) */
    assert_int_equal(r.parts, 6);
    assert_ok(decode(&r, &st));
    assert_int_equal(dec.model.nparts, 6);
    /* format 4.12: the names the parts answer to, the first of each (the box and its copies their
       subfigure's; the loose squares and the group none) */
    static const char *const name[7] = {NULL, "BOX", "BOX", "BOX", NULL, NULL, NULL};
    for (uint32_t k = 0; k <= 6; k++) {
        const char *got = cm_model_part_name(&dec.model, k);
        if (name[k])
            assert_string_equal(got, name[k]);
        else
            assert_null(got);
    }
    assert_null(cm_model_part_name(&dec.model, 7));
    assert_int_equal(dec.model.part_names_left_out, 0);
    uint32_t got[32], n;
    decoded_parts(got, &n);
    assert_int_equal(n, 13);
    /* the box's faces, then the four squares in file order, then the two copies: the box's 408s
       come after its geometry and before the squares, so the copies are parts 2 and 3 */
    const uint32_t want[13] = {1, 1, 1, 1, 1, 1, 1, 4, 5, 6, 6, 2, 3};
    for (uint32_t i = 0; i < n; i++)
        assert_int_equal(got[i], want[i]);
    /* the viewer steps through the file's parts: a face's step is its part, a copy's its copy's */
    cm_view_opts o;
    cm_view_opts_default(&o);
    float lo[3] = {-10, -10, -10}, hi[3] = {250, 50, 140};
    assert_ok(cm_view_begin(&view, &o, lo, hi, NULL));
    assert_int_equal(cm_view_parts(&view, &dec.model), 6);
    for (uint32_t f = 0; f < dec.model.nfaces; f++)
        assert_int_equal(view.part_of_face[f], want[f]);
    assert_int_equal(view.place_part[0], 2);
    assert_int_equal(view.place_part[1], 3);
    encode_result_free(&r);
    model_free(&lm);
}

/* --steps: the parts it names first, by name (the subfigure's) or number, the rest after in file order */
static void test_parts_in_steps_order(void **state)
{
    (void)state;
    loaded_model lm;
    load_assembly(&lm);
    encode_result r;
    cm_status st;
    /* #6 (the group's squares), then the first two boxes by name, then the rest in file order: the
       third box, the two loose squares */
    assert_ok(encode_with(&lm, steps_file("#6\n\nBOX\r\n  BOX \n"), NULL, -1, &r, &st));
    assert_int_equal(r.parts, 6);
    assert_int_equal(r.parts_stepped, 3);
    assert_ok(decode(&r, &st));
    uint32_t got[32], n;
    decoded_parts(got, &n);
    const uint32_t want[13] = {2, 2, 2, 2, 2, 2, 2, 5, 6, 1, 1, 3, 4};
    assert_int_equal(n, 13);
    for (uint32_t i = 0; i < n; i++)
        assert_int_equal(got[i], want[i]);
    encode_result_free(&r);
    /* names and numbers that name nothing: refused before the long work, by line */
    static const struct {
        const char *text, *says;
    } bad[] = {
        {"BOX\nBOX\nBOX\nBOX\n", "line 4: no part (left) is named \"BOX\""},
        {"#7\n", "line 1: there is no part #7 (the model has 6)"},
        {"#0\n", "line 1: there is no part #0"},
        {"BOX\n#1\n", "line 2: part #1 is already a step"},
        {"Box\n", "line 1: no part (left) is named \"Box\""},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        assert_err(encode_with(&lm, steps_file(bad[i].text), NULL, -1, &r, &st), CM_E_ARG);
        assert_non_null(strstr(r.refusal, bad[i].says));
        encode_result_free(&r);
    }
    assert_err(encode_with(&lm, "/nonexistent/steps.txt", NULL, -1, &r, &st), CM_E_IO);
    assert_non_null(strstr(r.refusal, "cannot be read"));
    encode_result_free(&r);
    remove(steps_path);
    model_free(&lm);
}

/* format 4.10 names no parts (its reader stops at the colours); a model of loose faces alone names
   none either (the viewer joins them itself) */
static void test_no_parts(void **state)
{
    (void)state;
    loaded_model lm;
    load_assembly(&lm);
    encode_result r;
    cm_status st;
    assert_ok(encode_with(&lm, NULL, NULL, 11, &r, &st)); /* (4.11: parts without names) */
    assert_int_equal(r.bytes[CM_HDR_MINOR], 11);
    assert_ok(decode(&r, &st));
    assert_int_equal(dec.model.nparts, 6);
    assert_int_equal(dec.model.part_names_len, 0);
    assert_null(cm_model_part_name(&dec.model, 1));
    encode_result_free(&r);
    assert_ok(encode_with(&lm, NULL, NULL, 10, &r, &st));
    assert_int_equal(r.bytes[CM_HDR_MINOR], 10);
    assert_int_equal(r.parts, 0);
    assert_ok(decode(&r, &st));
    assert_int_equal(dec.model.nparts, 0);
    for (uint32_t f = 0; f < dec.model.nfaces; f++)
        assert_int_equal(dec.model.faces[f].part, 0);
    encode_result_free(&r);
    model_free(&lm);
    igw w;
    igw_init(&w);
    igw_box_144(&w, 10, 10, 10);
    cm_status_init(&st);
    assert_ok(igw_load(&w, "box", &lm, &st));
    assert_ok(encode_with(&lm, NULL, NULL, -1, &r, &st));
    assert_int_equal(r.parts, 0);
    assert_ok(decode(&r, &st));
    assert_int_equal(dec.model.nparts, 0);
    encode_result_free(&r);
    model_free(&lm);
}

/* names beyond the build's room for them (CM_MAX_PART_NAME_BYTES): the model decodes, each part
   still a step, without names, and says so; within it, each copy's name */
static void test_part_names_left_out(void **state)
{
    (void)state;
    /* (copies of a box whose subfigure's name has 39 bytes: with their 0s beyond the room; 19:
       within it) */
    enum { COPIES = CM_MAX_PART_NAME_BYTES / 40 + 4 };
    if (COPIES > CM_MAX_PLACEMENTS + 1)
        skip();
    static double xfs[COPIES][12];
    for (int k = 0; k < COPIES; k++) {
        const double x[12] = {1, 0, 0, 100.0 * k, 0, 1, 0, 0, 0, 0, 1, 0};
        memcpy(xfs[k], x, sizeof x);
    }
    for (int over = 0; over < 2; over++) {
        char name[40];
        memset(name, 'N', sizeof name);
        name[over ? 39 : 19] = 0;
        igw w;
        igw_init(&w);
        igw_placed_boxes_named(&w, COPIES, (const double(*)[12])xfs, name);
        loaded_model lm;
        cm_status st;
        cm_status_init(&st);
        size_t len = 0;
        char *text = igw_text(&w, &len);
        assert_ok(model_load_data_ex("boxes", text, len, &lm, MODEL_LOAD_FOLD, NULL, NULL, &st));
        free(text);
        assert_int_equal(lm.brep.nplacements, COPIES - 1);
        encode_result r;
        assert_ok(encode_with(&lm, NULL, NULL, -1, &r, &st));
        assert_ok(decode(&r, &st));
        assert_int_equal(dec.model.nparts, COPIES);
        assert_int_equal(dec.model.part_names_left_out, over);
        const char *got = cm_model_part_name(&dec.model, COPIES);
        if (over)
            assert_null(got);
        else
            assert_string_equal(got, name);
        encode_result_free(&r);
        model_free(&lm);
        igw_free(&w);
    }
}

static void assert_says(const cm_status *st, const char *cause)
{
    char text[512];
    cm_format_status(text, sizeof text, st);
    if (!strstr(text, cause))
        fail_msg("status \"%s\" does not say \"%s\"", text, cause);
}

/* a broken writer's part records: each refused by name (by the encoder's own reading of what it
   wrote, which is the terminal's decoder: the file is never written) */
static void too_many_parts(enc_parts *p) { p->nparts = 14; } /* 11 faces and 2 copies */
static void part_beyond(enc_parts *p) { p->face_part[3] = p->nparts + 1; } /* by number */
static void next_beyond(enc_parts *p)
{
    p->nparts = 1; /* the second part is "the next one" */
    for (int f = 0; f < 11; f++)
        p->face_part[f] = f < 7 ? 1 : 2;
}

static void test_broken_part_records(void **state)
{
    (void)state;
    static const struct {
        void (*hook)(enc_parts *);
        const char *says;
    } bad[] = {{too_many_parts, "part count"}, {part_beyond, "part"}, {next_beyond, "part"}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        loaded_model lm;
        load_assembly(&lm);
        encode_result r;
        cm_status st;
        assert_err(encode_with(&lm, NULL, bad[i].hook, -1, &r, &st), CM_E_RANGE);
        assert_says(&st, bad[i].says);
        encode_result_free(&r);
        model_free(&lm);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parts_in_file_order),
        cmocka_unit_test(test_parts_in_steps_order),
        cmocka_unit_test(test_no_parts),
        cmocka_unit_test(test_part_names_left_out),
        cmocka_unit_test(test_broken_part_records),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
