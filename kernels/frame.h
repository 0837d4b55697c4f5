/* Orthonormal shading frames (z = normal). The basis follows Duff et al. 2017 (branchless, continuous
   except at n.z = -1 where it flips). */
#ifndef CLRENDER_FRAME_H
#define CLRENDER_FRAME_H
#include "math.h"

typedef struct { float3 s, t, n; } Frame;

INLINE Frame frame_from_normal(float3 n) {
    Frame f;
    float sign = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    f.s = (float3)(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    f.t = (float3)(b, sign + n.y * n.y * a, -n.y);
    f.n = n;
    return f;
}
/* Mitsuba's shading frame: n, with its first axis along the tangent dpdu made orthogonal to n (Gram-Schmidt; the
   axis an anisotropic roughness's alpha_u runs along); the frame above where dpdu is (nearly) along n or zero. */
INLINE Frame frame_from_tangent(float3 n, float3 dpdu) {
    float3 s = dpdu - n * dot3(n, dpdu);
    float l2 = dot3(s, s);
    if (!(l2 > 1e-12f * dot3(dpdu, dpdu)) || !isfinite(l2)) return frame_from_normal(n);
    Frame f;
    f.s = s * (1.0f / sqrt(l2));
    f.t = cross3(n, f.s);
    f.n = n;
    return f;
}
INLINE float3 to_local(const Frame* f, float3 v) { return (float3)(dot3(v, f->s), dot3(v, f->t), dot3(v, f->n)); }
INLINE float3 to_world(const Frame* f, float3 v) { return f->s * v.x + f->t * v.y + f->n * v.z; }

#endif
