/* Lambertian: f = albedo/pi when wi and wo are both above the surface; cosine-weighted sampling.
   Row: p.diffuse.albedo, albedo_tex (a colour or a texture: see texture.h). */
#ifndef CLRENDER_BSDFS_DIFFUSE_H
#define CLRENDER_BSDFS_DIFFUSE_H
#include "common.h"
#include "../texture.h"
#include "warp.h"

INLINE vec3 diffuse_eval(__global const Bsdf* b, const BsdfQuery* q) {
    if (q->wi.z <= 0.0f || q->wo.z <= 0.0f) return v3s(0.0f);
    return vscale(param_color(q, b->p.diffuse.albedo, b->p.diffuse.albedo_tex), INV_PI);
}

INLINE float diffuse_pdf(__global const Bsdf* b, const BsdfQuery* q) {
    if (q->wi.z <= 0.0f || q->wo.z <= 0.0f) return 0.0f;
    return q->wo.z * INV_PI;
}

INLINE vec3 diffuse_sample(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    q->measure = MEASURE_SOLID_ANGLE;
    q->eta = 1.0f;
    q->wo = square_to_cosine_hemisphere(u);
    /* f cos / pdf = albedo; a direction on the horizon has pdf 0 and gets no weight */
    if (q->wi.z <= 0.0f || q->wo.z <= 0.0f) return v3s(0.0f);
    return param_color(q, b->p.diffuse.albedo, b->p.diffuse.albedo_tex);
}

INLINE vec3 diffuse_albedo(__global const Bsdf* b, const BsdfQuery* q) {
    return param_color(q, b->p.diffuse.albedo, b->p.diffuse.albedo_tex);
}

#endif
