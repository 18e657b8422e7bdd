/*
 * test_import_hostile.c - the IGES import against hostile input (issue 10):
 * numbers an int cannot hold, counts of 2147483647, coordinates and
 * matrices that overflow, subfigure and composite-curve DAGs that expand
 * into astronomically many faces or curve pieces, allocation failures, and
 * random mutations.  Every input must be answered promptly, by an import
 * or by an error that names the place in the file (a line or a DE), and an
 * allocation failure must be CM_E_NOMEM, never blamed on the input.
 *
 * Each case would have caught its defect: under the sanitizers
 * (make check-clang) the undefined conversions and overflows abort, and in
 * any build the time limits catch the loops that ran for minutes.
 */
#define _POSIX_C_SOURCE 200809L
#include "../unit/test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "geom/hnurbs.h"
#include "igs_writer.h"
#include "iges/iges_brep.h"
#include "model_load.h"

/* a prompt answer: generous for sanitizer builds on a busy 2-core machine, far below the
 * minutes (or hours) the defects took */
#define PROMPT_SECONDS 5.0

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int names_place(const char *msg)
{
    return strstr(msg, "line ") != NULL || strstr(msg, "DE ") != NULL;
}

/* load IGES text; fail the test if it took longer than PROMPT_SECONDS */
static cm_err load_text(const char *t, size_t len, loaded_model *lm, cm_status *st)
{
    cm_status_init(st);
    double t0 = now();
    cm_err e = model_load_data("hostile.igs", t, len, lm, NULL, NULL, st);
    double dt = now() - t0;
    if (dt > PROMPT_SECONDS)
        fail_msg("the import took %.1f s (limit %.0f s): %s", dt, PROMPT_SECONDS, lm->iges.err);
    return e;
}

static cm_err load_w(const igw *w, loaded_model *lm, cm_status *st)
{
    size_t len;
    char *t = igw_text(w, &len);
    cm_err e = load_text(t, len, lm, st);
    free(t);
    return e;
}

/* the result is an import or a clear error: every message names its place in the input */
static void assert_clear(cm_err e, const loaded_model *lm)
{
    if (e != CM_OK && e != CM_E_NOMEM && !names_place(lm->iges.err))
        fail_msg("%s without a line or DE: \"%s\"", cm_err_name(e), lm->iges.err);
    for (int i = 0; i < lm->iges.nwarn; i++)
        if (lm->iges.warn[i].line <= 0 && !names_place(lm->iges.warn[i].msg))
            fail_msg("warning without a line or DE: \"%s\"", lm->iges.warn[i].msg);
}

/* index of the first warning containing every given text, or -1 */
static int find_warning(const loaded_model *lm, const char *a, const char *b)
{
    for (int i = 0; i < lm->iges.nwarn; i++)
        if (strstr(lm->iges.warn[i].msg, a) && (!b || strstr(lm->iges.warn[i].msg, b)))
            return i;
    return -1;
}

static void expect_warning(const loaded_model *lm, const char *a, const char *b)
{
    if (find_warning(lm, a, b) < 0) {
        for (int i = 0; i < lm->iges.nwarn; i++)
            print_message("  warning: line %d: %s\n", lm->iges.warn[i].line, lm->iges.warn[i].msg);
        fail_msg("no warning with \"%s\"%s%s", a, b ? " and " : "", b ? b : "");
    }
}

#define BOX(w) igw_box_with_hole_144((w), 40.0, 30.0, 10.0, 6.0) /* 7 faces */

/* ---- 1. numbers an int cannot hold, counts that overflow ---- */

/*
 * Replace `old` by `rep` (same length or shorter plus the spaces after it) at the start of the
 * first Parameter line that begins with `old`.  Lines are 80 columns: the parameter field keeps its
 * width by taking spaces from its padding.
 */
static void replace_param_start(char *t, const char *old, const char *rep)
{
    size_t lo = strlen(old);
    for (char *l = t; *l; l = strchr(l, '\n') + 1) {
        if (l[72] == 'P' && strncmp(l, old, lo) == 0) {
            char field[65];
            memcpy(field, l, 64);
            field[64] = 0;
            char out[200];
            snprintf(out, sizeof out, "%s%s", rep, field + lo);
            size_t n = strlen(out);
            while (n > 64 && out[n - 1] == ' ')
                n--;
            assert_true(n <= 64);
            memset(l, ' ', 64);
            memcpy(l, out, n);
            return;
        }
        if (!strchr(l, '\n'))
            break;
    }
    fail_msg("no parameter line starts with %s", old);
}

/* The entity type number 5e13 at the start of an entity's parameters was cast to int (UB). */
static void test_type_number_out_of_int_range(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    BOX(&w);
    size_t len;
    char *t = igw_text(&w, &len);
    replace_param_start(t, "110,", "5.02D13,");
    loaded_model lm;
    cm_status st;
    assert_ok(load_text(t, len, &lm, &st));
    assert_clear(CM_OK, &lm);
    expect_warning(&lm, "does not start with the entity type 110", NULL);
    expect_warning(&lm, ") skipped: ", "DE "); /* the face that used the line */
    assert_int_equal(lm.brep.nfaces, 6);
    model_free(&lm);
    free(t);
    igw_free(&w);
}

typedef struct count_case {
    const char *name;
    int structural; /* 1: a malformed solid/shell/instance: left out by name, the rest imported */
} count_case;

/* Entities whose count parameters are 2147483647, reached from a face or at top level.  Before,
 * K + 1, n + 1, 3 + i, 1 + 3 * n ... overflowed (UB), and mark_references looped 2^31 times per
 * count. */
static int add_count_case(igw *w, int which)
{
    if (which == 3) /* 128: upper index */
        return igw_add(w, 128, 0, "2147483647,1,1,1,0,0,1,0,0,0,0,1,1");
    /* a unit bilinear patch for the others to trim */
    int s = igw_add(w, 128, 0, "1,1,1,1,1,0,1,0,0,0,0,1,1,0,0,1,1,1,1,1,1,0,0,0,1,0,0,0,1,0,1,1,0,0,1,0,1");
    igw_set(w, s, 1, 0, 0);
    switch (which) {
    case 0: /* 144: inner boundaries */
        return igw_add(w, 144, 0, "%d,1,2147483647,0", s);
    case 1: /* 143: boundaries */
        return igw_add(w, 143, 0, "1,%d,2147483647,0", s);
    case 2: /* 510: loops */
        return igw_add(w, 510, 0, "%d,2147483647,1,0", s);
    case 4: { /* 102 boundary with 2147483647 members */
        int c = igw_add(w, 102, 0, "2147483647,1");
        igw_set(w, c, 1, 0, 0);
        int cs = igw_add(w, 142, 0, "0,%d,0,%d,2", s, c);
        igw_set(w, cs, 1, 0, 0);
        return igw_add(w, 144, 0, "%d,1,0,%d", s, cs);
    }
    case 5: { /* 126 boundary with upper index 2147483647 */
        int c = igw_add(w, 126, 0, "2147483647,3,0,0,1,0,0,0,0,1");
        igw_set(w, c, 1, 0, 0);
        int cs = igw_add(w, 142, 0, "0,%d,0,%d,2", s, c);
        igw_set(w, cs, 1, 0, 0);
        return igw_add(w, 144, 0, "%d,1,0,%d", s, cs);
    }
    case 6: { /* 141 boundary: 2147483647 parameter-space curves */
        int c = igw_add(w, 110, 0, "0,0,0,1,0,0");
        igw_set(w, c, 1, 0, 0);
        int b = igw_add(w, 141, 0, "0,0,%d,1,%d,1,2147483647,%d", s, c, c);
        igw_set(w, b, 1, 0, 0);
        return igw_add(w, 143, 0, "0,%d,1,%d", s, b);
    }
    case 7:   /* 508 loop: 2147483647 parameter-space curves */
    case 8:   /* 504 edge list: 2147483647 edges */
    case 9: { /* 502 vertex list: 2147483647 vertices */
        int vl = igw_add(w, 502, 1, "%s,0,0,0,1,0,0", which == 9 ? "2147483647" : "2");
        igw_set(w, vl, 1, 0, 0);
        int c = igw_add(w, 110, 0, "0,0,0,1,0,0");
        igw_set(w, c, 1, 0, 0);
        int el = igw_add(w, 504, 1, "%s,%d,%d,1,%d,2", which == 8 ? "2147483647" : "1", c, vl, vl);
        igw_set(w, el, 1, 0, 0);
        int lp = igw_add(w, 508, 1, "1,0,%d,1,1,%s,0,%d", el, which == 7 ? "2147483647" : "0", c);
        igw_set(w, lp, 1, 0, 0);
        return igw_add(w, 510, 1, "%d,1,1,%d", s, lp);
    }
    case 10: { /* 308 with 2147483647 members, placed by a 408 */
        int d = igw_add(w, 308, 0, "0,3HDEF,2147483647,%d", s);
        igw_set(w, d, 1, 0, 0);
        return igw_add(w, 408, 0, "%d,0,0,0,1", d);
    }
    case 11: /* 186 with 2147483647 void shells */
        return igw_add(w, 186, 0, "%d,1,2147483647,0,1", s);
    default: /* 514 with 2147483647 faces */
        return igw_add(w, 514, 1, "2147483647,%d,1", s);
    }
}

static void test_counts_of_2147483647(void **state)
{
    (void)state;
    static const count_case cases[] = {{"144", 0}, {"143", 0}, {"510", 0}, {"128", 0}, {"102", 0}, {"126", 0},
                                       {"141", 0}, {"508", 0}, {"504", 0}, {"502", 0}, {"308", 1}, {"186", 1},
                                       {"514", 1}};
    for (int c = 0; c < (int)(sizeof cases / sizeof cases[0]); c++) {
        igw w;
        igw_init(&w);
        BOX(&w);
        int de = add_count_case(&w, c);
        loaded_model lm;
        cm_status st;
        cm_err e = load_w(&w, &lm, &st);
        print_message("  %s: %s %s\n", cases[c].name, cm_err_name(e), e == CM_OK ? "" : lm.iges.err);
        assert_clear(e, &lm);
        char dename[32];
        snprintf(dename, sizeof dename, "DE %d", de);
        if (cases[c].structural) {
            /* one bad entity never sinks the model (it once stopped the import with an error) */
            assert_ok(e);
            assert_int_equal(lm.brep.nfaces, 7);
            assert_int_equal(lm.brep.entities_failed, 1);
            expect_warning(&lm, ") left out: ", "DE ");
            print_message("    %s\n", lm.iges.warn[find_warning(&lm, ") left out: ", "DE ")].msg);
        } else {
            assert_ok(e);
            assert_int_equal(lm.brep.nfaces, 7); /* the box; the hostile face is skipped, by name */
            expect_warning(&lm, ") skipped: ", dename);
            print_message("    %s\n", lm.iges.warn[find_warning(&lm, ") skipped: ", dename)].msg);
        }
        model_free(&lm);
        igw_free(&w);
    }
}

/* ---- 2. coordinates and matrices that overflow or lie absurdly far ---- */

/* One matrix entry of -1e308: the face's geometry went to -inf, the curve mesh's spatial grid got
 * NaN cells and grid_query looped over 2^64 of them (`cmz info` still running after 60 s). */
static void test_matrix_entry_minus_1e308(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    BOX(&w);
    int sq = igw_square_144(&w, 10.0, 20.0, 0);
    const double m[12] = {-1e308, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    int x = igw_transform_124(&w, m);
    igw_set(&w, sq, 0, x, 0);
    loaded_model lm;
    cm_status st;
    assert_ok(load_w(&w, &lm, &st));
    assert_clear(CM_OK, &lm);
    char dename[32];
    snprintf(dename, sizeof dename, "DE %d", sq);
    expect_warning(&lm, dename, "beyond +-1e+12 mm");
    assert_int_equal(lm.brep.nfaces, 7);
    assert_near(brep_diag(&lm.brep), sqrt(40.0 * 40 + 30 * 30 + 10 * 10), 1e-9); /* the box alone */
    assert_int_equal(lm.mesh.nedges, 15);
    model_free(&lm);
    igw_free(&w);
}

/* A finite but absurd entry (1e10) puts one face 1e11 mm away: without the check the model's
 * diagonal, and every relative tolerance, became 1e11 mm and the box's vertices all merged. */
static void test_far_away_face_is_skipped(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    BOX(&w);
    int sq = igw_square_144(&w, 10.0, 20.0, 0);
    const double m[12] = {1e10, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    igw_set(&w, sq, 0, igw_transform_124(&w, m), 0);
    loaded_model lm;
    cm_status st;
    assert_ok(load_w(&w, &lm, &st));
    assert_clear(CM_OK, &lm);
    char dename[32];
    snprintf(dename, sizeof dename, "DE %d", sq);
    expect_warning(&lm, dename, "from the middle of the model");
    assert_int_equal(lm.brep.nfaces, 7);
    assert_int_equal(lm.brep.faces_failed, 1);
    assert_int_equal(lm.mesh.nverts, 10); /* the box's topology is intact */
    assert_int_equal(lm.mesh.nedges, 15);
    model_free(&lm);
    igw_free(&w);
}

/* Coordinates of 1e300 (finite in the file) are refused by name, not squared into infinity. */
static void test_huge_coordinates(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    BOX(&w);
    int c = igw_add(&w, 110, 0, "0,0,0,1e300,0,0");
    igw_set(&w, c, 1, 0, 0);
    int s = igw_add(&w, 128, 0, "1,1,1,1,1,0,1,0,0,0,0,1,1,0,0,1,1,1,1,1,1,0,0,0,1,0,0,0,1,0,1,1,0,0,1,0,1");
    igw_set(&w, s, 1, 0, 0);
    int cs = igw_add(&w, 142, 0, "0,%d,0,%d,2", s, c);
    igw_set(&w, cs, 1, 0, 0);
    int face = igw_add(&w, 144, 0, "%d,1,0,%d", s, cs);
    loaded_model lm;
    cm_status st;
    assert_ok(load_w(&w, &lm, &st));
    assert_clear(CM_OK, &lm);
    char dename[32];
    snprintf(dename, sizeof dename, "DE %d", face);
    expect_warning(&lm, dename, "beyond +-1e+12 mm");
    assert_int_equal(lm.brep.nfaces, 7);
    model_free(&lm);
    igw_free(&w);
}

/* ---- 3. DAG explosions ---- */

/* a warning of lm's that names DE `de` and says `what` */
static int warned(const iges_file *f, int de, const char *what)
{
    char dename[32];
    snprintf(dename, sizeof dename, "DE %d)", de);
    for (int i = 0; i < f->nwarn; i++)
        if (strstr(f->warn[i].msg, dename) && strstr(f->warn[i].msg, what))
            return 1;
    return 0;
}

/*
 * Blanked (hidden) entities are not part of the model a CAD system shows (issue 14: ovt__asmo's six
 * blanked planes 3.6 m off the part, Shelt_channel_5's 30 blanked subfigure instances placing 24 000
 * of its 27 734 faces): left out by default, each named in a warning and counted; imported with
 * include_blanked; imported anyway, with a warning, when they are all the file has.
 */
static void test_blanked_left_out(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    BOX(&w);                                          /* 7 visible faces */
    int far = igw_square_144(&w, 10.0, 5000.0, 0);    /* a blanked face far away */
    igw_blank(&w, far);
    int dag = igw_subfigure_dag(&w, 3, 2);            /* a blanked instance placing 2^3 faces */
    igw_blank(&w, dag);
    /* a visible instance of a definition holding a face and a blanked nested instance */
    int inner_face = igw_square_144(&w, 10.0, 100.0, 1);
    int inner_def = igw_add(&w, 308, 0, "0,3HIN1,1,%d", inner_face);
    igw_set(&w, inner_def, 1, 0, 0);
    int nested = igw_add(&w, 408, 0, "%d,0,0,0,1", inner_def);
    igw_set(&w, nested, 1, 0, 0);
    igw_blank(&w, nested);
    int outer_face = igw_square_144(&w, 10.0, 200.0, 1);
    int outer_def = igw_add(&w, 308, 0, "0,3HOUT,2,%d,%d", outer_face, nested);
    igw_set(&w, outer_def, 1, 0, 0);
    igw_add(&w, 408, 0, "%d,0,0,0,1", outer_def);
    size_t len;
    char *text = igw_text(&w, &len);
    loaded_model lm;
    cm_status st;
    assert_ok(load_text(text, len, &lm, &st));
    assert_int_equal(lm.brep.nfaces, 7 + 1);          /* the box and the outer definition's face */
    assert_int_equal(lm.stats.blanked_entities, 3);
    assert_int_equal(lm.stats.blanked_faces, 1 + 8 + 1);
    if (!warned(&lm.iges, far, "not imported: blanked") || !warned(&lm.iges, dag, "8 faces") ||
        !warned(&lm.iges, nested, "not imported: blanked"))
        fail_msg("the blanked entities are not named in the warnings");
    assert_true(lm.brep.box.hi.z < 1000.0);           /* the far face took no part in the model */
    assert_int_equal(lm.nleft_out, 0);                /* not faults: nothing is "left out" */
    model_free(&lm);

    /* include_blanked: all of them */
    iges_file f;
    brep_model m;
    brep_import_stats stats;
    cm_status_init(&st);
    memset(&f, 0, sizeof f);
    assert_ok(iges_parse(text, len, &f, &st));
    assert_ok(iges_to_brep(&f, &m, &stats, 1, &st));
    assert_int_equal(m.nfaces, 7 + 1 + 8 + 1 + 1);
    assert_int_equal(stats.blanked_entities, 0);
    brep_free(&m);
    iges_free(&f);
    free(text);
    igw_free(&w);

    /* a file of nothing but blanked faces: imported anyway, and said so */
    igw_init(&w);
    igw_blank(&w, igw_square_144(&w, 10.0, 0.0, 0));
    igw_blank(&w, igw_square_144(&w, 10.0, 50.0, 0));
    text = igw_text(&w, &len);
    assert_ok(load_text(text, len, &lm, &st));
    assert_int_equal(lm.brep.nfaces, 2);
    assert_int_equal(lm.stats.blanked_entities, 0);
    int said = 0;
    for (int i = 0; i < lm.iges.nwarn; i++)
        said |= strstr(lm.iges.warn[i].msg, "every face of the file is blanked") != NULL;
    assert_true(said);
    model_free(&lm);
    free(text);
    igw_free(&w);
}

/* 308/408 nested 15 levels x 8 instances: 8^15 = 3.5e13 placed faces.  Before: a hang. */
static void test_subfigure_dag_refused_by_name(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    int top = igw_subfigure_dag(&w, 15, 8);
    loaded_model lm;
    cm_status st;
    cm_err e = load_w(&w, &lm, &st);
    assert_int_equal(e, CM_E_LIMIT);
    assert_int_equal(st.code, CM_E_LIMIT);
    char dename[32];
    snprintf(dename, sizeof dename, "DE %d", top);
    if (!strstr(lm.iges.err, "subfigure instances expand to more than 262144 faces (limit 262144") ||
        !strstr(lm.iges.err, dename) || !strstr(lm.iges.err, "line "))
        fail_msg("unclear message: %s", lm.iges.err);
    model_free(&lm);
    igw_free(&w);
    /* a DAG within the budget is expanded: 4^3 = 64 placed squares */
    igw_init(&w);
    igw_subfigure_dag(&w, 3, 4);
    assert_ok(load_w(&w, &lm, &st));
    assert_int_equal(lm.brep.nfaces, 64);
    model_free(&lm);
    igw_free(&w);
}

/* A hole made of a 102 DAG, 12 levels x 8: 8^12 = 6.9e10 pieces.  Before: 3 GB in 20 s, then
 * "out of memory" as CM_E_IO (exit 3), blaming an innocent arc. */
static void test_composite_dag_refused_by_name(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    BOX(&w);
    int face = igw_composite_dag_144(&w, 12, 8);
    loaded_model lm;
    cm_status st;
    assert_ok(load_w(&w, &lm, &st));
    assert_clear(CM_OK, &lm);
    char dename[32];
    snprintf(dename, sizeof dename, "DE %d", face);
    expect_warning(&lm, dename, "expands to more than 4096 curve pieces (limit 4096 per curve)");
    assert_int_equal(lm.brep.nfaces, 7);
    model_free(&lm);
    igw_free(&w);
    /* alone, the file has no face left: the error says which face failed, and why */
    igw_init(&w);
    face = igw_composite_dag_144(&w, 12, 8);
    snprintf(dename, sizeof dename, "DE %d", face);
    cm_err e = load_w(&w, &lm, &st);
    assert_int_equal(e, CM_E_IGES);
    if (!strstr(lm.iges.err, "none of the file's 1 faces could be read") || !strstr(lm.iges.err, dename) ||
        !strstr(lm.iges.err, "expands to more than 4096 curve pieces"))
        fail_msg("unclear message: %s", lm.iges.err);
    model_free(&lm);
    igw_free(&w);
}

/* a composite DAG of fan^levels full circles (radius r about (5, 5)) without the writer's face */
static int circle_dag(igw *w, double r, int levels, int fan)
{
    int c = igw_add(w, 100, 0, "0,5,5,%.17g,5,%.17g,5", 5 + r, 5 + r);
    igw_set(w, c, 1, 0, 0);
    for (int k = 0; k < levels; k++) {
        char buf[256];
        int n = snprintf(buf, sizeof buf, "%d", fan);
        for (int i = 0; i < fan; i++)
            n += snprintf(buf + n, sizeof buf - (size_t)n, ",%d", c);
        c = igw_add(w, 102, 0, "%s", buf);
        igw_set(w, c, 1, 0, 0);
    }
    return c;
}

/* Curves each within their budget that together overflow a loop (4096 pieces) or a face (16384):
 * refused before they are built (a loop is chained in time quadratic in its pieces). */
static void test_loop_and_face_piece_budgets(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    BOX(&w);
    int s = igw_add(&w, 128, 0, "1,1,1,1,1,0,1,0,0,0,0,1,1,0,0,1,1,1,1,1,1,0,0,0,10,0,0,0,10,0,10,10,0,0,1,0,1");
    igw_set(&w, s, 1, 0, 0);
    int outer = igw_add(&w, 100, 0, "0,5,5,9,5,9,5");
    igw_set(&w, outer, 1, 0, 0);
    /* a 141 boundary listing a 1024-piece DAG five times: one loop of 5120 pieces */
    int d = circle_dag(&w, 1.0, 5, 4);
    int b = igw_add(&w, 141, 0, "0,0,%d,5,%d,1,0,%d,1,0,%d,1,0,%d,1,0,%d,1,0", s, d, d, d, d, d);
    igw_set(&w, b, 1, 0, 0);
    int f1 = igw_add(&w, 143, 0, "0,%d,1,%d", s, b);
    /* a 144 with five holes of 4096 pieces each: 20480 pieces in one face */
    int h = circle_dag(&w, 1.0, 6, 4);
    int hs = igw_add(&w, 142, 0, "0,%d,0,%d,2", s, h);
    igw_set(&w, hs, 1, 0, 0);
    int os = igw_add(&w, 142, 0, "0,%d,0,%d,2", s, outer);
    igw_set(&w, os, 1, 0, 0);
    int f2 = igw_add(&w, 144, 0, "%d,1,5,%d,%d,%d,%d,%d,%d", s, os, hs, hs, hs, hs, hs);
    loaded_model lm;
    cm_status st;
    assert_ok(load_w(&w, &lm, &st));
    assert_clear(CM_OK, &lm);
    char dename[32];
    snprintf(dename, sizeof dename, "DE %d", f1);
    expect_warning(&lm, dename, "a loop has more than 4096 curve pieces (limit 4096 per loop)");
    snprintf(dename, sizeof dename, "DE %d", f2);
    expect_warning(&lm, dename, "its loops have more than 16384 curve pieces (limit 16384 per face)");
    assert_int_equal(lm.brep.nfaces, 7);
    model_free(&lm);
    igw_free(&w);
}

/* ---- 4. allocation failures are CM_E_NOMEM, never the input's fault ---- */

static void test_allocation_failure_is_nomem(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    BOX(&w); /* arcs, lines, composites, 128 and 120 surfaces */
    size_t len;
    char *t = igw_text(&w, &len);
    int nomem = 0, n;
    for (n = 0; n < 100000; n++) {
        loaded_model lm;
        cm_status st;
        hnurbs_fail_alloc_after(n);
        cm_err e = load_text(t, len, &lm, &st);
        int fired = !hnurbs_fail_alloc_pending();
        hnurbs_fail_alloc_after(-1);
        if (!fired) { /* every allocation of the import has been made to fail once */
            assert_ok(e);
            model_free(&lm);
            break;
        }
        if (e != CM_OK) {
            if (e != CM_E_NOMEM || st.code != CM_E_NOMEM)
                fail_msg("allocation %d failed: %s (status %s), \"%s\"", n, cm_err_name(e), cm_err_name(st.code),
                         lm.iges.err);
            if (lm.iges.err[0] && (!strstr(lm.iges.err, "out of memory") || strstr(lm.iges.err, "cannot build")))
                fail_msg("allocation %d failed: the message blames the input: \"%s\"", n, lm.iges.err);
            nomem++;
        }
        model_free(&lm);
    }
    print_message("  %d allocations, %d of their failures reported as CM_E_NOMEM\n", n, nomem);
    assert_true(nomem > 10);
    free(t);
    igw_free(&w);
}

/* ---- 5. every error names its place; mutations answered promptly ---- */

static void expect_error_with_place(const char *t, size_t len, const char *what)
{
    loaded_model lm;
    cm_status st;
    cm_err e = load_text(t, len, &lm, &st);
    if (e == CM_OK)
        fail_msg("%s: imported", what);
    if (!names_place(lm.iges.err))
        fail_msg("%s: the error names no line or DE: \"%s\"", what, lm.iges.err);
    print_message("  %s: %s\n", what, lm.iges.err);
    model_free(&lm);
}

/* set the section letter (column 73) of every line of section `from` to `to` */
static void relabel(char *t, char from, char to)
{
    for (char *l = t; *l; l = strchr(l, '\n') + 1) {
        if (l[72] == from)
            l[72] = to;
        if (!strchr(l, '\n'))
            break;
    }
}

static void test_errors_name_the_place(void **state)
{
    (void)state;
    igw w;
    igw_init(&w);
    BOX(&w);
    size_t len;
    char *base = igw_text(&w, &len);
    char *t = malloc(len + 1);
    memcpy(t, base, len + 1);
    relabel(t, 'G', 'S'); /* no Global section */
    expect_error_with_place(t, len, "no Global section");
    memcpy(t, base, len + 1);
    relabel(t, 'D', 'G'); /* no Directory section */
    expect_error_with_place(t, len, "no Directory section");
    memcpy(t, base, len + 1);
    relabel(t, 'P', 'D'); /* no Parameter section (and an odd D count) */
    expect_error_with_place(t, len, "no Parameter section");
    expect_error_with_place("\n\n", 2, "empty file");
    /* every face entity's parameters unreadable: no face at all */
    memcpy(t, base, len + 1);
    static const char *const kinds[] = {"\n144,", "\n128,", "\n120,"}; /* faces and untrimmed surfaces */
    for (int k = 0; k < 3; k++)
        for (char *p = t; (p = strstr(p, kinds[k])) != NULL; p += 5)
            p[1] = '9';
    expect_error_with_place(t, len, "no face entity left");
    free(t);
    free(base);
    igw_free(&w);
    /* the only face's surface is not a surface */
    igw_init(&w);
    int c = igw_add(&w, 110, 0, "0,0,0,1,0,0");
    igw_add(&w, 144, 0, "%d,1,0,%d", c, c);
    base = igw_text(&w, &len);
    expect_error_with_place(base, len, "the only face fails");
    free(base);
    igw_free(&w);
}

/* ---- 6. one malformed solid, shell or instance never sinks the model ---- */

/* Before, each of these stopped the whole import with an error (issue 10: "malformed 186/514/408
 * still stops the whole import").  Now the entity is left out by name (a solid's or shell's faces,
 * then owned by nothing, are imported on their own), a bad member pointer is skipped by name, and
 * the summary counts what was left out. */
static void test_bad_structure_left_out(void **state)
{
    (void)state;
    loaded_model lm;
    cm_status st;
    size_t len;
    /* a 186 whose shell pointer names no entity */
    igw w;
    igw_init(&w);
    igw_box_with_hole_186(&w, 40.0, 30.0, 10.0, 6.0);
    char *t = igw_text(&w, &len);
    char *p = strstr(t, "\n186,");
    assert_non_null(p);
    char *comma = strchr(p + 5, ',');
    memset(p + 5, '8', (size_t)(comma - (p + 5))); /* an even DE: never an entry */
    assert_ok(load_text(t, len, &lm, &st));
    assert_clear(CM_OK, &lm);
    expect_warning(&lm, "entity 186 (manifold solid B-rep object, DE ", ") left out: ");
    assert_int_equal(lm.brep.entities_failed, 1);
    assert_int_equal(lm.brep.nfaces, 7);
    model_free(&lm);
    free(t);
    /* a 514 whose first member pointer names no entity: that member is skipped */
    t = igw_text(&w, &len);
    p = strstr(t, "\n514,");
    assert_non_null(p);
    char *m1 = strchr(p + 5, ',') + 1;
    comma = strchr(m1, ',');
    memset(m1, '8', (size_t)(comma - m1)); /* an even DE: never an entry */
    assert_ok(load_text(t, len, &lm, &st));
    assert_clear(CM_OK, &lm);
    expect_warning(&lm, "shell DE ", ": member 1 skipped: ");
    assert_int_equal(lm.brep.nfaces, 7); /* the face it was meant to name comes in on its own */
    model_free(&lm);
    free(t);
    igw_free(&w);
    /* an instance of something that is not a subfigure definition, beside a good face */
    igw_init(&w);
    igw_square_144(&w, 1.0, 0.0, 0);
    igw_add(&w, 408, 0, "1,0,0,0,1");
    t = igw_text(&w, &len);
    assert_ok(load_text(t, len, &lm, &st));
    assert_clear(CM_OK, &lm);
    expect_warning(&lm, "entity 408 (", ") left out: ");
    assert_int_equal(lm.brep.nfaces, 1);
    model_free(&lm);
    free(t);
    igw_free(&w);
}

/* Random byte mutations of the two synthetic solids (144 and B-rep): each is answered within
 * PROMPT_SECONDS, by an import whose warnings name their place or by an error that does. */
static void test_random_mutations(void **state)
{
    (void)state;
    static const char alphabet[] = "0123456789,;.-+DEH 9e\n";
    char *texts[2];
    size_t lens[2];
    for (int k = 0; k < 2; k++) {
        igw w;
        igw_init(&w);
        if (k == 0)
            BOX(&w);
        else
            igw_box_with_hole_186(&w, 40.0, 30.0, 10.0, 6.0);
        texts[k] = igw_text(&w, &lens[k]);
        igw_free(&w);
    }
    uint32_t seed = 20261122u;
    int ok = 0, failed = 0;
    for (int r = 0; r < 400; r++) {
        int k = r & 1;
        char *t = malloc(lens[k] + 1);
        memcpy(t, texts[k], lens[k] + 1);
        int nmut = 1 + (int)(test_rand(&seed) * 4);
        for (int m = 0; m < nmut; m++) {
            size_t at = (size_t)(test_rand(&seed) * (double)lens[k]);
            t[at] = alphabet[(int)(test_rand(&seed) * (double)(sizeof alphabet - 1))];
        }
        loaded_model lm;
        cm_status st;
        cm_err e = load_text(t, lens[k], &lm, &st);
        assert_clear(e, &lm);
        if (e == CM_OK)
            ok++;
        else
            failed++;
        model_free(&lm);
        free(t);
    }
    print_message("  400 mutations: %d imported, %d refused with a message naming the place\n", ok, failed);
    free(texts[0]);
    free(texts[1]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_type_number_out_of_int_range),
        cmocka_unit_test(test_counts_of_2147483647),
        cmocka_unit_test(test_matrix_entry_minus_1e308),
        cmocka_unit_test(test_far_away_face_is_skipped),
        cmocka_unit_test(test_huge_coordinates),
        cmocka_unit_test(test_subfigure_dag_refused_by_name),
        cmocka_unit_test(test_blanked_left_out),
        cmocka_unit_test(test_composite_dag_refused_by_name),
        cmocka_unit_test(test_loop_and_face_piece_budgets),
        cmocka_unit_test(test_allocation_failure_is_nomem),
        cmocka_unit_test(test_errors_name_the_place),
        cmocka_unit_test(test_bad_structure_left_out),
        cmocka_unit_test(test_random_mutations),
    };
    if (getenv("TEST_FILTER")) /* one test at a time: TEST_FILTER=test_subfigure_dag_refused_by_name */
        cmocka_set_test_filter(getenv("TEST_FILTER"));
    return cmocka_run_group_tests(tests, NULL, NULL);
}
