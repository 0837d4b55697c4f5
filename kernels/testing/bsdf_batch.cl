/* Test kernels (clrender/testing/kernels.py): bsdf_sample, bsdf_pdf and bsdf_eval in bulk, for the statistical
   tests of every BSDF. */
#include "rng.h"
#include "bsdf.h"

/* Work-item i's query: its wi, wo and uv, the side tables, and the surface's derivatives where the program carries
   them (kernels/derivatives.h): geo[4 i .. 4 i + 3] = dp/du, dp/dv, the geometric normal (local frame) and dp/du in
   world space. */
INLINE BsdfQuery batch_query(vec3 wi, vec3 wo, float2 uv, __global const Texture* textures,
                             __global const BsdfTable* tables, __global const float4* geo, uint i) {
    BsdfQuery q;
    q.wi = wi;
    q.wo = wo;
    q.eta = 1.0f;
    q.measure = MEASURE_SOLID_ANGLE;
    q.uv = uv;
    q.textures = textures;
    q.tables = tables;
#ifdef CLR_SURFACE_DERIVATIVES
    q.dpdu = vrow(geo[4u * i]);
    q.dpdv = vrow(geo[4u * i + 1u]);
    q.ng = vrow(geo[4u * i + 2u]);
    q.dpdu_world = vrow(geo[4u * i + 3u]);
#endif
    return q;
}

/* One bsdf_sample per work-item. args[i] = (wi.xyz, bitcast row index); uvs[i] = uv. */
__kernel void bsdf_sample_batch(__global const Bsdf* rows, __global const Texture* textures,
                                __global const BsdfTable* tables, __global const float4* args,
                                __global const float2* uvs, __global const float4* geo, uint n, uint first, uint seed,
                                __global float4* wo_out, __global float4* w_out, __global float4* f_out,
                                __global float* pdf_out, __global uint* measure_out) {
    uint i = get_global_id(0);
    if (i >= n) return;
    float4 a = args[i];
    __global const Bsdf* b = rows + as_uint(a.w);
    Sampler s;
    sampler_init(&s, seed, first + i, 0u);
    BsdfQuery q = batch_query(vxyz(a), v3s(0.0f), uvs[i], textures, tables, geo, i);
    vec3 w = bsdf_sample(b, &q, next2d(&s));
    wo_out[i] = vf4(q.wo, q.eta);
    w_out[i] = vf4(w, 0.0f);
    f_out[i] = vf4(bsdf_eval(b, &q), 0.0f);
    pdf_out[i] = bsdf_pdf(b, &q);
    measure_out[i] = q.measure;
}

/* bsdf_pdf and bsdf_eval for given (wi, wo); wi[i].w = bitcast row index, wo[i].w unused. */
__kernel void bsdf_pdf_eval_batch(__global const Bsdf* rows, __global const Texture* textures,
                                  __global const BsdfTable* tables, __global const float4* wi_in,
                                  __global const float4* wo_in, __global const float2* uvs, __global const float4* geo,
                                  uint n,
                                  __global float* pdf_out, __global float4* f_out, __global float4* alb_out) {
    uint i = get_global_id(0);
    if (i >= n) return;
    float4 a = wi_in[i];
    __global const Bsdf* b = rows + as_uint(a.w);
    BsdfQuery q = batch_query(vxyz(a), vxyz(wo_in[i]), uvs[i], textures, tables, geo, i);
    pdf_out[i] = bsdf_pdf(b, &q);
    f_out[i] = vf4(bsdf_eval(b, &q), bsdf_is_delta(b) ? 1.0f : 0.0f);
    alb_out[i] = vf4(bsdf_albedo(b, &q), 0.0f);
}
