/* ETH Nori's checkerboard_color: value1 where floor(u/su - du) + floor(v/sv - dv) is even, else value2 (delta is in
   cells; clrender/textures/checkerboard_color.py derives this from the ETH course's references).
   Row: p.checkerboard_color.value1, value2, delta_scale = (du, dv, su, sv). */
#ifndef CLRENDER_TEXTURES_CHECKERBOARD_COLOR_H
#define CLRENDER_TEXTURES_CHECKERBOARD_COLOR_H

INLINE vec3 checkerboard_color_eval(__global const Texture* t, float2 uv) {
    float4 ds = t->p.checkerboard_color.delta_scale;
    float cu = floor(uv.x / ds.z - ds.x);
    float cv = floor(uv.y / ds.w - ds.y);
    /* parity of a sum of floats that are integers: fmod keeps it exact for any magnitude */
    float s = fabs(fmod(cu + cv, 2.0f));
    return s < 0.5f ? vrow(t->p.checkerboard_color.value1) : vrow(t->p.checkerboard_color.value2);
}

#endif
