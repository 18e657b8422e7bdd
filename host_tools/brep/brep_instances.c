/*
 * brep_instances.c - placed copies folded out of an assembly (see brep.h, brep_fold_instances).
 *
 * An IGES assembly places one subfigure definition (308) several times by 408 instances; the
 * importer expands each placement into faces of its own (asitus__IAD_v3: 416 face entities placed
 * 2012 times).  A part placed k times need travel only once: its first placement's faces stay in
 * the model, each further placement becomes one transform (format 4.3), and the terminal places
 * the copies' triangles (cm_place.h).  A copy is folded only when it is what the transform says:
 * the same entities in the same order, every surface and boundary curve control point of the
 * prototype moved onto the copy's within the model's tolerance, the same colours and sides.
 */
#include "brep.h"

#include "cm/cm_format.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* the faces [first, first + n) of instance id, contiguous in face order; 0 when it has none or
   they are not contiguous (then it is not folded) */
static int instance_faces(const brep_model *m, int id, int *first, int *n)
{
    int f0 = -1, k = 0;
    for (int f = 0; f < m->nfaces; f++)
        if (m->faces[f].instance == id) {
            if (f0 < 0)
                f0 = f;
            else if (f != f0 + k)
                return 0;
            k++;
        }
    *first = f0;
    *n = k;
    return k > 0;
}

static int same_points(const cm_vec3 *a, const cm_vec3 *b, int n, const haffine *x, double tol)
{
    for (int i = 0; i < n; i++)
        if (!(cm_dist(haffine_apply(x, a[i]), b[i]) <= tol))
            return 0;
    return 1;
}

static int same_weights(const double *a, const double *b, int n)
{
    if (!a || !b)
        return a == b;
    for (int i = 0; i < n; i++)
        if (!(fabs(a[i] - b[i]) <= 1e-12 * fabs(a[i])))
            return 0;
    return 1;
}

static int same_knots(const double *a, const double *b, int n)
{
    for (int i = 0; i < n; i++)
        if (!(fabs(a[i] - b[i]) <= 1e-12 * (1.0 + fabs(a[i]))))
            return 0;
    return 1;
}

/* face g is face f moved by x */
static int same_face(const brep_model *m, int f, int g, const haffine *x, double tol)
{
    const brep_face *F = &m->faces[f], *G = &m->faces[g];
    if (F->src_de != G->src_de || F->flip != G->flip || F->nloops != G->nloops || F->natural != G->natural ||
        F->has_color != G->has_color || (F->has_color && F->rgb != G->rgb))
        return 0;
    const hsurf *a = &m->surfs[F->surf], *b = &m->surfs[G->surf];
    if (a->p != b->p || a->q != b->q || a->nu != b->nu || a->nv != b->nv ||
        !same_knots(a->U, b->U, a->nu + a->p + 1) || !same_knots(a->V, b->V, a->nv + a->q + 1) ||
        !same_weights(a->w, b->w, a->nu * a->nv) || !same_points(a->ctrl, b->ctrl, a->nu * a->nv, x, tol))
        return 0;
    for (int l = 0; l < F->nloops; l++) {
        const brep_loop *la = &m->loops[F->first_loop + l], *lb = &m->loops[G->first_loop + l];
        if (la->n != lb->n)
            return 0;
        for (int s = 0; s < la->n; s++) {
            const hcurve *c = &m->segs[la->first + s], *d = &m->segs[lb->first + s];
            if (c->p != d->p || c->n != d->n || !same_knots(c->knots, d->knots, c->n + c->p + 1) ||
                !same_weights(c->w, d->w, c->n) || !same_points(c->ctrl, d->ctrl, c->n, x, tol))
                return 0;
        }
    }
    return 1;
}

cm_err brep_fold_instances(brep_model *m, int *folded, cm_status *st)
{
    if (folded)
        *folded = 0;
    if (m->ninstances < 2)
        return CM_OK;
    unsigned char *drop = calloc((size_t)m->nfaces + 1, 1);
    brep_placement *pl = malloc((size_t)m->ninstances * sizeof *pl);
    int *ifirst = malloc((size_t)m->ninstances * sizeof *ifirst), *inum = malloc((size_t)m->ninstances * sizeof *inum);
    if (!drop || !pl || !ifirst || !inum) {
        free(drop);
        free(pl);
        free(ifirst);
        free(inum);
        return cm_fail(st, CM_E_NOMEM, "out of memory");
    }
    /* each instance's faces, once (0 faces: none, or not together: not folded) */
    for (int i = 0; i < m->ninstances; i++)
        if (!instance_faces(m, m->instances[i].id, &ifirst[i], &inum[i]))
            inum[i] = 0;
    /* the copies are the same entities moved by their own transforms at import: they agree to
       rounding, far inside spec 5.1's vertex tolerance (not the file's resolution, which
       brep_tolerance may take: a copy is not measured again after it is folded) */
    double tol = 1e-6 * brep_diag(m);
    int npl = 0, nface = 0;
    for (int i = 0; i < m->ninstances; i++) {
        const brep_instance *I = &m->instances[i];
        int first = ifirst[i], n = inum[i];
        if (n == 0)
            continue;
        /* the prototype: the first instance of the same definition that has faces and stays */
        int proto = -1;
        for (int j = 0; j < i && proto < 0; j++)
            if (m->instances[j].def_de == I->def_de && inum[j] > 0 && !drop[ifirst[j]])
                proto = j;
        if (proto < 0 || inum[proto] != n)
            continue;
        int pfirst = ifirst[proto];
        haffine inv, x;
        if (!haffine_invert(&m->instances[proto].xf, &inv))
            continue;
        x = haffine_compose(&I->xf, &inv); /* prototype -> copy */
        /* what format 4.3 can say (the rule its reader applies) */
        double xm[12];
        haffine_rows(&x, xm);
        if (cm_fmt_placement_fault(xm))
            continue;
        int same = 1;
        for (int k = 0; k < n && same; k++)
            same = same_face(m, pfirst + k, first + k, &x, tol);
        if (!same)
            continue;
        for (int k = 0; k < n; k++)
            drop[first + k] = 1;
        pl[npl].proto = m->instances[proto].id;
        pl[npl].nfaces = n;
        pl[npl].xf = x;
        pl[npl].top = m->faces[first].top;
        pl[npl].owner = m->faces[first].owner;
        pl[npl].product = m->faces[first].product;
        npl++;
        nface += n;
    }
    /* the copies of one part one after another (by the part's place in the model: insertion sort,
       stable), so a GLB shares one mesh between them */
    for (int i = 1; i < npl; i++) {
        brep_placement p = pl[i];
        int j = i;
        for (; j > 0 && pl[j - 1].proto > p.proto; j--)
            pl[j] = pl[j - 1];
        pl[j] = p;
    }
    cm_err e = CM_OK;
    if (npl > 0) {
        hbox whole = m->box;
        e = brep_remove_faces(m, drop, st);
        if (e == CM_OK) {
            free(m->placements);
            m->placements = pl;
            pl = NULL;
            m->nplacements = npl;
            m->placed_faces = nface;
            m->placed_box = whole;
            if (folded)
                *folded = npl;
        }
    }
    free(pl);
    free(drop);
    free(ifirst);
    free(inum);
    return e;
}
