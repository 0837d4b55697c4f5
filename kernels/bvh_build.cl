/* Binary SAH BVH subtrees, one work-item per subtree (clrender/accel/bvh_device.py drives it).

   The host builds the top of the tree level by level and hands every node of at most a few thousand
   primitives to this kernel. A work-item builds its node's whole subtree depth-first with an explicit stack:
   binned SAH on all three axes (BVH_BINS bins, every primitive binned, so the children's boxes are exact),
   an in-place partition of its own range of the primitive arrays, and for nodes of 2..4 primitives the
   exact SAH optimum over every two-way partition (a dynamic programme over subsets), as the host builder
   does. Work-items touch disjoint ranges, so no synchronisation is needed; the arrays stay in memory order
   so the binning passes read sequentially.

   Per subtree s (active range [off, off + n) of the primitive arrays, node slots [2*off, 2*off + 2n - 1)):
   node slot 2*off + j is local node j (j = 0 is the subtree's root, already known to the host):
     nlo[j] = (box lo, 0), nhi[j] = (box hi, 0),
     nmeta[j] = (left child's local index or -1, first primitive (relative to off) for a leaf, primitive
                 count for a leaf (0 for an interior node), depth below the subtree's root);
   the right child of an interior node is its left child + 1. The leaves' primitives end up in leaf order
   in the arrays: plo/phi/pid[off .. off + n). task_nodes[s] = the subtree's node count. */

#ifndef BVH_BINS
#define BVH_BINS 32
#endif
#define BUILD_STACK 64
#define DP_MAX 4

inline float half_area3(float3 lo, float3 hi) {
    float3 d = fmax(hi - lo, (float3)(0.0f));
    return d.x * d.y + d.y * d.z + d.z * d.x;
}

inline float comp(float3 v, int a) { return a == 0 ? v.x : (a == 1 ? v.y : v.z); }

inline void swap_prims(__global float4* plo, __global float4* phi, __global int* pid, int i, int j) {
    float4 a = plo[i]; plo[i] = plo[j]; plo[j] = a;
    float4 b = phi[i]; phi[i] = phi[j]; phi[j] = b;
    int c = pid[i]; pid[i] = pid[j]; pid[j] = c;
}

/* Exact SAH subtree for the n (2..DP_MAX) primitives at [b, b + n): every subset's box and best cost
   (leaf, or the best two-way partition), then the chosen tree emitted top-down. Returns the new `next`. */
int dp_subtree(__global float4* plo, __global float4* phi, __global int* pid, __global float4* nlo,
               __global float4* nhi, __global int4* nmeta, int node0, int b, int n, int depth0, int next,
               int max_leaf, float ct, float ci) {
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
            mlo[m] = fmin(mlo[low], mlo[m ^ low]);
            mhi[m] = fmax(mhi[low], mhi[m ^ low]);
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
    /* (mask, node, first, depth) of the open nodes; a subtree of 4 primitives has at most 4 open at once. */
    int smask[2 * DP_MAX], snode[2 * DP_MAX], sfirst[2 * DP_MAX], sdepth[2 * DP_MAX];
    int sp = 0;
    smask[0] = full; snode[0] = node0; sfirst[0] = b; sdepth[0] = depth0; sp = 1;
    while (sp > 0) {
        --sp;
        int m = smask[sp], node = snode[sp], first = sfirst[sp], d = sdepth[sp];
        int ch = mch[m];
        if (ch == 0) {
            int r = first;
            for (int i = 0; i < n; ++i)
                if ((m >> i) & 1) { plo[r] = tlo[i]; phi[r] = thi[i]; pid[r] = tid[i]; ++r; }
            nmeta[node] = (int4)(-1, first, popcount(m), d);
            continue;
        }
        int rm = m ^ ch;
        int l = next;
        next += 2;
        nmeta[node] = (int4)(l, 0, 0, d);
        nlo[l] = (float4)(mlo[ch], 0.0f);     nhi[l] = (float4)(mhi[ch], 0.0f);
        nlo[l + 1] = (float4)(mlo[rm], 0.0f); nhi[l + 1] = (float4)(mhi[rm], 0.0f);
        smask[sp] = rm; snode[sp] = l + 1; sfirst[sp] = first + popcount(ch); sdepth[sp] = d + 1; ++sp;
        smask[sp] = ch; snode[sp] = l;     sfirst[sp] = first;                sdepth[sp] = d + 1; ++sp;
    }
    return next;
}

__kernel void bvh_build_subtrees(__global float4* plo, __global float4* phi, __global int* pid,
                                 __global const int* task_off, __global const int* task_n,
                                 __global const int* task_depth, __global float4* nlo_all,
                                 __global float4* nhi_all, __global int4* nmeta_all, __global int* task_nodes,
                                 uint n_tasks, int max_leaf, float ct, float ci, int force_depth) {
    uint s = get_global_id(0);
    if (s >= n_tasks) return;
    int off = task_off[s], n = task_n[s], depth0 = task_depth[s];
    __global float4* nlo = nlo_all + 2 * off;
    __global float4* nhi = nhi_all + 2 * off;
    __global int4* nmeta = nmeta_all + 2 * off;
    plo += off; phi += off; pid += off;

    float3 blo = (float3)(INFINITY), bhi = (float3)(-INFINITY);
    float3 cmin = (float3)(INFINITY), cmax = (float3)(-INFINITY);
    for (int i = 0; i < n; ++i) {
        float3 lo = plo[i].xyz, hi = phi[i].xyz, c = lo + hi;   /* doubled centroids, as on the host */
        blo = fmin(blo, lo); bhi = fmax(bhi, hi);
        cmin = fmin(cmin, c); cmax = fmax(cmax, c);
    }
    nlo[0] = (float4)(blo, 0.0f);
    nhi[0] = (float4)(bhi, 0.0f);

    int st_node[BUILD_STACK], st_b[BUILD_STACK], st_n[BUILD_STACK], st_d[BUILD_STACK];
    float3 st_cmin[BUILD_STACK], st_cmax[BUILD_STACK];
    int sp = 0, next = 1;
    st_node[0] = 0; st_b[0] = 0; st_n[0] = n; st_d[0] = 0; st_cmin[0] = cmin; st_cmax[0] = cmax; sp = 1;

    int bcnt[3][BVH_BINS];
    float3 bbl[3][BVH_BINS], bbh[3][BVH_BINS];
    float racc[BVH_BINS];
    int rcnt[BVH_BINS];

    while (sp > 0) {
        --sp;
        int node = st_node[sp], b = st_b[sp], cnt = st_n[sp], d = st_d[sp];
        cmin = st_cmin[sp]; cmax = st_cmax[sp];
        if (cnt >= 2 && cnt <= DP_MAX) {
            next = dp_subtree(plo, phi, pid, nlo, nhi, nmeta, node, b, cnt, d, next, max_leaf, ct, ci);
            continue;
        }
        if (cnt <= 1) {
            nmeta[node] = (int4)(-1, b, cnt, d);
            continue;
        }
        float area = half_area3(nlo[node].xyz, nhi[node].xyz);
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
                float3 lo = plo[i].xyz, hi = phi[i].xyz;
                int3 bi = clamp(convert_int3_rtz((lo + hi - cmin) * scale), 0, BVH_BINS - 1);
                bcnt[0][bi.x]++; bbl[0][bi.x] = fmin(bbl[0][bi.x], lo); bbh[0][bi.x] = fmax(bbh[0][bi.x], hi);
                bcnt[1][bi.y]++; bbl[1][bi.y] = fmin(bbl[1][bi.y], lo); bbh[1][bi.y] = fmax(bbh[1][bi.y], hi);
                bcnt[2][bi.z]++; bbl[2][bi.z] = fmin(bbl[2][bi.z], lo); bbh[2][bi.z] = fmax(bbh[2][bi.z], hi);
            }
            for (int a = 0; a < 3; ++a) {
                if (comp(scale, a) == 0.0f) continue;
                float3 rl = (float3)(INFINITY), rh = (float3)(-INFINITY);
                int rc = 0;
                for (int j = BVH_BINS - 1; j > 0; --j) {
                    rl = fmin(rl, bbl[a][j]); rh = fmax(rh, bbh[a][j]); rc += bcnt[a][j];
                    racc[j] = half_area3(rl, rh); rcnt[j] = rc;
                }
                float3 ll = (float3)(INFINITY), lh = (float3)(-INFINITY);
                int lc = 0;
                for (int j = 0; j < BVH_BINS - 1; ++j) {
                    ll = fmin(ll, bbl[a][j]); lh = fmax(lh, bbh[a][j]); lc += bcnt[a][j];
                    if (lc == 0 || rcnt[j + 1] == 0) continue;
                    float c = half_area3(ll, lh) * (float)lc + racc[j + 1] * (float)rcnt[j + 1];
                    if (c < best) { best = c; best_axis = a; best_plane = j; }
                }
            }
        }
        /* SAH in units of the node's area: a leaf when small enough and no more expensive than a split. */
        float ratio = area > 0.0f ? best / area : (isfinite(best) ? (float)cnt : INFINITY);
        if (cnt <= max_leaf && ci * (float)cnt <= ct + ci * ratio) {
            nmeta[node] = (int4)(-1, b, cnt, d);
            continue;
        }
        int mid = b + cnt / 2;
        if (best_plane >= 0) {
            /* Same expression as the binning, so the same primitives go left as were counted left. */
            float c0 = comp(cmin, best_axis), sc = comp(scale, best_axis);
            int i = b, j = b + cnt - 1;
            while (i <= j) {
                float ci_ = comp(plo[i].xyz + phi[i].xyz, best_axis);
                int bi = clamp(convert_int_rtz((ci_ - c0) * sc), 0, BVH_BINS - 1);
                if (bi <= best_plane) { ++i; continue; }
                swap_prims(plo, phi, pid, i, j);
                --j;
            }
            if (i > b && i < b + cnt) mid = i;   /* else (never expected) fall back to the middle */
        }
        /* Children: exact boxes and centroid bounds from their primitives (one pass over the node). */
        float3 lb0 = (float3)(INFINITY), lb1 = (float3)(-INFINITY), lc0 = lb0, lc1 = lb1;
        float3 rb0 = lb0, rb1 = lb1, rc0 = lb0, rc1 = lb1;
        for (int i = b; i < mid; ++i) {
            float3 lo = plo[i].xyz, hi = phi[i].xyz, c = lo + hi;
            lb0 = fmin(lb0, lo); lb1 = fmax(lb1, hi); lc0 = fmin(lc0, c); lc1 = fmax(lc1, c);
        }
        for (int i = mid; i < b + cnt; ++i) {
            float3 lo = plo[i].xyz, hi = phi[i].xyz, c = lo + hi;
            rb0 = fmin(rb0, lo); rb1 = fmax(rb1, hi); rc0 = fmin(rc0, c); rc1 = fmax(rc1, c);
        }
        int l = next;
        next += 2;
        nmeta[node] = (int4)(l, 0, 0, d);
        nlo[l] = (float4)(lb0, 0.0f); nhi[l] = (float4)(lb1, 0.0f);
        nlo[l + 1] = (float4)(rb0, 0.0f); nhi[l + 1] = (float4)(rb1, 0.0f);
        if (sp + 2 > BUILD_STACK) { task_nodes[s] = -1; return; }   /* cannot happen below depth 64 */
        st_node[sp] = l + 1; st_b[sp] = mid; st_n[sp] = b + cnt - mid; st_d[sp] = d + 1;
        st_cmin[sp] = rc0; st_cmax[sp] = rc1; ++sp;
        st_node[sp] = l; st_b[sp] = b; st_n[sp] = mid - b; st_d[sp] = d + 1;
        st_cmin[sp] = lc0; st_cmax[sp] = lc1; ++sp;
    }
    task_nodes[s] = next;
}
