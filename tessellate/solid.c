/* solid.c: closing a height-field mesh into a printable solid: walls down
 * from every boundary loop and a bottom triangulated from the loops.
 *
 * Boundary loops are followed through the half-edge structure by rotating
 * around each end vertex inside its own fan (the usual half-edge "next
 * boundary" rule), so loops that touch at a vertex (pinches) stay apart and
 * every boundary corner gets its own bottom vertex. The bottom is the
 * constrained Delaunay triangulation of the projected loops with the even-
 * odd region rule (triangulate.h); where loops touch, the triangulator
 * merges the coincident points and each bottom triangle at such a point is
 * given the corner whose angular sector (between its two loop edges, on
 * the surface's side) contains it, decided with exact orientation tests. */
#include "tessellate/tessellate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct ctx {
    const tsr_allocator *a;
    uint32_t *bh;    /* boundary half-edges, increasing */
    uint32_t *bnext; /* per boundary index: the next one along its loop */
    uint32_t *bprev;
    uint32_t *pos;   /* per boundary index: its point in the PSLG, in loop order */
    uint32_t *order; /* per PSLG point: its boundary index */
    double *xy;
    uint32_t *seg;
    uint32_t *first, *list; /* per output vertex of the triangulation: its corners */
} ctx;

static void ctx_free(ctx *c)
{
    tsr_free(c->a, c->bh);
    tsr_free(c->a, c->bnext);
    tsr_free(c->a, c->bprev);
    tsr_free(c->a, c->pos);
    tsr_free(c->a, c->order);
    tsr_free(c->a, c->xy);
    tsr_free(c->a, c->seg);
    tsr_free(c->a, c->first);
    tsr_free(c->a, c->list);
}

static uint32_t he_from(const tsr_mesh *m, uint32_t h)
{
    return m->indices[h];
}
static uint32_t he_to(const tsr_mesh *m, uint32_t h)
{
    return m->indices[3 * (h / 3) + (h % 3 + 1) % 3];
}
static uint32_t he_next(uint32_t h)
{
    return 3 * (h / 3) + (h % 3 + 1) % 3;
}

/* Index of half-edge h among the sorted boundary half-edges, or UINT32_MAX. */
static uint32_t find_boundary(const uint32_t *bh, uint32_t nb, uint32_t h)
{
    uint32_t lo = 0, hi = nb;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (bh[mid] < h)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < nb && bh[lo] == h ? lo : UINT32_MAX;
}

/* True when g lies in the sector swept counter-clockwise around v from the
 * ray v->q to the ray v->p (the surface's side of a boundary corner whose
 * loop runs p -> v -> q). */
static bool in_sector(const double v[2], const double q[2], const double p[2], const double g[2])
{
    double turn = tsr_orient2d(v, q, p);
    double gq = tsr_orient2d(v, q, g), gp = tsr_orient2d(v, p, g);
    if (turn > 0)
        return gq > 0 && gp < 0;
    if (turn < 0)
        return gq >= 0 || gp <= 0;
    double dot = (q[0] - v[0]) * (p[0] - v[0]) + (q[1] - v[1]) * (p[1] - v[1]);
    return dot < 0 ? gq > 0 : true;
}

tsr_status tsr_mesh_add_base(tsr_mesh *m, double base_z, tsr_error *err)
{
    if (!m)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "add base: no mesh");
    if (!isfinite(base_z))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "add base: base z %g is not finite", base_z);
    if (m->triangle_count == 0)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "add base: the mesh has no triangle");
    const uint32_t v0 = m->vertex_count, t0 = m->triangle_count;

    /* Input checks: indices, finite positions, lowest point. */
    double zmin = INFINITY;
    for (uint32_t t = 0; t < t0; t++) {
        const uint32_t *ix = m->indices + 3 * (size_t)t;
        for (int k = 0; k < 3; k++) {
            if (ix[k] >= v0)
                return tsr_error_set(err, TSR_ERR_INVALID_MESH, "add base: triangle %u has index %u >= %u vertices", t,
                                     ix[k], v0);
            const float *p = m->positions + 3 * (size_t)ix[k];
            if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
                return tsr_error_set(err, TSR_ERR_ARGUMENT, "add base: vertex %u has a non-finite coordinate", ix[k]);
            if (p[2] < zmin)
                zmin = p[2];
        }
        if (ix[0] == ix[1] || ix[1] == ix[2] || ix[2] == ix[0])
            return tsr_error_set(err, TSR_ERR_INVALID_MESH, "add base: triangle %u repeats a vertex (%u %u %u)", t,
                                 ix[0], ix[1], ix[2]);
    }
    const float bz = (float)base_z;
    if (!(base_z < zmin) || !(bz < zmin))
        return tsr_error_set(err, TSR_ERR_ARGUMENT,
                             "add base: base z %.9g must be strictly below the mesh's lowest point (z = %.9g)", base_z,
                             zmin);

    const tsr_allocator *a = m->alloc.realloc ? &m->alloc : NULL;
    tsr_halfedges he;
    if (tsr_halfedges_build(&he, m, a) != TSR_OK)
        return tsr_error_set(err, TSR_ERR_NOMEM, "add base: out of memory");
    uint32_t nb = 0;
    for (uint32_t h = 0; h < he.count; h++) {
        uint32_t tw = he.twin[h];
        if (tw == TSR_NONMANIFOLD) {
            uint32_t x = he_from(m, h), y = he_to(m, h);
            tsr_halfedges_free(&he);
            return tsr_error_set(err, TSR_ERR_INVALID_MESH, "add base: edge %u-%u is used by more than two triangles",
                                 x, y);
        }
        if (tw == TSR_NO_TWIN)
            nb++;
        else if (he_from(m, tw) == he_from(m, h)) {
            uint32_t x = he_from(m, h), y = he_to(m, h);
            tsr_halfedges_free(&he);
            return tsr_error_set(err, TSR_ERR_INVALID_MESH,
                                 "add base: edge %u-%u is traversed the same way by two triangles (inconsistent "
                                 "orientation)",
                                 x, y);
        }
    }
    if (nb == 0) { /* already closed */
        tsr_halfedges_free(&he);
        return TSR_OK;
    }
    if ((uint64_t)v0 + nb >= UINT32_MAX - 2 || (uint64_t)t0 + 2ull * nb + 2ull * nb >= UINT32_MAX / 3) {
        tsr_halfedges_free(&he);
        return tsr_error_set(err, TSR_ERR_TOO_LARGE, "add base: the solid would exceed 32-bit indices");
    }

    ctx c;
    memset(&c, 0, sizeof c);
    c.a = a;
    c.bh = tsr_alloc(a, nb * sizeof *c.bh);
    c.bnext = tsr_alloc(a, nb * sizeof *c.bnext);
    c.bprev = tsr_alloc(a, nb * sizeof *c.bprev);
    c.pos = tsr_alloc(a, nb * sizeof *c.pos);
    c.order = tsr_alloc(a, nb * sizeof *c.order);
    c.xy = tsr_alloc(a, 2 * (size_t)nb * sizeof *c.xy);
    c.seg = tsr_alloc(a, 2 * (size_t)nb * sizeof *c.seg);
    tsr_status s = TSR_OK;
    if (!c.bh || !c.bnext || !c.bprev || !c.pos || !c.order || !c.xy || !c.seg) {
        s = tsr_error_set(err, TSR_ERR_NOMEM, "add base: out of memory");
        goto done;
    }
    nb = 0;
    for (uint32_t h = 0; h < he.count; h++)
        if (he.twin[h] == TSR_NO_TWIN)
            c.bh[nb++] = h;
    for (uint32_t k = 0; k < nb; k++)
        c.bprev[k] = UINT32_MAX;
    /* The next boundary half-edge: rotate around the end vertex, inside
     * the fan this half-edge belongs to, until the boundary. */
    for (uint32_t k = 0; k < nb; k++) {
        uint32_t g = he_next(c.bh[k]), steps = 0;
        while (he.twin[g] != TSR_NO_TWIN && steps++ <= he.count)
            g = he_next(he.twin[g]);
        uint32_t j = find_boundary(c.bh, nb, g);
        if (j == UINT32_MAX || c.bprev[j] != UINT32_MAX) {
            s = tsr_error_set(err, TSR_ERR_INVALID_MESH, "add base: boundary at vertex %u is not a simple loop",
                              he_to(m, c.bh[k]));
            goto done;
        }
        c.bnext[k] = j;
        c.bprev[j] = k;
    }
    /* PSLG points in loop order, one per boundary corner (the start of
     * each boundary half-edge), and the loops' segments. */
    {
        uint32_t n = 0;
        for (uint32_t k = 0; k < nb; k++)
            c.pos[k] = UINT32_MAX;
        for (uint32_t k0 = 0; k0 < nb; k0++) {
            if (c.pos[k0] != UINT32_MAX)
                continue;
            uint32_t k = k0;
            do {
                c.pos[k] = n;
                c.order[n] = k;
                const float *p = m->positions + 3 * (size_t)he_from(m, c.bh[k]);
                c.xy[2 * n] = p[0];
                c.xy[2 * n + 1] = p[1];
                n++;
                k = c.bnext[k];
            } while (k != k0);
        }
        for (uint32_t k = 0; k < nb; k++) {
            c.seg[2 * k] = c.pos[k];
            c.seg[2 * k + 1] = c.pos[c.bnext[k]];
        }
    }

    tsr_pslg in = {c.xy, nb, c.seg, nb, NULL, 0};
    tsr_tri_options opt;
    memset(&opt, 0, sizeof opt);
    opt.method = TSR_TRI_DELAUNAY;
    opt.region = TSR_REGION_EVEN_ODD;
    tsr_triangulation tri;
    tsr_error terr;
    s = tsr_triangulate(&in, &opt, &tri, a, &terr);
    if (s != TSR_OK) {
        s = tsr_error_set(err, s, "add base: bottom: %s", terr.message);
        goto done;
    }
    if (tri.degenerate_segments || tri.intersections || tri.steiner || tri.nedge != nb || tri.nt == 0) {
        /* Name a culprit: a vertical boundary edge, or else the loops
         * cross or overlap in xy. */
        for (uint32_t k = 0; k < nb; k++) {
            const double *p = c.xy + 2 * (size_t)c.seg[2 * k], *q = c.xy + 2 * (size_t)c.seg[2 * k + 1];
            if (p[0] == q[0] && p[1] == q[1]) {
                s = tsr_error_set(err, TSR_ERR_INVALID_MESH,
                                  "add base: boundary edge %u-%u is vertical (the mesh is not a height field)",
                                  he_from(m, c.bh[k]), he_to(m, c.bh[k]));
                break;
            }
        }
        if (s == TSR_OK)
            s = tsr_error_set(err, TSR_ERR_INVALID_MESH,
                              "add base: boundary loops cross, overlap or touch an edge seen from +z (%u crossings, "
                              "%u of %u boundary edges kept): the mesh is not a height field",
                              tri.intersections, tri.nedge, nb);
        tsr_triangulation_free(&tri);
        goto done;
    }
    /* Corners per output vertex (several only where loops touch). */
    c.first = tsr_alloc(a, ((size_t)tri.nv + 1) * sizeof *c.first);
    c.list = tsr_alloc(a, (size_t)nb * sizeof *c.list);
    if (!c.first || !c.list || tsr_mesh_reserve(m, v0 + nb, t0 + 2 * nb + tri.nt) != TSR_OK) {
        tsr_triangulation_free(&tri);
        s = tsr_error_set(err, TSR_ERR_NOMEM, "add base: out of memory");
        goto done;
    }
    memset(c.first, 0, ((size_t)tri.nv + 1) * sizeof *c.first);
    for (uint32_t i = 0; i < nb; i++)
        c.first[tri.vertex_of_input[i] + 1]++;
    for (uint32_t o = 0; o < tri.nv; o++)
        c.first[o + 1] += c.first[o];
    for (uint32_t i = 0; i < nb; i++) {
        uint32_t o = tri.vertex_of_input[i];
        c.list[c.first[o]++] = i;
    }
    for (uint32_t o = tri.nv; o > 0; o--)
        c.first[o] = c.first[o - 1];
    c.first[0] = 0;

    /* Bottom vertices, in PSLG order: vertex v0 + i for point i. */
    for (uint32_t i = 0; i < nb; i++) {
        uint32_t k = c.order[i];
        uint32_t top = he_from(m, c.bh[k]);
        const float *p = m->positions + 3 * (size_t)top;
        float q[3] = {p[0], p[1], bz}, n[3] = {0, 0, -1};
        /* outward horizontal normals of the incoming and outgoing walls */
        double hx = 0, hy = 0;
        const double *pv = c.xy + 2 * (size_t)i, *pp = c.xy + 2 * (size_t)c.pos[c.bprev[k]],
                     *pn = c.xy + 2 * (size_t)c.pos[c.bnext[k]];
        double e[2][2] = {{pv[0] - pp[0], pv[1] - pp[1]}, {pn[0] - pv[0], pn[1] - pv[1]}};
        for (int j = 0; j < 2; j++) {
            double l = hypot(e[j][0], e[j][1]);
            if (l > 0) {
                hx += e[j][1] / l;
                hy += -e[j][0] / l;
            }
        }
        double l = hypot(hx, hy);
        if (l > 1e-12) {
            const double r = 0.70710678118654752440;
            n[0] = (float)(hx / l * r);
            n[1] = (float)(hy / l * r);
            n[2] = (float)-r;
        }
        const float *uv = m->uvs ? m->uvs + 2 * (size_t)top : NULL;
        tsr_mesh_add_vertex(m, q, n, uv);
    }
    /* Walls: a->b on top, a'->b' below; outward is right of a->b. */
    for (uint32_t k = 0; k < nb; k++) {
        uint32_t ta = he_from(m, c.bh[k]), tb = he_to(m, c.bh[k]);
        uint32_t ba = v0 + c.pos[k], bb = v0 + c.pos[c.bnext[k]];
        tsr_mesh_add_triangle(m, tb, ta, ba);
        tsr_mesh_add_triangle(m, tb, ba, bb);
    }
    /* Bottom, reversed to face -z. */
    for (uint32_t t = 0; t < tri.nt; t++) {
        const uint32_t *o = tri.tri + 3 * (size_t)t;
        uint32_t v[3];
        for (int j = 0; j < 3; j++) {
            uint32_t lo = c.first[o[j]], hi = c.first[o[j] + 1], pick = c.list[lo];
            if (hi - lo > 1) {
                const double *A = tri.xy + 2 * (size_t)o[0], *B = tri.xy + 2 * (size_t)o[1],
                             *C = tri.xy + 2 * (size_t)o[2];
                double g[2] = {(A[0] + B[0] + C[0]) / 3, (A[1] + B[1] + C[1]) / 3};
                for (uint32_t x = lo; x < hi; x++) {
                    uint32_t i = c.list[x], k = c.order[i];
                    if (in_sector(c.xy + 2 * (size_t)i, c.xy + 2 * (size_t)c.pos[c.bnext[k]],
                                  c.xy + 2 * (size_t)c.pos[c.bprev[k]], g)) {
                        pick = i;
                        break;
                    }
                }
            }
            v[j] = v0 + pick;
        }
        tsr_mesh_add_triangle(m, v[0], v[2], v[1]);
    }
    tsr_triangulation_free(&tri);

    /* The added triangles must pair up among themselves except for the
     * walls' top edges, which meet the surface's boundary. A failure here
     * is a bug, or input the checks above let through. */
    {
        tsr_mesh sub = *m;
        sub.indices = m->indices + 3 * (size_t)t0;
        sub.triangle_count = m->triangle_count - t0;
        tsr_halfedges sh;
        if (tsr_halfedges_build(&sh, &sub, a) != TSR_OK) {
            s = tsr_error_set(err, TSR_ERR_NOMEM, "add base: out of memory");
        } else {
            for (uint32_t h = 0; h < sh.count && s == TSR_OK; h++) {
                bool wall_top = h < 6 * nb && h % 6 == 0;
                uint32_t tw = sh.twin[h];
                bool ok = wall_top ? tw == TSR_NO_TWIN : tw < sh.count && he_from(&sub, tw) == he_to(&sub, h);
                if (!ok)
                    s = tsr_error_set(err, TSR_ERR_INVALID_MESH,
                                      "add base: could not close the solid at edge %u-%u (boundary loops touching "
                                      "in xy?)",
                                      he_from(&sub, h), he_to(&sub, h));
            }
            tsr_halfedges_free(&sh);
        }
    }
done:
    if (s != TSR_OK) {
        m->vertex_count = v0;
        m->triangle_count = t0;
    }
    tsr_halfedges_free(&he);
    ctx_free(&c);
    return s;
}

/* ---- Flat faces ----------------------------------------------------------- */

typedef struct fgroup {
    double first[3];
    uint32_t vertex;
} fgroup;

tsr_status tsr_mesh_split_flat(tsr_mesh *m, uint32_t first, double crease_deg, tsr_error *err)
{
    if (!m)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "flat faces: no mesh");
    if (!m->normals && m->vertex_count)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "flat faces: the mesh has no normals");
    if (first > m->triangle_count)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "flat faces: triangle %u is beyond the %u triangles", first,
                             m->triangle_count);
    if (!(crease_deg >= 0 && crease_deg <= 180))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "flat faces: the crease angle %g is not within 0..180 degrees",
                             crease_deg);
    uint32_t nv = m->vertex_count, nt = m->triangle_count;
    for (size_t c = 0; c < 3 * (size_t)nt; c++)
        if (m->indices[c] >= nv)
            return tsr_error_set(err, TSR_ERR_INVALID_MESH, "flat faces: triangle %zu has index %u >= %u vertices",
                                 c / 3, m->indices[c], nv);
    double cos_lim = crease_deg >= 180 ? -2 : cos(crease_deg * (3.14159265358979323846 / 180));
    const tsr_allocator *a = &m->alloc;
    size_t nc = 3 * (size_t)(nt - first);
    uint32_t *off = tsr_alloc(a, ((size_t)nv + 2) * sizeof *off), *list = tsr_alloc(a, (nc + 1) * sizeof *list);
    uint32_t *idx = tsr_alloc(a, (nc + 1) * sizeof *idx), *gof = tsr_alloc(a, (nc + 1) * sizeof *gof);
    uint8_t *top = tsr_alloc(a, (size_t)nv + 1);
    double *fn = tsr_alloc(a, (3 * (size_t)(nt - first) + 1) * sizeof *fn);
    fgroup *g = NULL;
    uint32_t gcap = 0;
    tsr_status st = TSR_ERR_NOMEM;
    if (!off || !list || !idx || !gof || !top || !fn)
        goto done;
    memset(top, 0, nv);
    for (size_t c = 0; c < 3 * (size_t)first; c++)
        top[m->indices[c]] = 1;
    for (uint32_t t = first; t < nt; t++) { /* unit normals (0 when degenerate) */
        const float *p0 = m->positions + 3 * (size_t)m->indices[3 * (size_t)t],
                    *p1 = m->positions + 3 * (size_t)m->indices[3 * (size_t)t + 1],
                    *p2 = m->positions + 3 * (size_t)m->indices[3 * (size_t)t + 2];
        double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        double *n = fn + 3 * (size_t)(t - first);
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; k++)
            n[k] = l > 0 ? n[k] / l : 0;
    }
    /* the new faces' corners, by vertex */
    memset(off, 0, ((size_t)nv + 2) * sizeof *off);
    for (size_t c = 0; c < nc; c++)
        off[m->indices[3 * (size_t)first + c] + 2]++;
    for (uint32_t v = 0; v < nv; v++)
        off[v + 2] += off[v + 1];
    for (size_t c = 0; c < nc; c++)
        list[off[m->indices[3 * (size_t)first + c] + 1]++] = (uint32_t)c;
    /* now off[v] .. off[v + 1] are v's corners; group them */
    uint32_t add = 0;
    for (uint32_t v = 0; v < nv; v++) {
        uint32_t lo = off[v], hi = off[v + 1], ng = 0;
        if (lo == hi)
            continue;
        if (hi - lo > gcap) {
            uint32_t cap = gcap ? gcap : 8;
            while (cap < hi - lo)
                cap *= 2;
            fgroup *ng2 = tsr_realloc(a, g, cap * sizeof *g);
            if (!ng2)
                goto done;
            g = ng2;
            gcap = cap;
        }
        /* faces with a normal first; then those without (no area) join
         * the first group, or make one if they are all there is */
        for (int pass = 0; pass < 2; pass++)
            for (uint32_t k = lo; k < hi; k++) {
                const double *n = fn + 3 * (size_t)(list[k] / 3);
                bool flat = n[0] == 0 && n[1] == 0 && n[2] == 0;
                if (flat != (pass == 1))
                    continue;
                uint32_t j = 0;
                while (j < ng && !flat && n[0] * g[j].first[0] + n[1] * g[j].first[1] + n[2] * g[j].first[2] < cos_lim)
                    j++;
                if (j == ng) {
                    memcpy(g[j].first, n, sizeof g[j].first);
                    ng++;
                }
                gof[k] = j;
            }
        for (uint32_t j = 0; j < ng; j++)
            g[j].vertex = j == 0 && !top[v] ? v : nv + add++;
        for (uint32_t k = lo; k < hi; k++)
            idx[list[k]] = g[gof[k]].vertex;
    }
    if ((uint64_t)nv + add > UINT32_MAX - 2) {
        st = tsr_error_set(err, TSR_ERR_TOO_LARGE, "flat faces: more than 2^32 - 2 vertices");
        goto done;
    }
    if (tsr_mesh_reserve(m, nv + add, nt) != TSR_OK)
        goto done;
    /* the copies: position, uv and (for faces without area) normal of the
     * vertex they split; then every vertex of the faces takes the unit sum
     * of its faces' normals */
    for (uint32_t v = 0; v < nv; v++)
        for (uint32_t k = off[v]; k < off[v + 1]; k++) {
            uint32_t w = idx[list[k]];
            if (w >= nv) {
                memcpy(m->positions + 3 * (size_t)w, m->positions + 3 * (size_t)v, 3 * sizeof(float));
                memcpy(m->normals + 3 * (size_t)w, m->normals + 3 * (size_t)v, 3 * sizeof(float));
                if (m->uvs)
                    memcpy(m->uvs + 2 * (size_t)w, m->uvs + 2 * (size_t)v, 2 * sizeof(float));
            }
        }
    double *sum = tsr_alloc(a, (3 * (size_t)(nv + add) + 1) * sizeof *sum);
    if (!sum)
        goto done;
    uint8_t *own = tsr_alloc(a, (size_t)(nv + add) + 1); /* vertex takes its faces' normal */
    if (!own) {
        tsr_free(a, sum);
        goto done;
    }
    memset(own, 0, (size_t)(nv + add));
    memset(sum, 0, 3 * (size_t)(nv + add) * sizeof *sum);
    for (size_t c = 0; c < nc; c++) {
        uint32_t w = idx[c];
        own[w] = 1;
        for (int x = 0; x < 3; x++)
            sum[3 * (size_t)w + x] += fn[3 * (c / 3) + x];
    }
    for (uint32_t w = 0; w < nv + add; w++) {
        if (!own[w])
            continue;
        double *s = sum + 3 * (size_t)w, l = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
        float *n = m->normals + 3 * (size_t)w;
        if (l > 0)
            for (int x = 0; x < 3; x++)
                n[x] = (float)(s[x] / l);
    }
    tsr_free(a, sum);
    tsr_free(a, own);
    m->vertex_count = nv + add;
    memcpy(m->indices + 3 * (size_t)first, idx, nc * sizeof *idx);
    st = TSR_OK;
done:
    tsr_free(a, off);
    tsr_free(a, list);
    tsr_free(a, idx);
    tsr_free(a, gof);
    tsr_free(a, top);
    tsr_free(a, fn);
    tsr_free(a, g);
    if (st == TSR_ERR_NOMEM)
        tsr_error_set(err, st, "flat faces: out of memory");
    return st;
}
