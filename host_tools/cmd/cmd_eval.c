/*
 * cmd_eval.c - `cmz eval MODEL.igs MODEL.cmz`: check a finished file
 * without trusting the encoder: rebuild every face with the terminal's code
 * and measure it against the IGES model (spec §12) and across tangent edges
 * (spec §13).
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_const.h"
#include "cm/cm_format.h"
#include "cm/cm_method.h"
#include "cm_decode_file.h"
#include "cm_report.h"
#include "encode/encode.h"
#include "encode/verify.h"

static cm_rebuild_ws eval_ws; /* large: static storage, as on the terminal */

/*
 * The file has fewer faces than the IGES model: the encoder left some out (see encode_model).  It is
 * deterministic, so encoding a second copy with the file's own settings tells which; those are left
 * out of lm too (lm itself keeps the orientation its face domains were built with).
 */
static cm_err match_left_out(const char *path, const cm_model *m, loaded_model *lm, int *left_out, cm_status *st)
{
    loaded_model again;
    cm_err e = model_load_ex(path, &again, lm->load_flags, NULL, NULL, st);
    encode_opts o;
    encode_opts_default(&o);
    double diag = brep_diag(&again.brep);
    if (m->rel_tol > 0)
        o.rel_tol = m->rel_tol;
    if (diag > 0) {
        o.tess_rel = m->tess_tol / diag;
        o.quant_rel = m->q / diag * (1.0 + 1e-9); /* the same power of two */
    }
    encode_result r;
    memset(&r, 0, sizeof r);
    if (e == CM_OK)
        e = encode_model(&again, &o, &r, st);
    if (e == CM_E_LIMIT)
        e = CM_OK;
    encode_result_free(&r);
    /* again's faces are lm's in the same order, less those left out */
    int *out = malloc(((size_t)lm->brep.nfaces + 1) * sizeof *out), nout = 0;
    if (e == CM_OK && !out)
        e = cm_fail(st, CM_E_NOMEM, "out of memory");
    for (int b = 0, i = 0; e == CM_OK && b < lm->brep.nfaces; b++) {
        const brep_face *A = &lm->brep.faces[b], *B = i < again.brep.nfaces ? &again.brep.faces[i] : NULL;
        if (B && A->src_de == B->src_de && A->instance == B->instance && A->surf_type == B->surf_type)
            i++;
        else
            out[nout++] = b;
    }
    for (int k = nout - 1; e == CM_OK && k >= 0; k--) {
        e = model_leave_out_face(lm, out[k], "as the encoder did", st);
        ++*left_out;
    }
    free(out);
    model_free(&again);
    return e;
}

int cmd_eval(int argc, char **argv)
{
    const char *paths[2] = {NULL, NULL}, *report = NULL;
    double rel = 0, abs_tol = 0;
    int rel_set = 0, np = 0;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--tol") == 0 && v) {
            if (cmd_parse_real(a, v, 1e-9, 0.5, &rel))
                return EXIT_USAGE;
            rel_set = 1;
            i++;
        } else if (strcmp(a, "--tol-abs") == 0 && v) {
            if (cmd_parse_real(a, v, 1e-9, 1e9, &abs_tol))
                return EXIT_USAGE;
            i++;
        } else if (strcmp(a, "--report") == 0 && v) {
            report = v;
            i++;
        } else if (strcmp(a, "-q") == 0) {
            cmd_quiet = 1;
        } else if ((a[0] == '-' && a[1]) || np == 2) {
            fprintf(stderr, "%s eval: usage: cmz eval MODEL.igs MODEL.cmz [--tol REL] [--tol-abs MM] [--report F]\n",
                    cmd_prog);
            return EXIT_USAGE;
        } else {
            paths[np++] = a;
        }
    }
    if (np != 2) {
        fprintf(stderr, "%s eval: usage: cmz eval MODEL.igs MODEL.cmz [--tol REL] [--tol-abs MM] [--report F]\n",
                cmd_prog);
        return EXIT_USAGE;
    }
    cm_decoder *decoder = cmd_decoder();
    cm_status st;
    cm_status_init(&st);
    if (cm_decode_read(paths[1], decoder, &st) != CM_OK) {
        cm_report_status(stderr, cmd_prog, paths[1], &st);
        return cmd_exit_for(st.code);
    }
    loaded_model lm;
    /* a file with placed copies (format 4.3) is measured against the model folded as the encoder
       folded it: the part's faces once, and each copy's transform against the model's own */
    cmd_fold_instances = decoder->model.nplacements > 0;
    int loaded = cmd_load(paths[0], &lm);
    if (loaded != EXIT_OK)
        return loaded;
    cm_err e = CM_OK;
    int fails = 0;
    const cm_model *m = &decoder->model;
    if (!rel_set)
        rel = m->rel_tol > 0 ? m->rel_tol : 0.01;
    /* the encoder's default (encode_opts_for_model): with neither --tol nor --tol-abs, a face's
       tolerance is also at most 1e-3 of the model's diagonal */
    if (!rel_set && !(abs_tol > 0)) {
        encode_opts d;
        encode_opts_default(&d);
        encode_opts_for_model(&d, brep_diag(&lm.brep));
        abs_tol = d.abs_tol;
        rel_set = d.rel_set;
    }
    int left_out = 0;
    if ((int)m->nfaces < lm.mesh.nfaces && (e = match_left_out(paths[0], m, &lm, &left_out, &st)) != CM_OK) {
        cm_report_status(stderr, cmd_prog, paths[0], &st);
        model_free(&lm);
        return cmd_exit_for(st.code);
    }
    if ((int)m->nfaces != lm.mesh.nfaces) {
        fprintf(stderr, "%s eval: %s has %u faces, %s %d: not the same model\n", cmd_prog, paths[1], m->nfaces,
                paths[0], lm.mesh.nfaces);
        model_free(&lm);
        return EXIT_INPUT;
    }
    /* the copies, in the writer's order: those of lm whose part still has a face (a part the encoder
       left out whole takes its copies with it); the linear part travels exactly, the translation as
       the grid origin's displacement (half a step off at most, and the origin's rounding) */
    uint32_t k = 0;
    for (int jp = 0; jp < lm.brep.nplacements; jp++) {
        int has = 0;
        for (int f = 0; f < lm.mesh.nfaces && !has; f++)
            has = lm.brep.faces[lm.mesh.faces[f].brep_face].instance == lm.brep.placements[jp].proto;
        if (!has)
            continue;
        if (k >= m->nplacements)
            break;
        if (!encode_placement_is(m->placements[k].m, &lm.brep.placements[jp].xf, m->q, m->origin)) {
            fprintf(stderr, "%s eval: %s: copy %u is not placed as in %s\n", cmd_prog, paths[1], k, paths[0]);
            fails++;
        }
        k++;
    }
    if (k != m->nplacements) {
        fprintf(stderr, "%s eval: %s places %u copies, %s %u: not the same model\n", cmd_prog, paths[1],
                m->nplacements, paths[0], k);
        model_free(&lm);
        return EXIT_INPUT;
    }
    int nf = (int)m->nfaces, rc = EXIT_OK;
    face_surface *fs = calloc((size_t)nf + 1, sizeof *fs);
    face_error *fe = calloc((size_t)nf + 1, sizeof *fe);
    double *g1c = malloc(((size_t)nf + 1) * sizeof *g1c);
    if (!fs || !fe || !g1c) {
        fprintf(stderr, "%s: out of memory\n", cmd_prog);
        free(fs);
        free(fe);
        free(g1c);
        model_free(&lm);
        return EXIT_NOMEM;
    }
    int count[CM_METHOD_COUNT] = {0};
    double worst_ratio[CM_METHOD_COUNT] = {0}, sum_ratio[CM_METHOD_COUNT] = {0};
    for (int f = 0; f < nf; f++) {
        cmd_progress("measuring", f + 1, nf, NULL);
        g1c[f] = 1.0;
        int meth = m->faces[f].method;
        count[meth]++;
        if (cm_method_of((unsigned)meth)->kept_surface)
            continue;
        cm_rebuilt rb;
        if (cm_rebuild_face(m, (uint32_t)f, &rb, &eval_ws, &st) != CM_OK) {
            cm_report_status(stderr, cmd_prog, paths[1], &st);
            rc = EXIT_INPUT;
            break;
        }
        if (!face_surface_set(&fs[f], &rb)) {
            rc = EXIT_NOMEM;
            break;
        }
        if (!verify_face(&lm, m, f, &rb, HUGE_VAL, &fe[f])) {
            fprintf(stderr, "%s eval: face %d: no parameter domain in the model to measure against\n", cmd_prog, f);
            fails++;
            continue;
        }
        double tol = encode_face_tol(rel, rel_set || !(abs_tol > 0), abs_tol, rb.bbox);
        worst_ratio[meth] = fe[f].ratio > worst_ratio[meth] ? fe[f].ratio : worst_ratio[meth];
        sum_ratio[meth] += fe[f].ratio;
        if (!(fe[f].max < tol)) {
            fprintf(stderr, "%s eval: face %d (%s): max error %.4g mm > tolerance %.4g mm (ratio %.4g %%)\n", cmd_prog,
                    f, cm_method_name((unsigned)meth), fe[f].max, tol, 100 * fe[f].ratio);
            fails++;
        }
    }
    /* §13 on every G1 edge next to a rebuilt face */
    int g1_edges = 0, g1_fail = 0;
    double g1_worst = 1.0;
    for (uint32_t ed = 0; rc == EXIT_OK && ed < m->nedges; ed++) {
        int32_t a = m->edge_face[ed][0], b = m->edge_face[ed][1];
        if (!m->edges[ed].g1 || a < 0 || b < 0 || a == b)
            continue;
        if (!fs[a].rebuilt && !fs[b].rebuilt)
            continue;
        double c = verify_g1_edge(&lm, m, ed, fs, NULL);
        g1_edges++;
        g1c[a] = c < g1c[a] ? c : g1c[a];
        g1c[b] = c < g1c[b] ? c : g1c[b];
        g1_worst = c < g1_worst ? c : g1_worst;
        if (c < CM_COS_G1) {
            fprintf(stderr, "%s eval: G1 edge %u between faces %d and %d: normals %.3g deg apart\n", cmd_prog, ed, a, b,
                    acos(c > 1 ? 1 : c) * 57.29577951308232);
            g1_fail++;
        }
    }
    if (rc == EXIT_OK && report) {
        FILE *out = fopen(report, "w");
        if (!out) {
            fprintf(stderr, "%s: %s: %s\n", cmd_prog, report, strerror(errno));
            rc = EXIT_IO;
        } else {
            fprintf(out, "face\tmethod\tlayout\tbbox_mm\tavg_err_mm\tmax_err_mm\tratio\tg1_worst_deg\n");
            for (int f = 0; f < nf; f++) {
                const cm_face *F = &m->faces[f];
                double c = g1c[f] > 1 ? 1 : g1c[f];
                fprintf(out, "%d\t%s\t%d\t%.6g\t%.6g\t%.6g\t%.6g\t%.4g\n", f, cm_method_name(F->method),
                        cm_method_of(F->method)->layouts ? F->layout : -1, fe[f].bbox,
                        fe[f].avg, fe[f].max, fe[f].ratio, acos(c) * 57.29577951308232);
            }
            if (fclose(out) != 0)
                rc = EXIT_IO;
        }
    }
    if (rc == EXIT_OK) {
        /* per method in the table's order: a rebuilt one with its worst and mean error ratio */
        printf("%s against %s: %d faces:", paths[1], paths[0], nf);
        for (int i = 0; i < CM_METHOD_COUNT; i++) {
            const cm_method *M = cm_method_table[i];
            if (M->kept_surface)
                printf("%s kept %d", i ? "," : "", count[M->id]);
            else
                printf("%s %s %d (worst ratio %.3g %%, mean %.3g %%)", i ? "," : "", M->name, count[M->id],
                       100 * worst_ratio[M->id], count[M->id] ? 100 * sum_ratio[M->id] / count[M->id] : 0.0);
        }
        printf("\n");
        if (left_out)
            printf("%d faces left out by the encoder (as cmz encode warned)\n", left_out);
        printf("G1: %d tangent edges next to rebuilt faces, worst %.3g deg%s\n", g1_edges,
               acos(g1_worst > 1 ? 1 : g1_worst) * 57.29577951308232, g1_fail ? "" : " (all within 1 deg)");
        if (fails || g1_fail) {
            printf("FAILED: %d faces out of tolerance, %d G1 edges over 1 deg\n", fails, g1_fail);
            rc = EXIT_INPUT;
        } else {
            printf("ok: every rebuilt face within tolerance\n");
        }
    }
    for (int f = 0; f < nf; f++)
        face_surface_free(&fs[f]);
    free(fs);
    free(fe);
    free(g1c);
    model_free(&lm);
    return rc;
}
