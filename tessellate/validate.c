/* validate.c: the half-edge view of an indexed mesh and the checks every
 * test uses: orientation, manifoldness, conformity (T-junctions), boundary
 * loops, degenerate and duplicate triangles, Euler characteristic.
 *
 * Edges are found by sorting (edge key, half-edge) pairs, so the cost is
 * O(T log T) with no hashing assumptions. Coincident vertices and
 * T-junctions are found through a k-d tree of the vertices: each vertex
 * and each open edge visits the nodes whose (slightly inflated) boxes it
 * meets. */
#include "tessellate/tessellate.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct kv {
    uint64_t key;
    uint32_t val;
} kv;

static int kv_cmp(const void *a, const void *b)
{
    const kv *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return x->val < y->val ? -1 : x->val > y->val;
}

/* Sorts e by (key, val) for input whose vals ascend (as every caller
 * builds it): a stable sort by key alone then gives the same order.
 * Least significant digit first, 16 bits a digit, all four histograms in
 * one pass, and a digit that every key shares skipped (edge keys of a
 * mesh below 2^16 vertices need two passes). qsort of 3.2 million
 * half-edges took most of a validation; this is several times faster.
 * Falls back to qsort when the buffer cannot be had. */
static void kv_sort(kv *e, size_t n, const tsr_allocator *al)
{
    kv *tmp = n >= 1024 && n <= UINT32_MAX ? tsr_alloc(al, n * sizeof *tmp) : NULL;
    uint32_t(*cnt)[65536] = tmp ? tsr_alloc(al, 4 * sizeof *cnt) : NULL;
    if (!cnt) {
        tsr_free(al, tmp);
        qsort(e, n, sizeof *e, kv_cmp);
        return;
    }
    memset(cnt, 0, 4 * sizeof *cnt);
    for (size_t i = 0; i < n; i++)
        for (int d = 0; d < 4; d++)
            cnt[d][(e[i].key >> (16 * d)) & 0xffff]++;
    kv *src = e, *dst = tmp;
    for (int d = 0; d < 4; d++) {
        if (cnt[d][(e[0].key >> (16 * d)) & 0xffff] == n)
            continue; /* every key has this digit */
        uint32_t sum = 0;
        for (uint32_t b = 0; b < 65536; b++) {
            uint32_t c = cnt[d][b];
            cnt[d][b] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++)
            dst[cnt[d][(src[i].key >> (16 * d)) & 0xffff]++] = src[i];
        kv *t = src;
        src = dst;
        dst = t;
    }
    if (src != e)
        memcpy(e, src, n * sizeof *e);
    tsr_free(al, cnt);
    tsr_free(al, tmp);
}

static uint64_t edge_key(uint32_t a, uint32_t b)
{
    return a < b ? ((uint64_t)a << 32 | b) : ((uint64_t)b << 32 | a);
}

tsr_status tsr_halfedges_build(tsr_halfedges *he, const tsr_mesh *m, const tsr_allocator *alloc)
{
    memset(he, 0, sizeof *he);
    if (alloc)
        he->alloc = *alloc;
    size_t n = 3 * (size_t)m->triangle_count;
    he->count = (uint32_t)n;
    he->twin = tsr_alloc(alloc, n * sizeof *he->twin);
    kv *e = tsr_alloc(alloc, n * sizeof *e);
    if (!he->twin || !e) {
        tsr_free(alloc, e);
        tsr_halfedges_free(he);
        return TSR_ERR_NOMEM;
    }
    size_t ne = 0;
    for (size_t h = 0; h < n; h++) {
        he->twin[h] = TSR_NO_TWIN;
        size_t t = h / 3, k = h % 3;
        uint32_t a = m->indices[h], b = m->indices[3 * t + (k + 1) % 3];
        if (a == b)
            continue;
        e[ne].key = edge_key(a, b);
        e[ne].val = (uint32_t)h;
        ne++;
    }
    kv_sort(e, ne, alloc);
    uint32_t edges = 0;
    for (size_t i = 0; i < ne;) {
        size_t j = i + 1;
        while (j < ne && e[j].key == e[i].key)
            j++;
        edges++;
        if (j - i == 2) {
            he->twin[e[i].val] = e[i + 1].val;
            he->twin[e[i + 1].val] = e[i].val;
        } else if (j - i > 2) {
            for (size_t k = i; k < j; k++)
                he->twin[e[k].val] = TSR_NONMANIFOLD;
        }
        i = j;
    }
    he->edge_count = edges;
    tsr_free(alloc, e);
    return TSR_OK;
}

void tsr_halfedges_free(tsr_halfedges *he)
{
    tsr_allocator a = he->alloc;
    tsr_free(a.realloc ? &a : NULL, he->twin);
    memset(he, 0, sizeof *he);
}

static uint32_t he_from(const tsr_mesh *m, uint32_t h) { return m->indices[h]; }
static uint32_t he_to(const tsr_mesh *m, uint32_t h) { return m->indices[3 * (h / 3) + (h % 3 + 1) % 3]; }

/* ---- a k-d tree of the vertices ---- */

/* The used vertices in a k-d tree (median splits along the box's longest
 * side, leaves of at most KD_LEAF vertices), so that a query costs about
 * its depth plus the vertices near it however they are spread: a uniform
 * grid sized by the mean edge length degrades where the density does not
 * match (a patch whose weights gather most of its samples in one spot put
 * 10^5 vertices into one cell, and each long open edge covering more
 * cells than there are vertices scanned them all). Boxes and tests use
 * the first dims coordinates (2 for a height field). */
#define KD_LEAF 16u

typedef struct kdnode {
    float lo[3], hi[3];
    uint32_t begin, end; /* its vertices: idx[begin .. end) */
    uint32_t kid[2];     /* children (0: a leaf) */
} kdnode;

typedef struct kdtree {
    const float *pos;
    int dims;
    uint32_t *idx;
    kdnode *node;
    uint32_t count;
    uint32_t stack[128], sp; /* the query under way (kd_query, kd_next) */
} kdtree;

static float kd_coord(const kdtree *t, uint32_t v, int k)
{
    return t->pos[3 * (size_t)v + k];
}

/* Reorders idx[b .. e) so that idx[m] is the vertex of rank m - b by
 * coordinate k, the ones before it no greater and the ones after no less. */
static void kd_select(kdtree *t, uint32_t b, uint32_t e, uint32_t m, int k)
{
    uint32_t *a = t->idx;
    while (e - b > 2) {
        uint32_t mid = b + (e - b) / 2;
        /* median of three as the pivot */
        float x = kd_coord(t, a[b], k), y = kd_coord(t, a[mid], k), z = kd_coord(t, a[e - 1], k);
        float piv = x < y ? (y < z ? y : x < z ? z : x) : (x < z ? x : y < z ? z : y);
        uint32_t i = b, j = e - 1;
        for (;;) {
            while (kd_coord(t, a[i], k) < piv)
                i++;
            while (kd_coord(t, a[j], k) > piv)
                j--;
            if (i >= j)
                break;
            uint32_t tmp = a[i];
            a[i] = a[j];
            a[j] = tmp;
            i++;
            j--;
        }
        /* [b, j] <= pivot <= [j + 1, e) */
        if (m <= j)
            e = j + 1;
        else
            b = j + 1;
    }
    if (e - b == 2 && kd_coord(t, a[b], k) > kd_coord(t, a[b + 1], k)) {
        uint32_t tmp = a[b];
        a[b] = a[b + 1];
        a[b + 1] = tmp;
    }
}

static uint32_t kd_build(kdtree *t, uint32_t b, uint32_t e, int depth)
{
    uint32_t id = t->count++;
    kdnode *n = &t->node[id];
    n->begin = b;
    n->end = e;
    n->kid[0] = n->kid[1] = 0;
    for (int k = 0; k < 3; k++)
        n->lo[k] = n->hi[k] = 0;
    for (int k = 0; k < t->dims; k++) {
        n->lo[k] = INFINITY;
        n->hi[k] = -INFINITY;
    }
    for (uint32_t i = b; i < e; i++)
        for (int k = 0; k < t->dims; k++) {
            float c = kd_coord(t, t->idx[i], k);
            n->lo[k] = c < n->lo[k] ? c : n->lo[k];
            n->hi[k] = c > n->hi[k] ? c : n->hi[k];
        }
    if (e - b <= KD_LEAF || depth >= 60)
        return id;
    int axis = 0;
    for (int k = 1; k < t->dims; k++)
        if ((double)n->hi[k] - n->lo[k] > (double)n->hi[axis] - n->lo[axis])
            axis = k;
    if (!(n->hi[axis] > n->lo[axis]))
        return id; /* all at one point: a leaf however many */
    uint32_t m = b + (e - b) / 2;
    kd_select(t, b, e, m, axis);
    uint32_t l = kd_build(t, b, m, depth + 1);
    uint32_t r = kd_build(t, m, e, depth + 1);
    t->node[id].kid[0] = l;
    t->node[id].kid[1] = r;
    return id;
}

/* Whether the box [lo - r, hi + r] meets segment ab (a point: a == b). */
static bool kd_meets(const kdtree *t, const kdnode *n, const float *a, const float *b, double r)
{
    double t0 = 0, t1 = 1;
    for (int k = 0; k < t->dims; k++) {
        double lo = n->lo[k] - r, hi = n->hi[k] + r, o = a[k], d = (double)b[k] - a[k];
        if (d == 0) {
            if (o < lo || o > hi)
                return false;
            continue;
        }
        double u = (lo - o) / d, w = (hi - o) / d;
        if (u > w) {
            double tmp = u;
            u = w;
            w = tmp;
        }
        t0 = u > t0 ? u : t0;
        t1 = w < t1 ? w : t1;
        if (t0 > t1)
            return false;
    }
    return true;
}

/* Starts a query: kd_next then gives, one by one, the leaves whose box,
 * widened by r, meets segment ab (a point: a == b). */
static void kd_query(kdtree *t)
{
    t->sp = 0;
    t->stack[t->sp++] = 0;
}

static const kdnode *kd_next(kdtree *t, const float *a, const float *b, double r)
{
    while (t->sp) {
        const kdnode *nd = &t->node[t->stack[--t->sp]];
        if (!kd_meets(t, nd, a, b, r))
            continue;
        if (!nd->kid[0])
            return nd;
        t->stack[t->sp++] = nd->kid[0];
        t->stack[t->sp++] = nd->kid[1];
    }
    return NULL;
}

/* tsr_point_on_open_segment in the first dims coordinates */
static bool on_open_segment(const float p[3], const float a[3], const float b[3], double eps, int dims)
{
    double ab[3] = {0, 0, 0}, ap[3] = {0, 0, 0}, l2 = 0, t = 0;
    for (int k = 0; k < dims; k++) {
        ab[k] = (double)b[k] - a[k];
        ap[k] = (double)p[k] - a[k];
        l2 += ab[k] * ab[k];
        t += ab[k] * ap[k];
    }
    if (l2 <= 0)
        return false;
    t /= l2;
    double len = sqrt(l2);
    /* strictly inside: farther than eps from both ends along the edge */
    if (t * len <= eps || (1 - t) * len <= eps)
        return false;
    double d2 = 0;
    for (int k = 0; k < dims; k++) {
        double q = ap[k] - t * ab[k];
        d2 += q * q;
    }
    return d2 <= eps * eps;
}

bool tsr_point_on_open_segment(const float p[3], const float a[3], const float b[3], double eps)
{
    return on_open_segment(p, a, b, eps, 3);
}

tsr_status tsr_mesh_validate(const tsr_mesh *m, const tsr_validate_options *opts, tsr_validation *v)
{
    memset(v, 0, sizeof *v);
    v->first_bad_triangle = v->first_degenerate = v->first_downward = UINT32_MAX;
    v->first_duplicate[0] = v->first_duplicate[1] = UINT32_MAX;
    v->first_nonmanifold[0] = v->first_nonmanifold[1] = UINT32_MAX;
    v->first_misoriented[0] = v->first_misoriented[1] = UINT32_MAX;
    v->first_t_junction[0] = v->first_t_junction[1] = v->first_t_junction[2] = UINT32_MAX;
    v->first_coincident[0] = v->first_coincident[1] = UINT32_MAX;
    v->triangles = m->triangle_count;
    const tsr_allocator *al = m->alloc.realloc ? &m->alloc : NULL;
    size_t nv = m->vertex_count, nt = m->triangle_count;

    /* Bounding box, non-finite positions. */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    unsigned char *bad_vertex = tsr_alloc(al, nv + 1);
    unsigned char *used = tsr_alloc(al, nv + 1);
    if (!bad_vertex || !used) {
        tsr_free(al, bad_vertex);
        tsr_free(al, used);
        return TSR_ERR_NOMEM;
    }
    memset(used, 0, nv + 1);
    for (size_t i = 0; i < nv; i++) {
        const float *p = m->positions + 3 * i;
        bad_vertex[i] = !(isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]));
        if (bad_vertex[i]) {
            v->nonfinite_positions++;
            continue;
        }
        for (int k = 0; k < 3; k++) {
            lo[k] = p[k] < lo[k] ? p[k] : lo[k];
            hi[k] = p[k] > hi[k] ? p[k] : hi[k];
        }
    }
    int dims = opts && opts->height_field ? 2 : 3;
    double diag = 0;
    for (int k = 0; k < dims; k++)
        diag += hi[k] > lo[k] ? (hi[k] - lo[k]) * (hi[k] - lo[k]) : 0;
    diag = sqrt(diag);
    double eps = opts && opts->epsilon > 0 ? opts->epsilon : 1e-6 * (diag > 0 ? diag : 1);

    /* Per-triangle checks. A triangle with a bad index or a non-finite
     * corner is excluded from every later check (it has no geometry). */
    unsigned char *skip = tsr_alloc(al, nt + 1);
    kv *tri_keys = tsr_alloc(al, (nt + 1) * sizeof *tri_keys);
    if (!skip || !tri_keys) {
        tsr_free(al, skip);
        tsr_free(al, tri_keys);
        tsr_free(al, bad_vertex);
        tsr_free(al, used);
        return TSR_ERR_NOMEM;
    }
    size_t nkeys = 0;
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *ix = m->indices + 3 * t;
        skip[t] = 0;
        if (ix[0] >= nv || ix[1] >= nv || ix[2] >= nv) {
            v->bad_indices++;
            skip[t] = 1;
        } else if (bad_vertex[ix[0]] || bad_vertex[ix[1]] || bad_vertex[ix[2]]) {
            skip[t] = 1;
        }
        if (skip[t]) {
            if (v->first_bad_triangle == UINT32_MAX)
                v->first_bad_triangle = (uint32_t)t;
            continue;
        }
        used[ix[0]] = used[ix[1]] = used[ix[2]] = 1;
        const float *p0 = m->positions + 3 * (size_t)ix[0];
        const float *p1 = m->positions + 3 * (size_t)ix[1];
        const float *p2 = m->positions + 3 * (size_t)ix[2];
        double e1[3], e2[3];
        for (int k = 0; k < 3; k++) {
            e1[k] = (double)p1[k] - p0[k];
            e2[k] = (double)p2[k] - p0[k];
        }
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
        double area2 = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        /* zero area: twice the area below eps times the longest edge */
        double l1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
        double l2 = sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]);
        double lmax = l1 > l2 ? l1 : l2;
        if (ix[0] == ix[1] || ix[1] == ix[2] || ix[0] == ix[2] || area2 <= eps * lmax * 1e-3) {
            v->degenerate_triangles++;
            if (v->first_degenerate == UINT32_MAX)
                v->first_degenerate = (uint32_t)t;
        }
        if (opts && opts->expect_up && !(n[2] > 0)) {
            v->downward_triangles++;
            if (v->first_downward == UINT32_MAX)
                v->first_downward = (uint32_t)t;
        }
        /* sorted triple, packed as 3 x 21 bits is not enough in general,
         * so hash the sorted triple and compare exactly on collisions */
        uint32_t s[3] = {ix[0], ix[1], ix[2]}, tmp;
        if (s[0] > s[1]) { tmp = s[0]; s[0] = s[1]; s[1] = tmp; }
        if (s[1] > s[2]) { tmp = s[1]; s[1] = s[2]; s[2] = tmp; }
        if (s[0] > s[1]) { tmp = s[0]; s[0] = s[1]; s[1] = tmp; }
        uint64_t h = s[0] * 0x9E3779B97F4A7C15ull;
        h = (h ^ s[1]) * 0xC2B2AE3D27D4EB4Full;
        h = (h ^ s[2]) * 0x165667B19E3779F9ull;
        tri_keys[nkeys].key = h;
        tri_keys[nkeys].val = (uint32_t)t;
        nkeys++;
    }
    kv_sort(tri_keys, nkeys, al);
    for (size_t i = 0; i + 1 < nkeys; i++) {
        for (size_t j = i + 1; j < nkeys && tri_keys[j].key == tri_keys[i].key; j++) {
            const uint32_t *a = m->indices + 3 * (size_t)tri_keys[i].val;
            const uint32_t *b = m->indices + 3 * (size_t)tri_keys[j].val;
            int same = 0;
            for (int x = 0; x < 3; x++)
                for (int y = 0; y < 3; y++)
                    if (a[x] == b[y]) {
                        same++;
                        break;
                    }
            if (same == 3) {
                v->duplicate_triangles++;
                if (v->first_duplicate[0] == UINT32_MAX) {
                    v->first_duplicate[0] = tri_keys[i].val;
                    v->first_duplicate[1] = tri_keys[j].val;
                }
                break;
            }
        }
    }
    tsr_free(al, tri_keys);

    /* Edges: half-edge view built over the usable triangles only. */
    tsr_mesh sub = *m;
    uint32_t *sub_idx = NULL;
    if (v->bad_indices || v->first_bad_triangle != UINT32_MAX) {
        sub_idx = tsr_alloc(al, (nt + 1) * 3 * sizeof *sub_idx);
        if (!sub_idx) {
            tsr_free(al, skip);
            tsr_free(al, bad_vertex);
            tsr_free(al, used);
            return TSR_ERR_NOMEM;
        }
        size_t k = 0;
        for (size_t t = 0; t < nt; t++)
            if (!skip[t])
                memcpy(sub_idx + 3 * k++, m->indices + 3 * t, 3 * sizeof *sub_idx);
        sub.indices = sub_idx;
        sub.triangle_count = (uint32_t)k;
    }
    tsr_free(al, skip);
    tsr_halfedges he;
    tsr_status st = tsr_halfedges_build(&he, &sub, al);
    if (st != TSR_OK) {
        tsr_free(al, sub_idx);
        tsr_free(al, bad_vertex);
        tsr_free(al, used);
        return st;
    }
    v->edges = he.edge_count;
    uint32_t *bnext = NULL; /* per vertex: a boundary half-edge leaving it */
    for (uint32_t h = 0; h < he.count; h++) {
        uint32_t a = he_from(&sub, h), b = he_to(&sub, h);
        if (a == b)
            continue;
        uint32_t tw = he.twin[h];
        if (tw == TSR_NONMANIFOLD)
            continue; /* counted below, once per edge */
        if (tw == TSR_NO_TWIN) {
            v->boundary_edges++;
            continue;
        }
        if (h < tw && he_from(&sub, tw) == a) {
            v->misoriented_edges++;
            if (v->first_misoriented[0] == UINT32_MAX) {
                v->first_misoriented[0] = a;
                v->first_misoriented[1] = b;
            }
        }
    }
    /* Non-manifold edges: count distinct keys among NONMANIFOLD half-edges. */
    {
        size_t nn = 0;
        for (uint32_t h = 0; h < he.count; h++)
            nn += he.twin[h] == TSR_NONMANIFOLD;
        if (nn) {
            kv *e = tsr_alloc(al, nn * sizeof *e);
            if (e) {
                size_t k = 0;
                for (uint32_t h = 0; h < he.count; h++)
                    if (he.twin[h] == TSR_NONMANIFOLD) {
                        e[k].key = edge_key(he_from(&sub, h), he_to(&sub, h));
                        e[k++].val = h;
                    }
                kv_sort(e, nn, al);
                for (size_t i = 0; i < nn; i++)
                    if (i == 0 || e[i].key != e[i - 1].key) {
                        v->nonmanifold_edges++;
                        if (v->first_nonmanifold[0] == UINT32_MAX) {
                            v->first_nonmanifold[0] = (uint32_t)(e[i].key >> 32);
                            v->first_nonmanifold[1] = (uint32_t)e[i].key;
                        }
                    }
                tsr_free(al, e);
            } else {
                st = TSR_ERR_NOMEM;
            }
        }
    }

    /* Boundary loops: follow boundary half-edges head to tail. At a vertex
     * where several boundary loops meet, any unused outgoing one is taken. */
    if (st == TSR_OK && v->boundary_edges) {
        bnext = tsr_alloc(al, (nv + 1) * sizeof *bnext);
        uint32_t *chain = tsr_alloc(al, (he.count + 1) * sizeof *chain);
        unsigned char *done = tsr_alloc(al, he.count + 1);
        if (!bnext || !chain || !done) {
            st = TSR_ERR_NOMEM;
        } else {
            for (size_t i = 0; i < nv; i++)
                bnext[i] = UINT32_MAX;
            memset(done, 0, he.count + 1);
            /* chain[h] links boundary half-edges leaving the same vertex */
            for (uint32_t h = 0; h < he.count; h++) {
                chain[h] = UINT32_MAX;
                if (he.twin[h] != TSR_NO_TWIN || he_from(&sub, h) == he_to(&sub, h))
                    continue;
                uint32_t a = he_from(&sub, h);
                chain[h] = bnext[a];
                bnext[a] = h;
            }
            for (uint32_t h = 0; h < he.count; h++) {
                if (he.twin[h] != TSR_NO_TWIN || done[h] || he_from(&sub, h) == he_to(&sub, h))
                    continue;
                uint32_t len = 0, cur = h;
                while (cur != UINT32_MAX && !done[cur]) {
                    done[cur] = 1;
                    len++;
                    uint32_t b = he_to(&sub, cur), nx = bnext[b];
                    while (nx != UINT32_MAX && done[nx])
                        nx = chain[nx];
                    cur = nx;
                }
                if (v->boundary_loops < TSR_VALIDATE_MAX_LOOPS)
                    v->loop_length[v->boundary_loops] = len;
                v->boundary_loops++;
            }
        }
        tsr_free(al, chain);
        tsr_free(al, done);
    }
    tsr_free(al, bnext);

    /* Referenced vertices and Euler characteristic. */
    for (size_t i = 0; i < nv; i++)
        v->vertices += used[i];
    v->euler = (int64_t)v->vertices - (int64_t)v->edges + (int64_t)sub.triangle_count;

    /* Coincident vertices and T-junctions, through a k-d tree of the used
     * vertices (queries inflated by 2 eps: rounding cannot drop a vertex
     * within eps). */
    if (st == TSR_OK && v->vertices > 0) {
        kdtree t = {.pos = m->positions, .dims = dims};
        uint32_t cap = v->vertices / 4 + 2;
        t.idx = tsr_alloc(al, (size_t)v->vertices * sizeof *t.idx);
        t.node = tsr_alloc(al, (size_t)cap * sizeof *t.node);
        if (!t.idx || !t.node) {
            st = TSR_ERR_NOMEM;
        } else {
            uint32_t n = 0;
            for (size_t i = 0; i < nv; i++)
                if (used[i])
                    t.idx[n++] = (uint32_t)i;
            kd_build(&t, 0, n, 0);
            double r = 2 * eps;
            /* coincident vertices: pairs i < j within eps; the first
             * reported is the smallest i's smallest j */
            for (size_t i = 0; i < nv; i++) {
                if (!used[i])
                    continue;
                const float *p = m->positions + 3 * i;
                uint32_t first = UINT32_MAX;
                kd_query(&t);
                for (const kdnode *nd; (nd = kd_next(&t, p, p, r)) != NULL;)
                    for (uint32_t k = nd->begin; k < nd->end; k++) {
                        uint32_t j = t.idx[k];
                        if (j <= i)
                            continue;
                        const float *q = m->positions + 3 * (size_t)j;
                        double d2 = 0;
                        for (int a = 0; a < dims; a++)
                            d2 += ((double)p[a] - q[a]) * ((double)p[a] - q[a]);
                        if (d2 <= eps * eps) {
                            v->coincident_vertices++;
                            first = j < first ? j : first;
                        }
                    }
                if (first != UINT32_MAX && v->first_coincident[0] == UINT32_MAX) {
                    v->first_coincident[0] = (uint32_t)i;
                    v->first_coincident[1] = first;
                }
            }
            /* T-junctions: for each open or non-manifold edge, the
             * vertices strictly inside it within eps. An edge two
             * triangles share closes the surface there: a vertex on it
             * (of a coincident sheet: a surface folded onto itself,
             * back-to-back faces) leaves no gap, and a real T-junction
             * always leaves its long edge open on one side. The first
             * reported is the first such edge's smallest vertex. */
            for (uint32_t h = 0; h < he.count; h++) {
                uint32_t a = he_from(&sub, h), b = he_to(&sub, h), tw = he.twin[h];
                if (a == b)
                    continue;
                if (tw != TSR_NO_TWIN && tw != TSR_NONMANIFOLD)
                    continue;
                const float *pa = m->positions + 3 * (size_t)a, *pb = m->positions + 3 * (size_t)b;
                uint32_t first = UINT32_MAX;
                kd_query(&t);
                for (const kdnode *nd; (nd = kd_next(&t, pa, pb, r)) != NULL;)
                    for (uint32_t k = nd->begin; k < nd->end; k++) {
                        uint32_t j = t.idx[k];
                        if (j != a && j != b && on_open_segment(m->positions + 3 * (size_t)j, pa, pb, eps, dims)) {
                            v->t_junctions++;
                            first = j < first ? j : first;
                        }
                    }
                if (first != UINT32_MAX && v->first_t_junction[0] == UINT32_MAX) {
                    v->first_t_junction[0] = first;
                    v->first_t_junction[1] = a;
                    v->first_t_junction[2] = b;
                }
            }
        }
        tsr_free(al, t.idx);
        tsr_free(al, t.node);
    }
    tsr_halfedges_free(&he);
    tsr_free(al, sub_idx);
    tsr_free(al, bad_vertex);
    tsr_free(al, used);
    return st;
}

bool tsr_validation_ok(const tsr_validation *v)
{
    return v->bad_indices == 0 && v->first_bad_triangle == UINT32_MAX && v->degenerate_triangles == 0 &&
           v->duplicate_triangles == 0 && v->nonmanifold_edges == 0 && v->misoriented_edges == 0 &&
           v->t_junctions == 0 && v->downward_triangles == 0;
}

void tsr_validation_describe(const tsr_validation *v, char *buf, size_t cap)
{
    size_t n = 0;
    buf[0] = '\0';
#define ADD(...)                                                                                   \
    do {                                                                                           \
        if (n < cap) {                                                                             \
            int w = snprintf(buf + n, cap - n, __VA_ARGS__);                                      \
            if (w > 0)                                                                             \
                n += (size_t)w;                                                                    \
        }                                                                                          \
    } while (0)
    if (v->bad_indices)
        ADD("%u triangles with out-of-range indices (first: triangle %u); ", v->bad_indices,
            v->first_bad_triangle);
    else if (v->first_bad_triangle != UINT32_MAX)
        ADD("triangles with non-finite corners (first: triangle %u); ", v->first_bad_triangle);
    if (v->degenerate_triangles)
        ADD("%u degenerate triangles (first: %u); ", v->degenerate_triangles, v->first_degenerate);
    if (v->duplicate_triangles)
        ADD("%u duplicate triangles (first: %u and %u); ", v->duplicate_triangles, v->first_duplicate[0],
            v->first_duplicate[1]);
    if (v->nonmanifold_edges)
        ADD("%u non-manifold edges (first: %u-%u); ", v->nonmanifold_edges, v->first_nonmanifold[0],
            v->first_nonmanifold[1]);
    if (v->misoriented_edges)
        ADD("%u inconsistently oriented edges (first: %u-%u); ", v->misoriented_edges,
            v->first_misoriented[0], v->first_misoriented[1]);
    if (v->t_junctions)
        ADD("%u T-junctions (first: vertex %u on edge %u-%u); ", v->t_junctions, v->first_t_junction[0],
            v->first_t_junction[1], v->first_t_junction[2]);
    if (v->downward_triangles)
        ADD("%u triangles facing down (first: %u); ", v->downward_triangles, v->first_downward);
    if (n == 0)
        ADD("ok: %u vertices, %u edges, %u triangles, %u boundary loops, Euler %lld", v->vertices, v->edges,
            v->triangles, v->boundary_loops, (long long)v->euler);
    else if (n >= 2 && n < cap)
        buf[n - 2] = '\0';
#undef ADD
}

bool tsr_mesh_boundary_is_rect(const tsr_mesh *m, double x0, double y0, double x1, double y1, double eps,
                               uint32_t *bad_vertex)
{
    if (bad_vertex)
        *bad_vertex = UINT32_MAX;
    tsr_validation v;
    if (tsr_mesh_validate(m, NULL, &v) != TSR_OK || v.boundary_loops != 1)
        return false;
    tsr_halfedges he;
    if (tsr_halfedges_build(&he, m, m->alloc.realloc ? &m->alloc : NULL) != TSR_OK)
        return false;
    bool ok = true;
    for (uint32_t h = 0; h < he.count && ok; h++) {
        if (he.twin[h] != TSR_NO_TWIN)
            continue;
        uint32_t ends[2] = {he_from(m, h), he_to(m, h)};
        if (ends[0] == ends[1])
            continue;
        const float *p = m->positions + 3 * (size_t)ends[0], *q = m->positions + 3 * (size_t)ends[1];
        /* both ends on one common side of the rectangle */
        bool left = fabs(p[0] - x0) <= eps && fabs(q[0] - x0) <= eps;
        bool right = fabs(p[0] - x1) <= eps && fabs(q[0] - x1) <= eps;
        bool bottom = fabs(p[1] - y0) <= eps && fabs(q[1] - y0) <= eps;
        bool top = fabs(p[1] - y1) <= eps && fabs(q[1] - y1) <= eps;
        if (!(left || right || bottom || top)) {
            ok = false;
            if (bad_vertex) {
                bool p_on = fabs(p[0] - x0) <= eps || fabs(p[0] - x1) <= eps || fabs(p[1] - y0) <= eps ||
                            fabs(p[1] - y1) <= eps;
                *bad_vertex = p_on ? ends[1] : ends[0];
            }
        }
    }
    tsr_halfedges_free(&he);
    return ok;
}

typedef struct gap_edge {
    uint32_t h, a, b; /* half-edge, its start and end vertices */
    uint32_t sheet;   /* its connected piece of surface (through shared edges) */
    float lo[3], hi[3];
} gap_edge;

static int cmp_gap_edge(const void *x, const void *y)
{
    float a = ((const gap_edge *)x)->lo[0], b = ((const gap_edge *)y)->lo[0];
    return a < b ? -1 : a > b;
}

double tsr_point_segment_dist2(const float p[3], const float a[3], const float b[3])
{
    double ab[3], ap[3], l2 = 0, t = 0;
    for (int k = 0; k < 3; k++) {
        ab[k] = (double)b[k] - a[k];
        ap[k] = (double)p[k] - a[k];
        l2 += ab[k] * ab[k];
        t += ab[k] * ap[k];
    }
    t = l2 > 0 ? t / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += (ap[k] - t * ab[k]) * (ap[k] - t * ab[k]);
    return d2;
}

/* Which of open edge e's ends and midpoint (bits 0, 1, 2) lie within eps
 * of f, when the two run opposite ways, or the same way on different sheets
 * (0 otherwise). */
static unsigned gap_along(const tsr_mesh *m, const gap_edge *e, const gap_edge *f, double eps2)
{
    const float *a0 = m->positions + 3 * (size_t)e->a, *a1 = m->positions + 3 * (size_t)e->b;
    const float *b0 = m->positions + 3 * (size_t)f->a, *b1 = m->positions + 3 * (size_t)f->b;
    double dot = 0, la = 0, lb = 0;
    float mid[3];
    for (int k = 0; k < 3; k++) {
        double u = (double)a1[k] - a0[k], v = (double)b1[k] - b0[k];
        dot += u * v;
        la += u * u;
        lb += v * v;
        mid[k] = (float)(0.5 * ((double)a0[k] + a1[k]));
    }
    if (!(dot < -0.5 * sqrt(la * lb)) && !(e->sheet != f->sheet && dot > 0.5 * sqrt(la * lb)))
        return 0;
    return (tsr_point_segment_dist2(a0, b0, b1) <= eps2 ? 1u : 0u) | (tsr_point_segment_dist2(a1, b0, b1) <= eps2 ? 2u : 0u) |
           (tsr_point_segment_dist2(mid, b0, b1) <= eps2 ? 4u : 0u);
}

/* The sheets of nt triangles: union-find parents (parent: nt entries)
 * joining triangles through shared (twinned, manifold) edges; find a
 * triangle's sheet with tsr__uf_find. */
static void join_sheets(const tsr_halfedges *he, uint32_t nt, uint32_t *parent)
{
    for (uint32_t t = 0; t < nt; t++)
        parent[t] = t;
    for (uint32_t h = 0; h < he->count; h++) {
        uint32_t tw = he->twin[h];
        if (tw == TSR_NO_TWIN || tw == TSR_NONMANIFOLD)
            continue;
        uint32_t a = tsr__uf_find(parent, h / 3), b = tsr__uf_find(parent, tw / 3);
        if (a != b)
            parent[a] = b;
    }
}

tsr_status tsr_mesh_find_gaps(const tsr_mesh *m, double eps, bool *hit, uint32_t *count)
{
    if (count)
        *count = 0;
    if (!m || !(eps >= 0))
        return TSR_ERR_ARGUMENT;
    if (hit)
        memset(hit, 0, 3 * (size_t)m->triangle_count * sizeof *hit);
    tsr_halfedges he;
    if (tsr_halfedges_build(&he, m, NULL) != TSR_OK)
        return TSR_ERR_NOMEM;
    uint32_t nb = 0;
    for (uint32_t h = 0; h < he.count; h++)
        nb += he.twin[h] == TSR_NO_TWIN;
    gap_edge *e = malloc((nb ? nb : 1) * sizeof *e);
    uint8_t *in = calloc(nb ? nb : 1, sizeof *in); /* gap_along's bits, over all opposite edges */
    uint32_t *sheet = malloc(((size_t)m->triangle_count + 1) * sizeof *sheet);
    if (!e || !in || !sheet) {
        free(e);
        free(in);
        free(sheet);
        tsr_halfedges_free(&he);
        return TSR_ERR_NOMEM;
    }
    join_sheets(&he, m->triangle_count, sheet);
    nb = 0;
    for (uint32_t h = 0; h < he.count; h++) {
        uint32_t a = m->indices[h], b = m->indices[3 * (h / 3) + (h % 3 + 1) % 3];
        if (he.twin[h] != TSR_NO_TWIN || a == b || a >= m->vertex_count || b >= m->vertex_count)
            continue;
        gap_edge *g = &e[nb++];
        *g = (gap_edge){h, a, b, tsr__uf_find(sheet, h / 3), {0}, {0}};
        for (int k = 0; k < 3; k++) {
            float pa = m->positions[3 * (size_t)a + k], pb = m->positions[3 * (size_t)b + k];
            g->lo[k] = (float)((pa < pb ? pa : pb) - eps);
            g->hi[k] = (float)((pa < pb ? pb : pa) + eps);
        }
    }
    tsr_halfedges_free(&he);
    free(sheet);
    qsort(e, nb, sizeof *e, cmp_gap_edge);
    double eps2 = eps * eps;
    uint32_t n = 0;
    for (uint32_t i = 0; i < nb; i++)
        for (uint32_t j = i + 1; j < nb && e[j].lo[0] <= e[i].hi[0]; j++) {
            if (e[j].lo[1] > e[i].hi[1] || e[j].hi[1] < e[i].lo[1] || e[j].lo[2] > e[i].hi[2] ||
                e[j].hi[2] < e[i].lo[2] || e[i].a == e[j].a || e[i].a == e[j].b || e[i].b == e[j].a || e[i].b == e[j].b)
                continue;
            if (in[i] != 7)
                in[i] |= (uint8_t)gap_along(m, &e[i], &e[j], eps2);
            if (in[j] != 7)
                in[j] |= (uint8_t)gap_along(m, &e[j], &e[i], eps2);
        }
    for (uint32_t i = 0; i < nb; i++)
        if (in[i] == 7) {
            n++;
            if (hit)
                hit[e[i].h] = true;
        }
    free(e);
    free(in);
    if (count)
        *count = n;
    return TSR_OK;
}

tsr_status tsr_mesh_find_inward_shells(const tsr_mesh *m, uint8_t *flip, uint32_t *shells)
{
    const tsr_allocator *al = m->alloc.realloc ? &m->alloc : NULL;
    uint32_t nt = m->triangle_count;
    if (shells)
        *shells = 0;
    memset(flip, 0, nt);
    for (uint32_t t = 0; t < 3 * nt; t++)
        if (m->indices[t] >= m->vertex_count)
            return TSR_ERR_ARGUMENT;
    tsr_halfedges he;
    tsr_status st = tsr_halfedges_build(&he, m, al);
    if (st != TSR_OK)
        return st;
    uint32_t *parent = tsr_alloc(al, ((size_t)nt + 1) * sizeof *parent);
    unsigned char *open = tsr_alloc(al, (size_t)nt + 1);
    double *vol = tsr_alloc(al, ((size_t)nt + 1) * sizeof *vol);
    if (!parent || !open || !vol) {
        st = TSR_ERR_NOMEM;
        goto done;
    }
    for (uint32_t t = 0; t < nt; t++) {
        open[t] = 0;
        vol[t] = 0;
    }
    join_sheets(&he, nt, parent);
    for (uint32_t h = 0; h < he.count; h++)
        if (he.twin[h] == TSR_NO_TWIN || he.twin[h] == TSR_NONMANIFOLD)
            open[tsr__uf_find(parent, h / 3)] = 1;
    for (uint32_t t = 0; t < nt; t++) {
        const float *p[3];
        for (int k = 0; k < 3; k++)
            p[k] = m->positions + 3 * (size_t)m->indices[3 * (size_t)t + k];
        double c[3] = {(double)p[1][1] * p[2][2] - (double)p[1][2] * p[2][1],
                       (double)p[1][2] * p[2][0] - (double)p[1][0] * p[2][2],
                       (double)p[1][0] * p[2][1] - (double)p[1][1] * p[2][0]};
        vol[tsr__uf_find(parent, t)] += (p[0][0] * c[0] + p[0][1] * c[1] + p[0][2] * c[2]) / 6;
    }
    for (uint32_t t = 0; t < nt; t++) {
        uint32_t r = tsr__uf_find(parent, t);
        flip[t] = !open[r] && vol[r] < 0;
        if (shells && r == t && flip[t])
            (*shells)++;
    }
done:
    tsr_free(al, parent);
    tsr_free(al, open);
    tsr_free(al, vol);
    tsr_halfedges_free(&he);
    return st;
}

void tsr_mesh_flip_marked(tsr_mesh *m, const uint8_t *flip)
{
    bool normals = (m->attributes & TSR_MESH_NORMALS) && m->normals;
    const tsr_allocator *al = m->alloc.realloc ? &m->alloc : NULL;
    unsigned char *done = normals ? tsr_alloc(al, (size_t)m->vertex_count + 1) : NULL;
    if (done)
        memset(done, 0, (size_t)m->vertex_count + 1);
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        if (!flip[t])
            continue;
        uint32_t *ix = m->indices + 3 * (size_t)t, tmp = ix[1];
        ix[1] = ix[2];
        ix[2] = tmp;
        for (int k = 0; k < 3 && done; k++)
            if (ix[k] < m->vertex_count && !done[ix[k]]) {
                done[ix[k]] = 1;
                for (int c = 0; c < 3; c++)
                    m->normals[3 * (size_t)ix[k] + c] = -m->normals[3 * (size_t)ix[k] + c];
            }
    }
    tsr_free(al, done);
}
