/* ETH Nori's uvtexture: (|u mod 1|, |v mod 1|, 1/2) under a ±20 % ripple of period 1/8 in u and v
   (clrender/textures/uvtexture.py derives it). No parameters. */
#ifndef CLRENDER_TEXTURES_UVTEXTURE_H
#define CLRENDER_TEXTURES_UVTEXTURE_H

INLINE vec3 uvtexture_eval(__global const Texture* t, float2 uv) {
    /* sinpi/cospi keep the phase exact where 16πu would round */
    float su = sinpi(16.0f * uv.x), cu = cospi(16.0f * uv.x), sv = sinpi(16.0f * uv.y);
    return v3(fabs(fmod(uv.x, 1.0f)) * (1.0f - 0.2f * su * sv), fabs(fmod(uv.y, 1.0f)) * (1.0f - 0.2f * cu * sv),
              0.5f);
}

#endif
