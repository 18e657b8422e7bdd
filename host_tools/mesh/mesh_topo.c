/* mesh_topo.c - welding by position and the edge census (see mesh_topo.h). */
#include "mesh_topo.h"

#include <stdlib.h>
#include <string.h>

static const cm_mesh *sort_mesh; /* qsort has no context argument in C11 */

static int cmp_pos(const void *a, const void *b)
{
    const float *p = sort_mesh->pos[*(const uint32_t *)a], *q = sort_mesh->pos[*(const uint32_t *)b];
    for (int k = 0; k < 3; k++)
        if (p[k] != q[k])
            return p[k] < q[k] ? -1 : 1;
    return 0;
}

typedef struct dedge {
    uint32_t a, b;
    uint32_t t; /* its triangle */
} dedge;

static int cmp_dedge(const void *x, const void *y)
{
    const dedge *p = x, *q = y;
    if (p->a != q->a)
        return p->a < q->a ? -1 : 1;
    if (p->b != q->b)
        return p->b < q->b ? -1 : 1;
    return 0;
}

static cm_vec3 vpos(const cm_mesh *m, uint32_t i)
{
    return cm_v3f(m->pos[i]);
}

/* 1 if triangles s and t face apart (their normals' dot product is negative) */
static int opposed(const cm_mesh *m, uint32_t s, uint32_t t)
{
    const uint32_t *a = m->idx + 3 * (size_t)s, *b = m->idx + 3 * (size_t)t;
    cm_vec3 na = cm_cross(cm_sub(vpos(m, a[1]), vpos(m, a[0])), cm_sub(vpos(m, a[2]), vpos(m, a[0])));
    cm_vec3 nb = cm_cross(cm_sub(vpos(m, b[1]), vpos(m, b[0])), cm_sub(vpos(m, b[2]), vpos(m, b[0])));
    return cm_dot(na, nb) < 0;
}

int mesh_topo_analyse(const cm_mesh *m, mesh_topo *out)
{
    memset(out, 0, sizeof *out);
    size_t nv = m->nverts, nt = m->nindex / 3;
    uint32_t *order = malloc((nv + 1) * sizeof *order), *id = malloc((nv + 1) * sizeof *id);
    uint32_t *rep = malloc((nv + 1) * sizeof *rep);
    dedge *de = malloc((3 * nt + 1) * sizeof *de);
    out->bnd = malloc((6 * nt + 1) * sizeof *out->bnd);
    if (!order || !id || !rep || !de || !out->bnd) {
        free(order), free(id), free(rep), free(de), free(out->bnd);
        out->bnd = NULL;
        return -1;
    }
    for (uint32_t i = 0; i < nv; i++)
        order[i] = i;
    sort_mesh = m;
    qsort(order, nv, sizeof *order, cmp_pos);
    uint32_t u = 0;
    for (size_t i = 0; i < nv; i++) {
        if (i > 0 && cmp_pos(&order[i - 1], &order[i]) != 0)
            u++;
        id[order[i]] = u;
        rep[u] = order[i];
    }
    out->welded_vertices = nv ? u + 1u : 0;
    out->triangles = nt;
    size_t nd = 0;
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *ix = m->idx + 3 * t;
        uint32_t v[3] = {id[ix[0]], id[ix[1]], id[ix[2]]};
        cm_vec3 A = vpos(m, ix[0]), B = vpos(m, ix[1]), C = vpos(m, ix[2]);
        out->volume += cm_dot(A, cm_cross(B, C)) / 6.0;
        if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) {
            out->degenerate++;
            continue;
        }
        for (int k = 0; k < 3; k++)
            de[nd++] = (dedge){v[k], v[(k + 1) % 3], (uint32_t)t};
    }
    qsort(de, nd, sizeof *de, cmp_dedge);
    for (size_t i = 0; i < nd; i++) {
        if (i > 0 && cmp_dedge(&de[i - 1], &de[i]) == 0) {
            /*
             * A chord through a thin lens: two faces whose surfaces meet along two shared edges
             * enclose a sliver (tail_section_asm: a 3 mm extrusion face on a cylinder, 0.013 mm
             * apart), and a chord between points of those edges can be in both faces' triangles,
             * each face using it both ways, the two triangles facing apart.  That is the model's
             * shape, not an overlap: exactly two uses each way, the triangles' normals opposed.
             */
            size_t first = i - 1, run = 0;
            while (first > 0 && cmp_dedge(&de[first - 1], &de[i]) == 0)
                first--;
            while (first + run < nd && cmp_dedge(&de[first], &de[first + run]) == 0)
                run++;
            dedge rev = {de[i].b, de[i].a, 0};
            const dedge *r = bsearch(&rev, de, nd, sizeof *de, cmp_dedge);
            size_t rrun = 0;
            if (r) {
                while (r > de && cmp_dedge(r - 1, &rev) == 0)
                    r--;
                while (r + rrun < de + nd && cmp_dedge(r + rrun, &rev) == 0)
                    rrun++;
            }
            if (run == 2 && rrun == 2 && opposed(m, de[first].t, de[first + 1].t)) {
                out->lens_chords++;
                continue;
            }
            out->duplicate++;
            continue;
        }
        dedge rev = {de[i].b, de[i].a, 0};
        if (!bsearch(&rev, de, nd, sizeof *de, cmp_dedge)) {
            out->bnd[2 * out->unpaired] = vpos(m, rep[de[i].a]);
            out->bnd[2 * out->unpaired + 1] = vpos(m, rep[de[i].b]);
            out->unpaired++;
        }
    }
    free(order);
    free(id);
    free(rep);
    free(de);
    return 0;
}

void mesh_topo_free(mesh_topo *t)
{
    free(t->bnd);
    t->bnd = NULL;
}
