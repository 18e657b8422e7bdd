/*
 * fuzz_glb - libFuzzer target for the viewer's glTF input (cm_glb_read.h, `cmz-view MODEL.glb`):
 * any bytes must end in CM_OK or a refusal with a reason, never a crash, a hang or an access out of
 * bounds; on CM_OK every index names a vertex of its own face, every face's vertices and indices lie
 * within the mesh, and each face has its part (1..nparts).  The mesh is a small one, for half the
 * inputs with a spill in memory and a window of 64 vertices (a primitive larger than it goes in
 * runs of triangles).  Seeds: tests/fuzz/corpus_glb (`cmz decode`'s GLBs of
 * three fuzz IGES seeds, one with placed copies as nodes).
 */
#include <stdint.h>
#include <string.h>

#include "cm/cm_glb_read.h"

static cm_glb_reader g;
static cm_model model;
static float pos[4096][3], nrm[4096][3];
static uint32_t idx[12288];
static cm_mesh_face faces[256];

static const uint8_t *data;
static size_t len;

/* the mesh's spill in memory (a streaming terminal's files): a small window, so that a primitive
   larger than it goes in runs of triangles */
#define SPILL_BYTES (1u << 20)
static uint8_t spilled[3][SPILL_BYTES];
static cm_mesh_spill spill;

static int mem_spill(void *ctx, int write, unsigned s, uint64_t off, void *buf, size_t n)
{
    (void)ctx;
    if (s >= 3 || off > SPILL_BYTES || n > SPILL_BYTES - off)
        return -1;
    if (write)
        memcpy(spilled[s] + off, buf, n);
    else
        memcpy(buf, spilled[s] + off, n);
    return 0;
}

static int mem_src(void *ctx, uint64_t off, void *buf, size_t n)
{
    (void)ctx;
    if (off > len || n > len - off)
        return -1;
    memcpy(buf, data + off, n);
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n);
int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n)
{
    data = d;
    len = n;
    cm_mesh mesh;
    memset(&mesh, 0, sizeof mesh);
    mesh.pos = pos;
    mesh.nrm = nrm;
    mesh.idx = idx;
    mesh.faces = faces;
    mesh.cap_verts = 4096;
    mesh.cap_index = 12288;
    mesh.cap_faces = 256;
    if (n > 0 && (d[n - 1] & 1)) { /* half the inputs through a spill with a window of 64 vertices */
        memset(&spill, 0, sizeof spill);
        spill.io = mem_spill;
        cm_mesh_set_spill(&mesh, &spill, 64, 192, SPILL_BYTES / 12u, SPILL_BYTES / 4u);
    }
    cm_status st;
    cm_status_init(&st);
    cm_err e = cm_glb_read(&g, mem_src, NULL, n, &mesh, &model, &st);
    if (e != CM_OK) {
        if (st.where == NULL)
            __builtin_trap(); /* a refusal without a reason */
        return 0;
    }
    if (mesh.nfaces != model.nfaces || mesh.nverts > mesh.cap_verts || mesh.nindex > mesh.cap_index)
        __builtin_trap();
    for (uint32_t f = 0; f < mesh.nfaces; f++) {
        const cm_mesh_face *F = &faces[f];
        if (F->first_vert + F->nverts > mesh.nverts || F->first_index + F->nindex > mesh.nindex || F->nindex % 3u)
            __builtin_trap();
        for (uint32_t k = 0; k < F->nindex; k++) {
            uint32_t v = cm_mesh_idx(&mesh, F->first_index + k); /* (from the window or the spill) */
            if (v < F->first_vert || v >= F->first_vert + F->nverts)
                __builtin_trap();
        }
        if (model.faces[f].part < 1 || model.faces[f].part > model.nparts)
            __builtin_trap();
    }
    return 0;
}
