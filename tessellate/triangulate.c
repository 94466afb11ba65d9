/* triangulate.c: tsr_triangulate, the driver of both methods.
 *
 * Delaunay method: the points go into the kernel (cdt.c) in BRIO order,
 * then the segments in input order (segment recovery by cavity
 * retriangulation, crossings split), then the region is chosen by a
 * flood fill over the constrained edges, then conforming or quality
 * refinement (refine.c) runs on the kept triangles only.
 *
 * Region selection (both methods): a 0-1 breadth-first search from the
 * outside gives each triangle the least number of constrained edges
 * crossed to reach it; HULL keeps every finite triangle, ENCLOSED those
 * at depth >= 1, EVEN_ODD those at odd depth (for closed loops the parity
 * does not depend on the path, so the least depth gives the even-odd
 * rule; an edge covered by an even number of input segments, such as a
 * ring given twice or a spike that doubles back, is not counted). Hole seeds then remove the triangles reachable from
 * them without crossing a constrained edge, like Triangle's holes. The
 * quadtree method makes the same choice from its cells where it can
 * (qtri.c), and comes here only otherwise. */
#include "tessellate/cdt_internal.h"
#include "tessellate/triangulate_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NONE UINT32_MAX

void tsr_triangulation_free(tsr_triangulation *t)
{
    const tsr_allocator *a = t->alloc.realloc ? &t->alloc : NULL;
    tsr_free(a, t->xy);
    tsr_free(a, t->tri);
    tsr_free(a, t->edge);
    tsr_free(a, t->edge_segment);
    tsr_free(a, t->vertex_of_input);
    memset(t, 0, sizeof *t);
}

/* ---- region ---------------------------------------------------------- */

/* Does crossing an edge with mark m count as crossing a segment? Under
 * the even-odd rule an edge covered by an even number of segments does
 * not. */
static bool counts(uint32_t m, tsr_region region)
{
    return m && !(region == TSR_REGION_EVEN_ODD && (m & CDT_EVEN));
}

/* keep[t] for nt triangles with neighbours tn (NONE: none) and marks tc
 * (0: unconstrained); ghost[t] (may be NULL) marks outside triangles;
 * seeds are triangle indices (NONE entries ignored). */
static bool region_keep(const tsr_allocator *a, uint32_t nt, const uint32_t *tn, const uint32_t *tc,
                        const uint8_t *ghost, tsr_region region, const uint32_t *seeds, uint32_t nseeds, uint8_t *keep)
{
    uint32_t *depth = tsr_alloc(a, ((size_t)nt + 1) * sizeof *depth);
    uint32_t *cur = tsr_alloc(a, ((size_t)nt + 1) * sizeof *cur);
    uint32_t *next = tsr_alloc(a, (3 * (size_t)nt + 1) * sizeof *next);
    if (!depth || !cur || !next) {
        tsr_free(a, depth);
        tsr_free(a, cur);
        tsr_free(a, next);
        return false;
    }
    uint32_t ncur = 0, nnext = 0;
    for (uint32_t t = 0; t < nt; t++) {
        depth[t] = NONE;
        if (ghost && ghost[t]) {
            depth[t] = 0;
            cur[ncur++] = t;
            continue;
        }
        for (int k = 0; k < 3; k++)
            if (tn[3 * (size_t)t + k] == NONE) {
                if (!counts(tc[3 * (size_t)t + k], region)) {
                    if (depth[t] != 0)
                        cur[ncur++] = t;
                    depth[t] = 0;
                } else
                    next[nnext++] = t;
            }
    }
    /* layer by layer: flood within a layer across unconstrained edges,
     * collect the next layer across constrained ones */
    for (uint32_t level = 0; ncur > 0 || nnext > 0; level++) {
        uint32_t top = ncur;
        while (top > 0) {
            uint32_t t = cur[--top];
            for (int k = 0; k < 3; k++) {
                uint32_t n = tn[3 * (size_t)t + k];
                if (n == NONE || depth[n] != NONE)
                    continue;
                if (counts(tc[3 * (size_t)t + k], region)) {
                    if (nnext < 3 * nt)
                        next[nnext++] = n;
                } else {
                    depth[n] = level;
                    cur[top++] = n;
                }
            }
        }
        ncur = 0;
        for (uint32_t i = 0; i < nnext; i++)
            if (depth[next[i]] == NONE) {
                depth[next[i]] = level + 1;
                cur[ncur++] = next[i];
            }
        nnext = 0;
    }
    for (uint32_t t = 0; t < nt; t++) {
        bool outside = ghost && ghost[t];
        uint32_t dd = depth[t];
        keep[t] = !outside && (region == TSR_REGION_HULL       ? true
                               : region == TSR_REGION_ENCLOSED ? dd != NONE && dd >= 1
                                                               : dd != NONE && dd % 2 == 1);
    }
    /* hole seeds */
    uint32_t top = 0;
    for (uint32_t i = 0; i < nseeds; i++)
        if (seeds[i] != NONE && keep[seeds[i]]) {
            keep[seeds[i]] = 0;
            cur[top++] = seeds[i];
        }
    while (top > 0) {
        uint32_t t = cur[--top];
        for (int k = 0; k < 3; k++) {
            uint32_t n = tn[3 * (size_t)t + k];
            if (n != NONE && keep[n] && !tc[3 * (size_t)t + k]) {
                keep[n] = 0;
                cur[top++] = n;
            }
        }
    }
    tsr_free(a, depth);
    tsr_free(a, cur);
    tsr_free(a, next);
    return true;
}

/* Drops Steiner vertices no triangle uses, renumbering the rest. */
static tsr_status compact_vertices(tsr_triangulation *t)
{
    const tsr_allocator *a = t->alloc.realloc ? &t->alloc : NULL;
    uint32_t *map = tsr_alloc(a, ((size_t)t->nv + 1) * sizeof *map);
    if (!map)
        return TSR_ERR_NOMEM;
    for (uint32_t v = 0; v < t->nv; v++)
        map[v] = v < t->input_vertices ? v : NONE;
    for (size_t i = 0; i < 3 * (size_t)t->nt; i++)
        map[t->tri[i]] = t->tri[i];
    uint32_t n = 0;
    for (uint32_t v = 0; v < t->nv; v++)
        if (map[v] != NONE) {
            t->xy[2 * (size_t)n] = t->xy[2 * (size_t)v];
            t->xy[2 * (size_t)n + 1] = t->xy[2 * (size_t)v + 1];
            map[v] = n++;
        }
    for (size_t i = 0; i < 3 * (size_t)t->nt; i++)
        t->tri[i] = map[t->tri[i]];
    uint32_t ne = 0;
    for (uint32_t e = 0; e < t->nedge; e++) {
        uint32_t u = map[t->edge[2 * (size_t)e]], w = map[t->edge[2 * (size_t)e + 1]];
        if (u == NONE || w == NONE)
            continue;
        t->edge[2 * (size_t)ne] = u;
        t->edge[2 * (size_t)ne + 1] = w;
        t->edge_segment[ne++] = t->edge_segment[e];
    }
    t->nedge = ne;
    t->nv = n;
    t->steiner = n - t->input_vertices;
    tsr_free(a, map);
    return TSR_OK;
}

typedef struct erec {
    uint64_t key;
    uint32_t t;
    uint32_t k;
} erec;

static int erec_cmp(const void *a, const void *b)
{
    const erec *x = a, *y = b;
    return x->key < y->key ? -1 : x->key > y->key;
}

static bool in_triangle(const double *xy, const uint32_t *v, const double p[2])
{
    for (int k = 0; k < 3; k++)
        if (tsr_orient2d(xy + 2 * (size_t)v[k], xy + 2 * (size_t)v[(k + 1) % 3], p) < 0)
            return false;
    return true;
}

tsr_status tsr__tri_apply_region(tsr_triangulation *t, const tsr_pslg *in, const tsr_tri_options *opt)
{
    const tsr_allocator *a = t->alloc.realloc ? &t->alloc : NULL;
    uint32_t nt = t->nt;
    if (nt == 0)
        return TSR_OK;
    if (opt->region == TSR_REGION_HULL && in->nholes == 0)
        return compact_vertices(t);
    size_t m = 3 * (size_t)nt;
    erec *r = tsr_alloc(a, (m + t->nedge + 1) * sizeof *r);
    uint32_t *tn = tsr_alloc(a, m * sizeof *tn), *tc = tsr_alloc(a, m * sizeof *tc);
    uint32_t *seeds = tsr_alloc(a, ((size_t)in->nholes + 1) * sizeof *seeds);
    uint8_t *keep = tsr_alloc(a, nt);
    tsr_status st = TSR_ERR_NOMEM;
    if (!r || !tn || !tc || !seeds || !keep)
        goto done;
    /* neighbours and marks by sorting the edges; constrained edges enter the
     * sort with t = NONE */
    for (uint32_t i = 0; i < nt; i++)
        for (uint32_t k = 0; k < 3; k++) {
            const uint32_t *v = t->tri + 3 * (size_t)i;
            r[3 * (size_t)i + k] = (erec){cdt_edge_key(v[k], v[(k + 1) % 3]), i, k};
            tn[3 * (size_t)i + k] = NONE;
            tc[3 * (size_t)i + k] = 0;
        }
    for (uint32_t e = 0; e < t->nedge; e++)
        r[m + e] = (erec){cdt_edge_key(t->edge[2 * (size_t)e], t->edge[2 * (size_t)e + 1]), NONE, 0};
    qsort(r, m + t->nedge, sizeof *r, erec_cmp);
    for (size_t i = 0; i < m + t->nedge;) {
        size_t j = i;
        uint32_t covered = 0; /* segments covering the edge: the even-odd rule needs the parity */
        while (j < m + t->nedge && r[j].key == r[i].key)
            covered += r[j++].t == NONE;
        uint32_t constrained = covered == 0 ? 0 : covered % 2 ? 1 : 1 | CDT_EVEN;
        uint32_t tri[2], kk[2], n = 0;
        for (size_t q = i; q < j; q++)
            if (r[q].t != NONE && n < 2) {
                tri[n] = r[q].t;
                kk[n++] = r[q].k;
            }
        for (uint32_t q = 0; q < n; q++) {
            tc[3 * (size_t)tri[q] + kk[q]] = constrained;
            if (n == 2)
                tn[3 * (size_t)tri[q] + kk[q]] = tri[1 - q];
        }
        i = j;
    }
    for (uint32_t h = 0; h < in->nholes; h++) {
        seeds[h] = NONE;
        for (uint32_t i = 0; i < nt && seeds[h] == NONE; i++)
            if (in_triangle(t->xy, t->tri + 3 * (size_t)i, in->holes + 2 * (size_t)h))
                seeds[h] = i;
    }
    if (!region_keep(a, nt, tn, tc, NULL, opt->region, seeds, in->nholes, keep))
        goto done;
    uint32_t n = 0;
    for (uint32_t i = 0; i < nt; i++)
        if (keep[i]) {
            memmove(t->tri + 3 * (size_t)n, t->tri + 3 * (size_t)i, 3 * sizeof *t->tri);
            n++;
        }
    t->nt = n;
    /* constrained edges that still border a kept triangle */
    {
        /* edges of kept triangles, sorted, to test membership */
        erec *kept = r;
        size_t nk = 3 * (size_t)n;
        for (uint32_t i = 0; i < n; i++)
            for (uint32_t k = 0; k < 3; k++) {
                const uint32_t *v = t->tri + 3 * (size_t)i;
                kept[3 * (size_t)i + k] = (erec){cdt_edge_key(v[k], v[(k + 1) % 3]), i, k};
            }
        qsort(kept, nk, sizeof *kept, erec_cmp);
        uint32_t ne = 0;
        for (uint32_t e = 0; e < t->nedge; e++) {
            erec key = {cdt_edge_key(t->edge[2 * (size_t)e], t->edge[2 * (size_t)e + 1]), 0, 0};
            if (!bsearch(&key, kept, nk, sizeof *kept, erec_cmp))
                continue;
            /* an edge listed once per covering segment: keep the lowest id */
            bool dup = false;
            for (uint32_t q = ne; q-- > 0 && !dup && ne - q <= 8;)
                dup = cdt_edge_key(t->edge[2 * (size_t)q], t->edge[2 * (size_t)q + 1]) == key.key;
            if (dup)
                continue;
            t->edge[2 * (size_t)ne] = t->edge[2 * (size_t)e];
            t->edge[2 * (size_t)ne + 1] = t->edge[2 * (size_t)e + 1];
            t->edge_segment[ne++] = t->edge_segment[e];
        }
        t->nedge = ne;
    }
    st = compact_vertices(t);
done:
    tsr_free(a, r);
    tsr_free(a, tn);
    tsr_free(a, tc);
    tsr_free(a, seeds);
    tsr_free(a, keep);
    return st;
}

/* ---- Delaunay method --------------------------------------------------- */

/* Copies the kept finite triangles (keep NULL: all) of d into out. */
static tsr_status extract(const tsr_cdt *d, const uint8_t *keep, tsr_triangulation *out)
{
    const tsr_allocator *a = out->alloc.realloc ? &out->alloc : NULL;
    uint32_t nv = d->nv - 1, nt = 0, ne = 0;
    for (uint32_t t = 0; t < d->nt; t++) {
        if (cdt_is_ghost(d, t) || (keep && !keep[t]))
            continue;
        nt++;
        for (int k = 0; k < 3; k++) {
            uint32_t m = cdt_mark(d, t, k), s = d->tn[3 * (size_t)t + k];
            bool s_kept = !cdt_is_ghost(d, s) && (!keep || keep[s]);
            if (m && CDT_LABEL(m) != CDT_BOUNDARY && (!s_kept || t < s))
                ne++;
        }
    }
    out->xy = tsr_alloc(a, 2 * ((size_t)nv + 1) * sizeof *out->xy);
    out->tri = tsr_alloc(a, 3 * ((size_t)nt + 1) * sizeof *out->tri);
    out->edge = tsr_alloc(a, 2 * ((size_t)ne + 1) * sizeof *out->edge);
    out->edge_segment = tsr_alloc(a, ((size_t)ne + 1) * sizeof *out->edge_segment);
    if (!out->xy || !out->tri || !out->edge || !out->edge_segment)
        return TSR_ERR_NOMEM;
    memcpy(out->xy, d->xy + 2, 2 * (size_t)nv * sizeof *out->xy);
    out->nv = nv;
    nt = ne = 0;
    for (uint32_t t = 0; t < d->nt; t++) {
        if (cdt_is_ghost(d, t) || (keep && !keep[t]))
            continue;
        const uint32_t *v = d->tv + 3 * (size_t)t;
        for (int k = 0; k < 3; k++) {
            out->tri[3 * (size_t)nt + k] = v[k] - 1;
            uint32_t m = cdt_mark(d, t, k), s = d->tn[3 * (size_t)t + k];
            bool s_kept = !cdt_is_ghost(d, s) && (!keep || keep[s]);
            if (m && CDT_LABEL(m) != CDT_BOUNDARY && (!s_kept || t < s)) {
                out->edge[2 * (size_t)ne] = v[k] - 1;
                out->edge[2 * (size_t)ne + 1] = v[(k + 1) % 3] - 1;
                out->edge_segment[ne++] = CDT_LABEL(m) - 1;
            }
        }
        nt++;
    }
    out->nt = nt;
    out->nedge = ne;
    return TSR_OK;
}

/* The regions of the area bounds (refine.c's area_bound): the part of the
 * domain reachable from each seed without crossing a constrained edge gets
 * tf = CDT_REGION0 + its index, a later seed's over an earlier one's. */
static bool mark_regions(tsr_cdt *d, const tsr_tri_options *opt)
{
    const tsr_allocator *a = tsr__cdt_alloc(d);
    uint32_t *stack = tsr_alloc(a, ((size_t)d->nt + 1) * sizeof *stack);
    if (!stack)
        return false;
    for (uint32_t r = 0; r < opt->nregions; r++) {
        uint32_t h = tsr_cdt_locate_handle(d, opt->regions[3 * (size_t)r], opt->regions[3 * (size_t)r + 1]);
        if (h == UINT32_MAX || d->tf[h] == CDT_OUTSIDE)
            continue;
        uint32_t f = CDT_REGION0 + r, n = 0;
        d->tf[h] = f;
        stack[n++] = h;
        while (n) {
            uint32_t t = stack[--n];
            for (int k = 0; k < 3; k++) {
                uint32_t s = d->tn[3 * (size_t)t + k];
                if (d->tc[3 * (size_t)t + k] || d->tf[s] == CDT_OUTSIDE || d->tf[s] == f)
                    continue;
                d->tf[s] = f;
                stack[n++] = s;
            }
        }
    }
    tsr_free(a, stack);
    return true;
}

static tsr_status delaunay(const tsr_pslg *in, const tsr_tri_options *opt, tsr_triangulation *out, tsr_error *err)
{
    const tsr_allocator *a = out->alloc.realloc ? &out->alloc : NULL;
    tsr_cdt *d = tsr_cdt_create(a);
    uint8_t *keep = NULL;
    uint32_t *seeds = NULL;
    tsr_status st = TSR_ERR_NOMEM;
    bool region_areas = tsr__tri_region_areas(opt);
    if (!d)
        goto fail;
    st = tsr_cdt_insert_points(d, in->xy, in->nv, out->vertex_of_input);
    if (st != TSR_OK)
        goto fail;
    out->duplicates = tsr_cdt_duplicate_count(d);
    out->input_vertices = tsr_cdt_vertex_count(d);
    for (uint32_t s = 0; s < in->nseg; s++) {
        uint32_t u = out->vertex_of_input[in->seg[2 * (size_t)s]], w = out->vertex_of_input[in->seg[2 * (size_t)s + 1]];
        if (u == w) {
            out->degenerate_segments++;
            continue;
        }
        st = tsr_cdt_insert_segment(d, u, w, s);
        if (st == TSR_ERR_VALUE) {
            tsr_cdt_destroy(d);
            return tsr_error_set(err, st,
                                 "segment %u (points %u-%u) could not be inserted: its crossings with other segments "
                                 "keep moving each other within rounding (coordinates of very different magnitudes)",
                                 s, in->seg[2 * (size_t)s], in->seg[2 * (size_t)s + 1]);
        }
        if (st != TSR_OK)
            goto fail;
    }
    out->intersections = tsr_cdt_intersection_count(d);
    bool refine = opt->conforming || opt->min_angle > 0 || opt->max_area > 0 || region_areas;
    bool trivial_region = opt->region == TSR_REGION_HULL && in->nholes == 0;
    if (d->started && (refine || !trivial_region)) {
        st = TSR_ERR_NOMEM;
        if (!tsr__cdt_enable_marks(d, refine))
            goto fail;
        keep = tsr_alloc(a, d->nt + 1);
        seeds = tsr_alloc(a, ((size_t)in->nholes + 1) * sizeof *seeds);
        uint8_t *ghost = tsr_alloc(a, d->nt + 1);
        if (!keep || !seeds || !ghost) {
            tsr_free(a, ghost);
            goto fail;
        }
        for (uint32_t t = 0; t < d->nt; t++)
            ghost[t] = cdt_is_ghost(d, t);
        for (uint32_t h = 0; h < in->nholes; h++)
            seeds[h] = tsr_cdt_locate_handle(d, in->holes[2 * (size_t)h], in->holes[2 * (size_t)h + 1]);
        bool ok = region_keep(a, d->nt, d->tn, d->tc, ghost, opt->region, seeds, in->nholes, keep);
        tsr_free(a, ghost);
        if (!ok)
            goto fail;
        if (refine) {
            /* the domain's boundary becomes constrained, so that refinement
             * stays inside it */
            for (uint32_t t = 0; t < d->nt; t++) {
                d->tf[t] = keep[t] ? 0 : CDT_OUTSIDE;
                for (int k = 0; k < 3; k++) {
                    uint32_t s = d->tn[3 * (size_t)t + k];
                    if (keep[t] && !keep[s] && !d->tc[3 * (size_t)t + k])
                        tsr__cdt_mark_edge(d, t, k, CDT_BOUNDARY);
                }
            }
            if (region_areas && !mark_regions(d, opt))
                goto fail;
            uint32_t *ends = tsr_alloc(a, (2 * (size_t)in->nseg + 1) * sizeof *ends);
            if (!ends)
                goto fail;
            for (size_t i = 0; i < 2 * (size_t)in->nseg; i++)
                ends[i] = out->vertex_of_input[in->seg[i]] + 1;
            st = tsr__cdt_refine(d, opt, out->input_vertices, ends, in->nseg, out);
            tsr_free(a, ends);
            if (st != TSR_OK)
                goto fail;
            tsr_free(a, keep);
            keep = tsr_alloc(a, d->nt + 1);
            if (!keep) {
                st = TSR_ERR_NOMEM;
                goto fail;
            }
            for (uint32_t t = 0; t < d->nt; t++)
                keep[t] = d->tf[t] != CDT_OUTSIDE;
        }
    }
    st = extract(d, keep, out);
    if (st != TSR_OK)
        goto fail;
    st = compact_vertices(out);
    if (st != TSR_OK)
        goto fail;
    tsr_free(a, keep);
    tsr_free(a, seeds);
    tsr_cdt_destroy(d);
    return TSR_OK;
fail:
    tsr_free(a, keep);
    tsr_free(a, seeds);
    tsr_cdt_destroy(d);
    if (st == TSR_ERR_TOO_LARGE && !region_areas)
        return tsr_error_set(err, st,
                             "a maximum triangle area of %g over the region's area of %g asks for more than %g "
                             "triangles: give a larger area, or a Steiner limit",
                             opt->max_area, out->refined_area, (double)TSR_TRI_MAX_AREA_TRIANGLES);
    if (st == TSR_ERR_TOO_LARGE)
        return tsr_error_set(err, st,
                             "the maximum triangle areas (%g, and the regions') over the region's area of %g ask for "
                             "%.3g triangles, more than %g: give larger areas, or a Steiner limit",
                             opt->max_area, out->refined_area, out->asked_triangles,
                             (double)TSR_TRI_MAX_AREA_TRIANGLES);
    return st == TSR_ERR_NOMEM ? tsr_error_set(err, st, "out of memory triangulating %u points", in->nv)
                               : tsr_error_set(err, st, "triangulation failed: %s", tsr_status_str(st));
}

/* Finite, and where the exact predicates stay exact (predicates.h): below
 * 2^250 (no product of four coordinates overflows) and, unless zero, at
 * least 2^-128 (no product of four differences, nor the error terms of
 * the expansions, underflows; the BRIO key's scale stays finite). */
#define COORDINATE_RANGE "out of range (0, or 2^-128 <= |x| < 2^250)"
static bool coordinate_ok(double x) { return x == 0 || (fabs(x) >= 0x1p-128 && fabs(x) < 0x1p250); }

tsr_status tsr_triangulate(const tsr_pslg *in, const tsr_tri_options *opt, tsr_triangulation *out,
                           const tsr_allocator *alloc, tsr_error *err)
{
    static const tsr_tri_options defaults;
    if (!opt)
        opt = &defaults;
    memset(out, 0, sizeof *out);
    if (alloc)
        out->alloc = *alloc;
    for (uint32_t i = 0; i < 2 * in->nv; i++)
        if (!coordinate_ok(in->xy[i]))
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "point %u has a %s coordinate (%g)", i / 2,
                                 isfinite(in->xy[i]) ? COORDINATE_RANGE : "non-finite", in->xy[i]);
    for (uint32_t i = 0; i < 2 * in->nholes; i++)
        if (!coordinate_ok(in->holes[i]))
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "hole %u has a %s coordinate (%g)", i / 2,
                                 isfinite(in->holes[i]) ? COORDINATE_RANGE : "non-finite", in->holes[i]);
    for (uint32_t s = 0; s < in->nseg; s++)
        if (in->seg[2 * (size_t)s] >= in->nv || in->seg[2 * (size_t)s + 1] >= in->nv)
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "segment %u refers to point %u, but there are %u points", s,
                                 in->seg[2 * (size_t)s] >= in->nv ? in->seg[2 * (size_t)s] : in->seg[2 * (size_t)s + 1],
                                 in->nv);
    if (!(opt->min_angle >= 0 && opt->min_angle < 60) || !(opt->max_area >= 0) || !isfinite(opt->max_area))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "minimum angle must be in [0, 60) degrees and maximum area >= 0");
    for (uint32_t r = 0; r < opt->nregions; r++) {
        const double *g = &opt->regions[3 * (size_t)r];
        if (!coordinate_ok(g[0]) || !coordinate_ok(g[1]) || isnan(g[2]) || isinf(g[2]))
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "region %u has a %s (%g, %g, maximum area %g)", r,
                                 isfinite(g[0]) && isfinite(g[1]) && isfinite(g[2]) ? "coordinate " COORDINATE_RANGE
                                                                                    : "non-finite value",
                                 g[0], g[1], g[2]);
    }
    const tsr_allocator *a = alloc;
    tsr_status st;
    if (opt->method == TSR_TRI_QUADTREE) {
        const char *why = NULL;
        bool region_done = false;
        st = tsr__tri_quadtree_region(in, opt, out, alloc, &region_done, &why, err);
        if (st == TSR_OK && !region_done)
            st = tsr__tri_apply_region(out, in, opt);
        if (st != TSR_ERR_UNSUPPORTED) {
            if (st != TSR_OK)
                tsr_triangulation_free(out);
            return st;
        }
        tsr_triangulation_free(out);
        if (alloc)
            out->alloc = *alloc;
        out->fell_back = true;
        out->fallback_reason = why ? why : "the quadtree method does not apply";
    }
    out->vertex_of_input = tsr_alloc(a, ((size_t)in->nv + 1) * sizeof *out->vertex_of_input);
    if (!out->vertex_of_input)
        return tsr_error_set(err, TSR_ERR_NOMEM, "out of memory");
    st = delaunay(in, opt, out, err);
    if (st != TSR_OK) {
        bool fb = out->fell_back;
        const char *why = out->fallback_reason;
        tsr_triangulation_free(out);
        out->fell_back = fb;
        out->fallback_reason = why;
    }
    return st;
}
