/*
 * record_io.h - what the tests of a face method's record share: its bytes read back through the
 * method's reader as a reader of some format version would (the version's flags in the coder
 * context), and a model encoded for a given format 4 minor.
 */
#ifndef RECORD_IO_H
#define RECORD_IO_H

#include <stddef.h>
#include <stdint.h>

#include "cm/cm_method.h"
#include "encode/encode.h"
#include "model_load.h"

/** The reader's version flags (cm_face_ctx): format 4.2's net corrections, 4.13's corner hints. */
typedef struct record_flags {
    int net_fit, hints;
} record_flags;

/** buf[0..len) read as a face of `method`'s record into F (zeroed, its method set) against model m's
    pools, as a reader of `flags` would; *after: the uint coded after the record (the writers of these
    tests put 77 there), to see that the record was read whole. */
cm_err record_read(cm_model *m, unsigned method, const uint8_t *buf, size_t len, record_flags flags, cm_face *F,
                   cm_method_fault *why, uint64_t *after);

/** The same must be refused with `code`, the fault naming `what` (cmocka's failure otherwise). */
void record_assert_refused(cm_model *m, unsigned method, const uint8_t *buf, size_t len, record_flags flags,
                           cm_err code, const char *what);

/** lm encoded with the default options for format 4.`minor` (-1: the newest) into r (cmocka's failure
    when it is not). */
void encode_for_minor(loaded_model *lm, int minor, encode_result *r);

#endif /* RECORD_IO_H */
