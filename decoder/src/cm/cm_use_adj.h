/*
 * cm_use_adj.h - format 4.5: an edge use predicted from where its loop is.
 *
 * A loop is closed: each use of it begins at the vertex where the use before ended.  So the
 * second use of an edge (the face across it) need not name the edge among all edges referenced
 * so far, as formats up to 4.4 do (a uint "back"): the writer names it among the referenced
 * edges that meet at that vertex, which are few, and its direction follows from which of its
 * ends is there.  Over the 34 corpus models the uses took 13 199 bytes in 4.4 and
 * take 6 855.
 *
 * The candidates at vertex v: the referenced edges at v as a list, most recently referenced
 * first; first those used fewer than twice so far (the side still open: a manifold edge has two
 * uses), then the others, each group in list order.  Only the first CM_USE_WALK entries of the
 * list are looked at, in each of the two passes, so that a vertex where thousands of edges meet
 * (a crafted file) costs at most 2 CM_USE_WALK steps per use; an edge beyond them is sent as in
 * 4.4 (the index one past the candidates, then `back`).
 *
 * The lists are kept in arrays the caller owns (the decoder borrows arrays it fills only after
 * the FACE section: see sec_face), heap-free; the writer (host_tools/encode/write_sections.c)
 * runs the same functions over its own, so both sides list the same candidates.
 */
#ifndef CM_USE_ADJ_H
#define CM_USE_ADJ_H

#include <stdint.h>

#include "cm/cm_format.h"

#define CM_USE_WALK 64                   /* list entries looked at per pass */
#define CM_USE_CANDIDATES (2 * CM_USE_WALK) /* candidates at most */

typedef struct cm_use_adj {
    int32_t *head;      /* per vertex: the edge referenced last at it, or -1 */
    int32_t (*next)[2]; /* per edge: the next edge of the list at its v0 [0] and at its v1 [1], or -1 */
    uint8_t *nuse;      /* per edge: its uses so far, saturating at 255 */
} cm_use_adj;

/** Empty lists at vertices [0, nverts). */
void cm_use_adj_begin(cm_use_adj *a, uint32_t nverts);

/** Edge e (its ends valid vertices) is referenced for the first time: it heads the lists at its ends. */
void cm_use_adj_add(cm_use_adj *a, const cm_edge *edges, uint32_t e);

/** Edge e has been used once more; a new one (`fresh`: referenced for the first time) joins the
    lists first.  Writer and reader call it after every use, a loop's first too. */
static inline void cm_use_adj_use(cm_use_adj *a, const cm_edge *edges, uint32_t e, int fresh)
{
    if (fresh)
        cm_use_adj_add(a, edges, e);
    if (a->nuse[e] < 255)
        a->nuse[e]++;
}

/** The candidates at vertex v, in their order (above), into out[CM_USE_CANDIDATES]; returns their count. */
int cm_use_adj_list(const cm_use_adj *a, const cm_edge *edges, int32_t v, uint32_t *out);

/** The direction of a use of edge e that begins at v: 1 (the loop runs v1 -> v0) when e's v0 is not v. */
static inline uint8_t cm_use_adj_rev(const cm_edge *edges, uint32_t e, int32_t v)
{
    return (uint8_t)(edges[e].v0 != v);
}

#endif
