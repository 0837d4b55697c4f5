/* mask: the child with probability a = opacity, else a straight pass-through (wo = -wi, weight 1, discrete).
   eval/pdf: a times the child's. Row: p.mask = opacity(_tex), child (offset of the child's row).
   Included once per nesting level (see twosided.h). */
#ifndef CLRENDER_BSDFS_MASK_H
#define CLRENDER_BSDFS_MASK_H
INLINE float mask_opacity(__global const Bsdf* b, const BsdfQuery* q) {
    return clamp(PARAM_FLOAT(q, b->p.mask, opacity), 0.0f, 1.0f);
}
#endif

INLINE vec3 COMPOSITE_FN(mask_eval)(__global const Bsdf* b, const BsdfQuery* q) {
    float a = mask_opacity(b, q);
    return a > 0.0f ? vscale(CHILD_FN(eval)(b + b->p.mask.child, q), a) : v3s(0.0f);
}

INLINE float COMPOSITE_FN(mask_pdf)(__global const Bsdf* b, const BsdfQuery* q) {
    float a = mask_opacity(b, q);
    return a > 0.0f ? a * CHILD_FN(pdf)(b + b->p.mask.child, q) : 0.0f;
}

INLINE vec3 COMPOSITE_FN(mask_sample)(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    float a = mask_opacity(b, q);
    if (u.x >= a) {
        q->wo = vneg(q->wi);
        q->eta = 1.0f;
        q->measure = MEASURE_DISCRETE;
        return v3s(1.0f);
    }
    /* the child's own weight: a f cos / (a pdf) for its smooth part, its delta weight otherwise */
    return CHILD_FN(sample)(b + b->p.mask.child, q, (float2)(u.x / a, u.y));
}

/* Mitsuba's eval_null_transmission: the pass-through's share, plus what the child lets through unscattered. */
INLINE vec3 COMPOSITE_FN(mask_null_transmission)(__global const Bsdf* b, const BsdfQuery* q) {
    float a = mask_opacity(b, q);
    vec3 child = a > 0.0f ? CHILD_FN(null_transmission)(b + b->p.mask.child, q) : v3s(0.0f);
    return vsub(v3s(1.0f), vscale(vsub(v3s(1.0f), child), a));
}

INLINE vec3 COMPOSITE_FN(mask_albedo)(__global const Bsdf* b, const BsdfQuery* q) {
    return CHILD_FN(albedo)(b + b->p.mask.child, q);
}
