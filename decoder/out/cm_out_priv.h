/*
 * cm_out_priv.h - shared parts of the mesh writers (cm_out.c, cm_glb.c,
 * cm_stl.c, cm_obj.c); not installed, not for callers.
 *
 * Each format is a state machine over cm_out.stage/item/sub.  Its fill
 * function appends the next piece of the file (a header, a JSON object, a
 * batch of binary records or text lines) to a cm_buf on cm_out.pending and
 * advances the state; cm_out_next copies the pending bytes to the caller's
 * buffer and refills when they are used up.  Pieces never depend on the
 * caller's buffer size, so neither do the bytes.
 */
#ifndef CM_OUT_PRIV_H
#define CM_OUT_PRIV_H

#include <stddef.h>
#include <stdint.h>

#include "cm/cm_mesh.h"
#include "cm/cm_out.h"

#define CM_OUT_PENDING ((uint32_t)sizeof(((cm_out *)0)->pending))
_Static_assert(sizeof(((cm_out *)0)->pending) >= 512, "the largest piece (a POSITION accessor) needs ~200 bytes");

/* vertices or indices the writers' checks and bounds read from the mesh at a time (a run through
   the spill's page logic instead of a call per element: the checks and the GLB's bounds read every
   vertex; 384 bytes of stack each) */
#define CM_OUT_RUN 32u

/* append-only byte buffer over cm_out.pending; overflow is a writer bug and is flagged, never written */
typedef struct cm_buf {
    uint8_t *p;
    uint32_t n, cap;
    int overflow;
} cm_buf;

void cm_buf_init(cm_buf *b, uint8_t *p, uint32_t cap);
uint32_t cm_buf_room(const cm_buf *b);
void cm_buf_bytes(cm_buf *b, const void *src, uint32_t n);
void cm_buf_str(cm_buf *b, const char *s);          /* NUL-terminated text */
void cm_buf_u64(cm_buf *b, uint64_t v);             /* decimal */
void cm_buf_f32(cm_buf *b, float f);                /* cm_fmt_f32 text */
void cm_buf_le16(cm_buf *b, uint16_t v);            /* little-endian, byte by byte */
void cm_buf_le32(cm_buf *b, uint32_t v);
void cm_buf_lef32(cm_buf *b, float f);              /* IEEE bits, little-endian */

/* triangles of face f (0 for a face the writers skip) */
uint32_t cm_out_face_tris(const cm_mesh *m, uint32_t f);

/* per format: prepare at cm_out_begin (mesh already validated), append the next piece */
cm_err cm_glb_begin(cm_out *w, cm_status *st);
void cm_glb_fill(cm_out *w, cm_buf *b);
cm_err cm_stl_begin(cm_out *w, cm_status *st);
void cm_stl_fill(cm_out *w, cm_buf *b);
cm_err cm_obj_begin(cm_out *w, cm_status *st);
void cm_obj_fill(cm_out *w, cm_buf *b);

/* stage value every format uses for "file complete" */
#define CM_OUT_DONE 0xFFFFFFFFu

#endif /* CM_OUT_PRIV_H */
