/* camera.c: camera placement over a terrain for the tools. */
#include "camera.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

double ground_height(const tsr_terrain *t, double x, double y)
{
    const tsr_heightfield *hf = tsr_terrain_heightfield(t);
    double dz;
    tsr_heightfield_spacing(hf, NULL, NULL, &dz);
    float mn, mx;
    tsr_qnode root = {0, 0, 0};
    tsr_terrain_node_range(t, root, &mn, &mx);
    double o[3] = {x, y, mx * dz + 1}, d[3] = {0, 0, -1}, th;
    if (!tsr_terrain_pick(t, o, d, &th))
        return NAN;
    return o[2] - th;
}

static double urand(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(*s >> 11) * (1.0 / 9007199254740992.0);
}

static void setup(tsr_camera *c, const view_options *v)
{
    c->fovy_deg = v->fovy_deg;
    c->width = v->width;
    c->height = v->height;
    c->near_dist = v->near_dist;
    c->pixel_error = v->pixel_error;
}

static void extent(const tsr_terrain *t, double *sx, double *sy, double *zmin, double *zmax)
{
    const tsr_heightfield *hf = tsr_terrain_heightfield(t);
    double dx, dy, dz;
    tsr_heightfield_spacing(hf, &dx, &dy, &dz);
    *sx = (tsr_heightfield_width(hf) - 1) * dx;
    *sy = (tsr_heightfield_height(hf) - 1) * dy;
    float mn, mx;
    tsr_qnode root = {0, 0, 0};
    tsr_terrain_node_range(t, root, &mn, &mx);
    *zmin = mn * dz;
    *zmax = mx * dz;
}

double terrain_unit(const tsr_terrain *t)
{
    double sx, sy, zmin, zmax;
    extent(t, &sx, &sy, &zmin, &zmax);
    double size = fmax(fmax(sx, sy), zmax - zmin);
    return size > 0 && 1e-3 * size < 1 ? 1e-3 * size : 1;
}

void random_camera(const tsr_terrain *t, uint64_t *rng, int index, const view_options *v, tsr_camera *c)
{
    double sx, sy, zmin, zmax;
    extent(t, &sx, &sy, &zmin, &zmax);
    double relief = zmax - zmin > 1e-6 ? zmax - zmin : 1, unit = terrain_unit(t);
    for (int tries = 0; tries < 1000; tries++) {
        memset(c, 0, sizeof *c);
        setup(c, v);
        bool low = index % 3 == 0;
        c->eye[0] = urand(rng) * sx;
        c->eye[1] = urand(rng) * sy;
        double g = ground_height(t, c->eye[0], c->eye[1]);
        if (isnan(g))
            g = zmax;
        double alt = low ? 2 * unit + urand(rng) * 0.02 * relief
                         : 0.05 * relief + urand(rng) * (relief + 0.3 * (sx > sy ? sx : sy));
        c->eye[2] = g + alt;
        double yaw = urand(rng) * 6.283185307179586;
        double pitch = low ? -(0.005 + urand(rng) * 0.1) : -(0.05 + urand(rng) * 1.3);
        c->target[0] = c->eye[0] + cos(yaw) * cos(pitch);
        c->target[1] = c->eye[1] + sin(yaw) * cos(pitch);
        c->target[2] = c->eye[2] + sin(pitch);
        if (tsr_camera_prepare(c))
            return;
    }
}

void flight_camera(const tsr_terrain *t, int f, int n, const view_options *v, tsr_camera *c)
{
    double sx, sy, zmin, zmax;
    extent(t, &sx, &sy, &zmin, &zmax);
    double relief = zmax - zmin > 1e-6 ? zmax - zmin : 1;
    double a = 6.283185307179586 * f / n, a2 = 6.283185307179586 * (f + 1) / n;
    double px = sx * (0.5 + 0.35 * sin(a)), py = sy * (0.5 + 0.35 * sin(2 * a + 0.7));
    double qx = sx * (0.5 + 0.35 * sin(a2)), qy = sy * (0.5 + 0.35 * sin(2 * a2 + 0.7));
    memset(c, 0, sizeof *c);
    setup(c, v);
    double g = ground_height(t, px, py);
    if (isnan(g))
        g = zmax;
    c->eye[0] = px;
    c->eye[1] = py;
    c->eye[2] = g + 0.08 * relief + 20 * terrain_unit(t);
    double hx = qx - px, hy = qy - py, hl = hypot(hx, hy);
    if (hl == 0) {
        hx = 1;
        hl = 1;
    }
    c->target[0] = px + hx / hl;
    c->target[1] = py + hy / hl;
    c->target[2] = c->eye[2] - 0.25;
    tsr_camera_prepare(c);
}

int view_option(const char *cmd, const char *a, const char *value, view_options *v)
{
    double *dst = !strcmp(a, "--pixel-error") ? &v->pixel_error
                  : !strcmp(a, "--width")     ? &v->width
                  : !strcmp(a, "--height")    ? &v->height
                  : !strcmp(a, "--fov")       ? &v->fovy_deg
                  : !strcmp(a, "--near")      ? &v->near_dist
                                              : NULL;
    if (!dst || !value)
        return 0; /* a missing value is the caller's "missing value" error */
    double d;
    bool fov = dst == &v->fovy_deg;
    if (!cli_parse_double(value, &d) || !(d > 0) || (fov && d >= 179)) {
        cli_error(cmd, "%s %s: must be a positive number%s", a, value, fov ? " below 179" : "");
        return -1;
    }
    *dst = d;
    return 1;
}

bool parse_camera(const char *s, const view_options *v, tsr_camera *c)
{
    double x[6];
    char *end;
    const char *p = s;
    for (int k = 0; k < 6; k++) {
        x[k] = strtod(p, &end);
        if (end == p || !isfinite(x[k]))
            return false;
        p = end;
        if (k < 5) {
            if (*p != ',')
                return false;
            p++;
        }
    }
    if (*p != '\0')
        return false;
    memset(c, 0, sizeof *c);
    setup(c, v);
    memcpy(c->eye, x, sizeof c->eye);
    memcpy(c->target, x + 3, sizeof c->target);
    return tsr_camera_prepare(c);
}
