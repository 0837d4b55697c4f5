/* Lanczos windowed sinc filter: sinc(x) sinc(x / lobes) on (-lobes, lobes). Row: p.lanczos.lobes. */
#ifndef CLRENDER_FILTERS_LANCZOS_H
#define CLRENDER_FILTERS_LANCZOS_H
INLINE float lanczos_sinc(float x) {
    float a = M_PI_F_ * x;
    return fabs(x) < 1e-4f ? 1.0f - a * a * (1.0f / 6.0f) : sin(a) / a;
}
INLINE float lanczos_eval(__global const Camera* cam, float x) {
    float tau = cam->p.lanczos.lobes;
    x = fabs(x);
    return x < tau ? lanczos_sinc(x) * lanczos_sinc(x / tau) : 0.0f;
}
#endif
