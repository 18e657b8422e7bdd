/* record_io.c - see record_io.h */
#include "../unit/test_util.h"

#include <string.h>

#include "cm/cm_arith.h"
#include "cm/cm_sections.h"
#include "record_io.h"

cm_err record_read(cm_model *m, unsigned method, const uint8_t *buf, size_t len, record_flags flags, cm_face *F,
                   cm_method_fault *why, uint64_t *after)
{
    cm_ac_dec d;
    cm_face_ctx c;
    cm_face_ctx_init(&c);
    c.net_fit = flags.net_fit;
    c.hints = flags.hints;
    cm_ac_dec_init(&d, buf, len);
    memset(F, 0, sizeof *F);
    F->method = (uint8_t)method;
    memset(why, 0, sizeof *why);
    cm_err e = cm_method_read_record(cm_method_of(method), &d, &c, m, F, why);
    *after = cm_ac_dec_uint(&d, &c.count);
    return e;
}

void record_assert_refused(cm_model *m, unsigned method, const uint8_t *buf, size_t len, record_flags flags,
                           cm_err code, const char *what)
{
    cm_face F;
    cm_method_fault why;
    uint64_t after;
    cm_err e = record_read(m, method, buf, len, flags, &F, &why, &after);
    if (e != code || !why.what || strcmp(why.what, what) != 0)
        fail_msg("refused %s (%s), expected %s (%s)", cm_strerror(e), why.what ? why.what : "-", cm_strerror(code),
                 what);
}

void encode_for_minor(loaded_model *lm, int minor, encode_result *r)
{
    encode_opts o;
    encode_opts_default(&o);
    if (minor >= 0)
        encode_opts_for_format(&o, 4, minor);
    cm_status st;
    cm_status_init(&st);
    memset(r, 0, sizeof *r);
    assert_ok(encode_model(lm, &o, r, &st));
}
