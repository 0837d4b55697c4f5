/* Counter-based random numbers: Philox4x32-10 keyed by (seed, pixel), counter (sample index, dimension
   block). Every sample of every pixel owns its own stream, so an image does not depend on how its samples
   are split into passes, processes or machines. Dimensions are drawn in order, four per Philox call. */
#ifndef CLRENDER_RNG_H
#define CLRENDER_RNG_H

#include <pyopencl-random123/philox.cl>
#include "math.h"

typedef struct {
    philox4x32_key_t key;
    philox4x32_ctr_t ctr;
    philox4x32_ctr_t out;
    uint used;
} Sampler;

INLINE void sampler_init(Sampler* s, uint seed, uint pixel, uint sample) {
    s->key.v[0] = seed;
    s->key.v[1] = pixel;
    s->ctr.v[0] = sample;
    s->ctr.v[1] = 0u;
    s->ctr.v[2] = 0x636c7265u; /* a constant lane keeps this stream apart from other users of Philox */
    s->ctr.v[3] = 0u;
    s->used = 4u;
}

/* Uniform in [0, 1): the top 24 bits, so 1.0f can never come out. */
INLINE float next1d(Sampler* s) {
    if (s->used >= 4u) {
        s->out = philox4x32(s->ctr, s->key);
        s->ctr.v[1] += 1u;
        s->used = 0u;
    }
    /* selects, not out.v[used]: a dynamic index keeps the whole Sampler in memory, and each Philox call then
       reloads the counter as 64-bit words just after 32-bit stores to it, a store-forwarding stall (perf: 9 % of
       the furnace twin's time; this is x1.10 there, x1.00 on the Cornell twin) */
    uint u = s->used;
    uint x = u == 0u ? s->out.v[0] : (u == 1u ? s->out.v[1] : (u == 2u ? s->out.v[2] : s->out.v[3]));
    s->used += 1u;
    return (float)(x >> 8) * (1.0f / 16777216.0f);
}

INLINE float2 next2d(Sampler* s) {
    float a = next1d(s);
    float b = next1d(s);
    return (float2)(a, b);
}

#endif
