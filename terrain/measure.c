/* measure.c: the brute-force error oracle. Every triangle of the mesh is
 * rasterised over the samples: each sample inside its (x, y) footprint
 * (barycentric coordinates from the float positions, with a tolerance of
 * 1e-7) is compared with the triangle's height there; a sample on an edge
 * shared by two triangles is compared with both and the larger error
 * kept. Works from the output mesh and the heightfield alone:
 * deliberately shares nothing with the meshers, the pyramid or the
 * quadtree. */
#include "terrain_internal.h"

#include <math.h>
#include <string.h>

tsr_status tsr_terrain_measure(const tsr_heightfield *hf, const tsr_mesh *mesh, const tsr_camera *cam,
                               tsr_error_report *out)
{
    return tsr_terrain_measure_window(hf, 0, 0, hf->width, hf->height, mesh, cam, out);
}

tsr_status tsr_terrain_measure_window(const tsr_heightfield *hf, uint32_t x0, uint32_t y0, uint32_t ww, uint32_t wh,
                                      const tsr_mesh *mesh, const tsr_camera *cam, tsr_error_report *out)
{
    memset(out, 0, sizeof *out);
    if (x0 >= hf->width || y0 >= hf->height || ww > hf->width - x0 || wh > hf->height - y0)
        return TSR_ERR_ARGUMENT;
    const tsr_allocator *a = hf->alloc.realloc ? &hf->alloc : NULL;
    size_t ns = (size_t)ww * wh;
    /* per sample: its worst error so far (NaN: not reached) */
    float *worst = tsr_alloc(a, ns * sizeof *worst);
    float *wpix = cam ? tsr_alloc(a, ns * sizeof *wpix) : NULL;
    if (!worst || (cam && !wpix)) {
        tsr_free(a, worst);
        tsr_free(a, wpix);
        return TSR_ERR_NOMEM;
    }
    for (size_t i = 0; i < ns; i++)
        worst[i] = NAN;
    if (wpix)
        for (size_t i = 0; i < ns; i++)
            wpix[i] = -1;
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *ix = mesh->indices + 3 * (size_t)t;
        const float *p0 = mesh->positions + 3 * (size_t)ix[0], *p1 = mesh->positions + 3 * (size_t)ix[1],
                    *p2 = mesh->positions + 3 * (size_t)ix[2];
        double d = ((double)p1[0] - p0[0]) * ((double)p2[1] - p0[1]) - ((double)p1[1] - p0[1]) * ((double)p2[0] - p0[0]);
        if (d == 0 || !isfinite(d))
            continue;
        double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
        const float *pp[3] = {p0, p1, p2};
        for (int k = 0; k < 3; k++) {
            double c = pp[k][0] / hf->dx - x0, r = pp[k][1] / hf->dy - y0;
            lo[0] = fmin(lo[0], c);
            hi[0] = fmax(hi[0], c);
            lo[1] = fmin(lo[1], r);
            hi[1] = fmax(hi[1], r);
        }
        double cl = ceil(lo[0] - 1e-6), ch = floor(hi[0] + 1e-6), rl = ceil(lo[1] - 1e-6), rh = floor(hi[1] + 1e-6);
        if (ch < 0 || rh < 0 || cl > (double)ww - 1 || rl > (double)wh - 1)
            continue;
        uint32_t c0 = cl < 0 ? 0 : (uint32_t)cl, c1 = ch > ww - 1 ? ww - 1 : (uint32_t)ch;
        uint32_t r0 = rl < 0 ? 0 : (uint32_t)rl, r1 = rh > wh - 1 ? wh - 1 : (uint32_t)rh;
        for (uint32_t r = r0; r <= r1; r++) {
            const float *row = hf->data + (size_t)(y0 + r) * hf->width + x0;
            double y = (double)(y0 + r) * hf->dy;
            for (uint32_t c = c0; c <= c1; c++) {
                float h = row[c];
                if (isnan(h))
                    continue;
                double x = (double)(x0 + c) * hf->dx;
                double l1 = ((x - p0[0]) * ((double)p2[1] - p0[1]) - (y - p0[1]) * ((double)p2[0] - p0[0])) / d;
                double l2 = (((double)p1[0] - p0[0]) * (y - p0[1]) - ((double)p1[1] - p0[1]) * (x - p0[0])) / d;
                const double eps = 1e-7;
                if (l1 < -eps || l2 < -eps || l1 + l2 > 1 + eps)
                    continue;
                double zm = p0[2] + l1 * ((double)p1[2] - p0[2]) + l2 * ((double)p2[2] - p0[2]);
                double z = h * hf->dz, ev = fabs(zm - z);
                size_t si = (size_t)r * ww + c;
                if (isnan(worst[si]) || ev > worst[si])
                    worst[si] = (float)ev;
                if (ev > out->max_vertical) {
                    out->max_vertical = ev;
                    if (!cam) {
                        out->worst_c = x0 + c;
                        out->worst_r = y0 + r;
                    }
                }
                if (!cam)
                    continue;
                double ps[3] = {x, y, z}, qs[3] = {x, y, zm}, sx0, sy0, f0, sx1, sy1, f1;
                tsr_camera_project(cam, ps, &sx0, &sy0, &f0);
                tsr_camera_project(cam, qs, &sx1, &sy1, &f1);
                if (f0 < cam->near_dist || f1 < cam->near_dist)
                    continue;
                bool in0 = sx0 >= 0 && sx0 <= cam->width && sy0 >= 0 && sy0 <= cam->height;
                bool in1 = sx1 >= 0 && sx1 <= cam->width && sy1 >= 0 && sy1 <= cam->height;
                if (!in0 && !in1)
                    continue;
                double e = hypot(sx1 - sx0, sy1 - sy0);
                if (e > wpix[si])
                    wpix[si] = (float)e;
                if (e > out->max_pixels) {
                    out->max_pixels = e;
                    out->worst_c = x0 + c;
                    out->worst_r = y0 + r;
                }
            }
        }
    }
    double sumsq = 0;
    for (uint32_t r = 0; r < wh; r++) {
        const float *row = hf->data + (size_t)(y0 + r) * hf->width + x0;
        for (uint32_t c = 0; c < ww; c++) {
            if (isnan(row[c]))
                continue;
            size_t si = (size_t)r * ww + c;
            if (isnan(worst[si])) {
                out->uncovered++;
                continue;
            }
            out->covered++;
            sumsq += (double)worst[si] * worst[si];
            if (wpix && wpix[si] >= 0)
                out->counted++;
        }
    }
    out->rms_vertical = out->covered ? sqrt(sumsq / (double)out->covered) : 0;
    tsr_free(a, worst);
    tsr_free(a, wpix);
    return TSR_OK;
}
