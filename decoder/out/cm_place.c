/* cm_place.c - a model's placed copies appended to its mesh (see cm_place.h). */
#include "cm/cm_place.h"

#include <math.h>

#include "cm/cm_limits_info.h"

void cm_place_counts(const cm_model *m, const uint32_t *tris, uint64_t *add_tris, uint64_t *add_faces)
{
    uint64_t t = 0, f = 0;
    for (uint32_t k = 0; k < m->nplacements; k++) {
        const cm_placement *P = &m->placements[k];
        for (uint32_t i = P->first; tris && i < P->first + P->count && i < m->nfaces; i++)
            t += tris[i];
        f += P->count;
    }
    *add_tris = t;
    *add_faces = f;
}

/* the cofactor matrix of M's linear part, signed by det M: it maps normals as M maps the surface;
   returns det M */
static double normal_map(const double *a, double c[9])
{
    c[0] = a[5] * a[10] - a[6] * a[9];
    c[1] = a[6] * a[8] - a[4] * a[10];
    c[2] = a[4] * a[9] - a[5] * a[8];
    c[3] = a[2] * a[9] - a[1] * a[10];
    c[4] = a[0] * a[10] - a[2] * a[8];
    c[5] = a[1] * a[8] - a[0] * a[9];
    c[6] = a[1] * a[6] - a[2] * a[5];
    c[7] = a[2] * a[4] - a[0] * a[6];
    c[8] = a[0] * a[5] - a[1] * a[4];
    double det = a[0] * c[0] + a[1] * c[1] + a[2] * c[2];
    if (det < 0.0)
        for (int i = 0; i < 9; i++)
            c[i] = -c[i];
    return det;
}

cm_err cm_mesh_place(const cm_model *m, cm_mesh *mesh, cm_status *st)
{
    const cm_mesh_mark mark = cm_mesh_save(mesh);
    const uint32_t n = mesh->nfaces;
    for (uint32_t k = 0; k < m->nplacements; k++) {
        const cm_placement *P = &m->placements[k];
        const double *a = P->m;
        double c[9];
        const int mirror = normal_map(a, c) < 0.0;
        for (uint32_t i = cm_mesh_face_from(mesh, n, P->first); i < n && mesh->faces[i].source_face < P->first + P->count;
             i++) {
            const cm_mesh_face src = mesh->faces[i];
            if (mesh->nfaces >= mesh->cap_faces) {
                cm_mesh_rollback(mesh, &mark);
                return cm_fail_limit(st, CM_LIMIT_MAX_FACES, (uint64_t)mesh->nfaces + 1u, mesh->cap_faces,
                                     "placed copies (mesh faces)");
            }
            if (src.nverts > mesh->cap_verts - mesh->nverts || src.nindex > mesh->cap_index - mesh->nindex) {
                uint64_t need = ((uint64_t)mesh->nindex + src.nindex) / 3u;
                cm_mesh_rollback(mesh, &mark);
                return cm_fail_limit(st, CM_LIMIT_MAX_TRIS, need, mesh->cap_index / 3u, "placed copies");
            }
            cm_mesh_face *dst = &mesh->faces[mesh->nfaces];
            *dst = src;
            dst->first_vert = mesh->nverts;
            dst->first_index = mesh->nindex;
            /* a streaming mesh takes the copy in runs that fit its window (a face of several
               patches can be larger than one: cm_mesh_make_room flushed between them) */
            for (uint32_t v0 = 0; v0 < src.nverts;) {
                uint32_t run = src.nverts - v0;
                if (mesh->spill && run > mesh->win_cap_verts)
                    run = mesh->win_cap_verts;
                cm_err room = cm_mesh_make_room(mesh, run, 0, st);
                if (room != CM_OK) {
                    cm_mesh_rollback(mesh, &mark);
                    return room;
                }
                for (uint32_t v = v0; v < v0 + run; v++) {
                    float p[3], q[3];
                    cm_mesh_pos(mesh, src.first_vert + v, p);
                    cm_mesh_nrm(mesh, src.first_vert + v, q);
                    double x = (double)p[0], y = (double)p[1], z = (double)p[2];
                    double nx = (double)q[0], ny = (double)q[1], nz = (double)q[2];
                    double X = a[0] * x + a[1] * y + a[2] * z + a[3];
                    double Y = a[4] * x + a[5] * y + a[6] * z + a[7];
                    double Z = a[8] * x + a[9] * y + a[10] * z + a[11];
                    double NX = c[0] * nx + c[1] * ny + c[2] * nz;
                    double NY = c[3] * nx + c[4] * ny + c[5] * nz;
                    double NZ = c[6] * nx + c[7] * ny + c[8] * nz;
                    double len = sqrt(NX * NX + NY * NY + NZ * NZ);
                    if (!(fabs(X) <= 3.0e38 && fabs(Y) <= 3.0e38 && fabs(Z) <= 3.0e38)) {
                        cm_mesh_rollback(mesh, &mark);
                        return cm_fail(st, CM_E_NONFINITE, "placed copies: a vertex beyond float range");
                    }
                    uint32_t at = dst->first_vert + v;
                    float *o = cm_mesh_wpos(mesh, at), *on = cm_mesh_wnrm(mesh, at);
                    o[0] = (float)X;
                    o[1] = (float)Y;
                    o[2] = (float)Z;
                    if (len > 0.0) {
                        on[0] = (float)(NX / len);
                        on[1] = (float)(NY / len);
                        on[2] = (float)(NZ / len);
                    } else {
                        on[0] = q[0];
                        on[1] = q[1];
                        on[2] = q[2];
                    }
                }
                mesh->nverts += run;
                v0 += run;
            }
            for (uint32_t t0 = 0; t0 < src.nindex;) {
                uint32_t run = src.nindex - t0;
                if (mesh->spill && run > mesh->win_cap_index)
                    run = mesh->win_cap_index;
                cm_err room = cm_mesh_make_room(mesh, 0, run, st);
                if (room != CM_OK) {
                    cm_mesh_rollback(mesh, &mark);
                    return room;
                }
                for (uint32_t t = t0; t < t0 + run; t++) {
                    /* a mirrored copy's triangles reversed: each one's second and third vertices
                       swapped (corner r of 1, 2 takes corner 3 - r; a trailing part triangle stays) */
                    uint32_t r = t % 3u, from = mirror && r ? t - r + (3u - r) : t;
                    if (from >= src.nindex)
                        from = t;
                    *cm_mesh_widx(mesh, dst->first_index + t) =
                        cm_mesh_idx(mesh, src.first_index + from) - src.first_vert + dst->first_vert;
                }
                mesh->nindex += run;
                t0 += run;
            }
            if (cm_mesh_spill_failed(mesh)) {
                cm_mesh_rollback(mesh, &mark);
                return cm_fail(st, CM_E_IO, "placed copies: reading the part back from the mesh spill");
            }
            mesh->nfaces++;
        }
    }
    if (m->nplacements > 0) {
        mesh->nbase_faces = mark.nfaces;
        mesh->nbase_verts = mark.nverts;
        mesh->nbase_index = mark.nindex;
        mesh->nplace = m->nplacements;
        mesh->place = m->placements;
    }
    return CM_OK;
}
