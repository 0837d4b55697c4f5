/* Counter-based random numbers: Philox4x32-10 keyed by (seed, pixel), counter (sample index, dimension
   block). Every sample of every pixel owns its own stream, so an image does not depend on how its samples
   are split into passes, processes or machines. Dimensions are drawn in order, four per Philox call.
   With CLR_SAMPLER_SOBOL (clrender/samplers/sobol.py): scrambled Sobol points instead, keyed the same way. */
#ifndef CLRENDER_RNG_H
#define CLRENDER_RNG_H

#include "math.h"

#if defined(CLR_SAMPLER_SOBOL)
/* Padded, shuffled, Owen-scrambled Sobol (Burley, "Practical Hash-based Owen Scrambling", JCGT 2020): each
   next1d/next2d call is a dimension d of its own, drawn from the first two Sobol dimensions (a (0,2)-sequence)
   at a shuffled index, both scrambled, with seeds hashed from (seed, pixel, d). The shuffle permutes indices
   within every aligned power-of-two block, so the first 2^k samples of a pixel form a stratified (0,k,2)-net in
   every pair of dimensions, while different d are decorrelated. Sample numbers key it, as Philox's are keyed. */
typedef struct {
    uint seed, pixel, sample, dim;
} Sampler;

INLINE uint rng_hash(uint x) {           /* an avalanching 32-bit integer hash (two multiply-xorshift rounds) */
    x ^= x >> 16; x *= 0x21f0aaadu;
    x ^= x >> 15; x *= 0x735a2d97u;
    x ^= x >> 15;
    return x;
}

INLINE uint rng_reverse_bits(uint x) {
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
    x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
    return (x >> 16) | (x << 16);
}

/* A Laine-Karras style hash permutation of bit-reversed values: each output bit depends only on the input bits
   below it, which (bits reversed around it) is a nested uniform (Owen) scramble. The constants are Vegdahl's
   ("Building a better LK hash", 2021); with the original ones, a dimension binned 64 ways over many pixels was
   overdispersed (chi-square up to 156 for 63 degrees of freedom: the later digits were poorly scrambled). */
INLINE uint rng_lk_permute(uint x, uint seed) {
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

INLINE uint rng_owen(uint x, uint seed) { return rng_reverse_bits(rng_lk_permute(rng_reverse_bits(x), seed)); }

/* The second Sobol dimension: direction numbers v_0 = 2^31, v_k = v_(k-1) ^ (v_(k-1) >> 1). */
INLINE uint rng_sobol1(uint i) {
    uint v = 0x80000000u, y = 0u;
    for (; i != 0u; i >>= 1, v ^= v >> 1)
        if (i & 1u) y ^= v;
    return y;
}

INLINE void sampler_init(Sampler* s, uint seed, uint pixel, uint sample) {
    s->seed = seed;
    s->pixel = pixel;
    s->sample = sample;
    s->dim = 0u;
}

INLINE float rng_unit(uint x) { return (float)(x >> 8) * (1.0f / 16777216.0f); }

/* The next dimension's seed; *i receives the sample's shuffled index there. */
INLINE uint rng_dimension(Sampler* s, uint* i) {
    uint h = rng_hash(rng_hash(rng_hash(s->seed ^ 0x5eed5eedu) ^ s->pixel) + s->dim * 0x9e3779b9u);
    s->dim += 1u;
    *i = rng_owen(s->sample, h);                                       /* the shuffle */
    return h;
}

INLINE float2 next2d(Sampler* s) {
    uint i, h = rng_dimension(s, &i);
    uint x = rng_owen(rng_reverse_bits(i), rng_hash(h ^ 0xa511e9b3u));  /* Sobol dimension 0: the radical inverse */
    uint y = rng_owen(rng_sobol1(i), rng_hash(h ^ 0x63d83595u));
    return (float2)(rng_unit(x), rng_unit(y));
}

/* next2d's x alone (the same number: a 1-D draw uses a dimension of its own, as next2d does) */
INLINE float next1d(Sampler* s) {
    uint i, h = rng_dimension(s, &i);
    return rng_unit(rng_owen(rng_reverse_bits(i), rng_hash(h ^ 0xa511e9b3u)));
}

#else
#include <pyopencl-random123/philox.cl>

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
#ifdef CLR_WAVEFRONT_STAGES
    /* and as masks in the stage kernels: LLVM turns the chain of ?: into a switch, which PoCL's vectoriser refuses */
    uint x = (s->out.v[0] & (0u - (uint)(u == 0u))) | (s->out.v[1] & (0u - (uint)(u == 1u)))
           | (s->out.v[2] & (0u - (uint)(u == 2u))) | (s->out.v[3] & (0u - (uint)(u >= 3u)));
#else
    uint x = u == 0u ? s->out.v[0] : (u == 1u ? s->out.v[1] : (u == 2u ? s->out.v[2] : s->out.v[3]));
#endif
    s->used += 1u;
    return (float)(x >> 8) * (1.0f / 16777216.0f);
}

INLINE float2 next2d(Sampler* s) {
    float a = next1d(s);
    float b = next1d(s);
    return (float2)(a, b);
}

#endif
#endif
