/*
 * cm_vec.h - 2D/3D vector algebra in binary64 (spec §1 notation).
 *
 * Header-only, inline, no libm beyond sqrt and fabs: the reconstruction
 * code must be bit-identical on every architecture (spec §2 rule 3), so
 * every operation here is a fixed sequence of + - * / sqrt, compiled with
 * -ffp-contract=off.
 */
#ifndef CM_VEC_H
#define CM_VEC_H

#include <math.h>

typedef struct cm_vec3 {
    double x, y, z;
} cm_vec3;

typedef struct cm_vec2 {
    double x, y;
} cm_vec2;

static inline cm_vec3 cm_v3(double x, double y, double z)
{
    cm_vec3 r;
    r.x = x;
    r.y = y;
    r.z = z;
    return r;
}

/* a mesh position (float[3], as cm_mesh stores it) widened to double */
static inline cm_vec3 cm_v3f(const float p[3]) { return cm_v3((double)p[0], (double)p[1], (double)p[2]); }

static inline cm_vec2 cm_v2(double x, double y)
{
    cm_vec2 r;
    r.x = x;
    r.y = y;
    return r;
}

static inline cm_vec3 cm_add(cm_vec3 a, cm_vec3 b) { return cm_v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline cm_vec3 cm_sub(cm_vec3 a, cm_vec3 b) { return cm_v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline cm_vec3 cm_scale(cm_vec3 a, double s) { return cm_v3(a.x * s, a.y * s, a.z * s); }
static inline cm_vec3 cm_neg(cm_vec3 a) { return cm_v3(-a.x, -a.y, -a.z); }
static inline double cm_dot(cm_vec3 a, cm_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline double cm_norm2(cm_vec3 a) { return cm_dot(a, a); }
static inline double cm_norm(cm_vec3 a) { return sqrt(cm_dot(a, a)); }
static inline double cm_dist(cm_vec3 a, cm_vec3 b) { return cm_norm(cm_sub(a, b)); }

static inline cm_vec3 cm_cross(cm_vec3 a, cm_vec3 b)
{
    return cm_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

/** a + s*b (written out: no fused multiply-add, see -ffp-contract=off). */
static inline cm_vec3 cm_axpy(cm_vec3 a, double s, cm_vec3 b)
{
    return cm_v3(a.x + s * b.x, a.y + s * b.y, a.z + s * b.z);
}

/** (1-t)a + t b. */
static inline cm_vec3 cm_lerp(cm_vec3 a, cm_vec3 b, double t)
{
    double s = 1.0 - t;
    return cm_v3(s * a.x + t * b.x, s * a.y + t * b.y, s * a.z + t * b.z);
}

/** a/|a|.  The caller guarantees |a| > 0 (spec §1: |v| > EPS_LEN). */
static inline cm_vec3 cm_unit(cm_vec3 a)
{
    double n = cm_norm(a);
    return cm_v3(a.x / n, a.y / n, a.z / n);
}

/**
 * a/|a| if |a| > eps, else `fallback`; *ok (may be NULL) tells which.
 * Used where a zero-length vector is a legitimate degenerate case.
 */
static inline cm_vec3 cm_unit_or(cm_vec3 a, double eps, cm_vec3 fallback, int *ok)
{
    double n = cm_norm(a);
    if (!(n > eps)) {
        if (ok)
            *ok = 0;
        return fallback;
    }
    if (ok)
        *ok = 1;
    return cm_v3(a.x / n, a.y / n, a.z / n);
}

/** perp(a, c) = unit(a - (a.ĉ)ĉ), the part of a orthogonal to c (spec §1). */
static inline cm_vec3 cm_perp(cm_vec3 a, cm_vec3 c)
{
    cm_vec3 ch = cm_unit(c);
    return cm_unit(cm_sub(a, cm_scale(ch, cm_dot(a, ch))));
}

static inline cm_vec2 cm_add2(cm_vec2 a, cm_vec2 b) { return cm_v2(a.x + b.x, a.y + b.y); }
static inline cm_vec2 cm_sub2(cm_vec2 a, cm_vec2 b) { return cm_v2(a.x - b.x, a.y - b.y); }
static inline double cm_dot2(cm_vec2 a, cm_vec2 b) { return a.x * b.x + a.y * b.y; }
static inline double cm_cross2(cm_vec2 a, cm_vec2 b) { return a.x * b.y - a.y * b.x; }

/** 1 if every component is finite. */
static inline int cm_finite3(cm_vec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }

#endif /* CM_VEC_H */
