/* measure.c: the brute-force error oracle. Triangles are binned on a
 * uniform grid over (x, y); each sample looks up the triangles of its bin
 * and takes the one containing it. Deliberately shares nothing with the
 * pyramid or the quadtree. */
#include "terrain_internal.h"

#include <math.h>
#include <string.h>

tsr_status tsr_terrain_measure(const tsr_heightfield *hf, const tsr_mesh *mesh, const tsr_camera *cam,
                               tsr_error_report *out)
{
    memset(out, 0, sizeof *out);
    const tsr_allocator *a = hf->alloc.realloc ? &hf->alloc : NULL;
    const uint32_t B = 8; /* samples per bin side */
    uint32_t bw = (hf->width + B - 1) / B, bh = (hf->height + B - 1) / B;
    size_t nb = (size_t)bw * bh;
    uint32_t *start = tsr_alloc(a, (nb + 2) * sizeof *start);
    if (!start)
        return TSR_ERR_NOMEM;
    memset(start, 0, (nb + 2) * sizeof *start);
    /* two passes: count, then fill (CSR) */
    uint32_t *items = NULL;
    for (int pass = 0; pass < 2; pass++) {
        for (uint32_t t = 0; t < mesh->triangle_count; t++) {
            const uint32_t *ix = mesh->indices + 3 * (size_t)t;
            double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
            for (int k = 0; k < 3; k++) {
                const float *p = mesh->positions + 3 * (size_t)ix[k];
                double c = p[0] / hf->dx, r = p[1] / hf->dy;
                lo[0] = fmin(lo[0], c);
                hi[0] = fmax(hi[0], c);
                lo[1] = fmin(lo[1], r);
                hi[1] = fmax(hi[1], r);
            }
            int64_t b0x = (int64_t)floor(lo[0] - 1e-6) / B, b1x = (int64_t)floor(hi[0] + 1e-6) / B;
            int64_t b0y = (int64_t)floor(lo[1] - 1e-6) / B, b1y = (int64_t)floor(hi[1] + 1e-6) / B;
            b0x = b0x < 0 ? 0 : b0x;
            b0y = b0y < 0 ? 0 : b0y;
            b1x = b1x >= bw ? bw - 1 : b1x;
            b1y = b1y >= bh ? bh - 1 : b1y;
            for (int64_t y = b0y; y <= b1y; y++)
                for (int64_t x = b0x; x <= b1x; x++) {
                    size_t bi = (size_t)y * bw + (size_t)x;
                    if (pass == 0)
                        start[bi + 2]++;
                    else
                        items[start[bi + 1]++] = t;
                }
        }
        if (pass == 0) {
            for (size_t i = 0; i <= nb; i++)
                start[i + 1] += start[i];
            items = tsr_alloc(a, ((size_t)start[nb + 1] + 1) * sizeof *items);
            if (!items) {
                tsr_free(a, start);
                return TSR_ERR_NOMEM;
            }
        }
    }
    for (uint32_t r = 0; r < hf->height; r++)
        for (uint32_t c = 0; c < hf->width; c++) {
            float h = hf->data[(size_t)r * hf->width + c];
            if (isnan(h))
                continue;
            double x = c * hf->dx, y = r * hf->dy, z = h * hf->dz;
            size_t bi = (size_t)(r / B) * bw + c / B;
            bool found = false;
            double zm = 0;
            for (uint32_t k = start[bi]; k < start[bi + 1] && !found; k++) {
                const uint32_t *ix = mesh->indices + 3 * (size_t)items[k];
                const float *p0 = mesh->positions + 3 * (size_t)ix[0], *p1 = mesh->positions + 3 * (size_t)ix[1],
                            *p2 = mesh->positions + 3 * (size_t)ix[2];
                double d = ((double)p1[0] - p0[0]) * ((double)p2[1] - p0[1]) - ((double)p1[1] - p0[1]) * ((double)p2[0] - p0[0]);
                if (d == 0)
                    continue;
                double l1 = ((x - p0[0]) * ((double)p2[1] - p0[1]) - (y - p0[1]) * ((double)p2[0] - p0[0])) / d;
                double l2 = (((double)p1[0] - p0[0]) * (y - p0[1]) - ((double)p1[1] - p0[1]) * (x - p0[0])) / d;
                const double eps = 1e-7;
                if (l1 < -eps || l2 < -eps || l1 + l2 > 1 + eps)
                    continue;
                zm = p0[2] + l1 * ((double)p1[2] - p0[2]) + l2 * ((double)p2[2] - p0[2]);
                found = true;
            }
            if (!found) {
                out->uncovered++;
                continue;
            }
            double ev = fabs(zm - z);
            if (ev > out->max_vertical) {
                out->max_vertical = ev;
                if (!cam) {
                    out->worst_c = c;
                    out->worst_r = r;
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
            out->counted++;
            double e = hypot(sx1 - sx0, sy1 - sy0);
            if (e > out->max_pixels) {
                out->max_pixels = e;
                out->worst_c = c;
                out->worst_r = r;
            }
        }
    tsr_free(a, items);
    tsr_free(a, start);
    return TSR_OK;
}
