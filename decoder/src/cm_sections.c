/* cm_sections.c - every section's coding contexts at their starting state (see cm_sections.h). */
#include "cm/cm_sections.h"

static void ints(cm_ac_int *m, int n)
{
    for (int i = 0; i < n; i++)
        cm_ac_int_init(&m[i]);
}

void cm_vert_ctx_init(cm_vert_ctx *c)
{
    cm_ac_int_init(&c->count);
    ints(c->coord, 3);
    cm_ac_int_init(&c->step);
    ints(c->slot, 3);
    for (int k = 0; k < 3; k++)
        cm_ac_prob_init(&c->repeat[k]);
}

void cm_edge_ctx_init(cm_edge_ctx *c)
{
    cm_ac_int_init(&c->count);
    cm_ac_int_init(&c->back);
    cm_ac_int_init(&c->degree);
    cm_ac_int_init(&c->ncoef);
    cm_ac_int_init(&c->knot);
    ints(c->coord, 3);
    cm_ac_int_init(&c->weight);
    cm_ac_prob_init(&c->is_new);
    cm_ac_prob_init(&c->g1);
    cm_ac_prob_init(&c->kind);
    cm_ac_prob_init(&c->rational);
    cm_ac_prob_init(&c->uniform);
    cm_ac_prob_init(&c->linear);
    cm_ac_prob_init(&c->knot_zero);
    cm_ac_int_init(&c->knot_delta);
    cm_ac_int_init(&c->step);
    cm_ac_prob_init(&c->arc);
    cm_ac_int_init(&c->arc_step);
    ints(c->arc_coord, 3);
}

void cm_surf_ctx_init(cm_surf_ctx *c)
{
    cm_ac_int_init(&c->count);
    cm_ac_int_init(&c->degree);
    cm_ac_int_init(&c->ncoef);
    cm_ac_int_init(&c->knot);
    ints(c->coord, 3);
    cm_ac_int_init(&c->weight);
    cm_ac_prob_init(&c->rational);
    cm_ac_prob_init(&c->uniform);
    cm_ac_prob_init(&c->quadratic);
    cm_ac_prob_init(&c->knot_zero);
    cm_ac_int_init(&c->knot_delta);
    cm_ac_int_init(&c->step);
    cm_ac_prob_init(&c->ruled);
    cm_ac_prob_init(&c->closed);
    cm_ac_prob_init(&c->along_v);
    cm_ac_int_init(&c->ruled_step);
    ints(c->ruled_coord, 3);
}

void cm_face_ctx_init(cm_face_ctx *c)
{
    cm_ac_int_init(&c->count);
    cm_ac_int_init(&c->method);
    cm_ac_int_init(&c->loops);
    cm_ac_int_init(&c->uses);
    cm_ac_int_init(&c->back);
    cm_ac_int_init(&c->layout);
    cm_ac_int_init(&c->corner);
    cm_ac_prob_init(&c->flip);
    cm_ac_prob_init(&c->is_new);
    cm_ac_prob_init(&c->rev_new);
    cm_ac_prob_init(&c->rev_old);
    cm_ac_int_init(&c->cand);
    cm_ac_prob_init(&c->rev_closed);
    cm_ac_int_init(&c->fit_m);
    cm_ac_int_init(&c->fit_patches);
    cm_ac_int_init(&c->fit_exp);
    cm_ac_int_init(&c->fit_coef);
    cm_ac_prob_init(&c->twist_on);
    cm_ac_prob_init(&c->twist_use);
    cm_ac_int_init(&c->twist_n);
    cm_ac_int_init(&c->twist);
    cm_ac_int_init(&c->place_n);
    cm_ac_int_init(&c->place_first);
    cm_ac_int_init(&c->place_count);
    cm_ac_int_init(&c->place_entry);
    cm_ac_int_init(&c->place_shift);
    cm_ac_prob_init(&c->hint_any);
    cm_ac_int_init(&c->hint_mask);
    cm_ac_int_init(&c->hint_oct);
    c->net_fit = 0;
    c->placements = 0;
    c->hints = 0;
}

void cm_colr_ctx_init(cm_colr_ctx *c)
{
    cm_ac_int_init(&c->count);
    cm_ac_int_init(&c->index);
    cm_ac_int_init(&c->nparts);
    cm_ac_int_init(&c->part);
    cm_ac_int_init(&c->name_bytes);
    cm_ac_int_init(&c->name_len);
    cm_ac_int_init(&c->name_back);
    cm_ac_prob_init(&c->name_again);
    cm_ac_prob_init(&c->part_same);
    cm_ac_prob_init(&c->part_next);
}
