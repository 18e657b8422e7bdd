/*
 * cm_const.h - the angles and relative tolerances of the method family
 * (docs/METHODS.md), named once.  Encoder and decoder must agree on each
 * to the last bit: a face's rebuild is verified on one side and repeated
 * on the other, so a constant written out twice is a bug waiting for the
 * copies to drift (they had: sin 5 deg existed in two spellings).
 */
#ifndef CM_CONST_H
#define CM_CONST_H

/** sin 5 deg (spec §1 SIN_FLAT): corners flatter than this have no geometric normal; a ray must
 *  meet a plane at least this steeply (spec K10, which writes the constant 2 ulps lower: the
 *  correctly rounded value serves both; no corpus model's output changed); a reflex corner turns by
 *  more than this. */
#define CM_SIN_FLAT 0.08715574274765817
/** cos 1 deg (spec §1 COS_G1): two faces are G1 along an edge when their normals agree this well. */
#define CM_COS_G1 0.9998476951563913

/** "Zero" length relative to a face's size (spec §1 EPS_LEN is 1e-12 of the model; a face's own
 *  size stands in for it where only that face's geometry is compared). */
#define CM_EPS_LEN_REL 1e-12
/** Two vectors are taken as parallel (a normal from their cross product does not exist) when
 *  |a x b| <= CM_EPS_CROSS_REL |a| |b|. */
#define CM_EPS_CROSS_REL 1e-12

#endif /* CM_CONST_H */
