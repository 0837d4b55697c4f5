/* normalmap: the child in the frame of the normal 2 rgb - 1 that the texture gives, relative to the shading frame
   (kernels/bsdfs/perturb.h). Row: p.normalmap = normalmap(_tex) (a colour or a texture), child (offset of the
   child's row), options (PERTURB_FLIP, PERTURB_SHADOW). Included once per nesting level (see twosided.h). */
#ifndef CLRENDER_BSDFS_NORMALMAP_H
#define CLRENDER_BSDFS_NORMALMAP_H
#include "perturb.h"
INLINE Frame normalmap_frame(__global const Bsdf* b, const BsdfQuery* q) {
    float3 c = param_color(q, b->p.normalmap.normalmap, b->p.normalmap.normalmap_tex);
    return perturbed_frame(2.0f * c - 1.0f, q->wi, (float3)(1.0f, 0.0f, 0.0f), b->p.normalmap.options);
}
#endif

INLINE float3 COMPOSITE_FN(normalmap_eval)(__global const Bsdf* b, const BsdfQuery* q) {
    Frame f = normalmap_frame(b, q);
    BsdfQuery c;
    if (!perturb_query(&f, q, &c)) return (float3)(0.0f);
    /* the child's f holds no cosine, which the integrators take of wo in this frame, not the child's */
    return CHILD_FN(eval)(b + b->p.normalmap.child, &c) *
           (fabs(c.wo.z) / fabs(q->wo.z) * perturb_shadowing(b->p.normalmap.options, &f, q->wo));
}

INLINE float COMPOSITE_FN(normalmap_pdf)(__global const Bsdf* b, const BsdfQuery* q) {
    Frame f = normalmap_frame(b, q);
    BsdfQuery c;
    if (!perturb_query(&f, q, &c)) return 0.0f;
    return CHILD_FN(pdf)(b + b->p.normalmap.child, &c);
}

INLINE float3 COMPOSITE_FN(normalmap_sample)(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    Frame f = normalmap_frame(b, q);
    BsdfQuery c;
    perturb_query(&f, q, &c);
    float3 w = CHILD_FN(sample)(b + b->p.normalmap.child, &c, u);
    q->wo = to_world(&f, c.wo);
    q->eta = c.eta;
    q->measure = c.measure;
    if (!(c.wo.z * q->wo.z > 0.0f)) return (float3)(0.0f);
    return w * perturb_shadowing(b->p.normalmap.options, &f, q->wo);
}

INLINE float3 COMPOSITE_FN(normalmap_albedo)(__global const Bsdf* b, const BsdfQuery* q) {
    return CHILD_FN(albedo)(b + b->p.normalmap.child, q);
}

/* the perturbed normal (aov's sh_normal); a wrapper's own, not its child's (Mitsuba 3.9's sh_frame) */
INLINE float3 COMPOSITE_FN(normalmap_normal)(__global const Bsdf* b, const BsdfQuery* q) {
    return normalmap_frame(b, q).n;
}
