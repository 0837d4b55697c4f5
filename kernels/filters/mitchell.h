/* Mitchell-Netravali filter on [-r, r] (the cubic's [-2, 2] scaled to the radius); negative lobes are handled by
   signed sample weights. Row: p.mitchell.B, p.mitchell.C. */
#ifndef CLRENDER_FILTERS_MITCHELL_H
#define CLRENDER_FILTERS_MITCHELL_H
INLINE float mitchell_eval(__global const Camera* cam, float x) {
    float B = cam->p.mitchell.B, C = cam->p.mitchell.C;
    float t = 2.0f * fabs(x) / cam->filter_radius;
    float t2 = t * t, t3 = t2 * t;
    if (t < 1.0f)
        return ((12.0f - 9.0f * B - 6.0f * C) * t3 + (-18.0f + 12.0f * B + 6.0f * C) * t2 + (6.0f - 2.0f * B)) * (1.0f / 6.0f);
    if (t < 2.0f)
        return ((-B - 6.0f * C) * t3 + (6.0f * B + 30.0f * C) * t2 + (-12.0f * B - 48.0f * C) * t + (8.0f * B + 24.0f * C)) * (1.0f / 6.0f);
    return 0.0f;
}
#endif
