/*
 * cmd_common.c - what every `cmz` command shares: its name on messages,
 * -q, the progress counter, the exit status of a failure, the common
 * arguments and the decoder's storage (see cmd.h).
 */
#define _POSIX_C_SOURCE 200809L
#include "cmd.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cm/cm_format.h"
#include "cm_report.h"

const char cmd_prog[] = "cmz";

int cmd_quiet;
int cmd_include_blanked;
int cmd_fold_instances;

void cmd_progress(const char *stage, int done, int total, void *ctx)
{
    (void)ctx;
    if (cmd_quiet || !isatty(2) || total < 200 || done % 50 != 0)
        return;
    fprintf(stderr, "\r%s: %s %d/%d ", cmd_prog, stage, done, total);
    if (done + 50 >= total)
        fprintf(stderr, "\r\033[K");
}

/* the failure's code, not its text, decides: every path that runs out of memory records CM_E_NOMEM */
int cmd_exit_for(cm_err code)
{
    return code == CM_E_NOMEM ? EXIT_NOMEM : code == CM_E_IO ? EXIT_IO : EXIT_INPUT;
}

/* the importer's own message names the file line; without one, the status says what failed */
int cmd_load(const char *path, loaded_model *lm)
{
    cm_status st;
    cm_status_init(&st);
    int flags = (cmd_include_blanked ? MODEL_LOAD_BLANKED : 0) | (cmd_fold_instances ? MODEL_LOAD_FOLD : 0);
    if (model_load_ex(path, lm, flags, cmd_progress, NULL, &st) == CM_OK)
        return EXIT_OK;
    if (lm->iges.err[0])
        fprintf(stderr, "%s: %s:%s%s\n", cmd_prog, path, lm->iges.err_line ? "" : " ", lm->iges.err);
    else
        cm_report_status(stderr, cmd_prog, path, &st);
    model_free(lm);
    return cmd_exit_for(st.code);
}

int cmd_common_arg(const char *cmd, const char *a, const char **path)
{
    if (strcmp(a, "-q") == 0) {
        cmd_quiet = 1;
        return 0;
    }
    if (strcmp(a, "--include-blanked") == 0) {
        cmd_include_blanked = 1;
        return 0;
    }
    if (a[0] == '-' && a[1]) {
        fprintf(stderr, "%s %s: unknown option %s (see cmz --help)\n", cmd_prog, cmd, a);
        return EXIT_USAGE;
    }
    if (*path) {
        fprintf(stderr, "%s %s: one file at a time (got %s and %s)\n", cmd_prog, cmd, *path, a);
        return EXIT_USAGE;
    }
    *path = a;
    return 0;
}

int cmd_parse_real(const char *opt, const char *text, double lo, double hi, double *out)
{
    char *end;
    double v = strtod(text, &end);
    if (*end || !(v >= lo && v <= hi)) {
        fprintf(stderr, "%s: %s wants a number in [%g, %g], not '%s'\n", cmd_prog, opt, lo, hi, text);
        return -1;
    }
    *out = v;
    return 0;
}

/* shared by decode and eval (one runs per process), so the program holds one decoder, not two */
static cm_decoder decoder;

cm_decoder *cmd_decoder(void)
{
    return &decoder;
}
