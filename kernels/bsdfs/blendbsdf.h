/* blendbsdf: f = (1-w) f_first + w f_second, w = weight (a constant or a texture's float view). Sampling picks
   a child with probability 1-w / w; a delta sample keeps that child's weight; a non-delta one is weighted by the
   mixture's eval and pdf (which hold the non-delta parts only), so weight == f cos / pdf for every sample with
   MEASURE_SOLID_ANGLE. Row: p.blendbsdf = weight(_tex), first, second (offsets of the children's rows).
   Included once per nesting level (see twosided.h). */
#ifndef CLRENDER_BSDFS_BLENDBSDF_H
#define CLRENDER_BSDFS_BLENDBSDF_H
INLINE float blendbsdf_weight(__global const Bsdf* b, const BsdfQuery* q) {
    return clamp(PARAM_FLOAT(q, b->p.blendbsdf, weight), 0.0f, 1.0f);
}
/* The body of a method whose value is the children's, blended: (1 - w) first's + w second's (a child of weight 0
   not called: a zero times its inf or NaN would poison the blend). */
#define BLENDBSDF_BLEND(method) \
    float w = blendbsdf_weight(b, q); \
    vec3 v = v3s(0.0f); \
    if (w < 1.0f) v = vmad(CHILD_FN(method)(b + b->p.blendbsdf.first, q), 1.0f - w, v); \
    if (w > 0.0f) v = vmad(CHILD_FN(method)(b + b->p.blendbsdf.second, q), w, v); \
    return v;
#endif

INLINE vec3 COMPOSITE_FN(blendbsdf_eval)(__global const Bsdf* b, const BsdfQuery* q) { BLENDBSDF_BLEND(eval) }

INLINE float COMPOSITE_FN(blendbsdf_pdf)(__global const Bsdf* b, const BsdfQuery* q) {
    float w = blendbsdf_weight(b, q);
    float p = 0.0f;
    if (w < 1.0f) p += (1.0f - w) * CHILD_FN(pdf)(b + b->p.blendbsdf.first, q);
    if (w > 0.0f) p += w * CHILD_FN(pdf)(b + b->p.blendbsdf.second, q);
    return p;
}

INLINE vec3 COMPOSITE_FN(blendbsdf_sample)(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    float w = blendbsdf_weight(b, q);
    bool second = u.x < w;
    u.x = second ? u.x / w : (u.x - w) / (1.0f - w);   /* uniform again on [0,1) */
    __global const Bsdf* child = b + (second ? b->p.blendbsdf.second : b->p.blendbsdf.first);
    vec3 r = CHILD_FN(sample)(child, q, u);
    if (q->measure == MEASURE_DISCRETE) return r;
    /* A black weight is a failed sample, or a direction from a child that reflects nothing there (a black diffuse):
       that direction is still a sample of the mixture, and the other child's share of it counts. */
    if (is_black(r) && !(CHILD_FN(pdf)(child, q) > 0.0f)) return r;
    return bsdf_sample_weight(COMPOSITE_FN(blendbsdf_eval)(b, q), q->wo.z, COMPOSITE_FN(blendbsdf_pdf)(b, q));
}

/* Mitsuba's eval_null_transmission of a blend: its children's, blended. */
INLINE vec3 COMPOSITE_FN(blendbsdf_null_transmission)(__global const Bsdf* b, const BsdfQuery* q) {
    BLENDBSDF_BLEND(null_transmission)
}

INLINE vec3 COMPOSITE_FN(blendbsdf_albedo)(__global const Bsdf* b, const BsdfQuery* q) {
    float w = blendbsdf_weight(b, q);
    vec3 first = CHILD_FN(albedo)(b + b->p.blendbsdf.first, q);
    vec3 second = CHILD_FN(albedo)(b + b->p.blendbsdf.second, q);
    return vadd(vscale(first, 1.0f - w), vscale(second, w));
}
