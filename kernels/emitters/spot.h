/* Mitsuba 3's spot light (clrender/emitters/spot.py): a point light whose intensity falls off linearly in angle
   between the beam width and the cutoff about its local +z.

   Emitter row: flags EMITTER_DELTA; p.spot: intensity.xyz = I, intensity.w = 1 / tan cutoff; position.xyz, position.w = 1 / (cutoff - beam);
   inv[0..2].xyz = rows of the inverse of to_world's linear part; inv[0].w = cos cutoff, inv[1].w = cos beam,
   inv[2].w = cutoff (radians); texture_tex = a projected texture's row or NONE.
   sample: wi toward the light, returns I falloff(-wi) tex(uv(-wi)) / dist^2 with pdf 1 and delta = 1, where uv is
   Mitsuba's direction_to_uv: 0.5 + 0.5 (x, y) / (z tan cutoff) of the local direction. */
#ifndef CLRENDER_EMITTERS_SPOT_H
#define CLRENDER_EMITTERS_SPOT_H
#include "common.h"
#include "gen/texture_dispatch.h"

INLINE vec3 spot_local(__global const Emitter* em, vec3 d) {
    return normalize3(v3(dot3(vrow(em->p.spot.inv[0]), d), dot3(vrow(em->p.spot.inv[1]), d),
                         dot3(vrow(em->p.spot.inv[2]), d)));
}

/* Falloff of the local direction ld leaving the light. */
INLINE float spot_falloff(__global const Emitter* em, vec3 ld) {
    float c = ld.z;
    if (!(c > em->p.spot.inv[0].w)) return 0.0f;
    if (c >= em->p.spot.inv[1].w) return 1.0f;
    return (em->p.spot.inv[2].w - acos(clampf(c, -1.0f, 1.0f))) * em->p.spot.position.w;
}

INLINE vec3 spot_sample(const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u) {
    float inv_d2 = emitter_point_query(q, vrow(em->p.spot.position));
    if (!(inv_d2 > 0.0f)) return v3s(0.0f);
    vec3 ld = spot_local(em, vneg(q->wi));
    float falloff = spot_falloff(em, ld);
    if (!(falloff > 0.0f)) return v3s(0.0f);   /* outside the cone: no texture lookup (Mitsuba's too) */
    vec3 I = vrow(em->p.spot.intensity);
    uint tex = em->p.spot.texture_tex;
    if (tex != NONE) {
        float k = 0.5f * em->p.spot.intensity.w / ld.z;
        I = vmul(I, texture_eval(sd->textures + tex, (float2)(0.5f + k * ld.x, 0.5f + k * ld.y)));
    }
    return vscale(I, falloff * inv_d2);
}

#endif
