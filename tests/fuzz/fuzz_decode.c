/*
 * fuzz_decode - libFuzzer target for the terminal's whole decode path:
 * .cmz bytes fed in chunks -> header and limit checks -> section decoding
 * -> surface rebuild -> tessellation -> GLB serialisation in memory.
 * Any input must end in CM_OK or a clear error (a code, a reason and the
 * byte offset where it was found; for a face's error, the face), never a
 * crash, a hang or an out-of-bounds access.  A face that fails is left out
 * (the mesh rolled back), as cm_decode_mesh does.  The first input byte
 * picks the chunk size, so the fuzzer also exercises feeds that split the
 * header, a varint or a section anywhere, as a serial link does.
 *
 * Built with clang -fsanitize=fuzzer,address,undefined (make fuzz-decode),
 * without CRC checks (FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION); replayed
 * without libFuzzer by replay_main.c in make check.  fuzz_decode_crc.c
 * runs the same checks on the product build (CRCs checked), its mutator
 * keeping the CRCs valid.
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "cm/cm_decode.h"
#include "cm/cm_decode_state.h"
#include "cm/cm_place.h"
#include "cm/cm_out.h"
#include "cm/cm_tessellate.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define FUZZ_FACES 3
#define FUZZ_COARSE 16.0
static cm_decode_state state;
static cm_out writer;

/* a failure of the file must always say why and where: the code, a reason and the byte offset (the
   decoder's misuse, CM_E_ARG, has no place in the input) */
static void check_reason(cm_err e, const cm_status *st)
{
    if (e != CM_OK && (st->code != e || st->where == NULL || (e != CM_E_ARG && st->offset == CM_NO_OFFSET)))
        __builtin_trap();
}

/* ... and a failure of face f names the face, and a place inside the file */
static void check_face_reason(cm_err e, const cm_status *st, uint32_t f, uint32_t file_len)
{
    check_reason(e, st);
    if (e != CM_OK && (st->face != f || st->offset >= file_len))
        __builtin_trap();
}

/* the mesh's spill in memory (the terminal's is files beside the output): the window's flushes,
   the pages read back and the spilled writers are fuzzed too; past its room a write fails, as a
   full disk would (CM_E_IO) */
static uint8_t spill_mem[CM_SPILL_STREAMS][1u << 21];
static uint64_t spill_len[CM_SPILL_STREAMS];

static int spill_mem_io(void *ctx, int write, unsigned s, uint64_t off, void *buf, size_t n)
{
    (void)ctx;
    if (s >= CM_SPILL_STREAMS || off > sizeof spill_mem[0] || n > sizeof spill_mem[0] - off)
        return -1;
    if (write) {
        memcpy(spill_mem[s] + off, buf, n);
        if (off + n > spill_len[s])
            spill_len[s] = off + n;
        return 0;
    }
    if (off + n > spill_len[s])
        __builtin_trap(); /* the mesh reads only what it wrote */
    memcpy(buf, spill_mem[s] + off, n);
    return 0;
}

/* the input as the decoder's source: a file longer than its window (8 KiB on the terminal) has its
   sections read again from it, as the terminal reads its stored file */
static const uint8_t *src_data;
static size_t src_size;

static int read_again(void *ctx, uint32_t off, uint8_t *buf, size_t n)
{
    (void)ctx;
    if (off > src_size || n > src_size - off)
        return -1;
    memcpy(buf, src_data + off, n);
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    size_t chunk = 1u + (size_t)data[0] * 97u; /* 1 .. 24736 bytes per feed */
    data++;
    size--;

    cm_status st;
    cm_status_init(&st);
    cm_dec_init(&state.dec);
    cm_err e = CM_OK;
    for (size_t off = 0; off < size && e == CM_OK; off += chunk) {
        size_t n = size - off < chunk ? size - off : chunk;
        e = cm_dec_feed(&state.dec, data + off, n, &st);
    }
    src_data = data;
    src_size = size;
    cm_dec_set_source(&state.dec, read_again, NULL);
    if (e == CM_OK)
        e = cm_dec_finish(&state.dec, &st);
    check_reason(e, &st);
    if (e != CM_OK)
        return 0;

    /* a model the decoder accepted must tessellate or fail cleanly, face by face; FUZZ_FACES faces
       only, from one the input picks (its length and a byte of it: not a CRC, which the structure-
       aware stage keeps constant), so that one input stays well under a second under the
       sanitizers and mutations still reach every face.  A KEEP face of a corpus model costs up to
       0.4 s under ASan (its loop projected onto a B-spline): 12 faces from the first one made the
       campaign crawl at 10 runs/s.  A face that fails is left out, as cm_decode_mesh
       (platform/cm_decode_file.c) does */
    /* most inputs are tessellated at 16 times the file's tolerance: the same code (boundary
       sampling, refinement, triangulation, the caps) with about 1/30 of the surface evaluations, so
       that a campaign reaches its millions of executions on a small machine (the refinement at the
       file's own tolerance made one input cost up to 0.6 G instructions); one input in eight
       (its length) keeps the file's tolerance, so the dense paths and the point caps stay fuzzed */
    double tol = (size & 7u) == 0 ? state.dec.model.tess_tol : state.dec.model.tess_tol * FUZZ_COARSE;
    memset(spill_len, 0, sizeof spill_len);
    cm_mesh mesh = cm_decode_state_mesh(&state, spill_mem_io, NULL);
    cm_mesh_clear(&mesh);
    uint32_t first = state.dec.model.nfaces ? (uint32_t)((size * 31u + data[size / 2]) % state.dec.model.nfaces) : 0;
    for (uint32_t f = first; f < state.dec.model.nfaces && f < first + FUZZ_FACES; f++) {
        cm_tess_info info;
        cm_status_init(&st);
        cm_mesh_mark mark = cm_mesh_save(&mesh);
        e = cm_tessellate_face(&state.dec.model, f, tol, &mesh, &state.tess, &info, &st);
        check_face_reason(e, &st, f, state.dec.file_len);
        /* the triangulator's last call stayed within its budgets (cm_tess.c: 16 ear tests per node,
           256 fallback steps per point, each + a constant and one last turn), whatever the ring */
        if (state.tess.tri.ear_tests > 17L * CM_TESS_MAX_NODES + 256 ||
            state.tess.tri.cdt_work > 259L * CM_MAX_TESS_POINTS + 4096)
            __builtin_trap();
        if (e == CM_E_LIMIT || e == CM_E_IO) /* the mesh is full, or its spill: the terminal stops too */
            break;
        if (e != CM_OK) {
            cm_mesh_rollback(&mesh, &mark);
            if (mesh.nverts != mark.nverts || mesh.nindex != mark.nindex || mesh.nfaces != mark.nfaces)
                __builtin_trap();
        } else if (info.points > cm_tess_point_cap(&state.dec.model, tol)) {
            __builtin_trap(); /* the face's work stayed within what the header declares */
        } else if (mesh.nindex / 3 > (uint32_t)cm_tess_triangle_cap(&state.dec.model, tol)) {
            break; /* the model's too: cm_decode_mesh stops here */
        }
    }
    /* the placed copies (format 4.3) of what there is, as cm_decode_mesh places them: within the
       mesh's capacities, or nothing of them kept */
    cm_status_init(&st);
    cm_mesh_mark before = cm_mesh_save(&mesh);
    if (cm_mesh_place(&state.dec.model, &mesh, &st) != CM_OK &&
        (mesh.nverts != before.nverts || mesh.nindex != before.nindex || mesh.nfaces != before.nfaces))
        __builtin_trap();
    /* every index the tessellator wrote points at a vertex it wrote */
    for (uint32_t i = 0; i < mesh.nindex; i++)
        if (cm_mesh_idx(&mesh, i) >= mesh.nverts && !cm_mesh_spill_failed(&mesh))
            __builtin_trap();

    /* serialise what there is, in small pieces */
    cm_status_init(&st);
    if (cm_out_begin(&writer, CM_OUT_GLB, &mesh, &st) == CM_OK) {
        uint8_t buf[4096];
        for (;;) {
            size_t n = 0;
            int done = 0;
            if (cm_out_next(&writer, buf, sizeof buf, &n, &done, &st) != CM_OK || done)
                break;
        }
    }
    return 0;
}
