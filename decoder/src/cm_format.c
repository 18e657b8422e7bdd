/* cm_format.c - byte order helpers and kernel views of the decoded model. */
#include "cm/cm_format.h"

#include <string.h>

#include "cm/cm_bspline.h"
#include "cm/cm_method.h"

double cm_get_f64(const uint8_t *p)
{
    uint64_t u = 0;
    for (int i = 7; i >= 0; i--)
        u = (u << 8) | p[i];
    double v;
    memcpy(&v, &u, sizeof v);
    return v;
}

void cm_put_f64(uint8_t *p, double v)
{
    uint64_t u;
    memcpy(&u, &v, sizeof u);
    for (int i = 0; i < 8; i++) {
        p[i] = (uint8_t)u;
        u >>= 8;
    }
}

void cm_fmt_header_pack(uint8_t *b, const cm_fmt_header *h)
{
    b[CM_HDR_MAGIC + 0] = CM_FMT_MAGIC0;
    b[CM_HDR_MAGIC + 1] = CM_FMT_MAGIC1;
    b[CM_HDR_MAGIC + 2] = CM_FMT_MAGIC2;
    b[CM_HDR_MAGIC + 3] = CM_FMT_MAGIC3;
    b[CM_HDR_MAJOR] = h->major;
    b[CM_HDR_MINOR] = h->minor;
    cm_put_u16(b + CM_HDR_FLAGS, h->flags);
    cm_put_u32(b + CM_HDR_LENGTH, h->header_len);
    cm_put_u32(b + CM_HDR_FILE_LENGTH, h->file_len);
    b[CM_HDR_NLIMITS] = h->nlimits;
    b[CM_HDR_NSECTIONS] = h->nsections;
    b[CM_HDR_QEXP] = (uint8_t)h->q_exp;
    b[CM_HDR_RESERVED] = 0;
    for (uint32_t k = 0; k < 3; k++)
        cm_put_f64(b + CM_HDR_ORIGIN + 8 * k, h->origin[k]);
    cm_put_f64(b + CM_HDR_TESS_TOL, h->tess_tol);
    cm_put_f64(b + CM_HDR_REL_TOL, h->rel_tol);
}

void cm_fmt_header_unpack(const uint8_t *b, cm_fmt_header *h)
{
    h->major = b[CM_HDR_MAJOR];
    h->minor = b[CM_HDR_MINOR];
    h->flags = cm_get_u16(b + CM_HDR_FLAGS);
    h->header_len = cm_get_u32(b + CM_HDR_LENGTH);
    h->file_len = cm_get_u32(b + CM_HDR_FILE_LENGTH);
    h->nlimits = b[CM_HDR_NLIMITS];
    h->nsections = b[CM_HDR_NSECTIONS];
    h->q_exp = (int8_t)b[CM_HDR_QEXP];
    for (uint32_t k = 0; k < 3; k++)
        h->origin[k] = cm_get_f64(b + CM_HDR_ORIGIN + 8 * k);
    h->tess_tol = cm_get_f64(b + CM_HDR_TESS_TOL);
    h->rel_tol = cm_get_f64(b + CM_HDR_REL_TOL);
}

void cm_model_edge_curve(const cm_model *m, uint32_t e, cm_curve *out)
{
    const cm_edge *E = &m->edges[e];
    out->p = E->p;
    out->n_ctrl = E->nctrl;
    out->knots = m->knots + E->knot0;
    out->ctrl = m->ctrl + E->ctrl0;
    out->w = E->rational ? m->w + E->ctrl0 : NULL;
}

void cm_model_surface(const cm_model *m, uint32_t s, cm_surf *out)
{
    const cm_ksurf *S = &m->surfs[s];
    out->p = S->p;
    out->q = S->q;
    out->nu = S->nu;
    out->nv = S->nv;
    out->U = m->knots + S->uknot0;
    out->V = m->knots + S->vknot0;
    out->ctrl = m->ctrl + S->ctrl0;
    out->w = S->rational ? m->w + S->ctrl0 : NULL;
}

void cm_model_adjacency(cm_model *m)
{
    for (uint32_t e = 0; e < m->nedges; e++) {
        m->edge_face[e][0] = m->edge_face[e][1] = CM_NO_FACE;
        m->edge_split[e] = 0;
    }
    for (uint32_t f = 0; f < m->nfaces; f++) {
        const cm_face *F = &m->faces[f];
        const cm_method *M = cm_method_of(F->method);
        int split = M && cm_method_needs_midpoints(M, F);
        for (uint32_t l = 0; l < F->nloops; l++) {
            const cm_loop *L = &m->loops[F->loop0 + l];
            for (uint32_t u = 0; u < L->nuse; u++) {
                uint32_t e = m->uses[L->use0 + u].edge;
                int32_t *ef = m->edge_face[e];
                if (split && l == 0)
                    m->edge_split[e] = 1;
                if (ef[0] == CM_NO_FACE)
                    ef[0] = (int32_t)f;
                else if (ef[1] == CM_NO_FACE)
                    ef[1] = (int32_t)f;
                else
                    ef[1] = CM_MANY_FACES;
            }
        }
    }
}

int32_t cm_model_partner(const cm_model *m, uint32_t e, uint32_t f)
{
    const int32_t *ef = m->edge_face[e];
    if (ef[1] < 0 || ef[0] == ef[1])
        return CM_NO_FACE; /* free, non-manifold, or a seam of one face */
    return ef[0] == (int32_t)f ? ef[1] : (ef[1] == (int32_t)f ? ef[0] : CM_NO_FACE);
}
