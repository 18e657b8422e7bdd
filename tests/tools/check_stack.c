/*
 * check_stack - stack gate for the decoder and kernels (make check-stack).
 *
 * Reads gcc's call graphs (-fcallgraph-info=su, one .ci file per object),
 * joins them into one graph and fails when
 *   - the graph has a cycle (recursion is forbidden: the stack must be
 *     bounded by a sum of frames),
 *   - a frame is unboundedly dynamic (VLA/alloca slipped through) or larger than
 *     --fn-max,
 *   - a call is indirect (its callee, hence its stack, is unknown) and
 *     --indirect FILE does not name where it goes: each line of FILE is
 *     `caller: callee callee ...` (function names; a static one matches in
 *     any file, so the bound stays conservative).  A caller that makes no
 *     indirect call, or a callee in no call graph, fails too, so the table
 *     stays true as the code changes; the callee `(platform)` says that the
 *     call leaves the decoder for a program's callback, whose frames the
 *     program gate (check-stack-programs, the callee named) counts,
 *   - the deepest call path, summed, exceeds --budget.
 * Calls out of the graph (libm, mem*) count as 0 bytes: check-noheap
 * restricts them to a short allowlist of leaf functions.
 *
 * This is a build tool, not decoder code: it may use the heap and stdio.
 */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct node {
    char *title;
    long bytes;   /* -1: not defined in any .ci (external) */
    int dynamic;
    int resolved; /* its indirect calls go where --indirect says */
    int nout;
    int *out;     /* callee node ids */
    int capout;
} node;

static node *nodes;
static int nnodes, capnodes;
static int failures;

static int node_id(const char *title)
{
    for (int i = 0; i < nnodes; i++)
        if (strcmp(nodes[i].title, title) == 0)
            return i;
    if (nnodes == capnodes) {
        capnodes = capnodes ? 2 * capnodes : 256;
        nodes = realloc(nodes, (size_t)capnodes * sizeof *nodes);
        if (!nodes) {
            perror("check_stack");
            exit(2);
        }
    }
    node *n = &nodes[nnodes];
    memset(n, 0, sizeof *n);
    n->title = strdup(title);
    n->bytes = -1;
    return nnodes++;
}

static void add_edge(int a, int b)
{
    node *n = &nodes[a];
    for (int i = 0; i < n->nout; i++)
        if (n->out[i] == b)
            return;
    if (n->nout == n->capout) {
        n->capout = n->capout ? 2 * n->capout : 8;
        n->out = realloc(n->out, (size_t)n->capout * sizeof *n->out);
        if (!n->out) {
            perror("check_stack");
            exit(2);
        }
    }
    n->out[n->nout++] = b;
}

/* copy the quoted value following `key` in line into buf; 0 if absent */
static int field(const char *line, const char *key, char *buf, size_t cap)
{
    const char *p = strstr(line, key);
    if (!p)
        return 0;
    p = strchr(p + strlen(key), '"');
    if (!p)
        return 0;
    p++;
    size_t k = 0;
    while (*p && *p != '"' && k + 1 < cap) {
        if (*p == '\\' && p[1] == '"')
            p++;
        buf[k++] = *p++;
    }
    buf[k] = 0;
    return 1;
}

static FILE *open_or_exit(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        perror(path);
        exit(2);
    }
    return f;
}

static void read_ci(const char *path)
{
    FILE *f = open_or_exit(path);
    char *line = NULL;
    size_t cap = 0;
    char a[4096], b[4096];
    while (getline(&line, &cap, f) > 0) {
        if (strncmp(line, "node:", 5) == 0 && field(line, "title:", a, sizeof a)) {
            int id = node_id(a);
            if (field(line, "label:", b, sizeof b)) {
                char *bytes = strstr(b, " bytes (");
                if (bytes) {
                    char *s = bytes;
                    while (s > b && s[-1] >= '0' && s[-1] <= '9')
                        s--;
                    nodes[id].bytes = strtol(s, NULL, 10);
                    /* "static" and "dynamic,bounded" (gcc knows the bound, e.g. for
                     * argument pushes) are fine; plain "dynamic" is a VLA/alloca */
                    nodes[id].dynamic = strncmp(bytes + 8, "static", 6) != 0 &&
                                        strncmp(bytes + 8, "dynamic,bounded", 15) != 0;
                }
            }
        } else if (strncmp(line, "edge:", 5) == 0 && field(line, "sourcename:", a, sizeof a) &&
                   field(line, "targetname:", b, sizeof b)) {
            int s = node_id(a), t = node_id(b);
            add_edge(s, t);
        }
    }
    free(line);
    fclose(f);
}

static const char *short_name(const char *title)
{
    const char *c = strrchr(title, ':');
    return c ? c + 1 : title;
}

/* a function's name without its file and without gcc's clone suffixes (.constprop.0, .part.1, .isra.0) */
static void base_name(const char *title, char *buf, size_t cap)
{
    snprintf(buf, cap, "%s", short_name(title));
    char *dot = strchr(buf, '.');
    if (dot)
        *dot = '\0';
}

/* --indirect FILE: every indirect call of a listed caller becomes calls to its listed callees */
static void resolve_indirect(const char *path, int indirect)
{
    FILE *f = open_or_exit(path);
    char *line = NULL;
    size_t cap = 0;
    int lineno = 0;
    while (getline(&line, &cap, f) > 0) {
        lineno++;
        char *colon = strchr(line, ':');
        if (line[0] == '#' || !colon)
            continue;
        *colon = '\0';
        char caller[256], nm[256];
        if (sscanf(line, "%255s", caller) != 1)
            continue;
        char *callee[64];
        int ncallee = 0;
        char *save = NULL;
        for (char *c = strtok_r(colon + 1, " \t\r\n", &save); c && ncallee < 64; c = strtok_r(NULL, " \t\r\n", &save))
            callee[ncallee++] = c;
        int callers = 0;
        for (int m = 0; m < nnodes; m++) {
            base_name(nodes[m].title, nm, sizeof nm);
            int calls_through = 0;
            for (int k = 0; k < nodes[m].nout; k++)
                calls_through |= nodes[m].out[k] == indirect;
            if (strcmp(nm, caller) != 0 || !calls_through)
                continue;
            callers++;
            nodes[m].resolved = 1;
            for (int e = 0; e < ncallee; e++) {
                /* "(platform)": the decoder calls back into a program (its mesh spill); the frames
                   there are check-stack-programs', whose table names the callee */
                int found = strcmp(callee[e], "(platform)") == 0;
                for (int c = 0; c < nnodes; c++) {
                    base_name(nodes[c].title, nm, sizeof nm);
                    if (strcmp(nm, callee[e]) == 0 && nodes[c].bytes >= 0) {
                        add_edge(m, c);
                        found = 1;
                    }
                }
                if (!found && callers == 1) {
                    printf("check-stack: %s line %d: %s's callee %s is in no call graph read\n", path, lineno, caller,
                           callee[e]);
                    failures++;
                }
            }
        }
        if (!callers) {
            printf("check-stack: %s line %d: %s makes no indirect call in the graphs read (a stale line)\n", path,
                   lineno, caller);
            failures++;
        }
    }
    free(line);
    fclose(f);
}

int main(int argc, char **argv)
{
    long fn_max = 0, budget = 0;
    const char *indirect_table = NULL;
    int i = 1;
    for (; i < argc; i++) {
        if (strcmp(argv[i], "--fn-max") == 0 && i + 1 < argc)
            fn_max = strtol(argv[++i], NULL, 10);
        else if (strcmp(argv[i], "--budget") == 0 && i + 1 < argc)
            budget = strtol(argv[++i], NULL, 10);
        else if (strcmp(argv[i], "--indirect") == 0 && i + 1 < argc)
            indirect_table = argv[++i];
        else
            break;
    }
    if (fn_max <= 0 || budget <= 0 || i >= argc) {
        fprintf(stderr, "usage: check_stack --fn-max BYTES --budget BYTES [--indirect FILE] FILE.ci...\n");
        return 2;
    }
    for (; i < argc; i++)
        read_ci(argv[i]);
    int indirect = -1;
    for (int n = 0; n < nnodes; n++)
        if (strstr(nodes[n].title, "__indirect_call"))
            indirect = n;
    if (indirect_table && indirect >= 0)
        resolve_indirect(indirect_table, indirect);
    else if (indirect_table) {
        printf("check-stack: %s: no indirect call in the graphs read (the table is stale)\n", indirect_table);
        failures++;
    }

    long maxframe = 0;
    int maxframe_id = -1;
    for (int n = 0; n < nnodes; n++) {
        node *x = &nodes[n];
        if (n == indirect) {
            for (int m = 0; m < nnodes; m++)
                for (int k = 0; k < nodes[m].nout; k++)
                    if (nodes[m].out[k] == n && !nodes[m].resolved) {
                        printf("check-stack: %s makes an indirect call (callee stack unknown)\n",
                               short_name(nodes[m].title));
                        failures++;
                    }
            continue;
        }
        if (x->bytes < 0)
            continue;
        if (x->dynamic) {
            printf("check-stack: %s has a dynamic stack frame\n", short_name(x->title));
            failures++;
        }
        if (x->bytes > fn_max) {
            printf("check-stack: %s uses %ld bytes > CM_STACK_FN_MAX %ld\n", short_name(x->title), x->bytes, fn_max);
            failures++;
        }
        if (x->bytes > maxframe) {
            maxframe = x->bytes;
            maxframe_id = n;
        }
    }

    /* iterative DFS: colour 0 new, 1 on the stack, 2 done; worst[] = deepest path from the node */
    int *colour = calloc((size_t)nnodes, sizeof *colour);
    long *worst = calloc((size_t)nnodes, sizeof *worst);
    int *next = calloc((size_t)nnodes, sizeof *next);
    int *via = malloc((size_t)nnodes * sizeof *via);
    int *stack = malloc((size_t)nnodes * sizeof *stack);
    if (!colour || !worst || !next || !via || !stack) {
        perror("check_stack");
        return 2;
    }
    for (int n = 0; n < nnodes; n++)
        via[n] = -1;
    for (int root = 0; root < nnodes; root++) {
        if (colour[root])
            continue;
        int sp = 0;
        stack[sp++] = root;
        colour[root] = 1;
        while (sp > 0) {
            int n = stack[sp - 1];
            if (next[n] < nodes[n].nout) {
                int c = nodes[n].out[next[n]++];
                if (colour[c] == 1) {
                    printf("check-stack: recursion: %s calls %s, which is on the call path:", short_name(nodes[n].title),
                           short_name(nodes[c].title));
                    for (int k = 0; k < sp; k++)
                        printf(" %s", short_name(nodes[stack[k]].title));
                    printf("\n");
                    failures++;
                } else if (colour[c] == 0) {
                    colour[c] = 1;
                    stack[sp++] = c;
                }
                continue;
            }
            long own = nodes[n].bytes > 0 ? nodes[n].bytes : 0, best = 0;
            for (int k = 0; k < nodes[n].nout; k++) {
                int c = nodes[n].out[k];
                if (colour[c] == 2 && worst[c] > best) {
                    best = worst[c];
                    via[n] = c;
                }
            }
            worst[n] = own + best;
            colour[n] = 2;
            sp--;
        }
    }
    int deepest = 0;
    for (int n = 1; n < nnodes; n++)
        if (worst[n] > worst[deepest])
            deepest = n;
    int defined = 0;
    for (int n = 0; n < nnodes; n++)
        defined += nodes[n].bytes >= 0;
    printf("check-stack: %d functions, largest frame %ld bytes (%s, limit %ld), deepest path %ld bytes (budget %ld):\n ",
           defined, maxframe, maxframe_id >= 0 ? short_name(nodes[maxframe_id].title) : "-", fn_max,
           nnodes ? worst[deepest] : 0L, budget);
    for (int n = deepest, k = 0; n >= 0 && k < nnodes; n = via[n], k++)
        printf(" %s(%ld)", short_name(nodes[n].title), nodes[n].bytes > 0 ? nodes[n].bytes : 0L);
    printf("\n");
    if (nnodes && worst[deepest] > budget) {
        printf("check-stack: deepest path %ld bytes exceeds CM_STACK_BUDGET %ld\n", worst[deepest], budget);
        failures++;
    }
    if (defined == 0) {
        printf("check-stack: no call graph read (was the code built with gcc -fcallgraph-info=su?)\n");
        failures++;
    }
    return failures ? 1 : 0;
}
