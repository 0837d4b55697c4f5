/* Mitsuba 3's checkerboard (clrender/textures/checkerboard.py): color0 where (frac(s) > 1/2) == (frac(t) > 1/2)
   for st = to_uv(uv), else color1. Row: p.checkerboard.c0 = (color0, a), c1 = (color1, b), uv2 = (c, d, e, f):
   s = a u + b v + c, t = d u + e v + f. */
#ifndef CLRENDER_TEXTURES_CHECKERBOARD_H
#define CLRENDER_TEXTURES_CHECKERBOARD_H

INLINE vec3 checkerboard_eval(__global const Texture* t, float2 uv) {
    float4 c0 = t->p.checkerboard.c0, c1 = t->p.checkerboard.c1, m = t->p.checkerboard.uv2;
    float s = c0.w * uv.x + c1.w * uv.y + m.x, tt = m.y * uv.x + m.z * uv.y + m.w;
    bool ms = s - floor(s) > 0.5f, mt = tt - floor(tt) > 0.5f;
    return ms == mt ? vxyz(c0) : vxyz(c1);
}

#endif
