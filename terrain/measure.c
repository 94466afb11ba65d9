/* measure.c: the brute-force error oracle. Every triangle of the mesh is
 * rasterised over the samples: each sample inside its (x, y) footprint
 * (barycentric coordinates from the float positions, with a tolerance of
 * 1e-7) is compared with the triangle's height there; a sample on an edge
 * shared by two triangles is compared with both and the larger error
 * kept. Bands of rows are measured on several threads, each over every
 * triangle but only its own rows. Works from the output mesh and the heightfield alone:
 * deliberately shares nothing with the meshers, the pyramid or the
 * quadtree. */
#include "terrain_internal.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <string.h>

tsr_status tsr_terrain_measure(const tsr_heightfield *hf, const tsr_mesh *mesh, const tsr_camera *cam,
                               tsr_error_report *out)
{
    return tsr_terrain_measure_window(hf, 0, 0, hf->width, hf->height, mesh, cam, out);
}

/* One band of rows [rb, re) of the window: every triangle's samples in
 * it. Bands are measured apart (on several threads), each writing only its
 * own rows of worst[] and wpix[], and their figures combined in band
 * order, so the result does not depend on the thread count. */
typedef struct band {
    const tsr_heightfield *hf;
    uint32_t x0, y0, ww, wh, rb, re;
    const tsr_mesh *mesh;
    const tsr_camera *cam;
    const tsr_allocator *alloc;
    const uint32_t *tris; /* the triangles whose rows meet the band, in order */
    uint32_t ntris;
    tsr_error_report out; /* the band's figures (rms_vertical unused) */
    double sumsq;         /* of the band's covered samples' errors */
    bool nomem;
} band;

/* How far (in rows or columns) a float coordinate near coord may lie from
 * the sample it stands for, spacing apart: float rounding, which at large
 * coordinates (EPSG:3857 metres, 3e7) is a good part of a metre. */
static double slack(double coord, double spacing)
{
    return 1e-6 + 2 * FLT_EPSILON * fabs(coord) / fabs(spacing);
}

/* The window rows a triangle's footprint may cover, [*r0, *r1]; false when
 * none (or a flat or non-finite triangle). */
static bool tri_rows(const tsr_heightfield *hf, uint32_t y0, uint32_t wh, const tsr_mesh *mesh, uint32_t t,
                     uint32_t *r0, uint32_t *r1)
{
    const uint32_t *ix = mesh->indices + 3 * (size_t)t;
    double lo = INFINITY, hi = -INFINITY, sl = 0;
    for (int k = 0; k < 3; k++) {
        double y = mesh->positions[3 * (size_t)ix[k] + 1], r = y / hf->dy - y0;
        lo = fmin(lo, r);
        hi = fmax(hi, r);
        sl = fmax(sl, slack(y, hf->dy));
    }
    double rl = ceil(lo - sl), rh = floor(hi + sl);
    if (!(rh >= 0) || !(rl <= (double)wh - 1))
        return false;
    *r0 = rl < 0 ? 0 : (uint32_t)rl;
    *r1 = rh > wh - 1 ? wh - 1 : (uint32_t)rh;
    return true;
}

/* Triangle t's samples in band b: each one inside the triangle's (x, y)
 * footprint compared with its height there, into worst and wpix (per
 * sample) and b->out. rounded: only the samples not reached yet, at their
 * coordinates rounded to float. */
static void tri_samples(band *b, uint32_t t, float *worst, float *wpix, bool rounded)
{
    const tsr_heightfield *hf = b->hf;
    const tsr_mesh *mesh = b->mesh;
    const tsr_camera *cam = b->cam;
    uint32_t x0 = b->x0, y0 = b->y0, ww = b->ww;
    tsr_error_report *out = &b->out;
    const uint32_t *ix = mesh->indices + 3 * (size_t)t;
    const float *p0 = mesh->positions + 3 * (size_t)ix[0], *p1 = mesh->positions + 3 * (size_t)ix[1],
                *p2 = mesh->positions + 3 * (size_t)ix[2];
    double d = ((double)p1[0] - p0[0]) * ((double)p2[1] - p0[1]) - ((double)p1[1] - p0[1]) * ((double)p2[0] - p0[0]);
    if (d == 0 || !isfinite(d))
        return;
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY}, sc = 0, sr = 0;
    const float *pp[3] = {p0, p1, p2};
    for (int k = 0; k < 3; k++) {
        double c = pp[k][0] / hf->dx - x0, r = pp[k][1] / hf->dy - y0;
        lo[0] = fmin(lo[0], c);
        hi[0] = fmax(hi[0], c);
        lo[1] = fmin(lo[1], r);
        hi[1] = fmax(hi[1], r);
        sc = fmax(sc, slack(pp[k][0], hf->dx));
        sr = fmax(sr, slack(pp[k][1], hf->dy));
    }
    double cl = ceil(lo[0] - sc), ch = floor(hi[0] + sc), rl = ceil(lo[1] - sr), rh = floor(hi[1] + sr);
    if (ch < 0 || rh < (double)b->rb || cl > (double)ww - 1 || rl > (double)b->re - 1)
        return;
    uint32_t c0 = cl < 0 ? 0 : (uint32_t)cl, c1 = ch > ww - 1 ? ww - 1 : (uint32_t)ch;
    uint32_t r0 = rl < b->rb ? b->rb : (uint32_t)rl, r1 = rh > b->re - 1 ? b->re - 1 : (uint32_t)rh;
    for (uint32_t r = r0; r <= r1; r++) {
        const float *row = hf->data + (size_t)(y0 + r) * hf->width + x0;
        double y = (double)(y0 + r) * hf->dy;
        if (rounded)
            y = (float)y;
        for (uint32_t c = c0; c <= c1; c++) {
            float h = row[c];
            size_t si = (size_t)(r - b->rb) * ww + c;
            if (isnan(h) || (rounded && !isnan(worst[si])))
                continue;
            double x = (double)(x0 + c) * hf->dx;
            if (rounded)
                x = (float)x;
            double l1 = ((x - p0[0]) * ((double)p2[1] - p0[1]) - (y - p0[1]) * ((double)p2[0] - p0[0])) / d;
            double l2 = (((double)p1[0] - p0[0]) * (y - p0[1]) - ((double)p1[1] - p0[1]) * (x - p0[0])) / d;
            const double eps = 1e-7;
            if (l1 < -eps || l2 < -eps || l1 + l2 > 1 + eps)
                continue;
            double zm = p0[2] + l1 * ((double)p1[2] - p0[2]) + l2 * ((double)p2[2] - p0[2]);
            double z = h * hf->dz, ev = fabs(zm - z);
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

static void measure_band(band *b)
{
    const tsr_heightfield *hf = b->hf;
    const tsr_camera *cam = b->cam;
    uint32_t x0 = b->x0, y0 = b->y0, ww = b->ww;
    tsr_error_report *out = &b->out;
    /* per sample of the band (its own rows: a band writes no other's):
     * its worst error so far (NaN: not reached), and in pixels */
    size_t ns = (size_t)(b->re - b->rb) * ww;
    float *worst = tsr_alloc(b->alloc, ns * sizeof *worst);
    float *wpix = cam ? tsr_alloc(b->alloc, ns * sizeof *wpix) : NULL;
    if (!worst || (cam && !wpix)) {
        tsr_free(b->alloc, worst);
        tsr_free(b->alloc, wpix);
        b->nomem = true;
        return;
    }
    for (size_t i = 0; i < ns; i++)
        worst[i] = NAN;
    for (size_t i = 0; wpix && i < ns; i++)
        wpix[i] = -1;
    for (uint32_t ti = 0; ti < b->ntris; ti++)
        tri_samples(b, b->tris[ti], worst, wpix, false);
    /* samples on the mesh's outer border that float rounding of the
     * vertices' coordinates put outside it (the last row of a raster in
     * EPSG:3857 metres): measured where the mesh has them, at their
     * coordinates rounded to float as the vertices' are */
    bool missed = false;
    for (uint32_t r = b->rb; r < b->re && !missed; r++) {
        const float *row = hf->data + (size_t)(y0 + r) * hf->width + x0;
        for (uint32_t c = 0; c < ww && !missed; c++)
            missed = !isnan(row[c]) && isnan(worst[(size_t)(r - b->rb) * ww + c]);
    }
    for (uint32_t ti = 0; missed && ti < b->ntris; ti++)
        tri_samples(b, b->tris[ti], worst, wpix, true);
    double sumsq = 0;
    for (uint32_t r = b->rb; r < b->re; r++) {
        const float *row = hf->data + (size_t)(y0 + r) * hf->width + x0;
        for (uint32_t c = 0; c < ww; c++) {
            if (isnan(row[c]))
                continue;
            size_t si = (size_t)(r - b->rb) * ww + c;
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
    b->sumsq = sumsq;
    tsr_free(b->alloc, worst);
    tsr_free(b->alloc, wpix);
}

typedef struct band_job {
    band *b;
    uint32_t n, next;
    pthread_mutex_t lock;
} band_job;

static void *band_worker(void *arg)
{
    band_job *j = arg;
    for (;;) {
        pthread_mutex_lock(&j->lock);
        uint32_t i = j->next++;
        pthread_mutex_unlock(&j->lock);
        if (i >= j->n)
            return NULL;
        measure_band(&j->b[i]);
    }
}

enum { BAND_ROWS = 128 };

tsr_status tsr_terrain_measure_window(const tsr_heightfield *hf, uint32_t x0, uint32_t y0, uint32_t ww, uint32_t wh,
                                      const tsr_mesh *mesh, const tsr_camera *cam, tsr_error_report *out)
{
    memset(out, 0, sizeof *out);
    if (x0 >= hf->width || y0 >= hf->height || ww > hf->width - x0 || wh > hf->height - y0)
        return TSR_ERR_ARGUMENT;
    const tsr_allocator *a = hf->alloc.realloc ? &hf->alloc : NULL;
    uint32_t nb = (wh + BAND_ROWS - 1) / BAND_ROWS;
    band *b = tsr_alloc(a, (size_t)nb * sizeof *b);
    uint32_t *start = tsr_alloc(a, ((size_t)nb + 1) * sizeof *start), *list = NULL;
    if (!b || !start) {
        tsr_free(a, b);
        tsr_free(a, start);
        return TSR_ERR_NOMEM;
    }
    /* each band's triangles, by a counting sort in triangle order */
    memset(start, 0, ((size_t)nb + 1) * sizeof *start);
    uint64_t entries = 0;
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        uint32_t r0, r1;
        if (!tri_rows(hf, y0, wh, mesh, t, &r0, &r1))
            continue;
        for (uint32_t k = r0 / BAND_ROWS; k <= r1 / BAND_ROWS; k++)
            start[k + 1]++;
        entries += r1 / BAND_ROWS - r0 / BAND_ROWS + 1;
    }
    for (uint32_t k = 0; k < nb; k++)
        start[k + 1] += start[k];
    list = entries < UINT32_MAX ? tsr_alloc(a, (size_t)entries * sizeof *list + 1) : NULL;
    if (!list) {
        tsr_free(a, b);
        tsr_free(a, start);
        return TSR_ERR_NOMEM;
    }
    for (uint32_t t = 0; t < mesh->triangle_count; t++) {
        uint32_t r0, r1;
        if (!tri_rows(hf, y0, wh, mesh, t, &r0, &r1))
            continue;
        for (uint32_t k = r0 / BAND_ROWS; k <= r1 / BAND_ROWS; k++)
            list[start[k]++] = t;
    }
    for (uint32_t k = nb; k > 0; k--) /* back to the bands' starts */
        start[k] = start[k - 1];
    start[0] = 0;
    memset(b, 0, (size_t)nb * sizeof *b);
    for (uint32_t i = 0; i < nb; i++) {
        b[i].hf = hf, b[i].x0 = x0, b[i].y0 = y0, b[i].ww = ww, b[i].wh = wh, b[i].mesh = mesh, b[i].cam = cam;
        b[i].alloc = a;
        b[i].tris = list + start[i], b[i].ntris = start[i + 1] - start[i];
        b[i].rb = i * BAND_ROWS;
        b[i].re = b[i].rb + BAND_ROWS < wh ? b[i].rb + BAND_ROWS : wh;
    }
    band_job j = {b, nb, 0, PTHREAD_MUTEX_INITIALIZER};
    tsr__run_threads(band_worker, &j, 0, nb);
    pthread_mutex_destroy(&j.lock);
    /* in band order: the first band's worst sample wins a tie */
    double sumsq = 0;
    bool nomem = false;
    for (uint32_t i = 0; i < nb; i++)
        nomem = nomem || b[i].nomem;
    for (uint32_t i = 0; i < nb && !nomem; i++) {
        const tsr_error_report *r = &b[i].out;
        if (r->max_vertical > out->max_vertical) {
            out->max_vertical = r->max_vertical;
            if (!cam) {
                out->worst_c = r->worst_c;
                out->worst_r = r->worst_r;
            }
        }
        if (cam && r->max_pixels > out->max_pixels) {
            out->max_pixels = r->max_pixels;
            out->worst_c = r->worst_c;
            out->worst_r = r->worst_r;
        }
        out->covered += r->covered;
        out->uncovered += r->uncovered;
        out->counted += r->counted;
        sumsq += b[i].sumsq;
    }
    out->rms_vertical = out->covered ? sqrt(sumsq / (double)out->covered) : 0;
    tsr_free(a, b);
    tsr_free(a, start);
    tsr_free(a, list);
    if (nomem) {
        memset(out, 0, sizeof *out);
        return TSR_ERR_NOMEM;
    }
    return TSR_OK;
}
