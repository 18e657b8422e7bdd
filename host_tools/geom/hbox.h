/*
 * hbox.h - an axis-aligned box in millimetre model space, for any input
 * format: the B-rep's model box, and the extent that sizes an unbounded
 * surface (a plane, cylinder or cone) to the face that uses it.
 *
 * Non-finite points are ignored.
 */
#ifndef HBOX_H
#define HBOX_H

#include "geom/hnurbs.h"

typedef struct hbox {
    cm_vec3 lo, hi;
    int empty; /* 1: no point yet (lo = +inf, hi = -inf) */
} hbox;

/** The empty box. */
hbox hbox_empty(void);
/** Grow b to contain p (ignored unless finite). */
void hbox_add(hbox *b, cm_vec3 p);
/** Grow b to contain sample points of a curve (33 per span, at most 2001). */
void hbox_add_curve(hbox *b, const hcurve *c);

/** X, Y completing unit Z to a right-handed frame; X along `ref` (projected) when given and not parallel to Z. */
void hbox_frame(cm_vec3 Z, const cm_vec3 *ref, cm_vec3 *X, cm_vec3 *Y);
/**
 * The extent of box b along the axis through o with unit direction dir (the 8 corners projected),
 * widened by a 10 % margin: how far an unbounded surface (plane, cylinder, cone) is built to cover
 * the face whose boundary is b.
 */
void hbox_axis_range(const hbox *b, cm_vec3 o, cm_vec3 dir, double *lo, double *hi);

#endif /* HBOX_H */
