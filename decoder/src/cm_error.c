/* cm_error.c - error names, texts and the first-failure-wins status. */
#include "cm/cm_error.h"

#include <stddef.h>

/* indexed by number; a number no code has (a dropped one) stays NULL */
#define CM_ERR_NAME_(id, num, text) [num] = "CM_" #id,
#define CM_ERR_TEXT_(id, num, text) [num] = text,
static const char *const err_names[CM_ERR_COUNT] = {CM_ERRORS(CM_ERR_NAME_)};
static const char *const err_texts[CM_ERR_COUNT] = {CM_ERRORS(CM_ERR_TEXT_)};
#undef CM_ERR_NAME_
#undef CM_ERR_TEXT_

int cm_err_defined(int code)
{
    return code >= 0 && code < (int)CM_ERR_COUNT && err_names[code] != NULL;
}

const char *cm_err_name(cm_err e)
{
    return cm_err_defined((int)e) ? err_names[e] : "CM_E_UNKNOWN";
}

const char *cm_strerror(cm_err e)
{
    return cm_err_defined((int)e) ? err_texts[e] : "unknown error";
}

void cm_status_init(cm_status *st)
{
    if (st == NULL)
        return;
    st->code = CM_OK;
    st->offset = CM_NO_OFFSET;
    st->limit = CM_NO_LIMIT;
    st->face = CM_NO_FACE_INDEX;
    st->need = 0;
    st->have = 0;
    st->sys_errno = 0;
    st->where = NULL;
}

/* Returns nonzero if `st` may take a new failure (it is there and still OK). */
static int status_open(const cm_status *st)
{
    return st != NULL && st->code == CM_OK;
}

cm_err cm_fail(cm_status *st, cm_err code, const char *where)
{
    if (status_open(st)) {
        st->code = code;
        st->where = where;
    }
    return code;
}

cm_err cm_fail_at(cm_status *st, cm_err code, uint32_t offset, const char *where)
{
    if (status_open(st)) {
        st->code = code;
        st->offset = offset;
        st->where = where;
    }
    return code;
}

cm_err cm_fail_limit(cm_status *st, unsigned limit, uint64_t need, uint64_t have, const char *where)
{
    if (status_open(st)) {
        st->code = CM_E_LIMIT;
        st->limit = (uint16_t)limit;
        st->need = need;
        st->have = have;
        st->where = where;
    }
    return CM_E_LIMIT;
}

cm_err cm_fail_nospace(cm_status *st, uint64_t need, uint64_t have, const char *where)
{
    if (status_open(st)) {
        st->code = CM_E_NOSPACE;
        st->need = need;
        st->have = have;
        st->where = where;
    }
    return CM_E_NOSPACE;
}

void cm_status_at_face(cm_status *st, uint32_t face, uint32_t offset)
{
    if (st == NULL || st->code == CM_OK)
        return;
    if (st->face == CM_NO_FACE_INDEX)
        st->face = face;
    if (st->offset == CM_NO_OFFSET)
        st->offset = offset;
}
