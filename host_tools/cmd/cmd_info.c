/*
 * cmd_info.c - `cmz info MODEL [--json]`: what the importer sees in a
 * CAD file, IGES or STEP (exporter, units, entities, faces, loops, the curve mesh's
 * edges, solids, bounding box, tolerances, warnings), as text or JSON.
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "encode/encode.h"

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

/* per IGES type (or STEP entity name): read, used */
typedef struct type_count {
    int type, read, used, bad;
    const char *name; /* STEP: the entity name (not NUL-terminated), name_len bytes */
    int name_len;
} type_count;

/* the name a STEP instance is listed under: a complex instance by its most telling part */
static void step_kind_name(const step_file *f, const step_entity *e, const char **name, int *len)
{
    static const char *const telling[] = {"B_SPLINE_CURVE_WITH_KNOTS", "B_SPLINE_SURFACE_WITH_KNOTS",
                                          "REPRESENTATION_RELATIONSHIP", "GEOMETRIC_REPRESENTATION_CONTEXT",
                                          "LENGTH_UNIT", "PLANE_ANGLE_UNIT", "SOLID_ANGLE_UNIT",
                                          "OVER_RIDING_STYLED_ITEM", "BREP_WITH_VOIDS"};
    const step_part *pick = e->nparts ? &f->parts[e->first_part] : NULL;
    for (size_t t = 0; t < sizeof telling / sizeof telling[0] && e->nparts > 1; t++)
        for (int i = 0; i < e->nparts; i++) {
            const step_part *p = &f->parts[e->first_part + i];
            if ((size_t)p->name_len == strlen(telling[t]) && strncasecmp(f->text + p->name, telling[t], strlen(telling[t])) == 0) {
                pick = p;
                t = sizeof telling / sizeof telling[0] - 1;
                break;
            }
        }
    *name = pick ? f->text + pick->name : "";
    *len = pick ? pick->name_len : 0;
}

static int cmp_type_name(const void *a, const void *b)
{
    const type_count *x = a, *y = b;
    int n = x->name_len < y->name_len ? x->name_len : y->name_len;
    int c = strncasecmp(x->name, y->name, (size_t)n);
    return c ? c : (x->name_len > y->name_len) - (x->name_len < y->name_len);
}

/* per STEP entity name: read, used (a file with more names than cap lists the first cap) */
static int count_step_types(const step_file *f, type_count *tc, int cap)
{
    int n = 0;
    for (int i = 0; i < f->nents; i++) {
        const char *name;
        int len, k = 0;
        step_kind_name(f, &f->ents[i], &name, &len);
        while (k < n && !(tc[k].name_len == len && strncasecmp(tc[k].name, name, (size_t)len) == 0))
            k++;
        if (k == n) {
            if (n == cap)
                continue;
            tc[n] = (type_count){0, 0, 0, 0, name, len};
            n++;
        }
        tc[k].read++;
        tc[k].used += f->ents[i].used;
    }
    qsort(tc, (size_t)n, sizeof *tc, cmp_type_name);
    return n;
}

/* a surface kind's name: brep_face.surf_type numbers surfaces as IGES does, for STEP too */
static const char *surface_name(int type, int step)
{
    if (!step)
        return iges_type_name(type);
    switch (type) {
    case 190: return "PLANE";
    case 192: return "CYLINDRICAL_SURFACE";
    case 194: return "CONICAL_SURFACE";
    case 196: return "SPHERICAL_SURFACE";
    case 198: return "TOROIDAL_SURFACE";
    case 120: return "SURFACE_OF_REVOLUTION";
    case 122: return "SURFACE_OF_LINEAR_EXTRUSION";
    case 128: return "B_SPLINE_SURFACE_WITH_KNOTS";
    default: return "unknown";
    }
}

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

typedef struct solid_info {
    int faces, free_edges, seams;
} solid_info;

/* `cmz info MODEL --parts`: the parts `cmz encode` names (format 4.11), one per line in file order,
   as a steps file names them: the number, the faces, the names */
static int list_parts(const char *path)
{
    cmd_fold_instances = 1; /* as `cmz encode` loads it: each placed copy a part */
    loaded_model lm;
    int loaded = cmd_load(path, &lm);
    if (loaded != EXIT_OK)
        return loaded;
    enc_parts p;
    char why[256];
    cm_status st;
    cm_status_init(&st);
    if (enc_parts_build(&lm, NULL, &p, why, sizeof why, &st) != CM_OK) {
        model_free(&lm);
        fprintf(stderr, "%s: out of memory\n", cmd_prog);
        return EXIT_NOMEM;
    }
    for (int k = 1; k <= p.nparts; k++) {
        char names[2][80];
        int nfaces, n = enc_part_names(&lm, &p, k, names, &nfaces);
        printf("#%d\t%d faces", k, nfaces);
        for (int i = 0; i < n; i++)
            printf("\t%s", names[i]);
        printf("\n");
    }
    enc_parts_free(&p);
    model_free(&lm);
    return EXIT_OK;
}

int cmd_info(int argc, char **argv)
{
    const char *path = NULL;
    int json = 0, parts = 0;
    for (int i = 0; i < argc; i++) {
        if (strcmp(argv[i], "--json") == 0)
            json = 1;
        else if (strcmp(argv[i], "--parts") == 0)
            parts = 1;
        else if (cmd_common_arg("info", argv[i], &path))
            return EXIT_USAGE;
    }
    if (!path) {
        fprintf(stderr, "%s info: which model? usage: cmz info MODEL.igs|MODEL.stp [--json] [--parts]\n", cmd_prog);
        return EXIT_USAGE;
    }
    if (parts)
        return list_parts(path);
    loaded_model lm;
    int loaded = cmd_load(path, &lm);
    if (loaded != EXIT_OK)
        return loaded;
    const iges_file *f = &lm.iges;
    const brep_model *m = &lm.brep;
    const cmesh *cm = &lm.mesh;
    type_count tc[256];
    int step = lm.is_step;
    int ntc = step ? count_step_types(&lm.step, tc, 256) : count_types(f, tc, 256);
    /* what the file says about itself */
    char units[200];
    const char *exporter = step ? lm.step.system : f->g.system_id, *preproc = step ? lm.step.schema : f->g.preprocessor;
    double to_mm = step ? lm.step_stats.unit_mm : f->to_mm;
    if (step)
        snprintf(units, sizeof units, "%g mm per unit (of the first shape representation)", to_mm);
    else
        snprintf(units, sizeof units, "%s (flag %d%s%s), model scale %g", units_name(f->g.units_flag), f->g.units_flag,
                 f->g.units_name[0] ? ", " : "", f->g.units_name, f->g.model_scale);
    int nread = 0, nused = 0, nbad = 0;
    for (int k = 0; k < ntc; k++) {
        nread += tc[k].read - tc[k].bad;
        nused += tc[k].used;
        nbad += tc[k].bad;
    }
    /* faces by base surface type */
    type_count sc[32];
    int nsc = 0;
    int holes = 0, face_loops = 0; /* (the faces' own: a face cut open keeps its loops as imported) */
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
        face_loops += m->faces[i].nloops;
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
        fprintf(stderr, "%s: out of memory\n", cmd_prog);
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
        json_str(stdout, exporter);
        printf(",\n  \"format\": \"%s\",\n  \"preprocessor\": ", step ? "step" : "iges");
        json_str(stdout, preproc);
        printf(",\n  \"units\": {\"flag\": %d, \"name\": ", step ? 0 : f->g.units_flag);
        json_str(stdout, step ? "" : f->g.units_name);
        printf(", \"to_mm\": %.17g, \"model_scale\": %.17g, \"resolution_mm\": %.6g},\n", to_mm,
               step ? 1.0 : f->g.model_scale, m->resolution_mm);
        printf("  \"entities\": {\"read\": %d, \"used\": %d, \"skipped\": %d, \"unreadable\": %d, \"by_type\": [", nread,
               nused, nread - nused, nbad);
        for (int k = 0; k < ntc; k++)
            printf("%s\n    {\"type\": %d, \"name\": \"%.*s\", \"read\": %d, \"used\": %d}", k ? "," : "", tc[k].type,
                   step ? tc[k].name_len : 64, step ? tc[k].name : iges_type_name(tc[k].type), tc[k].read - tc[k].bad,
                   tc[k].used);
        printf("]},\n  \"faces\": {\"total\": %d, \"trimmed_144\": %d, \"bounded_143\": %d, \"brep_510\": %d, "
               "\"untrimmed\": %d, \"failed\": %d, \"instances\": %d, \"face_entities\": %d, "
               "\"blanked_entities\": %d, \"blanked_faces\": %lld, \"by_surface\": [",
               m->nfaces, lm.stats.faces_144, lm.stats.faces_143, lm.stats.faces_510, lm.stats.faces_untrimmed,
               m->faces_failed, step ? lm.step_stats.placements : lm.stats.instances,
               step ? lm.step_stats.face_entities : lm.stats.face_entities, lm.stats.blanked_entities,
               lm.stats.blanked_faces);
        for (int k = 0; k < nsc; k++)
            printf("%s{\"type\": %d, \"name\": \"%s\", \"faces\": %d}", k ? ", " : "", sc[k].type,
                   surface_name(sc[k].type, step), sc[k].read);
        printf("]},\n  \"loops\": {\"total\": %d, \"holes\": %d, \"reoriented_faces\": %d, \"outer_reordered\": %d, "
               "\"seam_joined\": %d, \"seams_cut\": %d, \"domains_failed\": %d},\n",
               face_loops, holes, lm.loops_reversed, lm.outer_reordered, lm.seam_joined, lm.seams_cut, lm.domains_failed);
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
        printf("format      %s\n", step ? "STEP (ISO 10303-21)" : "IGES");
        printf("exporter    %s%s%s\n", exporter[0] ? exporter : "(not named)", preproc[0] ? " / " : "", preproc);
        printf("units       %s, resolution %.3g mm\n", units, m->resolution_mm);
        printf("entities    %d read, %d used, %d skipped%s", nread, nused, nread - nused, nbad ? "" : "\n");
        if (nbad)
            printf(", %d unreadable\n", nbad);
        for (int k = 0; k < ntc; k++)
            if (step)
                printf("  %-41.*s %6d read %6d used\n", tc[k].name_len, tc[k].name, tc[k].read, tc[k].used);
            else
                printf("  %4d %-36s %6d read %6d used\n", tc[k].type, iges_type_name(tc[k].type),
                       tc[k].read - tc[k].bad, tc[k].used);
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
        if (step)
            printf(" from %d solids and %d shells%s", lm.step_stats.solids, lm.step_stats.shells,
                   lm.step_stats.colored_faces ? ", coloured" : "");
        if (step && lm.step_stats.placements)
            printf(", %d placements of parts (%d distinct faces)", lm.step_stats.placements,
                   lm.step_stats.face_entities);
        if (m->faces_failed)
            printf("; %d could not be read (see warnings)", m->faces_failed);
        if (m->entities_failed)
            printf("; %d solids, shells or instances left out (see warnings)", m->entities_failed);
        if (lm.stats.blanked_entities)
            printf("; %lld more in %d blanked (hidden) entities not imported (--include-blanked)",
                   lm.stats.blanked_faces, lm.stats.blanked_entities);
        printf("\n  by surface:");
        for (int k = 0; k < nsc; k++)
            if (step)
                printf(" %d %s%s", sc[k].read, surface_name(sc[k].type, 1), k + 1 < nsc ? "," : "");
            else
                printf(" %d %s (%d)%s", sc[k].read, iges_type_name(sc[k].type), sc[k].type, k + 1 < nsc ? "," : "");
        printf("\nloops       %d: %d outer, %d holes", face_loops, face_loops - holes, holes);
        if (lm.loops_reversed)
            printf("; %d faces re-oriented to the surface normal", lm.loops_reversed);
        if (lm.outer_reordered)
            printf("; %d outer loops not listed first", lm.outer_reordered);
        if (lm.seam_joined)
            printf("; %d faces wound around a closed surface (%d cut open along it)", lm.seam_joined, lm.seams_cut);
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
        fprintf(stderr, "%s: writing the report failed: %s\n", cmd_prog, strerror(errno));
        return EXIT_IO;
    }
    return EXIT_OK;
}
