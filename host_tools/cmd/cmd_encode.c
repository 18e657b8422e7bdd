/*
 * cmd_encode.c - `cmz encode MODEL.igs -o MODEL.cmz`: import the model,
 * encode it (encode/encode.h), write the file atomically, and report every
 * face left out, the summary line and, with --report, a row per face.
 * A folder or a list of models goes to cmd_vault.c, which runs this once
 * per model.
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cm/cm_format.h"
#include "cm/cm_method.h"
#include "cm_report.h"
#include "encode/encode.h"
#include "profiles.h"

/* an import warning about the structure around faces (iges_brep.c, step_brep.c): a solid, shell,
   instance or placement left out, or a member pointer of one skipped */
static int is_structure_warning(const char *msg)
{
    return (strncmp(msg, "entity ", 7) == 0 && strstr(msg, ") left out: ")) ||
           ((strncmp(msg, "shell DE ", 9) == 0 || strncmp(msg, "solid DE ", 9) == 0) && strstr(msg, " skipped")) ||
           (msg[0] == '#' && strstr(msg, "left out")); /* STEP (step_brep.c): a shell, placement or mapped item */
}

/* write a buffer to `path` through a temporary file and a rename: never half a file */
static int write_atomic(const char *path, const uint8_t *data, size_t len)
{
    size_t tl = strlen(path) + 32;
    char *tmp = malloc(tl);
    if (!tmp) {
        fprintf(stderr, "%s: out of memory\n", cmd_prog);
        return EXIT_NOMEM;
    }
    snprintf(tmp, tl, "%s.tmp%ld", path, (long)getpid());
    FILE *f = fopen(tmp, "wb");
    int ok = f && fwrite(data, 1, len, f) == len;
    if (f && fclose(f) != 0)
        ok = 0;
    if (!ok || rename(tmp, path) != 0) {
        fprintf(stderr, "%s: writing %s failed: %s\n", cmd_prog, path, strerror(errno));
        remove(tmp);
        free(tmp);
        return EXIT_IO;
    }
    free(tmp);
    return EXIT_OK;
}

/* --format MAJOR[.MINOR]: write what a reader of that version reads (encode_opts_for_format) */
static int parse_format(const char *v, encode_opts *o)
{
    int major = 0, minor = 0, used = 0;
    int n = sscanf(v, "%d%n.%d%n", &major, &used, &minor, &used);
    int newest_minor = major == CM_FMT_VERSION_MAJOR ? CM_FMT_VERSION_MINOR : major == 2 ? CM_FMT_V2_MINOR : 0;
    if (n < 1 || v[used] != '\0' || major < CM_FMT_VERSION_MIN_MAJOR || major > CM_FMT_VERSION_MAJOR || minor < 0 ||
        minor > newest_minor) {
        fprintf(stderr, "%s encode: --format '%s': a version this writer knows: 1.0, 2.0 to 2.%d, %d.0, or %d.0 to the newest, %d.%d\n",
                cmd_prog, v, CM_FMT_V2_MINOR, CM_FMT_PREDICT_MAJOR, CM_FMT_VERSION_MAJOR, CM_FMT_VERSION_MAJOR,
                CM_FMT_VERSION_MINOR);
        return 1;
    }
    if (n == 1)
        minor = newest_minor;
    encode_opts_for_format(o, major, minor);
    return 0;
}

cmd_encode_summary *cmd_encode_summary_out;

/* a vault option (cmd_vault.c): taken into vo, 1 (2 with its value), 0 if `a` is not one, -1 on a bad value */
static int vault_arg(const char *a, const char *v, cmd_vault_opts *vo)
{
    if (strcmp(a, "--list") == 0 && v) {
        vo->list = v;
        return 2;
    }
    if (strcmp(a, "--summary") == 0 && v) {
        vo->summary = v;
        return 2;
    }
    if (strcmp(a, "--force") == 0) {
        vo->force = 1;
        return 1;
    }
    if (strcmp(a, "-j") == 0 && v) {
        double j;
        if (cmd_parse_real(a, v, 1, 256, &j) || j != (int)j)
            return -1;
        vo->jobs = (int)j;
        return 2;
    }
    if (strcmp(a, "--timeout") == 0 && v) {
        if (cmd_parse_real(a, v, 0, 1e6, &vo->timeout_s))
            return -1;
        return 2;
    }
    if (strcmp(a, "--shard") == 0 && v) {
        int k = -1, n = 0, used = 0;
        if (sscanf(v, "%d/%d%n", &k, &n, &used) != 2 || v[used] || n < 1 || k < 0 || k >= n) {
            fprintf(stderr, "%s: --shard wants K/N with 0 <= K < N (this task's index and the task count), not '%s'\n",
                    cmd_prog, v);
            return -1;
        }
        vo->shard_k = k;
        vo->shard_n = n;
        return 2;
    }
    return 0;
}

static int is_directory(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 && S_ISDIR(sb.st_mode);
}

/* a folder or a list of models (cmd_vault.c), `pass` the encoding options as given: what only one
   model can take is refused here, before any worker starts */
static int encode_vault(cmd_vault_opts *vo, const char *path, const char *out, const char *report,
                        const char *profile, const char **pass, int npass)
{
    struct stat sb;
    if (report)
        fprintf(stderr, "%s encode: --report is a model's face table: give it one model, not a folder or a list\n",
                cmd_prog);
    else if (vo->list && path)
        fprintf(stderr, "%s encode: a folder or --list, not both (got %s and --list %s)\n", cmd_prog, path, vo->list);
    else if (!out)
        fprintf(stderr, "%s encode: usage: cmz encode FOLDER|--list FILE -o OUTFOLDER [-j N] [options] (see cmz --help)\n",
                cmd_prog);
    else if (profile && !cm_profile_limits(profile)) /* every model would fail alike */
        fprintf(stderr, "%s encode: unknown profile '%s' (terminal, host or tiny)\n", cmd_prog, profile);
    else if (stat(out, &sb) == 0 && !S_ISDIR(sb.st_mode))
        fprintf(stderr, "%s encode: -o %s: a folder for the outputs, and this is a file\n", cmd_prog, out);
    else {
        vo->folder = path;
        vo->out = out;
        return cmd_vault(vo, pass, npass);
    }
    return EXIT_USAGE;
}

int cmd_encode(int argc, char **argv)
{
    const char *path = NULL, *out = NULL, *report = NULL, *profile = NULL;
    encode_opts o;
    encode_opts_default(&o);
    o.progress = cmd_progress;
    /* the options each model of a vault is encoded with, as given (cmd_vault.c) */
    const char **pass = calloc((size_t)argc + 1, sizeof *pass);
    int npass = 0, vault_opt = 0;
    cmd_vault_opts vo = {.jobs = 1};
    if (!pass) {
        fprintf(stderr, "%s: out of memory\n", cmd_prog);
        return EXIT_NOMEM;
    }
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int taken = vault_arg(a, v, &vo), first = i;
        if (taken < 0) {
            goto usage;
        }
        if (taken > 0) {
            vault_opt |= strcmp(a, "-j") != 0; /* -j: a vault's models, or one model's faces */
            i += taken - 1;
            continue;
        }
        /* an encoding option, with the value the parser below takes for it (argv[first..i]) */
        int encoding = a[0] == '-' && a[1] && strcmp(a, "-o") != 0 && strcmp(a, "-q") != 0 && strcmp(a, "--report") != 0;
        if (strcmp(a, "-o") == 0 && v) {
            out = v;
            i++;
        } else if (strcmp(a, "--report") == 0 && v) {
            report = v;
            o.measure_mesh = 1; /* the report's mesh_dev_mm column */
            i++;
        } else if (strcmp(a, "--profile") == 0 && v) {
            profile = v;
            i++;
        } else if (strcmp(a, "--tol") == 0 && v) {
            if (cmd_parse_real(a, v, 1e-9, 0.5, &o.rel_tol))
                goto usage;
            o.rel_set = 1;
            i++;
        } else if (strcmp(a, "--tol-abs") == 0 && v) {
            if (cmd_parse_real(a, v, 1e-9, 1e9, &o.abs_tol))
                goto usage;
            i++;
        } else if (strcmp(a, "--no-gregory") == 0) {
            o.gregory = 0; /* planes only (cmz --help): no fitted surface either */
            o.g1fit = 0;
            o.nfill = 0;
        } else if (strcmp(a, "--no-gregory-exact") == 0) {
            o.gregory_exact = 0;
        } else if (strcmp(a, "--no-gregory-fit") == 0) {
            o.gregory_fit = 0;
        } else if (strcmp(a, "--no-nfill") == 0) {
            o.nfill = 0;
        } else if (strcmp(a, "--no-g1fit") == 0) {
            o.g1fit = 0;
        } else if (strcmp(a, "--steps") == 0 && v) {
            o.steps = v;
            i++;
        } else if (strcmp(a, "--no-instances") == 0) {
            o.instances = 0;
        } else if (strcmp(a, "--no-turning-basis") == 0) {
            o.turning_basis = 0;
        } else if (strcmp(a, "--budget-steps") == 0) { /* the default since format 4; still accepted */
            o.budget_steps = 1;
        } else if (strcmp(a, "--no-budget-steps") == 0) {
            o.budget_steps = 0;
        } else if (strcmp(a, "--format") == 0 && v) {
            if (parse_format(v, &o))
                goto usage;
            i++;
        } else if (strcmp(a, "--strict") == 0) {
            o.strict = 1;
        } else if (strcmp(a, "--quant") == 0 && v) {
            if (cmd_parse_real(a, v, 1e-12, 1e-2, &o.quant_rel))
                goto usage;
            i++;
        } else if (strcmp(a, "--tess") == 0 && v) {
            if (cmd_parse_real(a, v, 1e-7, 0.1, &o.tess_rel))
                goto usage;
            i++;
        } else if (cmd_common_arg("encode", a, &path)) {
            goto usage;
        }
        for (int k = first; encoding && k <= i; k++)
            pass[npass++] = argv[k];
    }
    if (vo.list || (path && is_directory(path))) {
        int rc = encode_vault(&vo, path, out, report, profile, pass, npass);
        free(pass);
        return rc;
    }
    free(pass);
    if (vault_opt) {
        fprintf(stderr, "%s encode: --list, --summary, --force, --timeout and --shard are for a folder or a list "
                        "of models (see cmz --help)\n", cmd_prog);
        return EXIT_USAGE;
    }
    if (!path || !out) {
        fprintf(stderr, "%s encode: usage: cmz encode MODEL.igs -o MODEL.cmz [options] (see cmz --help)\n", cmd_prog);
        return EXIT_USAGE;
    }
    o.jobs = vo.jobs; /* one model: its faces' methods chosen on N processes */
    if (profile) {
        o.target = cm_profile_limits(profile);
        o.target_name = profile;
        if (!o.target) {
            fprintf(stderr, "%s encode: unknown profile '%s' (terminal, host or tiny)\n", cmd_prog, profile);
            return EXIT_USAGE;
        }
    }
    loaded_model lm;
    /* format 4.3: an assembly's part placed several times travels once, each copy as a transform */
    cmd_fold_instances = encode_places(&o);
    int loaded = cmd_load(path, &lm);
    if (loaded != EXIT_OK)
        return loaded;
    cm_status st;
    encode_result r;
    cm_status_init(&st);
    if (o.strict && lm.brep.entities_failed > 0) {
        for (int i = 0; i < lm.iges.nwarn; i++)
            if (is_structure_warning(lm.iges.warn[i].msg)) {
                fprintf(stderr, "%s: %s: line %d: %s (--strict: nothing written)\n", cmd_prog, path,
                        lm.iges.warn[i].line, lm.iges.warn[i].msg);
                break;
            }
        model_free(&lm);
        return EXIT_INPUT;
    }
    if (o.strict && lm.nleft_out > 0) {
        const iges_warning *w = &lm.iges.warn[lm.left_out[0]];
        fprintf(stderr, "%s: %s: %s%.0d%s%s (--strict: nothing written)\n", cmd_prog, path, w->line ? "line " : "",
                w->line, w->line ? ": " : "", w->msg);
        model_free(&lm);
        return EXIT_INPUT;
    }
    cm_err e = encode_model(&lm, &o, &r, &st);
    if (e == CM_E_LIMIT && st.limit == CM_LIMIT_MAX_PLACEMENTS && lm.brep.nplacements > 0 && o.target) {
        /* the board places fewer copies than the model has: every placed face sent as a face of
           its own (MAX_FACES counts the copies either way) */
        encode_result_free(&r);
        model_free(&lm);
        cmd_fold_instances = 0;
        if ((loaded = cmd_load(path, &lm)) != EXIT_OK)
            return loaded;
        fprintf(stderr, "%s: %s: note: profile %s places at most %u copies: every placed face sent as a face\n",
                cmd_prog, path, profile, (unsigned)o.target[CM_LIMIT_MAX_PLACEMENTS].value);
        cm_status_init(&st);
        e = encode_model(&lm, &o, &r, &st);
    }
    int rc = EXIT_OK;
    /* every face left out, by the import or the encoder, is named; so is every solid, shell or
       instance the import left out, and every member pointer it skipped */
    for (int i = 0; i < lm.nleft_out; i++) {
        const iges_warning *w = &lm.iges.warn[lm.left_out[i]];
        fprintf(stderr, "%s: %s: warning: %s%.0d%s%s\n", cmd_prog, path, w->line ? "line " : "", w->line,
                w->line ? ": " : "", w->msg);
    }
    for (int i = 0; i < lm.iges.nwarn; i++) {
        const iges_warning *w = &lm.iges.warn[i];
        if (is_structure_warning(w->msg))
            fprintf(stderr, "%s: %s: warning: %s%.0d%s%s\n", cmd_prog, path, w->line ? "line " : "", w->line,
                    w->line ? ": " : "", w->msg);
    }
    if (r.refusal[0] && e != CM_E_LIMIT) {
        fprintf(stderr, "%s: %s: %s (nothing written)\n", cmd_prog, path, r.refusal);
        rc = EXIT_INPUT;
    } else if (e == CM_E_LIMIT && r.refusal[0]) {
        fprintf(stderr, "%s: %s: refused: %s (nothing written)\n", cmd_prog, path, r.refusal);
        rc = EXIT_INPUT;
    } else if (e != CM_OK) {
        cm_report_status(stderr, cmd_prog, path, &st);
        rc = cmd_exit_for(st.code);
    }
    if (rc == EXIT_OK)
        rc = write_atomic(out, r.bytes, r.len);
    if (rc == EXIT_OK && report) {
        FILE *f = fopen(report, "w");
        if (!f) {
            fprintf(stderr, "%s: %s: %s\n", cmd_prog, report, strerror(errno));
            rc = EXIT_IO;
        } else {
            fprintf(f, "face\tde\tentity\tsurface\tmethod\tbbox_mm\tplane_dev_mm\tmax_err_mm\tratio\tsurf_ctrl"
                       "\tlayout\tavg_err_mm\tg1_worst_deg\tgregory_ratio\twhy_kept\tfit_m"
                       "\tsides\tholes\tmesh_dev_mm\n");
            for (int i = 0; i < lm.mesh.nfaces; i++) {
                const face_report *fr = &r.faces[i];
                const brep_face *bf = &lm.brep.faces[lm.mesh.faces[i].brep_face];
                const cmesh_face *cf = &lm.mesh.faces[i];
                double c = fr->g1_cos > 1.0 ? 1.0 : fr->g1_cos;
                char dev[32] = "-";
                if (fr->mesh_dev >= 0)
                    snprintf(dev, sizeof dev, "%.6g", fr->mesh_dev);
                fprintf(f, "%d\t%d\t%d\t%d\t%s\t%.6g\t%.6g\t%.6g\t%.6g\t%d\t%d\t%.6g\t%.4g\t%.6g\t%s\t%d\t%d\t%d\t%s\n", i,
                        bf->src_de, bf->src_type, bf->surf_type,
                        cm_method_name((unsigned)fr->method), fr->bbox, fr->plane_dev, fr->rebuild_max, fr->ratio, fr->surf_ctrl,
                        fr->layout, fr->rebuild_avg, acos(c) * 57.29577951308232, fr->greg_ratio,
                        cm_method_of((unsigned)fr->method)->kept_surface && fr->why ? fr->why : "-", fr->fit_m,
                        lm.mesh.loops[cf->first_loop].n, cf->nloops - 1, dev);
            }
            if (fclose(f) != 0)
                rc = EXIT_IO;
        }
    }
    if (rc == EXIT_OK) {
        FILE *in = fopen(path, "rb");
        long isize = 0;
        if (in) {
            fseek(in, 0, SEEK_END);
            isize = ftell(in);
            fclose(in);
        }
        char left[128] = "";
        if (lm.nleft_out > 0)
            snprintf(left, sizeof left, ", %d left out (see warnings)", lm.nleft_out);
        if (lm.brep.entities_failed > 0)
            snprintf(left + strlen(left), sizeof left - strlen(left), "; %d solids, shells or instances left out "
                     "(see warnings)", lm.brep.entities_failed);
        char methods[128];
        cm_report_method_counts(methods, sizeof methods, r.faces_by_method, 0);
        /* format 4.3: the faces the model shows, those sent and those placed again as copies */
        char placed[128] = "";
        if (r.placements > 0)
            snprintf(placed, sizeof placed, "; %d sent, %u as %u placed copies of parts", lm.mesh.nfaces,
                     r.placed_faces, r.placements);
        /* format 4.11: the parts the terminal steps through */
        char parts[96] = "";
        if (r.parts > 0 && o.steps)
            snprintf(parts, sizeof parts, "; %d parts, %d in the order of %s", r.parts, r.parts_stepped, o.steps);
        else if (r.parts > 0)
            snprintf(parts, sizeof parts, "; %d parts", r.parts);
        char arcs[32] = "";
        if (r.edges_arcs > 0)
            snprintf(arcs, sizeof arcs, ", %d arcs", r.edges_arcs);
        printf("%s -> %s: %d faces (%s%s%s%s), %d edges (%d lines%s), %zu bytes, %.1fx smaller than the %s (%ld bytes)\n",
               path, out, lm.mesh.nfaces + (int)r.placed_faces, methods, left, placed, parts,
               r.edges_line + r.edges_curve, r.edges_line, arcs, r.len, r.len ? (double)isize / (double)r.len : 0.0,
               lm.is_step ? "STEP" : "IGES", isize);
        if (r.edges_refit + r.surfs_refit > 0)
            fprintf(stderr, "%s: %s: note: %d edge curves and %d surfaces re-approximated within a quarter of "
                    "their tolerance to fit profile %s\n", cmd_prog, path, r.edges_refit, r.surfs_refit,
                    o.target_name ? o.target_name : "?");
        if (cmd_encode_summary_out) {
            cmd_encode_summary *sm = cmd_encode_summary_out;
            memset(sm, 0, sizeof *sm);
            sm->cmz_bytes = (long)r.len;
            sm->faces_sent = lm.mesh.nfaces;
            sm->faces_placed = (int)r.placed_faces;
            sm->left_out = lm.nleft_out;
            for (int i = 0; i < lm.mesh.nfaces; i++) {
                const face_report *fr = &r.faces[i];
                if (cm_method_of((unsigned)fr->method)->kept_surface)
                    sm->kept++;
                if (fr->rebuild_max > sm->max_err_mm)
                    sm->max_err_mm = fr->rebuild_max;
                if (fr->ratio > sm->max_ratio)
                    sm->max_ratio = fr->ratio;
            }
        }
        if (r.tess_used > r.tess_asked)
            fprintf(stderr, "%s: %s: note: recommended chordal tolerance %.3g mm, not %.3g mm (%.0fx coarser), so that "
                    "profile %s can tessellate the model (a viewer may ask for finer: --tess)\n", cmd_prog, path,
                    r.tess_used, r.tess_asked, r.tess_used / r.tess_asked, o.target_name ? o.target_name : "?");
    }
    encode_result_free(&r);
    model_free(&lm);
    return rc;
usage: /* a bad argument, already said */
    free(pass);
    return EXIT_USAGE;
}
