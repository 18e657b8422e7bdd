/*
 * fuzz_glb - libFuzzer target for the viewer's glTF input (cm_glb_read.h, `cmz-view MODEL.glb`):
 * any bytes must end in CM_OK or a refusal with a reason, never a crash, a hang or an access out of
 * bounds; on CM_OK every index names a vertex of its own face, every face's vertices and indices lie
 * within the mesh, and each face has its part (1..nparts).  The mesh is a small one without a spill
 * (its capacity checks are the reader's).  Seeds: tests/fuzz/corpus_glb (`cmz decode`'s GLBs of
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
        for (uint32_t k = 0; k < F->nindex; k++)
            if (idx[F->first_index + k] < F->first_vert || idx[F->first_index + k] >= F->first_vert + F->nverts)
                __builtin_trap();
        if (model.faces[f].part < 1 || model.faces[f].part > model.nparts)
            __builtin_trap();
    }
    return 0;
}
