/* Binary SAH BVH subtrees, one work-item per subtree (clrender/accel/bvh_device.py drives it).

   The host builds the top of the tree level by level and hands every node of at most a few thousand
   primitives (a "task") to this kernel. A work-item builds its task's whole subtree depth-first with an
   explicit stack: binned SAH on all three axes (BVH_BINS bins, every primitive binned, so the children's
   boxes are exact), an in-place partition of its own range of the primitive arrays, and for nodes of 2..4
   primitives the exact SAH optimum over every two-way partition (a dynamic programme over subsets), as the
   host builder does. Work-items touch disjoint ranges, so they need no synchronisation, and the primitive
   arrays stay in memory order so the binning passes read sequentially.

   Output: the subtree already in the final node layout of kernels/bvh.h (2-wide nodes of 4 float4, interior
   nodes only, depth-first: an interior left child directly follows its parent). Task s owns primitive rows
   [off, off + n) and node rows [4 off, 4 (off + n - 1)) (a subtree of n primitives has < n interior nodes).
   Leaf references are final (BVH_LEAF_BIT | (start + first)); interior references are local node numbers,
   to which the host adds the subtree's place in the whole table. stats[s] = (interior nodes, the deepest
   leaf's depth below the task's root); 0 interior nodes means the task's root is itself a leaf. The
   leaves' primitives end up in leaf order in plo/phi/pid[off .. off + n). */

#ifndef BVH_BINS
#define BVH_BINS 32
#endif
#define BUILD_STACK 64
#define DP_MAX 4

/* min / max without fmin's NaN rules (boxes hold no NaN): one instruction on every target. */
inline float3 vmin(float3 a, float3 b) { return a < b ? a : b; }
inline float3 vmax(float3 a, float3 b) { return a > b ? a : b; }

inline float half_area3(float3 lo, float3 hi) {
    float3 d = vmax(hi - lo, (float3)(0.0f));
    return d.x * d.y + d.y * d.z + d.z * d.x;
}

inline float comp(float3 v, int a) { return a == 0 ? v.x : (a == 1 ? v.y : v.z); }

/* The bin of a doubled centroid c: clamped as a float before the conversion, which is undefined for values
   an int cannot hold. The binning and the partition both use it, so they agree on every primitive. */
inline int bin_of(float c, float c0, float sc) {
    float t = (c - c0) * sc;
    t = t > 0.0f ? t : 0.0f;
    t = t < (float)(BVH_BINS - 1) ? t : (float)(BVH_BINS - 1);
    return (int)t;
}

inline void swap_prims(__global float4* plo, __global float4* phi, __global int* pid, int i, int j) {
    float4 a = plo[i]; plo[i] = plo[j]; plo[j] = a;
    float4 b = phi[i]; phi[i] = phi[j]; phi[j] = b;
    int c = pid[i]; pid[i] = pid[j]; pid[j] = c;
}

/* Child slot `slot` (0 = A, 2 = B) of node row `k`: its box and, for leaves, the final reference. The
   reference of an interior child is written when the child is numbered (set_ref). */
inline void set_slot(__global float4* out, int k, int slot, float3 lo, float3 hi) {
    out[4 * k + slot] = (float4)(lo, 0.0f);
    out[4 * k + slot + 1] = (float4)(hi, 0.0f);
}

inline void set_ref(__global float4* out, int patch, uint ref, uint count) {
    if (patch < 0) return;                      /* the task's root: the host's tree refers to it */
    out[patch].w = as_float(ref);
    out[patch + 1].w = as_float(count);
}

/* Exact SAH subtree for the n (2..DP_MAX) primitives at [b, b + n) of a node whose parent slot is `patch`:
   every subset's box and best cost (leaf, or the best two-way partition), then the chosen tree emitted
   depth-first. Returns the new interior node count; *maxd = the deepest leaf seen. */
int dp_subtree(__global float4* plo, __global float4* phi, __global int* pid, __global float4* out, int patch,
               int b, int n, int depth0, int kount, int* maxd, uint start, int max_leaf, float ct, float ci) {
    float3 mlo[1 << DP_MAX], mhi[1 << DP_MAX];
    float mcost[1 << DP_MAX];
    int mch[1 << DP_MAX];
    int full = (1 << n) - 1;
    for (int m = 1; m <= full; ++m) {
        int low = m & -m;
        if (m == low) {
            int i = 31 - clz(low);
            mlo[m] = plo[b + i].xyz;
            mhi[m] = phi[b + i].xyz;
        } else {
            mlo[m] = vmin(mlo[low], mlo[m ^ low]);
            mhi[m] = vmax(mhi[low], mhi[m ^ low]);
        }
        float area = half_area3(mlo[m], mhi[m]);
        int k = popcount(m);
        float best = k <= max_leaf ? ci * (float)k * area : INFINITY;
        int ch = 0;
        int rest = m ^ low;
        int t = (rest - 1) & rest;             /* proper subsets of rest, largest first */
        while (rest) {
            int sub = low | t;
            float c = ct * area + mcost[sub] + mcost[m ^ sub];
            if (c < best) { best = c; ch = sub; }
            if (t == 0) break;
            t = (t - 1) & rest;
        }
        mcost[m] = best;
        mch[m] = ch;
    }
    float4 tlo[DP_MAX], thi[DP_MAX];
    int tid[DP_MAX];
    for (int i = 0; i < n; ++i) { tlo[i] = plo[b + i]; thi[i] = phi[b + i]; tid[i] = pid[b + i]; }
    /* (mask, parent slot, first primitive, depth) of the open nodes: at most n on the stack. */
    int smask[DP_MAX], spatch[DP_MAX], sfirst[DP_MAX], sdepth[DP_MAX];
    smask[0] = full; spatch[0] = patch; sfirst[0] = b; sdepth[0] = depth0;
    int sp = 1;
    while (sp > 0) {
        --sp;
        int m = smask[sp], pt = spatch[sp], first = sfirst[sp], d = sdepth[sp];
        int ch = mch[m];
        if (ch == 0) {
            int r = first;
            for (int i = 0; i < n; ++i)
                if ((m >> i) & 1) { plo[r] = tlo[i]; phi[r] = thi[i]; pid[r] = tid[i]; ++r; }
            set_ref(out, pt, BVH_LEAF_BIT | (start + (uint)first), (uint)popcount(m));
            *maxd = max(*maxd, d);
            continue;
        }
        int rm = m ^ ch;
        int k = kount++;
        set_ref(out, pt, (uint)k, 0u);
        set_slot(out, k, 0, mlo[ch], mhi[ch]);
        set_slot(out, k, 2, mlo[rm], mhi[rm]);
        smask[sp] = rm; spatch[sp] = 4 * k + 2; sfirst[sp] = first + popcount(ch); sdepth[sp] = d + 1; ++sp;
        smask[sp] = ch; spatch[sp] = 4 * k;     sfirst[sp] = first;                sdepth[sp] = d + 1; ++sp;
    }
    return kount;
}

__kernel void bvh_build_subtrees(__global float4* plo, __global float4* phi, __global int* pid,
                                 __global const int* task_off, __global const int* task_n,
                                 __global const int* task_depth, __global const uint* task_start,
                                 __global float4* out_all, __global int2* stats, uint n_tasks, int max_leaf,
                                 float ct, float ci, int force_depth) {
    uint s = get_global_id(0);
    if (s >= n_tasks) return;
    int off = task_off[s], n = task_n[s], depth0 = task_depth[s];
    uint start = task_start[s];
    __global float4* out = out_all + 4 * off;
    plo += off; phi += off; pid += off;

    float3 blo = (float3)(INFINITY), bhi = (float3)(-INFINITY);
    float3 cmin = (float3)(INFINITY), cmax = (float3)(-INFINITY);
    for (int i = 0; i < n; ++i) {
        float3 lo = plo[i].xyz, hi = phi[i].xyz, c = lo + hi;   /* doubled centroids, as on the host */
        blo = vmin(blo, lo); bhi = vmax(bhi, hi);
        cmin = vmin(cmin, c); cmax = vmax(cmax, c);
    }

    /* Open nodes: parent slot row (-1: the root), range, depth, box, centroid bounds. */
    int st_patch[BUILD_STACK], st_b[BUILD_STACK], st_n[BUILD_STACK], st_d[BUILD_STACK];
    float3 st_lo[BUILD_STACK], st_hi[BUILD_STACK], st_cmin[BUILD_STACK], st_cmax[BUILD_STACK];
    st_patch[0] = -1; st_b[0] = 0; st_n[0] = n; st_d[0] = 0;
    st_lo[0] = blo; st_hi[0] = bhi; st_cmin[0] = cmin; st_cmax[0] = cmax;
    int sp = 1, kount = 0, maxd = 0;

    int bcnt[3][BVH_BINS];
    float3 bbl[3][BVH_BINS], bbh[3][BVH_BINS];
    float racc[BVH_BINS];
    int rcnt[BVH_BINS];

    while (sp > 0) {
        --sp;
        int patch = st_patch[sp], b = st_b[sp], cnt = st_n[sp], d = st_d[sp];
        cmin = st_cmin[sp]; cmax = st_cmax[sp];
        if (cnt >= 2 && cnt <= DP_MAX) {
            kount = dp_subtree(plo, phi, pid, out, patch, b, cnt, d, kount, &maxd, start, max_leaf, ct, ci);
            continue;
        }
        if (cnt <= 1) {
            set_ref(out, patch, BVH_LEAF_BIT | (start + (uint)b), (uint)cnt);
            maxd = max(maxd, d);
            continue;
        }
        float area = half_area3(st_lo[sp], st_hi[sp]);
        float3 ext = cmax - cmin;
        bool forced = depth0 + d + 1 >= force_depth;
        float best = INFINITY;
        int best_axis = 0, best_plane = -1;
        float3 scale = (float3)(0.0f);
        if (!forced && (ext.x > 0.0f || ext.y > 0.0f || ext.z > 0.0f)) {
            /* (1 - 2^-20) keeps the largest centroid in the last bin despite rounding. */
            float k = (float)BVH_BINS * (1.0f - 9.5367431640625e-7f);
            scale = (float3)(ext.x > 1e-30f ? k / ext.x : 0.0f, ext.y > 1e-30f ? k / ext.y : 0.0f,
                             ext.z > 1e-30f ? k / ext.z : 0.0f);
            for (int a = 0; a < 3; ++a)
                for (int j = 0; j < BVH_BINS; ++j) {
                    bcnt[a][j] = 0;
                    bbl[a][j] = (float3)(INFINITY);
                    bbh[a][j] = (float3)(-INFINITY);
                }
            for (int i = b; i < b + cnt; ++i) {
                float3 lo = plo[i].xyz, hi = phi[i].xyz, c = lo + hi;
                int bx = bin_of(c.x, cmin.x, scale.x), by = bin_of(c.y, cmin.y, scale.y);
                int bz = bin_of(c.z, cmin.z, scale.z);
                bcnt[0][bx]++; bbl[0][bx] = vmin(bbl[0][bx], lo); bbh[0][bx] = vmax(bbh[0][bx], hi);
                bcnt[1][by]++; bbl[1][by] = vmin(bbl[1][by], lo); bbh[1][by] = vmax(bbh[1][by], hi);
                bcnt[2][bz]++; bbl[2][bz] = vmin(bbl[2][bz], lo); bbh[2][bz] = vmax(bbh[2][bz], hi);
            }
            for (int a = 0; a < 3; ++a) {
                if (comp(scale, a) == 0.0f) continue;
                float3 rl = (float3)(INFINITY), rh = (float3)(-INFINITY);
                int rc = 0;
                for (int j = BVH_BINS - 1; j > 0; --j) {
                    rl = vmin(rl, bbl[a][j]); rh = vmax(rh, bbh[a][j]); rc += bcnt[a][j];
                    racc[j] = half_area3(rl, rh); rcnt[j] = rc;
                }
                float3 ll = (float3)(INFINITY), lh = (float3)(-INFINITY);
                int lc = 0;
                for (int j = 0; j < BVH_BINS - 1; ++j) {
                    ll = vmin(ll, bbl[a][j]); lh = vmax(lh, bbh[a][j]); lc += bcnt[a][j];
                    if (lc == 0 || rcnt[j + 1] == 0) continue;
                    float c = half_area3(ll, lh) * (float)lc + racc[j + 1] * (float)rcnt[j + 1];
                    if (c < best) { best = c; best_axis = a; best_plane = j; }
                }
            }
        }
        /* SAH in units of the node's area: a leaf when small enough and no more expensive than a split. */
        float ratio = area > 0.0f ? best / area : (isfinite(best) ? (float)cnt : INFINITY);
        if (cnt <= max_leaf && ci * (float)cnt <= ct + ci * ratio) {
            set_ref(out, patch, BVH_LEAF_BIT | (start + (uint)b), (uint)cnt);
            maxd = max(maxd, d);
            continue;
        }
        /* Children: centroid bounds gathered while partitioning; boxes from the bins (exact), or from the
           primitives after a split in the middle. */
        float3 lb0, lb1, rb0, rb1;
        float3 lc0 = (float3)(INFINITY), lc1 = (float3)(-INFINITY), rc0 = lc0, rc1 = lc1;
        int mid = -1;
        if (best_plane >= 0) {
            /* Same expression as the binning, so the same primitives go left as were counted left. */
            float c0 = comp(cmin, best_axis), sc = comp(scale, best_axis);
            int i = b, j = b + cnt - 1;
            while (i <= j) {
                float3 c = plo[i].xyz + phi[i].xyz;
                if (bin_of(comp(c, best_axis), c0, sc) <= best_plane) {
                    lc0 = vmin(lc0, c); lc1 = vmax(lc1, c);
                    ++i;
                } else {
                    rc0 = vmin(rc0, c); rc1 = vmax(rc1, c);
                    swap_prims(plo, phi, pid, i, j);
                    --j;
                }
            }
            if (i > b && i < b + cnt) {
                mid = i;
                lb0 = bbl[best_axis][0]; lb1 = bbh[best_axis][0];
                for (int k = 1; k <= best_plane; ++k) {
                    lb0 = vmin(lb0, bbl[best_axis][k]); lb1 = vmax(lb1, bbh[best_axis][k]);
                }
                rb0 = bbl[best_axis][BVH_BINS - 1]; rb1 = bbh[best_axis][BVH_BINS - 1];
                for (int k = BVH_BINS - 2; k > best_plane; --k) {
                    rb0 = vmin(rb0, bbl[best_axis][k]); rb1 = vmax(rb1, bbh[best_axis][k]);
                }
            }
        }
        if (mid < 0) {                      /* no usable plane (or, never expected, a one-sided partition) */
            mid = b + cnt / 2;
            lb0 = lc0 = rb0 = rc0 = (float3)(INFINITY);
            lb1 = lc1 = rb1 = rc1 = (float3)(-INFINITY);
            for (int i = b; i < mid; ++i) {
                float3 lo = plo[i].xyz, hi = phi[i].xyz, c = lo + hi;
                lb0 = vmin(lb0, lo); lb1 = vmax(lb1, hi); lc0 = vmin(lc0, c); lc1 = vmax(lc1, c);
            }
            for (int i = mid; i < b + cnt; ++i) {
                float3 lo = plo[i].xyz, hi = phi[i].xyz, c = lo + hi;
                rb0 = vmin(rb0, lo); rb1 = vmax(rb1, hi); rc0 = vmin(rc0, c); rc1 = vmax(rc1, c);
            }
        }
        int k = kount++;
        set_ref(out, patch, (uint)k, 0u);
        set_slot(out, k, 0, lb0, lb1);
        set_slot(out, k, 2, rb0, rb1);
        if (sp + 2 > BUILD_STACK) { stats[s] = (int2)(-1, 0); return; }   /* not below depth 64 */
        st_patch[sp] = 4 * k + 2; st_b[sp] = mid; st_n[sp] = b + cnt - mid; st_d[sp] = d + 1;
        st_lo[sp] = rb0; st_hi[sp] = rb1; st_cmin[sp] = rc0; st_cmax[sp] = rc1; ++sp;
        st_patch[sp] = 4 * k; st_b[sp] = b; st_n[sp] = mid - b; st_d[sp] = d + 1;
        st_lo[sp] = lb0; st_hi[sp] = lb1; st_cmin[sp] = lc0; st_cmax[sp] = lc1; ++sp;
    }
    stats[s] = (int2)(kount, maxd);
}
