/*
 * igs_writer.h - a minimal IGES 5.3 writer for tests: entities with
 * free-format parameters, laid out in fixed 80-column S/G/D/P/T sections.
 * Tests build synthetic models with exactly known geometry and topology
 * (tests stand alone without ../shared/models).
 */
#ifndef IGS_WRITER_H
#define IGS_WRITER_H

#include <stddef.h>

#include "cm/cm_error.h"
#include "model_load.h"

typedef struct igw {
    struct igw_ent {
        int type, form, xform, subord, color, blank;
        char *params; /* "1.,2.,3" without the type number and terminator */
    } *e;
    int n, cap;
    int units;     /* Global units flag (2 = mm) */
    double scale;  /* model space scale */
    char exporter[64];
} igw;

void igw_init(igw *w);
void igw_free(igw *w);

/** Add an entity; params is printf-style text of its parameters (comma separated). Returns its DE. */
int igw_add(igw *w, int type, int form, const char *fmt, ...) __attribute__((format(printf, 4, 5)));

/** Mark entity `de` subordinate (physically dependent) and/or give it a transformation or colour. */
void igw_set(igw *w, int de, int subord, int xform, int color);
/** Mark entity `de` blanked (hidden: status blank = 01). */
void igw_blank(igw *w, int de);

/** The whole file (malloc'd, NUL-terminated); *len its length. */
char *igw_text(const igw *w, size_t *len);

/** Write the file to `path`; 0 on success. */
int igw_save(const igw *w, const char *path);

/* ---- shapes used by the tests ---- */

/** Box [0,a]x[0,b]x[0,c] with a through hole of radius r along z at (a/2, b/2), as 7 trimmed (144) faces. */
void igw_box_with_hole_144(igw *w, double a, double b, double c, double r);

/** Box [0,a]x[0,b]x[0,c] as 6 trimmed (144) plane faces on bilinear patches. */
void igw_box_144(igw *w, double a, double b, double c);

/** A pyramid: n (3..128) triangular sides from a regular n-gon of radius r at z = 0 to the apex at
 *  height h, and the n-gon base, as n + 1 trimmed (144) faces on planar bilinear patches: n + 1
 *  edges meet at the apex. */
void igw_pyramid_144(igw *w, int n, double r, double h);

/** The same solid as a 186 manifold solid B-rep (502/504/508/510/514, planes 190, cylinder 192). */
void igw_box_with_hole_186(igw *w, double a, double b, double c, double r);
/** The same, with every face's orientation flag in the shell (514) turned when inside_out: an
 *  exporter that wrote the solid inside out (every normal pointing in). */
void igw_box_with_hole_186_oriented(igw *w, double a, double b, double c, double r, int inside_out);

/** Half cylinder radius r, height h, as an untrimmed 120 surface of revolution (line revolved by pi). */
void igw_half_cylinder_120(igw *w, double r, double h);

/** The same half cylinder under a mirroring 124 (form 1, y -> -y): the surface must be the half at y <= 0. */
void igw_half_cylinder_120_mirrored(igw *w, double r, double h);

/** A planar square [0,a]^2 (z = 0) as a 144 whose boundary composite lists its sides out of order,
 *  two of them backwards. */
void igw_square_scrambled_144(igw *w, double a);

/** An untrimmed bicubic 128 patch: P_ij = (i, j, z_ij) with z from a fixed table. */
void igw_bicubic_128(igw *w);
/** An untrimmed bicubic 128 of n x n points on uneven knots over [0,a]^2, a dish flat inside and
 *  steep at its rim (z = h (s^8 + t^8), s and t from -1 to 1, at each point): far more points
 *  than its shape needs. */
void igw_dense_128(igw *w, int n, double a, double h);
/** Half cylinder (radius r, height h, axis z, angles 0..pi) as two 144 quarter faces, each on a
 *  120 surface of revolution, sharing the line at angle pi/2 (spec §17 T5). */
void igw_split_half_cylinder_144(igw *w, double r, double h);

/* one half cylinder (a 120 from 0 to pi, as igw_half_cylinder_120) trimmed by a 144 whose two
   straight edges are each cut into `pieces` (1..16) lines of unequal length: as1_pe_203's kept
   half cylinders, whose loops have points along their rulings */
void igw_ruled_half_cylinder_144(igw *w, double r, double h, int pieces);

/* a trough z = 4 h t (1 - t), t = y / b, over [0, a] x [0, b] as one bicubic 128 (straight along x
   but of degree 3 both ways, as an exporter's re-fitted cylinder), trimmed by a 144 whose two
   straight edges are each cut into `pieces` (1..16) lines of unequal length */
void igw_trough_144(igw *w, double a, double b, double h, int pieces);

/* one face: a bicubic bump of height h over the square [0,a]^2 at z = 0, flat (with its cross
   slopes) on its four straight edges - the patches from the boundary come out flat */
/* igw_split_half_cylinder_144 with T-vertices: the first quarter's bottom arc and the second's top
   arc cut into `pieces` (1..4) arcs at unequal angles (pieces 2: at 3/8); `both`: the first
   quarter's top arc too (pieces 4: ten edges, six flat corners) */
void igw_t_vertex_half_cylinder_144(igw *w, double r, double h, int pieces, int both);
void igw_bump_144(igw *w, double a, double h);
/** The bump's three-sided sibling: a biquartic 128 over the right triangle (0,0), (a,0), (0,a), flat
 *  with its cross slopes on all three straight edges, h high at the centroid; one 144. */
void igw_tri_bump_144(igw *w, double a, double h);
/** Two faces of z = h (x/a) (y/a)^3 over [-a, 0] and [0, a] x [-a, a] (a bicubic 128 each, their
 *  edges along y cubics, along x lines), sharing the line x = 0: along it the surface's normal
 *  (-h/a (y/a)^3, 0, 1) twists about the edge, where a normal carried from the ends stays put. */
void igw_twisted_pair_144(igw *w, double a, double h);
/** The model w holds, imported as `name` (w freed): model_load_data's result. */
cm_err igw_load(igw *w, const char *name, loaded_model *lm, cm_status *st);

/** Spec §17 T8 without its hole: the L-shaped polygon (0,0), (20,0), (20,8), (8,8), (8,16), (0,16)
 *  lifted onto z = 0.02 (x^2 - 0.5 y^2) + 0.1 x + 0.01 x y (a biquadratic 128; each edge an exact
 *  quadratic 126), one 144 with a reflex corner at (8, 8). */
void igw_l_shape_144(igw *w);
/** The square [-a, a]^2 (a < 20) lifted onto the paraboloid z = 5 (1 - (x^2 + y^2) / 400) (a
 *  biquadratic 128; each side an exact quadratic 126) with a round hole of radius r0 about the apex
 *  (two arcs at one height): one 144 with one inner loop. */
void igw_dome_square_hole_144(igw *w, double a, double r0);

/* one face on that dome: the half band r0 <= r <= r1 (< 20) over y >= 0, bounded by two half circles
   about the apex (edges whose end bases are opposite while the surface turns round with them: the
   turning basis of format 2.6) and two parabolas along y = 0 */
void igw_half_dome_band_144(igw *w, double r0, double r1);
/** The z values of igw_bicubic_128 (row-major [i][j]). */
extern const double igw_bicubic_z[4][4];

/** A flat disc of radius r at height z: a 144 on a bilinear 128, its outer loop one full circle (100). */
int igw_disc_144(igw *w, double r, double z);

/* ---- building blocks for hostile inputs (tests/host/test_import_hostile.c) ---- */

/** A planar square [0,a]^2 at height z as a 144 (bilinear 128, composite of 4 lines); returns the
 *  144's DE.  `subord` 1 makes it a member of something (a subfigure) rather than a top-level face. */
int igw_square_144(igw *w, double a, double z, int subord);

/** A 124 transformation x -> R x + t with m = {R11, R12, R13, T1, R21, ..., T3} (the file's order);
 *  returns its DE. */
int igw_transform_124(igw *w, const double m[12]);

/**
 * An acyclic subfigure DAG: definition 0 holds one square face; definition k (1..levels) holds
 * `fan` 408 instances of definition k-1; one top-level 408 places the last definition, so the
 * model places fan^levels faces.  Returns the DE of the top-level instance.
 */
int igw_subfigure_dag(igw *w, int levels, int fan);

/**
 * An assembly: the box with a hole (igw_box_with_hole_144, 40 x 30 x 20, r 5) as one subfigure
 * definition (308), placed `copies` times by top-level 408 instances, copy k under the 124
 * xform[k] (row-major 3 x 4: {R11, R12, R13, T1, R21, ...}).  Returns the 308's DE.
 */
int igw_placed_boxes(igw *w, int copies, const double (*xform)[12]);
/* the same, the subfigure named name (at most 100 bytes) */
int igw_placed_boxes_named(igw *w, int copies, const double (*xform)[12], const char *name);

/**
 * A trimmed square whose hole is a composite-curve DAG: composite 0 is a full circle (100),
 * composite k (1..levels) lists composite k-1 `fan` times, so the hole flattens into fan^levels
 * pieces.  Returns the DE of the 144.
 */
int igw_composite_dag_144(igw *w, int levels, int fan);

#endif /* IGS_WRITER_H */
