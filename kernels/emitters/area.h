/* Area light on any shape: radiance L on the side the shading normal faces; L may be a texture over the surface's
   uv (Mitsuba's textured `radiance`; sampling stays uniform by area / by the subtended cone).

   Emitter row: flags EMITTER_SURFACE; shape = the emitting shape; p.area.radiance.xyz = L, radiance_tex = NONE or
   the texture's row (the shape then has SHAPE_NEEDS_UV, so that hits and samples carry uv). The shape samples its
   own surface (shape_sample/shape_pdf, generated from kernels/shapes/<name>.h): meshes uniformly by area
   (pdf = dist^2 / (A |cos theta_l|), theta_l against the geometric normal), spheres by the cone they subtend. */
#ifndef CLRENDER_EMITTERS_AREA_H
#define CLRENDER_EMITTERS_AREA_H
#include "common.h"
#include "gen/texture_dispatch.h"

INLINE vec3 area_radiance(const SceneData* sd, __global const Emitter* em, float2 uv) {
    uint tex = em->p.area.radiance_tex;
    return tex == NONE ? vrow(em->p.area.radiance) : texture_eval(sd->textures + tex, uv);
}

/* Complete the query from the emitting shape's sample (solid-angle density pdf at ref); returns L/pdf, or 0 when
   the point faces away from ref (one-sided) or the sample is unusable. */
INLINE vec3 area_sample(const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u) {
    ShapeSample ss;
    float pdf = shape_sample(sd, &sd->shapes[em->shape], q->ref, u, &ss);
    q->wi = ss.wi;
    q->p = ss.p;
    q->n = ss.n;
    q->ng = ss.ng;
    q->dist = ss.dist;
    q->pdf = pdf;
    q->uv = ss.uv;
    return (pdf > 0.0f && dot3(ss.n, ss.wi) < 0.0f) ? vscale(area_radiance(sd, em, ss.uv), 1.0f / pdf) : v3s(0.0f);
}

INLINE float area_pdf(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return shape_pdf(sd, &sd->shapes[em->shape], q->ref, q->p, q->ng, q->wi);
}

INLINE vec3 area_eval(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return dot3(q->n, q->wi) < 0.0f ? area_radiance(sd, em, q->uv) : v3s(0.0f);
}

#endif
