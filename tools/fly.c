/* fly.c: a terrain drawn through hw/'s tile renderer, and flight paths. */
#define _POSIX_C_SOURCE 200809L
#include "fly.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

tsr_status fly_init(fly_ctx *f, const tsr_heightfield *hf, tsr_hw_backend *backend, const fly_options *o,
                    tsr_error *err)
{
    memset(f, 0, sizeof *f);
    f->o = *o;
    if (!f->o.tile_n)
        f->o.tile_n = 16;
    if (!(f->o.pixel_error > 0))
        f->o.pixel_error = 2;
    if (!(f->o.fovy_deg > 0))
        f->o.fovy_deg = 60;
    f->hf = hf;
    f->backend = backend;
    tsr_heightfield_spacing(hf, &f->dx, &f->dy, &f->dz);
    tsr_terrain_options to = {.tile_n = f->o.tile_n};
    tsr_status st = tsr_terrain_create(hf, &to, NULL, &f->terrain, err);
    if (st != TSR_OK)
        return st;
    const tsr_surface *s = tsr_terrain_surface(f->terrain);
    f->levels = s->levels;
    f->qt = tsr_quadtree_create(s, NULL);
    if (!f->qt) {
        fly_free(f);
        return tsr_error_set(err, TSR_ERR_NOMEM, "out of memory for the quadtree");
    }
    float mn, mx;
    tsr_terrain_node_range(f->terrain, (tsr_qnode){0, 0, 0}, &mn, &mx);
    f->zmin = mn <= mx ? mn * f->dz : 0;
    f->zmax = mn <= mx ? mx * f->dz : 1;
    if (!(f->o.near_dist > 0)) /* a terrain in kilometres, or a few units across, would otherwise sit
                                  inside the near plane and the cameras' clearance above the ground */
        f->o.near_dist = terrain_unit(f->terrain);
    if (!f->o.cache_bytes)
        f->o.cache_bytes = (uint64_t)256 << 20; /* the renderer's default, named for the notes */
    tsr_hw_renderer_options ro = {.tile_n = f->o.tile_n, .cache_bytes = f->o.cache_bytes};
    /* a U16 tile may move a sample by a thousandth of the height unit:
     * far below any pixel, exact for integer samples anyway */
    ro.max_quantization = 1e-3;
    st = tsr_hw_renderer_create(backend, &ro, NULL, &f->renderer, err);
    if (st != TSR_OK) {
        fly_free(f);
        return st;
    }
    return TSR_OK;
}

void fly_free(fly_ctx *f)
{
    if (f->renderer)
        tsr_hw_renderer_destroy(f->renderer);
    if (f->qt)
        tsr_quadtree_destroy(f->qt);
    if (f->terrain)
        tsr_terrain_destroy(f->terrain);
    free(f->tiles);
    tsr_keymap_free(&f->drawn, NULL);
    memset(f, 0, sizeof *f);
}

bool fly_camera(const fly_ctx *f, const double eye[3], const double target[3], tsr_camera *cam)
{
    memset(cam, 0, sizeof *cam);
    memcpy(cam->eye, eye, sizeof cam->eye);
    memcpy(cam->target, target, sizeof cam->target);
    cam->fovy_deg = f->o.fovy_deg;
    cam->width = f->backend->width;
    cam->height = f->backend->height;
    cam->near_dist = f->o.near_dist;
    cam->pixel_error = f->o.pixel_error;
    return tsr_camera_prepare(cam);
}

void fly_frame_desc(const fly_ctx *f, const tsr_camera *cam, tsr_hw_frame *frame)
{
    memset(frame, 0, sizeof *frame);
    memcpy(frame->eye, cam->eye, sizeof frame->eye);
    tsr_hw_view_proj(cam, frame->view_proj);
    /* Mirrored left to right: y runs down the heightfield's rows (south in
     * a north-up raster), so x, y, z up is the map's mirror image, and a
     * camera in it would show east on the west. Negating clip x (row 0 of
     * the matrix) shows the map the right way round; nothing is culled by
     * winding, and the frustum is symmetric, so the tiles are the same. */
    for (int j = 0; j < 4; j++)
        frame->view_proj[4 * j] = -frame->view_proj[4 * j];
    /* the sun toward -x, -y (west and, y being south, north), 35 degrees
     * up: from the map's north-west, the image's top-left, as hillshades
     * are lit */
    double el = 35 * M_PI / 180, az = 225 * M_PI / 180;
    frame->sun[0] = (float)(cos(el) * cos(az));
    frame->sun[1] = (float)(cos(el) * sin(az));
    frame->sun[2] = (float)sin(el);
    double w = (tsr_heightfield_width(f->hf) - 1) * f->dx, h = (tsr_heightfield_height(f->hf) - 1) * f->dy;
    double fog = f->o.fog_distance;
    frame->fog_distance = (float)(fog < 0 ? 0 : fog > 0 ? fog : hypot(w, h) / 3);
    frame->zmin = (float)f->zmin;
    frame->zmax = (float)f->zmax;
    frame->spacing_min = (float)(f->dx < f->dy ? f->dx : f->dy);
    frame->flags = (f->o.wireframe ? TSR_HW_FRAME_WIREFRAME : 0) | (f->o.geomorph ? TSR_HW_FRAME_GEOMORPH : 0) |
                   (f->o.show_normals ? TSR_HW_FRAME_NORMALS : 0);
}

static tsr_qnode node_of_key(uint64_t key)
{
    tsr_qnode n = {0, 0, (uint8_t)(key >> 56)};
    for (unsigned b = 0; b < 28; b++) {
        n.x |= (uint32_t)((key >> (2 * b)) & 1) << b;
        n.y |= (uint32_t)((key >> (2 * b + 1)) & 1) << b;
    }
    return n;
}

/* The renderer asks for a tile's samples: the heightfield's, at the
 * node's spacing, clamped onto the extent like tsr_quadtree_mesh. */
static bool fetch(void *user, const tsr_hw_tile *tile, float *samples)
{
    const fly_ctx *f = user;
    tsr_qnode n = node_of_key(tile->key);
    uint32_t tn = f->o.tile_n, w = 1u << (f->levels - n.level);
    uint32_t W = tsr_heightfield_width(f->hf), H = tsr_heightfield_height(f->hf);
    const float *h = tsr_heightfield_cdata(f->hf);
    uint64_t c0 = (uint64_t)n.x * tn * w, r0 = (uint64_t)n.y * tn * w;
    for (uint32_t j = 0; j <= tn; j++) {
        uint64_t r = r0 + (uint64_t)j * w;
        if (r > H - 1)
            r = H - 1;
        for (uint32_t i = 0; i <= tn; i++) {
            uint64_t c = c0 + (uint64_t)i * w;
            if (c > W - 1)
                c = W - 1;
            samples[j * (tn + 1) + i] = h[r * W + c];
        }
    }
    return true;
}

/* 1 + the index of the drawn tile of node (x, y, level), 0 for none. */
static uint32_t drawn_tile(const fly_ctx *f, uint32_t x, uint32_t y, int level)
{
    if (level < 0)
        return 0;
    const uint32_t *hit = tsr_keymap_find(&f->drawn, tsr_qnode_key((tsr_qnode){x, y, (uint8_t)level}));
    return hit ? *hit : 0;
}

/* Each drawn tile's neighbours across its edges (tsr_hw_tile.neighbour):
 * the leaf at the same level, else the coarser one (the cut is
 * restricted: neighbours differ by at most one level), else the two finer
 * ones along the edge. Culled leaves are not drawn: no neighbour there. */
static tsr_status link_neighbours(fly_ctx *f, uint32_t count, tsr_error *err)
{
    tsr_keymap_clear(&f->drawn);
    if (!tsr_keymap_reserve(&f->drawn, count, NULL))
        return tsr_error_set(err, TSR_ERR_NOMEM, "out of memory for the neighbours of %u tiles", count);
    for (uint32_t k = 0; k < count; k++) {
        bool found;
        *tsr_keymap_slot(&f->drawn, f->tiles[k].key, &found, NULL) = k + 1; /* reserved: no failure */
    }
    static const int dir[4][2] = {{0, -1}, {1, 0}, {0, 1}, {-1, 0}}; /* TSR_EDGE_* order */
    for (uint32_t k = 0; k < count; k++) {
        tsr_hw_tile *t = &f->tiles[k];
        tsr_qnode n = node_of_key(t->key);
        int64_t side = (int64_t)1 << n.level;
        for (int e = 0; e < 4; e++) {
            int64_t nx = (int64_t)n.x + dir[e][0], ny = (int64_t)n.y + dir[e][1];
            uint32_t *nb = t->neighbour + 2 * e;
            nb[0] = nb[1] = 0;
            if (nx < 0 || ny < 0 || nx >= side || ny >= side)
                continue;
            uint32_t x = (uint32_t)nx, y = (uint32_t)ny, hit = drawn_tile(f, x, y, n.level);
            if (!hit)
                hit = drawn_tile(f, x >> 1, y >> 1, n.level - 1);
            if (hit) {
                nb[0] = nb[1] = hit;
                continue;
            }
            for (uint32_t h = 0; h < 2; h++) /* the finer pair along the edge */
                nb[h] = drawn_tile(f, 2 * x + (e == 3 ? 1 : e == 1 ? 0 : h), 2 * y + (e == 0 ? 1 : e == 2 ? 0 : h),
                                   n.level + 1);
        }
    }
    return TSR_OK;
}

/* One try of fly_frame at cam's pixel error. */
static tsr_status draw_cut(fly_ctx *f, const tsr_camera *cam, fly_frame_stats *st, tsr_error *err)
{
    double t0 = cli_now();
    tsr_status sel = tsr_quadtree_select(f->qt, tsr_refine_camera, (void *)cam);
    if (sel != TSR_OK)
        return tsr_error_set(err, sel, "quadtree selection failed");
    tsr_quadtree_apply_camera(f->qt, cam);
    uint32_t nl = tsr_quadtree_leaf_count(f->qt);
    const tsr_qleaf *L = tsr_quadtree_leaves(f->qt);
    if (nl > f->tiles_cap) {
        tsr_hw_tile *nt = realloc(f->tiles, nl * sizeof *nt);
        if (!nt)
            return tsr_error_set(err, TSR_ERR_NOMEM, "out of memory for %u tiles", nl);
        f->tiles = nt;
        f->tiles_cap = nl;
    }
    const tsr_surface *s = tsr_terrain_surface(f->terrain);
    uint32_t tn = f->o.tile_n, count = 0;
    double xmax = (tsr_heightfield_width(f->hf) - 1) * f->dx, ymax = (tsr_heightfield_height(f->hf) - 1) * f->dy;
    for (uint32_t i = 0; i < nl; i++) {
        if (L[i].culled)
            continue;
        tsr_qnode n = L[i].node;
        double w = (double)(1u << (f->levels - n.level));
        tsr_hw_tile *t = &f->tiles[count++];
        t->key = tsr_qnode_key(n);
        t->origin[0] = n.x * tn * w * f->dx;
        t->origin[1] = n.y * tn * w * f->dy;
        t->spacing[0] = w * f->dx;
        t->spacing[1] = w * f->dy;
        t->limit[0] = xmax;
        t->limit[1] = ymax;
        t->z_scale = f->dz;
        /* 16-bit samples may move by 2% of the node's own error: on screen
         * at most 2% of tau on top of the cut's bound */
        float delta = s->error(s->user, n);
        t->max_quantization = isfinite(delta) ? 0.02 * delta / f->dz : 0;
        t->morph = f->o.geomorph ? L[i].morph : 0;
        t->stitch = L[i].stitch;
        t->level = n.level;
        t->parity = (uint8_t)((n.x & 1) | (n.y & 1) << 1);
        memset(t->neighbour, 0, sizeof t->neighbour);
    }
    if (!f->o.one_sided_normals) {
        tsr_status ln = link_neighbours(f, count, err);
        if (ln != TSR_OK)
            return ln;
    }
    st->leaves = nl;
    st->select_ms += (cli_now() - t0) * 1e3;
    tsr_hw_frame frame;
    fly_frame_desc(f, cam, &frame);
    return tsr_hw_renderer_frame(f->renderer, &frame, f->tiles, count, fetch, f, &st->render, err);
}

tsr_status fly_frame(fly_ctx *f, const tsr_camera *cam, fly_frame_stats *st, tsr_error *err)
{
    memset(st, 0, sizeof *st);
    tsr_camera c = *cam;
    for (;;) {
        st->pixel_error = c.pixel_error;
        tsr_status s = draw_cut(f, &c, st, err);
        /* the cut does not fit the tile cache: a coarser one, never a
         * failed flight (after 40 tries, 1.5^40 = 1e7 times tau, the cache
         * cannot even hold the coarsest cut) */
        if (s != TSR_ERR_TOO_LARGE || st->coarsened >= 40)
            return s;
        c.pixel_error *= 1.5;
        st->coarsened++;
    }
}

/* ---- paths ------------------------------------------------------------------ */

void fly_path_free(fly_path *p)
{
    free(p->eye);
    free(p->target);
    memset(p, 0, sizeof *p);
}

static bool path_grow(fly_path *p, uint32_t *cap, bool targets)
{
    if (p->count < *cap)
        return true;
    uint32_t nc = *cap ? *cap * 2 : 16;
    double(*e)[3] = realloc(p->eye, nc * sizeof *e);
    if (!e)
        return false;
    p->eye = e;
    if (targets) {
        double(*t)[3] = realloc(p->target, nc * sizeof *t);
        if (!t)
            return false;
        p->target = t;
    }
    *cap = nc;
    return true;
}

tsr_status fly_path_read(const char *path, fly_path *p, tsr_error *err)
{
    memset(p, 0, sizeof *p);
    FILE *fp = fopen(path, "r");
    if (!fp)
        return tsr_error_set(err, errno == ENOENT ? TSR_ERR_NOT_FOUND : TSR_ERR_IO, "%s: %s", path, strerror(errno));
    struct stat sb;
    if (fstat(fileno(fp), &sb) == 0 && S_ISDIR(sb.st_mode)) {
        fclose(fp);
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: is a folder, not a path file", path);
    }
    char line[1024];
    uint32_t cap = 0, lineno = 0;
    int per_line = 0;
    tsr_status st = TSR_OK;
    while (fgets(line, sizeof line, fp)) {
        lineno++;
        char *hash = strchr(line, '#');
        if (hash)
            *hash = 0;
        double v[7];
        int n = 0;
        char *s = line, *end;
        while (n < 7) {
            while (*s == ' ' || *s == '\t' || *s == ',' || *s == '\r' || *s == '\n')
                s++;
            if (!*s)
                break;
            v[n] = strtod(s, &end);
            if (end == s || !isfinite(v[n])) {
                /* what was found, printable (a binary file's bytes as ?) */
                char shown[24];
                size_t len = strcspn(s, " \t\r\n,"), k;
                for (k = 0; k < len && k < 20; k++)
                    shown[k] = s[k] >= 0x20 && s[k] < 0x7f ? s[k] : '?';
                shown[k] = 0;
                st = tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: expected a number, found '%s'", path, lineno, shown);
                goto done;
            }
            if (fabs(v[n]) > 1e15) { /* cameras are floats on the GPU */
                st = tsr_error_set(err, TSR_ERR_VALUE, "%s:%u: %g is beyond 1e15 world units", path, lineno, v[n]);
                goto done;
            }
            n++;
            s = end;
        }
        if (n == 0)
            continue;
        if (n != 3 && n != 6) {
            st = tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: a keyframe is 3 numbers (eye) or 6 (eye, target), found %d%s",
                               path, lineno, n, n == 7 ? " or more" : "");
            goto done;
        }
        if (per_line && n != per_line) {
            st = tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: %d numbers, but earlier keyframes have %d", path, lineno, n,
                               per_line);
            goto done;
        }
        per_line = n;
        if (p->count >= 1000000 || !path_grow(p, &cap, n == 6)) {
            st = tsr_error_set(err, TSR_ERR_NOMEM, "%s:%u: too many keyframes", path, lineno);
            goto done;
        }
        memcpy(p->eye[p->count], v, sizeof p->eye[0]);
        if (n == 6) {
            memcpy(p->target[p->count], v + 3, sizeof p->target[0]);
            if (v[0] == v[3] && v[1] == v[4] && v[2] == v[5]) {
                st = tsr_error_set(err, TSR_ERR_VALUE, "%s:%u: the target is the eye", path, lineno);
                goto done;
            }
        }
        p->count++;
    }
    if (ferror(fp))
        st = tsr_error_set(err, TSR_ERR_IO, "%s: read error", path);
    else if (p->count == 0)
        st = tsr_error_set(err, TSR_ERR_EMPTY, "%s: no keyframes (one per line: EX EY EZ [TX TY TZ])", path);
done:
    fclose(fp);
    if (st != TSR_OK)
        fly_path_free(p);
    return st;
}

tsr_status fly_path_auto(const fly_ctx *f, fly_path *p, tsr_error *err)
{
    memset(p, 0, sizeof *p);
    enum { K = 12 };
    p->eye = malloc(K * sizeof *p->eye);
    if (!p->eye)
        return tsr_error_set(err, TSR_ERR_NOMEM, "out of memory");
    double sx = (tsr_heightfield_width(f->hf) - 1) * f->dx, sy = (tsr_heightfield_height(f->hf) - 1) * f->dy;
    double relief = f->zmax - f->zmin > 1e-6 ? f->zmax - f->zmin : 1;
    for (int k = 0; k < K; k++) {
        double a = 2 * M_PI * k / K;
        double x = sx * (0.5 + 0.34 * sin(a)), y = sy * (0.5 + 0.34 * sin(2 * a + 0.7));
        /* the highest ground within a tenth of the extent, sampled */
        double top = -INFINITY, rad = 0.1 * (sx > sy ? sx : sy);
        for (int u = -3; u <= 3; u++)
            for (int v = -3; v <= 3; v++) {
                double g = ground_height(f->terrain, x + u * rad / 3, y + v * rad / 3);
                if (!isnan(g) && g > top)
                    top = g;
            }
        if (!isfinite(top))
            top = f->zmax;
        p->eye[k][0] = x;
        p->eye[k][1] = y;
        p->eye[k][2] = top + 0.2 * relief;
    }
    p->count = K;
    p->closed = true;
    return TSR_OK;
}

/* Keyframe m of n: wrapped around a closed path, clamped on an open one. */
static uint32_t wrap(int64_t m, uint32_t n, bool closed)
{
    if (closed)
        return (uint32_t)((m % n + n) % n);
    return (uint32_t)(m < 0 ? 0 : m >= n ? n - 1 : m);
}

static void catmull_rom(const double (*pts)[3], uint32_t n, bool closed, double s, double out[3], double tan[3])
{
    uint32_t segs = closed ? n : n - 1;
    double u = s * segs;
    uint32_t k = (uint32_t)u;
    if (k >= segs)
        k = segs - 1;
    double t = u - k;
    const double *p0 = pts[wrap((int64_t)k - 1, n, closed)], *p1 = pts[wrap(k, n, closed)];
    const double *p2 = pts[wrap((int64_t)k + 1, n, closed)], *p3 = pts[wrap((int64_t)k + 2, n, closed)];
    double t2 = t * t, t3 = t2 * t;
    for (int c = 0; c < 3; c++) {
        out[c] = 0.5 * (2 * p1[c] + (-p0[c] + p2[c]) * t + (2 * p0[c] - 5 * p1[c] + 4 * p2[c] - p3[c]) * t2 +
                        (-p0[c] + 3 * p1[c] - 3 * p2[c] + p3[c]) * t3);
        if (tan)
            tan[c] = 0.5 * ((-p0[c] + p2[c]) + 2 * (2 * p0[c] - 5 * p1[c] + 4 * p2[c] - p3[c]) * t +
                            3 * (-p0[c] + 3 * p1[c] - 3 * p2[c] + p3[c]) * t2);
    }
}

bool fly_path_camera(const fly_ctx *f, const fly_path *p, double s, double clearance, tsr_camera *cam,
                     bool *lifted)
{
    if (p->count < 1)
        return false;
    s = s < 0 ? 0 : s > 1 ? 1 : s;
    double eye[3], tan[3], target[3];
    bool still = p->count == 1;
    if (still) {
        /* a still camera: toward its target, else the terrain's centre */
        memcpy(eye, p->eye[0], sizeof eye);
        double w = (tsr_heightfield_width(f->hf) - 1) * f->dx, h = (tsr_heightfield_height(f->hf) - 1) * f->dy;
        double centre[3] = {0.5 * w, 0.5 * h, 0.5 * (f->zmin + f->zmax)};
        memcpy(target, p->target ? p->target[0] : centre, sizeof target);
    } else {
        catmull_rom((const double(*)[3])p->eye, p->count, p->closed, s, eye, tan);
    }
    double g = ground_height(f->terrain, eye[0], eye[1]);
    bool low = !isnan(g) && eye[2] < g + clearance;
    if (low)
        eye[2] = g + clearance;
    if (lifted)
        *lifted = low;
    if (!still && p->target) {
        catmull_rom((const double(*)[3])p->target, p->count, p->closed, s, target, NULL);
    } else if (!still) {
        double l = hypot(tan[0], tan[1]);
        if (l == 0) {
            tan[0] = 1;
            tan[1] = 0;
            l = 1;
        }
        /* look along the path, a little down */
        target[0] = eye[0] + tan[0] / l;
        target[1] = eye[1] + tan[1] / l;
        target[2] = eye[2] - 0.3;
    }
    return fly_camera(f, eye, target, cam);
}
