/* twosided: the front child where cos theta_i >= 0, the back child in the mirrored frame (z of wi and wo flipped)
   where it is < 0. Row: p.twosided.front, back (offsets of the children's rows from this one).
   A composite's header is included once per nesting level by gen/bsdf_dispatch.h: COMPOSITE_FN names this level's
   functions and CHILD_FN the dispatcher one level down (see clrender/device/codegen.py). */
#ifndef CLRENDER_BSDFS_TWOSIDED_H
#define CLRENDER_BSDFS_TWOSIDED_H
INLINE vec3 flip_z(vec3 v) { return v3(v.x, v.y, -v.z); }
#endif

INLINE vec3 COMPOSITE_FN(twosided_eval)(__global const Bsdf* b, const BsdfQuery* q) {
    if (q->wi.z >= 0.0f) return CHILD_FN(eval)(b + b->p.twosided.front, q);
    BsdfQuery c = *q;
    c.wi = flip_z(c.wi);
    c.wo = flip_z(c.wo);
    return CHILD_FN(eval)(b + b->p.twosided.back, &c);
}

INLINE float COMPOSITE_FN(twosided_pdf)(__global const Bsdf* b, const BsdfQuery* q) {
    if (q->wi.z >= 0.0f) return CHILD_FN(pdf)(b + b->p.twosided.front, q);
    BsdfQuery c = *q;
    c.wi = flip_z(c.wi);
    c.wo = flip_z(c.wo);
    return CHILD_FN(pdf)(b + b->p.twosided.back, &c);
}

INLINE vec3 COMPOSITE_FN(twosided_sample)(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    if (q->wi.z >= 0.0f) return CHILD_FN(sample)(b + b->p.twosided.front, q, u);
    vec3 wi = q->wi;
    q->wi = flip_z(wi);
    vec3 w = CHILD_FN(sample)(b + b->p.twosided.back, q, u);
    q->wi = wi;
    q->wo = flip_z(q->wo);
    return w;
}

INLINE vec3 COMPOSITE_FN(twosided_albedo)(__global const Bsdf* b, const BsdfQuery* q) {
    return CHILD_FN(albedo)(b + (q->wi.z >= 0.0f ? b->p.twosided.front : b->p.twosided.back), q);
}
