/*
 * cmz - the curvemesh workstation tool.
 *
 *   cmz info MODEL.igs [--json]            what the importer sees in a CAD file
 *   cmz sample MODEL.igs -o POINTS.xyz     points on every trimmed face
 *   cmz --limits | --version | --help
 *
 * Exit codes: 0 success, 1 the input is malformed or unsupported, 2 usage,
 * 3 I/O error (cannot read or write a file), 4 out of memory.
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cm/cm_format.h"
#include "cm/cm_limits_info.h"
#include "cm_decode_file.h"
#include "cm_report.h"
#include "encode/encode.h"
#include "model_load.h"
#include "encode/verify.h"
#include "profiles.h"
#include "send/send_cmd.h"

#define CMZ_VERSION "0.1.0"

enum { EXIT_OK = 0, EXIT_INPUT = 1, EXIT_USAGE = 2, EXIT_IO = 3, EXIT_NOMEM = 4 };

static const char *prog = "cmz";

static void usage(FILE *f)
{
    fprintf(f,
            "usage: cmz COMMAND [OPTIONS] ...\n"
            "\n"
            "curvemesh workstation tool: reads CAD models (IGES 5.3) for compression to .cmz.\n"
            "\n"
            "commands:\n"
            "  info MODEL.igs [--json]\n"
            "      Import the model and report what was read: exporter, units, entity counts\n"
            "      (read / used / skipped), faces by surface kind, loops and holes, vertices,\n"
            "      edges (shared / free / seam / non-manifold), G1 edges, solids, bounding box,\n"
            "      tolerances and warnings.  --json prints the same as one JSON object.\n"
            "  encode MODEL.igs -o MODEL.cmz [--tol REL] [--tol-abs MM] [--quant REL] [--tess REL]\n"
            "         [--no-gregory] [--profile NAME] [--report FACES.tsv] [--strict]\n"
            "      Compress the model: each face's surface is deleted and rebuilt from its\n"
            "      boundary curves - a PLANE, else Gregory patches (3 to 8 sides) - when the\n"
            "      rebuilt surface, measured by the decoder's own code, stays within the\n"
            "      tolerance of the original and keeps tangent edges within 1 deg; else the\n"
            "      surface is kept.  --tol: fraction of the face's bounding box (default 0.01,\n"
            "      1 %%); --tol-abs: millimetres instead (with --tol too, the smaller applies).\n"
            "      --quant: coordinate grid as a fraction of the model diagonal (default 1e-6);\n"
            "      --tess: recommended chordal tolerance for viewers (default 5e-4).\n"
            "      --no-gregory: planes only.  --profile refuses, with the reason, a file the\n"
            "      named board profile (terminal, host, tiny) cannot load.  Prints one\n"
            "      summary line; --report writes a row per face (method, errors, G1, why kept).\n"
            "      A face that cannot be sent (it cannot be imported, or its surface does not\n"
            "      tessellate even kept) is left out with a warning naming its entity, and the\n"
            "      summary counts it; --strict makes that an error (exit status 1).\n"
            "  eval MODEL.igs MODEL.cmz [--tol REL] [--tol-abs MM] [--report FACES.tsv]\n"
            "      Rebuild every face of MODEL.cmz with the terminal's code and measure it\n"
            "      against MODEL.igs (spec §12 grid and boundary, §13 G1 across tangent edges);\n"
            "      prints the summary per method, exit status 1 if a face is out of tolerance.\n"
            "  decode MODEL.cmz -o OUT.glb|OUT.stl|OUT.obj [--tess MM] [--face-map FACES.tsv]\n"
            "      Rebuild every face and tessellate it (chordal tolerance --tess in mm,\n"
            "      default the file's recommendation) into binary glTF (metres, +Y up),\n"
            "      binary STL or OBJ (millimetres), chosen by the extension.  --face-map:\n"
            "      each face's number and triangle count, in the output's triangle order.\n"
            "  send MODEL.cmz|MODEL.igs --serial DEV[:BAUD] | --gadget FFSDIR | --usb VID:PID\n"
            "       [--stay] [--no-wait] [--chunk N] [--timeout S]\n"
            "      Send the model to a cmz-terminal, checked against (an IGES model: encoded\n"
            "      for) the limits the terminal announces; resumes after a cable pull; a\n"
            "      progress bar on a TTY.  --stay: send again whenever the terminal's request\n"
            "      button is pressed.  Exit status 3: link failure.  (cmz send --help)\n"
            "  sample MODEL.igs -o POINTS.xyz [--per-face N]\n"
            "      Write N points (default 20) lying on every trimmed face, inside its outer\n"
            "      loop and outside its holes, one 'x y z face_id' line each (millimetres,\n"
            "      face_id as in 'cmz info --json'), to check the import against another kernel.\n"
            "\n"
            "options:\n"
            "  --help      this text        --version   the version\n"
            "  --limits    the compile-time limits of this build (profile %s)\n"
            "  -q          no progress on stderr\n"
            "\n"
            "exit status: 0 success, 1 malformed or unsupported input, 2 usage error,\n"
            "             3 I/O error, 4 out of memory.\n",
            cm_profile_name);
}

static int quiet;

static void progress(const char *stage, int done, int total, void *ctx)
{
    (void)ctx;
    if (quiet || !isatty(2) || total < 200 || done % 50 != 0)
        return;
    fprintf(stderr, "\r%s: %s %d/%d ", prog, stage, done, total);
    if (done + 50 >= total)
        fprintf(stderr, "\r\033[K");
}

/* the exit status of a failure: out of memory, I/O, else the input */
/* an import warning about the structure around faces (iges_brep.c): a solid, shell or instance
   left out, or a member pointer of one skipped */
static int is_structure_warning(const char *msg)
{
    return (strncmp(msg, "entity ", 7) == 0 && strstr(msg, ") left out: ")) ||
           ((strncmp(msg, "shell DE ", 9) == 0 || strncmp(msg, "solid DE ", 9) == 0) && strstr(msg, " skipped"));
}

static int exit_for(cm_err code)
{
    return code == CM_E_NOMEM ? EXIT_NOMEM : code == CM_E_IO ? EXIT_IO : EXIT_INPUT;
}

/* report a load failure and return the exit code */
static int load_failed(const char *path, const loaded_model *lm, const cm_status *st)
{
    if (lm->iges.err[0])
        fprintf(stderr, "%s: %s:%s%s\n", prog, path, lm->iges.err_line ? "" : " ", lm->iges.err);
    else
        cm_report_status(stderr, prog, path, st);
    return exit_for(st->code);
}

/* ---- JSON helpers (strings from files may hold any byte: escaped as Latin-1) ---- */

static void json_str(FILE *f, const char *s)
{
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)(s ? s : ""); *p; p++) {
        if (*p == '"' || *p == '\\')
            fprintf(f, "\\%c", *p);
        else if (*p < 0x20 || *p >= 0x7f)
            fprintf(f, "\\u%04x", *p);
        else
            fputc(*p, f);
    }
    fputc('"', f);
}

static const char *units_name(int flag)
{
    static const char *n[12] = {"?", "inch", "mm", "(named)", "foot", "mile", "m", "km", "mil", "micron", "cm",
                                "microinch"};
    return flag >= 1 && flag <= 11 ? n[flag] : "?";
}

/* per IGES type: read, used */
typedef struct type_count {
    int type, read, used, bad;
} type_count;

static int count_types(const iges_file *f, type_count *tc, int cap)
{
    int n = 0;
    for (int i = 0; i < f->nents; i++) {
        const iges_entity *e = &f->ents[i];
        int k = 0;
        while (k < n && tc[k].type != e->type)
            k++;
        if (k == n) {
            if (n == cap)
                continue;
            tc[n].type = e->type;
            tc[n].read = tc[n].used = tc[n].bad = 0;
            n++;
        }
        tc[k].read++;
        tc[k].used += e->used;
        tc[k].bad += e->bad;
    }
    /* insertion sort by type */
    for (int a = 1; a < n; a++)
        for (int b = a; b > 0 && tc[b].type < tc[b - 1].type; b--) {
            type_count t = tc[b];
            tc[b] = tc[b - 1];
            tc[b - 1] = t;
        }
    return n;
}

/*
 * The arguments every command shares: -q, the one input file, and the refusal of anything else.
 * Returns 0 when `a` was taken, EXIT_USAGE (after saying why) otherwise.
 */
static int common_arg(const char *cmd, const char *a, const char **path)
{
    if (strcmp(a, "-q") == 0) {
        quiet = 1;
        return 0;
    }
    if (a[0] == '-' && a[1]) {
        fprintf(stderr, "%s %s: unknown option %s (see cmz --help)\n", prog, cmd, a);
        return EXIT_USAGE;
    }
    if (*path) {
        fprintf(stderr, "%s %s: one file at a time (got %s and %s)\n", prog, cmd, *path, a);
        return EXIT_USAGE;
    }
    *path = a;
    return 0;
}

typedef struct solid_info {
    int faces, free_edges, seams;
} solid_info;

static int cmd_info(int argc, char **argv)
{
    const char *path = NULL;
    int json = 0;
    for (int i = 0; i < argc; i++) {
        if (strcmp(argv[i], "--json") == 0)
            json = 1;
        else if (common_arg("info", argv[i], &path))
            return EXIT_USAGE;
    }
    if (!path) {
        fprintf(stderr, "%s info: which model? usage: cmz info MODEL.igs [--json]\n", prog);
        return EXIT_USAGE;
    }
    loaded_model lm;
    cm_status st;
    cm_status_init(&st);
    if (model_load(path, &lm, progress, NULL, &st) != CM_OK) {
        int rc = load_failed(path, &lm, &st);
        model_free(&lm);
        return rc;
    }
    const iges_file *f = &lm.iges;
    const brep_model *m = &lm.brep;
    const cmesh *cm = &lm.mesh;
    type_count tc[128];
    int ntc = count_types(f, tc, 128);
    int nread = 0, nused = 0, nbad = 0;
    for (int k = 0; k < ntc; k++) {
        nread += tc[k].read - tc[k].bad;
        nused += tc[k].used;
        nbad += tc[k].bad;
    }
    /* faces by base surface type */
    type_count sc[32];
    int nsc = 0;
    int holes = 0;
    for (int i = 0; i < m->nfaces; i++) {
        int k = 0;
        while (k < nsc && sc[k].type != m->faces[i].surf_type)
            k++;
        if (k == nsc && nsc < 32) {
            sc[nsc].type = m->faces[i].surf_type;
            sc[nsc].read = 0;
            nsc++;
        }
        if (k < nsc)
            sc[k].read++;
        holes += m->faces[i].nloops - 1;
    }
    int nfree, nshared, nseam, nnm, ng1;
    cmesh_counts(cm, &nfree, &nshared, &nseam, &nnm, &ng1);
    int *comp = malloc((size_t)(cm->nfaces + 1) * sizeof *comp);
    int ncomp = comp ? cmesh_components(cm, comp) : 0;
    solid_info *si = calloc((size_t)(ncomp > 0 ? ncomp : 1), sizeof *si);
    if (!comp || !si || ncomp < 0) {
        free(comp);
        free(si);
        model_free(&lm);
        fprintf(stderr, "%s: out of memory\n", prog);
        return EXIT_NOMEM;
    }
    for (int i = 0; i < cm->nfaces; i++)
        si[comp[i]].faces++;
    for (int e = 0; e < cm->nedges; e++) {
        const cmesh_edge *E = &cm->edges[e];
        if (E->kind == CMESH_FREE)
            si[comp[E->face[0]]].free_edges++;
    }
    int closed = 0;
    for (int c = 0; c < ncomp; c++)
        closed += si[c].free_edges == 0;
    double diag = brep_diag(m);
    if (json) {
        printf("{\n  \"file\": ");
        json_str(stdout, path);
        printf(",\n  \"exporter\": ");
        json_str(stdout, f->g.system_id);
        printf(",\n  \"preprocessor\": ");
        json_str(stdout, f->g.preprocessor);
        printf(",\n  \"units\": {\"flag\": %d, \"name\": ", f->g.units_flag);
        json_str(stdout, f->g.units_name);
        printf(", \"to_mm\": %.17g, \"model_scale\": %.17g, \"resolution_mm\": %.6g},\n", f->to_mm, f->g.model_scale,
               m->resolution_mm);
        printf("  \"entities\": {\"read\": %d, \"used\": %d, \"skipped\": %d, \"unreadable\": %d, \"by_type\": [", nread,
               nused, nread - nused, nbad);
        for (int k = 0; k < ntc; k++)
            printf("%s\n    {\"type\": %d, \"name\": \"%s\", \"read\": %d, \"used\": %d}", k ? "," : "", tc[k].type,
                   iges_type_name(tc[k].type), tc[k].read - tc[k].bad, tc[k].used);
        printf("]},\n  \"faces\": {\"total\": %d, \"trimmed_144\": %d, \"bounded_143\": %d, \"brep_510\": %d, "
               "\"untrimmed\": %d, \"failed\": %d, \"instances\": %d, \"face_entities\": %d, \"by_surface\": [",
               m->nfaces, lm.stats.faces_144, lm.stats.faces_143, lm.stats.faces_510, lm.stats.faces_untrimmed,
               m->faces_failed, lm.stats.instances, lm.stats.face_entities);
        for (int k = 0; k < nsc; k++)
            printf("%s{\"type\": %d, \"name\": \"%s\", \"faces\": %d}", k ? ", " : "", sc[k].type,
                   iges_type_name(sc[k].type), sc[k].read);
        printf("]},\n  \"loops\": {\"total\": %d, \"holes\": %d, \"reoriented_faces\": %d, \"outer_reordered\": %d, "
               "\"seam_joined\": %d, \"domains_failed\": %d},\n",
               m->nloops, holes, lm.loops_reversed, lm.outer_reordered, lm.seam_joined, lm.domains_failed);
        printf("  \"vertices\": %d,\n  \"edges\": {\"total\": %d, \"shared\": %d, \"free\": %d, \"seam\": %d, "
               "\"non_manifold\": %d, \"g1\": %d, \"split_at_vertices\": %d, \"inconsistent\": %d},\n",
               cm->nverts, cm->nedges, nshared, nfree, nseam, nnm, ng1, cm->nsplits, cm->inconsistent);
        printf("  \"solids\": {\"components\": %d, \"closed\": %d, \"open\": [", ncomp, closed);
        int first = 1;
        for (int c = 0; c < ncomp; c++)
            if (si[c].free_edges) {
                printf("%s{\"component\": %d, \"faces\": %d, \"free_edges\": %d}", first ? "" : ", ", c, si[c].faces,
                       si[c].free_edges);
                first = 0;
            }
        printf("]},\n  \"bbox\": {\"min\": [%.9g, %.9g, %.9g], \"max\": [%.9g, %.9g, %.9g], \"diagonal\": %.9g},\n",
               m->box.lo.x, m->box.lo.y, m->box.lo.z, m->box.hi.x, m->box.hi.y, m->box.hi.z, diag);
        printf("  \"tolerance\": {\"vertex_mm\": %.6g, \"pair_mm\": %.6g, \"max_boundary_gap_mm\": %.6g, "
               "\"forced_joints\": %d, \"max_forced_gap_mm\": %.6g},\n",
               cm->tol_vertex, cm->tol_pair, lm.max_gap, cm->nforced, cm->max_forced_gap);
        printf("  \"face_list\": [");
        for (int i = 0; i < m->nfaces; i++)
            printf("%s\n    {\"id\": %d, \"de\": %d, \"entity\": %d, \"surface\": %d, \"loops\": %d, \"shell\": %d, "
                   "\"instance\": %d}",
                   i ? "," : "", i, m->faces[i].src_de, m->faces[i].src_type, m->faces[i].surf_type,
                   m->faces[i].nloops, m->faces[i].shell, m->faces[i].instance);
        printf("],\n  \"warnings\": [");
        for (int i = 0; i < f->nwarn; i++) {
            printf("%s\n    {\"line\": %d, \"message\": ", i ? "," : "", f->warn[i].line);
            json_str(stdout, f->warn[i].msg);
            printf("}");
        }
        printf("]\n}\n");
    } else {
        printf("file        %s\n", path);
        printf("exporter    %s%s%s\n", f->g.system_id[0] ? f->g.system_id : "(not named)",
               f->g.preprocessor[0] ? " / " : "", f->g.preprocessor);
        printf("units       %s (flag %d%s%s), model scale %g, resolution %.3g mm\n", units_name(f->g.units_flag),
               f->g.units_flag, f->g.units_name[0] ? ", " : "", f->g.units_name, f->g.model_scale, m->resolution_mm);
        printf("entities    %d read, %d used, %d skipped%s", nread, nused, nread - nused, nbad ? "" : "\n");
        if (nbad)
            printf(", %d unreadable\n", nbad);
        for (int k = 0; k < ntc; k++)
            printf("  %4d %-36s %6d read %6d used\n", tc[k].type, iges_type_name(tc[k].type), tc[k].read - tc[k].bad,
                   tc[k].used);
        printf("faces       %d", m->nfaces);
        if (lm.stats.faces_144)
            printf(", %d trimmed (144)", lm.stats.faces_144);
        if (lm.stats.faces_143)
            printf(", %d bounded (143)", lm.stats.faces_143);
        if (lm.stats.faces_510)
            printf(", %d B-rep (510)", lm.stats.faces_510);
        if (lm.stats.faces_untrimmed)
            printf(", %d untrimmed surfaces", lm.stats.faces_untrimmed);
        if (lm.stats.instances)
            printf(", placed by %d subfigure instances (%d distinct face entities)", lm.stats.instances,
                   lm.stats.face_entities);
        if (m->faces_failed)
            printf("; %d could not be read (see warnings)", m->faces_failed);
        if (m->entities_failed)
            printf("; %d solids, shells or instances left out (see warnings)", m->entities_failed);
        printf("\n  by surface:");
        for (int k = 0; k < nsc; k++)
            printf(" %d %s (%d)%s", sc[k].read, iges_type_name(sc[k].type), sc[k].type, k + 1 < nsc ? "," : "");
        printf("\nloops       %d: %d outer, %d holes", m->nloops, m->nloops - holes, holes);
        if (lm.loops_reversed)
            printf("; %d faces re-oriented to the surface normal", lm.loops_reversed);
        if (lm.outer_reordered)
            printf("; %d outer loops not listed first", lm.outer_reordered);
        if (lm.seam_joined)
            printf("; %d faces wound around a closed surface", lm.seam_joined);
        printf("\nvertices    %d\n", cm->nverts);
        printf("edges       %d: %d shared, %d free, %d seam, %d non-manifold; %d G1 (normals within 1 deg)\n",
               cm->nedges, nshared, nfree, nseam, nnm, ng1);
        if (nnm)
            printf("            non-manifold: 3 or more faces of one body meet there (touching parts of a flattened "
                   "assembly, or overlapping faces)\n");
        if (cm->nsplits)
            printf("            %d boundary curves split where another face's vertex lies on them\n", cm->nsplits);
        if (cm->inconsistent)
            printf("            %d shared edges run the same way in both faces (normals not consistent)\n",
                   cm->inconsistent);
        printf("solids      %d connected %s, %d closed (no free edges)\n", ncomp, ncomp == 1 ? "part" : "parts",
               closed);
        for (int c = 0, shown = 0; c < ncomp && shown < 20; c++)
            if (si[c].free_edges) {
                printf("  part %d: %d faces, %d free edges (an open sheet or a gap wider than the tolerance)\n", c,
                       si[c].faces, si[c].free_edges);
                shown++;
            }
        printf("bbox        [%.6g, %.6g] x [%.6g, %.6g] x [%.6g, %.6g] mm, diagonal %.6g mm\n", m->box.lo.x,
               m->box.hi.x, m->box.lo.y, m->box.hi.y, m->box.lo.z, m->box.hi.z, diag);
        printf("tolerance   vertices merged within %.3g mm, edges paired within %.3g mm; boundary-to-surface gap "
               "up to %.3g mm\n",
               cm->tol_vertex, cm->tol_pair, lm.max_gap);
        if (cm->nforced)
            printf("            %d loop joints were farther apart than that (up to %.3g mm) and were closed\n",
                   cm->nforced, cm->max_forced_gap);
        printf("warnings    %d\n", f->nwarn);
        for (int i = 0; i < f->nwarn && i < 50; i++)
            printf("  %s%.0d%s%s\n", f->warn[i].line ? "line " : "", f->warn[i].line, f->warn[i].line ? ": " : "",
                   f->warn[i].msg);
        if (f->nwarn > 50)
            printf("  ... %d more (cmz info --json lists all)\n", f->nwarn - 50);
        printf("time        read %.2f s, faces %.2f s, domains %.2f s, curve mesh %.2f s\n", lm.seconds_read,
               lm.seconds_brep, lm.seconds_domains, lm.seconds_mesh);
    }
    free(comp);
    free(si);
    model_free(&lm);
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "%s: writing the report failed: %s\n", prog, strerror(errno));
        return EXIT_IO;
    }
    return EXIT_OK;
}

static int cmd_sample(int argc, char **argv)
{
    const char *path = NULL, *out = NULL;
    int per_face = 20;
    for (int i = 0; i < argc; i++) {
        if (strcmp(argv[i], "-o") == 0 && i + 1 < argc)
            out = argv[++i];
        else if (strcmp(argv[i], "--per-face") == 0 && i + 1 < argc) {
            char *end;
            long v = strtol(argv[++i], &end, 10);
            if (*end || v < 1 || v > 100000) {
                fprintf(stderr, "%s sample: --per-face wants a number in 1..100000, not '%s'\n", prog, argv[i]);
                return EXIT_USAGE;
            }
            per_face = (int)v;
        } else if (common_arg("sample", argv[i], &path))
            return EXIT_USAGE;
    }
    if (!path || !out) {
        fprintf(stderr, "%s sample: usage: cmz sample MODEL.igs -o POINTS.xyz [--per-face N]\n", prog);
        return EXIT_USAGE;
    }
    loaded_model lm;
    cm_status st;
    cm_status_init(&st);
    if (model_load(path, &lm, progress, NULL, &st) != CM_OK) {
        int rc = load_failed(path, &lm, &st);
        model_free(&lm);
        return rc;
    }
    /* write to a temporary file and rename, so a failure never leaves half an output */
    size_t tl = strlen(out) + 16;
    char *tmp = malloc(tl);
    cm_vec2 *uv = malloc((size_t)per_face * sizeof *uv);
    if (!tmp || !uv) {
        free(tmp);
        free(uv);
        model_free(&lm);
        fprintf(stderr, "%s: out of memory\n", prog);
        return EXIT_NOMEM;
    }
    snprintf(tmp, tl, "%s.tmp%ld", out, (long)getpid());
    FILE *fo = fopen(tmp, "w");
    if (!fo) {
        fprintf(stderr, "%s: %s: %s\n", prog, tmp, strerror(errno));
        free(tmp);
        free(uv);
        model_free(&lm);
        return EXIT_IO;
    }
    fprintf(fo, "# cmz sample %s: %d faces, up to %d points per face; x y z face_id (mm)\n", path, lm.brep.nfaces,
            per_face);
    int empty = 0, total = 0;
    for (int fi = 0; fi < lm.brep.nfaces; fi++) {
        const face_domain *fd = &lm.fds[fi];
        int n = fd->uv ? face_domain_sample(fd, per_face, 0x9e3779b9u ^ (uint32_t)fi, uv) : 0;
        if (n == 0) {
            empty++;
            fprintf(stderr, "%s: warning: face %d (DE %d) got no sample points%s\n", prog, fi, lm.brep.faces[fi].src_de,
                    fd->uv ? "" : " (no parameter domain)");
        }
        for (int k = 0; k < n; k++) {
            cm_vec3 P;
            if (face_domain_eval(&lm.brep, fd, uv[k].x, uv[k].y, &P, NULL, NULL) == CM_OK)
                fprintf(fo, "%.17g %.17g %.17g %d\n", P.x, P.y, P.z, fi);
        }
        total += n;
    }
    int werr = ferror(fo);
    if (fclose(fo) != 0 || werr || rename(tmp, out) != 0) {
        fprintf(stderr, "%s: writing %s failed: %s\n", prog, out, strerror(errno));
        remove(tmp);
        free(tmp);
        free(uv);
        model_free(&lm);
        return EXIT_IO;
    }
    if (!quiet)
        fprintf(stderr, "%s: %d points on %d faces written to %s%s\n", prog, total, lm.brep.nfaces - empty, out,
                empty ? " (some faces got none, see above)" : "");
    free(tmp);
    free(uv);
    int rc = empty ? EXIT_INPUT : EXIT_OK;
    model_free(&lm);
    return rc;
}

/* write a buffer to `path` through a temporary file and a rename: never half a file */
static int write_atomic(const char *path, const uint8_t *data, size_t len)
{
    size_t tl = strlen(path) + 32;
    char *tmp = malloc(tl);
    if (!tmp) {
        fprintf(stderr, "%s: out of memory\n", prog);
        return EXIT_NOMEM;
    }
    snprintf(tmp, tl, "%s.tmp%ld", path, (long)getpid());
    FILE *f = fopen(tmp, "wb");
    int ok = f && fwrite(data, 1, len, f) == len;
    if (f && fclose(f) != 0)
        ok = 0;
    if (!ok || rename(tmp, path) != 0) {
        fprintf(stderr, "%s: writing %s failed: %s\n", prog, path, strerror(errno));
        remove(tmp);
        free(tmp);
        return EXIT_IO;
    }
    free(tmp);
    return EXIT_OK;
}

static int parse_real(const char *opt, const char *text, double lo, double hi, double *out)
{
    char *end;
    double v = strtod(text, &end);
    if (*end || !(v >= lo && v <= hi)) {
        fprintf(stderr, "%s: %s wants a number in [%g, %g], not '%s'\n", prog, opt, lo, hi, text);
        return -1;
    }
    *out = v;
    return 0;
}

static const char *method_name(int m)
{
    return m == CM_METHOD_PLANE ? "plane" : m == CM_METHOD_GREGORY ? "gregory" : m == CM_METHOD_KEEP ? "keep" : "?";
}

static int cmd_encode(int argc, char **argv)
{
    const char *path = NULL, *out = NULL, *report = NULL, *profile = NULL;
    encode_opts o;
    encode_opts_default(&o);
    o.progress = progress;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "-o") == 0 && v) {
            out = v;
            i++;
        } else if (strcmp(a, "--report") == 0 && v) {
            report = v;
            i++;
        } else if (strcmp(a, "--profile") == 0 && v) {
            profile = v;
            i++;
        } else if (strcmp(a, "--tol") == 0 && v) {
            if (parse_real(a, v, 1e-9, 0.5, &o.rel_tol))
                return EXIT_USAGE;
            o.rel_set = 1;
            i++;
        } else if (strcmp(a, "--tol-abs") == 0 && v) {
            if (parse_real(a, v, 1e-9, 1e9, &o.abs_tol))
                return EXIT_USAGE;
            i++;
        } else if (strcmp(a, "--no-gregory") == 0) {
            o.gregory = 0;
        } else if (strcmp(a, "--strict") == 0) {
            o.strict = 1;
        } else if (strcmp(a, "--quant") == 0 && v) {
            if (parse_real(a, v, 1e-12, 1e-2, &o.quant_rel))
                return EXIT_USAGE;
            i++;
        } else if (strcmp(a, "--tess") == 0 && v) {
            if (parse_real(a, v, 1e-7, 0.1, &o.tess_rel))
                return EXIT_USAGE;
            i++;
        } else if (common_arg("encode", a, &path)) {
            return EXIT_USAGE;
        }
    }
    if (!path || !out) {
        fprintf(stderr, "%s encode: usage: cmz encode MODEL.igs -o MODEL.cmz [options] (see cmz --help)\n", prog);
        return EXIT_USAGE;
    }
    if (profile) {
        o.target = cm_profile_limits(profile);
        o.target_name = profile;
        if (!o.target) {
            fprintf(stderr, "%s encode: unknown profile '%s' (terminal, host or tiny)\n", prog, profile);
            return EXIT_USAGE;
        }
    }
    loaded_model lm;
    cm_status st;
    cm_status_init(&st);
    if (model_load(path, &lm, progress, NULL, &st) != CM_OK) {
        int rc = load_failed(path, &lm, &st);
        model_free(&lm);
        return rc;
    }
    encode_result r;
    cm_status_init(&st);
    if (o.strict && lm.brep.entities_failed > 0) {
        for (int i = 0; i < lm.iges.nwarn; i++)
            if (is_structure_warning(lm.iges.warn[i].msg)) {
                fprintf(stderr, "%s: %s: line %d: %s (--strict: nothing written)\n", prog, path, lm.iges.warn[i].line,
                        lm.iges.warn[i].msg);
                break;
            }
        model_free(&lm);
        return EXIT_INPUT;
    }
    if (o.strict && lm.nleft_out > 0) {
        const iges_warning *w = &lm.iges.warn[lm.left_out[0]];
        fprintf(stderr, "%s: %s: %s%.0d%s%s (--strict: nothing written)\n", prog, path, w->line ? "line " : "",
                w->line, w->line ? ": " : "", w->msg);
        model_free(&lm);
        return EXIT_INPUT;
    }
    cm_err e = encode_model(&lm, &o, &r, &st);
    int rc = EXIT_OK;
    /* every face left out, by the import or the encoder, is named; so is every solid, shell or
       instance the import left out, and every member pointer it skipped */
    for (int i = 0; i < lm.nleft_out; i++) {
        const iges_warning *w = &lm.iges.warn[lm.left_out[i]];
        fprintf(stderr, "%s: %s: warning: %s%.0d%s%s\n", prog, path, w->line ? "line " : "", w->line,
                w->line ? ": " : "", w->msg);
    }
    for (int i = 0; i < lm.iges.nwarn; i++) {
        const iges_warning *w = &lm.iges.warn[i];
        if (is_structure_warning(w->msg))
            fprintf(stderr, "%s: %s: warning: %s%.0d%s%s\n", prog, path, w->line ? "line " : "", w->line,
                    w->line ? ": " : "", w->msg);
    }
    if (r.refusal[0] && e != CM_E_LIMIT) {
        fprintf(stderr, "%s: %s: %s (nothing written)\n", prog, path, r.refusal);
        rc = EXIT_INPUT;
    } else if (e == CM_E_LIMIT && r.refusal[0]) {
        fprintf(stderr, "%s: %s: refused: %s (nothing written)\n", prog, path, r.refusal);
        rc = EXIT_INPUT;
    } else if (e != CM_OK) {
        cm_report_status(stderr, prog, path, &st);
        rc = exit_for(st.code);
    }
    if (rc == EXIT_OK)
        rc = write_atomic(out, r.bytes, r.len);
    if (rc == EXIT_OK && report) {
        FILE *f = fopen(report, "w");
        if (!f) {
            fprintf(stderr, "%s: %s: %s\n", prog, report, strerror(errno));
            rc = EXIT_IO;
        } else {
            fprintf(f, "face\tde\tentity\tsurface\tmethod\tbbox_mm\tplane_dev_mm\tmax_err_mm\tratio\tsurf_ctrl"
                       "\tlayout\tavg_err_mm\tg1_worst_deg\tgregory_ratio\twhy_kept\n");
            for (int i = 0; i < lm.mesh.nfaces; i++) {
                const face_report *fr = &r.faces[i];
                const brep_face *bf = &lm.brep.faces[lm.mesh.faces[i].brep_face];
                double c = fr->g1_cos > 1.0 ? 1.0 : fr->g1_cos;
                fprintf(f, "%d\t%d\t%d\t%d\t%s\t%.6g\t%.6g\t%.6g\t%.6g\t%d\t%d\t%.6g\t%.4g\t%.6g\t%s\n", i,
                        bf->src_de, bf->src_type, bf->surf_type,
                        method_name(fr->method), fr->bbox, fr->plane_dev, fr->rebuild_max, fr->ratio, fr->surf_ctrl,
                        fr->layout, fr->rebuild_avg, acos(c) * 57.29577951308232, fr->greg_ratio,
                        fr->method == CM_METHOD_KEEP && fr->why ? fr->why : "-");
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
        printf("%s -> %s: %d faces (%d plane, %d gregory, %d kept%s), %d edges (%d lines), %zu bytes, %.1fx smaller "
               "than the IGES (%ld bytes)\n",
               path, out, lm.mesh.nfaces, r.faces_plane, r.faces_gregory, r.faces_keep, left,
               r.edges_line + r.edges_curve, r.edges_line, r.len, r.len ? (double)isize / (double)r.len : 0.0, isize);
    }
    encode_result_free(&r);
    model_free(&lm);
    return rc;
}

static cm_decoder decoder;   /* large: static storage, as on the terminal */
static cm_tess_ws tess_ws;

/* --face-map: one line per decoded face, in the order of the output's triangles: the face's
   number in the model and its triangle count (lets a test attribute each triangle to its face) */
static int write_face_map(const char *path, const cm_mesh *mesh)
{
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "%s: %s: %s\n", prog, path, strerror(errno));
        return EXIT_IO;
    }
    fprintf(f, "face\ttriangles\n");
    for (uint32_t k = 0; k < mesh->nfaces; k++)
        fprintf(f, "%u\t%u\n", mesh->faces[k].source_face, mesh->faces[k].nindex / 3u);
    if (fclose(f) != 0) {
        fprintf(stderr, "%s: %s: %s\n", prog, path, strerror(errno));
        return EXIT_IO;
    }
    return EXIT_OK;
}

static int cmd_decode(int argc, char **argv)
{
    const char *path = NULL, *out = NULL, *face_map = NULL;
    double tol = 0;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "-o") == 0 && v) {
            out = v;
            i++;
        } else if (strcmp(a, "--face-map") == 0 && v) {
            face_map = v;
            i++;
        } else if (strcmp(a, "--tess") == 0 && v) {
            if (parse_real(a, v, 1e-9, 1e9, &tol))
                return EXIT_USAGE;
            i++;
        } else if (common_arg("decode", a, &path)) {
            return EXIT_USAGE;
        }
    }
    int fmt = out ? cm_out_format_of(out) : -1;
    if (!path || !out || fmt < 0) {
        fprintf(stderr, "%s decode: usage: cmz decode MODEL.cmz -o OUT.glb|OUT.stl|OUT.obj [--tess MM]\n", prog);
        return EXIT_USAGE;
    }
    cm_status st;
    cm_status_init(&st);
    if (cm_decode_read(path, &decoder, &st) != CM_OK) {
        cm_report_status(stderr, prog, path, &st);
        return exit_for(st.code);
    }
    /* the mesh sized by what the file says it needs (the workstation may use the heap) */
    uint64_t tris = decoder.need[CM_LIMIT_MAX_TRIS];
    if (tol > 0 && tol < decoder.model.tess_tol)
        tris = tris * (uint64_t)(decoder.model.tess_tol / tol + 1.0) * 2; /* finer than the file planned */
    /* the header's need is what the encoder's decoder made; a newer decoder may tessellate a little
       finer (its refinement improves), so the workstation leaves room for twice that */
    tris = 2 * tris + 1024;
    if (tris > CM_MAX_TRIS)
        tris = CM_MAX_TRIS;
    cm_mesh mesh;
    memset(&mesh, 0, sizeof mesh);
    int rc = EXIT_OK;
    cm_decode_summary sum;
    uint64_t bytes = 0;
    cm_err e;
    /* a damaged file may declare less than it makes: the workstation grows the mesh (the terminal's
       is its build's limit) */
    for (;;) {
        mesh.cap_verts = (uint32_t)(3 * tris);
        mesh.cap_index = (uint32_t)(3 * tris);
        mesh.cap_faces = decoder.model.nfaces ? decoder.model.nfaces : 1;
        free(mesh.pos);
        free(mesh.nrm);
        free(mesh.idx);
        free(mesh.faces);
        mesh.pos = malloc((size_t)mesh.cap_verts * sizeof *mesh.pos);
        mesh.nrm = malloc((size_t)mesh.cap_verts * sizeof *mesh.nrm);
        mesh.idx = malloc((size_t)mesh.cap_index * sizeof *mesh.idx);
        mesh.faces = malloc((size_t)mesh.cap_faces * sizeof *mesh.faces);
        if (!mesh.pos || !mesh.nrm || !mesh.idx || !mesh.faces) {
            e = CM_E_NOMEM;
            break;
        }
        cm_status_init(&st);
        e = cm_decode_mesh(&decoder, tol, &mesh, &tess_ws, &sum, &st);
        if (e != CM_E_LIMIT || st.limit != CM_LIMIT_MAX_TRIS || tris >= CM_MAX_TRIS)
            break;
        tris = 4 * tris > CM_MAX_TRIS ? CM_MAX_TRIS : 4 * tris;
    }
    if (e == CM_E_NOMEM && st.code == CM_OK) {
        fprintf(stderr, "%s: out of memory for %llu triangles\n", prog, (unsigned long long)tris);
        rc = EXIT_NOMEM;
    } else if (e != CM_OK || cm_write_mesh(&mesh, (cm_out_format)fmt, out, &bytes, &st) != CM_OK) {
        cm_report_status(stderr, prog, path, &st);
        rc = exit_for(st.code);
    } else {
        /* one bad face never sinks a model: each one left out is named */
        for (uint32_t i = 0; i < sum.faces_left_out && i < CM_DECODE_LEFT_OUT_LIST; i++) {
            char why[512];
            cm_format_status(why, sizeof why, &sum.left_out[i]);
            fprintf(stderr, "%s: %s: warning: face left out: %s\n", prog, path, why);
        }
        if (sum.faces_left_out > CM_DECODE_LEFT_OUT_LIST)
            fprintf(stderr, "%s: %s: warning: %lu more faces left out\n", prog, path,
                    (unsigned long)(sum.faces_left_out - CM_DECODE_LEFT_OUT_LIST));
        if (face_map && (rc = write_face_map(face_map, &mesh)) != EXIT_OK) {
            /* reported */
        } else if (!quiet) {
            char left[64] = "";
            if (sum.faces_left_out)
                snprintf(left, sizeof left, ", %lu left out", (unsigned long)sum.faces_left_out);
            printf("%s -> %s: %u faces (%u plane, %u gregory, %u kept%s), %u triangles, %u vertices, chordal "
                   "tolerance %.3g mm, %llu bytes\n",
                   path, out, sum.faces, sum.faces_plane, sum.faces_gregory, sum.faces_keep, left, sum.triangles,
                   sum.vertices, sum.tess_tol, (unsigned long long)bytes);
        }
    }
    free(mesh.pos);
    free(mesh.nrm);
    free(mesh.idx);
    free(mesh.faces);
    return rc;
}

static cm_rebuild_ws eval_ws;

/* `cmz eval`: re-measure a finished file against its model with the terminal's rebuild */
/*
 * The file has fewer faces than the IGES model: the encoder left some out (see encode_model).  It is
 * deterministic, so encoding a second copy with the file's own settings tells which; those are left
 * out of lm too (lm itself keeps the orientation its face domains were built with).
 */
static cm_err match_left_out(const char *path, const cm_model *m, loaded_model *lm, int *left_out, cm_status *st)
{
    loaded_model again;
    cm_err e = model_load(path, &again, NULL, NULL, st);
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

static int cmd_eval(int argc, char **argv)
{
    const char *paths[2] = {NULL, NULL}, *report = NULL;
    double rel = 0, abs_tol = 0;
    int rel_set = 0, np = 0;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--tol") == 0 && v) {
            if (parse_real(a, v, 1e-9, 0.5, &rel))
                return EXIT_USAGE;
            rel_set = 1;
            i++;
        } else if (strcmp(a, "--tol-abs") == 0 && v) {
            if (parse_real(a, v, 1e-9, 1e9, &abs_tol))
                return EXIT_USAGE;
            i++;
        } else if (strcmp(a, "--report") == 0 && v) {
            report = v;
            i++;
        } else if (strcmp(a, "-q") == 0) {
            quiet = 1;
        } else if ((a[0] == '-' && a[1]) || np == 2) {
            fprintf(stderr, "%s eval: usage: cmz eval MODEL.igs MODEL.cmz [--tol REL] [--tol-abs MM] [--report F]\n",
                    prog);
            return EXIT_USAGE;
        } else {
            paths[np++] = a;
        }
    }
    if (np != 2) {
        fprintf(stderr, "%s eval: usage: cmz eval MODEL.igs MODEL.cmz [--tol REL] [--tol-abs MM] [--report F]\n", prog);
        return EXIT_USAGE;
    }
    cm_status st;
    cm_status_init(&st);
    if (cm_decode_read(paths[1], &decoder, &st) != CM_OK) {
        cm_report_status(stderr, prog, paths[1], &st);
        return exit_for(st.code);
    }
    loaded_model lm;
    cm_err e = model_load(paths[0], &lm, progress, NULL, &st);
    if (e != CM_OK) {
        int rc = load_failed(paths[0], &lm, &st);
        model_free(&lm);
        return rc;
    }
    const cm_model *m = &decoder.model;
    if (!rel_set)
        rel = m->rel_tol > 0 ? m->rel_tol : 0.01;
    int left_out = 0;
    if ((int)m->nfaces < lm.mesh.nfaces && (e = match_left_out(paths[0], m, &lm, &left_out, &st)) != CM_OK) {
        cm_report_status(stderr, prog, paths[0], &st);
        model_free(&lm);
        return exit_for(st.code);
    }
    if ((int)m->nfaces != lm.mesh.nfaces) {
        fprintf(stderr, "%s eval: %s has %u faces, %s %d: not the same model\n", prog, paths[1], m->nfaces, paths[0],
                lm.mesh.nfaces);
        model_free(&lm);
        return EXIT_INPUT;
    }
    int nf = (int)m->nfaces, rc = EXIT_OK, fails = 0;
    face_surface *fs = calloc((size_t)nf + 1, sizeof *fs);
    face_error *fe = calloc((size_t)nf + 1, sizeof *fe);
    double *g1c = malloc(((size_t)nf + 1) * sizeof *g1c);
    if (!fs || !fe || !g1c) {
        fprintf(stderr, "%s: out of memory\n", prog);
        free(fs);
        free(fe);
        free(g1c);
        model_free(&lm);
        return EXIT_NOMEM;
    }
    int count[CM_METHOD_COUNT] = {0};
    double worst_ratio[CM_METHOD_COUNT] = {0}, sum_ratio[CM_METHOD_COUNT] = {0};
    for (int f = 0; f < nf; f++) {
        progress("measuring", f + 1, nf, NULL);
        g1c[f] = 1.0;
        int meth = m->faces[f].method;
        count[meth]++;
        fs[f].method = CM_METHOD_KEEP;
        if (meth == CM_METHOD_KEEP)
            continue;
        cm_rebuilt rb;
        if (cm_rebuild_face(m, (uint32_t)f, &rb, &eval_ws, &st) != CM_OK) {
            cm_report_status(stderr, prog, paths[1], &st);
            rc = EXIT_INPUT;
            break;
        }
        if (!face_surface_set(&fs[f], &rb)) {
            rc = EXIT_NOMEM;
            break;
        }
        if (!verify_face(&lm, m, f, &rb, HUGE_VAL, &fe[f])) {
            fprintf(stderr, "%s eval: face %d: no parameter domain in the model to measure against\n", prog, f);
            fails++;
            continue;
        }
        double tol = encode_face_tol(rel, rel_set || !(abs_tol > 0), abs_tol, rb.bbox);
        worst_ratio[meth] = fe[f].ratio > worst_ratio[meth] ? fe[f].ratio : worst_ratio[meth];
        sum_ratio[meth] += fe[f].ratio;
        if (!(fe[f].max < tol)) {
            fprintf(stderr, "%s eval: face %d (%s): max error %.4g mm > tolerance %.4g mm (ratio %.4g %%)\n", prog, f,
                    method_name(meth), fe[f].max, tol, 100 * fe[f].ratio);
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
        if (fs[a].method == CM_METHOD_KEEP && fs[b].method == CM_METHOD_KEEP)
            continue;
        double c = verify_g1_edge(&lm, m, ed, fs, NULL);
        g1_edges++;
        g1c[a] = c < g1c[a] ? c : g1c[a];
        g1c[b] = c < g1c[b] ? c : g1c[b];
        g1_worst = c < g1_worst ? c : g1_worst;
        if (c < 0.9998476951563913) {
            fprintf(stderr, "%s eval: G1 edge %u between faces %d and %d: normals %.3g deg apart\n", prog, ed, a, b,
                    acos(c > 1 ? 1 : c) * 57.29577951308232);
            g1_fail++;
        }
    }
    if (rc == EXIT_OK && report) {
        FILE *out = fopen(report, "w");
        if (!out) {
            fprintf(stderr, "%s: %s: %s\n", prog, report, strerror(errno));
            rc = EXIT_IO;
        } else {
            fprintf(out, "face\tmethod\tlayout\tbbox_mm\tavg_err_mm\tmax_err_mm\tratio\tg1_worst_deg\n");
            for (int f = 0; f < nf; f++) {
                const cm_face *F = &m->faces[f];
                double c = g1c[f] > 1 ? 1 : g1c[f];
                fprintf(out, "%d\t%s\t%d\t%.6g\t%.6g\t%.6g\t%.6g\t%.4g\n", f, method_name(F->method),
                        F->method == CM_METHOD_GREGORY ? F->layout : -1, fe[f].bbox,
                        fe[f].avg, fe[f].max, fe[f].ratio, acos(c) * 57.29577951308232);
            }
            if (fclose(out) != 0)
                rc = EXIT_IO;
        }
    }
    if (rc == EXIT_OK) {
        printf("%s against %s: %d faces: plane %d (worst ratio %.3g %%), gregory %d (worst ratio %.3g %%, mean %.3g %%), "
               "kept %d\n",
               paths[1], paths[0], nf, count[CM_METHOD_PLANE], 100 * worst_ratio[CM_METHOD_PLANE],
               count[CM_METHOD_GREGORY], 100 * worst_ratio[CM_METHOD_GREGORY],
               count[CM_METHOD_GREGORY] ? 100 * sum_ratio[CM_METHOD_GREGORY] / count[CM_METHOD_GREGORY] : 0.0,
               count[CM_METHOD_KEEP]);
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

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return EXIT_USAGE;
    }
    const char *cmd = argv[1];
    if (strcmp(cmd, "--help") == 0 || strcmp(cmd, "-h") == 0 || strcmp(cmd, "help") == 0) {
        usage(stdout);
        return EXIT_OK;
    }
    if (strcmp(cmd, "--version") == 0) {
        printf("cmz %s (profile %s)\n", CMZ_VERSION, cm_profile_name);
        return EXIT_OK;
    }
    if (strcmp(cmd, "--limits") == 0) {
        cm_report_limits(stdout);
        return EXIT_OK;
    }
    /* `cmz COMMAND --help` (anywhere among its arguments) is the same text; send has its own */
    for (int i = 2; i < argc && strcmp(cmd, "send") != 0; i++)
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage(stdout);
            return EXIT_OK;
        }
    if (strcmp(cmd, "info") == 0)
        return cmd_info(argc - 2, argv + 2);
    if (strcmp(cmd, "sample") == 0)
        return cmd_sample(argc - 2, argv + 2);
    if (strcmp(cmd, "encode") == 0)
        return cmd_encode(argc - 2, argv + 2);
    if (strcmp(cmd, "decode") == 0)
        return cmd_decode(argc - 2, argv + 2);
    if (strcmp(cmd, "eval") == 0)
        return cmd_eval(argc - 2, argv + 2);
    if (strcmp(cmd, "send") == 0)
        return cmz_cmd_send(argc - 2, argv + 2);
    fprintf(stderr, "%s: unknown command '%s' (cmz --help lists them)\n", prog, cmd);
    return EXIT_USAGE;
}
