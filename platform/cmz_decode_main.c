/*
 * cmz-decode - the terminal's decoder: .cmz in, .glb/.stl/.obj out.
 *
 *   cmz-decode MODEL.cmz -o MODEL.glb [--tess MM] [--sync]
 *   cmz-decode --limits | --version | --help
 *
 * Built with the board's profile (PROFILE=terminal by default): every
 * buffer is static and sized by fixedcfg; the decode path never touches
 * the heap.  A model larger than this build's limits is refused before
 * its body is read, naming the limit.  The output appears atomically
 * (a temporary file renamed into place; --sync: fsynced first).
 * Errors name the place in the input: the byte offset and, for a face's
 * error, the face.  A face that cannot be tessellated is left out, with a
 * warning naming it; the summary line then ends ", N faces left out".
 *
 * Exit status: 0 success, 1 the file is malformed or exceeds a limit,
 * 2 usage, 3 I/O error.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cm/cm_decode_state.h"
#include "cm/cm_limits_info.h"
#include "cm_decode_file.h"
#include "cm_report.h"

/* everything big is static: the decode path never touches the heap */
static cm_decode_state state;

/* "PROG: IN: [face F, ]byte N: text (CODE) [in where]": the place in the input first (cm_format_status) */
static void report(FILE *f, const char *level, const char *in, const cm_status *st)
{
    char text[512];
    cm_format_status(text, sizeof text, st);
    fprintf(f, "cmz-decode: %s%s: %s\n", level, in, text);
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: cmz-decode MODEL.cmz -o OUT.glb|OUT.stl|OUT.obj [--tess MM] [--sync]\n"
            "       cmz-decode --limits | --version | --help\n"
            "\n"
            "Rebuild a curvemesh model and write it as binary glTF (metres, +Y up), binary STL\n"
            "or OBJ (millimetres), chosen by the extension.  --tess: chordal tolerance in mm\n"
            "(default: the file's recommendation).  The output appears whole or not at all (a\n"
            "temporary file renamed into place); --sync also flushes it to the disk first, so\n"
            "that a power cut cannot undo it (slower on an SD card).  Built with profile %s\n"
            "(--limits shows its limits).\n"
            "\n"
            "exit status: 0 success, 1 malformed file or over a limit, 2 usage, 3 I/O error.\n",
            cm_profile_name);
}

int main(int argc, char **argv)
{
    const char *in = NULL, *out = NULL;
    double tol = 0;
    int sync = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(argv[i], "--limits") == 0) {
            cm_report_limits(stdout);
            const cm_ram_part own[] = {
                {"  I/O chunks", "the reader's and the writer's chunks, the mesh spill's files", cm_decode_file_static_bytes()}};
            cm_report_program_ram(stdout, own, sizeof own / sizeof own[0]);
            return 0;
        } else if (strcmp(argv[i], "--version") == 0) {
            printf("cmz-decode 0.1.0 (format 1, profile %s)\n", cm_profile_name);
            return 0;
        } else if (strcmp(argv[i], "--sync") == 0) {
            sync = 1;
        } else if (strcmp(argv[i], "-o") == 0 && i + 1 < argc) {
            out = argv[++i];
        } else if (strcmp(argv[i], "--tess") == 0 && i + 1 < argc) {
            char *end;
            tol = strtod(argv[++i], &end);
            if (*end || !(tol > 0)) {
                fprintf(stderr, "cmz-decode: --tess wants a positive number of millimetres, not '%s'\n", argv[i]);
                return 2;
            }
        } else if (argv[i][0] == '-') {
            fprintf(stderr, "cmz-decode: unknown option %s\n", argv[i]);
            usage(stderr);
            return 2;
        } else if (!in) {
            in = argv[i];
        } else {
            fprintf(stderr, "cmz-decode: one model at a time\n");
            return 2;
        }
    }
    int fmt = out ? cm_out_format_of(out) : -1;
    if (!in || fmt < 0) {
        usage(stderr);
        return 2;
    }
    cm_mesh mesh = cm_decode_stream_mesh(&state, out, 0);
    cm_status st;
    cm_status_init(&st);
    cm_decode_summary sum;
    uint64_t bytes = 0;
    if (cm_decode_read(in, &state.dec, &st) != CM_OK ||
        cm_decode_mesh(&state.dec, tol, &mesh, &state.tess, &sum, &st) != CM_OK) {
        report(stderr, "", in, &st);
        return st.code == CM_E_IO ? 3 : 1;
    }
    /* faces left out: one warning each (the first CM_DECODE_LEFT_OUT_LIST), the count in the summary */
    for (uint32_t i = 0; i < sum.faces_left_out && i < CM_DECODE_LEFT_OUT_LIST; i++)
        report(stderr, "warning: ", in, &sum.left_out[i]);
    if (sum.faces_left_out > CM_DECODE_LEFT_OUT_LIST)
        fprintf(stderr, "cmz-decode: warning: %s: %lu more faces left out\n", in,
                (unsigned long)(sum.faces_left_out - CM_DECODE_LEFT_OUT_LIST));
    if (cm_write_mesh(&mesh, (cm_out_format)fmt, out, sync, &bytes, &st) != CM_OK) {
        report(stderr, "", in, &st);
        return st.code == CM_E_IO ? 3 : 1;
    }
    printf("%s -> %s: %u faces, %u triangles, %llu bytes", in, out, sum.faces, sum.triangles,
           (unsigned long long)bytes);
    if (sum.faces_left_out > 0)
        printf(", %lu faces left out", (unsigned long)sum.faces_left_out);
    printf("\n");
    return 0;
}
