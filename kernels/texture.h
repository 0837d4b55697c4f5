/* Textures: rows of the scene's textures table, evaluated through texture_eval (generated from the registered
   texture plugins: kernels/textures/<prefix>.h). A BSDF parameter declared as "texture" in Python is a constant
   colour plus the index of a texture row (NONE: use the constant); param_color reads it at the query's uv. */
#ifndef CLRENDER_TEXTURE_H
#define CLRENDER_TEXTURE_H
#include "gen/texture_dispatch.h"
#include "bsdfs/common.h"

INLINE float3 param_color(const BsdfQuery* q, float4 value, uint tex) {
    return tex == NONE ? value.xyz : texture_eval(q->textures + tex, q->uv);
}

#endif
