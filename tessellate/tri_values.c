/* tri_values.c: what Triangle carries from its input to a triangulation:
 * values at the input points to every output vertex (tsr_tri_interpolate;
 * the interpolant is that of the input's own constrained Delaunay
 * triangulation, so it does not depend on refinement, and the Steiner
 * points are located in it by a walk from a nearby triangle), and regions
 * grown from seed points to the triangles (tsr_tri_regions). */
#include "tessellate/tessellate.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* The input's own triangulation and what the walk needs of it. */
typedef struct base {
    const tsr_triangulation *t;
    uint32_t *adj;   /* 3 per triangle: the triangle across edge (k, k+1), or NONE */
    uint32_t *start; /* per cell: a triangle whose centroid lies in it, or NONE */
    uint32_t cells;  /* per side */
    double lo[2], scale[2];
    uint32_t last, seed;
} base;

#define NONE UINT32_MAX

/* Incidences per vertex (CSR): first[v] .. first[v + 1] in list. */
typedef struct incid {
    uint32_t *first, *list;
} incid;

static bool incid_build(incid *c, uint32_t nv, const uint32_t *items, uint32_t nitems, uint32_t per,
                        const tsr_allocator *a)
{
    c->first = tsr_alloc(a, ((size_t)nv + 2) * sizeof *c->first);
    c->list = tsr_alloc(a, ((size_t)nitems * per + 1) * sizeof *c->list);
    if (!c->first || !c->list)
        return false;
    memset(c->first, 0, ((size_t)nv + 2) * sizeof *c->first);
    for (size_t i = 0; i < (size_t)nitems * per; i++)
        c->first[items[i] + 2]++;
    for (uint32_t v = 0; v < nv; v++)
        c->first[v + 2] += c->first[v + 1];
    for (size_t i = 0; i < (size_t)nitems * per; i++)
        c->list[c->first[items[i] + 1]++] = (uint32_t)(i / per);
    return true;
}

static void incid_free(incid *c, const tsr_allocator *a)
{
    tsr_free(a, c->first);
    tsr_free(a, c->list);
}

/* Neighbours across each triangle edge, from the triangles at each vertex. */
static bool build_adjacency(base *b, const tsr_allocator *a)
{
    const tsr_triangulation *t = b->t;
    incid at;
    b->adj = tsr_alloc(a, (3 * (size_t)t->nt + 1) * sizeof *b->adj);
    if (!b->adj || !incid_build(&at, t->nv, t->tri, t->nt, 3, a)) {
        if (b->adj)
            incid_free(&at, a);
        return false;
    }
    for (uint32_t i = 0; i < t->nt; i++)
        for (int k = 0; k < 3; k++) {
            uint32_t u = t->tri[3 * (size_t)i + k], w = t->tri[3 * (size_t)i + (k + 1) % 3], found = NONE;
            for (uint32_t j = at.first[u]; j < at.first[u + 1] && found == NONE; j++) {
                uint32_t o = at.list[j];
                const uint32_t *q = &t->tri[3 * (size_t)o];
                /* the neighbour has the edge the other way: w then u */
                for (int m = 0; m < 3 && o != i; m++)
                    if (q[m] == w && q[(m + 1) % 3] == u)
                        found = o;
            }
            b->adj[3 * (size_t)i + k] = found;
        }
    incid_free(&at, a);
    return true;
}

static uint32_t cell_of(const base *b, const double p[2])
{
    uint32_t c[2];
    for (int d = 0; d < 2; d++) {
        double f = (p[d] - b->lo[d]) * b->scale[d];
        c[d] = !(f > 0) ? 0 : f >= b->cells - 1 ? b->cells - 1 : (uint32_t)f;
    }
    return c[1] * b->cells + c[0];
}

static bool build_start_grid(base *b, const tsr_allocator *a)
{
    const tsr_triangulation *t = b->t;
    double hi[2] = {-INFINITY, -INFINITY};
    b->lo[0] = b->lo[1] = INFINITY;
    for (uint32_t v = 0; v < t->nv; v++)
        for (int d = 0; d < 2; d++) {
            b->lo[d] = fmin(b->lo[d], t->xy[2 * (size_t)v + d]);
            hi[d] = fmax(hi[d], t->xy[2 * (size_t)v + d]);
        }
    double side = ceil(sqrt(t->nt / 4.0));
    b->cells = side < 1 ? 1 : side > 4096 ? 4096 : (uint32_t)side;
    for (int d = 0; d < 2; d++)
        b->scale[d] = hi[d] > b->lo[d] ? b->cells / (hi[d] - b->lo[d]) : 0;
    b->start = tsr_alloc(a, (size_t)b->cells * b->cells * sizeof *b->start);
    if (!b->start)
        return false;
    memset(b->start, 0xff, (size_t)b->cells * b->cells * sizeof *b->start);
    for (uint32_t i = 0; i < t->nt; i++) {
        double c[2] = {0, 0};
        for (int k = 0; k < 3; k++)
            for (int d = 0; d < 2; d++)
                c[d] += t->xy[2 * (size_t)t->tri[3 * (size_t)i + k] + d] / 3;
        b->start[cell_of(b, c)] = i;
    }
    return true;
}

/* Twice the signed area of a, b, c, nearly exact (within a few units in
 * the last place of the result, however thin the triangle): the six
 * products of the expanded determinant, each exact as two doubles (fma),
 * summed with Neumaier's compensation. The differences of the plain formula
 * would lose the area of a sliver: with edges of length L it is off by
 * about L^2 times the rounding unit, which for a sliver 1e-11 wide and 30
 * long moves the interpolated point by a hundredth of a unit. */
static double area2(const double *a, const double *b, const double *c)
{
    const double f[6][2] = {{a[0], b[1]}, {-a[1], b[0]}, {b[0], c[1]}, {-b[1], c[0]}, {c[0], a[1]}, {-c[1], a[0]}};
    double s = 0, comp = 0;
    for (int i = 0; i < 6; i++) {
        double hi = f[i][0] * f[i][1], lo = fma(f[i][0], f[i][1], -hi), t[2] = {hi, lo};
        for (int k = 0; k < 2; k++) {
            double u = s + t[k];
            comp += fabs(s) >= fabs(t[k]) ? (s - u) + t[k] : (t[k] - u) + s;
            s = u;
        }
    }
    return s + comp;
}

/* The weights of p on triangle i's vertices: its barycentric coordinates
 * when p lies in it; otherwise (p beyond a hull edge by rounding) those of
 * the nearest point of the triangle's edges, so the point used moves no
 * further than p is outside. */
static void barycentric(const base *b, uint32_t i, const double p[2], double l[3])
{
    const uint32_t *q = &b->t->tri[3 * (size_t)i];
    const double *v[3] = {&b->t->xy[2 * (size_t)q[0]], &b->t->xy[2 * (size_t)q[1]], &b->t->xy[2 * (size_t)q[2]]};
    double sum = 0;
    bool outside = false;
    for (int k = 0; k < 3; k++) {
        l[k] = area2(v[(k + 1) % 3], v[(k + 2) % 3], p); /* the sub-triangle opposite vertex k */
        outside = outside || l[k] < 0;
        sum += l[k];
    }
    if (!outside && sum > 0) {
        for (int k = 0; k < 3; k++)
            l[k] /= sum;
        return;
    }
    double best = INFINITY;
    for (int k = 0; k < 3; k++) {
        const double *u = v[k], *w = v[(k + 1) % 3];
        double d[2] = {w[0] - u[0], w[1] - u[1]}, len2 = d[0] * d[0] + d[1] * d[1];
        double f = len2 > 0 ? ((p[0] - u[0]) * d[0] + (p[1] - u[1]) * d[1]) / len2 : 0;
        f = f < 0 ? 0 : f > 1 ? 1 : f;
        double dist = hypot(u[0] + f * d[0] - p[0], u[1] + f * d[1] - p[1]);
        if (dist < best) {
            best = dist;
            l[k] = 1 - f;
            l[(k + 1) % 3] = f;
            l[(k + 2) % 3] = 0;
        }
    }
}

/* The triangle p lies in (or, outside the hull, a hull triangle it lies
 * beyond): a visibility walk with a random first edge at each step, which
 * ends on any triangulation; a brute-force search if it runs long. */
static uint32_t locate(base *b, const double p[2])
{
    const tsr_triangulation *t = b->t;
    uint32_t i = b->start[cell_of(b, p)];
    if (i == NONE)
        i = b->last;
    for (uint64_t steps = 0; steps <= 4 * (uint64_t)t->nt + 64; steps++) {
        b->seed = b->seed * 1664525u + 1013904223u;
        uint32_t r = (b->seed >> 16) % 3, next = NONE;
        for (uint32_t m = 0; m < 3 && next == NONE; m++) {
            uint32_t k = (r + m) % 3, o = b->adj[3 * (size_t)i + k];
            if (o == NONE)
                continue;
            const double *u = &t->xy[2 * (size_t)t->tri[3 * (size_t)i + k]];
            const double *w = &t->xy[2 * (size_t)t->tri[3 * (size_t)i + (k + 1) % 3]];
            if (tsr_orient2d(u, w, p) < 0)
                next = o;
        }
        if (next == NONE)
            return b->last = i;
        i = next;
    }
    /* not reached on a valid triangulation: the triangle whose nearest
     * point (barycentric) is nearest */
    uint32_t best = 0;
    double best_d = INFINITY;
    for (uint32_t j = 0; j < t->nt; j++) {
        double l[3], q[2] = {0, 0};
        barycentric(b, j, p, l);
        for (int k = 0; k < 3; k++)
            for (int d = 0; d < 2; d++)
                q[d] += l[k] * t->xy[2 * (size_t)t->tri[3 * (size_t)j + k] + d];
        double dd = hypot(q[0] - p[0], q[1] - p[1]);
        if (dd < best_d)
            best_d = dd, best = j;
    }
    return b->last = best;
}

/* Rows of the input values at a triangulation's input vertices (a point
 * given twice: its first row). */
static void input_rows(const tsr_pslg *in, const double *in_vals, uint32_t n, const tsr_triangulation *t, double *vals)
{
    for (uint32_t i = in->nv; i-- > 0;)
        memcpy(&vals[(size_t)t->vertex_of_input[i] * n], &in_vals[(size_t)i * n], n * sizeof *vals);
}

static double dist(const double *a, const double *b)
{
    return hypot(a[0] - b[0], a[1] - b[1]);
}

/* Vertex v of t takes the row of the input vertex nearest it (brute
 * force: for the cases no triangle or segment can value). */
static void nearest_input_row(const tsr_triangulation *t, uint32_t v, uint32_t n, double *vals)
{
    uint32_t best = 0;
    double best_d = INFINITY;
    for (uint32_t u = 0; u < t->input_vertices; u++) {
        double d = dist(&t->xy[2 * (size_t)v], &t->xy[2 * (size_t)u]);
        if (d < best_d)
            best_d = d, best = u;
    }
    memcpy(&vals[(size_t)v * n], &vals[(size_t)best * n], n * sizeof *vals);
}

/* c = (1 - f) a + f b, kept within [a, b]: a constant stays exact, and
 * huge values do not round beyond the largest double. */
static double lerp(double a, double b, double f)
{
    double c = (1 - f) * a + f * b;
    return c < fmin(a, b) ? fmin(a, b) : c > fmax(a, b) ? fmax(a, b) : c;
}

/* A vertex of the base triangulation on an input segment, at t along it. */
typedef struct onseg {
    uint32_t s, v;
    double t;
} onseg;

static int onseg_cmp(const void *pa, const void *pb)
{
    const onseg *a = pa, *b = pb;
    if (a->s != b->s)
        return a->s < b->s ? -1 : 1;
    if (a->t != b->t)
        return a->t < b->t ? -1 : 1;
    return (a->v > b->v) - (a->v < b->v);
}

/* The crossings of segments in the base triangulation: linear along the
 * lower-numbered segment through each, between the nearest input points on
 * it (the segment's own ends at the latest). The vertices on each segment
 * are sorted along it once, so this is O(E log E) however many crossings a
 * segment has. */
static bool crossing_rows(const tsr_pslg *in, uint32_t n, const base *b, double *vals, const tsr_allocator *a)
{
    const tsr_triangulation *t = b->t;
    uint32_t nin = t->input_vertices;
    if (t->nv == nin)
        return true;
    size_t cap = 2 * (size_t)t->nedge + 2 * (size_t)in->nseg + 1;
    onseg *e = tsr_alloc(a, cap * sizeof *e);
    uint32_t *low = tsr_alloc(a, ((size_t)t->nv + 1) * sizeof *low);
    uint8_t *done = tsr_alloc(a, (size_t)t->nv + 1);
    if (!e || !low || !done) {
        tsr_free(a, e);
        tsr_free(a, low);
        tsr_free(a, done);
        return false;
    }
    memset(done, 0, (size_t)t->nv + 1);
    for (uint32_t v = 0; v < t->nv; v++)
        low[v] = NONE;
    size_t ne = 0;
    for (uint32_t k = 0; k < t->nedge; k++)
        for (int j = 0; j < 2; j++) {
            uint32_t v = t->edge[2 * (size_t)k + j], sg = t->edge_segment[k];
            low[v] = sg < low[v] ? sg : low[v];
            e[ne++] = (onseg){sg, v, 0};
        }
    for (uint32_t sg = 0; sg < in->nseg; sg++) /* the ends: anchors even where overlaps relabel the chain */
        for (int j = 0; j < 2; j++)
            e[ne++] = (onseg){sg, t->vertex_of_input[in->seg[2 * (size_t)sg + j]], 0};
    for (size_t i = 0; i < ne; i++) {
        const double *pa = &in->xy[2 * (size_t)in->seg[2 * (size_t)e[i].s]];
        const double *pb = &in->xy[2 * (size_t)in->seg[2 * (size_t)e[i].s + 1]], *p = &t->xy[2 * (size_t)e[i].v];
        e[i].t = (p[0] - pa[0]) * (pb[0] - pa[0]) + (p[1] - pa[1]) * (pb[1] - pa[1]);
    }
    qsort(e, ne, sizeof *e, onseg_cmp);
    for (size_t g = 0; g < ne;) {
        size_t h = g;
        while (h < ne && e[h].s == e[g].s)
            h++;
        /* in [g, h): one segment's vertices in order; each crossing whose
         * lowest segment this is, between the input vertices around it */
        size_t prev = SIZE_MAX;
        for (size_t i = g; i < h; i++) {
            uint32_t v = e[i].v;
            if (v < nin) {
                prev = i;
                continue;
            }
            if (low[v] != e[i].s || done[v] || prev == SIZE_MAX)
                continue;
            size_t next = i + 1;
            while (next < h && e[next].v >= nin)
                next++;
            if (next == h)
                continue;
            uint32_t va = e[prev].v, vb = e[next].v;
            const double *p = &t->xy[2 * (size_t)v];
            double da = dist(p, &t->xy[2 * (size_t)va]), db = dist(p, &t->xy[2 * (size_t)vb]);
            double f = da + db > 0 ? da / (da + db) : 0.5;
            for (uint32_t c = 0; c < n; c++)
                vals[(size_t)v * n + c] = lerp(vals[(size_t)va * n + c], vals[(size_t)vb * n + c], f);
            done[v] = 1;
        }
        g = h;
    }
    /* not expected: a crossing on no segment, or with no input point on one
     * side */
    for (uint32_t v = nin; v < t->nv; v++)
        if (!done[v])
            nearest_input_row(t, v, n, vals);
    tsr_free(a, e);
    tsr_free(a, low);
    tsr_free(a, done);
    return true;
}

tsr_status tsr_tri_interpolate(const tsr_pslg *in, const double *in_vals, uint32_t n, const tsr_triangulation *out,
                               double *vals, const tsr_allocator *alloc, tsr_error *err)
{
    if (n == 0)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "values to interpolate: none per point");
    if (!out->vertex_of_input || out->input_vertices > in->nv || out->input_vertices > out->nv)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "values to interpolate: the triangulation is not of this input");
    for (uint32_t i = 0; i < in->nv; i++)
        if (out->vertex_of_input[i] >= out->input_vertices)
            return tsr_error_set(err, TSR_ERR_ARGUMENT,
                                 "values to interpolate: the triangulation is not of this input");
    input_rows(in, in_vals, n, out, vals);
    if (out->nv == out->input_vertices)
        return TSR_OK;
    base b;
    memset(&b, 0, sizeof b);
    tsr_pslg p0 = *in;
    p0.holes = NULL;
    p0.nholes = 0;
    tsr_tri_options o0 = {.method = TSR_TRI_DELAUNAY, .region = TSR_REGION_HULL};
    tsr_triangulation t0;
    tsr_status st = tsr_triangulate(&p0, &o0, &t0, alloc, err);
    if (st != TSR_OK)
        return st;
    b.t = &t0;
    double *v0 = NULL;
    if (t0.nt == 0) { /* all points on a line */
        for (uint32_t v = out->input_vertices; v < out->nv; v++)
            nearest_input_row(out, v, n, vals);
        goto done;
    }
    v0 = tsr_alloc(alloc, (size_t)t0.nv * n * sizeof *v0);
    if (v0)
        input_rows(in, in_vals, n, &t0, v0); /* before the crossings, which read them */
    if (!v0 || !build_adjacency(&b, alloc) || !build_start_grid(&b, alloc) || !crossing_rows(in, n, &b, v0, alloc)) {
        st = tsr_error_set(err, TSR_ERR_NOMEM, "values to interpolate: out of memory");
        goto done;
    }
    for (uint32_t v = out->input_vertices; v < out->nv; v++) {
        const double *p = &out->xy[2 * (size_t)v];
        uint32_t i = locate(&b, p);
        double l[3];
        barycentric(&b, i, p, l);
        const uint32_t *q = &t0.tri[3 * (size_t)i];
        for (uint32_t c = 0; c < n; c++) {
            /* kept within the three values: a constant stays exact, and
             * huge values do not round beyond the largest double */
            double x = v0[(size_t)q[0] * n + c], y = v0[(size_t)q[1] * n + c], z = v0[(size_t)q[2] * n + c];
            double r = l[0] * x + l[1] * y + l[2] * z, lo = fmin(x, fmin(y, z)), hi = fmax(x, fmax(y, z));
            vals[(size_t)v * n + c] = r < lo ? lo : r > hi ? hi : r;
        }
    }
done:
    tsr_free(alloc, v0);
    tsr_free(alloc, b.adj);
    tsr_free(alloc, b.start);
    tsr_triangulation_free(&t0);
    return st;
}

/* Does triangle i of t hold p (inside or on its boundary)? Exact. */
static bool holds(const tsr_triangulation *t, uint32_t i, const double p[2])
{
    for (int k = 0; k < 3; k++)
        if (tsr_orient2d(&t->xy[2 * (size_t)t->tri[3 * (size_t)i + k]],
                         &t->xy[2 * (size_t)t->tri[3 * (size_t)i + (k + 1) % 3]], p) < 0)
            return false;
    return true;
}

/* Is u-w a constrained edge? (ce: the constrained edges at each vertex) */
static bool constrained(const tsr_triangulation *t, const incid *ce, uint32_t u, uint32_t w)
{
    for (uint32_t j = ce->first[u]; j < ce->first[u + 1]; j++) {
        const uint32_t *e = &t->edge[2 * (size_t)ce->list[j]];
        if (e[0] == w || e[1] == w)
            return true;
    }
    return false;
}

tsr_status tsr_tri_regions(const tsr_triangulation *t, const double *seeds, uint32_t nseeds, uint32_t *region,
                           const tsr_allocator *alloc, tsr_error *err)
{
    for (uint32_t i = 0; i < t->nt; i++)
        region[i] = NONE;
    if (nseeds == 0 || t->nt == 0)
        return TSR_OK;
    base b;
    memset(&b, 0, sizeof b);
    b.t = t;
    incid ce = {0};
    uint32_t *stack = tsr_alloc(alloc, ((size_t)t->nt + 1) * sizeof *stack);
    tsr_status st = TSR_OK;
    if (!stack || !build_adjacency(&b, alloc) || !build_start_grid(&b, alloc) ||
        !incid_build(&ce, t->nv, t->edge, t->nedge, 2, alloc)) {
        st = tsr_error_set(err, TSR_ERR_NOMEM, "regions: out of memory");
        goto done;
    }
    for (uint32_t s = 0; s < nseeds; s++) {
        const double *p = &seeds[2 * (size_t)s];
        if (!isfinite(p[0]) || !isfinite(p[1]))
            continue;
        uint32_t i = locate(&b, p);
        if (!holds(t, i, p)) { /* the walk stops at a hole or beyond the hull: look everywhere */
            for (i = 0; i < t->nt && !holds(t, i, p); i++)
                ;
            if (i == t->nt)
                continue;
        }
        uint32_t n = 0;
        region[i] = s;
        stack[n++] = i;
        while (n) {
            uint32_t j = stack[--n];
            for (int k = 0; k < 3; k++) {
                uint32_t o = b.adj[3 * (size_t)j + k];
                if (o == NONE || region[o] == s ||
                    constrained(t, &ce, t->tri[3 * (size_t)j + k], t->tri[3 * (size_t)j + (k + 1) % 3]))
                    continue;
                region[o] = s;
                stack[n++] = o;
            }
        }
    }
done:
    tsr_free(alloc, stack);
    tsr_free(alloc, b.adj);
    tsr_free(alloc, b.start);
    incid_free(&ce, alloc);
    return st;
}
