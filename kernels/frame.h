/* Orthonormal shading frames (z = normal). The basis follows Duff et al. 2017 (branchless, continuous
   except at n.z = -1 where it flips). */
#ifndef CLRENDER_FRAME_H
#define CLRENDER_FRAME_H
#include "math.h"

typedef struct { vec3 s, t, n; } Frame;

INLINE Frame frame_from_normal(vec3 n) {
    Frame f;
    float sign = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    f.s = v3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    f.t = v3(b, sign + n.y * n.y * a, -n.y);
    f.n = n;
    return f;
}
/* Mitsuba's shading frame: n, with its first axis along the tangent dpdu made orthogonal to n (Gram-Schmidt; the
   axis an anisotropic roughness's alpha_u runs along); the frame above where dpdu is (nearly) along n or zero. */
INLINE Frame frame_from_tangent(vec3 n, vec3 dpdu) {
    vec3 s = vsub(dpdu, vscale(n, dot3(n, dpdu)));
    float l2 = dot3(s, s);
    if (!(l2 > 1e-12f * dot3(dpdu, dpdu)) || !isfinite(l2)) return frame_from_normal(n);
    Frame f;
    f.s = vscale(s, 1.0f / sqrt(l2));
    f.t = cross3(n, f.s);
    f.n = n;
    return f;
}
INLINE vec3 to_local(const Frame* f, vec3 v) { return v3(dot3(v, f->s), dot3(v, f->t), dot3(v, f->n)); }
INLINE vec3 to_world(const Frame* f, vec3 v) { return vmad(f->s, v.x, vmad(f->t, v.y, vscale(f->n, v.z))); }

#endif
