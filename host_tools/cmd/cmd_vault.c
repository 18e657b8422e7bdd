/*
 * cmd_vault.c - `cmz encode FOLDER|--list FILE -o OUTFOLDER [-j N]`: encode
 * a design department's whole vault, one model per worker process.
 *
 * Each model is encoded by `cmz encode MODEL -o OUT` (cmd_encode.c) run in a
 * child process of its own: a model that fails, crashes or runs past
 * --timeout is named in the summary and the exit status while the rest still
 * encode, and nothing of it is left behind but its messages.  The outputs
 * mirror the input tree (`a/b/part.igs` -> `OUT/a/b/part.cmz`; models that
 * would share an output keep their extension, `part.igs.cmz`, then `~2`).
 *
 * The summary (`OUT/cmz-vault.tsv` unless --summary) has a row per model:
 * sizes, the share of faces whose surface is deleted, the worst rebuilt
 * face's deviation, seconds, the encoder and options it was built with, and
 * the error of a model that failed.  It is also the record that lets the next
 * run skip a model: its output has the size recorded, the model the size and
 * modification time recorded before it was encoded, and the same encoder
 * binary built it with the same options (--force encodes everything again).
 *
 * Processes, not threads: the importers and the encoder keep per-thread
 * caches and process-wide state (cmd.h), a crash or a runaway model cannot
 * take the others with it, and a batch engine (README) runs the same command
 * on many machines with --shard K/N.
 */
#define _GNU_SOURCE /* prctl's PR_SET_PDEATHSIG: a worker does not outlive its vault */
#include "cmd.h"

#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "cm/cm_crc32.h"

/* what happened to one model */
enum { JOB_PENDING, JOB_ENCODED, JOB_UP_TO_DATE, JOB_FAILED, JOB_NOT_RUN, JOB_DUPLICATE };
static const char *const job_status_name[] = {"pending", "encoded", "up-to-date", "failed", "not-run"};

typedef struct vault_job {
    char *in;   /* the model's path as found or listed */
    char *rel;  /* its path under the folder (or the list's path, made relative) */
    char *out;  /* OUT/rel with the extension .cmz */
    int status; /* JOB_FAILED before any run: a folder or link that cannot be read (message says why) */
    int exit_code;
    int have_stat;
    int is_link;    /* found as a symbolic link (a model reached also by its own path is encoded there) */
    long long in_size, in_mtime_ns; /* the model as it was just before it was encoded */
    dev_t dev;
    ino_t ino;
    double seconds;
    int warnings;
    cmd_encode_summary sm;
    char *message; /* a failure's first error line, or a carried row's message */
} vault_job;

typedef struct job_list {
    vault_job *v;
    size_t n, cap;
} job_list;

static char *join3(const char *a, const char *b, const char *c)
{
    size_t n = strlen(a) + strlen(b) + strlen(c) + 1;
    char *s = malloc(n);
    if (s)
        snprintf(s, n, "%s%s%s", a, b, c);
    return s;
}

/* room for one more job */
static int reserve_one(job_list *l)
{
    if (l->n == l->cap) {
        size_t cap = l->cap ? 2 * l->cap : 64;
        vault_job *v = realloc(l->v, cap * sizeof *v);
        if (!v)
            return -1;
        l->v = v;
        l->cap = cap;
    }
    return 0;
}

/* append *j to l, which now owns its strings (j is left empty) */
static int move_job(job_list *l, vault_job *j)
{
    if (reserve_one(l))
        return -1;
    l->v[l->n++] = *j;
    memset(j, 0, sizeof *j);
    return 0;
}

static int push_job(job_list *l, const char *in, const char *rel)
{
    if (reserve_one(l))
        return -1;
    vault_job *j = &l->v[l->n];
    memset(j, 0, sizeof *j);
    j->in = strdup(in);
    j->rel = strdup(rel);
    if (!j->in || !j->rel) {
        free(j->in);
        free(j->rel);
        return -1;
    }
    l->n++;
    return 0;
}

/* a model that cannot even be looked at: a failed row from the start */
static int push_failed(job_list *l, const char *in, const char *rel, const char *why)
{
    if (push_job(l, in, rel))
        return -1;
    vault_job *j = &l->v[l->n - 1];
    j->status = JOB_FAILED;
    j->exit_code = EXIT_IO;
    return (j->message = join3(in, ": ", why)) ? 0 : -1;
}

static void free_job(vault_job *j)
{
    free(j->in);
    free(j->rel);
    free(j->out);
    free(j->message);
}

static void free_jobs(job_list *l)
{
    for (size_t i = 0; i < l->n; i++)
        free_job(&l->v[i]);
    free(l->v);
    memset(l, 0, sizeof *l);
}

/* ---- finding the models ---- */

/* the extensions CAD systems give IGES and STEP files; the content still decides the format */
static int is_model_name(const char *name)
{
    static const char *const ext[] = {".igs", ".iges", ".stp", ".step", ".p21"};
    size_t n = strlen(name);
    for (size_t k = 0; k < sizeof ext / sizeof ext[0]; k++) {
        size_t e = strlen(ext[k]);
        if (n > e && strcasecmp(name + n - e, ext[k]) == 0)
            return 1;
    }
    return 0;
}

/* nftw's callback has no context argument */
static job_list walk_found;
static const char *walk_real;   /* the folder walked, resolved (nftw walks it without following links) */
static const char *walk_given;  /* ... as the user spelled it: the models' paths start with it */
static const char *walk_prefix; /* NULL, or a listed folder's place in the output tree */

static int walk_one(const char *path, const struct stat *sb, int type, struct FTW *ftw)
{
    (void)sb;
    const char *rel = path + strlen(walk_real);
    while (*rel == '/')
        rel++;
    if (rel[0] == '.' || strstr(rel, "/.")) /* hidden: .git, .cache, an editor's copy */
        return 0;
    const char *base = path + ftw->base;
    char why[160] = "";
    struct stat target;
    if (type == FTW_DNR) {
        snprintf(why, sizeof why, "a folder that cannot be read: its models are not encoded");
    } else if (type == FTW_NS) {
        /* a model, or a folder that may hold some: said, not skipped in silence */
        snprintf(why, sizeof why, "cannot look at it (%s): its models, if any, are not encoded", strerror(errno));
    } else if (type == FTW_SL || type == FTW_SLN) {
        /* a link to a model is read (links to folders are not followed: no loops) */
        if (!is_model_name(base))
            return 0;
        if (stat(path, &target) != 0)
            snprintf(why, sizeof why, "a symbolic link to nothing (%s)", strerror(errno));
        else if (!S_ISREG(target.st_mode))
            return 0;
    } else if (type != FTW_F || !is_model_name(base)) {
        return 0;
    }
    char *in = join3(walk_given, walk_given[0] && walk_given[strlen(walk_given) - 1] == '/' ? "" : "/", rel);
    char *r = walk_prefix && walk_prefix[0] ? join3(walk_prefix, "/", rel) : strdup(rel);
    int bad = !in || !r || (why[0] ? push_failed(&walk_found, in, r, why) : push_job(&walk_found, in, r));
    if (!bad && (type == FTW_SL || type == FTW_SLN))
        walk_found.v[walk_found.n - 1].is_link = 1;
    free(in);
    free(r);
    return bad;
}

static int by_in(const void *a, const void *b)
{
    return strcmp(((const vault_job *)a)->in, ((const vault_job *)b)->in);
}

/* every model under `folder` (sorted: the same order on every machine) into l, `prefix`/ before their
   place in the output tree */
static int walk_folder(const char *folder, const char *prefix, job_list *l)
{
    char *real = realpath(folder, NULL); /* a link to the vault, or "vault/", is walked as the vault */
    if (!real) {
        fprintf(stderr, "%s: %s: %s\n", cmd_prog, folder, strerror(errno));
        return EXIT_IO;
    }
    walk_real = real;
    walk_given = folder;
    walk_prefix = prefix;
    walk_found = (job_list){0};
    errno = 0;
    int rc = EXIT_OK;
    if (nftw(real, walk_one, 32, FTW_PHYS) != 0) {
        fprintf(stderr, "%s: %s: %s\n", cmd_prog, folder, errno ? strerror(errno) : "out of memory");
        rc = errno ? EXIT_IO : EXIT_NOMEM;
    }
    qsort(walk_found.v, walk_found.n, sizeof *walk_found.v, by_in);
    for (size_t i = 0; rc == EXIT_OK && i < walk_found.n; i++)
        if (move_job(l, &walk_found.v[i]))
            rc = EXIT_NOMEM;
    free_jobs(&walk_found);
    free(real);
    return rc;
}

/* a listed path made relative for the output tree: '/' and '.' components dropped, '..' as "__" */
static char *relative_of(const char *path)
{
    size_t n = strlen(path);
    char *r = malloc(2 * n + 1), *w = r;
    if (!r)
        return NULL;
    const char *p = path;
    while (*p) {
        while (*p == '/')
            p++;
        const char *e = strchr(p, '/');
        size_t len = e ? (size_t)(e - p) : strlen(p);
        if (len == 0)
            break;
        if (!(len == 1 && p[0] == '.')) {
            if (w != r)
                *w++ = '/';
            if (len == 2 && p[0] == '.' && p[1] == '.') {
                memcpy(w, "__", 2);
                w += 2;
            } else {
                memcpy(w, p, len);
                w += len;
            }
        }
        p += len;
    }
    *w = '\0';
    return r;
}

static int read_list(const char *list, job_list *l)
{
    FILE *f = strcmp(list, "-") == 0 ? stdin : fopen(list, "r");
    if (!f) {
        fprintf(stderr, "%s: %s: %s\n", cmd_prog, list, strerror(errno));
        return EXIT_IO;
    }
    char *line = NULL;
    size_t cap = 0;
    ssize_t len;
    int rc = EXIT_OK;
    while (rc == EXIT_OK && (len = getline(&line, &cap, f)) >= 0) {
        while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r'))
            line[--len] = '\0';
        if (len == 0 || line[0] == '#')
            continue;
        char *rel = relative_of(line);
        struct stat sb;
        if (!rel)
            rc = EXIT_NOMEM;
        else if (stat(line, &sb) == 0 && S_ISDIR(sb.st_mode))
            rc = walk_folder(line, rel, l); /* a listed folder: its models, in its place */
        else if (push_job(l, line, rel))
            rc = EXIT_NOMEM;
        free(rel);
    }
    free(line);
    if (f != stdin)
        fclose(f);
    if (rc == EXIT_NOMEM)
        fprintf(stderr, "%s: out of memory\n", cmd_prog);
    return rc;
}

/* the model's size, time and identity now (before it is encoded, and for the skip decision) */
static void stat_input(vault_job *j)
{
    struct stat sb;
    j->have_stat = stat(j->in, &sb) == 0;
    if (j->have_stat) {
        j->in_size = (long long)sb.st_size;
        j->in_mtime_ns = (long long)sb.st_mtim.tv_sec * 1000000000LL + (long long)sb.st_mtim.tv_nsec;
        j->dev = sb.st_dev;
        j->ino = sb.st_ino;
    }
}

static const vault_job *sorting; /* qsort's comparators have no context argument */

static int by_identity(const void *a, const void *b)
{
    const vault_job *x = &sorting[*(const size_t *)a], *y = &sorting[*(const size_t *)b];
    int c = (x->have_stat > y->have_stat) - (x->have_stat < y->have_stat);
    if (!c && x->have_stat)
        c = x->dev != y->dev ? (x->dev > y->dev ? 1 : -1) : x->ino != y->ino ? (x->ino > y->ino ? 1 : -1) : 0;
    if (!c && !x->have_stat)
        c = strcmp(x->in, y->in);
    if (!c) /* of one file, its own path before a link to it */
        c = x->is_link - y->is_link;
    return c ? c : (*(const size_t *)a > *(const size_t *)b) - (*(const size_t *)a < *(const size_t *)b);
}

static int same_identity(const vault_job *x, const vault_job *y)
{
    return x->have_stat ? y->have_stat && x->dev == y->dev && x->ino == y->ino
                        : !y->have_stat && strcmp(x->in, y->in) == 0;
}

/* one model listed twice (or under two spellings of its path, or through a link) is encoded once,
   where first listed */
static int drop_duplicates(job_list *l)
{
    size_t *ix = malloc((l->n + 1) * sizeof *ix);
    if (!ix)
        return -1;
    for (size_t i = 0; i < l->n; i++)
        ix[i] = i;
    sorting = l->v;
    qsort(ix, l->n, sizeof *ix, by_identity);
    for (size_t i = 0, first = 0; i + 1 < l->n; i++) {
        vault_job *a = &l->v[ix[first]], *b = &l->v[ix[i + 1]];
        if (!same_identity(a, b) || b->status == JOB_FAILED || a->status == JOB_FAILED) {
            first = i + 1;
            continue;
        }
        fprintf(stderr, "%s: note: %s is listed again as %s: encoded once\n", cmd_prog, a->in, b->in);
        b->status = JOB_DUPLICATE;
    }
    size_t w = 0;
    for (size_t i = 0; i < l->n; i++)
        if (l->v[i].status == JOB_DUPLICATE) {
            free_job(&l->v[i]);
        } else {
            l->v[w++] = l->v[i];
        }
    l->n = w;
    free(ix);
    return 0;
}

static int by_out(const void *a, const void *b)
{
    int c = strcmp(sorting[*(const size_t *)a].out, sorting[*(const size_t *)b].out);
    return c ? c : (*(const size_t *)a > *(const size_t *)b) - (*(const size_t *)a < *(const size_t *)b);
}

/* flag every model whose output another model has too (clash[i] = its place in its group, 1 the first,
   0 alone); the number of clashing groups */
static size_t find_clashes(const job_list *l, size_t *ix, unsigned *clash)
{
    for (size_t i = 0; i < l->n; i++) {
        ix[i] = i;
        clash[i] = 0;
    }
    sorting = l->v;
    qsort(ix, l->n, sizeof *ix, by_out);
    size_t groups = 0;
    for (size_t i = 0; i + 1 < l->n; i++)
        if (strcmp(l->v[ix[i]].out, l->v[ix[i + 1]].out) == 0) {
            if (!clash[ix[i]]) {
                clash[ix[i]] = 1;
                groups++;
            }
            clash[ix[i + 1]] = clash[ix[i]] + 1;
        }
    return groups;
}

/* OUT/rel with .cmz for the extension; where two models would share one output, both keep their
   extension, and any still sharing one (part.igs beside part.igs.iges) get ~2, ~3 ... after the first */
static int name_outputs(job_list *l, const char *out)
{
    if (drop_duplicates(l) != 0)
        return -1;
    for (size_t i = 0; i < l->n; i++) {
        char *rel = strdup(l->v[i].rel);
        if (!rel)
            return -1;
        char *slash = strrchr(rel, '/'), *dot = strrchr(rel, '.');
        if (dot && (!slash || dot > slash + 1))
            *dot = '\0';
        char *o = join3(out, "/", rel);
        free(rel);
        l->v[i].out = o ? join3(o, ".cmz", "") : NULL;
        free(o);
        if (!l->v[i].out)
            return -1;
    }
    size_t *ix = malloc((l->n + 1) * sizeof *ix);
    unsigned *clash = malloc((l->n + 1) * sizeof *clash);
    int rc = ix && clash ? 0 : -1;
    for (int round = 0; rc == 0 && round < 8 && find_clashes(l, ix, clash) > 0; round++)
        for (size_t i = 0; rc == 0 && i < l->n; i++) {
            if (!clash[i] || (round > 0 && clash[i] == 1))
                continue;
            vault_job *j = &l->v[i];
            char suffix[32];
            snprintf(suffix, sizeof suffix, "~%u.cmz", clash[i]);
            char *o = round == 0 ? join3(out, "/", j->rel) : strdup(j->out);
            if (o && round > 0)
                o[strlen(o) - 4] = '\0'; /* drop ".cmz" */
            free(j->out);
            j->out = o ? join3(o, round == 0 ? ".cmz" : suffix, "") : NULL;
            free(o);
            if (!j->out)
                rc = -1;
        }
    if (rc == 0 && find_clashes(l, ix, clash) > 0)
        rc = -1; /* cannot happen: ~N names are distinct */
    free(ix);
    free(clash);
    return rc;
}

/* the output folder as one spelling ("out", "out/" and "./out" are one folder, so that the summary's
   rows, found by output path, are found again): repeated '/' and '.' components dropped */
static char *folder_spelling(const char *path)
{
    size_t n = strlen(path);
    char *r = malloc(n + 2), *w = r;
    if (!r)
        return NULL;
    if (path[0] == '/')
        *w++ = '/';
    for (const char *p = path; *p;) {
        while (*p == '/')
            p++;
        const char *e = strchr(p, '/');
        size_t len = e ? (size_t)(e - p) : strlen(p);
        if (len > 0 && !(len == 1 && p[0] == '.')) {
            if (w > r && w[-1] != '/')
                *w++ = '/';
            memcpy(w, p, len);
            w += len;
        }
        p += len;
    }
    if (w == r)
        *w++ = '.';
    *w = '\0';
    return r;
}

/* mkdir -p of the folder that holds `path` */
static int make_parents(const char *path)
{
    char *p = strdup(path);
    if (!p)
        return -1;
    for (char *s = strchr(p + 1, '/'); s; s = strchr(s + 1, '/')) {
        *s = '\0';
        if (mkdir(p, 0777) != 0 && errno != EEXIST) {
            free(p);
            return -1;
        }
        *s = '/';
    }
    free(p);
    return 0;
}

/* this encoder binary: its version and a CRC-32 of its own file (a rebuilt encoder encodes again) */
static void encoder_id(char *id, size_t n)
{
    uint32_t crc = 0;
    int ok = 0;
    FILE *f = fopen("/proc/self/exe", "rb");
    if (f) {
        uint8_t buf[65536];
        size_t got;
        while ((got = fread(buf, 1, sizeof buf, f)) > 0)
            crc = cm_crc32_update(crc, buf, got);
        ok = !ferror(f);
        fclose(f);
    }
    if (ok)
        snprintf(id, n, "cmz-%s-%08x", CMZ_VERSION, (unsigned)crc);
    else
        snprintf(id, n, "cmz-%s-unknown", CMZ_VERSION); /* never matches: every model is encoded */
}

/* ---- the summary: one row per model, tabs, line ends and backslashes escaped as \t \n \r \\ ---- */

static void tsv_field(FILE *f, const char *s)
{
    for (; s && *s; s++) {
        if (*s == '\t')
            fputs("\\t", f);
        else if (*s == '\n')
            fputs("\\n", f);
        else if (*s == '\r')
            fputs("\\r", f);
        else if (*s == '\\')
            fputs("\\\\", f);
        else
            fputc(*s, f);
    }
}

/* a field as written by tsv_field, back in place */
static void tsv_unescape(char *s)
{
    char *w = s;
    for (; *s; s++) {
        if (*s == '\\' && s[1]) {
            s++;
            *w++ = *s == 't' ? '\t' : *s == 'n' ? '\n' : *s == 'r' ? '\r' : *s;
        } else {
            *w++ = *s;
        }
    }
    *w = '\0';
}

typedef struct prev_row {
    char *out, *status, *encoder, *options;
    long long in_bytes, in_mtime_ns, cmz_bytes;
    char *line; /* the whole row, for the numbers an up-to-date model keeps */
} prev_row;

static const char summary_header[] =
    "input\toutput\tstatus\texit\tinput_bytes\tinput_mtime_ns\tcmz_bytes\tx_smaller\tfaces\tfaces_sent\tdeleted_pct"
    "\tkept\tleft_out\tworst_err_mm\tworst_err_pct_of_face\twarnings\tseconds\tencoder\toptions\tmessage";
enum { COL_INPUT, COL_OUTPUT, COL_STATUS, COL_EXIT, COL_IN_BYTES, COL_IN_MTIME, COL_CMZ_BYTES, COL_X, COL_FACES,
       COL_SENT, COL_DELETED, COL_KEPT, COL_LEFT_OUT, COL_ERR_MM, COL_ERR_PCT, COL_WARNINGS, COL_SECONDS, COL_ENCODER,
       COL_OPTIONS, COL_MESSAGE, COL_COUNT };

/* split a row in place at its tabs; the number of fields */
static int split_row(char *line, char **col, int max)
{
    int n = 0;
    col[n++] = line;
    for (char *p = line; *p && n < max; p++)
        if (*p == '\t') {
            *p = '\0';
            col[n++] = p + 1;
        }
    return n;
}

static long long number_or(const char *s, long long otherwise)
{
    char *end;
    long long v = strtoll(s, &end, 10);
    return end != s && *end == '\0' ? v : otherwise;
}

static void free_previous(prev_row *rows, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        free(rows[i].out), free(rows[i].status), free(rows[i].encoder), free(rows[i].options);
        free(rows[i].line);
    }
    free(rows);
}

static prev_row *read_previous(const char *path, size_t *count)
{
    *count = 0;
    FILE *f = fopen(path, "r");
    if (!f)
        return NULL;
    prev_row *rows = NULL;
    size_t cap = 0, n = 0;
    char *line = NULL;
    size_t lcap = 0;
    ssize_t len;
    int first = 1;
    while ((len = getline(&line, &lcap, f)) >= 0) {
        while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r'))
            line[--len] = '\0';
        if (first) {
            first = 0;
            if (strcmp(line, summary_header) != 0)
                break; /* another layout (an older cmz): nothing is skipped */
            continue;
        }
        char *copy = strdup(line);
        char *col[COL_COUNT];
        if (!copy)
            break;
        if (split_row(line, col, COL_COUNT) != COL_COUNT) {
            free(copy);
            continue;
        }
        if (n == cap) {
            size_t nc = cap ? 2 * cap : 64;
            prev_row *r = realloc(rows, nc * sizeof *r);
            if (!r) {
                free(copy);
                break;
            }
            rows = r;
            cap = nc;
        }
        prev_row *r = &rows[n];
        tsv_unescape(col[COL_OUTPUT]);
        r->line = copy;
        r->out = strdup(col[COL_OUTPUT]);
        r->status = strdup(col[COL_STATUS]);
        r->encoder = strdup(col[COL_ENCODER]);
        r->options = strdup(col[COL_OPTIONS]);
        r->in_bytes = number_or(col[COL_IN_BYTES], -1);
        r->in_mtime_ns = number_or(col[COL_IN_MTIME], -1);
        r->cmz_bytes = number_or(col[COL_CMZ_BYTES], -1);
        if (!r->out || !r->status || !r->encoder || !r->options) {
            free(r->out), free(r->status), free(r->encoder), free(r->options), free(copy);
            break;
        }
        n++;
    }
    free(line);
    fclose(f);
    *count = n;
    return rows;
}

/* the last run's row of the model that writes `out` (however the model's path was spelled then) */
static const prev_row *find_previous(const prev_row *rows, size_t n, const char *out)
{
    for (size_t i = n; i-- > 0;)
        if (strcmp(rows[i].out, out) == 0)
            return &rows[i];
    return NULL;
}

/* the same model (size and time, taken before its encode), this encoder, these options, and the output
   of the size that encode wrote */
static int up_to_date(const vault_job *j, const prev_row *p, const char *encoder, const char *options)
{
    struct stat so;
    if (!p || !j->have_stat || strstr(encoder, "-unknown") || strcmp(p->encoder, encoder) != 0 ||
        strcmp(p->options, options) != 0 || p->cmz_bytes <= 0)
        return 0;
    if (strcmp(p->status, "encoded") != 0 && strcmp(p->status, "up-to-date") != 0 &&
        strcmp(p->status, "not-run") != 0)
        return 0;
    return p->in_bytes == j->in_size && p->in_mtime_ns == j->in_mtime_ns && stat(j->out, &so) == 0 &&
           (long long)so.st_size == p->cmz_bytes;
}

/* ---- running the models ---- */

static volatile sig_atomic_t interrupted; /* the signal that stopped the vault, or 0 */

static void on_interrupt(int sig)
{
    interrupted = sig;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

typedef struct slot {
    pid_t pid;
    size_t job;
    FILE *err, *res; /* the child's stderr, and its cmd_encode_summary */
    double t0;
} slot;

/* in the child: encode one model, its messages into `err`, its summary into `res`; never returns */
static void run_child(const vault_job *j, const char **pass, int npass, const cmd_vault_opts *vo, slot *slots,
                      int nslots, const slot *mine, pid_t parent, const sigset_t *mask)
{
    /* (INT, TERM and HUP arrive blocked.)  Stopped with the vault, however the vault ends: a worker
       left behind would write an output the summary says was not made */
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    signal(SIGHUP, SIG_DFL);
    signal(SIGCHLD, SIG_DFL);
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent)
        _exit(128 + SIGTERM);
    sigprocmask(SIG_SETMASK, mask, NULL);
    int dn = open("/dev/null", O_WRONLY);
    if (dn >= 0) {
        dup2(dn, 1);
        close(dn);
    }
    dup2(fileno(mine->err), 2);
    for (int k = 0; k < nslots; k++) /* the other workers' files are theirs */
        if (&slots[k] != mine && slots[k].pid) {
            fclose(slots[k].err);
            fclose(slots[k].res);
        }
    if (vo->timeout_s > 0) {
        struct itimerval t = {{0, 0}, {(time_t)vo->timeout_s, (suseconds_t)((vo->timeout_s - (double)(time_t)vo->timeout_s) * 1e6)}};
        if (t.it_value.tv_sec == 0 && t.it_value.tv_usec == 0)
            t.it_value.tv_usec = 1;
        setitimer(ITIMER_REAL, &t, NULL); /* SIGALRM ends the encode: the parent names the timeout */
    }
    if (make_parents(j->out) != 0) {
        fprintf(stderr, "%s: %s: cannot make its folder: %s\n", cmd_prog, j->out, strerror(errno));
        _exit(EXIT_IO);
    }
    const char **argv = calloc((size_t)npass + 4, sizeof *argv);
    char *in = j->in[0] == '-' ? join3("./", j->in, "") : j->in; /* not an option */
    if (!argv || !in)
        _exit(EXIT_NOMEM);
    int n = 0;
    argv[n++] = in;
    argv[n++] = "-o";
    argv[n++] = j->out;
    for (int i = 0; i < npass; i++)
        argv[n++] = pass[i];
    static cmd_encode_summary sm;
    cmd_encode_summary_out = &sm;
    cmd_quiet = 1;
    int rc = cmd_encode(n, (char **)argv);
    if (rc == EXIT_OK && fwrite(&sm, sizeof sm, 1, mine->res) != 1)
        rc = EXIT_IO;
    fflush(NULL);
    _exit(rc);
}

static char *slurp(FILE *f)
{
    fflush(f);
    long n = ftell(f);
    if (n < 0)
        n = 0;
    char *s = malloc((size_t)n + 1);
    if (!s)
        return NULL;
    rewind(f);
    size_t got = fread(s, 1, (size_t)n, f);
    s[got] = '\0';
    return s;
}

/* the first line of a failure that is not a warning or a note, without "cmz: " */
static char *failure_line(const char *text)
{
    for (const char *p = text; p && *p;) {
        const char *e = strchr(p, '\n');
        size_t len = e ? (size_t)(e - p) : strlen(p);
        char *line = malloc(len + 1);
        if (!line)
            return NULL;
        memcpy(line, p, len);
        line[len] = '\0';
        if (len > 0 && !strstr(line, ": warning: ") && !strstr(line, ": note: ")) {
            if (strncmp(line, "cmz: ", 5) == 0)
                memmove(line, line + 5, len - 4);
            return line;
        }
        free(line);
        p = e ? e + 1 : NULL;
    }
    return NULL;
}

static int count_lines_with(const char *text, const char *what)
{
    int n = 0;
    for (const char *p = text; p && (p = strstr(p, what)); p += strlen(what))
        n++;
    return n;
}

/* write_atomic's temporary file (cmd_encode.c), the only thing a stopped encode leaves */
static void remove_temporary(const vault_job *j, pid_t pid)
{
    char tmp[32];
    snprintf(tmp, sizeof tmp, ".tmp%ld", (long)pid);
    char *t = join3(j->out, tmp, "");
    if (t)
        remove(t);
    free(t);
}

/* the child is done: its status, messages and log (OUT.log while there is something to say) */
static void finish(vault_job *j, slot *s, int wstatus, const cmd_vault_opts *vo)
{
    j->seconds = now_s() - s->t0;
    char *text = slurp(s->err);
    char *log = join3(j->out, ".log", "");
    if (WIFEXITED(wstatus) && WEXITSTATUS(wstatus) == 0) {
        rewind(s->res);
        if (fread(&j->sm, sizeof j->sm, 1, s->res) == 1) {
            j->status = JOB_ENCODED;
        } else {
            j->status = JOB_FAILED;
            j->message = join3(j->in, ": ", "the encoder finished without its summary");
        }
    } else if (WIFSIGNALED(wstatus) && interrupted) {
        j->status = JOB_NOT_RUN; /* stopped by the interrupt, not by its model: nothing to say of it */
        j->message = strdup("interrupted");
        remove_temporary(j, s->pid);
        free(text);
        text = NULL;
    } else {
        j->status = JOB_FAILED;
        char why[160];
        if (WIFSIGNALED(wstatus)) {
            int sig = WTERMSIG(wstatus);
            if (sig == SIGALRM)
                snprintf(why, sizeof why, "took longer than --timeout %g s: stopped", vo->timeout_s);
            else
                snprintf(why, sizeof why, "the encoder stopped on signal %d (%s)", sig, strsignal(sig));
            j->exit_code = 128 + sig;
            j->message = join3(j->in, ": ", why);
            remove_temporary(j, s->pid);
            if (text && j->message) {
                char *more = join3(text, "cmz: ", j->message);
                free(text);
                text = more ? join3(more, "\n", "") : NULL;
                free(more);
            }
        } else {
            j->exit_code = WEXITSTATUS(wstatus);
            j->message = text ? failure_line(text) : NULL;
            if (!j->message) {
                snprintf(why, sizeof why, "exit status %d", j->exit_code);
                j->message = join3(j->in, ": ", why);
            }
        }
    }
    if (j->status == JOB_FAILED && WIFEXITED(wstatus) && WEXITSTATUS(wstatus) == EXIT_INPUT)
        remove(j->out); /* the model no longer reads: its last good encode would not be this model (a
                           timeout, a crash, memory or I/O says nothing of the model: its output stays) */
    j->warnings = text ? count_lines_with(text, ": warning: ") : 0;
    if (log && j->status != JOB_NOT_RUN) {
        if (text && text[0] && make_parents(log) == 0) {
            FILE *f = fopen(log, "w");
            if (f) {
                fputs(text, f);
                fclose(f);
            }
        } else {
            remove(log);
        }
    }
    if (j->status == JOB_FAILED && text && !cmd_quiet)
        fputs(text, stderr); /* with its warnings; -q: only the list of failures at the end */
    else if (j->warnings > 0 && !cmd_quiet)
        fprintf(stderr, "%s: %s: %d warning%s (%s)\n", cmd_prog, j->in, j->warnings, j->warnings == 1 ? "" : "s",
                log ? log : "");
    free(log);
    free(text);
    fclose(s->err);
    fclose(s->res);
    s->pid = 0;
}

static void progress(size_t done, size_t total, const size_t count[], double t0)
{
    if (cmd_quiet || !isatty(2))
        return;
    int width = 24, fill = total ? (int)((double)width * (double)done / (double)total) : width;
    double el = now_s() - t0;
    char eta[32] = "";
    if (done > 0 && done < total)
        snprintf(eta, sizeof eta, ", about %.0f s left", el / (double)done * (double)(total - done));
    fprintf(stderr, "\r\033[K[%.*s%*s] %zu/%zu models: %zu encoded, %zu up to date, %zu failed, %.0f s%s", fill,
            "########################", width - fill, "", done, total, count[JOB_ENCODED], count[JOB_UP_TO_DATE],
            count[JOB_FAILED], el, eta);
}

static void clear_progress(void)
{
    if (!cmd_quiet && isatty(2))
        fprintf(stderr, "\r\033[K");
}

/* ---- the summary ---- */

static void write_row(FILE *f, const vault_job *j, const prev_row *carried, const char *encoder, const char *options)
{
    if ((j->status == JOB_UP_TO_DATE || j->status == JOB_NOT_RUN) && carried && carried->cmz_bytes > 0) {
        /* the numbers of the run that built it; the status says it was not encoded again (up to date,
           or this run did not reach it: the next run may still find it up to date) */
        char *copy = strdup(carried->line);
        char *col[COL_COUNT];
        if (copy && split_row(copy, col, COL_COUNT) == COL_COUNT) {
            for (int c = 0; c < COL_COUNT; c++) {
                if (c)
                    fputc('\t', f);
                if (c == COL_STATUS)
                    fputs(job_status_name[j->status], f);
                else if (c == COL_INPUT)
                    tsv_field(f, j->in);
                else if (c == COL_MESSAGE && j->status == JOB_NOT_RUN)
                    tsv_field(f, j->message ? j->message : "");
                else
                    fputs(col[c], f);
            }
            fputc('\n', f);
            free(copy);
            return;
        }
        free(copy);
    }
    tsv_field(f, j->in);
    fputc('\t', f);
    tsv_field(f, j->out);
    fprintf(f, "\t%s\t%d", job_status_name[j->status], j->exit_code);
    if (j->have_stat)
        fprintf(f, "\t%lld\t%lld", j->in_size, j->in_mtime_ns);
    else
        fputs("\t-\t-", f);
    if (j->status == JOB_ENCODED) {
        const cmd_encode_summary *s = &j->sm;
        int faces = s->faces_sent + s->faces_placed;
        fprintf(f, "\t%ld\t%.1f\t%d\t%d\t%.1f\t%d\t%d\t%.4g\t%.4g", s->cmz_bytes,
                s->cmz_bytes ? (double)j->in_size / (double)s->cmz_bytes : 0.0, faces, s->faces_sent,
                s->faces_sent ? 100.0 * (double)(s->faces_sent - s->kept) / (double)s->faces_sent : 100.0, s->kept,
                s->left_out, s->max_err_mm, 100.0 * s->max_ratio);
    } else {
        fputs("\t-\t-\t-\t-\t-\t-\t-\t-\t-", f);
    }
    fprintf(f, "\t%d\t%.2f\t", j->warnings, j->seconds);
    tsv_field(f, j->status == JOB_NOT_RUN ? "-" : encoder);
    fputc('\t', f);
    tsv_field(f, options);
    fputc('\t', f);
    tsv_field(f, j->message ? j->message : "");
    fputc('\n', f);
}

static int write_summary(const char *path, const job_list *l, const prev_row *prev, size_t nprev, const char *encoder,
                         const char *options)
{
    char suffix[32];
    snprintf(suffix, sizeof suffix, ".tmp%ld", (long)getpid());
    char *tmp = join3(path, suffix, "");
    if (!tmp || make_parents(path) != 0) {
        free(tmp);
        return -1;
    }
    FILE *f = fopen(tmp, "w");
    if (!f) {
        free(tmp);
        return -1;
    }
    fprintf(f, "%s\n", summary_header);
    for (size_t i = 0; i < l->n; i++)
        write_row(f, &l->v[i], find_previous(prev, nprev, l->v[i].out), encoder, options);
    int ok = !ferror(f);
    if (fclose(f) != 0)
        ok = 0;
    if (!ok || rename(tmp, path) != 0) {
        remove(tmp);
        free(tmp);
        return -1;
    }
    free(tmp);
    return 0;
}

/* start model `next` in a free slot: 0, or -1 (errno set) when no worker could be started */
static int launch(job_list *l, size_t next, slot *slots, int nslots, const char **pass, int npass,
                  const cmd_vault_opts *vo)
{
    int k = 0;
    while (slots[k].pid)
        k++;
    slot *s = &slots[k];
    stat_input(&l->v[next]); /* what the summary records: the model as this encode reads it */
    s->err = tmpfile();
    s->res = s->err ? tmpfile() : NULL;
    if (!s->res) {
        int e = errno;
        if (s->err)
            fclose(s->err);
        errno = e;
        return -1;
    }
    s->job = next;
    s->t0 = now_s();
    fflush(NULL); /* a child must not write the parent's buffered output again */
    pid_t parent = getpid();
    sigset_t stop, was;
    sigemptyset(&stop);
    sigaddset(&stop, SIGINT);
    sigaddset(&stop, SIGTERM);
    sigaddset(&stop, SIGHUP);
    sigprocmask(SIG_BLOCK, &stop, &was); /* a ^C between fork and the child's own handlers is not lost */
    pid_t pid = fork();
    if (pid == 0)
        run_child(&l->v[next], pass, npass, vo, slots, nslots, s, parent, &was);
    sigprocmask(SIG_SETMASK, &was, NULL);
    if (pid < 0) {
        int e = errno;
        fclose(s->err);
        fclose(s->res);
        errno = e;
        return -1;
    }
    s->pid = pid;
    return 0;
}

int cmd_vault(const cmd_vault_opts *vo, const char **pass, int npass)
{
    job_list all = {0};
    int rc = vo->list ? read_list(vo->list, &all) : walk_folder(vo->folder, NULL, &all);
    for (size_t i = 0; rc == EXIT_OK && i < all.n; i++)
        stat_input(&all.v[i]);
    /* the outputs are named over all the models, so that a shard names them as the whole run would */
    char *out = folder_spelling(vo->out);
    if (!out)
        rc = EXIT_NOMEM;
    if (rc == EXIT_OK && name_outputs(&all, out) != 0)
        rc = EXIT_NOMEM;
    /* this task's share (--shard K/N: a batch engine's task K of N), by a hash of the model's place in
       the tree: a model stays in its shard when others are added or removed */
    job_list l = {0};
    for (size_t i = 0; rc == EXIT_OK && i < all.n; i++) {
        const char *rel = all.v[i].rel;
        if (vo->shard_n && cm_crc32_update(0, (const uint8_t *)rel, strlen(rel)) % (uint32_t)vo->shard_n !=
                               (uint32_t)vo->shard_k)
            continue;
        if (move_job(&l, &all.v[i]))
            rc = EXIT_NOMEM;
    }
    free_jobs(&all);
    const char *from = vo->list ? (strcmp(vo->list, "-") == 0 ? "the list on stdin" : vo->list) : vo->folder;
    if (rc == EXIT_OK && l.n == 0 && !vo->shard_n) {
        fprintf(stderr, "%s: %s: no IGES or STEP model (*.igs, *.iges, *.stp, *.step, *.p21)%s\n", cmd_prog, from,
                vo->list ? " listed" : " in the folder");
        rc = EXIT_INPUT;
    }
    char summary_default[64] = "cmz-vault.tsv";
    if (vo->shard_n)
        snprintf(summary_default, sizeof summary_default, "cmz-vault.%d-of-%d.tsv", vo->shard_k, vo->shard_n);
    char *summary = !out ? NULL : vo->summary ? strdup(vo->summary) : join3(out, "/", summary_default);
    size_t olen = 1;
    for (int i = 0; i < npass; i++)
        olen += strlen(pass[i]) + 1;
    char *options = malloc(olen);
    if (rc == EXIT_OK && (!summary || !options))
        rc = EXIT_NOMEM;
    if (rc != EXIT_OK) {
        free(summary);
        free(out);
        free(options);
        free_jobs(&l);
        return rc;
    }
    options[0] = '\0';
    for (int i = 0; i < npass; i++) {
        if (i)
            strcat(options, " ");
        strcat(options, pass[i]);
    }
    char encoder[96];
    encoder_id(encoder, sizeof encoder);
    size_t nprev = 0;
    prev_row *prev = read_previous(summary, &nprev); /* --force skips nothing, but an interrupted run's rows
                                                          still carry what the last one knew */

    size_t count[5] = {0};
    for (size_t i = 0; i < l.n; i++) {
        vault_job *j = &l.v[i];
        if (j->status == JOB_FAILED)
            count[JOB_FAILED]++; /* a folder or link that cannot be read */
        else if (!vo->force && up_to_date(j, find_previous(prev, nprev, j->out), encoder, options)) {
            j->status = JOB_UP_TO_DATE;
            count[JOB_UP_TO_DATE]++;
        }
    }

    struct sigaction sa, old_int, old_term, old_hup;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_interrupt; /* no SA_RESTART: waitpid returns to look at the flag */
    sigemptyset(&sa.sa_mask);
    interrupted = 0;
    sigaction(SIGINT, &sa, &old_int);
    sigaction(SIGTERM, &sa, &old_term);
    sigaction(SIGHUP, &sa, &old_hup);
    struct sigaction child_default, old_chld;
    memset(&child_default, 0, sizeof child_default);
    child_default.sa_handler = SIG_DFL; /* an inherited SIG_IGN would let the kernel reap the workers */
    sigemptyset(&child_default.sa_mask);
    sigaction(SIGCHLD, &child_default, &old_chld);

    int jobs = vo->jobs < 1 ? 1 : vo->jobs;
    slot *slots = calloc((size_t)jobs, sizeof *slots);
    double t0 = now_s();
    size_t next = 0, running = 0, done = count[JOB_UP_TO_DATE] + count[JOB_FAILED];
    int stopped = 0, cannot_start = 0, signalled = 0;
    char start_error[128] = "";
    if (!slots)
        rc = EXIT_NOMEM;
    progress(done, l.n, count, t0);
    while (slots) {
        if (interrupted && !signalled) { /* the workers stop with the vault (the terminal's ^C reached them) */
            for (int k = 0; k < jobs; k++)
                if (slots[k].pid)
                    kill(slots[k].pid, SIGTERM);
            signalled = 1;
        }
        while (!interrupted && !stopped && !cannot_start && running < (size_t)jobs && next < l.n) {
            if (l.v[next].status != JOB_PENDING) {
                next++;
                continue;
            }
            if (launch(&l, next, slots, jobs, pass, npass, vo) != 0) {
                /* out of processes or temporary files: wait for a worker to end, else give up */
                if (running == 0) {
                    snprintf(start_error, sizeof start_error, "%s", strerror(errno));
                    stopped = 1;
                } else {
                    cannot_start = 1;
                }
                break;
            }
            running++;
            next++;
        }
        if (running == 0)
            break;
        int wstatus;
        pid_t pid = waitpid(-1, &wstatus, 0);
        if (pid < 0 && errno == ECHILD) {
            /* no worker left to wait for (SIGCHLD was ignored: the kernel reaped them): say so */
            for (int k = 0; k < jobs; k++)
                if (slots[k].pid) {
                    vault_job *j = &l.v[slots[k].job];
                    j->status = JOB_FAILED;
                    j->message = join3(j->in, ": ", "its worker's end was not seen (SIGCHLD ignored?)");
                    fclose(slots[k].err);
                    fclose(slots[k].res);
                    slots[k].pid = 0;
                    count[JOB_FAILED]++;
                    running--;
                    done++;
                }
            stopped = 1;
            continue;
        }
        if (pid < 0)
            continue; /* EINTR: the loop looks at the flag */
        for (int k = 0; k < jobs; k++)
            if (slots[k].pid == pid) {
                vault_job *j = &l.v[slots[k].job];
                clear_progress();
                finish(j, &slots[k], wstatus, vo);
                count[j->status]++;
                running--;
                done++;
                cannot_start = 0;
                progress(done, l.n, count, t0);
            }
    }
    clear_progress();
    sigaction(SIGINT, &old_int, NULL);
    sigaction(SIGTERM, &old_term, NULL);
    sigaction(SIGHUP, &old_hup, NULL);
    sigaction(SIGCHLD, &old_chld, NULL);
    for (size_t i = 0; i < l.n; i++)
        if (l.v[i].status == JOB_PENDING) {
            l.v[i].status = JOB_NOT_RUN;
            l.v[i].message = start_error[0] ? join3("not started: ", start_error, "") : strdup("interrupted");
            count[JOB_NOT_RUN]++;
        }

    long long in_total = 0, out_total = 0;
    for (size_t i = 0; i < l.n; i++) {
        const vault_job *j = &l.v[i];
        if (j->status == JOB_ENCODED) {
            in_total += j->in_size;
            out_total += j->sm.cmz_bytes;
        } else if (j->status == JOB_UP_TO_DATE) {
            const prev_row *p = find_previous(prev, nprev, j->out);
            in_total += p ? p->in_bytes : 0;
            out_total += p ? p->cmz_bytes : 0;
        }
    }
    int wrote = write_summary(summary, &l, prev, nprev, encoder, options);
    char not_run[128] = "";
    if (count[JOB_NOT_RUN])
        snprintf(not_run, sizeof not_run, ", %zu not run (%s)", count[JOB_NOT_RUN],
                 start_error[0] ? "no worker could be started" : "interrupted");
    printf("%s -> %s: %zu models: %zu encoded, %zu up to date, %zu failed%s; %lld bytes -> %lld (%.1fx); %.0f s; "
           "summary %s\n",
           from, out, l.n, count[JOB_ENCODED], count[JOB_UP_TO_DATE], count[JOB_FAILED], not_run, in_total,
           out_total, out_total ? (double)in_total / (double)out_total : 0.0, now_s() - t0, summary);
    fflush(stdout);
    for (size_t i = 0; i < l.n; i++)
        if (l.v[i].status == JOB_FAILED)
            fprintf(stderr, "%s: failed: %s\n", cmd_prog, l.v[i].message ? l.v[i].message : l.v[i].in);
    if (start_error[0])
        fprintf(stderr, "%s: cannot start a worker: %s\n", cmd_prog, start_error);
    if (wrote != 0) {
        fprintf(stderr, "%s: writing the summary %s failed: %s\n", cmd_prog, summary, strerror(errno));
        if (rc == EXIT_OK)
            rc = EXIT_IO;
    }
    if (interrupted)
        rc = 128 + interrupted;
    else if (rc == EXIT_OK && start_error[0])
        rc = EXIT_NOMEM;
    else if (rc == EXIT_OK && count[JOB_FAILED] > 0)
        rc = EXIT_INPUT;
    free_previous(prev, nprev);
    free(slots);
    free(summary);
    free(out);
    free(options);
    free_jobs(&l);
    return rc;
}
