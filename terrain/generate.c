/* generate.c: the deterministic sample terrain of `make demo`.
 *
 * Our own gradient noise (Perlin's 2002 improved-noise idea: hashed
 * gradients at lattice points, a quintic fade), summed as fractal Brownian
 * motion and as a ridged multifractal (Musgrave, "Texturing & Modeling",
 * ch. 16), the domain warped by a second noise (Quilez's domain warping),
 * then particle hydraulic erosion (water droplets that pick up sediment
 * on steep descents and drop it when slowing, after Mei et al. 2007 and
 * many game-terrain writeups) and thermal erosion (slopes above a talus
 * angle relax, Musgrave, Kolb & Mace 1989). Integer hashing and a
 * fixed-order loop make the result identical for a seed on any platform
 * with IEEE doubles. */
#include "terrain_internal.h"

#include <math.h>
#include <pthread.h>
#include <string.h>

static uint32_t hash3(uint32_t x, uint32_t y, uint32_t s)
{
    uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u ^ s * 0xcb1ab31fu;
    h ^= h >> 16;
    h *= 0x7feb352du;
    h ^= h >> 15;
    h *= 0x846ca68bu;
    h ^= h >> 16;
    return h;
}

static double fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }

/* The 16 gradient directions, (cos, sin) of h * 2 pi / 16, made once per
 * terrain with the C library (as each noise call once made them: the same
 * bits, without a sine and cosine per lattice point). */
typedef struct gradients {
    double d[16][2];
} gradients;

static void gradients_init(gradients *g)
{
    for (uint32_t h = 0; h < 16; h++) {
        double a = h * (2 * 3.14159265358979323846 / 16);
        g->d[h][0] = cos(a);
        g->d[h][1] = sin(a);
    }
}

/* Gradient noise in about [-1, 1]; 16 gradient directions. */
static double noise(const gradients *g, double x, double y, uint32_t seed)
{
    double fx = floor(x), fy = floor(y);
    int64_t ix = (int64_t)fx, iy = (int64_t)fy;
    double tx = x - fx, ty = y - fy;
    double v[4];
    for (int k = 0; k < 4; k++) {
        int dx = k & 1, dy = k >> 1;
        uint32_t h = hash3((uint32_t)(ix + dx), (uint32_t)(iy + dy), seed) & 15u;
        v[k] = g->d[h][0] * (tx - dx) + g->d[h][1] * (ty - dy);
    }
    double u = fade(tx), w = fade(ty);
    double a = v[0] + u * (v[1] - v[0]), b = v[2] + u * (v[3] - v[2]);
    return 1.41421356 * (a + w * (b - a));
}

static double fbm(const gradients *g, double x, double y, int octaves, uint32_t seed)
{
    double sum = 0, amp = 0.5, norm = 0;
    for (int o = 0; o < octaves; o++) {
        sum += amp * noise(g, x, y, seed + (uint32_t)o * 1013u);
        norm += amp;
        /* rotate a little between octaves to hide the lattice */
        double nx = 1.6 * x - 1.2 * y, ny = 1.2 * x + 1.6 * y;
        x = nx + 17.3;
        y = ny - 9.1;
        amp *= 0.5;
    }
    return sum / norm;
}

static double ridged(const gradients *g, double x, double y, int octaves, uint32_t seed)
{
    double sum = 0, amp = 0.5, weight = 1, norm = 0;
    for (int o = 0; o < octaves; o++) {
        double n = 1 - fabs(noise(g, x, y, seed + 7919u + (uint32_t)o * 31u));
        n *= n;
        n *= weight;
        weight = n * 2 > 1 ? 1 : n * 2;
        sum += n * amp;
        norm += amp;
        double nx = 1.6 * x - 1.2 * y, ny = 1.2 * x + 1.6 * y;
        x = nx - 3.7;
        y = ny + 11.9;
        amp *= 0.5;
    }
    return sum / norm;
}

static double smoothstep(double a, double b, double x)
{
    double t = (x - a) / (b - a);
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return t * t * (3 - 2 * t);
}

typedef struct rng {
    uint64_t s;
} rng;

static uint32_t rng_next(rng *r)
{
    /* PCG-XSH-RR 64/32 */
    uint64_t old = r->s;
    r->s = old * 6364136223846793005ull + 1442695040888963407ull;
    uint32_t xs = (uint32_t)(((old >> 18) ^ old) >> 27), rot = (uint32_t)(old >> 59);
    return (xs >> rot) | (xs << ((32 - rot) & 31));
}

static double rng_unit(rng *r) { return rng_next(r) * (1.0 / 4294967296.0); }

/* Height and gradient of the bilinear interpolant at (x, y). */
static double sample_grad(const double *h, uint32_t w, double x, double y, double *gx, double *gy)
{
    uint32_t c = (uint32_t)x, r = (uint32_t)y;
    double u = x - c, v = y - r;
    const double *p = h + (size_t)r * w + c;
    double a = p[0], b = p[1], cc = p[w], d = p[w + 1];
    *gx = (b - a) * (1 - v) + (d - cc) * v;
    *gy = (cc - a) * (1 - u) + (d - b) * u;
    return a * (1 - u) * (1 - v) + b * u * (1 - v) + cc * (1 - u) * v + d * u * v;
}

/* Progress of one terrain: each stage reports its own fraction, scaled
 * into its share [start, start + share) of the whole. */
typedef struct reporter {
    const tsr_generate_options *o;
    double start, share;
} reporter;

static void report(const reporter *r, double f)
{
    if (r->o->progress)
        r->o->progress(r->o->progress_user, r->start + r->share * (f < 1 ? f : 1));
}

static void hydraulic_erosion(double *h, uint32_t w, uint32_t ht, uint32_t seed, const reporter *rep)
{
    const double inertia = 0.05, capacity_k = 4, min_capacity = 0.01, erode_k = 0.3, deposit_k = 0.3,
                 evaporate = 0.02, gravity = 4;
    const int max_steps = 48;
    rng r = {(uint64_t)seed * 0x9E3779B97F4A7C15ull + 12345};
    uint64_t droplets = (uint64_t)w * ht / 3;
    for (uint64_t d = 0; d < droplets; d++) {
        if ((d & 0xffff) == 0)
            report(rep, (double)d / (double)droplets);
        double x = rng_unit(&r) * (w - 1.001), y = rng_unit(&r) * (ht - 1.001);
        double dx = 0, dy = 0, speed = 1, water = 1, sediment = 0;
        for (int step = 0; step < max_steps; step++) {
            double gx, gy;
            uint32_t c = (uint32_t)x, rr = (uint32_t)y;
            double u = x - c, v = y - rr;
            double hh = sample_grad(h, w, x, y, &gx, &gy);
            dx = dx * inertia - gx * (1 - inertia);
            dy = dy * inertia - gy * (1 - inertia);
            double len = sqrt(dx * dx + dy * dy);
            if (len < 1e-12)
                break;
            dx /= len;
            dy /= len;
            double nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= w - 1.001 || ny >= ht - 1.001)
                break;
            double g2x, g2y;
            double dh = sample_grad(h, w, nx, ny, &g2x, &g2y) - hh;
            double cap = -dh * speed * water * capacity_k;
            if (cap < min_capacity * water * 0.01)
                cap = min_capacity * water * 0.01;
            double wts[4] = {(1 - u) * (1 - v), u * (1 - v), (1 - u) * v, u * v};
            size_t idx[4] = {(size_t)rr * w + c, (size_t)rr * w + c + 1, (size_t)(rr + 1) * w + c,
                             (size_t)(rr + 1) * w + c + 1};
            if (sediment > cap || dh > 0) {
                double amt = dh > 0 ? (dh < sediment ? dh : sediment) : (sediment - cap) * deposit_k;
                sediment -= amt;
                for (int k = 0; k < 4; k++)
                    h[idx[k]] += amt * wts[k];
            } else {
                double amt = (cap - sediment) * erode_k;
                if (amt > -dh)
                    amt = -dh;
                for (int k = 0; k < 4; k++)
                    h[idx[k]] -= amt * wts[k];
                sediment += amt;
            }
            double s2 = speed * speed - dh * gravity;
            speed = s2 > 0 ? sqrt(s2) : 0;
            water *= 1 - evaporate;
            x = nx;
            y = ny;
        }
    }
}

static void thermal_erosion(double *h, uint32_t w, uint32_t ht, double talus, uint32_t iterations, const reporter *rep)
{
    for (uint32_t it = 0; it < iterations; it++)
        for (uint32_t r = 0; r + 1 < ht; r++) {
            if ((r & 255) == 0)
                report(rep, (it + (double)r / ht) / iterations);
            for (uint32_t c = 0; c + 1 < w; c++) {
                size_t i = (size_t)r * w + c;
                size_t nb[2] = {i + 1, i + w};
                for (int k = 0; k < 2; k++) {
                    double d = h[i] - h[nb[k]];
                    double ad = fabs(d);
                    if (ad > talus) {
                        double move = 0.25 * (ad - talus) * (d > 0 ? 1 : -1);
                        h[i] -= move;
                        h[nb[k]] += move;
                    }
                }
            }
        }
}

/* The noise stage, rows in bands over several threads: each sample is a
 * pure function of its position, so the thread count changes nothing. */
enum { NOISE_BAND = 16 };

typedef struct noise_job {
    gradients g;
    double *h, feature;
    uint32_t w, ht, seed, bands, next, rows_done;
    double *lo, *hi; /* per band */
    pthread_mutex_t lock;
    reporter rep;
} noise_job;

static void noise_band(noise_job *j, uint32_t b)
{
    uint32_t w = j->w, seed = j->seed, r1 = (b + 1) * NOISE_BAND < j->ht ? (b + 1) * NOISE_BAND : j->ht;
    const gradients *g = &j->g;
    double feature = j->feature, lo = INFINITY, hi = -INFINITY;
    for (uint32_t r = b * NOISE_BAND; r < r1; r++)
        for (uint32_t c = 0; c < w; c++) {
            double x = c / feature, y = r / feature;
            double wx = fbm(g, x * 0.7 + 5.2, y * 0.7 + 1.3, 4, seed + 101);
            double wy = fbm(g, x * 0.7 - 3.1, y * 0.7 + 8.7, 4, seed + 202);
            double qx = x + 0.45 * wx, qy = y + 0.45 * wy;
            double base = fbm(g, qx, qy, 8, seed);
            double mountains = ridged(g, qx * 1.3, qy * 1.3, 8, seed);
            double mask = smoothstep(-0.25, 0.35, fbm(g, x * 0.45 + 40, y * 0.45 - 20, 3, seed + 303));
            double v = 0.55 * base + mask * (mountains - 0.3) * 1.1;
            j->h[(size_t)r * w + c] = v;
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
    j->lo[b] = lo;
    j->hi[b] = hi;
}

static void *noise_worker(void *arg)
{
    noise_job *j = arg;
    pthread_mutex_lock(&j->lock);
    for (;;) {
        uint32_t b = j->next++;
        pthread_mutex_unlock(&j->lock);
        if (b >= j->bands)
            return NULL;
        noise_band(j, b);
        pthread_mutex_lock(&j->lock);
        j->rows_done += NOISE_BAND;
        report(&j->rep, (double)j->rows_done / j->ht);
    }
}

/* Without memory for the erosion: plain noise, straight into hf. */
static void plain_noise(tsr_heightfield *hf, const tsr_generate_options *o, uint32_t seed, double relief,
                        double feature)
{
    gradients g;
    gradients_init(&g);
    size_t w = hf->width, n = w * hf->height;
    for (size_t i = 0; i < n; i++)
        hf->data[i] =
            (float)(relief * 0.5 * (1 + fbm(&g, (double)(i % w) / feature, (double)(i / w) / feature, 6, seed)));
    if (o->progress)
        o->progress(o->progress_user, 1);
}

void tsr_terrain_generate(tsr_heightfield *hf, const tsr_generate_options *opts)
{
    static const tsr_generate_options defaults = {0};
    const tsr_generate_options *o = opts ? opts : &defaults;
    uint32_t w = hf->width, ht = hf->height, seed = o->seed;
    double relief = o->relief > 0 ? o->relief : 1200;
    double feature = o->feature_size > 0 ? o->feature_size : (w > ht ? w : ht) / 3.0;
    uint32_t thermal_iters = o->erosion_iterations ? o->erosion_iterations : 40;
    size_t n = (size_t)w * ht;
    const tsr_allocator *a = hf->alloc.realloc ? &hf->alloc : NULL;
    double *h = tsr_alloc(a, n * sizeof *h);
    if (!h) {
        plain_noise(hf, o, seed, relief, feature);
        return;
    }
    /* Shares of the time in the progress (4097^2 on 2 threads: noise 3.5 s,
     * droplets 31.6 s, thermal 1.3 s). */
    double share_noise = 0.1, share_hydraulic = 0.85;
    if (!(w >= 8 && ht >= 8))
        share_noise = 1;
    uint32_t bands = (ht + NOISE_BAND - 1) / NOISE_BAND;
    noise_job j = {.h = h,
                   .feature = feature,
                   .w = w,
                   .ht = ht,
                   .seed = seed,
                   .bands = bands,
                   .lock = PTHREAD_MUTEX_INITIALIZER,
                   .rep = {o, 0, share_noise}};
    gradients_init(&j.g);
    j.lo = tsr_alloc(a, 2 * (size_t)bands * sizeof *j.lo);
    if (!j.lo) {
        tsr_free(a, h);
        plain_noise(hf, o, seed, relief, feature);
        return;
    }
    j.hi = j.lo + bands;
    tsr__run_threads(noise_worker, &j, o->threads, bands);
    pthread_mutex_destroy(&j.lock);
    double lo = INFINITY, hi = -INFINITY;
    for (uint32_t b = 0; b < bands; b++) {
        lo = j.lo[b] < lo ? j.lo[b] : lo;
        hi = j.hi[b] > hi ? j.hi[b] : hi;
    }
    tsr_free(a, j.lo);
    /* Normalise, flatten valleys a little (a power curve), and express
     * heights in cell units with a relief of 4% of the side (1200 m over
     * 1025 cells of 30 m), so erosion sees the slopes of real terrain
     * whatever the resolution. */
    double span = hi > lo ? hi - lo : 1;
    double side = w > ht ? w : ht;
    for (size_t i = 0; i < n; i++)
        h[i] = pow((h[i] - lo) / span, 1.35) * 0.04 * side;
    if (w >= 8 && ht >= 8) {
        reporter rh = {o, share_noise, share_hydraulic},
                 rt = {o, share_noise + share_hydraulic, 1 - share_noise - share_hydraulic};
        hydraulic_erosion(h, w, ht, seed, &rh);
        thermal_erosion(h, w, ht, 0.8 /* tan 39 degrees */, thermal_iters, &rt);
    }
    lo = INFINITY;
    hi = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        lo = h[i] < lo ? h[i] : lo;
        hi = h[i] > hi ? h[i] : hi;
    }
    span = hi > lo ? hi - lo : 1;
    for (size_t i = 0; i < n; i++)
        hf->data[i] = (float)((h[i] - lo) / span * relief);
    tsr_free(a, h);
    if (o->progress)
        o->progress(o->progress_user, 1);
}

/* Midpoint displacement on the (2^k+1)^2 square that encloses the
 * heightfield; other sizes are cropped from a temporary square. */
static double offset_at(uint32_t x, uint32_t y, uint32_t seed)
{
    return (hash3(x, y, seed) * (1.0 / 4294967296.0)) - 0.5;
}

void tsr_terrain_generate_fast(tsr_heightfield *hf, uint32_t seed, double relief)
{
    uint32_t w = hf->width, h = hf->height;
    uint32_t side = 1;
    while (side + 1 < w || side + 1 < h)
        side <<= 1;
    if (side + 1 != w || side + 1 != h) {
        tsr_heightfield *tmp = tsr_heightfield_create(side + 1, side + 1, hf->alloc.realloc ? &hf->alloc : NULL);
        if (!tmp)
            return;
        tsr_terrain_generate_fast(tmp, seed, relief);
        for (uint32_t r = 0; r < h; r++)
            memcpy(hf->data + (size_t)r * w, tmp->data + (size_t)r * (side + 1), w * sizeof(float));
        tsr_heightfield_destroy(tmp);
        return;
    }
    uint32_t n = side + 1;
    float *d = hf->data;
    d[0] = (float)offset_at(0, 0, seed);
    d[side] = (float)offset_at(side, 0, seed);
    d[(size_t)side * n] = (float)offset_at(0, side, seed);
    d[(size_t)side * n + side] = (float)offset_at(side, side, seed);
    double amp = 1.0;
    for (uint32_t step = side; step > 1; step /= 2, amp *= 0.5) {
        uint32_t half = step / 2;
        /* diamond: centres of squares */
        for (uint32_t y = half; y < n; y += step)
            for (uint32_t x = half; x < n; x += step) {
                double avg = 0.25 * ((double)d[(size_t)(y - half) * n + x - half] + d[(size_t)(y - half) * n + x + half] +
                                     d[(size_t)(y + half) * n + x - half] + d[(size_t)(y + half) * n + x + half]);
                d[(size_t)y * n + x] = (float)(avg + amp * offset_at(x, y, seed));
            }
        /* square: edge midpoints */
        for (uint32_t y = 0; y < n; y += half)
            for (uint32_t x = (y / half) % 2 ? 0 : half; x < n; x += step) {
                double sum = 0;
                int cnt = 0;
                if (x >= half) { sum += d[(size_t)y * n + x - half]; cnt++; }
                if (x + half < n) { sum += d[(size_t)y * n + x + half]; cnt++; }
                if (y >= half) { sum += d[(size_t)(y - half) * n + x]; cnt++; }
                if (y + half < n) { sum += d[(size_t)(y + half) * n + x]; cnt++; }
                d[(size_t)y * n + x] = (float)(sum / cnt + amp * offset_at(x, y, seed));
            }
    }
    float lo = INFINITY, hi = -INFINITY;
    size_t total = (size_t)n * n;
    for (size_t i = 0; i < total; i++) {
        lo = fminf(lo, d[i]);
        hi = fmaxf(hi, d[i]);
    }
    double span = hi > lo ? hi - lo : 1;
    for (size_t i = 0; i < total; i++)
        d[i] = (float)((d[i] - lo) / span * relief);
}
