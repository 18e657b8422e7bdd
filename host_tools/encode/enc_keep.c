/* enc_keep.c - the encoder's half of KEEP (decoder/methods/keep.c): nothing to try, the kept
   surface measured for the report. */
#include "enc_method.h"

#include <math.h>

#include "cm/cm_method.h"

/* distance between the original surface and the kept one at a 21 x 21 grid of the same parameters */
static void measure_keep(enc_work *w, const loaded_model *lm, int f, face_report *rep)
{
    const hsurf *orig = &lm->brep.surfs[lm->brep.faces[lm->mesh.faces[f].brep_face].surf];
    cm_surf kept;
    cm_model_surface(&w->dec.model, w->dec.model.faces[f].surf, &kept);
    cm_surf ov = hsurf_view(orig);
    double u0, u1, v0, v1, worst = 0;
    hsurf_domain(orig, &u0, &u1, &v0, &v1);
    for (int i = 0; i <= 20; i++)
        for (int j = 0; j <= 20; j++) {
            cm_vec3 a[3][3], b[3][3];
            double s = i / 20.0, t = j / 20.0;
            if (cm_surf_eval(&ov, u0 + (u1 - u0) * s, v0 + (v1 - v0) * t, 0, a, NULL) != CM_OK ||
                cm_surf_eval(&kept, s, t, 0, b, NULL) != CM_OK)
                continue;
            worst = fmax(worst, cm_dist(a[0][0], b[0][0]));
        }
    rep->rebuild_max = worst;
    rep->ratio = rep->bbox > 0 ? worst / rep->bbox : 0;
    rep->surf_ctrl = kept.nu * kept.nv;
}

const enc_method enc_method_keep = {CM_METHOD_KEEP, NULL, measure_keep};
