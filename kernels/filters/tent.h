/* Tent filter: f(x) = max(0, 1 - |x| / r). */
#ifndef CLRENDER_FILTERS_TENT_H
#define CLRENDER_FILTERS_TENT_H
INLINE float tent_eval(__global const Camera* cam, float x) { return maxf(0.0f, 1.0f - fabs(x) / cam->filter_radius); }
#endif
