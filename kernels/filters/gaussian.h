/* Gaussian filter (Nori's): f(x) = max(0, exp(-x^2 / 2 sigma^2) - exp(-r^2 / 2 sigma^2)).
   Row: p.gaussian.stddev, p.gaussian.floor = exp(-r^2 / 2 sigma^2) (so the weight reaches 0 at the radius). */
#ifndef CLRENDER_FILTERS_GAUSSIAN_H
#define CLRENDER_FILTERS_GAUSSIAN_H
INLINE float gaussian_eval(__global const Camera* cam, float x) {
    float s = cam->p.gaussian.stddev;
    return maxf(0.0f, exp(-x * x / (2.0f * s * s)) - cam->p.gaussian.floor);
}
#endif
