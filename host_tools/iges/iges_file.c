/* iges_file.c - IGES sections, Global, Directory and Parameter Data (see iges_file.h). */
#define _POSIX_C_SOURCE 200809L
#include "iges_file.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* one physical line of the file */
typedef struct line {
    const char *s;
    int len;   /* without the line end */
    int no;    /* 1-based file line number */
} line;

typedef struct reader {
    iges_file *f;
    line *lines;
    int nlines;
    int *sec[5];  /* indices into lines[] per section S G D P T */
    int nsec[5];
} reader;

enum { SEC_S, SEC_G, SEC_D, SEC_P, SEC_T };
static const char sec_letters[] = "SGDPT";

/* ---- errors and warnings ---- */

__attribute__((format(printf, 3, 0))) static void set_error(iges_file *f, int line_no, const char *fmt, va_list ap)
{
    if (f->err[0] != 0)
        return; /* the first (innermost) error wins */
    char msg[400];
    vsnprintf(msg, sizeof msg, fmt, ap);
    if (line_no > 0)
        snprintf(f->err, sizeof f->err, "line %d: %s", line_no, msg);
    else
        snprintf(f->err, sizeof f->err, "%s", msg);
    f->err_line = line_no;
}

cm_err iges_error(iges_file *f, int line_no, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    set_error(f, line_no, fmt, ap);
    va_end(ap);
    return CM_E_IGES;
}

cm_err iges_nomem(iges_file *f, int line_no, const char *fmt, ...)
{
    char what[300];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    iges_error(f, line_no, "out of memory (%s)", what);
    return CM_E_NOMEM;
}

void iges_warn(iges_file *f, int line_no, const char *fmt, ...)
{
    char msg[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (f->nwarn == f->capwarn) {
        int cap = f->capwarn ? 2 * f->capwarn : 16;
        iges_warning *w = realloc(f->warn, (size_t)cap * sizeof *w);
        if (!w)
            return; /* out of memory: the warning is lost, nothing else */
        f->warn = w;
        f->capwarn = cap;
    }
    char *copy = strdup(msg);
    if (!copy)
        return;
    f->warn[f->nwarn].line = line_no;
    f->warn[f->nwarn].msg = copy;
    f->nwarn++;
}

cm_err iges_entity_error(iges_file *f, const iges_entity *e, const char *fmt, ...)
{
    char msg[300];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return iges_error(f, e->pd_line, "entity %d (%s, DE %d): %s", e->type, iges_type_name(e->type), e->de, msg);
}

/* ---- small parsers ---- */

/* integer in a fixed 8-column Directory field; blank = 0; *ok = 0 if not an integer */
static int de_field(const line *l, int field, int *ok)
{
    int start = (field - 1) * 8;
    char buf[9];
    int k = 0;
    for (int i = start; i < start + 8; i++) {
        char c = i < l->len ? l->s[i] : ' ';
        if (c != ' ')
            buf[k++] = c;
    }
    buf[k] = 0;
    if (k == 0)
        return 0;
    char *end;
    errno = 0;
    long v = strtol(buf, &end, 10);
    if (*end != 0 || errno || v > 99999999 || v < -9999999) {
        *ok = 0;
        return 0;
    }
    return (int)v;
}

/* sequence number in columns 74-80 */
static int seq_field(const line *l)
{
    int v = 0, any = 0;
    for (int i = 73; i < 80 && i < l->len; i++) {
        char c = l->s[i];
        if (c >= '0' && c <= '9') {
            v = v * 10 + (c - '0');
            any = 1;
        }
    }
    return any ? v : -1;
}

/* strtod on an IGES number: blanks ignored, D exponent accepted; 0 if not a number */
static int parse_number(const char *s, int n, double *out)
{
    char buf[96];
    int k = 0;
    for (int i = 0; i < n; i++) {
        char c = s[i];
        if (c == ' ')
            continue;
        if (k >= (int)sizeof buf - 1)
            return 0;
        if (c == 'D' || c == 'd')
            c = 'E';
        buf[k++] = c;
    }
    buf[k] = 0;
    if (k == 0)
        return 0;
    for (int i = 0; i < k; i++)
        if (!(isdigit((unsigned char)buf[i]) || buf[i] == '.' || buf[i] == '+' || buf[i] == '-' || buf[i] == 'E' ||
              buf[i] == 'e'))
            return 0;
    char *end;
    double v = strtod(buf, &end);
    if (*end != 0 || !isfinite(v))
        return 0;
    *out = v;
    return 1;
}

/*
 * Tokenise free-format parameter text into params (growing array).  Stops
 * at the record delimiter.  Returns 0 on success, else writes a reason.
 * `start_field` is 1 for the Global section's third field onwards (the
 * first two are delimiters, parsed by the caller).
 */
typedef struct plist {
    iges_param *p;
    int n, cap;
} plist;

static int plist_push(plist *pl, iges_param v)
{
    if (pl->n == pl->cap) {
        int cap = pl->cap ? 2 * pl->cap : 16;
        iges_param *q = realloc(pl->p, (size_t)cap * sizeof *q);
        if (!q)
            return -1;
        pl->p = q;
        pl->cap = cap;
    }
    pl->p[pl->n++] = v;
    return 0;
}

static void plist_free(plist *pl)
{
    for (int i = 0; i < pl->n; i++)
        free((char *)pl->p[i].str);
    free(pl->p);
    pl->p = NULL;
    pl->n = pl->cap = 0;
}

static int tokenize(const char *t, int n, char pd, char rd, plist *out, char *why, size_t whycap)
{
    int pos = 0;
    for (;;) {
        while (pos < n && t[pos] == ' ')
            pos++;
        if (pos >= n) {
            snprintf(why, whycap, "no record delimiter '%c' before the end of the entity's parameter lines", rd);
            return -1;
        }
        iges_param v = {IGES_P_EMPTY, 0.0, NULL, 0};
        char c = t[pos];
        if (c == pd || c == rd) {
            if (plist_push(out, v))
                goto oom;
            pos++;
            if (c == rd)
                return 0;
            continue;
        }
        /* Hollerith string: digits then H */
        int k = pos, count = 0;
        while (k < n && isdigit((unsigned char)t[k]) && count < 100000) {
            count = count * 10 + (t[k] - '0');
            k++;
        }
        if (k > pos && k < n && (t[k] == 'H' || t[k] == 'h')) {
            k++;
            if (k + count > n) {
                snprintf(why, whycap, "string %dH... runs past the end of the parameter lines", count);
                return -1;
            }
            char *s = malloc((size_t)count + 1);
            if (!s)
                goto oom;
            memcpy(s, t + k, (size_t)count);
            s[count] = 0;
            v.kind = IGES_P_STR;
            v.str = s;
            v.len = count;
            if (plist_push(out, v)) {
                free(s);
                goto oom;
            }
            pos = k + count;
            while (pos < n && t[pos] == ' ')
                pos++;
            if (pos >= n) {
                snprintf(why, whycap, "no delimiter after a string");
                return -1;
            }
            if (t[pos] != pd && t[pos] != rd) {
                snprintf(why, whycap, "unexpected '%c' after a %dH string", t[pos], count);
                return -1;
            }
            if (t[pos++] == rd)
                return 0;
            continue;
        }
        /* number (or pointer) up to the next delimiter */
        int e = pos;
        while (e < n && t[e] != pd && t[e] != rd)
            e++;
        if (e >= n) {
            snprintf(why, whycap, "no record delimiter '%c' before the end of the entity's parameter lines", rd);
            return -1;
        }
        if (!parse_number(t + pos, e - pos, &v.num)) {
            snprintf(why, whycap, "'%.*s' is not a number", e - pos > 40 ? 40 : e - pos, t + pos);
            return -1;
        }
        v.kind = IGES_P_NUM;
        if (plist_push(out, v))
            goto oom;
        pos = e + 1;
        if (t[e] == rd)
            return 0;
    }
oom:
    snprintf(why, whycap, "out of memory");
    return -2;
}

/* ---- sections ---- */

static cm_err split_lines(reader *r, const char *data, size_t len)
{
    iges_file *f = r->f;
    if (len > (size_t)0x7fffffff)
        return iges_error(f, 0, "file larger than 2 GiB");
    int cap = 1024;
    r->lines = malloc((size_t)cap * sizeof *r->lines);
    if (!r->lines)
        return iges_nomem(f, 1, "splitting the file into lines");
    size_t i = 0;
    int no = 0;
    while (i < len) {
        size_t s = i;
        while (i < len && data[i] != '\n' && data[i] != '\r')
            i++;
        size_t e = i;
        if (i < len && data[i] == '\r')
            i++;
        if (i < len && data[i] == '\n')
            i++;
        no++;
        if (e == s)
            continue; /* blank line: ignored (some writers end with one) */
        if (e - s > 4096)
            return iges_error(f, no, "line of %zu bytes: not a fixed-format ASCII IGES file (binary?)", e - s);
        if (r->nlines == cap) {
            if (cap > 0x3fffffff)
                return iges_error(f, no, "more than %d lines: not an IGES file this tool can read", cap);
            cap *= 2;
            line *q = realloc(r->lines, (size_t)cap * sizeof *q);
            if (!q)
                return iges_nomem(f, no, "splitting the file into lines");
            r->lines = q;
        }
        r->lines[r->nlines].s = data + s;
        r->lines[r->nlines].len = (int)(e - s);
        r->lines[r->nlines].no = no;
        r->nlines++;
    }
    if (r->nlines == 0)
        return iges_error(f, no > 0 ? no : 1, "empty file: no IGES line (%zu bytes)", len);
    return CM_OK;
}

static cm_err find_sections(reader *r)
{
    iges_file *f = r->f;
    for (int k = 0; k < 5; k++) {
        r->sec[k] = malloc((size_t)r->nlines * sizeof(int));
        if (!r->sec[k])
            return iges_nomem(f, 1, "indexing the file's %d lines", r->nlines);
    }
    int last = 0;
    for (int i = 0; i < r->nlines; i++) {
        const line *l = &r->lines[i];
        for (int c = 0; c < l->len; c++)
            if (l->s[c] == 0)
                return iges_error(f, l->no, "NUL byte: not an ASCII IGES file");
        if (l->len < 73)
            return iges_error(f, l->no, "line has %d columns; IGES lines have 80 with the section letter in column 73",
                              l->len);
        char c = l->s[72];
        if (c == 'C' && i == 0)
            return iges_error(f, l->no, "compressed ASCII IGES is not supported; re-export as fixed-format ASCII");
        if (c == 'B' && i == 0)
            return iges_error(f, l->no, "binary IGES is not supported; re-export as fixed-format ASCII");
        const char *p = strchr(sec_letters, c);
        if (c == 0 || p == NULL)
            return iges_error(f, l->no, "column 73 holds '%c', not a section letter (S, G, D, P or T)",
                              isprint((unsigned char)c) ? c : '?');
        int k = (int)(p - sec_letters);
        if (k < last)
            return iges_error(f, l->no, "%c section line after the %c section: sections out of order", c,
                              sec_letters[last]);
        last = k;
        r->sec[k][r->nsec[k]++] = i;
    }
    /* a missing section is reported at the line where it should have started */
    if (r->nsec[SEC_G] == 0)
        return iges_error(f, r->lines[r->nsec[SEC_S] < r->nlines ? r->nsec[SEC_S] : r->nlines - 1].no,
                          "no Global section (no line with G in column 73)");
    if (r->nsec[SEC_D] == 0)
        return iges_error(f, r->lines[r->sec[SEC_G][r->nsec[SEC_G] - 1]].no + 1,
                          "no Directory Entry section: the file holds no entities");
    if (r->nsec[SEC_P] == 0)
        return iges_error(f, r->lines[r->sec[SEC_D][r->nsec[SEC_D] - 1]].no + 1, "no Parameter Data section");
    if (r->nsec[SEC_D] % 2 != 0)
        return iges_error(f, r->lines[r->sec[SEC_D][r->nsec[SEC_D] - 1]].no,
                          "odd number of Directory lines (%d): the file is truncated or corrupted", r->nsec[SEC_D]);
    f->nlines_s = r->nsec[SEC_S];
    f->nlines_g = r->nsec[SEC_G];
    f->nlines_d = r->nsec[SEC_D];
    f->nlines_p = r->nsec[SEC_P];
    /* Terminate: counts are a checksum of completeness, mismatches are warned */
    if (r->nsec[SEC_T] == 0) {
        iges_warn(f, r->lines[r->nlines - 1].no,
                  "no Terminate section after this last line: the file may be truncated (the data read is complete)");
    } else {
        const line *t = &r->lines[r->sec[SEC_T][0]];
        int ok = 1;
        int counts[4];
        for (int k = 0; k < 4; k++) {
            /* fields "S0000004G0000003D0000120P0000315" */
            char buf[8];
            memcpy(buf, t->s + k * 8 + 1, 7);
            buf[7] = 0;
            counts[k] = (int)strtol(buf, NULL, 10);
            if (t->s[k * 8] != sec_letters[k])
                ok = 0;
        }
        if (!ok)
            iges_warn(f, t->no, "Terminate section is malformed");
        else
            for (int k = 0; k < 4; k++)
                if (counts[k] != r->nsec[k])
                    iges_warn(f, t->no, "Terminate section counts %d %c lines, the file has %d", counts[k],
                              sec_letters[k], r->nsec[k]);
    }
    /* sequence numbers: warn once per section if they are not 1, 2, 3, ... */
    for (int k = 0; k < 5; k++)
        for (int j = 0; j < r->nsec[k]; j++) {
            const line *l = &r->lines[r->sec[k][j]];
            if (seq_field(l) != j + 1) {
                iges_warn(f, l->no, "%c section sequence number is %d, expected %d", sec_letters[k], seq_field(l),
                          j + 1);
                break;
            }
        }
    return CM_OK;
}

static char *dup_str(const plist *pl, int i)
{
    if (i < pl->n && pl->p[i].kind == IGES_P_STR)
        return strdup(pl->p[i].str);
    return strdup("");
}

static double units_to_mm(iges_file *f, int line_no)
{
    static const double factor[12] = {0, 25.4, 1.0, 0, 304.8, 1609344.0, 1000.0, 1e6, 0.0254, 0.001, 10.0, 2.54e-5};
    int u = f->g.units_flag;
    if (u >= 1 && u <= 11 && u != 3)
        return factor[u];
    /* flag 3 (or an unknown flag): the units name decides */
    const char *n = f->g.units_name ? f->g.units_name : "";
    static const struct {
        const char *name;
        double mm;
    } names[] = {{"IN", 25.4}, {"INCH", 25.4}, {"MM", 1.0}, {"FT", 304.8}, {"MI", 1609344.0}, {"M", 1000.0},
                 {"KM", 1e6},  {"MIL", 0.0254}, {"UM", 0.001}, {"CM", 10.0},  {"UIN", 2.54e-5}};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (strcmp(n, names[i].name) == 0)
            return names[i].mm;
    iges_warn(f, line_no, "Global section: unknown units (flag %d, name '%s'); assuming millimetres", u, n);
    return 1.0;
}

static cm_err parse_global(reader *r)
{
    iges_file *f = r->f;
    int n = r->nsec[SEC_G];
    int line0 = r->lines[r->sec[SEC_G][0]].no;
    char *t = malloc((size_t)n * 72 + 1);
    if (!t)
        return iges_nomem(f, line0, "reading the Global section");
    for (int j = 0; j < n; j++)
        memcpy(t + j * 72, r->lines[r->sec[SEC_G][j]].s, 72);
    int len = n * 72; /* n <= nlines, and a file of at most 2 GiB has fewer than 2^31 / 72 lines of 73 bytes */
    t[len] = 0;
    /* the first two fields define the delimiters themselves */
    char pd = ',', rd = ';';
    int pos = 0;
    while (pos < len && t[pos] == ' ')
        pos++;
    if (pos + 2 < len && t[pos] == '1' && (t[pos + 1] == 'H' || t[pos + 1] == 'h')) {
        pd = t[pos + 2];
        pos += 3;
    }
    while (pos < len && t[pos] == ' ')
        pos++;
    if (pos >= len || t[pos] != pd) {
        free(t);
        return iges_error(f, line0, "Global section does not start with the parameter delimiter definition");
    }
    pos++;
    while (pos < len && t[pos] == ' ')
        pos++;
    if (pos + 2 < len && t[pos] == '1' && (t[pos + 1] == 'H' || t[pos + 1] == 'h')) {
        rd = t[pos + 2];
        pos += 3;
        while (pos < len && t[pos] == ' ')
            pos++;
        if (pos < len && t[pos] == pd)
            pos++;
    } else if (pos < len && t[pos] == pd) {
        pos++;
    } else if (pos < len && t[pos] == rd) {
        pos = len; /* only delimiters: everything else defaulted */
    }
    if (pd == rd || pd == ' ' || rd == ' ') {
        free(t);
        return iges_error(f, line0, "Global section defines unusable delimiters '%c' and '%c'", pd, rd);
    }
    f->g.pdelim = pd;
    f->g.rdelim = rd;
    plist pl = {0};
    char why[200];
    int rc = pos < len ? tokenize(t + pos, len - pos, pd, rd, &pl, why, sizeof why) : 0;
    free(t);
    if (rc == -2) {
        plist_free(&pl);
        return iges_nomem(f, line0, "reading the Global section");
    }
    if (rc < 0) /* a broken Global section loses metadata, not geometry: warn and go on with defaults */
        iges_warn(f, line0, "Global section: %s; using defaults for the rest", why);
    /* pl[0] is Global parameter 3 */
#define G(i) ((i) - 3)
    f->g.sender_id = dup_str(&pl, G(3));
    f->g.file_name = dup_str(&pl, G(4));
    f->g.system_id = dup_str(&pl, G(5));
    f->g.preprocessor = dup_str(&pl, G(6));
    f->g.receiver_id = dup_str(&pl, G(12));
    f->g.model_scale = (G(13) < pl.n && pl.p[G(13)].kind == IGES_P_NUM) ? pl.p[G(13)].num : 1.0;
    f->g.units_flag = (G(14) < pl.n && pl.p[G(14)].kind == IGES_P_NUM) ? iges_to_int(pl.p[G(14)].num, -99, 99, 0) : 1;
    f->g.units_name = dup_str(&pl, G(15));
    f->g.date = dup_str(&pl, G(18));
    f->g.resolution = (G(19) < pl.n && pl.p[G(19)].kind == IGES_P_NUM) ? pl.p[G(19)].num : 0.0;
    f->g.max_coord = (G(20) < pl.n && pl.p[G(20)].kind == IGES_P_NUM) ? pl.p[G(20)].num : 0.0;
    f->g.author = dup_str(&pl, G(21));
    f->g.organization = dup_str(&pl, G(22));
    f->g.version = (G(23) < pl.n && pl.p[G(23)].kind == IGES_P_NUM) ? iges_to_int(pl.p[G(23)].num, -999, 999, 0) : 0;
    f->g.drafting = (G(24) < pl.n && pl.p[G(24)].kind == IGES_P_NUM) ? iges_to_int(pl.p[G(24)].num, -999, 999, 0) : 0;
    f->g.model_date = dup_str(&pl, G(25));
#undef G
    plist_free(&pl);
    if (!f->g.sender_id || !f->g.file_name || !f->g.system_id || !f->g.preprocessor || !f->g.receiver_id ||
        !f->g.units_name || !f->g.date || !f->g.author || !f->g.organization || !f->g.model_date)
        return iges_nomem(f, line0, "reading the Global section");
    /* a scale far from 1 would send every coordinate to 0 or past the range of doubles */
    if (!(f->g.model_scale >= 1e-9 && f->g.model_scale <= 1e9)) {
        iges_warn(f, line0, "Global section: model space scale %g is not a positive number in [1e-9, 1e9]; using 1",
                  f->g.model_scale);
        f->g.model_scale = 1.0;
    }
    if (!(f->g.resolution >= 0.0))
        f->g.resolution = 0.0;
    f->to_mm = units_to_mm(f, line0) / f->g.model_scale;
    return CM_OK;
}

static cm_err parse_directory(reader *r)
{
    iges_file *f = r->f;
    int n = r->nsec[SEC_D] / 2;
    f->ents = calloc((size_t)n, sizeof *f->ents);
    f->de_map = malloc((size_t)n * sizeof(int));
    if (!f->ents || !f->de_map)
        return iges_nomem(f, r->lines[r->sec[SEC_D][0]].no, "reading %d Directory entries", n);
    f->de_map_n = n;
    for (int i = 0; i < n; i++)
        f->de_map[i] = -1;
    for (int i = 0; i < n; i++) {
        const line *a = &r->lines[r->sec[SEC_D][2 * i]];
        const line *b = &r->lines[r->sec[SEC_D][2 * i + 1]];
        iges_entity *e = &f->ents[f->nents];
        int ok = 1;
        e->de = 2 * i + 1;
        e->line = a->no;
        e->type = de_field(a, 1, &ok);
        e->pd_seq = de_field(a, 2, &ok);
        e->structure = de_field(a, 3, &ok);
        e->font = de_field(a, 4, &ok);
        e->level = de_field(a, 5, &ok);
        e->view = de_field(a, 6, &ok);
        e->xform = de_field(a, 7, &ok);
        e->label_assoc = de_field(a, 8, &ok);
        int type2 = de_field(b, 1, &ok);
        e->weight = de_field(b, 2, &ok);
        e->color = de_field(b, 3, &ok);
        e->pd_count = de_field(b, 4, &ok);
        e->form = de_field(b, 5, &ok);
        /* status 9: four 2-digit fields; blanks count as zeros */
        int st_ok = 1;
        char sbuf[9];
        for (int c = 0; c < 8; c++) {
            char ch = 64 + c < a->len ? a->s[64 + c] : ' ';
            sbuf[c] = ch == ' ' ? '0' : ch;
            if (!isdigit((unsigned char)sbuf[c]))
                st_ok = 0;
        }
        if (st_ok) {
            e->blank = (sbuf[0] - '0') * 10 + (sbuf[1] - '0');
            e->subord = (sbuf[2] - '0') * 10 + (sbuf[3] - '0');
            e->use = (sbuf[4] - '0') * 10 + (sbuf[5] - '0');
            e->hier = (sbuf[6] - '0') * 10 + (sbuf[7] - '0');
        } else {
            iges_warn(f, a->no, "DE %d: status field '%.8s' is not numeric; treated as 00000000", e->de, a->s + 64);
        }
        /* label (columns 57-64 of line 2) and subscript (65-72) */
        int k = 0;
        for (int c = 56; c < 64; c++)
            if (c < b->len && b->s[c] != ' ' && k < 8)
                e->label[k++] = isprint((unsigned char)b->s[c]) ? b->s[c] : '?';
        e->label[k] = 0;
        int ok2 = 1;
        e->subscript = de_field(b, 9, &ok2);
        if (!ok)
            return iges_error(f, a->no, "Directory entry DE %d has a non-numeric field", e->de);
        if (type2 != e->type)
            return iges_error(f, b->no, "Directory entry DE %d: entity type %d on its first line, %d on its second",
                              e->de, e->type, type2);
        if (e->pd_seq < 1 || e->pd_count < 1 || e->pd_seq > r->nsec[SEC_P] ||
            e->pd_seq + e->pd_count - 1 > r->nsec[SEC_P])
            return iges_error(f, a->no,
                              "Directory entry DE %d (entity %d): parameter lines %d..%d outside the %d-line "
                              "Parameter section",
                              e->de, e->type, e->pd_seq, e->pd_seq + e->pd_count - 1, r->nsec[SEC_P]);
        e->pd_line = r->lines[r->sec[SEC_P][e->pd_seq - 1]].no;
        f->de_map[i] = f->nents;
        f->nents++;
    }
    return CM_OK;
}

static cm_err parse_parameters(reader *r)
{
    iges_file *f = r->f;
    char *buf = NULL;
    size_t cap = 0;
    int warned_backptr = 0;
    for (int i = 0; i < f->nents; i++) {
        iges_entity *e = &f->ents[i];
        size_t need = (size_t)e->pd_count * 64 + 1;
        if (need > cap) {
            char *q = realloc(buf, need);
            if (!q) {
                free(buf);
                return iges_nomem(f, e->pd_line, "reading the %d parameter lines of DE %d", e->pd_count, e->de);
            }
            buf = q;
            cap = need;
        }
        for (int j = 0; j < e->pd_count; j++) {
            const line *l = &r->lines[r->sec[SEC_P][e->pd_seq - 1 + j]];
            memcpy(buf + (size_t)j * 64, l->s, 64);
            int ok = 1;
            int back = de_field(l, 9, &ok) ; /* columns 65-72: 66-72 hold the DE back pointer */
            if ((!ok || back != e->de) && !warned_backptr) {
                iges_warn(f, l->no, "parameter line points back to DE %d, expected %d", back, e->de);
                warned_backptr = 1;
            }
        }
        /* no overflow: a file of at most 2 GiB has fewer than 2^31 / 73 lines, times 64 columns */
        int len = e->pd_count * 64;
        buf[len] = 0;
        plist pl = {0};
        char why[200];
        int rc = tokenize(buf, len, f->g.pdelim, f->g.rdelim, &pl, why, sizeof why);
        if (rc == -2) {
            plist_free(&pl);
            free(buf);
            return iges_nomem(f, e->pd_line, "reading the parameters of DE %d", e->de);
        }
        /* compared as doubles: the number may be anything (5e13), which an int cannot hold */
        if (rc < 0 || pl.n == 0 || pl.p[0].kind != IGES_P_NUM || pl.p[0].num != (double)e->type) {
            if (rc == 0)
                snprintf(why, sizeof why, "parameter data does not start with the entity type %d", e->type);
            iges_warn(f, e->pd_line, "entity %d (DE %d) skipped: %s", e->type, e->de, why);
            e->bad = 1;
            plist_free(&pl);
            continue;
        }
        /* drop the leading type number: params[0] is the entity's first parameter */
        free((char *)pl.p[0].str);
        memmove(pl.p, pl.p + 1, (size_t)(pl.n - 1) * sizeof *pl.p);
        e->nparams = pl.n - 1;
        e->params = pl.p;
    }
    free(buf);
    return CM_OK;
}

cm_err iges_parse(const char *data, size_t len, iges_file *f, cm_status *st)
{
    reader r;
    memset(&r, 0, sizeof r);
    r.f = f;
    cm_err e;
    if ((e = split_lines(&r, data, len)) == CM_OK && (e = find_sections(&r)) == CM_OK &&
        (e = parse_global(&r)) == CM_OK && (e = parse_directory(&r)) == CM_OK)
        e = parse_parameters(&r);
    free(r.lines);
    for (int k = 0; k < 5; k++)
        free(r.sec[k]);
    if (e != CM_OK)
        return cm_fail(st, e, "iges_parse");
    return CM_OK;
}

cm_err iges_read(const char *path, iges_file *f, cm_status *st)
{
    memset(f, 0, sizeof *f);
    f->path = strdup(path);
    FILE *fp = fopen(path, "rb");
    if (!fp) {
        int err = errno;
        snprintf(f->err, sizeof f->err, "cannot open: %s", strerror(err));
        cm_err e = cm_fail(st, CM_E_IO, "iges_read");
        if (st)
            st->sys_errno = err;
        return e;
    }
    char *data = NULL;
    size_t len = 0, cap = 0;
    for (;;) {
        if (len + 65536 > cap) {
            cap = cap ? 2 * cap : 1 << 20;
            char *q = realloc(data, cap);
            if (!q) {
                free(data);
                fclose(fp);
                snprintf(f->err, sizeof f->err, "out of memory reading the file (%zu bytes read)", len);
                return cm_fail(st, CM_E_NOMEM, "iges_read");
            }
            data = q;
        }
        size_t got = fread(data + len, 1, cap - len, fp);
        len += got;
        if (got == 0)
            break;
    }
    int rerr = ferror(fp);
    fclose(fp);
    if (rerr) {
        free(data);
        snprintf(f->err, sizeof f->err, "read error");
        return cm_fail(st, CM_E_IO, "iges_read");
    }
    char *keep = f->path;
    f->path = NULL;
    memset(f, 0, sizeof *f);
    f->path = keep;
    cm_err e = iges_parse(data, len, f, st);
    free(data);
    return e;
}

void iges_free(iges_file *f)
{
    if (!f)
        return;
    for (int i = 0; i < f->nents; i++) {
        for (int j = 0; j < f->ents[i].nparams; j++)
            free((char *)f->ents[i].params[j].str);
        free(f->ents[i].params);
    }
    free(f->ents);
    free(f->de_map);
    free(f->curve_pieces);
    for (int i = 0; i < f->nwarn; i++)
        free(f->warn[i].msg);
    free(f->warn);
    free(f->g.sender_id);
    free(f->g.file_name);
    free(f->g.system_id);
    free(f->g.preprocessor);
    free(f->g.receiver_id);
    free(f->g.units_name);
    free(f->g.date);
    free(f->g.author);
    free(f->g.organization);
    free(f->g.model_date);
    free(f->path);
    memset(f, 0, sizeof *f);
}

const iges_entity *iges_by_de(const iges_file *f, int de)
{
    if (de < 1 || (de & 1) == 0)
        return NULL;
    int i = (de - 1) / 2;
    if (i >= f->de_map_n || f->de_map[i] < 0)
        return NULL;
    return &f->ents[f->de_map[i]];
}

/* ---- typed access ---- */

double iges_num_or(const iges_entity *e, int i, double dflt)
{
    if (i < 0 || i >= e->nparams || e->params[i].kind != IGES_P_NUM)
        return dflt;
    return e->params[i].num;
}

int iges_to_int(double v, int lo, int hi, int dflt)
{
    if (!(v >= (double)lo && v <= (double)hi) || v != floor(v))
        return dflt;
    return (int)v;
}

int iges_int_or(const iges_entity *e, int i, int dflt)
{
    double v = iges_num_or(e, i, (double)dflt);
    if (!(v >= -2147483647.0 && v <= 2147483647.0))
        return dflt;
    return (int)v;
}

int iges_count_or0(const iges_entity *e, int i)
{
    double v = iges_num_or(e, i, 0.0);
    if (!(v > 0.0))
        return 0;
    return v >= (double)e->nparams ? e->nparams : (int)v;
}

int iges_num(iges_file *f, const iges_entity *e, int i, double *out)
{
    if (i < 0 || i >= e->nparams) {
        iges_entity_error(f, e, "parameter %d missing (the entity has %d)", i + 1, e->nparams);
        return -1;
    }
    if (e->params[i].kind != IGES_P_NUM) {
        iges_entity_error(f, e, "parameter %d: expected a number, found %s", i + 1,
                          e->params[i].kind == IGES_P_STR ? "a string" : "nothing");
        return -1;
    }
    *out = e->params[i].num;
    return 0;
}

int iges_int(iges_file *f, const iges_entity *e, int i, int *out)
{
    double v;
    if (iges_num(f, e, i, &v))
        return -1;
    if (!(v >= -2147483647.0 && v <= 2147483647.0) || v != floor(v)) {
        iges_entity_error(f, e, "parameter %d: expected an integer, found %g", i + 1, v);
        return -1;
    }
    *out = (int)v;
    return 0;
}

int iges_ptr(iges_file *f, const iges_entity *e, int i, int allow_null, int *de_out)
{
    int de = 0;
    if (allow_null && (i >= e->nparams || e->params[i].kind == IGES_P_EMPTY)) {
        *de_out = 0;
        return 0;
    }
    if (iges_int(f, e, i, &de))
        return -1;
    if (de == 0 && allow_null) {
        *de_out = 0;
        return 0;
    }
    if (de < 0)
        de = -de; /* negated pointers (e.g. colour) still name the entity */
    if (!iges_by_de(f, de)) {
        iges_entity_error(f, e, "parameter %d points to DE %d, which is not an entity of this file", i + 1, de);
        return -1;
    }
    *de_out = de;
    return 0;
}

const char *iges_type_name(int type)
{
    switch (type) {
    case 100: return "circular arc";
    case 102: return "composite curve";
    case 104: return "conic arc";
    case 106: return "copious data";
    case 108: return "plane";
    case 110: return "line";
    case 112: return "parametric spline curve";
    case 114: return "parametric spline surface";
    case 116: return "point";
    case 118: return "ruled surface";
    case 120: return "surface of revolution";
    case 122: return "tabulated cylinder";
    case 123: return "direction";
    case 124: return "transformation matrix";
    case 126: return "rational B-spline curve";
    case 128: return "rational B-spline surface";
    case 141: return "boundary";
    case 142: return "curve on a parametric surface";
    case 143: return "bounded surface";
    case 144: return "trimmed surface";
    case 186: return "manifold solid B-rep object";
    case 190: return "plane surface";
    case 192: return "right circular cylindrical surface";
    case 194: return "right circular conical surface";
    case 196: return "spherical surface";
    case 198: return "toroidal surface";
    case 308: return "subfigure definition";
    case 314: return "color definition";
    case 402: return "associativity instance";
    case 406: return "property";
    case 408: return "singular subfigure instance";
    case 502: return "vertex list";
    case 504: return "edge list";
    case 508: return "loop";
    case 510: return "face";
    case 514: return "shell";
    default: return "unknown";
    }
}
