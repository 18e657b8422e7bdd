/*
 * cmd_decode.c - `cmz decode MODEL.cmz -o OUT.glb|OUT.stl|OUT.obj`: the
 * terminal's decode path on the workstation (same code, host limits), the
 * mesh on the heap and grown when a file declares less than it makes.
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_format.h"
#include "cm/cm_place.h"
#include "cm_decode_file.h"
#include "cm_report.h"

static cm_tess_ws tess_ws; /* large: static storage, as on the terminal */

/* --face-map: one line per decoded face, in the order of the output's triangles: the face's
   number in the model and its triangle count (lets a test attribute each triangle to its face) */
static int write_face_map(const char *path, const cm_mesh *mesh)
{
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "%s: %s: %s\n", cmd_prog, path, strerror(errno));
        return EXIT_IO;
    }
    fprintf(f, "face\ttriangles\n");
    for (uint32_t k = 0; k < mesh->nfaces; k++)
        fprintf(f, "%u\t%u\n", mesh->faces[k].source_face, mesh->faces[k].nindex / 3u);
    if (fclose(f) != 0) {
        fprintf(stderr, "%s: %s: %s\n", cmd_prog, path, strerror(errno));
        return EXIT_IO;
    }
    return EXIT_OK;
}

int cmd_decode(int argc, char **argv)
{
    const char *path = NULL, *out = NULL, *face_map = NULL;
    double tol = 0;
    int sync = 0;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "-o") == 0 && v) {
            out = v;
            i++;
        } else if (strcmp(a, "--sync") == 0) {
            sync = 1;
        } else if (strcmp(a, "--face-map") == 0 && v) {
            face_map = v;
            i++;
        } else if (strcmp(a, "--tess") == 0 && v) {
            if (cmd_parse_real(a, v, 1e-9, 1e9, &tol))
                return EXIT_USAGE;
            i++;
        } else if (cmd_common_arg("decode", a, &path)) {
            return EXIT_USAGE;
        }
    }
    int fmt = out ? cm_out_format_of(out) : -1;
    if (!path || !out || fmt < 0) {
        fprintf(stderr, "%s decode: usage: cmz decode MODEL.cmz -o OUT.glb|OUT.stl|OUT.obj [--tess MM] [--sync]\n",
                cmd_prog);
        return EXIT_USAGE;
    }
    cm_decoder *decoder = cmd_decoder();
    cm_status st;
    cm_status_init(&st);
    if (cm_decode_read(path, decoder, &st) != CM_OK) {
        cm_report_status(stderr, cmd_prog, path, &st);
        return cmd_exit_for(st.code);
    }
    /* the mesh sized by what the file says it needs (the workstation may use the heap) */
    uint64_t tris = decoder->need[CM_LIMIT_MAX_TRIS];
    if (tol > 0 && tol < decoder->model.tess_tol)
        tris = tris * (uint64_t)(decoder->model.tess_tol / tol + 1.0) * 2; /* finer than the file planned */
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
        /* the model's faces and their placed copies (format 4.3) */
        uint64_t no_tris, copies;
        cm_place_counts(&decoder->model, NULL, &no_tris, &copies);
        copies += decoder->model.nfaces;
        mesh.cap_faces = (uint32_t)(copies == 0 ? 1 : copies > CM_MAX_FACES ? CM_MAX_FACES : copies);
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
        e = cm_decode_mesh(decoder, tol, &mesh, &tess_ws, &sum, &st);
        if (e != CM_E_LIMIT || st.limit != CM_LIMIT_MAX_TRIS || tris >= CM_MAX_TRIS)
            break;
        tris = 4 * tris > CM_MAX_TRIS ? CM_MAX_TRIS : 4 * tris;
    }
    if (e == CM_E_NOMEM && st.code == CM_OK) {
        fprintf(stderr, "%s: out of memory for %llu triangles\n", cmd_prog, (unsigned long long)tris);
        rc = EXIT_NOMEM;
    } else if (e != CM_OK || cm_write_mesh(&mesh, (cm_out_format)fmt, out, sync, &bytes, &st) != CM_OK) {
        cm_report_status(stderr, cmd_prog, path, &st);
        rc = cmd_exit_for(st.code);
    } else {
        /* one bad face never sinks a model: each one left out is named */
        for (uint32_t i = 0; i < sum.faces_left_out && i < CM_DECODE_LEFT_OUT_LIST; i++) {
            char why[512];
            cm_format_status(why, sizeof why, &sum.left_out[i]);
            fprintf(stderr, "%s: %s: warning: face left out: %s\n", cmd_prog, path, why);
        }
        if (sum.faces_left_out > CM_DECODE_LEFT_OUT_LIST)
            fprintf(stderr, "%s: %s: warning: %lu more faces left out\n", cmd_prog, path,
                    (unsigned long)(sum.faces_left_out - CM_DECODE_LEFT_OUT_LIST));
        if (face_map && (rc = write_face_map(face_map, &mesh)) != EXIT_OK) {
            /* reported */
        } else if (!cmd_quiet) {
            char left[64] = "";
            if (sum.faces_left_out)
                snprintf(left, sizeof left, ", %lu left out", (unsigned long)sum.faces_left_out);
            char methods[128];
            cm_report_method_counts(methods, sizeof methods, sum.faces_by_method, 0);
            char placed[96] = "";
            if (decoder->model.nplacements > 0)
                snprintf(placed, sizeof placed, "; %u rebuilt, the rest as %u placed copies", sum.faces,
                         decoder->model.nplacements);
            printf("%s -> %s: %u faces (%s%s%s), %u triangles, %u vertices, chordal tolerance %.3g mm, %llu bytes\n",
                   path, out, sum.placed_faces, methods, left, placed, sum.triangles, sum.vertices, sum.tess_tol,
                   (unsigned long long)bytes);
        }
    }
    free(mesh.pos);
    free(mesh.nrm);
    free(mesh.idx);
    free(mesh.faces);
    return rc;
}
