/*
 * fuzz_glb - libFuzzer target for the viewer's glTF input (cm_glb_read.h, `cmz-view MODEL.glb`):
 * any bytes must end in CM_OK or a refusal with a reason, never a crash, a hang or an access out of
 * bounds; on CM_OK every index names a vertex of its own face, every face's vertices and indices lie
 * within the mesh, and each face has its part (1..nparts).  The mesh is a small one, for half the
 * inputs with a spill in memory and a window of 64 vertices (a primitive larger than it goes in
 * runs of triangles).  Then it is drawn as `cmz-view MODEL.glb` draws it (cm_view.h: parts, the
 * fit and its faces' boxes, nearest first with the coarse depth, the rasteriser's set-ups), in a
 * small frame from a direction, turn, step and projection the input's first bytes choose: any
 * vertices (huge, not numbers, behind the eye) must draw without a fault.  Seeds: tests/fuzz/corpus_glb (`cmz decode`'s GLBs of
 * three fuzz IGES seeds, one with placed copies as nodes).
 */
#include <stdint.h>
#include <string.h>

#include "cm/cm_glb_read.h"
#include "cm/cm_view.h"
#include "../unit/test_mesh.h"

static cm_glb_reader g;
static cm_view view;
static cm_model model;
static float pos[4096][3], nrm[4096][3];
static uint32_t idx[12288];
static cm_mesh_face faces[256];
static float boxes[256][6];

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
    cm_mesh mesh = test_mesh_on(pos, nrm, idx, faces, 4096, 12288, 256);
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
    float lo[3], hi[3], blo[3], bhi[3];
    uint32_t nboxed = 0;
    int any = cm_mesh_bounds(&mesh, lo, hi);
    /* the faces' boxes give the same bounds (the union), and below the same fit */
    if (cm_mesh_face_boxes(&mesh, boxes, 256, &nboxed, blo, bhi) != any ||
        (any && (memcmp(lo, blo, sizeof lo) != 0 || memcmp(hi, bhi, sizeof hi) != 0)))
        __builtin_trap();
    if (!any)
        return 0;
    cm_view_opts o;
    cm_view_opts_default(&o);
    uint8_t pick = n > 1 ? d[n - 2] : 0;
    o.width = 96 + (pick & 7) * 9; /* (80-ish to 160 across: tiles cut short at the edges) */
    o.height = 64 + (pick >> 3 & 3) * 7;
    o.width = o.width <= CM_VIEW_MAX_W ? o.width : CM_VIEW_MAX_W;
    o.height = o.height <= CM_VIEW_MAX_H ? o.height : CM_VIEW_MAX_H;
    o.dir = (cm_view_dir)((pick >> 5) % CM_VIEW_DIR_COUNT);
    o.perspective = n > 2 && (d[n - 3] & 1);
    o.turn = n > 2 ? d[n - 3] >> 1 : 0;
    cm_status_init(&st);
    if (cm_view_begin(&view, &o, lo, hi, &st) != CM_OK)
        return 0;
    uint32_t parts = cm_view_parts(&view, &model);
    o.step = parts > 0 && n > 3 ? d[n - 4] % (parts + 1) : 0;
    view.o.step = o.step;
    if (nboxed) { /* (the fit from every vertex, then from the boxes: the same camera) */
        cm_view_fit(&view, &mesh, NULL, 0);
        const double c0[3] = {view.c[0], view.c[1], view.c[2]}, s0 = view.scale;
        if (cm_view_begin(&view, &o, lo, hi, &st) != CM_OK)
            __builtin_trap();
        (void)cm_view_parts(&view, &model);
        view.o.step = o.step;
        cm_view_fit(&view, &mesh, (const float(*)[6])boxes, nboxed);
        if (memcmp(c0, view.c, sizeof c0) != 0 || memcmp(&s0, &view.scale, sizeof s0) != 0)
            __builtin_trap();
    } else {
        cm_view_fit(&view, &mesh, NULL, 0);
    }
    cm_view_mesh(&view, &mesh);
    cm_view_edges(&view, &model);
    return 0;
}
