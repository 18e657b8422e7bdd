/*
 * cm_report.h - the one place that turns limits and statuses into text for
 * people: `--limits` tables, error lines on stderr, README tables.
 * (The decoder never prints; binaries call these.)
 */
#ifndef CM_REPORT_H
#define CM_REPORT_H

#include <stdint.h>
#include <stdio.h>

#include "cm/cm_error.h"

/**
 * Faces by method, in the method table's order: "90 plane, 1 gregory, 69 kept" (key_value 0) or
 * "plane=90 gregory=1 kept=69" (1, for logs).  count[] is indexed by the method's number.
 */
char *cm_report_method_counts(char *buf, size_t cap, const uint32_t *count, int key_value);

/** The limits table of this build (profile name, then one row per limit). */
void cm_report_limits(FILE *f);

/** A program's own static storage, beside its decode state: one row of `--limits` each. */
typedef struct cm_ram_part {
    const char *name, *doc;
    unsigned long long bytes;
} cm_ram_part;

/** The program's own static storage, part by part, and their sum against CM_PROGRAM_STATIC_BUDGET
 *  (make check-ram measures the whole program). */
void cm_report_program_ram(FILE *f, const cm_ram_part *part, size_t n);

/** The limits table as a Markdown table (for README). */
void cm_report_limits_markdown(FILE *f);

/** The error codes as a Markdown table: code, name, meaning (for README). */
void cm_report_errors_markdown(FILE *f);

/**
 * One line describing a failure, e.g.
 * "cmz: part.cmz: byte 42: exceeds a compile-time limit of this build
 *  (CM_E_LIMIT): the model needs MAX_FACES=20000, this build (profile
 *  terminal) has 16384".
 * @param prog     program name (may be NULL)
 * @param subject  file or device concerned (may be NULL)
 */
void cm_report_status(FILE *f, const char *prog, const char *subject, const cm_status *st);

/** A failed system call at `where`: CM_E_IO, with errno kept in st->sys_errno (the first failure
 *  wins, as cm_fail's).  Returns CM_E_IO. */
cm_err cm_fail_errno(cm_status *st, const char *where);

/** Format the same text into buf (always NUL-terminated); returns buf. */
char *cm_format_status(char *buf, size_t cap, const cm_status *st);

#endif /* CM_REPORT_H */
