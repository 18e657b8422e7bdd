/*
 * mesh_check FILE.cmz... - decode each file as the terminal does, tessellate
 * it at the file's recommended tolerance, weld the mesh by position and
 * check what a viewer relies on:
 *   - no triangle with two corners at one point;
 *   - every directed edge used once (no overlapping or misoriented faces);
 *   - open boundary exactly where the model has free edges: the unpaired
 *     triangle sides must number the samples of the edges only one face
 *     uses (an edge shared by two faces is stitched, sample for sample).
 * Each part (faces connected through shared edges) is checked on its own:
 * parts of an assembly may touch, and welding across them would report
 * their contact as overlap.  Parts with non-manifold edges (three or more
 * uses) get the first check only: there several parts' faces meet and may
 * coincide (an assembly's parts joined along their edges).  One "ok"/"not ok" line per file;
 * exit status 1 if any failed.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_decode.h"
#include "cm/cm_tessellate.h"
#include "cm_decode_file.h"
#include "mesh/mesh_topo.h"

static cm_decoder dec;
static cm_tess_ws tess;
static double ts[CM_MAX_EDGE_SAMPLES + 1];

static uint32_t find(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: mesh_check FILE.cmz...\n");
        return 2;
    }
    size_t cap_t = 1u << 24, cap_v = cap_t + 2u * CM_MAX_FACES;
    cm_mesh mesh = {malloc(cap_v * sizeof *mesh.pos), malloc(cap_v * sizeof *mesh.nrm),
                    malloc(3 * cap_t * sizeof *mesh.idx), malloc(CM_MAX_FACES * sizeof *mesh.faces), 0,
                    (uint32_t)cap_v, 0, (uint32_t)(3 * cap_t), 0, CM_MAX_FACES, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    unsigned *uses = malloc(CM_MAX_EDGES * sizeof *uses);
    uint32_t *parent = malloc(CM_MAX_FACES * sizeof *parent), *owner = malloc(CM_MAX_EDGES * sizeof *owner);
    cm_mesh part_mesh = {malloc(cap_v * sizeof *mesh.pos), NULL, malloc(3 * cap_t * sizeof *mesh.idx), NULL, 0,
                         (uint32_t)cap_v, 0, (uint32_t)(3 * cap_t), 0, 0, 0, 0, 0, 0, NULL, NULL, 0, 0, 0, 0};
    if (!mesh.pos || !mesh.nrm || !mesh.idx || !mesh.faces || !uses || !parent || !owner || !part_mesh.pos ||
        !part_mesh.idx) {
        fprintf(stderr, "mesh_check: out of memory\n");
        return 2;
    }
    int bad = 0;
    for (int a = 1; a < argc; a++) {
        cm_status st;
        cm_status_init(&st);
        cm_decode_summary sum;
        cm_err e = cm_decode_read(argv[a], &dec, &st);
        if (e == CM_OK)
            e = cm_decode_mesh(&dec, 0, &mesh, &tess, &sum, &st);
        if (e != CM_OK) {
            printf("not ok - %s: %s (%s)\n", argv[a], cm_err_name(e), st.where ? st.where : "?");
            bad++;
            continue;
        }
        const cm_model *m = &dec.model;
        /* parts: union-find over faces through the edges they share */
        for (uint32_t f = 0; f < m->nfaces; f++)
            parent[f] = f;
        for (uint32_t ed = 0; ed < m->nedges; ed++)
            owner[ed] = UINT32_MAX;
        for (uint32_t f = 0; f < m->nfaces; f++)
            for (uint32_t l = 0; l < m->faces[f].nloops; l++) {
                const cm_loop *L = &m->loops[m->faces[f].loop0 + l];
                for (uint32_t k = 0; k < L->nuse; k++) {
                    uint32_t ed = m->uses[L->use0 + k].edge;
                    if (owner[ed] == UINT32_MAX)
                        owner[ed] = f;
                    else
                        parent[find(parent, f)] = find(parent, owner[ed]);
                }
            }
        memset(uses, 0, m->nedges * sizeof *uses);
        for (uint32_t u = 0; u < m->nuses; u++)
            uses[m->uses[u].edge]++;
        size_t nparts = 0, parts_bad = 0, tri = 0, degenerate = 0, duplicate = 0, unpaired = 0, expect = 0, lens = 0;
        size_t nonmanifold_parts = 0;
        double volume = 0;
        char worst[256] = "";
        for (uint32_t root = 0; root < m->nfaces; root++) {
            if (find(parent, root) != root)
                continue;
            nparts++;
            /* the part's triangles, as a mesh of its own (vertices are per face already) */
            cm_mesh sub = part_mesh;
            sub.nverts = sub.nindex = sub.nfaces = 0;
            for (uint32_t mf = 0; mf < mesh.nfaces; mf++) {
                const cm_mesh_face *F = &mesh.faces[mf];
                if (find(parent, F->source_face) != root)
                    continue;
                memcpy(sub.pos + sub.nverts, mesh.pos + F->first_vert, F->nverts * sizeof *sub.pos);
                for (uint32_t i = 0; i < F->nindex; i++)
                    sub.idx[sub.nindex + i] = mesh.idx[F->first_index + i] - F->first_vert + sub.nverts;
                sub.nverts += F->nverts;
                sub.nindex += F->nindex;
            }
            size_t expect_free = 0, nonmanifold = 0;
            for (uint32_t ed = 0; ed < m->nedges; ed++) {
                if (owner[ed] == UINT32_MAX || find(parent, owner[ed]) != root)
                    continue;
                nonmanifold += uses[ed] >= 3;
                if (uses[ed] != 1)
                    continue;
                int n = 0;
                cm_status_init(&st);
                if (cm_edge_params(m, ed, sum.tess_tol, ts, NULL, CM_MAX_EDGE_SAMPLES + 1, &n, &st) == CM_OK)
                    expect_free += (size_t)n;
            }
            mesh_topo t;
            if (mesh_topo_analyse(&sub, &t) != 0) {
                fprintf(stderr, "mesh_check: out of memory\n");
                return 2;
            }
            int ok = t.degenerate == 0 && (nonmanifold > 0 || (t.duplicate == 0 && t.unpaired == expect_free));
            if (!ok && !worst[0])
                snprintf(worst, sizeof worst,
                         "; first bad part (face %u): %zu degenerate, %zu overlapping, open %zu vs %zu free samples",
                         root, t.degenerate, t.duplicate, t.unpaired, expect_free);
            parts_bad += !ok;
            nonmanifold_parts += nonmanifold > 0;
            tri += t.triangles;
            degenerate += t.degenerate;
            duplicate += t.duplicate;
            lens += t.lens_chords;
            if (!nonmanifold) {
                unpaired += t.unpaired;
                expect += expect_free;
            }
            volume += t.volume;
            mesh_topo_free(&t);
        }
        char lens_note[96] = "";
        if (lens)
            snprintf(lens_note, sizeof lens_note, " (%zu chords through thin lenses between faces)", lens);
        printf("%s - %s: %u faces, %zu parts, %zu triangles; %zu degenerate, %zu overlapping%s; "
               "open sides %zu = free-edge samples %zu%s; volume %.6g%s\n",
               parts_bad ? "not ok" : "ok", argv[a], m->nfaces, nparts, tri, degenerate, duplicate, lens_note, unpaired, expect,
               nonmanifold_parts ? " (parts with non-manifold edges not compared)" : "", volume, worst);
        bad += parts_bad > 0;
    }
    free(mesh.pos);
    free(mesh.nrm);
    free(mesh.idx);
    free(mesh.faces);
    free(uses);
    free(parent);
    free(owner);
    free(part_mesh.pos);
    free(part_mesh.idx);
    return bad ? 1 : 0;
}
