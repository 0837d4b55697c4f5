/* Mitsuba 3.9's sky (clrender/emitters/sunsky.py; its sun is a distantdisk row of its own): the Hosek-Wilkie model
   evaluated per direction, importance sampled by a latitude-longitude map of it made on the host. The row's
   parameters are an envmap's field for field (Sunsky.PARAMS is EnvMap.PARAMS), so envmap.h's functions sample the
   map through the union's envmap member.

   Why the model and not the map's bilinear lookup: the sky is black below the horizon and rises as sqrt(cos theta)
   above it, which no row spacing holds (a lookup blends the horizon row into the black one below, and is several
   percent off within a tenth of a degree above it). The map's cells below the horizon have no sampling weight, so sample and pdf
   never reach directions that eval calls black.

   Texels after the map's H x (W + 1): rows 0..8 the coefficients A..I (xyz = R, G, B), row 9 the mean radiance
   (sky_scale and Mitsuba's CIE normalisation folded in), row 10 the direction toward the sun in the map's frame
   (+y up, the frame of envmap_to_local). */
#ifndef CLRENDER_EMITTERS_SUNSKY_H
#define CLRENDER_EMITTERS_SUNSKY_H
#include "common.h"
#include "envmap.h"

INLINE float3 sunsky_radiance(const SceneData* sd, __global const Emitter* em, float3 wi) {
    float3 v = envmap_to_local(em, wi);
    float ct = v.y;
    if (ct < 0.0f) return (float3)(0.0f);
    uint4 dims = em->p.envmap.dims;
    __global const float4* c = (__global const float4*)(sd->textures + dims.x) + dims.z * (dims.y + 1u);
    float cg = clampf(dot3(v, c[10].xyz), -1.0f, 1.0f);
    float g = acos(cg);
    float3 i = c[8].xyz;
    float3 b = 1.0f + i * i - 2.0f * i * cg;
    float3 chi = (1.0f + cg * cg) / (b * sqrt(b));
    float3 c1 = 1.0f + c[0].xyz * exp(c[1].xyz / (ct + 0.01f));
    float3 c2 = c[2].xyz + c[3].xyz * exp(c[4].xyz * g) + c[5].xyz * (cg * cg) + c[6].xyz * chi
              + c[7].xyz * sqrt(ct);
    return c1 * c2 * c[9].xyz;
}

INLINE float3 sunsky_sample(const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u) {
    envmap_sample(sd, em, q, u);
    return q->pdf > 0.0f ? sunsky_radiance(sd, em, q->wi) * (1.0f / q->pdf) : (float3)(0.0f);
}

INLINE float sunsky_pdf(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return envmap_pdf(sd, em, q);
}

INLINE float3 sunsky_eval(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return sunsky_radiance(sd, em, q->wi);
}

#endif
