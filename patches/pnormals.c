/* pnormals.c: normals at creases (ptess.h, tsr_ptess_crease_normals).
 *
 * A source is smooth but for its kinks (tsr_pmodel_source_kinks), so a
 * vertex can only sit on a crease where triangles of several sources share
 * it or where it lies on a kink. A corner's side is its source and, on a
 * kink, which side of it its triangle lies; the corners of such vertices
 * are gathered by vertex, each side's normal there is evaluated once, and
 * the sides are grouped by the angle between them. */
#include "patches/ptess.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define NONE UINT32_MAX

typedef struct vsrc { /* a side met at the vertex in hand */
    uint64_t key;
    uint32_t group;
} vsrc;

typedef struct kinks { /* every source's kinks, u then v: off[2 s + axis] .. off[2 s + axis + 1] */
    uint32_t *off;
    double *at;
} kinks;

/* Which side of a kink of its source corner c lies on, along axis: 0 on
 * none, 1 below, 2 above (by its triangle's centroid). */
static uint32_t corner_side(const tsr_ptess_result *r, const kinks *kk, size_t c, int axis, double tol)
{
    uint32_t s = r->tri_source[c / 3], a = kk->off[2 * s + axis], b = kk->off[2 * s + axis + 1];
    if (a == b)
        return 0;
    double x = r->tri_uv[2 * c + axis];
    while (b - a > 1) { /* the last kink at or below x + tol */
        uint32_t mid = a + (b - a) / 2;
        if (kk->at[mid] <= x + tol)
            a = mid;
        else
            b = mid;
    }
    double k = kk->at[a];
    if (fabs(x - k) > fmax(tol, 16 * DBL_EPSILON * fabs(k)))
        return 0;
    const double *t = r->tri_uv + 6 * (c / 3);
    double mid = (t[axis] + t[2 + axis] + t[4 + axis]) / 3;
    return mid < k ? 1 : mid > k ? 2 : 0;
}

/* The side of corner c: its source, and its sides of the source's kinks. */
static uint64_t corner_key(const tsr_ptess_result *r, const kinks *kk, const double *tol, size_t c)
{
    uint32_t s = r->tri_source[c / 3];
    return (uint64_t)s * 9 + corner_side(r, kk, c, 0, tol[2 * s]) * 3 + corner_side(r, kk, c, 1, tol[2 * s + 1]);
}

typedef struct vgroup { /* sources whose normals agree there */
    double first[3], sum[3];
    uint32_t vertex;
} vgroup;

static tsr_status fail(tsr_error *err, tsr_status st, const char *msg)
{
    return tsr_error_set(err, st, "crease normals: %s", msg);
}

/* Room for n records of size sz in *p (capacity *cap). */
static bool grow(const tsr_allocator *a, void **p, uint32_t *cap, uint32_t n, size_t sz)
{
    if (n <= *cap)
        return true;
    uint32_t c = *cap ? *cap : 8;
    while (c < n)
        c *= 2;
    void *q = tsr_realloc(a, *p, c * sz);
    if (!q)
        return false;
    *p = q;
    *cap = c;
    return true;
}

tsr_status tsr_ptess_crease_normals(const tsr_pmodel *m, const tsr_ptess_result *r, double crease_deg,
                                    const tsr_allocator *alloc, tsr_mesh *out, uint32_t *added, tsr_error *err)
{
    if (err)
        err->message[0] = 0;
    if (added)
        *added = 0;
    if (out)
        memset(out, 0, sizeof *out);
    if (!m || !r || !out)
        return fail(err, TSR_ERR_ARGUMENT, "NULL model, tessellation or output");
    const tsr_mesh *in = &r->mesh;
    uint32_t nv = in->vertex_count, nt = in->triangle_count;
    if (!in->normals || (nt && (!r->tri_source || !r->tri_uv || !in->indices)))
        return fail(err, TSR_ERR_ARGUMENT, "the tessellation has no normals (tsr_ptess_options.normals)");
    if (!(crease_deg >= 0 && crease_deg <= 180))
        return fail(err, TSR_ERR_ARGUMENT, "the crease angle must be within 0..180 degrees");
    double cos_lim = crease_deg >= 180 ? -2 : cos(crease_deg * (3.14159265358979323846 / 180));
    size_t nc = 3 * (size_t)nt;
    for (size_t c = 0; c < nc; c++)
        if (in->indices[c] >= nv)
            return fail(err, TSR_ERR_ARGUMENT, "a triangle's index is beyond the vertices");

    tsr_status st = TSR_ERR_NOMEM;
    const char *msg = "out of memory";
    char buf[96];
    uint32_t *src1 = tsr_alloc(alloc, ((size_t)nv + 1) * sizeof *src1); /* first source met, or NONE */
    uint8_t *multi = tsr_alloc(alloc, (size_t)nv + 1);
    uint32_t *off = tsr_alloc(alloc, ((size_t)nv + 1) * sizeof *off);
    uint32_t *cur = tsr_alloc(alloc, ((size_t)nv + 1) * sizeof *cur);
    uint32_t *idx = tsr_alloc(alloc, (nc + 1) * sizeof *idx);
    uint32_t *list = NULL, *side = NULL, vs_cap = 0, vg_cap = 0; /* side: a listed corner's entry in vs */
    vsrc *vs = NULL;
    vgroup *vg = NULL;
    tsr_pmodel_info info;
    tsr_pmodel_get_info(m, &info);
    uint32_t nsrc = info.sources;
    kinks kk = {tsr_alloc(alloc, (2 * (size_t)nsrc + 1) * sizeof *kk.off), NULL};
    double *tol = tsr_alloc(alloc, (2 * (size_t)nsrc + 1) * sizeof *tol); /* 1e-9 of the domain, u and v */
    if (!src1 || !multi || !off || !cur || !idx || !kk.off || !tol)
        goto done;
    kk.off[0] = 0;
    for (uint32_t q = 0; q < 2 * nsrc; q++)
        kk.off[q + 1] = kk.off[q] + tsr_pmodel_source_kinks(m, q / 2, (int)(q & 1), NULL, 0);
    if (!(kk.at = tsr_alloc(alloc, ((size_t)kk.off[2 * nsrc] + 1) * sizeof *kk.at)))
        goto done;
    for (uint32_t q = 0; q < 2 * nsrc; q++) {
        tsr_pmodel_source_kinks(m, q / 2, (int)(q & 1), kk.at + kk.off[q], kk.off[q + 1] - kk.off[q]);
        tsr_psource_info si;
        tol[q] = tsr_pmodel_source_info(m, q / 2, &si) ? 1e-9 * (si.domain[2 * (q & 1) + 1] - si.domain[2 * (q & 1)]) : 0;
    }
    for (size_t c = 0; c < nc; c++)
        if (r->tri_source[c / 3] >= nsrc) {
            st = TSR_ERR_ARGUMENT;
            msg = "a triangle's source is beyond the model's";
            goto done;
        }
    memcpy(idx, in->indices, nc * sizeof *idx);
    for (uint32_t v = 0; v < nv; v++)
        src1[v] = NONE;
    memset(multi, 0, nv);
    for (size_t c = 0; c < nc; c++) {
        uint32_t v = idx[c], s = r->tri_source[c / 3];
        if (src1[v] == NONE)
            src1[v] = s;
        else if (src1[v] != s)
            multi[v] = 1;
        if (!multi[v] && kk.off[2 * s + 2] > kk.off[2 * s] && corner_key(r, &kk, tol, c) != (uint64_t)s * 9)
            multi[v] = 1; /* on a kink */
    }
    /* the corners of shared vertices, by vertex */
    memset(off, 0, ((size_t)nv + 1) * sizeof *off);
    for (size_t c = 0; c < nc; c++)
        off[idx[c] + 1] += multi[idx[c]];
    for (uint32_t v = 0; v < nv; v++)
        off[v + 1] += off[v];
    memcpy(cur, off, (size_t)nv * sizeof *cur);
    list = tsr_alloc(alloc, ((size_t)off[nv] + 1) * sizeof *list);
    side = tsr_alloc(alloc, ((size_t)off[nv] + 1) * sizeof *side);
    if (!list || !side)
        goto done;
    for (size_t c = 0; c < nc; c++)
        if (multi[idx[c]])
            list[cur[idx[c]]++] = (uint32_t)c;

    tsr_mesh_init(out, in->attributes | TSR_MESH_NORMALS, alloc);
    if (tsr_mesh_reserve(out, nv, nt) != TSR_OK)
        goto done;
    for (uint32_t v = 0; v < nv; v++)
        if (tsr_mesh_add_vertex(out, in->positions + 3 * (size_t)v, in->normals + 3 * (size_t)v,
                                in->uvs ? in->uvs + 2 * (size_t)v : NULL) == NONE)
            goto done;
    for (uint32_t v = 0; v < nv; v++) {
        uint32_t a = off[v], b = off[v + 1], ns = 0, ng = 0;
        if (a == b)
            continue;
        if (!grow(alloc, (void **)&vs, &vs_cap, b - a, sizeof *vs) ||
            !grow(alloc, (void **)&vg, &vg_cap, b - a, sizeof *vg))
            goto done;
        for (uint32_t k = a; k < b; k++) {
            uint32_t c = list[k], j = 0;
            uint64_t key = corner_key(r, &kk, tol, c);
            while (j < ns && vs[j].key != key)
                j++;
            side[k] = j;
            if (j < ns)
                continue;
            uint32_t s = (uint32_t)(key / 9), su = (uint32_t)(key % 9) / 3, sv = (uint32_t)(key % 3);
            /* off the kink by a hair (and by more than its rounding) */
            double pos[3], n[3], u = r->tri_uv[2 * (size_t)c], w = r->tri_uv[2 * (size_t)c + 1];
            double hu = fmax(tol[2 * s], 16 * DBL_EPSILON * fabs(u)), hw = fmax(tol[2 * s + 1], 16 * DBL_EPSILON * fabs(w));
            u += su == 1 ? -hu : su == 2 ? hu : 0;
            w += sv == 1 ? -hw : sv == 2 ? hw : 0;
            tsr_status es = tsr_pmodel_eval(m, s, u, w, pos, n);
            if (es != TSR_OK) {
                snprintf(buf, sizeof buf, "source %u could not be evaluated (%s)", s, tsr_status_str(es));
                st = es;
                msg = buf;
                goto done;
            }
            uint32_t g = 0;
            while (g < ng && n[0] * vg[g].first[0] + n[1] * vg[g].first[1] + n[2] * vg[g].first[2] < cos_lim)
                g++;
            if (g == ng) {
                memcpy(vg[g].first, n, sizeof n);
                memset(vg[g].sum, 0, sizeof vg[g].sum);
                vg[g].vertex = ng ? NONE : v;
                ng++;
            }
            for (int x = 0; x < 3; x++)
                vg[g].sum[x] += n[x];
            vs[ns++] = (vsrc){key, g};
        }
        for (uint32_t g = 0; g < ng; g++) {
            double *s = vg[g].sum, l = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
            const double *d = l > 1e-9 ? s : vg[g].first;
            l = l > 1e-9 ? l : 1;
            float fn[3] = {(float)(d[0] / l), (float)(d[1] / l), (float)(d[2] / l)};
            if (g == 0) {
                memcpy(out->normals + 3 * (size_t)v, fn, sizeof fn);
                continue;
            }
            if (out->vertex_count >= NONE - 2) { /* (tsr_mesh's limit) */
                st = TSR_ERR_TOO_LARGE;
                msg = "more than 2^32 - 2 vertices";
                goto done;
            }
            vg[g].vertex = tsr_mesh_add_vertex(out, in->positions + 3 * (size_t)v, fn,
                                               in->uvs ? in->uvs + 2 * (size_t)v : NULL);
            if (vg[g].vertex == NONE)
                goto done;
        }
        for (uint32_t k = a; k < b; k++)
            idx[list[k]] = vg[vs[side[k]].group].vertex;
    }
    for (uint32_t t = 0; t < nt; t++)
        if (!tsr_mesh_add_triangle(out, idx[3 * (size_t)t], idx[3 * (size_t)t + 1], idx[3 * (size_t)t + 2]))
            goto done;
    if (added)
        *added = out->vertex_count - nv;
    st = TSR_OK;
done:
    tsr_free(alloc, src1);
    tsr_free(alloc, multi);
    tsr_free(alloc, off);
    tsr_free(alloc, cur);
    tsr_free(alloc, idx);
    tsr_free(alloc, list);
    tsr_free(alloc, side);
    tsr_free(alloc, vs);
    tsr_free(alloc, vg);
    tsr_free(alloc, kk.off);
    tsr_free(alloc, kk.at);
    tsr_free(alloc, tol);
    if (st != TSR_OK) {
        tsr_mesh_free(out);
        memset(out, 0, sizeof *out);
        fail(err, st, msg);
    }
    return st;
}
