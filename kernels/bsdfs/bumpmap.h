/* bumpmap: the child in the frame of the normal that the height texture's slope gives (kernels/bsdfs/perturb.h):
   with (gu, gv) = scale * the bitmap's uv gradient (bitmap_grad, Mitsuba's eval_1_grad), dp/du and dp/dv get gu
   and gv as their components along the shading normal, n = dp/du x dp/dv, turned to the geometric normal's side.
   Needs the derivatives in the query (kernels/derivatives.h). Row: p.bumpmap = tex (the height bitmap's float
   view, a row of the textures table), scale, child (offset of the child's row), options. Included once per nesting
   level (see twosided.h). */
#ifndef CLRENDER_BSDFS_BUMPMAP_H
#define CLRENDER_BSDFS_BUMPMAP_H
#include "perturb.h"
#include "textures/bitmap.h"
INLINE Frame bumpmap_frame(__global const Bsdf* b, const BsdfQuery* q) {
    float2 g = b->p.bumpmap.scale * bitmap_grad(q->textures + b->p.bumpmap.tex, q->uv);
    float3 du = (float3)(q->dpdu.x, q->dpdu.y, g.x), dv = (float3)(q->dpdv.x, q->dpdv.y, g.y);
    float3 n = cross3(du, dv);
    if (dot3(q->ng, n) < 0.0f) n = -n;
    return perturbed_frame(n, q->wi, q->dpdu_world, b->p.bumpmap.options);
}
#endif

INLINE float3 COMPOSITE_FN(bumpmap_eval)(__global const Bsdf* b, const BsdfQuery* q) {
    Frame f = bumpmap_frame(b, q);
    BsdfQuery c;
    if (!perturb_query(&f, q, &c)) return (float3)(0.0f);
    /* the child's f holds no cosine, which the integrators take of wo in this frame, not the child's */
    return CHILD_FN(eval)(b + b->p.bumpmap.child, &c) *
           (fabs(c.wo.z) / fabs(q->wo.z) * perturb_shadowing(b->p.bumpmap.options, &f, q->wo));
}

INLINE float COMPOSITE_FN(bumpmap_pdf)(__global const Bsdf* b, const BsdfQuery* q) {
    Frame f = bumpmap_frame(b, q);
    BsdfQuery c;
    if (!perturb_query(&f, q, &c)) return 0.0f;
    return CHILD_FN(pdf)(b + b->p.bumpmap.child, &c);
}

INLINE float3 COMPOSITE_FN(bumpmap_sample)(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    Frame f = bumpmap_frame(b, q);
    BsdfQuery c;
    perturb_query(&f, q, &c);
    float3 w = CHILD_FN(sample)(b + b->p.bumpmap.child, &c, u);
    q->wo = to_world(&f, c.wo);
    q->eta = c.eta;
    q->measure = c.measure;
    if (!(c.wo.z * q->wo.z > 0.0f)) return (float3)(0.0f);
    return w * perturb_shadowing(b->p.bumpmap.options, &f, q->wo);
}

INLINE float3 COMPOSITE_FN(bumpmap_albedo)(__global const Bsdf* b, const BsdfQuery* q) {
    return CHILD_FN(albedo)(b + b->p.bumpmap.child, q);
}

/* the perturbed normal (aov's sh_normal); a wrapper's own, not its child's (Mitsuba 3.9's sh_frame) */
INLINE float3 COMPOSITE_FN(bumpmap_normal)(__global const Bsdf* b, const BsdfQuery* q) {
    return bumpmap_frame(b, q).n;
}
