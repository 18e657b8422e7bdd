/*
 * cmd_vault.c - `cmz encode FOLDER|--list FILE -o OUTFOLDER [-j N]`: encode
 * a design department's whole vault, one model per worker process.
 *
 * Each model is encoded by `cmz encode MODEL -o OUT` (cmd_encode.c) run in a
 * child process of its own: a model that fails, crashes or runs past
 * --timeout is named in the summary and the exit status while the rest still
 * encode, and nothing of it is left behind but its messages.  The outputs
 * mirror the input tree (`a/b/part.igs` -> `OUT/a/b/part.cmz`; two models of
 * one stem in one folder keep their extension: `part.igs.cmz`,
 * `part.stp.cmz`).
 *
 * The summary (`OUT/cmz-vault.tsv` unless --summary) has a row per model:
 * sizes, the share of faces whose surface is deleted, the worst rebuilt
 * face's deviation, seconds, the encoder and options it was built with, and
 * the error of a model that failed.  It is also the record that lets the next
 * run skip a model: its output exists, is newer than the model, has the size
 * recorded, and was built by this same encoder binary with the same options
 * (--force encodes everything again).
 *
 * Processes, not threads: the importers and the encoder keep per-thread
 * caches and process-wide state (cmd.h), a crash or a runaway model cannot
 * take the others with it, and a batch engine (README) runs the same command
 * on many machines with --shard K/N.
 */
#define _XOPEN_SOURCE 700
#include "cmd.h"

#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
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
    int status;
    int exit_code;
    double seconds;
    int warnings;
    cmd_encode_summary sm;
    char *message; /* a failure's first error line, or a carried row's message */
} vault_job;

typedef struct job_list {
    vault_job *v;
    size_t n, cap;
} job_list;

static job_list found;   /* nftw's callback has no context argument */
static const char *walk_root;   /* the folder walked */
static const char *walk_prefix; /* NULL, or a listed folder's place in the output tree */
static int by_in(const void *a, const void *b)
{
    return strcmp(((const vault_job *)a)->in, ((const vault_job *)b)->in);
}

static char *join3(const char *a, const char *b, const char *c)
{
    size_t n = strlen(a) + strlen(b) + strlen(c) + 1;
    char *s = malloc(n);
    if (s)
        snprintf(s, n, "%s%s%s", a, b, c);
    return s;
}

static int push_job(job_list *l, const char *in, const char *rel)
{
    if (l->n == l->cap) {
        size_t cap = l->cap ? 2 * l->cap : 64;
        vault_job *v = realloc(l->v, cap * sizeof *v);
        if (!v)
            return -1;
        l->v = v;
        l->cap = cap;
    }
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

static int walk_one(const char *path, const struct stat *sb, int type, struct FTW *ftw)
{
    (void)sb;
    if (type != FTW_F || !is_model_name(path + ftw->base))
        return 0;
    const char *rel = path + strlen(walk_root);
    while (*rel == '/')
        rel++;
    if (rel[0] == '.' || strstr(rel, "/.")) /* hidden: .git, .cache, an editor's copy */
        return 0;
    if (!walk_prefix || !walk_prefix[0])
        return push_job(&found, path, rel) ? 1 : 0;
    char *r = join3(walk_prefix, "/", rel);
    int bad = !r || push_job(&found, path, r);
    free(r);
    return bad;
}

/* every model under `folder` (sorted: the same order on every machine) into l, `prefix`/ before their
   place in the output tree */
static int walk_folder(const char *folder, const char *prefix, job_list *l)
{
    walk_root = folder;
    walk_prefix = prefix;
    found = (job_list){0};
    errno = 0;
    int rc = EXIT_OK;
    if (nftw(folder, walk_one, 32, FTW_PHYS) != 0) {
        fprintf(stderr, "%s: %s: %s\n", cmd_prog, folder, errno ? strerror(errno) : "out of memory");
        rc = errno ? EXIT_IO : EXIT_NOMEM;
    }
    qsort(found.v, found.n, sizeof *found.v, by_in);
    for (size_t i = 0; rc == EXIT_OK && i < found.n; i++)
        if (push_job(l, found.v[i].in, found.v[i].rel))
            rc = EXIT_NOMEM;
    for (size_t i = 0; i < found.n; i++)
        free(found.v[i].in), free(found.v[i].rel);
    free(found.v);
    found = (job_list){0};
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

static const vault_job *sort_jobs_by_out;
static int by_out(const void *a, const void *b)
{
    const vault_job *v = sort_jobs_by_out;
    int c = strcmp(v[*(const size_t *)a].out, v[*(const size_t *)b].out);
    return c ? c : (*(const size_t *)a > *(const size_t *)b) - (*(const size_t *)a < *(const size_t *)b);
}

static int by_rel(const void *a, const void *b)
{
    const vault_job *v = sort_jobs_by_out;
    int c = strcmp(v[*(const size_t *)a].rel, v[*(const size_t *)b].rel);
    return c ? c : (*(const size_t *)a > *(const size_t *)b) - (*(const size_t *)a < *(const size_t *)b);
}

/* one model listed twice (or under two spellings of its path) is encoded once, where first listed */
static int drop_duplicates(job_list *l)
{
    size_t *ix = malloc((l->n + 1) * sizeof *ix);
    if (!ix)
        return -1;
    for (size_t i = 0; i < l->n; i++)
        ix[i] = i;
    sort_jobs_by_out = l->v;
    qsort(ix, l->n, sizeof *ix, by_rel);
    for (size_t i = 0, first = 0; i + 1 < l->n; i++) {
        if (strcmp(l->v[ix[i]].rel, l->v[ix[i + 1]].rel) != 0) {
            first = i + 1;
            continue;
        }
        vault_job *twice = &l->v[ix[i + 1]];
        fprintf(stderr, "%s: note: %s is listed again as %s: encoded once\n", cmd_prog, l->v[ix[first]].in, twice->in);
        twice->status = JOB_DUPLICATE;
    }
    size_t w = 0;
    for (size_t i = 0; i < l->n; i++)
        if (l->v[i].status == JOB_DUPLICATE) {
            free(l->v[i].in), free(l->v[i].rel), free(l->v[i].out), free(l->v[i].message);
        } else {
            l->v[w++] = l->v[i];
        }
    l->n = w;
    free(ix);
    return 0;
}

/* OUT/rel with .cmz for the extension; where two models would share one output, both keep theirs */
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
        l->v[i].out = join3(out, "/", rel);
        free(rel);
        char *o = l->v[i].out ? join3(l->v[i].out, ".cmz", "") : NULL;
        free(l->v[i].out);
        if (!(l->v[i].out = o))
            return -1;
    }
    size_t *ix = malloc((l->n + 1) * sizeof *ix);
    if (!ix)
        return -1;
    for (size_t i = 0; i < l->n; i++)
        ix[i] = i;
    sort_jobs_by_out = l->v;
    qsort(ix, l->n, sizeof *ix, by_out);
    char *clash = calloc(l->n + 1, 1);
    if (!clash) {
        free(ix);
        return -1;
    }
    for (size_t i = 0; i + 1 < l->n; i++)
        if (strcmp(l->v[ix[i]].out, l->v[ix[i + 1]].out) == 0)
            clash[ix[i]] = clash[ix[i + 1]] = 1;
    for (size_t i = 0; i < l->n; i++) {
        if (!clash[i])
            continue;
        vault_job *j = &l->v[i];
        free(j->out);
        j->out = join3(out, "/", j->rel);
        char *o = j->out ? join3(j->out, ".cmz", "") : NULL;
        free(j->out);
        if (!(j->out = o)) {
            free(clash);
            free(ix);
            return -1;
        }
    }
    free(clash);
    free(ix);
    return 0;
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

/* tabs and line ends out of a field of the summary */
static void tsv_field(FILE *f, const char *s)
{
    for (; s && *s; s++)
        fputc(*s == '\t' || *s == '\n' || *s == '\r' ? ' ' : *s, f);
}

/* ---- the previous run's summary: what may be skipped ---- */

typedef struct prev_row {
    char *in, *status, *encoder, *options;
    long cmz_bytes;
    char *line; /* the whole row, for the numbers an up-to-date model keeps */
} prev_row;

static const char summary_header[] =
    "input\toutput\tstatus\texit\tinput_bytes\tcmz_bytes\tx_smaller\tfaces\tfaces_sent\tdeleted_pct\tkept"
    "\tleft_out\tworst_err_mm\tworst_err_pct_of_face\twarnings\tseconds\tencoder\toptions\tmessage";
enum { COL_INPUT, COL_OUTPUT, COL_STATUS, COL_EXIT, COL_IN_BYTES, COL_CMZ_BYTES, COL_X, COL_FACES, COL_SENT,
       COL_DELETED, COL_KEPT, COL_LEFT_OUT, COL_ERR_MM, COL_ERR_PCT, COL_WARNINGS, COL_SECONDS, COL_ENCODER,
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
        r->line = copy;
        r->in = strdup(col[COL_INPUT]);
        r->status = strdup(col[COL_STATUS]);
        r->encoder = strdup(col[COL_ENCODER]);
        r->options = strdup(col[COL_OPTIONS]);
        r->cmz_bytes = strtol(col[COL_CMZ_BYTES], NULL, 10);
        if (!r->in || !r->status || !r->encoder || !r->options) {
            free(r->in), free(r->status), free(r->encoder), free(r->options), free(copy);
            break;
        }
        n++;
    }
    free(line);
    fclose(f);
    *count = n;
    return rows;
}

static const prev_row *find_previous(const prev_row *rows, size_t n, const char *in)
{
    for (size_t i = n; i-- > 0;) /* the last row of a model wins */
        if (strcmp(rows[i].in, in) == 0)
            return &rows[i];
    return NULL;
}

/* a model whose output is newer, of the recorded size, and built by this encoder with these options */
static int up_to_date(const vault_job *j, const prev_row *p, const char *encoder, const char *options)
{
    struct stat si, so;
    if (!p || strstr(encoder, "-unknown") || strcmp(p->encoder, encoder) != 0 || strcmp(p->options, options) != 0 ||
        (strcmp(p->status, "encoded") != 0 && strcmp(p->status, "up-to-date") != 0 &&
         !(strcmp(p->status, "not-run") == 0 && p->cmz_bytes > 0)))
        return 0;
    if (stat(j->in, &si) != 0 || stat(j->out, &so) != 0 || so.st_size != p->cmz_bytes)
        return 0;
    return so.st_mtim.tv_sec > si.st_mtim.tv_sec ||
           (so.st_mtim.tv_sec == si.st_mtim.tv_sec && so.st_mtim.tv_nsec >= si.st_mtim.tv_nsec);
}

/* ---- running the models ---- */

static volatile sig_atomic_t interrupted;

static void on_interrupt(int sig)
{
    (void)sig;
    interrupted = 1;
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
static void run_child(const vault_job *j, const char **pass, int npass, const cmd_vault_opts *vo, FILE *err,
                      FILE *res)
{
    int dn = open("/dev/null", O_WRONLY);
    if (dn >= 0)
        dup2(dn, 1);
    dup2(fileno(err), 2);
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    if (vo->timeout_s > 0)
        alarm((unsigned)ceil(vo->timeout_s));
    if (make_parents(j->out) != 0) {
        fprintf(stderr, "%s: %s: cannot make its folder: %s\n", cmd_prog, j->out, strerror(errno));
        _exit(EXIT_IO);
    }
    const char **argv = calloc((size_t)npass + 4, sizeof *argv);
    if (!argv)
        _exit(EXIT_NOMEM);
    int n = 0;
    argv[n++] = j->in;
    argv[n++] = "-o";
    argv[n++] = j->out;
    for (int i = 0; i < npass; i++)
        argv[n++] = pass[i];
    static cmd_encode_summary sm;
    cmd_encode_summary_out = &sm;
    cmd_quiet = 1;
    int rc = cmd_encode(n, (char **)argv);
    if (rc == EXIT_OK && fwrite(&sm, sizeof sm, 1, res) != 1)
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
    const char *best = NULL;
    for (const char *p = text; p && *p;) {
        const char *e = strchr(p, '\n');
        size_t len = e ? (size_t)(e - p) : strlen(p);
        char line[1024];
        snprintf(line, sizeof line, "%.*s", (int)(len < sizeof line ? len : sizeof line - 1), p);
        if (len > 0 && !strstr(line, ": warning: ") && !strstr(line, ": note: ")) {
            best = p;
            break;
        }
        p = e ? e + 1 : NULL;
    }
    if (!best)
        return NULL;
    if (strncmp(best, "cmz: ", 5) == 0)
        best += 5;
    const char *e = strchr(best, '\n');
    size_t len = e ? (size_t)(e - best) : strlen(best);
    char *s = malloc(len + 1);
    if (s) {
        memcpy(s, best, len);
        s[len] = '\0';
    }
    return s;
}

static int count_lines_with(const char *text, const char *what)
{
    int n = 0;
    for (const char *p = text; p && (p = strstr(p, what)); p += strlen(what))
        n++;
    return n;
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
            j->message = strdup("the encoder finished without its summary");
        }
    } else if (WIFSIGNALED(wstatus) && interrupted) {
        j->status = JOB_NOT_RUN; /* stopped by the interrupt, not by its model: nothing to say of it */
        j->message = strdup("interrupted");
        char tmp[32];
        snprintf(tmp, sizeof tmp, ".tmp%ld", (long)s->pid);
        char *t = join3(j->out, tmp, "");
        if (t)
            remove(t);
        free(t);
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
            /* write_atomic's temporary file (cmd_encode.c) is the only thing a stopped encode leaves */
            char tmp[32];
            snprintf(tmp, sizeof tmp, ".tmp%ld", (long)s->pid);
            char *t = join3(j->out, tmp, "");
            if (t)
                remove(t);
            free(t);
            if (text) {
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
    j->warnings = text ? count_lines_with(text, ": warning: ") : 0;
    if (log && j->status != JOB_NOT_RUN) {
        if (text && text[0] && (j->status != JOB_FAILED || make_parents(log) == 0)) {
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
    if ((j->status == JOB_UP_TO_DATE || j->status == JOB_NOT_RUN) && carried) {
        /* the numbers of the run that built it; the status says it was not encoded again (up to date,
           or an interrupted run did not reach it: the next run may still find it up to date) */
        char *copy = strdup(carried->line);
        char *col[COL_COUNT];
        if (copy && split_row(copy, col, COL_COUNT) == COL_COUNT) {
            for (int c = 0; c < COL_COUNT; c++) {
                if (c)
                    fputc('\t', f);
                if (c == COL_STATUS)
                    fputs(job_status_name[j->status], f);
                else if (c == COL_MESSAGE && j->status == JOB_NOT_RUN)
                    fputs("interrupted", f);
                else if (c == COL_OUTPUT)
                    tsv_field(f, j->out);
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
    if (j->status == JOB_ENCODED) {
        const cmd_encode_summary *s = &j->sm;
        int faces = s->faces_sent + s->faces_placed;
        fprintf(f, "\t%ld\t%ld\t%.1f\t%d\t%d\t%.1f\t%d\t%d\t%.4g\t%.4g", s->in_bytes, s->cmz_bytes,
                s->cmz_bytes ? (double)s->in_bytes / (double)s->cmz_bytes : 0.0, faces, s->faces_sent,
                s->faces_sent ? 100.0 * (double)(s->faces_sent - s->kept) / (double)s->faces_sent : 100.0, s->kept,
                s->left_out, s->max_err_mm, 100.0 * s->max_ratio);
    } else {
        fputs("\t-\t-\t-\t-\t-\t-\t-\t-\t-\t-", f);
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
    char *tmp = join3(path, ".tmp", "");
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
        write_row(f, &l->v[i], find_previous(prev, nprev, l->v[i].in), encoder, options);
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

static void free_jobs(job_list *l)
{
    for (size_t i = 0; i < l->n; i++) {
        free(l->v[i].in);
        free(l->v[i].rel);
        free(l->v[i].out);
        free(l->v[i].message);
    }
    free(l->v);
    memset(l, 0, sizeof *l);
}

int cmd_vault(const cmd_vault_opts *vo, const char **pass, int npass)
{
    job_list all = {0};
    int rc = EXIT_OK;
    if (vo->list)
        rc = read_list(vo->list, &all);
    else
        rc = walk_folder(vo->folder, NULL, &all);
    /* the outputs are named over all the models, so that a shard names them as the whole run would */
    if (rc == EXIT_OK && name_outputs(&all, vo->out) != 0)
        rc = EXIT_NOMEM;
    /* this task's share of the models (--shard K/N: a batch engine's task K of N) */
    job_list l = {0};
    for (size_t i = 0; rc == EXIT_OK && i < all.n; i++)
        if (vo->shard_n == 0 || (int)(i % (size_t)vo->shard_n) == vo->shard_k) {
            if (push_job(&l, all.v[i].in, all.v[i].rel) || !(l.v[l.n - 1].out = strdup(all.v[i].out)))
                rc = EXIT_NOMEM;
        }
    free_jobs(&all);
    if (rc != EXIT_OK) {
        free_jobs(&l);
        return rc;
    }
    if (l.n == 0 && !vo->shard_n) {
        fprintf(stderr, "%s: %s: no IGES or STEP model (*.igs, *.iges, *.stp, *.step, *.p21)%s\n", cmd_prog,
                vo->list ? vo->list : vo->folder, vo->list ? " listed" : " in the folder");
        free_jobs(&l);
        return EXIT_INPUT;
    }
    char summary_default[64] = "cmz-vault.tsv";
    if (vo->shard_n)
        snprintf(summary_default, sizeof summary_default, "cmz-vault.%d-of-%d.tsv", vo->shard_k, vo->shard_n);
    char *summary = vo->summary ? strdup(vo->summary) : join3(vo->out, "/", summary_default);
    size_t olen = 1;
    for (int i = 0; i < npass; i++)
        olen += strlen(pass[i]) + 1;
    char *options = malloc(olen);
    if (!summary || !options) {
        free(summary);
        free(options);
        free_jobs(&l);
        return EXIT_NOMEM;
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
    prev_row *prev = vo->force ? NULL : read_previous(summary, &nprev);

    size_t count[5] = {0};
    for (size_t i = 0; i < l.n; i++)
        if (up_to_date(&l.v[i], find_previous(prev, nprev, l.v[i].in), encoder, options)) {
            l.v[i].status = JOB_UP_TO_DATE;
            count[JOB_UP_TO_DATE]++;
        }

    struct sigaction sa, old_int, old_term;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_interrupt; /* no SA_RESTART: waitpid returns to look at the flag */
    sigemptyset(&sa.sa_mask);
    interrupted = 0;
    sigaction(SIGINT, &sa, &old_int);
    sigaction(SIGTERM, &sa, &old_term);

    int jobs = vo->jobs < 1 ? 1 : vo->jobs;
    slot *slots = calloc((size_t)jobs, sizeof *slots);
    double t0 = now_s();
    size_t next = 0, running = 0, done = count[JOB_UP_TO_DATE];
    if (!slots)
        rc = EXIT_NOMEM;
    fflush(NULL); /* a child must not write the parent's buffered output again */
    progress(done, l.n, count, t0);
    while (rc == EXIT_OK) {
        while (!interrupted && running < (size_t)jobs && next < l.n) {
            if (l.v[next].status != JOB_PENDING) {
                next++;
                continue;
            }
            int k = 0;
            while (slots[k].pid)
                k++;
            slot *s = &slots[k];
            s->err = tmpfile();
            s->res = tmpfile();
            if (!s->err || !s->res) {
                fprintf(stderr, "%s: a temporary file: %s\n", cmd_prog, strerror(errno));
                if (s->err)
                    fclose(s->err);
                if (s->res)
                    fclose(s->res);
                rc = EXIT_IO;
                break;
            }
            s->job = next;
            s->t0 = now_s();
            pid_t pid = fork();
            if (pid == 0)
                run_child(&l.v[next], pass, npass, vo, s->err, s->res);
            if (pid < 0) {
                fprintf(stderr, "%s: fork: %s\n", cmd_prog, strerror(errno));
                fclose(s->err);
                fclose(s->res);
                rc = EXIT_NOMEM;
                break;
            }
            s->pid = pid;
            running++;
            next++;
        }
        if (running == 0)
            break;
        int wstatus;
        pid_t pid = waitpid(-1, &wstatus, 0);
        if (pid < 0) {
            if (errno == EINTR && interrupted)
                for (int k = 0; k < jobs; k++)
                    if (slots[k].pid)
                        kill(slots[k].pid, SIGTERM);
            continue;
        }
        for (int k = 0; k < jobs; k++)
            if (slots[k].pid == pid) {
                vault_job *j = &l.v[slots[k].job];
                clear_progress();
                finish(j, &slots[k], wstatus, vo);
                count[j->status]++;
                running--;
                done++;
                progress(done, l.n, count, t0);
            }
    }
    clear_progress();
    sigaction(SIGINT, &old_int, NULL);
    sigaction(SIGTERM, &old_term, NULL);
    for (size_t i = 0; i < l.n; i++)
        if (l.v[i].status == JOB_PENDING) {
            l.v[i].status = JOB_NOT_RUN;
            count[JOB_NOT_RUN]++;
        }

    long in_total = 0, out_total = 0;
    for (size_t i = 0; i < l.n; i++) {
        const vault_job *j = &l.v[i];
        if (j->status == JOB_ENCODED) {
            in_total += j->sm.in_bytes;
            out_total += j->sm.cmz_bytes;
        } else if (j->status == JOB_UP_TO_DATE) {
            const prev_row *p = find_previous(prev, nprev, j->in);
            char *copy = p ? strdup(p->line) : NULL;
            char *col[COL_COUNT];
            if (copy && split_row(copy, col, COL_COUNT) == COL_COUNT) {
                in_total += strtol(col[COL_IN_BYTES], NULL, 10);
                out_total += strtol(col[COL_CMZ_BYTES], NULL, 10);
            }
            free(copy);
        }
    }
    int wrote = write_summary(summary, &l, prev, nprev, encoder, options);
    char not_run[64] = "";
    if (count[JOB_NOT_RUN])
        snprintf(not_run, sizeof not_run, ", %zu not run (interrupted)", count[JOB_NOT_RUN]);
    printf("%s -> %s: %zu models: %zu encoded, %zu up to date, %zu failed%s; %ld bytes -> %ld (%.1fx); %.0f s; "
           "summary %s\n",
           vo->list ? vo->list : vo->folder, vo->out, l.n, count[JOB_ENCODED], count[JOB_UP_TO_DATE],
           count[JOB_FAILED], not_run, in_total, out_total,
           out_total ? (double)in_total / (double)out_total : 0.0, now_s() - t0, summary);
    fflush(stdout);
    for (size_t i = 0; i < l.n; i++)
        if (l.v[i].status == JOB_FAILED)
            fprintf(stderr, "%s: failed: %s\n", cmd_prog, l.v[i].message ? l.v[i].message : l.v[i].in);
    if (wrote != 0) {
        fprintf(stderr, "%s: writing the summary %s failed: %s\n", cmd_prog, summary, strerror(errno));
        if (rc == EXIT_OK)
            rc = EXIT_IO;
    }
    if (rc == EXIT_OK && count[JOB_FAILED] > 0)
        rc = EXIT_INPUT;
    if (rc == EXIT_OK && interrupted)
        rc = 128 + SIGINT;
    for (size_t i = 0; i < nprev; i++) {
        free(prev[i].in), free(prev[i].status), free(prev[i].encoder), free(prev[i].options);
        free(prev[i].line);
    }
    free(prev);
    free(slots);
    free(summary);
    free(options);
    free_jobs(&l);
    return rc;
}
