/* Mitsuba 3's projection light (clrender/emitters/projector.py): a pinhole projecting the irradiance texture, the
   reciprocal of the perspective sensor.

   Emitter row: flags EMITTER_DELTA; p.projector: irradiance.xyz = E, irradiance_tex = a texture's row or NONE,
   irradiance.w = pi scale; position.xyz = the pinhole, position.w = 0.5 cot(fov_x / 2); inv[0..2].xyz = rows of
   the inverse of to_world's linear part, (inv[0].w, inv[1].w, inv[2].w) = n = to_world (0, 0, 1); v_scale =
   0.5 aspect cot(fov_x / 2).
   sample: wi toward the pinhole, pdf 1, delta 1; returns pi scale E(uv) / (z^2 (n . -wi)) for a reference point
   at local (x, y, z), z > 0, whose uv = (0.5 - position.w x / z, 0.5 - v_scale y / z) lies in [0, 1]^2, else 0.
   The 1 / (z^2 cos) is a perspective camera's inverse importance over dist^2 (dist^2 cos^3 = z^2 cos): it makes
   the irradiance on the plane z = 1 that of the texture (times pi scale) everywhere, not darker towards the
   corners. */
#ifndef CLRENDER_EMITTERS_PROJECTOR_H
#define CLRENDER_EMITTERS_PROJECTOR_H
#include "common.h"
#include "gen/texture_dispatch.h"

INLINE vec3 projector_sample(const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u) {
    vec3 o = vrow(em->p.projector.position);
    if (!(emitter_point_query(q, o) > 0.0f)) return v3s(0.0f);
    vec3 d = vsub(q->ref, o);
    float z = dot3(vrow(em->p.projector.inv[2]), d);
    if (!(z > 0.0f)) return v3s(0.0f);
    float2 uv = (float2)(0.5f - em->p.projector.position.w * dot3(vrow(em->p.projector.inv[0]), d) / z,
                         0.5f - em->p.projector.v_scale * dot3(vrow(em->p.projector.inv[1]), d) / z);
    if (!(uv.x >= 0.0f && uv.x <= 1.0f && uv.y >= 0.0f && uv.y <= 1.0f)) return v3s(0.0f);
    vec3 n = v3(em->p.projector.inv[0].w, em->p.projector.inv[1].w, em->p.projector.inv[2].w);
    /* n . (ref - o) / dist: to_world need not be rigid, so this is not z / dist */
    float cosn = dot3(n, d) / q->dist;
    if (!(cosn > 0.0f)) return v3s(0.0f);
    uint tex = em->p.projector.irradiance_tex;
    vec3 E = tex == NONE ? vrow(em->p.projector.irradiance) : texture_eval(sd->textures + tex, uv);
    return vscale(E, em->p.projector.irradiance.w / (z * z * cosn));
}

#endif
