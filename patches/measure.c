/* measure.c: tsr_ptess_measure, the independent oracle of ptess.h.
 *
 * It knows nothing of pieces' quadtrees, stitching or welding: it reads
 * the welded mesh (positions, indices), tri_source and tri_uv, and
 * compares the mesh's point at (u, v) with tsr_pmodel_eval at (u, v).
 *
 * Samples. Per source, a grid of (per_side pieces_u) x (per_side
 * pieces_v) points spread evenly over the source's (u, v) domain, ends
 * included: the same density as per_side x per_side per piece. (The
 * model does not expose the pieces' rectangles, which for a B-spline
 * follow its knots and are not equal in general, so the grid is laid
 * over the domain rather than over each piece.) Where that is more than
 * 64 samples per triangle of the source's mesh (many small pieces, as a
 * cylinder cut across its curve, each piece a tile of 2 x 2 quads), the
 * grid is thinned to 64 per triangle, and never below per_side x
 * per_side: a cut cylinder of 1,792 triangles took 922,880 samples (515
 * a triangle), 120,064 so. Plus the midpoint of
 * every triangle's every edge, in (u, v) of that triangle's source,
 * where the mesh's point is the midpoint of the edge's two welded
 * vertices: the sagitta of every edge is measured, whatever the grid.
 *
 * Locating. Per source, its triangles are bucketed in a uniform grid of
 * about one cell per triangle over its domain (each triangle in every
 * cell its (u, v) box touches); a grid sample is looked up in its cell by
 * barycentric coordinates with a tolerance of 1e-12 of the domain's size
 * (plus the rounding of its coordinates), so samples on shared edges and
 * at the domain's borders are found. Cost O(samples + triangles) for a
 * mesh of reasonably shaped triangles; a mesh whose triangles' boxes
 * would fill the buckets beyond a few dozen entries per triangle gets a
 * coarser grid instead (slower lookups, bounded memory).
 *
 * Collapsed edges. Where a piece edge collapses to one point (the
 * teapot's lid top), ptess.h welds its points into one vertex and drops
 * the triangles that then repeat a vertex; in (u, v) these leave gaps
 * along the collapsed edge. The mesh's point there is the one of the
 * dropped, degenerate triangle (p, p, c): on the mesh edge from p to c.
 * It is reconstructed from the mesh alone: a vertex seen at several
 * distinct (u, v) within one source is collapsed; across a kept
 * triangle's edge from such a corner e to a corner c, the gap triangle
 * is (e, q, c) with q the next location of the same vertex on the far
 * side of the edge (the first one met turning away from the triangle,
 * no farther than 4 edge lengths, a corner of the domain on a collapsed
 * side included), kept only when its side q-c too is a kept triangle's
 * edge or on the domain's border, so that a real hole next to a
 * collapsed edge is not papered over. These triangles are consulted only
 * for samples that no kept triangle contains. A sample in neither is
 * `uncovered` (untrimmed source: a gap of the mesh) or `trimmed_out`.
 *
 * Threads. Sources are measured independently, each into its own record
 * (largest error and where, sum of squares, counts), and the records are
 * merged in source order afterwards, so the figures are the same on any
 * number of threads. With the default allocator and enough samples the
 * sources are shared out among every core's thread (claimed a few at a
 * time, a thread's scratch made at its first claim); a caller's allocator,
 * the measurement's or the model's, keeps it on the calling thread.
 */
#include "patches/ptess.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

/* A reconstructed dropped triangle: (u, v) corners and welded vertices. */
typedef struct gap_tri {
    double uv[6];
    uint32_t v[3];
} gap_tri;

/* One distinct (u, v) location of a collapsed vertex. */
typedef struct vloc {
    uint32_t v;
    double u, w;
    int64_t qu, qw; /* (u, w) on a grid of 2^-36 of the domain: a sort key that rounding does not reorder */
} vloc;

/* What one source measured (merged in source order). */
typedef struct src_result {
    double max, sum2, uv[2];
    uint64_t samples, uncovered, trimmed_out;
} src_result;

typedef struct measurer {
    const tsr_pmodel *m;
    const tsr_ptess_result *r;
    const tsr_camera *cam;
    const tsr_allocator *alloc;
    src_result *out;     /* the current source's record */
    double *source_error; /* per source max, or NULL */
    uint32_t nsrc;

    uint32_t *src_start; /* nsrc + 1: triangles of source s are src_tris[src_start[s] .. src_start[s+1]) */
    uint32_t *src_tris;

    /* per vertex, for finding collapsed vertices source by source */
    uint32_t *stamp, *multi;
    double *uv0;

    /* per source scratch, grown as needed */
    vloc *locs;
    size_t nlocs, locs_cap;
    gap_tri *gaps;
    size_t ngaps, gaps_cap;
    uint32_t *cell_start;
    size_t cell_cap;
    uint32_t *entries;
    size_t entry_cap;

    /* samples waiting for their true points: evaluated BATCH at a time
     * (one preparation of the source), then recorded in order */
    double *buv, *bmesh, *btruth;
    uint32_t nbatch;

    /* the current source */
    uint32_t src, ntri;
    const uint32_t *tris;
    double dom[4], tol, sep;
    uint32_t gx, gy;
} measurer;

static bool grow(const tsr_allocator *a, void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return true;
    size_t n = *cap ? *cap : 64;
    while (n < need)
        n *= 2;
    if (n > SIZE_MAX / elem)
        return false;
    void *q = tsr_realloc(a, *p, n * elem);
    if (!q)
        return false;
    *p = q;
    *cap = n;
    return true;
}

static const double *tri_uv(const measurer *M, uint32_t t)
{
    return M->r->tri_uv + 6 * (size_t)t;
}

static void vertex_pos(const measurer *M, uint32_t v, double p[3])
{
    const float *f = M->r->mesh.positions + 3 * (size_t)v;
    p[0] = f[0], p[1] = f[1], p[2] = f[2];
}

/* Records one comparison. */
static void record(measurer *M, double u, double v, const double truth[3], const double mesh[3])
{
    double e;
    if (M->cam) {
        double ax, ay, ad, bx, by, bd;
        tsr_camera_project(M->cam, truth, &ax, &ay, &ad);
        tsr_camera_project(M->cam, mesh, &bx, &by, &bd);
        if (!(ad > M->cam->near_dist && bd > M->cam->near_dist))
            return;
        bool ain = ax >= 0 && ax <= M->cam->width && ay >= 0 && ay <= M->cam->height;
        bool bin = bx >= 0 && bx <= M->cam->width && by >= 0 && by <= M->cam->height;
        if (!ain && !bin)
            return;
        e = hypot(ax - bx, ay - by);
    } else {
        e = sqrt((truth[0] - mesh[0]) * (truth[0] - mesh[0]) + (truth[1] - mesh[1]) * (truth[1] - mesh[1]) +
                 (truth[2] - mesh[2]) * (truth[2] - mesh[2]));
    }
    if (!isfinite(e))
        e = INFINITY; /* a NaN position is the worst error, not an ignored one */
    src_result *o = M->out;
    o->samples++;
    o->sum2 += e * e;
    if (o->samples == 1 || e > o->max) {
        o->max = e;
        o->uv[0] = u;
        o->uv[1] = v;
    }
    if (M->source_error && e > M->source_error[M->src])
        M->source_error[M->src] = e;
}

enum { BATCH = 512 };

/* Evaluates the waiting samples and records them, in order. */
static tsr_status flush(measurer *M)
{
    if (!M->nbatch)
        return TSR_OK;
    tsr_status st = tsr_pmodel_eval_points(M->m, M->src, M->buv, M->nbatch, M->btruth);
    for (uint32_t k = 0; k < M->nbatch && st == TSR_OK; k++)
        record(M, M->buv[2 * k], M->buv[2 * k + 1], M->btruth + 3 * k, M->bmesh + 3 * k);
    M->nbatch = 0;
    return st;
}

/* A sample at (u, v) whose mesh point is mesh: queued. */
static tsr_status sample(measurer *M, double u, double v, const double mesh[3])
{
    uint32_t k = M->nbatch++;
    M->buv[2 * k] = u;
    M->buv[2 * k + 1] = v;
    memcpy(M->bmesh + 3 * k, mesh, 3 * sizeof *mesh);
    return M->nbatch == BATCH ? flush(M) : TSR_OK;
}

/* Twice the signed area of (a, b, c). */
static double orient(const double a[2], const double b[2], const double c[2])
{
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* Barycentric coordinates w of (u, v) in the triangle with corners t (6
 * doubles), either orientation; false when outside by more than tol (a
 * distance in (u, v)) or degenerate in (u, v). exact (when not NULL):
 * whether inside or on it without the tolerance. */
static bool locate_in(const double *t, double u, double v, double tol, double w[3], bool *exact)
{
    /* within tol of the triangle, so of its box: the test of the edges'
     * lines below alone would take a point far along a sliver's line */
    for (int c = 0; c < 2; c++) {
        double x = c ? v : u, lo = fmin(fmin(t[c], t[2 + c]), t[4 + c]), hi = fmax(fmax(t[c], t[2 + c]), t[4 + c]);
        if (!(x >= lo - tol && x <= hi + tol))
            return false;
    }
    double p[2] = {u, v};
    double d = orient(t, t + 2, t + 4);
    if (!(d != 0))
        return false;
    double sg = d > 0 ? 1 : -1;
    double e[3] = {sg * orient(p, t + 2, t + 4), sg * orient(p, t + 4, t), sg * orient(p, t, t + 2)};
    if (exact)
        *exact = e[0] >= 0 && e[1] >= 0 && e[2] >= 0;
    for (int k = 0; k < 3; k++) {
        const double *a = t + 2 * ((k + 1) % 3), *b = t + 2 * ((k + 2) % 3);
        if (e[k] < 0 && e[k] < -tol * sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1])))
            return false;
        if (!(e[k] >= 0))
            e[k] = 0;
    }
    double s = e[0] + e[1] + e[2];
    if (!(s > 0))
        return false;
    for (int k = 0; k < 3; k++)
        w[k] = e[k] / s;
    return true;
}

static void cell_of(const measurer *M, double u, double v, uint32_t *ci, uint32_t *cj)
{
    double fu = (u - M->dom[0]) / (M->dom[1] - M->dom[0]) * M->gx;
    double fv = (v - M->dom[2]) / (M->dom[3] - M->dom[2]) * M->gy;
    *ci = fu >= 1 ? (fu < M->gx ? (uint32_t)fu : M->gx - 1) : 0; /* NaN goes to 0 */
    *cj = fv >= 1 ? (fv < M->gy ? (uint32_t)fv : M->gy - 1) : 0;
}

static const double *entry_uv(const measurer *M, uint32_t e)
{
    return e < M->ntri ? tri_uv(M, M->tris[e]) : M->gaps[e - M->ntri].uv;
}

static void entry_box(const measurer *M, uint32_t e, uint32_t *i0, uint32_t *j0, uint32_t *i1, uint32_t *j1)
{
    const double *t = entry_uv(M, e);
    double lo[2] = {t[0], t[1]}, hi[2] = {t[0], t[1]};
    for (int k = 1; k < 3; k++)
        for (int c = 0; c < 2; c++) {
            lo[c] = t[2 * k + c] < lo[c] ? t[2 * k + c] : lo[c];
            hi[c] = t[2 * k + c] > hi[c] ? t[2 * k + c] : hi[c];
        }
    cell_of(M, lo[0] - M->tol, lo[1] - M->tol, i0, j0);
    cell_of(M, hi[0] + M->tol, hi[1] + M->tol, i1, j1);
}

/* Buckets the current source's triangles and gap triangles. */
static tsr_status build_buckets(measurer *M)
{
    size_t n = (size_t)M->ntri + M->ngaps;
    tsr_psource_info si;
    tsr_pmodel_source_info(M->m, M->src, &si);
    double aspect = si.pieces_u && si.pieces_v ? (double)si.pieces_u / si.pieces_v : 1;
    double gxd = sqrt((double)n * aspect);
    gxd = gxd < 1 ? 1 : gxd > 2048 ? 2048 : gxd;
    double gyd = (double)n / gxd;
    gyd = gyd < 1 ? 1 : gyd > 2048 ? 2048 : gyd;
    M->gx = (uint32_t)gxd;
    M->gy = (uint32_t)gyd;
    for (;;) {
        size_t cells = (size_t)M->gx * M->gy;
        if (!grow(M->alloc, (void **)&M->cell_start, &M->cell_cap, cells + 1, sizeof *M->cell_start))
            return TSR_ERR_NOMEM;
        memset(M->cell_start, 0, (cells + 1) * sizeof *M->cell_start);
        size_t total = 0;
        for (uint32_t e = 0; e < n; e++) {
            uint32_t i0, j0, i1, j1;
            entry_box(M, e, &i0, &j0, &i1, &j1);
            total += (size_t)(i1 - i0 + 1) * (j1 - j0 + 1);
        }
        if ((total > 32 * n + 65536 || total > UINT32_MAX / 2) && (M->gx > 1 || M->gy > 1)) {
            M->gx = (M->gx + 1) / 2;
            M->gy = (M->gy + 1) / 2;
            continue;
        }
        if (total > UINT32_MAX / 2)
            return TSR_ERR_NOMEM;
        if (!grow(M->alloc, (void **)&M->entries, &M->entry_cap, total ? total : 1, sizeof *M->entries))
            return TSR_ERR_NOMEM;
        for (uint32_t e = 0; e < n; e++) {
            uint32_t i0, j0, i1, j1;
            entry_box(M, e, &i0, &j0, &i1, &j1);
            for (uint32_t j = j0; j <= j1; j++)
                for (uint32_t i = i0; i <= i1; i++)
                    M->cell_start[(size_t)j * M->gx + i + 1]++;
        }
        for (size_t c = 0; c < cells; c++)
            M->cell_start[c + 1] += M->cell_start[c];
        for (uint32_t e = 0; e < n; e++) {
            uint32_t i0, j0, i1, j1;
            entry_box(M, e, &i0, &j0, &i1, &j1);
            for (uint32_t j = j0; j <= j1; j++)
                for (uint32_t i = i0; i <= i1; i++)
                    M->entries[M->cell_start[(size_t)j * M->gx + i]++] = e;
        }
        /* cell_start[c] now holds the end of cell c: shift back */
        for (size_t c = cells; c > 0; c--)
            M->cell_start[c] = M->cell_start[c - 1];
        M->cell_start[0] = 0;
        return TSR_OK;
    }
}

/* The mesh's point at (u, v) of the current source; false when no
 * triangle (kept or reconstructed) contains it. */
static bool mesh_point(const measurer *M, double u, double v, double p[3])
{
    uint32_t ci, cj;
    cell_of(M, u, v, &ci, &cj);
    size_t c = (size_t)cj * M->gx + ci;
    const uint32_t *ix = M->r->mesh.indices;
    uint32_t gap = UINT32_MAX, near = UINT32_MAX;
    double w[3], nw[3] = {0}, gw[3] = {0};
    /* a triangle holding (u, v) exactly, else the first within the
     * tolerance (a sliver's lines pass near points far from it) */
    for (uint32_t k = M->cell_start[c]; k < M->cell_start[c + 1]; k++) {
        uint32_t e = M->entries[k];
        if (e >= M->ntri) {
            if (gap == UINT32_MAX && locate_in(entry_uv(M, e), u, v, M->tol, gw, NULL))
                gap = e - M->ntri;
            continue;
        }
        bool exact;
        if (!locate_in(entry_uv(M, e), u, v, M->tol, w, &exact))
            continue;
        if (exact || near == UINT32_MAX) {
            near = e;
            memcpy(nw, w, sizeof nw);
        }
        if (exact)
            break;
    }
    if (near != UINT32_MAX) {
        uint32_t t = M->tris[near];
        p[0] = p[1] = p[2] = 0;
        for (int q = 0; q < 3; q++) {
            double x[3];
            vertex_pos(M, ix[3 * (size_t)t + q], x);
            for (int d = 0; d < 3; d++)
                p[d] += nw[q] * x[d];
        }
        return true;
    }
    if (gap == UINT32_MAX)
        return false;
    p[0] = p[1] = p[2] = 0;
    for (int q = 0; q < 3; q++) {
        double x[3];
        vertex_pos(M, M->gaps[gap].v[q], x);
        for (int d = 0; d < 3; d++)
            p[d] += gw[q] * x[d];
    }
    return true;
}

static vloc make_loc(const measurer *M, uint32_t v, double u, double w)
{
    double fu = (u - M->dom[0]) / (M->dom[1] - M->dom[0]), fw = (w - M->dom[2]) / (M->dom[3] - M->dom[2]);
    fu = fu > -4 && fu < 4 ? fu : 0; /* NaN and wild values: any key */
    fw = fw > -4 && fw < 4 ? fw : 0;
    return (vloc){v, u, w, (int64_t)llround(fu * 68719476736.0), (int64_t)llround(fw * 68719476736.0)};
}

static int cmp_loc(const void *pa, const void *pb)
{
    const vloc *a = pa, *b = pb;
    if (a->v != b->v)
        return a->v < b->v ? -1 : 1;
    if (a->qu != b->qu)
        return a->qu < b->qu ? -1 : 1;
    return a->qw < b->qw ? -1 : a->qw > b->qw;
}

/* Index in locs of the first location of vertex v (nlocs if none). */
static size_t first_loc(const measurer *M, uint32_t v)
{
    size_t lo = 0, hi = M->nlocs;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (M->locs[mid].v < v)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* Finds the collapsed vertices of the current source (seen at more than
 * one (u, v)) and reconstructs the triangles dropped along them. */
static tsr_status find_gaps(measurer *M)
{
    const uint32_t *ix = M->r->mesh.indices;
    uint32_t tag = M->src + 1;
    bool any = false;
    for (uint32_t k = 0; k < M->ntri; k++) {
        const uint32_t t = M->tris[k];
        const double *uv = tri_uv(M, t);
        for (int q = 0; q < 3; q++) {
            uint32_t v = ix[3 * (size_t)t + q];
            if (M->stamp[v] != tag) {
                M->stamp[v] = tag;
                M->uv0[2 * (size_t)v] = uv[2 * q];
                M->uv0[2 * (size_t)v + 1] = uv[2 * q + 1];
            } else if (fabs(M->uv0[2 * (size_t)v] - uv[2 * q]) > M->sep ||
                       fabs(M->uv0[2 * (size_t)v + 1] - uv[2 * q + 1]) > M->sep) {
                M->multi[v] = tag;
                any = true;
            }
        }
    }
    M->nlocs = 0;
    M->ngaps = 0;
    if (!any)
        return TSR_OK;
    for (uint32_t k = 0; k < M->ntri; k++) {
        const uint32_t t = M->tris[k];
        const double *uv = tri_uv(M, t);
        for (int q = 0; q < 3; q++) {
            uint32_t v = ix[3 * (size_t)t + q];
            if (M->multi[v] != tag)
                continue;
            if (!grow(M->alloc, (void **)&M->locs, &M->locs_cap, M->nlocs + 1, sizeof *M->locs))
                return TSR_ERR_NOMEM;
            M->locs[M->nlocs++] = make_loc(M, v, uv[2 * q], uv[2 * q + 1]);
        }
    }
    qsort(M->locs, M->nlocs, sizeof *M->locs, cmp_loc);
    size_t n = 0;
    for (size_t k = 0; k < M->nlocs; k++)
        if (n == 0 || M->locs[k].v != M->locs[n - 1].v || fabs(M->locs[k].u - M->locs[n - 1].u) > M->sep ||
            fabs(M->locs[k].w - M->locs[n - 1].w) > M->sep)
            M->locs[n++] = M->locs[k];
    M->nlocs = n;

    for (uint32_t k = 0; k < M->ntri; k++) {
        const uint32_t t = M->tris[k];
        const double *uv = tri_uv(M, t);
        for (int ed = 0; ed < 3; ed++) {
            int ca = ed, cb = (ed + 1) % 3, cc = (ed + 2) % 3;
            for (int side = 0; side < 2; side++) {
                int ce = side ? cb : ca, co = side ? ca : cb; /* collapsed end, other end */
                uint32_t ve = ix[3 * (size_t)t + ce], vo = ix[3 * (size_t)t + co];
                if (M->multi[ve] != tag || ve == vo)
                    continue;
                const double *e = uv + 2 * ce, *o = uv + 2 * co, *third = uv + 2 * cc;
                double len = sqrt((o[0] - e[0]) * (o[0] - e[0]) + (o[1] - e[1]) * (o[1] - e[1]));
                double s_third = orient(e, o, third);
                if (!(len > 0) || s_third == 0)
                    continue;
                /* the location of ve here, then its neighbours in sorted
                 * order (along the collapsed edge, an axis-aligned border) */
                size_t lo = first_loc(M, ve), hi = lo;
                while (hi < M->nlocs && M->locs[hi].v == ve)
                    hi++;
                size_t at = lo;
                {
                    size_t a = lo, b = hi; /* first location >= e in (u, w) order */
                    vloc key = make_loc(M, ve, e[0], e[1]);
                    while (a < b) {
                        size_t mid = a + (b - a) / 2;
                        if (cmp_loc(&M->locs[mid], &key) < 0)
                            a = mid + 1;
                        else
                            b = mid;
                    }
                    double best_d = INFINITY;
                    for (size_t z = a > lo ? a - 1 : a; z < hi && z <= a + 1; z++) {
                        double dz = fabs(M->locs[z].u - e[0]) + fabs(M->locs[z].w - e[1]);
                        if (dz < best_d)
                            best_d = dz, at = z;
                    }
                }
                /* candidates: up to 3 locations either way, and the
                 * corners ending a border side of the domain that holds e
                 * and another location of ve (a collapsed side: its
                 * corner need not be any kept triangle's corner); the
                 * one on the far side of the edge at the smallest angle
                 * from it */
                double cand[11][2];
                int nc = 0;
                size_t q0 = at >= lo + 3 ? at - 3 : lo, q1 = at + 4 < hi ? at + 4 : hi;
                for (size_t q = q0; q < q1; q++) {
                    cand[nc][0] = M->locs[q].u;
                    cand[nc++][1] = M->locs[q].w;
                }
                for (int side = 0; side < 4; side++) {
                    int c = side < 2 ? 0 : 1; /* the coordinate fixed on that side */
                    double at_side = M->dom[side];
                    if (fabs(e[c] - at_side) > M->sep)
                        continue;
                    bool other = false;
                    for (int k = 0; k < nc; k++)
                        other |= fabs(cand[k][c] - at_side) <= M->sep && fabs(cand[k][1 - c] - e[1 - c]) > M->sep;
                    if (!other)
                        continue;
                    for (int end = 0; end < 2; end++) {
                        cand[nc][c] = at_side;
                        cand[nc++][1 - c] = M->dom[2 * (1 - c) + end];
                    }
                }
                double dx = (o[0] - e[0]) / len, dy = (o[1] - e[1]) / len;
                double best_cos = -2, best_ql = INFINITY;
                int best = -1;
                for (int k = 0; k < nc; k++) {
                    double qx = cand[k][0] - e[0], qy = cand[k][1] - e[1], ql = sqrt(qx * qx + qy * qy);
                    if (!(ql > M->sep) || ql > 4 * len)
                        continue;
                    double s_q = orient(e, o, cand[k]);
                    if (!(s_q * s_third < 0) || fabs(s_q) <= M->tol * len)
                        continue;
                    /* of candidates in one direction (collinear along the
                     * collapsed side: equal angles up to rounding), the
                     * nearest */
                    double cosang = (qx * dx + qy * dy) / ql;
                    if (cosang > best_cos + 1e-9 || (cosang >= best_cos - 1e-9 && ql < best_ql))
                        best_cos = cosang, best_ql = ql, best = k;
                }
                if (best < 0)
                    continue;
                if (!grow(M->alloc, (void **)&M->gaps, &M->gaps_cap, M->ngaps + 1, sizeof *M->gaps))
                    return TSR_ERR_NOMEM;
                gap_tri *g = &M->gaps[M->ngaps++];
                g->uv[0] = e[0], g->uv[1] = e[1];
                g->uv[2] = cand[best][0], g->uv[3] = cand[best][1];
                g->uv[4] = o[0], g->uv[5] = o[1];
                g->v[0] = g->v[1] = ve;
                g->v[2] = vo;
            }
        }
    }
    return TSR_OK;
}

static bool near_uv(const measurer *M, const double *a, const double *b)
{
    return fabs(a[0] - b[0]) <= M->sep && fabs(a[1] - b[1]) <= M->sep;
}

/* Whether some kept triangle of the current source (bucketed) has the
 * edge a-b in (u, v). */
static bool kept_edge(const measurer *M, const double a[2], const double b[2])
{
    uint32_t ci, cj;
    cell_of(M, 0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), &ci, &cj);
    size_t c = (size_t)cj * M->gx + ci;
    for (uint32_t k = M->cell_start[c]; k < M->cell_start[c + 1]; k++) {
        const double *t = entry_uv(M, M->entries[k]);
        for (int q = 0; q < 3; q++) {
            const double *p0 = t + 2 * q, *p1 = t + 2 * ((q + 1) % 3);
            if ((near_uv(M, p0, a) && near_uv(M, p1, b)) || (near_uv(M, p0, b) && near_uv(M, p1, a)))
                return true;
        }
    }
    return false;
}

/* A reconstructed gap triangle (e, q, o) is kept when its side q-o, like
 * e-o, is the edge of a kept triangle or lies on the domain's border: a
 * dropped triangle is enclosed by its neighbours, whereas a "gap" reaching
 * past a missing triangle (a hole of the mesh next to a collapsed edge)
 * is not, and must stay uncovered. */
static bool keep_gap(const measurer *M, const gap_tri *g)
{
    const double *q = g->uv + 2, *o = g->uv + 4;
    for (int side = 0; side < 4; side++) {
        int c = side < 2 ? 0 : 1;
        if (fabs(q[c] - M->dom[side]) <= M->sep && fabs(o[c] - M->dom[side]) <= M->sep)
            return true;
    }
    return kept_edge(M, q, o);
}

/* The most grid samples a source takes per triangle of its mesh, beyond
 * per_side x per_side (Samples, above). */
#define SAMPLES_PER_TRIANGLE 64u

static tsr_status measure_source(measurer *M, uint32_t per_side)
{
    tsr_psource_info si;
    if (!tsr_pmodel_source_info(M->m, M->src, &si))
        return TSR_ERR_ARGUMENT;
    memcpy(M->dom, si.domain, sizeof M->dom);
    if (!(M->dom[1] > M->dom[0]) || !(M->dom[3] > M->dom[2]))
        return TSR_ERR_ARGUMENT;
    double size = (M->dom[1] - M->dom[0]) + (M->dom[3] - M->dom[2]);
    double mag = fmax(fmax(fabs(M->dom[0]), fabs(M->dom[1])), fmax(fabs(M->dom[2]), fabs(M->dom[3])));
    M->tol = 1e-12 * size + 16 * DBL_EPSILON * mag;
    M->sep = 1e-9 * size + 16 * DBL_EPSILON * mag;
    M->tris = M->src_tris + M->src_start[M->src];
    M->ntri = M->src_start[M->src + 1] - M->src_start[M->src];

    tsr_status st = find_gaps(M);
    if (st == TSR_OK && M->ngaps) {
        /* keep the gap triangles closed by kept edges (see keep_gap) */
        size_t n = M->ngaps, kept = 0;
        M->ngaps = 0;
        st = build_buckets(M);
        for (size_t k = 0; k < n && st == TSR_OK; k++)
            if (keep_gap(M, &M->gaps[k]))
                M->gaps[kept++] = M->gaps[k];
        M->ngaps = kept;
    }
    if (st == TSR_OK)
        st = build_buckets(M);
    if (st != TSR_OK)
        return st;

    uint64_t nu = (uint64_t)per_side * (si.pieces_u ? si.pieces_u : 1);
    uint64_t nv = (uint64_t)per_side * (si.pieces_v ? si.pieces_v : 1);
    if (nu * nv > SAMPLES_PER_TRIANGLE * (uint64_t)M->ntri) {
        /* many pieces, few triangles each: the grid thinned to
         * SAMPLES_PER_TRIANGLE samples per triangle, per_side a side at
         * least */
        uint64_t cap = SAMPLES_PER_TRIANGLE * (uint64_t)M->ntri;
        double f = sqrt((double)cap / ((double)nu * (double)nv));
        uint64_t tu = (uint64_t)ceil((double)nu * f), tv = (uint64_t)ceil((double)nv * f);
        if (tv < per_side) /* (a side at the floor: the other takes the rest) */
            tv = per_side, tu = (cap + per_side - 1) / per_side;
        else if (tu < per_side)
            tu = per_side, tv = (cap + per_side - 1) / per_side;
        nu = tu > per_side ? tu : per_side;
        nv = tv > per_side ? tv : per_side;
    }
    for (uint64_t j = 0; j < nv; j++) {
        double v = j + 1 == nv ? M->dom[3] : M->dom[2] + (M->dom[3] - M->dom[2]) * ((double)j / (double)(nv - 1));
        for (uint64_t i = 0; i < nu; i++) {
            double u = i + 1 == nu ? M->dom[1] : M->dom[0] + (M->dom[1] - M->dom[0]) * ((double)i / (double)(nu - 1));
            double mesh[3];
            if (!mesh_point(M, u, v, mesh)) {
                if (si.trimmed)
                    M->out->trimmed_out++;
                else
                    M->out->uncovered++;
                continue;
            }
            if ((st = sample(M, u, v, mesh)) != TSR_OK)
                return st;
        }
    }

    /* the midpoint of every edge, on its own triangle */
    const uint32_t *ix = M->r->mesh.indices;
    for (uint32_t k = 0; k < M->ntri; k++) {
        uint32_t t = M->tris[k];
        const double *uv = tri_uv(M, t);
        for (int q = 0; q < 3; q++) {
            int q2 = (q + 1) % 3;
            double u = 0.5 * (uv[2 * q] + uv[2 * q2]), v = 0.5 * (uv[2 * q + 1] + uv[2 * q2 + 1]);
            double a[3], b[3], mesh[3];
            vertex_pos(M, ix[3 * (size_t)t + q], a);
            vertex_pos(M, ix[3 * (size_t)t + q2], b);
            for (int d = 0; d < 3; d++)
                mesh[d] = 0.5 * (a[d] + b[d]);
            if ((st = sample(M, u, v, mesh)) != TSR_OK)
                return st;
        }
    }
    return flush(M);
}

enum { MAX_THREADS = 64, CLAIM = 8 /* sources a thread takes at a time */ };

/* What the threads share: the prototype measurer (model, mesh, sources'
 * triangles), the per-source records, the next source to claim and the
 * first failure. */
typedef struct mshare {
    const measurer *proto;
    uint32_t per_side;
    src_result *res;
    uint32_t next, done;
    tsr_status st;
    void (*progress)(void *, double);
    void *user;
} mshare;

typedef struct mworker {
    mshare *sh;
    bool caller; /* the calling thread: the one that reports progress */
} mworker;

static void measurer_free(measurer *M)
{
    tsr_free(M->alloc, M->stamp);
    tsr_free(M->alloc, M->multi);
    tsr_free(M->alloc, M->uv0);
    tsr_free(M->alloc, M->locs);
    tsr_free(M->alloc, M->gaps);
    tsr_free(M->alloc, M->cell_start);
    tsr_free(M->alloc, M->entries);
    tsr_free(M->alloc, M->buv);
    tsr_free(M->alloc, M->bmesh);
    tsr_free(M->alloc, M->btruth);
}

/* One thread: its own scratch, sources claimed until none is left or one
 * fails. */
static void *measure_worker(void *arg)
{
    const mworker *w = arg;
    mshare *sh = w->sh;
    measurer M = *sh->proto;
    uint32_t nvert = M.r->mesh.vertex_count;
    size_t nv = nvert ? nvert : 1;
    tsr_status st = TSR_OK;
    while (st == TSR_OK && __atomic_load_n(&sh->st, __ATOMIC_ACQUIRE) == TSR_OK) {
        uint32_t s0 = __atomic_fetch_add(&sh->next, CLAIM, __ATOMIC_RELAXED);
        if (s0 >= M.nsrc)
            break;
        if (!M.stamp) { /* the first claim: this thread's scratch */
            M.stamp = tsr_alloc(M.alloc, nv * sizeof *M.stamp);
            M.multi = tsr_alloc(M.alloc, nv * sizeof *M.multi);
            M.uv0 = tsr_alloc(M.alloc, 2 * nv * sizeof *M.uv0);
            M.buv = tsr_alloc(M.alloc, 2 * BATCH * sizeof *M.buv);
            M.bmesh = tsr_alloc(M.alloc, 3 * BATCH * sizeof *M.bmesh);
            M.btruth = tsr_alloc(M.alloc, 3 * BATCH * sizeof *M.btruth);
            M.nbatch = 0;
            if (!M.stamp || !M.multi || !M.uv0 || !M.buv || !M.bmesh || !M.btruth) {
                st = TSR_ERR_NOMEM;
                break;
            }
            memset(M.stamp, 0, nv * sizeof *M.stamp);
            memset(M.multi, 0, nv * sizeof *M.multi);
        }
        uint32_t s = s0;
        for (; s < s0 + CLAIM && s < M.nsrc && st == TSR_OK; s++) {
            M.src = s;
            M.out = &sh->res[s];
            st = measure_source(&M, sh->per_side);
        }
        uint32_t done = __atomic_add_fetch(&sh->done, s - s0, __ATOMIC_RELAXED);
        if (w->caller && sh->progress)
            sh->progress(sh->user, (double)done / M.nsrc);
    }
    if (st != TSR_OK) {
        tsr_status ok = TSR_OK;
        __atomic_compare_exchange_n(&sh->st, &ok, st, false, __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE);
    }
    measurer_free(&M);
    return NULL;
}

tsr_status tsr_ptess_measure(const tsr_pmodel *m, const tsr_ptess_result *r, uint32_t per_side,
                             const tsr_camera *camera, bool per_source_error, const tsr_allocator *alloc,
                             tsr_ptess_measure_result *out)
{
    return tsr_ptess_measure_progress(m, r, per_side, camera, per_source_error, alloc, NULL, NULL, out);
}

tsr_status tsr_ptess_measure_progress(const tsr_pmodel *m, const tsr_ptess_result *r, uint32_t per_side,
                                      const tsr_camera *camera, bool per_source_error, const tsr_allocator *alloc,
                                      void (*progress)(void *user, double fraction), void *user,
                                      tsr_ptess_measure_result *out)
{
    if (!out)
        return TSR_ERR_ARGUMENT;
    memset(out, 0, sizeof *out);
    out->worst_source = UINT32_MAX;
    if (!m || !r || per_side < 2)
        return TSR_ERR_ARGUMENT;
    const tsr_mesh *mesh = &r->mesh;
    uint32_t ntri = mesh->triangle_count, nvert = mesh->vertex_count;
    if (ntri && (!mesh->indices || !mesh->positions || !r->tri_source || !r->tri_uv))
        return TSR_ERR_ARGUMENT;
    tsr_pmodel_info info;
    tsr_pmodel_get_info(m, &info);
    for (size_t k = 0; k < 3 * (size_t)ntri; k++)
        if (mesh->indices[k] >= nvert)
            return TSR_ERR_ARGUMENT;
    for (uint32_t t = 0; t < ntri; t++)
        if (r->tri_source[t] >= info.sources)
            return TSR_ERR_ARGUMENT;

    measurer M = {0};
    M.m = m;
    M.r = r;
    M.cam = camera;
    M.alloc = alloc;
    M.nsrc = info.sources;
    tsr_status st = TSR_OK;
    src_result *res = NULL;
    if (per_source_error && info.sources) {
        out->source_error = tsr_alloc(alloc, info.sources * sizeof *out->source_error);
        if (!out->source_error)
            return TSR_ERR_NOMEM;
        for (uint32_t s = 0; s < info.sources; s++)
            out->source_error[s] = 0;
    }
    M.source_error = out->source_error;
    M.src_start = tsr_alloc(alloc, ((size_t)info.sources + 1) * sizeof *M.src_start);
    M.src_tris = tsr_alloc(alloc, (ntri ? ntri : 1) * sizeof *M.src_tris);
    res = tsr_alloc(alloc, ((size_t)info.sources + 1) * sizeof *res);
    if (!M.src_start || !M.src_tris || !res) {
        st = TSR_ERR_NOMEM;
        goto done;
    }
    memset(res, 0, ((size_t)info.sources + 1) * sizeof *res);
    /* triangles grouped by source (counting sort) */
    memset(M.src_start, 0, ((size_t)info.sources + 1) * sizeof *M.src_start);
    for (uint32_t t = 0; t < ntri; t++)
        M.src_start[r->tri_source[t] + 1]++;
    for (uint32_t s = 0; s < info.sources; s++)
        M.src_start[s + 1] += M.src_start[s];
    for (uint32_t t = 0; t < ntri; t++)
        M.src_tris[M.src_start[r->tri_source[t]]++] = t;
    for (uint32_t s = info.sources; s > 0; s--)
        M.src_start[s] = M.src_start[s - 1];
    M.src_start[0] = 0;

    /* about how many samples: threads where that is worth their start */
    uint64_t work = 3 * (uint64_t)ntri + (uint64_t)info.pieces * per_side * per_side;
    long ncpu = alloc || info.own_alloc || work < ((uint64_t)1 << 17) ? 1 : (long)tsr_cpu_count();
    uint32_t claims = (info.sources + CLAIM - 1) / CLAIM; /* no more threads than claims */
    uint32_t nthreads = ncpu < 1 ? 1 : ncpu > MAX_THREADS ? MAX_THREADS : (uint32_t)ncpu;
    nthreads = nthreads > claims ? (claims ? claims : 1) : nthreads;
    mshare sh = {&M, per_side, res, 0, 0, TSR_OK, progress, user};
    mworker helper = {&sh, false}, caller = {&sh, true};
    pthread_t th[MAX_THREADS];
    uint32_t started = 0;
    for (uint32_t k = 1; k < nthreads; k++)
        if (pthread_create(&th[started], NULL, measure_worker, &helper) == 0)
            started++;
    measure_worker(&caller);
    for (uint32_t k = 0; k < started; k++)
        pthread_join(th[k], NULL);
    st = __atomic_load_n(&sh.st, __ATOMIC_ACQUIRE);
    if (st == TSR_OK && progress)
        progress(user, 1); /* (the last sources may have been another thread's) */

    /* merged in source order, whatever the threads */
    double sum2 = 0;
    for (uint32_t s = 0; s < info.sources && st == TSR_OK; s++) {
        const src_result *q = &res[s];
        if (q->samples && (!out->samples || q->max > out->max_error)) {
            out->max_error = q->max;
            out->worst_source = s;
            out->worst_uv[0] = q->uv[0];
            out->worst_uv[1] = q->uv[1];
        }
        out->samples += q->samples;
        out->uncovered += q->uncovered;
        out->trimmed_out += q->trimmed_out;
        sum2 += q->sum2;
    }
    if (st == TSR_OK && out->samples)
        out->rms_error = sqrt(sum2 / (double)out->samples);

done:
    tsr_free(alloc, M.src_start);
    tsr_free(alloc, M.src_tris);
    tsr_free(alloc, res);
    if (st != TSR_OK) {
        tsr_free(alloc, out->source_error);
        double *none = NULL;
        memset(out, 0, sizeof *out);
        out->source_error = none;
        out->worst_source = UINT32_MAX;
    }
    return st;
}
