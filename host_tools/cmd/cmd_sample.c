/*
 * cmd_sample.c - `cmz sample MODEL.igs -o POINTS.xyz`: points on every
 * trimmed face, inside its outer loop and outside its holes, to check the
 * import against another CAD kernel.
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int cmd_sample(int argc, char **argv)
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
                fprintf(stderr, "%s sample: --per-face wants a number in 1..100000, not '%s'\n", cmd_prog, argv[i]);
                return EXIT_USAGE;
            }
            per_face = (int)v;
        } else if (cmd_common_arg("sample", argv[i], &path))
            return EXIT_USAGE;
    }
    if (!path || !out) {
        fprintf(stderr, "%s sample: usage: cmz sample MODEL.igs -o POINTS.xyz [--per-face N]\n", cmd_prog);
        return EXIT_USAGE;
    }
    loaded_model lm;
    int loaded = cmd_load(path, &lm);
    if (loaded != EXIT_OK)
        return loaded;
    /* write to a temporary file and rename, so a failure never leaves half an output */
    size_t tl = strlen(out) + 16;
    char *tmp = malloc(tl);
    cm_vec2 *uv = malloc((size_t)per_face * sizeof *uv);
    if (!tmp || !uv) {
        free(tmp);
        free(uv);
        model_free(&lm);
        fprintf(stderr, "%s: out of memory\n", cmd_prog);
        return EXIT_NOMEM;
    }
    snprintf(tmp, tl, "%s.tmp%ld", out, (long)getpid());
    FILE *fo = fopen(tmp, "w");
    if (!fo) {
        fprintf(stderr, "%s: %s: %s\n", cmd_prog, tmp, strerror(errno));
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
            char src[64];
            fprintf(stderr, "%s: warning: face %d (%s) got no sample points%s\n", cmd_prog, fi,
                    brep_face_source(&lm.brep.faces[fi], src, sizeof src), fd->uv ? "" : " (no parameter domain)");
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
        fprintf(stderr, "%s: writing %s failed: %s\n", cmd_prog, out, strerror(errno));
        remove(tmp);
        free(tmp);
        free(uv);
        model_free(&lm);
        return EXIT_IO;
    }
    if (!cmd_quiet)
        fprintf(stderr, "%s: %d points on %d faces written to %s%s\n", cmd_prog, total, lm.brep.nfaces - empty, out,
                empty ? " (some faces got none, see above)" : "");
    free(tmp);
    free(uv);
    int rc = empty ? EXIT_INPUT : EXIT_OK;
    model_free(&lm);
    return rc;
}
