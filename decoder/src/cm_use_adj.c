/* cm_use_adj.c - format 4.5's candidates for an edge use (cm/cm_use_adj.h) */
#include "cm/cm_use_adj.h"

void cm_use_adj_begin(cm_use_adj *a, uint32_t nverts)
{
    for (uint32_t v = 0; v < nverts; v++)
        a->head[v] = -1;
}

void cm_use_adj_add(cm_use_adj *a, const cm_edge *edges, uint32_t e)
{
    int32_t v0 = edges[e].v0, v1 = edges[e].v1;
    a->nuse[e] = 0;
    a->next[e][0] = a->head[v0];
    a->head[v0] = (int32_t)e;
    a->next[e][1] = -1;
    if (v1 != v0) { /* a closed edge is in its one vertex's list once */
        a->next[e][1] = a->head[v1];
        a->head[v1] = (int32_t)e;
    }
}

int cm_use_adj_list(const cm_use_adj *a, const cm_edge *edges, int32_t v, uint32_t *out)
{
    int n = 0;
    for (int pass = 0; pass < 2; pass++) {
        int32_t x = a->head[v];
        for (int steps = 0; x >= 0 && steps < CM_USE_WALK; steps++) {
            uint32_t e = (uint32_t)x;
            if ((a->nuse[e] < 2) == (pass == 0))
                out[n++] = e;
            x = edges[e].v0 == v ? a->next[e][0] : a->next[e][1];
        }
    }
    return n;
}
