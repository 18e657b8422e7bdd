/* cm_error.c - error names, texts and the first-failure-wins status. */
#include "cm/cm_error.h"

#include <stddef.h>
#include <stdint.h>

/*
 * The names and texts, each code's one member of a struct laid out once in read-only data, found by
 * its offset: no pointers, so nothing for the loader to relocate in a position-independent program
 * (two tables of 25 pointers, 42 of them relocated: 1 KB of the terminal's read-only 256 KiB).
 * Offset 0 (the struct's leading empty string) marks a number no code has (a dropped one).
 */
#define CM_ERR_NAME_MEMBER_(id, num, text) char id[sizeof("CM_" #id)];
#define CM_ERR_TEXT_MEMBER_(id, num, text) char id[sizeof(text)];
#define CM_ERR_NAME_INIT_(id, num, text) "CM_" #id,
#define CM_ERR_TEXT_INIT_(id, num, text) text,
#define CM_ERR_NAME_AT_(id, num, text) [num] = offsetof(struct err_name_pool, id),
#define CM_ERR_TEXT_AT_(id, num, text) [num] = offsetof(struct err_text_pool, id),
static const struct err_name_pool {
    char none[1];
    CM_ERRORS(CM_ERR_NAME_MEMBER_)
} err_names = {"", CM_ERRORS(CM_ERR_NAME_INIT_)};
static const struct err_text_pool {
    char none[1];
    CM_ERRORS(CM_ERR_TEXT_MEMBER_)
} err_texts = {"", CM_ERRORS(CM_ERR_TEXT_INIT_)};
static const uint16_t err_name_at[CM_ERR_COUNT] = {CM_ERRORS(CM_ERR_NAME_AT_)};
static const uint16_t err_text_at[CM_ERR_COUNT] = {CM_ERRORS(CM_ERR_TEXT_AT_)};
#undef CM_ERR_NAME_MEMBER_
#undef CM_ERR_TEXT_MEMBER_
#undef CM_ERR_NAME_INIT_
#undef CM_ERR_TEXT_INIT_
#undef CM_ERR_NAME_AT_
#undef CM_ERR_TEXT_AT_
_Static_assert(sizeof(struct err_name_pool) <= UINT16_MAX && sizeof(struct err_text_pool) <= UINT16_MAX,
               "error texts beyond a 16-bit offset");

int cm_err_defined(int code)
{
    return code >= 0 && code < (int)CM_ERR_COUNT && err_name_at[code] != 0;
}

const char *cm_err_name(cm_err e)
{
    return cm_err_defined((int)e) ? (const char *)&err_names + err_name_at[e] : "CM_E_UNKNOWN";
}

const char *cm_strerror(cm_err e)
{
    return cm_err_defined((int)e) ? (const char *)&err_texts + err_text_at[e] : "unknown error";
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
