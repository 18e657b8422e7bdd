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
 *  meet a plane at least this steeply (spec K10); a reflex corner turns by more than this. */
#define CM_SIN_FLAT 0.08715574274765817
/** cos 1 deg (spec §1 COS_G1): two faces are G1 along an edge when their normals agree this well. */
#define CM_COS_G1 0.9998476951563913

#endif /* CM_CONST_H */
