/* heterogeneous (clrender/media/heterogeneous.py): sigma_t and albedo read from volumes (rows of sd->volumes).
   Row: p.heterogeneous.sigma_t, .albedo (rows of `volumes`), .scale (multiplies sigma_t), .majorant (scale times
   the sigma_t volume's largest value over every channel, Mitsuba's m_max_density). As Mitsuba's, the medium has
   extinction only inside the sigma_t volume's bounding box (its intersect_aabb). */
#ifndef CLRENDER_MEDIA_HETEROGENEOUS_H
#define CLRENDER_MEDIA_HETEROGENEOUS_H
#include "math.h"
#include "gen/volume_dispatch.h"

INLINE vec3 heterogeneous_sigma_t(const SceneData* sd, __global const Medium* m, vec3 p) {
    return vscale(volume_eval(sd, sd->volumes + m->p.heterogeneous.sigma_t, p), m->p.heterogeneous.scale);
}

INLINE vec3 heterogeneous_albedo(const SceneData* sd, __global const Medium* m, vec3 p) {
    return volume_eval(sd, sd->volumes + m->p.heterogeneous.albedo, p);
}

INLINE float heterogeneous_majorant(const SceneData* sd, __global const Medium* m) {
    return m->p.heterogeneous.majorant;
}

/* [t0, t1] cut to the slab intersection of o + t d with the sigma_t volume's box. */
INLINE bool heterogeneous_clip(const SceneData* sd, __global const Medium* m, vec3 o, vec3 d, float* t0,
                               float* t1) {
    __global const Volume* v = sd->volumes + m->p.heterogeneous.sigma_t;
    vec3 lo = vrow(v->bbox_min), hi = vrow(v->bbox_max);
    float a = *t0, b = *t1;
    float ox[3] = {o.x, o.y, o.z}, dx[3] = {d.x, d.y, d.z}, l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
    for (int i = 0; i < 3; ++i) {
        if (dx[i] == 0.0f) {
            if (ox[i] < l[i] || ox[i] > h[i]) return false;
            continue;
        }
        float inv = 1.0f / dx[i];
        float ta = (l[i] - ox[i]) * inv, tb = (h[i] - ox[i]) * inv;
        a = fmax(a, fmin(ta, tb));
        b = fmin(b, fmax(ta, tb));
    }
    *t0 = a;
    *t1 = b;
    return a < b;
}
#endif
