/*
 * cmz_splice.h - a test's edit of a format 4.0-4.5 file (4.6's five sections are one stream, which
 * bytes cannot be spliced into): one section replaced by bytes the test coded
 * itself (a broken or hostile writer's records), the header's section length, the file's length
 * among the needs and both CRCs made right, so that the decoder reads the records.
 */
#ifndef CMZ_SPLICE_H
#define CMZ_SPLICE_H

#include <stddef.h>
#include <stdint.h>

#include "cm/cm_decode.h"
#include "encode/encode.h"

/** File r with its section `tag` (CM_SEC_EDGE, CM_SEC_FACE, ...) replaced by sec[0..slen) (malloc'd,
    *out_len its length), or NULL when r's header does not parse. */
uint8_t *cmz_with_section(const encode_result *r, int tag, const uint8_t *sec, size_t slen, size_t *out_len);

/** Decode b[0..len) into d as the terminal does (cm_dec_feed, then cm_dec_finish). */
cm_err cmz_decode(cm_decoder *d, const uint8_t *b, size_t len, cm_status *st);

/** r with its section `tag` replaced by sec[0..slen), decoded into d: NULL when refused with `code`
    and a reason that contains `cause`, else what happened instead (a static string). */
const char *cmz_section_refused(cm_decoder *d, const encode_result *r, int tag, const uint8_t *sec, size_t slen,
                                cm_err code, const char *cause);

/** The header alone (b[0..hl)), then the whole file b[0..n), decoded into d: NULL when both are refused
    with `want` at byte `at`, naming `where`, else what happened instead (a static string). */
const char *cmz_header_refused(cm_decoder *d, const uint8_t *b, size_t n, size_t hl, cm_err want, uint32_t at,
                               const char *where);

#endif
