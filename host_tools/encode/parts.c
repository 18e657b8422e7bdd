/* parts.c - the model's parts, in the order of the terminal's assembly steps (issue 17; format 4.11).

   A part is what the CAD system made one: an outermost subfigure instance (IGES 408) or assembly
   occurrence (STEP), else a solid or shell (IGES 186/514, STEP's solid or shell model), else an
   associativity group listing the faces (IGES 402: how Open CASCADE writes a solid as trimmed
   surfaces); faces that none of these holds are joined by their edges (two faces sharing an edge of
   two uses), as the viewer would join them.  Each placed copy is a part of its own.  By default the
   parts come in file order (the top-level entity that imported them; a copy after the parts its
   instance's entity comes after); `cmz encode --steps FILE` puts the parts FILE names first, in its
   order, the others after them in file order.  The terminal's viewer steps through them in the order
   the file sends (cm_view_parts); a file without parts leaves the viewer its connected pieces.

   Measured where it matters: as1_pe_203's 19 associativity groups hold its 24 solids' faces (the
   viewer's connected pieces made 16 of them, faces of touching solids sharing edges). */
#include "encode_internal.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "iges/iges_file.h"
#include "step/step_file.h"

/* a face's or a copy's part before the parts are numbered: what holds it, and where it comes */
typedef struct part_key {
    long long key;  /* kind << 40 | id: 1 instance, 2 owner, 3 loose faces' first face; copies: 4 | k */
    long long top;  /* the import's ordinal of its top-level entity */
    int first;      /* its first face (a copy: after every face) */
    int item;       /* face f, or nfaces + k for copy k */
} part_key;

static int cmp_key(const void *a, const void *b)
{
    const part_key *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return (x->item > y->item) - (x->item < y->item);
}

static int cmp_order(const void *a, const void *b)
{
    const part_key *x = a, *y = b;
    if (x->top != y->top)
        return x->top < y->top ? -1 : 1;
    return (x->first > y->first) - (x->first < y->first);
}

static int root(int *up, int f)
{
    while (up[f] != f) {
        up[f] = up[up[f]];
        f = up[f];
    }
    return f;
}

/* the len bytes at t without their leading and trailing spaces, into out (0: nothing left) */
static int trimmed_name(const char *t, int len, char out[80])
{
    int at = 0;
    while (len > 0 && t[len - 1] == ' ')
        len--;
    while (at < len && t[at] == ' ')
        at++;
    if (len <= at)
        return 0;
    snprintf(out, 80, "%.*s", len - at, t + at);
    return 1;
}

/* STEP entity id's string parameter k, trimmed, into out (0: none or empty) */
static int step_name(const step_file *f, int id, int k, char out[80])
{
    const step_entity *e = id > 0 ? step_by_id(f, id) : NULL;
    const step_val *v = e && e->nparts > 0 ? step_item(&f->vals[f->parts[e->first_part].params], k) : NULL;
    return v && v->kind == STEP_STR && trimmed_name(f->text + v->text, v->len, out);
}

/* the names a part answers to in --steps: an IGES entity's label, a 408 instance's subfigure name too;
   STEP the name of the PRODUCT its faces' representation shapes (else its id), and the solid's or
   shell's own name (its first parameter, mostly empty) */
static int part_names(const loaded_model *lm, int owner, int product, char names[2][80])
{
    int n = 0;
    names[0][0] = names[1][0] = 0;
    if (lm->is_step) {
        const step_file *f = &lm->step;
        if (product > 0 && (step_name(f, product, 1, names[n]) || step_name(f, product, 0, names[n])))
            n++;
        if (owner > 0 && step_name(f, owner, 0, names[n]) && !(n == 1 && strcmp(names[0], names[1]) == 0))
            n++;
        return n;
    }
    if (owner <= 0)
        return 0;
    const iges_file *f = &lm->iges;
    const iges_entity *e = iges_by_de(f, owner);
    if (!e)
        return 0;
    n += trimmed_name(e->label, (int)strlen(e->label), names[n]);
    if (e->type == 408 && e->nparams > 0 && e->params[0].kind == IGES_P_NUM) {
        const iges_entity *d = iges_by_de(f, (int)e->params[0].num);
        if (d && d->type == 308 && d->nparams > 1 && d->params[1].kind == IGES_P_STR && d->params[1].len > 0)
            snprintf(names[n++], sizeof names[0], "%.*s", d->params[1].len, d->params[1].str);
    }
    return n;
}

/* the entity that names a part (its first face's owner; a copy's, its instance's), and its STEP
   product */
static int key_owner(const loaded_model *lm, const part_key *k, int *product)
{
    if (k->key >> 40 == 4) {
        *product = lm->brep.placements[k->key & 0xffffffffffLL].product;
        return lm->brep.placements[k->key & 0xffffffffffLL].owner;
    }
    const brep_face *bf = &lm->brep.faces[lm->mesh.faces[k->first].brep_face];
    *product = bf->product;
    return bf->owner;
}

void enc_parts_free(enc_parts *p)
{
    free(p->face_part);
    free(p->place_part);
    memset(p, 0, sizeof *p);
}

/* --steps: the parts FILE names, in its order; order[] is the default order (part numbers from 1),
   rewritten; why says what is wrong with the file */
static cm_err apply_steps(const loaded_model *lm, const char *path, const part_key *first_of, int nparts, int *order,
                          int *stepped, char *why, size_t whylen, cm_status *st)
{
    FILE *fp = fopen(path, "r");
    if (!fp) {
        snprintf(why, whylen, "--steps %s: cannot be read", path);
        return cm_fail(st, CM_E_IO, "steps file");
    }
    int *taken = calloc((size_t)nparts + 1, sizeof *taken), *out = malloc(((size_t)nparts + 1) * sizeof *out);
    if (!taken || !out) {
        fclose(fp);
        free(taken);
        free(out);
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    }
    char line[512];
    int n = 0, lineno = 0;
    cm_err e = CM_OK;
    while (e == CM_OK && fgets(line, sizeof line, fp)) {
        lineno++;
        size_t len = strlen(line);
        if (len == sizeof line - 1 && line[len - 1] != '\n') {
            snprintf(why, whylen, "--steps %s line %d: longer than %d characters", path, lineno, (int)sizeof line - 2);
            e = cm_fail(st, CM_E_ARG, "steps file");
            break;
        }
        while (len > 0 && isspace((unsigned char)line[len - 1]))
            line[--len] = 0;
        char *s = line;
        while (isspace((unsigned char)*s))
            s++;
        if (!*s)
            continue; /* blank lines separate nothing */
        int found = 0;
        char *end;
        long num = s[0] == '#' ? strtol(s + 1, &end, 10) : 0;
        if (s[0] == '#' && end != s + 1 && *end == 0) { /* "#N": the part the viewer numbers N without --steps */
            if (num < 1 || num > nparts) {
                snprintf(why, whylen, "--steps %s line %d: there is no part %s (the model has %d)", path, lineno, s,
                         nparts);
                e = cm_fail(st, CM_E_ARG, "steps file");
            } else if (taken[order[num - 1]]) {
                snprintf(why, whylen, "--steps %s line %d: part %s is already a step", path, lineno, s);
                e = cm_fail(st, CM_E_ARG, "steps file");
            } else {
                found = order[num - 1]; /* (its provisional number) */
            }
        } else { /* a name: the first part in file order that answers to it and is no step yet */
            for (int i = 0; i < nparts && !found; i++) {
                int p = order[i];
                if (taken[p])
                    continue;
                char names[2][80];
                int product, owner = key_owner(lm, &first_of[p], &product);
                int nn = part_names(lm, owner, product, names);
                for (int k = 0; k < nn && !found; k++)
                    if (strcmp(names[k], s) == 0)
                        found = p;
            }
            if (!found) {
                snprintf(why, whylen, "--steps %s line %d: no part (left) is named \"%.100s\" (`cmz info MODEL --parts` lists them)",
                         path, lineno, s);
                e = cm_fail(st, CM_E_ARG, "steps file");
            }
        }
        if (found) {
            taken[found] = 1;
            out[n++] = found;
        }
    }
    if (e == CM_OK && ferror(fp)) {
        snprintf(why, whylen, "--steps %s: read error", path);
        e = cm_fail(st, CM_E_IO, "steps file");
    }
    fclose(fp);
    if (e == CM_OK) {
        *stepped = n;
        for (int i = 0; i < nparts; i++)
            if (!taken[order[i]])
                out[n++] = order[i];
        memcpy(order, out, (size_t)nparts * sizeof *order);
    }
    free(taken);
    free(out);
    return e;
}

cm_err enc_parts_build(const loaded_model *lm, const char *steps, enc_parts *p, char *why, size_t whylen,
                       cm_status *st)
{
    memset(p, 0, sizeof *p);
    const cmesh *cm = &lm->mesh;
    const int nf = cm->nfaces, npl = lm->brep.nplacements, n = nf + npl;
    part_key *k = malloc(((size_t)n + 1) * sizeof *k);
    int *up = malloc(((size_t)nf + 1) * sizeof *up), *edge_face = malloc(((size_t)cm->nedges + 1) * sizeof *edge_face);
    int *edge_uses = calloc((size_t)cm->nedges + 1, sizeof *edge_uses);
    int *num = malloc(((size_t)n + 1) * sizeof *num), *order = NULL;
    part_key *first_of = NULL;
    p->face_part = calloc((size_t)nf + 1, sizeof *p->face_part);
    p->place_part = calloc((size_t)npl + 1, sizeof *p->place_part);
    cm_err e = CM_OK;
    if (!k || !up || !edge_face || !edge_uses || !num || !p->face_part || !p->place_part) {
        e = cm_fail(st, CM_E_NOMEM, "out of memory");
        goto done;
    }
    /* loose faces joined by their edges of two uses */
    for (int f = 0; f < nf; f++)
        up[f] = f;
    for (int f = 0; f < nf; f++) {
        const cmesh_face *cf = &cm->faces[f];
        for (int l = 0; l < cf->nloops; l++) {
            const cmesh_loop *cl = &cm->loops[cf->first_loop + l];
            for (int i = 0; i < cl->n; i++)
                edge_uses[cm->uses[cl->first + i].edge]++;
        }
    }
    for (int ed = 0; ed < cm->nedges; ed++)
        edge_face[ed] = -1;
    for (int f = 0; f < nf; f++) {
        const brep_face *bf = &lm->brep.faces[cm->faces[f].brep_face];
        if (bf->instance != 0 || bf->owner != 0)
            continue;
        const cmesh_face *cf = &cm->faces[f];
        for (int l = 0; l < cf->nloops; l++) {
            const cmesh_loop *cl = &cm->loops[cf->first_loop + l];
            for (int i = 0; i < cl->n; i++) {
                int ed = cm->uses[cl->first + i].edge;
                if (edge_uses[ed] != 2)
                    continue;
                if (edge_face[ed] < 0) {
                    edge_face[ed] = f;
                } else {
                    int a = root(up, edge_face[ed]), b = root(up, f);
                    if (a != b)
                        up[a > b ? a : b] = a < b ? a : b;
                }
            }
        }
    }
    for (int f = 0; f < nf; f++) {
        const brep_face *bf = &lm->brep.faces[cm->faces[f].brep_face];
        p->held += bf->instance != 0 || bf->owner != 0;
        long long key = bf->instance != 0 ? (1LL << 40) | bf->instance
                        : bf->owner != 0  ? (2LL << 40) | bf->owner
                                          : (3LL << 40) | root(up, f);
        k[f] = (part_key){key, bf->top, f, f};
    }
    p->held += npl;
    for (int j = 0; j < npl; j++)
        k[nf + j] = (part_key){(4LL << 40) | j, lm->brep.placements[j].top, nf, nf + j};
    qsort(k, (size_t)n, sizeof *k, cmp_key);
    /* one part per key: its place in file order is its entity's (the least top) and its first face */
    int nparts = 0;
    first_of = malloc(((size_t)n + 1) * sizeof *first_of);
    order = malloc(((size_t)n + 1) * sizeof *order);
    if (!first_of || !order) {
        e = cm_fail(st, CM_E_NOMEM, "out of memory");
        goto done;
    }
    for (int i = 0; i < n; i++) {
        if (i == 0 || k[i].key != k[i - 1].key) {
            nparts++;
            first_of[nparts] = k[i];
            first_of[nparts].item = nparts; /* (its provisional number) */
        } else {
            first_of[nparts].top = k[i].top < first_of[nparts].top ? k[i].top : first_of[nparts].top;
            first_of[nparts].first = k[i].first < first_of[nparts].first ? k[i].first : first_of[nparts].first;
        }
        num[k[i].item] = nparts;
    }
    qsort(first_of + 1, (size_t)nparts, sizeof *first_of, cmp_order);
    /* order[i]: the provisional number of the part at step i + 1; first_of[] back by provisional number */
    for (int i = 0; i < nparts; i++)
        order[i] = first_of[i + 1].item;
    {
        part_key *byp = malloc(((size_t)nparts + 1) * sizeof *byp);
        if (!byp) {
            e = cm_fail(st, CM_E_NOMEM, "out of memory");
            goto done;
        }
        for (int i = 1; i <= nparts; i++)
            byp[first_of[i].item] = first_of[i];
        memcpy(first_of + 1, byp + 1, (size_t)nparts * sizeof *byp);
        free(byp);
    }
    if (steps && (e = apply_steps(lm, steps, first_of, nparts, order, &p->stepped, why, whylen, st)) != CM_OK)
        goto done;
    /* the step of each provisional part, then each face's and copy's */
    {
        int *step_of = malloc(((size_t)nparts + 1) * sizeof *step_of);
        if (!step_of) {
            e = cm_fail(st, CM_E_NOMEM, "out of memory");
            goto done;
        }
        for (int i = 0; i < nparts; i++)
            step_of[order[i]] = i + 1;
        for (int f = 0; f < nf; f++)
            p->face_part[f] = step_of[num[f]];
        for (int j = 0; j < npl; j++)
            p->place_part[j] = step_of[num[nf + j]];
        free(step_of);
    }
    p->nparts = nparts;
done:
    free(k);
    free(up);
    free(edge_face);
    free(edge_uses);
    free(num);
    free(order);
    free(first_of);
    if (e != CM_OK)
        enc_parts_free(p);
    return e;
}

int enc_part_names(const loaded_model *lm, const enc_parts *p, int part, char names[2][80], int *nfaces)
{
    int owner = -1, product = 0, n = 0;
    for (int f = 0; f < lm->mesh.nfaces; f++)
        if (p->face_part[f] == part) {
            n++;
            if (owner < 0) {
                owner = lm->brep.faces[lm->mesh.faces[f].brep_face].owner;
                product = lm->brep.faces[lm->mesh.faces[f].brep_face].product;
            }
        }
    for (int j = 0; j < lm->brep.nplacements; j++)
        if (p->place_part[j] == part) {
            n += lm->brep.placements[j].nfaces;
            if (owner < 0) {
                owner = lm->brep.placements[j].owner;
                product = lm->brep.placements[j].product;
            }
        }
    *nfaces = n;
    return part_names(lm, owner, product, names);
}
