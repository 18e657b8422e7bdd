/*
 * cm_error.h - error codes and the caller-owned status.
 *
 * One X-macro is the source of the enum, the symbolic names and the human
 * texts, so they cannot drift apart.  Codes travel in the link protocol's
 * REFUSE, DONE and ABORT messages, so each carries its number: a new code
 * takes the next number at the end, a code is never renumbered, and the
 * number of a code that was dropped stays unused (18-21: timeout, USB,
 * serial and GPIO codes that nothing raised; the transports report
 * CM_E_IO with errno).  The last entry has the largest number.
 *
 * Three families are kept apart on purpose:
 *   bad input      (E_TRUNCATED, E_MAGIC, E_RANGE, E_KNOTS, E_NONFINITE, ...)
 *   no room        (E_NOSPACE: a caller buffer is too small)
 *   exceeds build  (E_LIMIT: valid input, but larger than this profile)
 */
#ifndef CM_ERROR_H
#define CM_ERROR_H

#include <stdint.h>

#define CM_ERRORS(X)                                                            \
    X(OK, 0, "ok")                                                              \
    X(E_ARG, 1, "invalid argument (a caller bug, not bad input)")               \
    X(E_LIMIT, 2, "exceeds a compile-time limit of this build")                 \
    X(E_NOSPACE, 3, "output buffer too small")                                  \
    X(E_TRUNCATED, 4, "input ends before the size its header declares")         \
    X(E_MAGIC, 5, "not a curvemesh file")                                       \
    X(E_VERSION, 6, "unsupported format version")                               \
    X(E_CRC, 7, "CRC mismatch: the data is corrupted")                          \
    X(E_RANGE, 8, "count or index out of range")                                \
    X(E_KNOTS, 9, "knot vector decreasing, too short or multiplicity > order")  \
    X(E_NONFINITE, 10, "NaN or infinity in input")                              \
    X(E_FORMAT, 11, "malformed data")                                           \
    X(E_SINGULAR, 12, "linear system is singular or ill-conditioned")           \
    X(E_DEGENERATE, 13, "degenerate geometry (zero-length vector or empty domain)") \
    X(E_CHECKSUM, 14, "rebuilt surface differs from the encoder's (checksum)")  \
    X(E_UNSUPPORTED, 15, "feature not supported by this build")                 \
    X(E_IGES, 16, "malformed IGES file")                                        \
    X(E_IO, 17, "I/O error")                                                    \
    X(E_PROTOCOL, 22, "link protocol error")                                    \
    X(E_NOMEM, 23, "out of memory")                                           \
    X(E_STEP, 24, "malformed STEP file")

#define CM_ERR_ENUM_(id, num, text) CM_##id = num,
typedef enum cm_err { CM_ERRORS(CM_ERR_ENUM_) CM_ERR_COUNT } cm_err;
#undef CM_ERR_ENUM_

#if defined(__GNUC__)
#  define CM_NODISCARD __attribute__((warn_unused_result))
#else
#  define CM_NODISCARD
#endif

/* A function run once per face, never per vertex (a method's net built from its record): gcc
   builds it for size (its "cold"), which leaves the terminal's aarch64 text room.  The G1FIT and
   NFILL builds: cmz-terminal 1.5 KB less, C1G0B0O's decode +0.2 % instructions, asmo's and Pieza1's
   a hair fewer. */
#if defined(__GNUC__)
#  define CM_ONCE_PER_FACE __attribute__((cold))
#else
#  define CM_ONCE_PER_FACE
#endif

/** Symbolic name, e.g. "CM_E_LIMIT" (for logs); "CM_E_UNKNOWN" if out of range. */
const char *cm_err_name(cm_err e);
/** 1 if `code` is the number of a code this build knows (numbers of dropped codes are not). */
int cm_err_defined(int code);
/** Human text (for the operator's screen); "unknown error" if out of range. */
const char *cm_strerror(cm_err e);

#define CM_NO_OFFSET UINT32_MAX /* status.offset when no byte position applies */
#define CM_NO_LIMIT 0xFFFFu     /* status.limit when no limit is involved */
#define CM_NO_FACE_INDEX UINT32_MAX /* status.face when the failure concerns no one face */

/*
 * Caller-owned detail of a failure.  The first (innermost) failure wins:
 * the cm_fail* helpers never overwrite a status that already holds an
 * error, so unwinding callers cannot replace the precise cause by a vague
 * one.  Every field but `code` is optional context.
 */
typedef struct cm_status {
    cm_err code;       /* CM_OK until the first failure */
    uint32_t offset;   /* byte offset in the input, or CM_NO_OFFSET */
    uint16_t limit;    /* cm_limit_id for CM_E_LIMIT, else CM_NO_LIMIT */
    uint32_t face;     /* the face (index in the file's FACE order) it concerns, or CM_NO_FACE_INDEX */
    uint64_t need;     /* CM_E_LIMIT / CM_E_NOSPACE: what the input needs */
    uint64_t have;     /* ... and what this build or buffer has */
    int sys_errno;     /* errno of a failed system call, or 0 */
    const char *where; /* static string: function or section that failed */
} cm_status;

/** Reset to CM_OK with no context. `st` may be NULL (then nothing happens). */
void cm_status_init(cm_status *st);

/** Record `code` at `where` (first failure wins); returns `code`. `st` may be NULL. */
cm_err cm_fail(cm_status *st, cm_err code, const char *where);

/** As cm_fail, with the byte offset of the failure in the input. */
cm_err cm_fail_at(cm_status *st, cm_err code, uint32_t offset, const char *where);

/** Record CM_E_LIMIT for limit `limit` (a cm_limit_id): input needs `need`, build has `have`. */
cm_err cm_fail_limit(cm_status *st, unsigned limit, uint64_t need, uint64_t have, const char *where);

/** Record CM_E_NOSPACE: a caller buffer of `have` elements, `need` required. */
cm_err cm_fail_nospace(cm_status *st, uint64_t need, uint64_t have, const char *where);

/**
 * Name the face a failure just recorded in `st` concerns, and where its data is in the input:
 * sets st->face (if not set yet) and, when the failure has no byte offset yet, st->offset =
 * `offset` (the face's record).  Nothing happens when st is NULL or holds no failure.
 */
void cm_status_at_face(cm_status *st, uint32_t face, uint32_t offset);

#endif /* CM_ERROR_H */
