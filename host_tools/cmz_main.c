/*
 * cmz - the curvemesh workstation tool: the top-level usage, --help,
 * --version, --limits and the dispatch to the commands, one file each in
 * cmd/ (`cmz send` in send/).
 *
 * Exit codes: 0 success, 1 the input is malformed or unsupported, 2 usage,
 * 3 I/O error (cannot read or write a file), 4 out of memory.
 */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <string.h>

#include "cm/cm_limits_info.h"
#include "cm_report.h"
#include "cmd/cmd.h"
#include "send/send_cmd.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: cmz COMMAND [OPTIONS] ...\n"
            "\n"
            "curvemesh workstation tool: reads CAD models (IGES 5.3, STEP AP203/AP214/AP242)\n"
            "for compression to .cmz.  The format is told by the file's content, not its name.\n"
            "\n"
            "commands:\n"
            "  info MODEL.igs|MODEL.stp [--json] [--parts]\n"
            "      Import the model and report what was read: exporter, units, entity counts\n"
            "      (read / used / skipped), faces by surface kind, loops and holes, vertices,\n"
            "      edges (shared / free / seam / non-manifold), G1 edges, solids, bounding box,\n"
            "      tolerances and warnings.  --json prints the same as one JSON object.\n"
            "      --parts lists the parts `encode` names instead, one per line in file order:\n"
            "      #N, faces, the names --steps knows it by.\n"
            "  encode MODEL.igs|MODEL.stp -o MODEL.cmz [--tol REL] [--tol-abs MM] [--quant REL] [--tess REL]\n"
            "         [--no-gregory] [--no-gregory-exact] [--no-gregory-fit] [--no-g1fit]\n"
            "         [--no-nfill] [--no-turning-basis] [--format MAJOR[.MINOR]] [--no-budget-steps]\n"
            "         [--no-instances] [--profile NAME] [--report FACES.tsv] [--strict] [-j N]\n"
            "         [--steps FILE]\n"
            "      Compress the model: each face's surface is deleted and rebuilt from its\n"
            "      boundary curves - a PLANE, else Gregory patches (3 to 8 sides) over cubics\n"
            "      close to its edges, else over the edges themselves (GREGORY-EXACT), else for a\n"
            "      four-edged face a B-spline over its edges that keeps their tangent planes\n"
            "      (G1FIT), else the exact patches plus a small fitted correction inside each\n"
            "      (GREGORY-FIT), else a B-spline fitted to the loop and its tangent planes (NFILL:\n"
            "      concave loops, up to 12 edges); G1FIT also on faces of 5 to 12 edges whose\n"
            "      trimmed mesh stays within the tolerance, and from format 4.2 a G1FIT or NFILL\n"
            "      net nearly within it with a small correction inside its two outer rings,\n"
            "      G1FIT with the twist of the surface's normal along each of its edges - when\n"
            "      the rebuilt surface, measured by the decoder's own code, stays within the\n"
            "      tolerance of the original and keeps tangent edges within 1 deg; else the\n"
            "      surface is kept.  A band bounded by two loops winding round its surface (a\n"
            "      full cylinder between two circles, no seam edge) is first cut open along its\n"
            "      surface, so the patches can take it; where the surface is kept anyway the cut\n"
            "      is undone.  The tolerance of a face is by default the smaller of 1 %%\n"
            "      of its bounding box and 1e-3 of the model's diagonal.  --tol: fraction of the\n"
            "      face's bounding box instead; --tol-abs: millimetres instead (with --tol too,\n"
            "      the smaller applies).\n"
            "      --quant: coordinate grid as a fraction of the model diagonal (default 1e-6);\n"
            "      --tess: recommended chordal tolerance for viewers (default 5e-4).\n"
            "      --no-gregory: planes only; --no-gregory-exact: no GREGORY-EXACT nor GREGORY-FIT\n"
            "      faces (the file stays readable by format 2.0 terminals); --no-gregory-fit: no\n"
            "      GREGORY-FIT faces (format 2.1 terminals); --no-nfill: no NFILL faces (format\n"
            "      2.3 terminals); --no-g1fit: no G1FIT faces (format 2.4 terminals);\n"
            "      --no-turning-basis: exact patches keep format 2.5's linear cross basis along\n"
            "      edges that turn (format 2.5 terminals).  --format 3 (or 2.6, 2, 1, 2.3, ...):\n"
            "      write what a terminal of that format reads - format 3's fixed 248-byte\n"
            "      header, format 2's coding of curves, and only the methods it knows\n"
            "      (default: 4.14, whose header is compact and range-coded, whose sections\n"
            "      are one stream, whose numbers are coded predicted, whose circular edges\n"
            "      are sent as arcs, whose edge uses are named among the edges at their\n"
            "      loop's vertex, whose terminal refines its tessellation faster, meshes\n"
            "      kept faces along their flatter direction and scales a Gregory patch by its\n"
            "      sides, which lists the model's parts and their names, whose Gregory\n"
            "      faces may carry the normals of flat corners, and whose Gregory sides\n"
            "      along arcs are cubics in closed form; --format 4.13, 4.12, 4.11, 4.10,\n"
            "      4.9, 4.8, 4.7, 4.6, 4.5, 4.4, 4.3, 4.2, 4.1 or 4.0 for terminals of\n"
            "      those).\n"
            "      An assembly\n"
            "      that places one part several times (IGES subfigure instances, STEP assembly\n"
            "      placements and mapped items) sends the\n"
            "      part once and each further placement as a transform (format 4.3; the\n"
            "      summary says how many faces were sent and how many placed);\n"
            "      --no-instances sends every placed face as a face of its own.\n"
            "      The file lists the model's parts and their names (format 4.12), the\n"
            "      terminal's assembly\n"
            "      steps: each outermost instance or occurrence, solid or shell, IGES\n"
            "      associativity group, loose faces joined by their edges, each placed copy;\n"
            "      in file order (`cmz info MODEL --parts` lists them), or with --steps FILE\n"
            "      those FILE names first, one per line (a name the part answers to, or #N,\n"
            "      the part's number in that list), the others after them in file order.\n"
            "      -j N: the methods chosen on N processes (the same file as with -j 1).\n"
            "      By default (format 3 or 4)\n"
            "      each curve is sent as the fewest\n"
            "      cubic points within a sixteenth of its faces' tolerance where that is\n"
            "      cheaper, and each curve and the vertices on a step of their own within\n"
            "      the same share, or as the arc through its ends and its middle point (format\n"
            "      4.4; the summary counts them) where that holds within the share and is\n"
            "      cheaper (the edges of kept faces: within two grid steps, on the grid);\n"
            "      a kept surface as the two arcs it is ruled between (a cylinder's or cone's\n"
            "      patch; format 4.4), else as the fewest uniform cubic points within\n"
            "      a quarter where that codes smaller (for terminals older than 4.1, its\n"
            "      boundary a sixteenth), whole where its face's triangles would fold; the edges\n"
            "      of kept faces stay on the grid and the methods are chosen again on them.\n"
            "      --no-budget-steps: every point on the grid, as\n"
            "      in the source (about 19 %% larger over the corpus, a quarter less time).\n"
            "      --profile refuses a file the\n"
            "      named board profile (terminal, host, tiny) cannot load; first, curves and kept\n"
            "      surfaces over its degree or control points are re-approximated within their\n"
            "      tolerance, and past its tessellation limits the recommended chordal\n"
            "      tolerance is made coarser, up to 16x (notes say so).  Prints one\n"
            "      summary line; --report writes a row per face (method, errors, G1, why kept,\n"
            "      and the face's triangles as the terminal makes them against its source).\n"
            "      A face that cannot be sent (it cannot be imported, or its surface does not\n"
            "      tessellate even kept) is left out with a warning naming its entity, and the\n"
            "      summary counts it; --strict makes that an error (exit status 1).\n"
            "  encode FOLDER|--list FILE -o OUTFOLDER [-j N] [--force] [--timeout S] [--shard K/N]\n"
            "         [--summary FILE.tsv] [encode options]\n"
            "      Encode a vault: every IGES and STEP model under FOLDER (*.igs, *.iges, *.stp,\n"
            "      *.step, *.p21; hidden folders left out), or every path in FILE (one a line,\n"
            "      '#' comments; a listed folder is walked; '-' reads the list from stdin), each\n"
            "      with the same options, N at a time in processes of their own.  The outputs\n"
            "      mirror the tree under OUTFOLDER (a/part.igs -> OUTFOLDER/a/part.cmz; two\n"
            "      models of one stem keep their extensions: part.igs.cmz, part.stp.cmz), each\n"
            "      model's warnings in OUT.cmz.log.  A model that fails, crashes or runs past\n"
            "      --timeout S seconds is named and the rest still encode.  A summary\n"
            "      (OUTFOLDER/cmz-vault.tsv, or --summary) has a row per model: sizes, share of\n"
            "      faces deleted, worst deviation, warnings, seconds, encoder and options, error.\n"
            "      A model of the size and time recorded there, whose output has the size\n"
            "      recorded and was built by this same cmz binary with the same options, is\n"
            "      skipped (--force: encode all).  A model that no longer reads loses an\n"
            "      earlier output (a timeout or a crash does not).\n"
            "      --shard K/N encodes only the models whose path hashes to K modulo N, for\n"
            "      task K of N of a batch engine (summary cmz-vault.K-of-N.tsv).\n"
            "      A progress bar on a TTY.  Exit status 1 if any model failed, 128 + the\n"
            "      signal when stopped by SIGINT, SIGTERM or SIGHUP (the summary is written,\n"
            "      the models not reached keep their rows).\n"
            "  eval MODEL.igs|MODEL.stp MODEL.cmz [--tol REL] [--tol-abs MM] [--report FACES.tsv]\n"
            "      Rebuild every face of MODEL.cmz with the terminal's code and measure it\n"
            "      against the model (a grid on each face and its boundary, normals across\n"
            "      tangent edges within 1 deg: docs/METHODS.md);\n"
            "      prints the summary per method, exit status 1 if a face is out of tolerance\n"
            "      (by default the encoder's: the smaller of the file's fraction of the face's\n"
            "      box and 1e-3 of the model's diagonal; --tol, --tol-abs as for encode).\n"
            "  decode MODEL.cmz -o OUT.glb|OUT.stl|OUT.obj [--tess MM] [--face-map FACES.tsv] [--sync]\n"
            "      Rebuild every face and tessellate it (chordal tolerance --tess in mm,\n"
            "      default the file's recommendation) into binary glTF (metres, +Y up),\n"
            "      binary STL or OBJ (millimetres), chosen by the extension.  --face-map:\n"
            "      each face's number and triangle count, in the output's triangle order.\n"
            "      The output appears whole or not at all (a temporary file renamed into\n"
            "      place); --sync flushes it to the disk first, as gzip --synchronous.\n"
            "  send MODEL.cmz|MODEL.igs|MODEL.stp --serial DEV[:BAUD] | --gadget FFSDIR | --usb VID:PID\n"
            "       [--stay] [--no-wait] [--chunk N] [--timeout S]\n"
            "      Send the model to a cmz-terminal, checked against (a CAD model: encoded\n"
            "      for) the limits the terminal announces; resumes after a cable pull; a\n"
            "      progress bar on a TTY.  --stay: send again whenever the terminal's request\n"
            "      button is pressed.  Exit status 3: link failure.  (cmz send --help)\n"
            "  sample MODEL.igs|MODEL.stp -o POINTS.xyz [--per-face N]\n"
            "      Write N points (default 20) lying on every trimmed face, inside its outer\n"
            "      loop and outside its holes, one 'x y z face_id' line each (millimetres,\n"
            "      face_id as in 'cmz info --json'), to check the import against another kernel.\n"
            "\n"
            "options:\n"
            "  --help      this text        --version   the version\n"
            "  --limits    the compile-time limits of this build (profile %s)\n"
            "  -q          no progress on stderr\n"
            "  --include-blanked\n"
            "              (info, encode, eval, sample) import blanked IGES entities too: hidden\n"
            "              in the CAD system, they are left out by default, each named in a\n"
            "              warning and counted by info (an IGES file of nothing but blanked\n"
            "              faces is imported whole, with a warning)\n"
            "\n"
            "exit status: 0 success, 1 malformed or unsupported input, 2 usage error,\n"
            "             3 I/O error, 4 out of memory.\n",
            cm_profile_name);
}

/* every command, in the order of the usage text: a new one is its file in cmd/ and a row here */
static const struct {
    const char *name;
    int (*run)(int argc, char **argv); /* the arguments after the command's name; returns the exit status */
} commands[] = {
    {"info", cmd_info},     {"encode", cmd_encode}, {"eval", cmd_eval},
    {"decode", cmd_decode}, {"send", cmz_cmd_send}, {"sample", cmd_sample},
};

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
    for (size_t k = 0; k < sizeof commands / sizeof commands[0]; k++)
        if (strcmp(cmd, commands[k].name) == 0)
            return commands[k].run(argc - 2, argv + 2);
    fprintf(stderr, "%s: unknown command '%s' (cmz --help lists them)\n", cmd_prog, cmd);
    return EXIT_USAGE;
}
