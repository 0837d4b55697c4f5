/* A texture in a BSDF row's header replaces the colour parameter the plugin hands to bsdf_texture (ETH Nori's
   checkerboard_color). Row: texture = TEXTURE_CHECKERBOARD, tex[0] = value2, tex[1] = (delta_u, delta_v,
   scale_u, scale_v); the plugin's own colour parameter holds value1. value1 where
   floor(u/su - du) + floor(v/sv - dv) is even (delta is in cells; clrender/bsdfs/checkerboard.py derives this
   from the ETH course's references). */
#ifndef CLRENDER_BSDFS_TEXTURE_H
#define CLRENDER_BSDFS_TEXTURE_H
#include "math.h"

INLINE float3 bsdf_texture(__global const Bsdf* b, float4 base, float2 uv) {
    if (b->texture == TEXTURE_CHECKERBOARD) {
        float4 t = b->tex[1];
        float cu = floor(uv.x / t.z - t.x);
        float cv = floor(uv.y / t.w - t.y);
        /* parity of a sum of floats that are integers: fmod keeps it exact for any magnitude */
        float s = fabs(fmod(cu + cv, 2.0f));
        return s < 0.5f ? base.xyz : b->tex[0].xyz;
    }
    return base.xyz;
}

#endif
