/*
 * cmd.h - the subcommands of `cmz` (one file each: cmd_info.c, cmd_sample.c,
 * cmd_encode.c, cmd_decode.c, cmd_eval.c; `cmz send` is send/send_cmd.c) and
 * the few helpers they share (cmd_common.c).  cmz_main.c only dispatches.
 *
 * Every entry takes the arguments after the command's name and returns the
 * process's exit status (README "exit status").
 */
#ifndef CMD_H
#define CMD_H

#include "cm/cm_decode.h"
#include "cm/cm_error.h"
#include "model_load.h"

/* the exit statuses of README's table; `cmz send` adds its own (send_cmd.c) */
enum { EXIT_OK = 0, EXIT_INPUT = 1, EXIT_USAGE = 2, EXIT_IO = 3, EXIT_NOMEM = 4 };

/** The workstation tool's version (`cmz --version`; with a CRC of the binary, a vault's encoder id). */
#define CMZ_VERSION "0.1.0"

/** The program's name, first on every message. */
extern const char cmd_prog[];

/** -q: no progress and no summary on stderr (set by cmd_common_arg, or a command's own parser). */
extern int cmd_quiet;
/** --include-blanked: import blanked (hidden) IGES entities too (cmd_load). */
extern int cmd_include_blanked;
/** Fold an assembly's placed copies out of the model (cmd_load; format 4.3 sends a part once). */
extern int cmd_fold_instances;

int cmd_info(int argc, char **argv);
int cmd_sample(int argc, char **argv);
int cmd_encode(int argc, char **argv);
int cmd_decode(int argc, char **argv);
int cmd_eval(int argc, char **argv);

/** What one model's encode measured, for a vault's summary (cmd_vault.c). */
typedef struct cmd_encode_summary {
    long cmz_bytes;
    int faces_sent, faces_placed; /* faces sent, and those placed again as copies of parts (format 4.3) */
    int kept;                     /* sent faces whose surface is kept */
    int left_out;                 /* faces left out */
    double max_err_mm, max_ratio; /* the worst face's rebuilt surface against its source: mm, and / its box */
} cmd_encode_summary;

/** When set, a successful `cmz encode` of one model fills it in. */
extern cmd_encode_summary *cmd_encode_summary_out;

/** A vault's options (`cmz encode FOLDER|--list FILE -o OUTFOLDER ...`). */
typedef struct cmd_vault_opts {
    const char *folder, *list, *out, *summary;
    int jobs, force;
    double timeout_s;       /* per model; 0: none */
    int shard_k, shard_n;   /* this task's share of the models: those whose index is k modulo n (n 0: all) */
} cmd_vault_opts;

/** Encode every model of a folder tree or a list, `pass` the encoding options given (cmd_vault.c). */
int cmd_vault(const cmd_vault_opts *vo, const char **pass, int npass);

/** Progress callback of the import and the encoder: a counter on stderr, only on a TTY and unless -q. */
void cmd_progress(const char *stage, int done, int total, void *ctx);

/** The exit status of a failure: out of memory, I/O, else the input. */
int cmd_exit_for(cm_err code);

/** Load the model at `path` (progress on a TTY): EXIT_OK, or the failure reported, lm freed and the
 *  exit status returned. */
int cmd_load(const char *path, loaded_model *lm);

/**
 * The arguments every command shares: -q, the one input file, and the refusal of anything else.
 * Returns 0 when `a` was taken, EXIT_USAGE (after saying why) otherwise.
 */
int cmd_common_arg(const char *cmd, const char *a, const char **path);

/** Parse option `opt`'s value `text` as a number in [lo, hi]; -1 (after saying why) if it is not one. */
int cmd_parse_real(const char *opt, const char *text, double lo, double hi, double *out);

/** A face method's name in reports and messages ("plane", "gregory", "keep"; "?" for no method). */

/**
 * The decoder of `cmz decode` and `cmz eval`: large, so static storage, as on the terminal; one per
 * process, since a process runs one command.
 */
cm_decoder *cmd_decoder(void);

#endif /* CMD_H */
