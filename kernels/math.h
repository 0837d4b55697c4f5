/* Small vector helpers. PoCL 3.0 runs plain arithmetic faster than the dot/cross/fmin/fmax builtins in hot
   loops (measured 1.2-2.4x), so these are spelled out. */
#ifndef CLRENDER_MATH_H
#define CLRENDER_MATH_H

#define INLINE static inline __attribute__((always_inline))

#define M_PI_F_ 3.14159265358979323846f
#define INV_PI 0.31830988618379067154f
#define INV_TWOPI 0.15915494309189533577f
#define INV_FOURPI 0.07957747154594766788f

/* vec3: three floats in a plain struct, with the arithmetic spelled as inline functions. PoCL vectorises a
   kernel across work-items (16 per AVX-512 instruction) only when no OpenCL vector type (float3/float4) is left in
   the code it inlines: the same stage in this struct ran at 501 M items/s against 160 M in float3
   (benchmarks/pocl_vectorise.py). float4 stays for loads of packed rows only (vxyz takes their xyz). Colours are
   vec3 too.
   On x86-64 a struct of three floats is passed to and returned from functions as {<2 x float>, float} (the SysV
   ABI's SSE classes), and those vector pieces survive inlining (wf_shade's IR for the Cornell twin: 230
   vector-typed instructions); a struct larger than 16 bytes is passed in memory and leaves none (0). The padded
   form is the one a vectorising build needs; it is opt-in (-DCLR_VEC3_PASS_IN_MEMORY) until a stage vectorises,
   because it costs the scalar megakernel a few per cent (benchmarks/README.md). */
#ifdef CLR_VEC3_PASS_IN_MEMORY
typedef struct { float x, y, z; float abi_pad_[2]; } vec3;
#else
typedef struct { float x, y, z; } vec3;
#endif

INLINE vec3 v3(float x, float y, float z) { vec3 r; r.x = x; r.y = y; r.z = z; return r; }
INLINE vec3 v3s(float s) { return v3(s, s, s); }
INLINE vec3 vxyz(float4 v) { return v3(v.x, v.y, v.z); }
/* xyz of a float4 row in __global memory, as three float loads: reading the float4 itself is a vector-typed load,
   and one vector-typed instruction keeps PoCL's work-item loop scalar */
INLINE vec3 vrow_at(__global const float* p) { return v3(p[0], p[1], p[2]); }
#define vrow(lvalue) vrow_at((__global const float*)&(lvalue))
INLINE float4 vf4(vec3 v, float w) { return (float4)(v.x, v.y, v.z, w); }
INLINE vec3 vadd(vec3 a, vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
INLINE vec3 vsub(vec3 a, vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
INLINE vec3 vmul(vec3 a, vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
INLINE vec3 vdiv(vec3 a, vec3 b) { return v3(a.x / b.x, a.y / b.y, a.z / b.z); }
INLINE vec3 vscale(vec3 a, float s) { return v3(a.x * s, a.y * s, a.z * s); }
INLINE vec3 vdivs(vec3 a, float s) { return v3(a.x / s, a.y / s, a.z / s); }
INLINE vec3 vadds(vec3 a, float s) { return v3(a.x + s, a.y + s, a.z + s); }
INLINE vec3 vneg(vec3 a) { return v3(-a.x, -a.y, -a.z); }
/* a * s + b: the most common update (throughput-weighted sums, points along rays) */
INLINE vec3 vmad(vec3 a, float s, vec3 b) { return v3(a.x * s + b.x, a.y * s + b.y, a.z * s + b.z); }
INLINE vec3 vlerp(vec3 a, vec3 b, float t) { return v3(a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t, a.z + (b.z - a.z) * t); }
INLINE vec3 vmin(vec3 a, vec3 b) { return v3(a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z); }
INLINE vec3 vmax(vec3 a, vec3 b) { return v3(a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z); }
INLINE vec3 vabs(vec3 a) { return v3(fabs(a.x), fabs(a.y), fabs(a.z)); }
INLINE vec3 vsqrt(vec3 a) { return v3(sqrt(a.x), sqrt(a.y), sqrt(a.z)); }
INLINE vec3 vexp(vec3 a) { return v3(exp(a.x), exp(a.y), exp(a.z)); }
INLINE vec3 vclamp(vec3 a, float lo, float hi) {
    return v3(a.x < lo ? lo : (a.x > hi ? hi : a.x), a.y < lo ? lo : (a.y > hi ? hi : a.y),
              a.z < lo ? lo : (a.z > hi ? hi : a.z));
}
INLINE float vcomp(vec3 a, uint i) { return i == 0u ? a.x : (i == 1u ? a.y : a.z); }

/* Searches of sorted tables with a fixed trip count. A `while` bisection runs a per-item number of steps, and
   one such loop anywhere in a stage kernel keeps PoCL's work-item loop scalar; CLR_SEARCH_STEPS halvings (the host
   sets it from the scene's largest searched table, so that 2^steps exceeds every count: clrender/pack.py
   SceneBuffers.search_steps) unroll into straight code with masked loads. Only the wavefront's stage kernels use
   them (CLR_WAVEFRONT_STAGES, defined by wavefront.cl): in the scalar megakernel the bisection is the faster
   (the fixed steps cost it 7 % on the Cornell twin, benchmarks/README.md); programs built without a scene keep the
   bisection too. */
#if defined(CLR_SEARCH_STEPS) && defined(CLR_WAVEFRONT_STAGES)
/* How many of the non-decreasing values t[0..count) are <= u. */
INLINE uint table_count_le(__global const float* t, uint count, float u) {
    uint n = 0u;
#pragma unroll
    for (int s = CLR_SEARCH_STEPS - 1; s >= 0; --s) {
        uint next = n + (1u << s);
        if (next <= count && t[next - 1u] <= u) n = next;
    }
    return n;
}
#endif

INLINE float dot3(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
INLINE vec3 cross3(vec3 a, vec3 b) { return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x); }
INLINE float len3(vec3 a) { return sqrt(dot3(a, a)); }
INLINE vec3 normalize3(vec3 a) { return vscale(a, 1.0f / sqrt(dot3(a, a))); }
INLINE float minf(float a, float b) { return a < b ? a : b; }
INLINE float maxf(float a, float b) { return a > b ? a : b; }
INLINE float clampf(float x, float lo, float hi) { return x < lo ? lo : (x > hi ? hi : x); }
INLINE float max3(vec3 a) { return maxf(a.x, maxf(a.y, a.z)); }
INLINE float luminance(vec3 c) { return 0.212671f * c.x + 0.715160f * c.y + 0.072169f * c.z; }
INLINE float safe_sqrt(float x) { return sqrt(maxf(x, 0.0f)); }
INLINE bool is_black(vec3 c) { return c.x == 0.0f && c.y == 0.0f && c.z == 0.0f; }
INLINE bool all_finite(vec3 c) { return isfinite(c.x) && isfinite(c.y) && isfinite(c.z); }

/* A texel or voxel index wrapped into [0, n) by mode 0 repeat / 1 mirror / 2 clamp (Mitsuba's wrap modes, as the
   bitmap texture and the grid volume number them). */
INLINE int wrap_index(int i, int n, uint mode) {
    if (mode == 2u) return clamp(i, 0, n - 1);
    if (mode == 1u) {
        int k = i % (2 * n);
        if (k < 0) k += 2 * n;
        return k >= n ? 2 * n - 1 - k : k;
    }
    int k = i % n;
    return k < 0 ? k + n : k;
}

/* A float texel or voxel coordinate to int, kept in a range where the wrap arithmetic cannot overflow. */
INLINE int floor_index(float x) { return (int)floor(clampf(x, -1.0e8f, 1.0e8f)); }

/* (sin x, cos x) for the moderate angles of sampling code (|x| up to a few thousand), in plain arithmetic:
   PoCL's sin/cos spend most of their time in a general argument reduction (measured: 5 % of a Cornell box
   render). Quadrant q = round(x / (pi/2)); r = x - q pi/2 with pi/2 in three parts (the first two short, so
   q times them is exact); Taylor series on |r| <= pi/4 (truncation < 2e-9). Error ~2 ulp of the result. */
INLINE float2 sin_cos(float x) {
    float qf = rint(x * 0.63661977236758134f);
    float r = ((x - qf * 1.5703125f) - qf * 4.837512969970703125e-4f) - qf * 7.549790126404332e-8f;
    float r2 = r * r;
    float sr = r + r * r2 * (-1.6666666666666667e-1f + r2 * (8.3333333333333333e-3f + r2 * (-1.9841269841269841e-4f
                   + r2 * 2.7557319223985891e-6f)));
    float cr = 1.0f + r2 * (-0.5f + r2 * (4.1666666666666667e-2f + r2 * (-1.3888888888888889e-3f
                   + r2 * (2.4801587301587302e-5f - r2 * 2.7557319223985891e-7f))));
    int q = (int)qf & 3;
    float sv = (q & 1) ? cr : sr, cv = (q & 1) ? sr : cr;
    return (float2)((q & 2) ? -sv : sv, ((q + 1) & 2) ? -cv : cv);
}

/* Ray offsets: Nori uses a fixed 1e-4; we scale it with the magnitude of the point so that large scenes
   do not self-intersect, and keep exactly 1e-4 for scenes of unit size. */
INLINE float ray_eps(vec3 p) {
    float m = maxf(fabs(p.x), maxf(fabs(p.y), fabs(p.z)));
    return 1e-4f * maxf(1.0f, m * 0.01f);
}

#endif
