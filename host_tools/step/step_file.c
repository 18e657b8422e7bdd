/* step_file.c - ISO 10303-21 sections, instances and parameters (see step_file.h). */
#define _POSIX_C_SOURCE 200809L
#include "step_file.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* Nesting of parameter lists one instance may use: exporters write 3 (a surface's control net
   inside its record); a deeper file is hostile and is refused instance by instance. */
#define STEP_MAX_DEPTH 32
/* Warnings kept (the rest are counted in warnings_dropped) */
#define STEP_MAX_WARNINGS 10000
/* Values one file may hold: 2^28 (a 4 GB file of single-character values); past it, refused. */
#define STEP_MAX_VALS (1 << 28)

/* ---- errors and warnings ---- */

__attribute__((format(printf, 3, 0))) static void vwarn(step_file *f, int line, const char *fmt, va_list ap)
{
    char msg[400];
    vsnprintf(msg, sizeof msg, fmt, ap);
    if (f->nwarn >= STEP_MAX_WARNINGS) { /* a garbled file would say the same thing a million times */
        f->warnings_dropped++;
        return;
    }
    if (f->nwarn == f->capwarn) {
        int cap = f->capwarn ? 2 * f->capwarn : 16;
        step_warning *w = realloc(f->warn, (size_t)cap * sizeof *w);
        if (!w)
            return; /* out of memory: the warning is lost, nothing else */
        f->warn = w;
        f->capwarn = cap;
    }
    char *copy = strdup(msg);
    if (!copy)
        return;
    f->warn[f->nwarn].line = line;
    f->warn[f->nwarn++].msg = copy;
}

void step_warn(step_file *f, int line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vwarn(f, line, fmt, ap);
    va_end(ap);
}

cm_err step_error(step_file *f, int line, const char *fmt, ...)
{
    if (f->err[0])
        return CM_E_STEP; /* the first error wins */
    char msg[440];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (line > 0)
        snprintf(f->err, sizeof f->err, "line %d: %s", line, msg);
    else
        snprintf(f->err, sizeof f->err, "%s", msg);
    f->err_line = line;
    return CM_E_STEP;
}

/* ---- the lexer ---- */

typedef enum tok_kind {
    T_EOF, T_BAD, T_LP, T_RP, T_COMMA, T_SEMI, T_EQ, T_KEY, T_REF, T_INT, T_REAL, T_STR, T_BIN, T_ENUM, T_DOLLAR,
    T_STAR
} tok_kind;

typedef struct lexer {
    step_file *f;
    const char *s; /* f->text */
    size_t pos, len;
    int line;
    /* the token just read */
    tok_kind k;
    size_t start, tlen; /* its text (a string's contents without the quotes) */
    double num;
    int ref;
    const char *why; /* T_BAD: what is wrong */
} lexer;

/* skip blanks and comments; an unterminated comment runs to the end */
static void skip_blank(lexer *L)
{
    for (;;) {
        while (L->pos < L->len && isspace((unsigned char)L->s[L->pos])) {
            if (L->s[L->pos] == '\n')
                L->line++;
            L->pos++;
        }
        if (L->pos + 1 < L->len && L->s[L->pos] == '/' && L->s[L->pos + 1] == '*') {
            L->pos += 2;
            while (L->pos < L->len && !(L->s[L->pos] == '*' && L->pos + 1 < L->len && L->s[L->pos + 1] == '/')) {
                if (L->s[L->pos] == '\n')
                    L->line++;
                L->pos++;
            }
            L->pos = L->pos + 2 <= L->len ? L->pos + 2 : L->len;
            continue;
        }
        return;
    }
}

static int is_key_char(int c)
{
    return isalnum(c) || c == '_' || c == '-';
}

static tok_kind lex(lexer *L)
{
    skip_blank(L);
    L->start = L->pos;
    L->tlen = 0;
    if (L->pos >= L->len)
        return L->k = T_EOF;
    const char *s = L->s;
    char c = s[L->pos];
    switch (c) {
    case '(': L->pos++; return L->k = T_LP;
    case ')': L->pos++; return L->k = T_RP;
    case ',': L->pos++; return L->k = T_COMMA;
    case ';': L->pos++; return L->k = T_SEMI;
    case '=': L->pos++; return L->k = T_EQ;
    case '$': L->pos++; return L->k = T_DOLLAR;
    case '*': L->pos++; return L->k = T_STAR;
    case '\'': {
        /* '' inside is a quote; a backslash escape never contains a quote */
        size_t i = ++L->pos;
        for (;;) {
            if (i >= L->len) {
                L->why = "a string runs to the end of the file";
                return L->k = T_BAD;
            }
            if (s[i] == '\n')
                L->line++;
            if (s[i] == '\'') {
                if (i + 1 < L->len && s[i + 1] == '\'') {
                    i += 2;
                    continue;
                }
                break;
            }
            i++;
        }
        L->start = L->pos;
        L->tlen = i - L->pos;
        L->pos = i + 1;
        return L->k = T_STR;
    }
    case '"': {
        size_t i = ++L->pos;
        while (i < L->len && s[i] != '"')
            i++;
        if (i >= L->len) {
            L->why = "a binary value runs to the end of the file";
            return L->k = T_BAD;
        }
        L->start = L->pos;
        L->tlen = i - L->pos;
        L->pos = i + 1;
        return L->k = T_BIN;
    }
    case '.': {
        size_t i = L->pos + 1;
        while (i < L->len && (isalnum((unsigned char)s[i]) || s[i] == '_'))
            i++;
        if (i < L->len && s[i] == '.' && i > L->pos + 1) {
            L->start = L->pos + 1;
            L->tlen = i - L->pos - 1;
            L->pos = i + 1;
            return L->k = T_ENUM;
        }
        break; /* a number such as .5 (not Part 21, but harmless) */
    }
    case '#': {
        size_t i = L->pos + 1;
        long long v = 0;
        while (i < L->len && isdigit((unsigned char)s[i]) && v <= 2147483647LL)
            v = v * 10 + (s[i++] - '0');
        if (i == L->pos + 1 || v > 2147483647LL || v < 1) {
            L->why = "an instance name (#n) is not a number from 1 to 2147483647";
            L->pos = i; /* past what was read: every token moves on */
            return L->k = T_BAD;
        }
        L->ref = (int)v;
        L->pos = i;
        return L->k = T_REF;
    }
    default:
        break;
    }
    if (isdigit((unsigned char)c) || c == '-' || c == '+' || c == '.') {
        char buf[64];
        size_t i = L->pos, n = 0;
        int real = 0;
        while (i < L->len && n + 1 < sizeof buf &&
               (isdigit((unsigned char)s[i]) || strchr("+-.eEdD", s[i]) != NULL)) {
            char ch = s[i++];
            if (ch == '.' || ch == 'e' || ch == 'E' || ch == 'd' || ch == 'D')
                real = 1;
            buf[n++] = (ch == 'd' || ch == 'D') ? 'E' : ch;
        }
        buf[n] = 0;
        char *end;
        errno = 0;
        double v = strtod(buf, &end);
        if (end == buf || *end != 0) {
            L->why = "a malformed number";
            L->pos = i;
            return L->k = T_BAD;
        }
        L->num = v;
        L->pos = i;
        return L->k = real ? T_REAL : T_INT;
    }
    if (isalpha((unsigned char)c) || c == '_' || c == '!') {
        size_t i = L->pos + 1;
        while (i < L->len && is_key_char((unsigned char)s[i]))
            i++;
        L->tlen = i - L->pos;
        L->pos = i;
        return L->k = T_KEY;
    }
    L->why = "an unexpected character";
    L->pos++;
    return L->k = T_BAD;
}

static int key_is(const lexer *L, const char *kw)
{
    return L->k == T_KEY && L->tlen == strlen(kw) && strncasecmp(L->s + L->start, kw, L->tlen) == 0;
}

/* ---- storage ---- */

static int grow(void **p, int *cap, int need, size_t elem)
{
    if (need <= *cap)
        return 0;
    int nc = *cap ? *cap : 256;
    while (nc < need) {
        if (nc > (1 << 29))
            return -1;
        nc *= 2;
    }
    void *q = realloc(*p, (size_t)nc * elem);
    if (!q)
        return -1;
    *p = q;
    *cap = nc;
    return 0;
}

static int push_val(step_file *f, step_kind k, const lexer *L)
{
    if (f->nvals >= STEP_MAX_VALS || grow((void **)&f->vals, &f->capvals, f->nvals + 1, sizeof *f->vals))
        return -1;
    step_val *v = &f->vals[f->nvals];
    memset(v, 0, sizeof *v);
    v->kind = (unsigned char)k;
    v->size = 1;
    if (L) {
        v->num = L->num;
        v->ref = L->ref;
        v->text = (int)L->start;
        v->len = (int)L->tlen;
    }
    return f->nvals++;
}

/*
 * One parameter list, the lexer standing on its '(' (already read).  Lists and typed values nest
 * by an explicit stack (STEP_MAX_DEPTH), not by recursion.  Returns the list's value index, -1
 * for a syntax error (L->why says what), -2 when out of memory.
 */
static int parse_list(step_file *f, lexer *L)
{
    int stack[STEP_MAX_DEPTH];
    int depth = 0;
    int root = push_val(f, STEP_LIST, NULL);
    if (root < 0)
        return -2;
    stack[depth++] = root;
    int expect_value = 1; /* after '(' or ',' */
    while (depth > 0) {
        tok_kind k = lex(L);
        int parent = stack[depth - 1];
        if (k == T_RP) {
            if (expect_value && f->vals[parent].n > 0) {
                L->why = "a value is missing before ')'";
                return -1;
            }
            f->vals[parent].size = f->nvals - parent;
            depth--;
            expect_value = 0;
            /* a typed value closes with its own ')' */
            continue;
        }
        if (k == T_COMMA) {
            if (expect_value || f->vals[parent].kind == STEP_TYPED) {
                L->why = "a value is missing before ','";
                return -1;
            }
            expect_value = 1;
            continue;
        }
        if (!expect_value) {
            L->why = k == T_SEMI ? "';' before the parameter list is closed" : "',' or ')' expected between values";
            return -1;
        }
        if (f->vals[parent].kind == STEP_TYPED && f->vals[parent].n >= 1) {
            L->why = "a typed value holds more than one value";
            return -1;
        }
        int idx;
        switch (k) {
        case T_LP:
        case T_KEY: {
            if (depth >= STEP_MAX_DEPTH) {
                L->why = "parameter lists nest deeper than 32";
                return -1;
            }
            lexer key = *L;
            if (k == T_KEY && lex(L) != T_LP) {
                L->why = "a keyword not followed by '('";
                return -1;
            }
            idx = push_val(f, k == T_LP ? STEP_LIST : STEP_TYPED, k == T_KEY ? &key : NULL);
            if (idx < 0)
                return -2;
            f->vals[parent].n++;
            stack[depth++] = idx;
            expect_value = 1;
            continue;
        }
        case T_REF: idx = push_val(f, STEP_REF, L); break;
        case T_INT: idx = push_val(f, STEP_INT, L); break;
        case T_REAL: idx = push_val(f, STEP_REAL, L); break;
        case T_STR: idx = push_val(f, STEP_STR, L); break;
        case T_BIN: idx = push_val(f, STEP_BINARY, L); break;
        case T_ENUM: idx = push_val(f, STEP_ENUM, L); break;
        case T_DOLLAR: idx = push_val(f, STEP_UNSET, NULL); break;
        case T_STAR: idx = push_val(f, STEP_DERIVED, NULL); break;
        case T_EOF: L->why = "the file ends inside a parameter list"; return -1;
        case T_BAD: return -1;
        default: L->why = "an unexpected token in a parameter list"; return -1;
        }
        if (idx < 0)
            return -2;
        f->vals[parent].n++;
        expect_value = 0;
    }
    return root;
}

/* skip to just after the next ';' (strings and comments respected): resynchronise after an error */
static void skip_instance(lexer *L)
{
    while (L->k != T_SEMI && L->k != T_EOF) {
        if (lex(L) == T_BAD && L->pos >= L->len)
            return;
    }
}

/*
 * One instance after its `#id =` (or a HEADER entity from its keyword, id 0): a simple record
 * KEY(...) or a complex one (KEY(...) KEY(...) ...), then ';'.  0 on success, -1 syntax error
 * (L->why), -2 out of memory.
 */
static int parse_record(step_file *f, lexer *L, step_entity *e)
{
    int complex_ = L->k == T_LP;
    e->first_part = f->nparts;
    e->nparts = 0;
    if (complex_)
        lex(L);
    for (;;) {
        if (L->k != T_KEY) {
            L->why = complex_ ? "an entity name or ')' expected in a complex instance" : "an entity name expected";
            return -1;
        }
        if (grow((void **)&f->parts, &f->capparts, f->nparts + 1, sizeof *f->parts))
            return -2;
        step_part *p = &f->parts[f->nparts];
        p->name = (int)L->start;
        p->name_len = (int)L->tlen;
        if (lex(L) != T_LP) {
            L->why = "an entity name not followed by '('";
            return -1;
        }
        int r = parse_list(f, L);
        if (r < 0)
            return r;
        f->parts[f->nparts].params = r;
        f->nparts++;
        e->nparts++;
        lex(L);
        if (!complex_)
            break;
        if (L->k == T_RP) {
            lex(L);
            break;
        }
    }
    if (L->k != T_SEMI) {
        L->why = "';' expected after the instance";
        return -1;
    }
    return 0;
}

typedef struct id_pair {
    int id, idx;
} id_pair;

static int cmp_pair(const void *a, const void *b)
{
    const id_pair *x = a, *y = b;
    if (x->id != y->id)
        return x->id < y->id ? -1 : 1;
    return (x->idx > y->idx) - (x->idx < y->idx);
}

static void header_strings(step_file *f)
{
    for (int i = 0; i < f->nhdr; i++) {
        const step_entity *e = &f->hdr[i];
        const step_val *p = step_params(f, e, NULL);
        if (step_is(f, e, "FILE_SCHEMA")) {
            const step_val *l = step_item(p, 0);
            step_str(f, step_item(l, 0), f->schema, sizeof f->schema);
        } else if (step_is(f, e, "FILE_NAME")) {
            step_str(f, step_item(p, 5), f->system, sizeof f->system);
            if (!f->system[0])
                step_str(f, step_item(p, 4), f->system, sizeof f->system);
        }
    }
}

int step_sniff(const char *data, size_t len)
{
    size_t i = 0;
    if (len >= 3 && (unsigned char)data[0] == 0xEF && (unsigned char)data[1] == 0xBB && (unsigned char)data[2] == 0xBF)
        i = 3;
    for (;;) {
        while (i < len && isspace((unsigned char)data[i]))
            i++;
        if (i + 1 < len && data[i] == '/' && data[i + 1] == '*') {
            const char *end = NULL;
            for (size_t j = i + 2; j + 1 < len; j++)
                if (data[j] == '*' && data[j + 1] == '/') {
                    end = data + j;
                    break;
                }
            if (!end)
                return 0;
            i = (size_t)(end - data) + 2;
            continue;
        }
        break;
    }
    return len - i >= 12 && strncasecmp(data + i, "ISO-10303-21", 12) == 0;
}

static void item_cache_clear(void);

cm_err step_parse(const char *data, size_t len, step_file *f, cm_status *st)
{
    item_cache_clear();
    memset(f, 0, sizeof *f);
    if (len > (size_t)0x7fffffff - 1)
        return cm_fail(st, step_error(f, 0, "the file is larger than 2 GB"), "step");
    f->text = malloc(len + 1);
    if (!f->text)
        return step_error(f, 0, "out of memory (%zu bytes of text)", len), cm_fail(st, CM_E_NOMEM, "out of memory");
    memcpy(f->text, data, len);
    f->text[len] = 0;
    f->len = len;
    if (!step_sniff(data, len))
        return cm_fail(st, step_error(f, 1, "not a STEP file: it does not begin with ISO-10303-21;"), "step");
    lexer L = {f, f->text, 0, len, 1, T_EOF, 0, 0, 0, 0, NULL};
    if (len >= 3 && (unsigned char)data[0] == 0xEF)
        L.pos = 3;
    lex(&L); /* ISO-10303-21 */
    if (lex(&L) != T_SEMI)
        return cm_fail(st, step_error(f, L.line, "';' expected after ISO-10303-21"), "step");
    enum { OUTSIDE, HEADER, DATA } sec = OUTSIDE;
    int saw_data = 0, saw_end = 0;
    for (lex(&L); L.k != T_EOF; lex(&L)) {
        int line = L.line;
        if (sec == OUTSIDE) {
            if (key_is(&L, "HEADER")) {
                if (lex(&L) != T_SEMI)
                    return cm_fail(st, step_error(f, L.line, "';' expected after HEADER"), "step");
                sec = HEADER;
            } else if (key_is(&L, "DATA")) {
                if (lex(&L) == T_LP) { /* edition 3: DATA('name', ('schema')); */
                    int r = parse_list(f, &L);
                    if (r == -2)
                        return step_error(f, line, "out of memory"), cm_fail(st, CM_E_NOMEM, "out of memory");
                    if (r < 0)
                        return cm_fail(st, step_error(f, L.line, "DATA: %s", L.why), "step");
                    lex(&L);
                }
                if (L.k != T_SEMI)
                    return cm_fail(st, step_error(f, L.line, "';' expected after DATA"), "step");
                sec = DATA;
                saw_data = 1;
            } else if (key_is(&L, "END-ISO-10303-21")) {
                saw_end = 1;
                break;
            } else {
                return cm_fail(st, step_error(f, line, "HEADER, DATA or END-ISO-10303-21 expected"), "step");
            }
            continue;
        }
        if (key_is(&L, "ENDSEC")) {
            if (lex(&L) != T_SEMI)
                return cm_fail(st, step_error(f, L.line, "';' expected after ENDSEC"), "step");
            sec = OUTSIDE;
            continue;
        }
        step_entity e;
        memset(&e, 0, sizeof e);
        e.line = line;
        int nv = f->nvals, np = f->nparts, r;
        if (sec == HEADER) {
            r = parse_record(f, &L, &e);
        } else if (L.k == T_REF) {
            e.id = L.ref;
            if (lex(&L) != T_EQ) {
                L.why = "'=' expected after the instance name";
                r = -1;
            } else {
                lex(&L);
                r = parse_record(f, &L, &e);
            }
        } else {
            L.why = "an instance (#n = ...;) or ENDSEC expected";
            r = -1;
        }
        if (r == -2)
            return step_error(f, line, "out of memory"), cm_fail(st, CM_E_NOMEM, "out of memory");
        if (r < 0) {
            /* one unreadable instance is left out; the model may not need it */
            if (e.id)
                step_warn(f, line, "#%d: cannot be read (%s); left out", e.id, L.why);
            else
                step_warn(f, line, "cannot be read (%s); skipped", L.why);
            f->bad_instances++;
            f->nvals = nv;
            f->nparts = np;
            skip_instance(&L);
            continue;
        }
        step_entity **list = sec == HEADER ? &f->hdr : &f->ents;
        int *n = sec == HEADER ? &f->nhdr : &f->nents, *cap = sec == HEADER ? &f->caphdr : &f->capents;
        if (grow((void **)list, cap, *n + 1, sizeof **list))
            return step_error(f, line, "out of memory"), cm_fail(st, CM_E_NOMEM, "out of memory");
        (*list)[(*n)++] = e;
    }
    f->nlines = L.line;
    if (!saw_data)
        return cm_fail(st, step_error(f, L.line, "no DATA section"), "step");
    if (!saw_end)
        step_warn(f, L.line, "the file ends without END-ISO-10303-21; (truncated?)");
    if (f->nents == 0)
        return cm_fail(st, step_error(f, L.line, "the DATA section holds no readable instance"), "step");
    f->by_id = malloc((size_t)f->nents * sizeof *f->by_id);
    if (!f->by_id)
        return step_error(f, 0, "out of memory"), cm_fail(st, CM_E_NOMEM, "out of memory");
    int sorted = 1;
    for (int i = 0; i < f->nents; i++) {
        f->by_id[i] = i;
        if (i && f->ents[i].id <= f->ents[i - 1].id)
            sorted = 0;
    }
    if (!sorted) { /* exporters write ascending names; others are sorted once (ties in file order) */
        id_pair *pr = malloc((size_t)f->nents * sizeof *pr);
        if (!pr)
            return step_error(f, 0, "out of memory"), cm_fail(st, CM_E_NOMEM, "out of memory");
        for (int i = 0; i < f->nents; i++)
            pr[i] = (id_pair){f->ents[i].id, i};
        qsort(pr, (size_t)f->nents, sizeof *pr, cmp_pair);
        for (int i = 0; i < f->nents; i++)
            f->by_id[i] = pr[i].idx;
        free(pr);
    }
    /* a name used twice: the first instance keeps it (later look-ups find that one) */
    int w = 0;
    for (int i = 0; i < f->nents; i++) {
        if (w && f->ents[f->by_id[w - 1]].id == f->ents[f->by_id[i]].id) {
            const step_entity *d = &f->ents[f->by_id[i]];
            step_warn(f, d->line, "#%d is defined twice (first at line %d); this one is ignored", d->id,
                      f->ents[f->by_id[w - 1]].line);
            continue;
        }
        f->by_id[w++] = f->by_id[i];
    }
    f->nents_indexed = w;
    header_strings(f);
    return CM_OK;
}

cm_err step_read(const char *path, step_file *f, cm_status *st)
{
    memset(f, 0, sizeof *f);
    FILE *fp = fopen(path, "rb");
    cm_err e = CM_OK;
    char *buf = NULL;
    size_t len = 0, cap = 0;
    if (!fp) {
        step_error(f, 0, "cannot open: %s", strerror(errno));
        e = cm_fail(st, CM_E_IO, "open");
    } else {
        for (;;) {
            if (len + 65536 > cap) {
                size_t nc = cap ? 2 * cap : 1 << 20;
                char *q = realloc(buf, nc);
                if (!q) {
                    e = cm_fail(st, CM_E_NOMEM, "out of memory");
                    step_error(f, 0, "out of memory reading the file");
                    break;
                }
                buf = q;
                cap = nc;
            }
            size_t got = fread(buf + len, 1, cap - len, fp);
            len += got;
            if (got == 0)
                break;
        }
        if (e == CM_OK && ferror(fp))
            e = cm_fail(st, CM_E_IO, "read"), step_error(f, 0, "read error");
        fclose(fp);
    }
    if (e == CM_OK)
        e = step_parse(buf, len, f, st);
    free(buf);
    free(f->path);
    f->path = strdup(path); /* NULL when out of memory: messages then name no file */
    return e;
}

void step_free(step_file *f)
{
    item_cache_clear();
    free(f->path);
    free(f->text);
    free(f->ents);
    free(f->hdr);
    free(f->parts);
    free(f->vals);
    free(f->by_id);
    for (int i = 0; i < f->nwarn; i++)
        free(f->warn[i].msg);
    free(f->warn);
    memset(f, 0, sizeof *f);
}

/* ---- access ---- */

const step_entity *step_by_id(const step_file *f, int id)
{
    int lo = 0, hi = f->nents_indexed - 1;
    while (lo <= hi) {
        int mid = lo + (hi - lo) / 2;
        int v = f->ents[f->by_id[mid]].id;
        if (v == id)
            return &f->ents[f->by_id[mid]];
        if (v < id)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return NULL;
}

static int name_eq(const step_file *f, int off, int len, const char *name)
{
    return (size_t)len == strlen(name) && strncasecmp(f->text + off, name, (size_t)len) == 0;
}

int step_is(const step_file *f, const step_entity *e, const char *type)
{
    return e && step_params(f, e, type) != NULL;
}

const step_val *step_params(const step_file *f, const step_entity *e, const char *type)
{
    if (!e)
        return NULL;
    for (int i = 0; i < e->nparts; i++) {
        const step_part *p = &f->parts[e->first_part + i];
        if (!type || name_eq(f, p->name, p->name_len, type))
            return &f->vals[p->params];
    }
    return NULL;
}

const char *step_type(const step_file *f, const step_entity *e, char *buf, size_t cap)
{
    if (!e || e->nparts == 0 || cap == 0) {
        if (cap)
            buf[0] = 0;
        return buf;
    }
    const step_part *p = &f->parts[e->first_part];
    snprintf(buf, cap, "%.*s", p->name_len, f->text + p->name);
    return buf;
}

/*
 * Item i of a list is found by walking its items (their subtree sizes), i steps.  Loops go through
 * a list in order, so the last item found of the last few lists is remembered: the next one is one
 * step on, and a loop over n items costs n steps, not n^2 / 2 (a shell listing 400 000 faces).
 */
#define STEP_ITEM_CACHE 4
static _Thread_local struct {
    const step_val *list, *item;
    int i;
} item_cache[STEP_ITEM_CACHE];
static _Thread_local int item_cache_next;

/* a file's values are freed or moved: what was remembered of them goes */
static void item_cache_clear(void)
{
    memset(item_cache, 0, sizeof item_cache);
    item_cache_next = 0;
}

const step_val *step_item(const step_val *list, int i)
{
    if (!list || (list->kind != STEP_LIST && list->kind != STEP_TYPED) || i < 0 || i >= list->n)
        return NULL;
    const step_val *c = list + 1;
    int k = 0;
    for (int j = 0; j < STEP_ITEM_CACHE; j++)
        if (item_cache[j].list == list && item_cache[j].i <= i && item_cache[j].i >= k) {
            c = item_cache[j].item;
            k = item_cache[j].i;
        }
    for (; k < i; k++)
        c += c->size;
    int slot = -1;
    for (int j = 0; j < STEP_ITEM_CACHE && slot < 0; j++)
        if (item_cache[j].list == list)
            slot = j;
    if (slot < 0) {
        slot = item_cache_next;
        item_cache_next = (item_cache_next + 1) % STEP_ITEM_CACHE;
    }
    item_cache[slot].list = list;
    item_cache[slot].item = c;
    item_cache[slot].i = i;
    return c;
}

const step_val *step_untyped(const step_val *v)
{
    for (int k = 0; v && v->kind == STEP_TYPED && k < STEP_MAX_DEPTH; k++)
        v = v->n == 1 ? v + 1 : NULL;
    return v;
}

int step_val_is(const step_file *f, const step_val *v, const char *name)
{
    return v && (v->kind == STEP_ENUM || v->kind == STEP_TYPED) && name_eq(f, v->text, v->len, name);
}

int step_num(const step_val *v, double *out)
{
    v = step_untyped(v);
    if (!v || (v->kind != STEP_INT && v->kind != STEP_REAL) || !isfinite(v->num))
        return -1;
    *out = v->num;
    return 0;
}

const step_entity *step_ref(const step_file *f, const step_val *v)
{
    return v && v->kind == STEP_REF ? step_by_id(f, v->ref) : NULL;
}

static int hexval(char c)
{
    return isdigit((unsigned char)c) ? c - '0' : (c >= 'A' && c <= 'F') ? c - 'A' + 10 : (c >= 'a' && c <= 'f') ? c - 'a' + 10 : -1;
}

const char *step_str(const step_file *f, const step_val *v, char *buf, size_t cap)
{
    if (cap == 0)
        return buf;
    buf[0] = 0;
    if (!v || v->kind != STEP_STR)
        return buf;
    const char *s = f->text + v->text;
    size_t n = 0;
    for (int i = 0; i < v->len && n + 1 < cap;) {
        if (s[i] == '\'' && i + 1 < v->len && s[i + 1] == '\'') {
            buf[n++] = '\'';
            i += 2;
        } else if (s[i] == '\\' && i + 4 < v->len && s[i + 1] == 'X' && s[i + 2] == '\\' && hexval(s[i + 3]) >= 0 &&
                   hexval(s[i + 4]) >= 0) {
            int c = hexval(s[i + 3]) * 16 + hexval(s[i + 4]);
            buf[n++] = (char)(c >= 32 && c < 127 ? c : '?'); /* ISO 8859-1 upper half: shown as '?' */
            i += 5;
        } else if (s[i] == '\\' && i + 1 < v->len && s[i + 1] == '\\') {
            buf[n++] = '\\';
            i += 2;
        } else {
            buf[n++] = s[i] == '\n' || s[i] == '\r' ? ' ' : s[i];
            i++;
        }
    }
    buf[n] = 0;
    return buf;
}
