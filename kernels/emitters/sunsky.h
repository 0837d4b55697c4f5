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

INLINE vec3 sunsky_radiance(const SceneData* sd, __global const Emitter* em, vec3 wi) {
    vec3 v = envmap_to_local(em, wi);
    float ct = v.y;
    if (ct < 0.0f) return v3s(0.0f);
    uint4 dims = em->p.envmap.dims;
    __global const float4* c = (__global const float4*)(sd->textures + dims.x) + dims.z * (dims.y + 1u);
    float cg = clampf(dot3(v, vrow(c[10])), -1.0f, 1.0f);
    float g = acos(cg);
    vec3 i = vrow(c[8]);
    vec3 b = vsub(vadds(vmul(i, i), 1.0f), vscale(vscale(i, 2.0f), cg));
    vec3 chi = vdiv(v3s(1.0f + cg * cg), vmul(b, vsqrt(b)));
    vec3 c1 = vadds(vmul(vrow(c[0]), vexp(vdivs(vrow(c[1]), ct + 0.01f))), 1.0f);
    vec3 c2 = vadd(vrow(c[2]), vmul(vrow(c[3]), vexp(vscale(vrow(c[4]), g))));
    c2 = vadd(c2, vscale(vrow(c[5]), cg * cg));
    c2 = vadd(c2, vmul(vrow(c[6]), chi));
    c2 = vadd(c2, vscale(vrow(c[7]), sqrt(ct)));
    return vmul(vmul(c1, c2), vrow(c[9]));
}

INLINE vec3 sunsky_sample(const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u) {
    envmap_sample(sd, em, q, u);
    return q->pdf > 0.0f ? vscale(sunsky_radiance(sd, em, q->wi), 1.0f / q->pdf) : v3s(0.0f);
}

INLINE float sunsky_pdf(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return envmap_pdf(sd, em, q);
}

INLINE vec3 sunsky_eval(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return sunsky_radiance(sd, em, q->wi);
}

#endif
