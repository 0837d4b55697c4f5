/* Textures: rows of the scene's textures table, evaluated through texture_eval (generated from the registered
   texture plugins: kernels/textures/<prefix>.h). A BSDF parameter declared as "texture" ("float_texture") in Python
   is a constant colour (float) plus the index of a texture row (NONE: use the constant), fields name and name_tex
   (clrender/device/layout.py TEXTURED); param_color (param_float) reads it at the query's uv. */
#ifndef CLRENDER_TEXTURE_H
#define CLRENDER_TEXTURE_H
#include "gen/texture_dispatch.h"
#include "bsdfs/common.h"

/* value: the parameter's float4 field of a __global row (read as three floats: kernels/math.h vrow) */
INLINE vec3 param_color_at(const BsdfQuery* q, __global const float* value, uint tex) {
    return tex == NONE ? v3(value[0], value[1], value[2]) : texture_eval(q->textures + tex, q->uv);
}
#define param_color(q, value, tex) param_color_at(q, (__global const float*)&(value), tex)

/* The host gives a float parameter the texture's float view (Texture.float_view), whose first channel it is. */
INLINE float param_float(const BsdfQuery* q, float value, uint tex) {
    return tex == NONE ? value : texture_eval(q->textures + tex, q->uv).x;
}

/* A float parameter by its name in a plugin's parameter struct: PARAM_FLOAT(q, b->p.principled, roughness) */
#define PARAM_FLOAT(q, params, name) param_float(q, (params).name, (params).name##_tex)

#endif
