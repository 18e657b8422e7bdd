/* orient.c - every face of a part facing the same way, and every closed part facing outwards,
   decided on the curve mesh and the B-rep before anything is written (see encode_internal.h).

   Agreement is topology: two faces sharing an edge walk it in opposite directions.  Outwards is
   geometry: the volume a closed part encloses, by the divergence theorem over its faces' own
   surfaces, is positive.  It is measured on the source B-rep (each face's surface over its parameter
   domain), not on the decoder's tessellation, so that the methods are chosen once, on faces that
   already run the right way (issue 12: the encoder used to choose, tessellate, find a part inside
   out, turn it and choose again). */
#include "encode_internal.h"

#include <math.h>
#include <stdlib.h>

#include "brep/face_domain.h"

/* ---- orientation: every part's faces agree on shared edges (they run both ways) ---- */

void enc_flip_face(loaded_model *lm, int f)
{
    cmesh *cm = &lm->mesh;
    const cmesh_face *cf = &cm->faces[f];
    for (int l = 0; l < cf->nloops; l++) {
        const cmesh_loop *cl = &cm->loops[cf->first_loop + l];
        for (int i = 0; i < cl->n / 2; i++) {
            cmesh_use t = cm->uses[cl->first + i];
            cm->uses[cl->first + i] = cm->uses[cl->first + cl->n - 1 - i];
            cm->uses[cl->first + cl->n - 1 - i] = t;
        }
        for (int i = 0; i < cl->n; i++)
            cm->uses[cl->first + i].rev ^= 1;
    }
    lm->brep.faces[cf->brep_face].flip ^= 1;
}

int enc_orient_parts(loaded_model *lm)
{
    cmesh *cm = &lm->mesh;
    int nf = cm->nfaces, flips = 0;
    /* per edge: the face and rev of its first two uses */
    int *ef = malloc((size_t)cm->nedges * 2 * sizeof(int)), *er = malloc((size_t)cm->nedges * 2 * sizeof(int));
    int *cnt = calloc((size_t)cm->nedges + 1, sizeof(int));
    int *queue = malloc((size_t)(nf + 1) * sizeof(int));
    unsigned char *seen = calloc((size_t)nf + 1, 1), *flip = calloc((size_t)nf + 1, 1);
    if (!ef || !er || !cnt || !queue || !seen || !flip)
        goto done;
    for (int f = 0; f < nf; f++) {
        const cmesh_face *cf = &cm->faces[f];
        for (int l = 0; l < cf->nloops; l++) {
            const cmesh_loop *cl = &cm->loops[cf->first_loop + l];
            for (int i = 0; i < cl->n; i++) {
                const cmesh_use *u = &cm->uses[cl->first + i];
                if (cnt[u->edge] < 2) {
                    ef[2 * u->edge + cnt[u->edge]] = f;
                    er[2 * u->edge + cnt[u->edge]] = u->rev;
                }
                cnt[u->edge]++;
            }
        }
    }
    for (int s = 0; s < nf; s++) {
        if (seen[s])
            continue;
        int head = 0, tail = 0;
        queue[tail++] = s;
        seen[s] = 1;
        while (head < tail) {
            int f = queue[head++];
            const cmesh_face *cf = &cm->faces[f];
            for (int l = 0; l < cf->nloops; l++) {
                const cmesh_loop *cl = &cm->loops[cf->first_loop + l];
                for (int i = 0; i < cl->n; i++) {
                    int e = cm->uses[cl->first + i].edge;
                    if (cm->edges[e].kind != CMESH_SHARED)
                        continue;
                    int side = ef[2 * e] == f ? 0 : 1, g = ef[2 * e + 1 - side];
                    if (seen[g])
                        continue;
                    int rf = er[2 * e + side] ^ flip[f], rg = er[2 * e + 1 - side];
                    flip[g] = rf == rg; /* the same way in both: turn g */
                    seen[g] = 1;
                    queue[tail++] = g;
                }
            }
        }
    }
    for (int f = 0; f < nf; f++)
        if (flip[f]) {
            enc_flip_face(lm, f);
            flips++;
        }
done:
    free(ef);
    free(er);
    free(cnt);
    free(queue);
    free(seen);
    free(flip);
    return flips;
}

/* ---- outwards: the signed volume of each closed part ---- */

/*
 * Rows across the domain in v, and along each row the exact stretches inside it (the polygon's
 * crossings, even-odd: the outer loop less its holes), integrated by Gauss-Legendre in u: a smooth
 * integrand over an exactly cut domain, so a face's share is good to a few per cent with about a
 * hundred evaluations.  The sign of the part's total is all that is used.
 */
enum { VOL_ROWS = 12, VOL_SPANS = 6 };

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* 3 * the face's share of its part's volume relative to c: the integral over the face's domain of
   (P - c) . (S_u x S_v), negated for a flipped face; its area added to *area.  *ok = 0 when it cannot
   be measured. */
static double face_volume3(const brep_model *m, const face_domain *fd, cm_vec3 c, double *xs, double *area, int *ok)
{
    static const double gx[3] = {-0.7745966692414834, 0.0, 0.7745966692414834};
    static const double gw[3] = {0.5555555555555556, 0.8888888888888888, 0.5555555555555556};
    double h = (fd->vmax - fd->vmin) / VOL_ROWS, du_max = (fd->umax - fd->umin) / VOL_SPANS, sum = 0;
    if (!fd->uv || fd->nloops == 0 || !(h > 0) || !(du_max > 0)) {
        *ok = 0;
        return 0;
    }
    for (int k = 0; k < VOL_ROWS; k++) {
        double v = fd->vmin + (k + 0.5) * h, row = 0, arow = 0;
        int nx = 0;
        for (int l = 0; l < fd->nloops; l++) {
            const cm_vec2 *q = fd->uv + fd->loops[l].first;
            int n = fd->loops[l].n;
            for (int i = 0, j = n - 1; i < n; j = i++)
                if ((q[i].y <= v) != (q[j].y <= v))
                    xs[nx++] = q[j].x + (v - q[j].y) * (q[i].x - q[j].x) / (q[i].y - q[j].y);
        }
        qsort(xs, (size_t)nx, sizeof *xs, cmp_double);
        for (int i = 0; i + 1 < nx; i += 2) {
            double len = xs[i + 1] - xs[i];
            /* a stretch wider than the outer loop's box comes only from a hole outside it: bounded */
            double want = ceil(len / du_max);
            int spans = want < 1 ? 1 : want > 4 * VOL_SPANS ? 4 * VOL_SPANS : (int)want;
            double du = len / spans;
            for (int s = 0; s < spans; s++)
                for (int g = 0; g < 3; g++) {
                    double u = xs[i] + du * (s + 0.5 + 0.5 * gx[g]);
                    cm_vec3 d[3];
                    if (cm_psurf_eval(&fd->ps, u, v, d, NULL) != CM_OK) {
                        *ok = 0;
                        return 0;
                    }
                    cm_vec3 n = cm_cross(d[1], d[2]);
                    row += gw[g] * 0.5 * du * cm_dot(cm_sub(d[0], c), n);
                    arow += gw[g] * 0.5 * du * cm_norm(n);
                }
        }
        sum += row * h;
        *area += arow * h;
    }
    return m->faces[fd->face].flip ? -sum : sum;
}

int enc_outward_parts(loaded_model *lm)
{
    cmesh *cm = &lm->mesh;
    int nf = cm->nfaces, flipped = 0, maxpts = 0;
    for (int f = 0; f < nf; f++) {
        const face_domain *fd = &lm->fds[cm->faces[f].brep_face];
        if (fd->npts > maxpts)
            maxpts = fd->npts;
    }
    int *comp = malloc((size_t)(nf + 1) * sizeof *comp);
    double *xs = malloc((size_t)(maxpts + 1) * sizeof *xs);
    int nc = comp ? cmesh_components(cm, comp) : 0;
    double *vol = calloc((size_t)nc + 1, sizeof *vol), *area = calloc((size_t)nc + 1, sizeof *area);
    cm_vec3 *lo = malloc((size_t)(nc + 1) * sizeof *lo), *hi = malloc((size_t)(nc + 1) * sizeof *hi);
    unsigned char *undecided = calloc((size_t)nc + 1, 1);
    if (!comp || !xs || !vol || !area || !lo || !hi || !undecided || nc == 0)
        goto done;
    /* an open part has no inside; a face without a domain leaves its part as it is.  (Solids that
       touch along an edge are one part with a non-manifold edge: their volumes add up, and the sign
       still tells.) */
    for (int e = 0; e < cm->nedges; e++)
        if (cm->edges[e].kind == CMESH_FREE)
            undecided[comp[cm->edges[e].face[0]]] = 1;
    for (int p = 0; p < nc; p++) {
        lo[p] = cm_v3(HUGE_VAL, HUGE_VAL, HUGE_VAL);
        hi[p] = cm_v3(-HUGE_VAL, -HUGE_VAL, -HUGE_VAL);
    }
    for (int f = 0; f < nf; f++) {
        const face_domain *fd = &lm->fds[cm->faces[f].brep_face];
        if (!fd->uv) {
            undecided[comp[f]] = 1;
            continue;
        }
        for (int i = 0; i < fd->npts; i++) {
            cm_vec3 x = fd->xyz[i], *a = &lo[comp[f]], *b = &hi[comp[f]];
            a->x = fmin(a->x, x.x), a->y = fmin(a->y, x.y), a->z = fmin(a->z, x.z);
            b->x = fmax(b->x, x.x), b->y = fmax(b->y, x.y), b->z = fmax(b->z, x.z);
        }
    }
    /* relative to the part's centre: a thin part's volume is not lost among large opposite terms */
    for (int f = 0; f < nf; f++) {
        int p = comp[f], ok = 1;
        if (undecided[p])
            continue;
        cm_vec3 c = cm_scale(cm_add(lo[p], hi[p]), 0.5);
        vol[p] += face_volume3(&lm->brep, &lm->fds[cm->faces[f].brep_face], c, xs, &area[p], &ok);
        if (!ok)
            undecided[p] = 1;
    }
    /* A solid of thickness t and area S holds about S t / 2.  One thinner than a millionth of its own
       diagonal (the format's coordinate grid is a millionth of the model's, encode.c) cannot be told
       from a sheet: a flat face closed on itself at a slit, whose volume is round-off.  Its sign says
       nothing, and it is left as the file has it. */
    for (int p = 0; p < nc; p++) {
        double diag = cm_dist(lo[p], hi[p]);
        if (!(fabs(vol[p]) / 3 > 1e-6 * diag * area[p] / 2))
            undecided[p] = 1;
    }
    for (int f = 0; f < nf; f++)
        if (!undecided[comp[f]] && vol[comp[f]] < 0) {
            enc_flip_face(lm, f);
            flipped++;
        }
done:
    free(comp);
    free(xs);
    free(vol);
    free(area);
    free(lo);
    free(hi);
    free(undecided);
    return flipped;
}
