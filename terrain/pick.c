/* pick.c: ray picking on the maximum mipmap (Tevs, Ihrke & Seidel 2008):
 * descend from the top block, skip any block whose height range the ray
 * passes entirely above or below over the block's footprint, visit
 * children front to back, and intersect the cells of the finest blocks
 * exactly (two triangles per cell, the union-jack diagonal of the finest
 * tiles; Moller & Trumbore 1997 for ray-triangle). */
#include "terrain_internal.h"

#include <math.h>

static bool ray_triangle(const double o[3], const double d[3], const double a[3], const double b[3], const double c[3],
                         double *t_out)
{
    double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double p[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
    double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    if (det == 0)
        return false;
    double inv = 1 / det, s[3] = {o[0] - a[0], o[1] - a[1], o[2] - a[2]};
    double u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) * inv;
    if (u < 0 || u > 1)
        return false;
    double q[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
    double v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * inv;
    if (v < 0 || u + v > 1)
        return false;
    double t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * inv;
    if (t < 0)
        return false;
    *t_out = t;
    return true;
}

/* Nearest hit with cell (c, r) of the full-resolution surface. */
static bool cell_hit(const tsr_heightfield *hf, uint32_t c, uint32_t r, const double o[3], const double d[3], double *t_out)
{
    const float *row0 = hf->data + (size_t)r * hf->width, *row1 = row0 + hf->width;
    float ha = row0[c], hb = row0[c + 1], hc = row1[c], hd = row1[c + 1];
    double A[3] = {c * hf->dx, r * hf->dy, ha * hf->dz}, B[3] = {(c + 1) * hf->dx, r * hf->dy, hb * hf->dz};
    double C[3] = {c * hf->dx, (r + 1) * hf->dy, hc * hf->dz}, D[3] = {(c + 1) * hf->dx, (r + 1) * hf->dy, hd * hf->dz};
    double best = INFINITY, t;
    bool even = ((c + r) & 1) == 0;
    /* a triangle with a NaN corner is a hole */
    if (even) {
        if (!isnan(ha) && !isnan(hb) && !isnan(hd) && ray_triangle(o, d, A, B, D, &t) && t < best)
            best = t;
        if (!isnan(ha) && !isnan(hd) && !isnan(hc) && ray_triangle(o, d, A, D, C, &t) && t < best)
            best = t;
    } else {
        if (!isnan(ha) && !isnan(hb) && !isnan(hc) && ray_triangle(o, d, A, B, C, &t) && t < best)
            best = t;
        if (!isnan(hb) && !isnan(hd) && !isnan(hc) && ray_triangle(o, d, B, D, C, &t) && t < best)
            best = t;
    }
    if (best == INFINITY)
        return false;
    *t_out = best;
    return true;
}

/* Parameter interval [t0, t1] of the ray over the box [x0,x1]x[y0,y1]
 * (world units); false when it misses. */
static bool slab(const double o[3], const double d[3], double x0, double x1, double y0, double y1, double *t0, double *t1)
{
    double lo = 0, hi = INFINITY;
    double bmin[2] = {x0, y0}, bmax[2] = {x1, y1};
    for (int k = 0; k < 2; k++) {
        if (d[k] == 0) {
            if (o[k] < bmin[k] || o[k] > bmax[k])
                return false;
            continue;
        }
        double a = (bmin[k] - o[k]) / d[k], b = (bmax[k] - o[k]) / d[k];
        if (a > b) {
            double tmp = a;
            a = b;
            b = tmp;
        }
        lo = a > lo ? a : lo;
        hi = b < hi ? b : hi;
        if (lo > hi)
            return false;
    }
    *t0 = lo;
    *t1 = hi;
    return true;
}

bool tsr_terrain_pick(const tsr_terrain *t, const double origin[3], const double dir[3], double *t_hit)
{
    pick_view v;
    if (!tsr_terrain_pick_view(t, &v))
        return false;
    const tsr_heightfield *hf = v.hf;
    uint32_t ex = hf->width - 1, ey = hf->height - 1;
    typedef struct item {
        uint32_t k, bx, by;
    } item;
    item stack[4 * 64];
    int sp = 0;
    stack[sp++] = (item){v.mip_levels, 0, 0};
    double best = INFINITY;
    /* relative slack so blocks are never skipped by rounding */
    double zslack = 1e-9 * (fabs(origin[2]) + 1);
    while (sp > 0) {
        item it = stack[--sp];
        size_t idx = (size_t)it.by * v.mw[it.k] + it.bx;
        float mn = v.mip_min[it.k][idx], mx = v.mip_max[it.k][idx];
        if (!(mn <= mx))
            continue; /* no valid sample */
        uint64_t cells = (uint64_t)1 << it.k;
        uint64_t c0 = it.bx * cells, r0 = it.by * cells;
        uint64_t c1 = c0 + cells > ex ? ex : c0 + cells, r1 = r0 + cells > ey ? ey : r0 + cells;
        double t0, t1;
        if (!slab(origin, dir, c0 * hf->dx, c1 * hf->dx, r0 * hf->dy, r1 * hf->dy, &t0, &t1) || t0 > best)
            continue;
        double z0 = origin[2] + t0 * dir[2], z1 = origin[2] + (isinf(t1) ? t0 : t1) * dir[2];
        if (isinf(t1) && dir[2] != 0)
            z1 = dir[2] > 0 ? INFINITY : -INFINITY;
        double zlo = fmin(z0, z1) - zslack, zhi = fmax(z0, z1) + zslack;
        if (zlo > mx * hf->dz || zhi < mn * hf->dz)
            continue;
        if (it.k == 1) {
            for (uint64_t r = r0; r < r1; r++)
                for (uint64_t c = c0; c < c1; c++) {
                    double th;
                    if (cell_hit(hf, (uint32_t)c, (uint32_t)r, origin, dir, &th) && th < best)
                        best = th;
                }
            continue;
        }
        /* children, pushed so the one the ray reaches first pops first */
        uint32_t order[4][2];
        int sx = dir[0] >= 0 ? 0 : 1, sy = dir[1] >= 0 ? 0 : 1;
        order[0][0] = sx;     order[0][1] = sy;
        order[1][0] = 1 - sx; order[1][1] = sy;
        order[2][0] = sx;     order[2][1] = 1 - sy;
        order[3][0] = 1 - sx; order[3][1] = 1 - sy;
        for (int q = 3; q >= 0; q--) {
            uint32_t cx = 2 * it.bx + order[q][0], cy = 2 * it.by + order[q][1];
            if (cx < v.mw[it.k - 1] && cy < v.mh[it.k - 1])
                stack[sp++] = (item){it.k - 1, cx, cy};
        }
    }
    if (best == INFINITY)
        return false;
    *t_hit = best;
    return true;
}
