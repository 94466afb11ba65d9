/* test_ptess.c: adaptive, crack-free tessellation of patches (patches/ptess.h),
 * each property against an oracle written here, never against numbers
 * taken from the code under test:
 *  - surfaces whose Bézier / NURBS form is exact, written as OBJ free-form
 *    text: a tilted plane (a parallelogram, which any tessellation meshes
 *    exactly, and a planar trapezoid, bilinear in (u, v)), a quarter
 *    cylinder and a sphere octant (rational quadratic arcs), the full
 *    sphere from eight octants, mirrored, reversed and transposed, and a
 *    bicubic B-spline of several knot spans. The oracle is the closed form
 *    of the rational quadratic circle, x = ((1-t)^2 + sqrt2 t(1-t)) / D,
 *    y = (sqrt2 t(1-t) + t^2) / D, D = (1-t)^2 + sqrt2 t(1-t) + t^2, and a
 *    de Boor evaluation written here: every triangle is sampled at a
 *    barycentric lattice (corners, edge midpoints and, but for the big
 *    teapot meshes, the centroid included),
 *    its (u, v) interpolated from tri_uv and its point from the mesh's
 *    positions, and compared with the closed form at that (u, v) (the
 *    parametric error ptess.h bounds) and with the implicit surface
 *    (distance to the axis, |p| = 1);
 *  - the welded mesh through tsr_mesh_validate: closed, conforming,
 *    oriented, Euler characteristic, signed volume against 4/3 pi;
 *  - view dependence: screen error by projecting the closed form and the
 *    mesh point, and the near part denser than the far part;
 *  - data: the Utah teapot against tsr_patch_eval, its open rims found by
 *    matching control rows here; OpenSubdiv cages against tsr_subd_eval,
 *    re-tessellated with piece_scale as the contract says the tool does;
 *  - the contract's refusals.
 * The mesh stores float positions, so "exact" means within a few float
 * ulps of the model's size (fslack below). */
#include "check.h"
#include "patches/ptess.h"

#include <float.h>
#include <stdarg.h>
#include <threads.h>

static const double PI = 3.14159265358979323846;
static const double H2 = 0.70710678118654752440; /* sqrt(2) / 2, the middle weight of a quarter circle */

/* ---- text buffers ------------------------------------------------------------ */

typedef struct sbuf {
    char *s;
    size_t n, cap;
} sbuf;

static void sb_printf(sbuf *b, const char *fmt, ...)
{
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int k = vsnprintf(b->s ? b->s + b->n : NULL, b->s ? b->cap - b->n : 0, fmt, ap);
        va_end(ap);
        if (k < 0)
            abort();
        if (b->s && b->n + (size_t)k < b->cap) {
            b->n += (size_t)k;
            return;
        }
        size_t cap = (b->cap + (size_t)k + 1) * 2;
        char *s = realloc(b->s, cap);
        if (!s)
            abort();
        b->s = s;
        b->cap = cap;
    }
}

/* ---- closed forms --------------------------------------------------------------- */

/* The rational quadratic quarter circle from (1, 0) to (0, 1), control
 * points (1, 0), (1, 1), (0, 1) with weights 1, sqrt2/2, 1. */
static void qcircle(double t, double *x, double *y)
{
    double a = (1 - t) * (1 - t), b = 2 * t * (1 - t) * H2, c = t * t, d = a + b + c;
    *x = (a + b) / d;
    *y = (b + c) / d;
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static double dist3(const double a[3], const double b[3])
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/* B-spline basis functions of degree deg at u (The NURBS Book, A2.1 and
 * A2.2): N[0..deg] are those of points span-deg .. span; returns span. */
static int bspline_basis(const double *kn, int count, int deg, double u, double *N)
{
    int span = deg;
    if (u >= kn[count])
        span = count - 1;
    else
        while (span + 1 < count && kn[span + 1] <= u)
            span++;
    double left[8], right[8];
    N[0] = 1;
    for (int j = 1; j <= deg; j++) {
        left[j] = u - kn[span + 1 - j];
        right[j] = kn[span + j] - u;
        double saved = 0;
        for (int r = 0; r < j; r++) {
            double t = N[r] / (right[r + 1] + left[j - r]);
            N[r] = saved + right[r + 1] * t;
            saved = left[j - r] * t;
        }
        N[j] = saved;
    }
    return span;
}

/* ---- models and results ------------------------------------------------------- */

static bool parse_set(const sbuf *text, const char *name, tsr_patch_set *set)
{
    tsr_error e = {0};
    tsr_status st = tsr_patch_set_parse(text->s, text->n, name, TSR_PATCH_FORMAT_OBJ, NULL, set, &e);
    CHECK_MSG(st == TSR_OK, "%s: %s", name, e.message);
    return st == TSR_OK;
}

static bool make_model(const tsr_patch_set *set, tsr_pmodel **m)
{
    tsr_error e = {0};
    *m = NULL;
    tsr_status st = tsr_pmodel_from_set(set, NULL, m, &e);
    CHECK_MSG(st == TSR_OK && *m, "tsr_pmodel_from_set: %s (%s)", tsr_status_str(st), e.message);
    return st == TSR_OK && *m;
}

static bool run_ptess(const tsr_pmodel *m, const tsr_ptess_options *o, tsr_ptess_result *r)
{
    tsr_error e = {0};
    tsr_status st = tsr_ptess_run(m, o, NULL, r, &e);
    CHECK_MSG(st == TSR_OK, "tsr_ptess_run: %s (%s)", tsr_status_str(st), e.message);
    if (st == TSR_OK)
        CHECK(r->mesh.triangle_count > 0 && r->tri_source && r->tri_uv);
    return st == TSR_OK && r->mesh.triangle_count > 0 && r->tri_source && r->tri_uv;
}

/* The largest absolute coordinate of the mesh. */
static double mesh_maxabs(const tsr_mesh *m)
{
    double a = 0;
    for (uint32_t k = 0; k < 3 * m->vertex_count; k++)
        a = fmax(a, fabs((double)m->positions[k]));
    return a;
}

/* Float rounding of positions of magnitude up to maxabs, with room for
 * the interpolation: a few ulps. */
static double fslack(double maxabs)
{
    return 8 * FLT_EPSILON * maxabs;
}

/* Checks what every result must satisfy: indices in range, sources in
 * range, (u, v) in the source's domain, normals when asked. */
static void check_shape(const tsr_pmodel *m, const tsr_ptess_result *r, bool normals)
{
    tsr_pmodel_info info;
    tsr_pmodel_get_info(m, &info);
    const tsr_mesh *me = &r->mesh;
    uint32_t bad_index = 0, bad_source = 0, bad_uv = 0;
    for (uint32_t t = 0; t < me->triangle_count; t++) {
        for (int k = 0; k < 3; k++)
            bad_index += me->indices[3 * t + k] >= me->vertex_count;
        uint32_t s = r->tri_source[t];
        tsr_psource_info si;
        if (s >= info.sources || !tsr_pmodel_source_info(m, s, &si)) {
            bad_source++;
            continue;
        }
        double du = 1e-12 * (si.domain[1] - si.domain[0]), dv = 1e-12 * (si.domain[3] - si.domain[2]);
        for (int k = 0; k < 3; k++) {
            double u = r->tri_uv[6 * t + 2 * k], v = r->tri_uv[6 * t + 2 * k + 1];
            bad_uv +=
                !(u >= si.domain[0] - du && u <= si.domain[1] + du && v >= si.domain[2] - dv && v <= si.domain[3] + dv);
        }
    }
    CHECK_MSG(bad_index == 0, "%u indices out of range", bad_index);
    CHECK_MSG(bad_source == 0, "%u triangles name no source", bad_source);
    CHECK_MSG(bad_uv == 0, "%u triangle corners outside their source's domain", bad_uv);
    CHECK(normals == (me->normals != NULL));
}

/* ---- sampling every triangle ------------------------------------------------------ */

/* The true surface of source src at n parameter pairs uv: positions. */
typedef void (*truth_fn)(void *ctx, uint32_t src, const double *uv, uint32_t n, double *pos);

typedef struct sampling {
    truth_fn truth;
    void *ctx;
    /* optional: distance of a point from the implicit surface */
    double (*implicit)(void *ctx, const double q[3]);
    /* optional: pixel error instead of (beside) model units */
    const tsr_camera *camera;
    /* optional: per source maximum of the parametric error */
    double *source_error;
    /* the barycentric lattice i + j + k = lat, 2..6 (0: 6, 28 points with
     * the corners, edge midpoints and centroid; 4: 15 points, the corners
     * and edge midpoints) */
    int lat;
    /* results */
    double param_error;    /* max |S(u, v) - mesh(u, v)| */
    double implicit_error; /* max implicit distance of mesh points */
    double corner_error;   /* max |S(u, v) - vertex| at triangle corners */
    double pixel_error;    /* max screen distance, samples in view */
    uint64_t samples, in_view;
    uint32_t worst_tri;
    double worst_uv[2];
} sampling;

static void project(const tsr_camera *c, const double p[3], double *x, double *y, double *depth)
{
    double d[3] = {p[0] - c->eye[0], p[1] - c->eye[1], p[2] - c->eye[2]};
    double r = dot3(d, c->right), u = dot3(d, c->up), f = dot3(d, c->fwd);
    *depth = f;
    *x = c->width / 2 + c->K * r / f;
    *y = c->height / 2 - c->K * u / f;
}

static void sample_result(const tsr_ptess_result *r, sampling *s)
{
    const tsr_mesh *m = &r->mesh;
    double uv[2 * 28], pos[3 * 28], q[3 * 28], lam[3 * 28];
    uint32_t n = 0;
    int lat = s->lat >= 2 && s->lat <= 6 ? s->lat : 6;
    for (int i = 0; i <= lat; i++)
        for (int j = 0; j + i <= lat; j++) {
            lam[3 * n] = (double)i / lat;
            lam[3 * n + 1] = (double)j / lat;
            lam[3 * n + 2] = (double)(lat - i - j) / lat;
            n++;
        }
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *ix = m->indices + 3 * t;
        if (ix[0] >= m->vertex_count || ix[1] >= m->vertex_count || ix[2] >= m->vertex_count)
            continue;
        const double *tuv = r->tri_uv + 6 * t;
        for (uint32_t k = 0; k < n; k++) {
            const double *l = lam + 3 * k;
            uv[2 * k] = l[0] * tuv[0] + l[1] * tuv[2] + l[2] * tuv[4];
            uv[2 * k + 1] = l[0] * tuv[1] + l[1] * tuv[3] + l[2] * tuv[5];
            for (int c = 0; c < 3; c++)
                q[3 * k + c] = l[0] * m->positions[3 * ix[0] + c] + l[1] * m->positions[3 * ix[1] + c] +
                               l[2] * m->positions[3 * ix[2] + c];
        }
        s->truth(s->ctx, r->tri_source[t], uv, n, pos);
        for (uint32_t k = 0; k < n; k++) {
            double e = dist3(pos + 3 * k, q + 3 * k);
            bool corner = lam[3 * k] == 1 || lam[3 * k + 1] == 1 || lam[3 * k + 2] == 1;
            if (corner)
                s->corner_error = fmax(s->corner_error, e);
            if (e > s->param_error) {
                s->param_error = e;
                s->worst_tri = t;
                s->worst_uv[0] = uv[2 * k];
                s->worst_uv[1] = uv[2 * k + 1];
            }
            if (s->source_error)
                s->source_error[r->tri_source[t]] = fmax(s->source_error[r->tri_source[t]], e);
            if (s->implicit)
                s->implicit_error = fmax(s->implicit_error, s->implicit(s->ctx, q + 3 * k));
            if (s->camera) {
                double px, py, pd, qx, qy, qd;
                project(s->camera, pos + 3 * k, &px, &py, &pd);
                project(s->camera, q + 3 * k, &qx, &qy, &qd);
                bool inside_p = px >= 0 && px <= s->camera->width && py >= 0 && py <= s->camera->height;
                bool inside_q = qx >= 0 && qx <= s->camera->width && qy >= 0 && qy <= s->camera->height;
                if (pd > s->camera->near_dist && qd > s->camera->near_dist && (inside_p || inside_q)) {
                    s->pixel_error = fmax(s->pixel_error, hypot(px - qx, py - qy));
                    s->in_view++;
                }
            }
            s->samples++;
        }
    }
}

/* After a refusal the result must be zeroed (so freeing it is safe):
 * checked, and freed only when it is. */
static void check_zeroed_and_free(tsr_ptess_result *r, const char *what)
{
    bool zeroed = r->mesh.triangle_count == 0 && r->mesh.vertex_count == 0 && r->mesh.positions == NULL &&
                  r->mesh.indices == NULL && r->mesh.normals == NULL && r->tri_source == NULL && r->tri_uv == NULL;
    CHECK_MSG(zeroed, "%s: the result is not zeroed after a refusal", what);
    if (zeroed)
        tsr_ptess_result_free(r);
}

static tsr_validation validate(const tsr_mesh *m)
{
    tsr_validation v;
    memset(&v, 0, sizeof v);
    CHECK(tsr_mesh_validate(m, NULL, &v) == TSR_OK);
    return v;
}

static void describe(const char *what, const tsr_validation *v)
{
    char buf[1024];
    tsr_validation_describe(v, buf, sizeof buf);
    fprintf(stderr, "  %s: V %u E %u F %u euler %lld boundary %u loops %u: %s\n", what, v->vertices, v->edges,
            v->triangles, (long long)v->euler, v->boundary_edges, v->boundary_loops, buf);
}

/* The conformity every tessellation promises: oriented, edge-manifold,
 * no T-junction, nothing degenerate or repeated. */
static void check_conforming(const char *what, const tsr_validation *v)
{
    CHECK_MSG(v->bad_indices == 0 && v->nonfinite_positions == 0, "%s", what);
    CHECK_MSG(v->degenerate_triangles == 0, "%s: %u degenerate triangles, first %u", what, v->degenerate_triangles,
              v->first_degenerate);
    CHECK_MSG(v->duplicate_triangles == 0, "%s: %u duplicate triangles", what, v->duplicate_triangles);
    CHECK_MSG(v->nonmanifold_edges == 0, "%s: %u non-manifold edges", what, v->nonmanifold_edges);
    CHECK_MSG(v->misoriented_edges == 0, "%s: %u misoriented edges", what, v->misoriented_edges);
    CHECK_MSG(v->t_junctions == 0, "%s: %u T-junctions, first vertex %u on edge %u-%u", what, v->t_junctions,
              v->first_t_junction[0], v->first_t_junction[1], v->first_t_junction[2]);
}

static double signed_volume(const tsr_mesh *m)
{
    double vol = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        double p[3][3];
        for (int k = 0; k < 3; k++)
            for (int c = 0; c < 3; c++)
                p[k][c] = m->positions[3 * m->indices[3 * t + k] + c];
        double x[3];
        cross3(p[1], p[2], x);
        vol += dot3(p[0], x) / 6;
    }
    return vol;
}

static void face_normal(const tsr_mesh *m, uint32_t t, double n[3])
{
    double p[3][3];
    for (int k = 0; k < 3; k++)
        for (int c = 0; c < 3; c++)
            p[k][c] = m->positions[3 * m->indices[3 * t + k] + c];
    double a[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
    double b[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    cross3(a, b, n);
}

/* Vertex normals: unit, and on the side the triangles face. Returns the
 * number of corners whose normal opposes its triangle. */
static uint32_t check_normals_agree(const tsr_mesh *m, const char *what)
{
    uint32_t not_unit = 0, opposed = 0;
    if (!m->normals)
        return 0;
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        const float *n = m->normals + 3 * v;
        not_unit += fabs(sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]) - 1) > 1e-5;
    }
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        double fn[3];
        face_normal(m, t, fn);
        for (int k = 0; k < 3; k++) {
            const float *n = m->normals + 3 * m->indices[3 * t + k];
            double nd[3] = {n[0], n[1], n[2]};
            opposed += dot3(nd, fn) <= 0;
        }
    }
    CHECK_MSG(not_unit == 0, "%s: %u normals not of unit length", what, not_unit);
    CHECK_MSG(opposed == 0, "%s: %u corners whose normal opposes the triangle's winding", what, opposed);
    return opposed;
}

/* ---- the plane -------------------------------------------------------------------- */

/* A tilted frame: origin o, orthonormal e1, e2, normal n = e1 x e2. */
static const double plane_o[3] = {1, -2, 0.5};
static const double plane_e1[3] = {2.0 / 3, 1.0 / 3, 2.0 / 3};
static const double plane_e2[3] = {-0.44721359549995794, 0.89442719099991588, 0}; /* (-1, 2, 0) / sqrt5 */

static void plane_point(double a, double b, double p[3])
{
    for (int c = 0; c < 3; c++)
        p[c] = plane_o[c] + a * plane_e1[c] + b * plane_e2[c];
}

/* Corners in the plane's (a, b): a bilinear patch over them. */
typedef struct quad4 {
    double a[4], b[4]; /* (0,0), (1,0), (0,1), (1,1) */
} quad4;

static void quad_truth(void *ctx, uint32_t src, const double *uv, uint32_t n, double *pos)
{
    const quad4 *q = ctx;
    (void)src;
    for (uint32_t k = 0; k < n; k++) {
        double u = uv[2 * k], v = uv[2 * k + 1];
        double w[4] = {(1 - u) * (1 - v), u * (1 - v), (1 - u) * v, u * v};
        double a = 0, b = 0;
        for (int c = 0; c < 4; c++) {
            a += w[c] * q->a[c];
            b += w[c] * q->b[c];
        }
        plane_point(a, b, pos + 3 * k);
    }
}

static double plane_distance(void *ctx, const double q[3])
{
    (void)ctx;
    double n[3], d[3] = {q[0] - plane_o[0], q[1] - plane_o[1], q[2] - plane_o[2]};
    cross3(plane_e1, plane_e2, n);
    return fabs(dot3(d, n));
}

static void quad_obj(sbuf *b, const quad4 *q)
{
    for (int c = 0; c < 4; c++) {
        double p[3];
        plane_point(q->a[c], q->b[c], p);
        sb_printf(b, "v %.17g %.17g %.17g\n", p[0], p[1], p[2]);
    }
    sb_printf(b, "cstype bezier\ndeg 1 1\nsurf 0 1 0 1 -4 -3 -2 -1\nend\n");
}

/* A parallelogram is linear in (u, v): the root tile of every tile size
 * is exact, so one leaf, tile_n^2 quads, a zero bound. */
TEST(plane_parallelogram_exact)
{
    quad4 q = {{0, 3, 0.8, 3.8}, {0, 0, 1.3, 1.3}};
    sbuf b = {0};
    quad_obj(&b, &q);
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(&b, "parallelogram.obj", &set)) {
        free(b.s);
        return;
    }
    if (make_model(&set, &m)) {
        tsr_pmodel_info info;
        tsr_pmodel_get_info(m, &info);
        CHECK(info.sources == 1 && info.pieces == 1 && info.links == 0 && info.collapsed_edges == 0 &&
              info.mirrored == 0 && info.trimmed_sources == 0);
        /* (tile 128 and depth 12: half tiles where no larger tile or no
         * deeper level is allowed) */
        const uint32_t tiles[] = {2, 4, 8, 16, 128};
        for (int ti = 0; ti < 6; ti++)
            for (double E = 1e-1; E >= 1e-6; E /= 100) {
                tsr_ptess_options o = {0};
                o.max_error = E;
                o.tile_n = tiles[ti < 5 ? ti : 1];
                o.max_level = ti < 5 ? 0 : 12;
                tsr_ptess_result r;
                if (run_ptess(m, &o, &r)) {
                    check_shape(m, &r, false);
                    CHECK_MSG(r.leaves == 1, "tile %u E %g: %u leaves for a linear patch", o.tile_n, E, r.leaves);
                    /* one tile, of half the size where half is even (a
                     * plane passes at any size: choose_tile's half tiles) */
                    uint32_t n = o.tile_n, t = n / 2 >= 2 && !(n / 2 & 1) ? n / 2 : n;
                    CHECK_MSG(r.mesh.triangle_count == 2 * t * t, "tile %u max level %u: %u triangles", n, o.max_level,
                              r.mesh.triangle_count);
                    CHECK_MSG(r.bound <= 1e-12 * 4, "bound %g", r.bound);
                    sampling s = {quad_truth, &q, plane_distance, NULL, NULL, 0, 0, 0, 0, 0, 0, 0, 0, {0, 0}};
                    sample_result(&r, &s);
                    double sl = fslack(mesh_maxabs(&r.mesh));
                    CHECK_MSG(s.implicit_error <= sl, "off the plane by %g", s.implicit_error);
                    CHECK_MSG(s.param_error <= sl, "parametric error %g", s.param_error);
                    tsr_validation v = validate(&r.mesh);
                    check_conforming("parallelogram", &v);
                    CHECK(v.boundary_loops == 1 && v.euler == 1);
                }
                tsr_ptess_result_free(&r);
            }
        /* the measurement agrees */
        tsr_ptess_options o = {0};
        o.max_error = 1e-3;
        tsr_ptess_result r;
        if (run_ptess(m, &o, &r)) {
            tsr_ptess_measure_result mr;
            memset(&mr, 0, sizeof mr);
            CHECK(tsr_ptess_measure(m, &r, 9, NULL, false, NULL, &mr) == TSR_OK);
            CHECK_MSG(mr.max_error <= fslack(5), "measured %g", mr.max_error);
            CHECK(mr.uncovered == 0 && mr.samples >= 81);
        }
        tsr_ptess_result_free(&r);
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* A planar trapezoid is bilinear in (u, v): every point stays in the
 * plane whatever the tessellation, and the parametric error is bounded. */
TEST(plane_trapezoid_bilinear)
{
    quad4 q = {{0, 3, 0.4, 2.1}, {0, 0, 1.3, 1.6}};
    sbuf b = {0};
    quad_obj(&b, &q);
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(&b, "trapezoid.obj", &set)) {
        free(b.s);
        return;
    }
    if (make_model(&set, &m)) {
        for (double E = 1e-1; E >= 1e-4; E /= 10) {
            tsr_ptess_options o = {0};
            o.max_error = E;
            o.normals = true;
            tsr_ptess_result r;
            if (run_ptess(m, &o, &r)) {
                check_shape(m, &r, true);
                sampling s = {quad_truth, &q, plane_distance, NULL, NULL, 0, 0, 0, 0, 0, 0, 0, 0, {0, 0}};
                sample_result(&r, &s);
                double sl = fslack(mesh_maxabs(&r.mesh));
                CHECK_MSG(s.implicit_error <= sl, "E %g: off the plane by %g", E, s.implicit_error);
                CHECK_MSG(s.param_error <= E + sl, "E %g: parametric error %g at (%g, %g)", E, s.param_error,
                          s.worst_uv[0], s.worst_uv[1]);
                CHECK_MSG(s.param_error <= r.bound + sl, "E %g: error %g beyond the reported bound %g", E,
                          s.param_error, r.bound);
                CHECK_MSG(r.bound <= E, "bound %g > E %g", r.bound, E);
                CHECK_MSG(s.corner_error <= sl, "corner error %g", s.corner_error);
                /* the true normal of a plane is its normal */
                double n[3];
                cross3(plane_e1, plane_e2, n);
                uint32_t off = 0;
                for (uint32_t v = 0; v < r.mesh.vertex_count; v++) {
                    const float *vn = r.mesh.normals + 3 * v;
                    double c = vn[0] * n[0] + vn[1] * n[1] + vn[2] * n[2];
                    if (fabs(c - 1) > 1e-6 && off++ == 0)
                        fprintf(stderr, "  vertex %u (%g %g %g): normal (%g %g %g), want (%g %g %g)\n", v,
                                r.mesh.positions[3 * v], r.mesh.positions[3 * v + 1], r.mesh.positions[3 * v + 2],
                                vn[0], vn[1], vn[2], n[0], n[1], n[2]);
                }
                CHECK_MSG(off == 0, "%u normals off the plane's normal", off);
                tsr_validation v = validate(&r.mesh);
                check_conforming("trapezoid", &v);
                CHECK(v.boundary_loops == 1 && v.euler == 1);
            }
            tsr_ptess_result_free(&r);
        }
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* ---- the quarter cylinder ----------------------------------------------------------- */

typedef struct cylinder {
    double cx, cy, z0, R, H;
} cylinder;

static void cyl_truth(void *ctx, uint32_t src, const double *uv, uint32_t n, double *pos)
{
    const cylinder *c = ctx;
    (void)src;
    for (uint32_t k = 0; k < n; k++) {
        double x, y;
        qcircle(uv[2 * k], &x, &y);
        pos[3 * k] = c->cx + c->R * x;
        pos[3 * k + 1] = c->cy + c->R * y;
        pos[3 * k + 2] = c->z0 + c->H * uv[2 * k + 1];
    }
}

static double cyl_distance(void *ctx, const double q[3])
{
    const cylinder *c = ctx;
    return fabs(hypot(q[0] - c->cx, q[1] - c->cy) - c->R);
}

static void cyl_obj(sbuf *b, const cylinder *c)
{
    const double A[3][2] = {{1, 0}, {1, 1}, {0, 1}}, w[3] = {1, H2, 1};
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 3; i++)
            sb_printf(b, "v %.17g %.17g %.17g %.17g\n", c->cx + c->R * A[i][0], c->cy + c->R * A[i][1],
                      c->z0 + c->H * j, w[i]);
    sb_printf(b, "cstype rat bezier\ndeg 2 1\nsurf 0 1 0 1 -6 -5 -4 -3 -2 -1\nend\n");
}

TEST(quarter_cylinder_error)
{
    cylinder c = {0.5, -1.25, 0.25, 2, 3};
    sbuf b = {0};
    cyl_obj(&b, &c);
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(&b, "cylinder.obj", &set)) {
        free(b.s);
        return;
    }
    check_alloc lc = {0};
    tsr_allocator al = {check_realloc, &lc, NULL};
    tsr_error e = {0};
    tsr_status st = tsr_pmodel_from_set(&set, &al, &m, &e);
    CHECK_MSG(st == TSR_OK && m, "%s", e.message);
    if (st == TSR_OK && m) {
        tsr_pmodel_info info;
        tsr_pmodel_get_info(m, &info);
        CHECK(info.sources == 1 && info.pieces == 1 && info.links == 0 && info.collapsed_edges == 0);
        CHECK_NEAR(info.lo[0], c.cx, 1e-12);
        CHECK_NEAR(info.hi[0], c.cx + c.R, 1e-12);
        CHECK_NEAR(info.lo[2], c.z0, 1e-12);
        CHECK_NEAR(info.hi[2], c.z0 + c.H, 1e-12);
        tsr_psource_info si;
        CHECK(tsr_pmodel_source_info(m, 0, &si));
        CHECK(si.patch == 0 && si.first_piece == 0 && si.pieces_u == 1 && si.pieces_v == 1 && !si.trimmed &&
              !si.mirrored);
        CHECK(si.domain[0] == 0 && si.domain[1] == 1 && si.domain[2] == 0 && si.domain[3] == 1);
        CHECK(!tsr_pmodel_source_info(m, 1, &si));
        /* the source's true surface, against the closed form */
        for (int k = 0; k < 49; k++) {
            double uv[2] = {(k % 7) / 6.0, (k / 7) / 6.0}, want[3], got[3], n[3];
            cyl_truth(&c, 0, uv, 1, want);
            CHECK(tsr_pmodel_eval(m, 0, uv[0], uv[1], got, n) == TSR_OK);
            CHECK(dist3(want, got) <= 1e-12);
            /* outward: du x dv of this net points away from the axis */
            double radial[3] = {want[0] - c.cx, want[1] - c.cy, 0};
            CHECK_NEAR(dot3(n, radial), c.R, 1e-9);
        }
        double pos[3];
        CHECK(tsr_pmodel_eval(m, 1, 0.5, 0.5, pos, NULL) == TSR_ERR_ARGUMENT);

        const uint32_t tiles[] = {2, 4, 8, 16};
        uint32_t prev_tris[4] = {0, 0, 0, 0};
        for (double E = 1e-1; E >= 0.99e-4; E /= 10)
            for (int ti = 0; ti < 4; ti++) {
                tsr_ptess_options o = {0};
                o.max_error = E;
                o.tile_n = tiles[ti];
                o.normals = ti == 1;
                tsr_ptess_result r;
                st = tsr_ptess_run(m, &o, &al, &r, &e);
                CHECK_MSG(st == TSR_OK, "E %g tile %u: %s", E, tiles[ti], e.message);
                if (st == TSR_OK) {
                    check_shape(m, &r, o.normals);
                    sampling s = {cyl_truth, &c, cyl_distance, NULL, NULL, 0, 0, 0, 0, 0, 0, 0, 0, {0, 0}};
                    sample_result(&r, &s);
                    double sl = fslack(mesh_maxabs(&r.mesh));
                    CHECK_MSG(s.param_error <= E + sl, "E %g tile %u: parametric error %g at (%.9g, %.9g)", E,
                              tiles[ti], s.param_error, s.worst_uv[0], s.worst_uv[1]);
                    CHECK_MSG(s.implicit_error <= E + sl, "E %g tile %u: %g off the cylinder", E, tiles[ti],
                              s.implicit_error);
                    CHECK_MSG(s.param_error <= r.bound + sl, "E %g tile %u: error %g beyond the reported bound %g", E,
                              tiles[ti], s.param_error, r.bound);
                    CHECK_MSG(r.bound <= E, "E %g tile %u: bound %g", E, tiles[ti], r.bound);
                    CHECK_MSG(s.corner_error <= sl, "corner error %g", s.corner_error);
                    if (ti == 1)
                        fprintf(stderr, "  E %g tile 4: %u triangles, %u leaves, bound %.3g, sampled error %.3g\n", E,
                                r.mesh.triangle_count, r.leaves, r.bound, s.param_error);
                    CHECK_MSG(r.mesh.triangle_count >= prev_tris[ti], "E %g tile %u: %u triangles, coarser than %u", E,
                              tiles[ti], r.mesh.triangle_count, prev_tris[ti]);
                    prev_tris[ti] = r.mesh.triangle_count;
                    tsr_validation v = validate(&r.mesh);
                    check_conforming("cylinder", &v);
                    CHECK(v.boundary_loops == 1 && v.euler == 1 && v.coincident_vertices == 0);
                    if (o.normals) {
                        /* the true normal: radial, outward */
                        uint32_t off = 0;
                        for (uint32_t k = 0; k < r.mesh.vertex_count; k++) {
                            const float *p = r.mesh.positions + 3 * k, *n = r.mesh.normals + 3 * k;
                            double rx = p[0] - c.cx, ry = p[1] - c.cy, l = hypot(rx, ry);
                            off += (n[0] * rx + n[1] * ry) / l < 1 - 1e-6 || fabs(n[2]) > 1e-3;
                        }
                        CHECK_MSG(off == 0, "%u normals not radial", off);
                    }
                    tsr_ptess_measure_result mr;
                    memset(&mr, 0, sizeof mr);
                    if (ti == 1) {
                        CHECK(tsr_ptess_measure(m, &r, 9, NULL, true, &al, &mr) == TSR_OK);
                        CHECK_MSG(mr.max_error <= E + sl, "E %g: measured %g", E, mr.max_error);
                        CHECK(mr.uncovered == 0 && mr.trimmed_out == 0 && mr.samples >= 81);
                        CHECK(mr.source_error != NULL);
                        if (mr.source_error)
                            CHECK_NEAR(mr.source_error[0], mr.max_error, 0);
                        tsr_free(&al, mr.source_error);
                    }
                }
                tsr_ptess_result_free(&r);
            }
    }
    tsr_pmodel_destroy(m);
    CHECK_MSG(lc.live == 0, "%ld blocks of the allocator not freed", lc.live);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* ---- spheres ---------------------------------------------------------------------- */

/* An octant of the unit sphere: the tensor product of two quarter
 * circles, S(u, v) = (X(u) X(v), Y(u) X(v), Y(v)), pole at v = 1 (a
 * collapsed edge), mirrored by signs, its net optionally reversed along
 * its first index (u -> 1 - u) and then transposed (u <-> v). */
typedef struct octant {
    int sx, sy, sz;
    bool rev, transpose;
} octant;

static void octant_point(const octant *o, double u, double v, double p[3])
{
    if (o->rev)
        u = 1 - u;
    if (o->transpose) {
        double t = u;
        u = v;
        v = t;
    }
    double xu, yu, xv, yv;
    qcircle(u, &xu, &yu);
    qcircle(v, &xv, &yv);
    p[0] = o->sx * xu * xv;
    p[1] = o->sy * yu * xv;
    p[2] = o->sz * yv;
}

static bool octant_outward(const octant *o)
{
    int flips = (o->sx < 0) + (o->sy < 0) + (o->sz < 0) + o->rev + o->transpose;
    return flips % 2 == 0;
}

static void octant_obj(sbuf *b, const octant *o)
{
    const double A[3][2] = {{1, 0}, {1, 1}, {0, 1}}, w[3] = {1, H2, 1};
    for (int j = 0; j < 3; j++)
        for (int i = 0; i < 3; i++) {
            int a = o->rev ? 2 - i : i, c = j;
            if (o->transpose) {
                int t = a;
                a = c;
                c = t;
            }
            /* net point (a, c) of the octant +++ */
            double p[3] = {A[a][0] * A[c][0], A[a][1] * A[c][0], A[c][1]};
            sb_printf(b, "v %.17g %.17g %.17g %.17g\n", o->sx * p[0] + 0.0, o->sy * p[1] + 0.0, o->sz * p[2] + 0.0,
                      w[a] * w[c]);
        }
    sb_printf(b, "cstype rat bezier\ndeg 2 2\nsurf 0 1 0 1 -9 -8 -7 -6 -5 -4 -3 -2 -1\nend\n");
}

typedef struct octants {
    const octant *o;
    uint32_t n;
} octants;

static void octants_truth(void *ctx, uint32_t src, const double *uv, uint32_t n, double *pos)
{
    const octants *os = ctx;
    for (uint32_t k = 0; k < n; k++) {
        if (src < os->n)
            octant_point(&os->o[src], uv[2 * k], uv[2 * k + 1], pos + 3 * k);
        else
            pos[3 * k] = pos[3 * k + 1] = pos[3 * k + 2] = NAN;
    }
}

static double sphere_distance(void *ctx, const double q[3])
{
    (void)ctx;
    return fabs(sqrt(dot3(q, q)) - 1);
}

/* Mesh vertices within tol of p. */
static uint32_t vertices_at(const tsr_mesh *m, const double p[3], double tol)
{
    uint32_t n = 0;
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        double q[3] = {m->positions[3 * v], m->positions[3 * v + 1], m->positions[3 * v + 2]};
        n += dist3(p, q) <= tol;
    }
    return n;
}

/* Normals along p / |p| (or against it, sign -1). */
static uint32_t normals_off_radial(const tsr_mesh *m, double sign, double tol)
{
    uint32_t off = 0;
    for (uint32_t v = 0; m->normals && v < m->vertex_count; v++) {
        const float *p = m->positions + 3 * v, *n = m->normals + 3 * v;
        double l = sqrt((double)p[0] * p[0] + (double)p[1] * p[1] + (double)p[2] * p[2]);
        double c = sign * (n[0] * p[0] + n[1] * p[1] + n[2] * p[2]) / l;
        off += c < 1 - tol;
    }
    return off;
}

TEST(sphere_octant_pole)
{
    const octant o = {1, 1, 1, false, false};
    octants os = {&o, 1};
    sbuf b = {0};
    octant_obj(&b, &o);
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(&b, "octant.obj", &set)) {
        free(b.s);
        return;
    }
    if (make_model(&set, &m)) {
        tsr_pmodel_info info;
        tsr_pmodel_get_info(m, &info);
        CHECK_MSG(info.sources == 1 && info.pieces == 1 && info.collapsed_edges == 1 && info.links == 0,
                  "sources %u pieces %u collapsed %u links %u", info.sources, info.pieces, info.collapsed_edges,
                  info.links);
        const uint32_t tiles[] = {2, 4, 8, 16};
        for (double E = 1e-1; E >= 0.99e-4; E /= 10)
            for (int ti = 0; ti < 4; ti++) {
                if (E < 0.99e-3 && ti != 2)
                    continue; /* 1e-4: one tile size, for time */
                tsr_ptess_options o2 = {0};
                o2.max_error = E;
                o2.tile_n = tiles[ti];
                o2.normals = true;
                tsr_ptess_result r;
                if (!run_ptess(m, &o2, &r)) {
                    tsr_ptess_result_free(&r);
                    continue;
                }
                check_shape(m, &r, true);
                sampling s = {octants_truth, &os, sphere_distance, NULL, NULL, 0, 0, 0, 0, 0, 0, 0, 0, {0, 0}};
                sample_result(&r, &s);
                double sl = fslack(1);
                CHECK_MSG(s.param_error <= E + sl, "E %g tile %u: parametric error %g at (%.9g, %.9g)", E, tiles[ti],
                          s.param_error, s.worst_uv[0], s.worst_uv[1]);
                CHECK_MSG(s.implicit_error <= E + sl, "E %g tile %u: %g off the sphere", E, tiles[ti],
                          s.implicit_error);
                CHECK_MSG(s.param_error <= r.bound + sl, "E %g: error %g beyond the bound %g", E, s.param_error,
                          r.bound);
                CHECK_MSG(r.bound <= E, "E %g: bound %g", E, r.bound);
                /* and not far above it where the tree has depth (its
                 * nodes' nets small; at the root a net's rows are far from
                 * the surface): the rows' and columns' |C''| from the
                 * Bernstein form of N / w^3 (rational_curve_second_tight);
                 * the quotient rule alone gave 2.0-2.5 times the error */
                fprintf(stderr, "  E %g tile %u: %u triangles, %u leaves, bound / error %.2f\n", E, tiles[ti],
                        r.mesh.triangle_count, r.leaves, r.bound / s.param_error);
                if (r.leaves >= 16)
                    CHECK_MSG(r.bound <= 2.2 * s.param_error, "E %g tile %u: bound %g, %.2f times the error", E,
                              tiles[ti], r.bound, r.bound / s.param_error);
                CHECK_MSG(s.corner_error <= sl, "corner error %g", s.corner_error);
                /* the pole: one vertex; no repeated corner, no zero area */
                const double pole[3] = {0, 0, 1};
                uint32_t at_pole = vertices_at(&r.mesh, pole, 1e-6);
                CHECK_MSG(at_pole == 1, "E %g tile %u: %u vertices at the pole", E, tiles[ti], at_pole);
                tsr_validation v = validate(&r.mesh);
                check_conforming("octant", &v);
                CHECK_MSG(v.boundary_loops == 1 && v.euler == 1 && v.coincident_vertices == 0,
                          "loops %u euler %lld coincident %u", v.boundary_loops, (long long)v.euler,
                          v.coincident_vertices);
                /* the true normals: radial, outward (|n| = 1 checked there) */
                check_normals_agree(&r.mesh, "octant");
                uint32_t off = normals_off_radial(&r.mesh, 1, 1e-6);
                CHECK_MSG(off == 0, "E %g: %u normals not along p / |p|", E, off);
                if (E > 0.5e-2 && ti == 1) {
                    tsr_ptess_measure_result mr;
                    memset(&mr, 0, sizeof mr);
                    CHECK(tsr_ptess_measure(m, &r, 9, NULL, false, NULL, &mr) == TSR_OK);
                    CHECK_MSG(mr.max_error <= E + sl, "E %g: measured %g", E, mr.max_error);
                    CHECK_MSG(mr.uncovered == 0, "E %g: %llu samples in no triangle (beside the collapsed edge?)", E,
                              (unsigned long long)mr.uncovered);
                }
                tsr_ptess_result_free(&r);
            }
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* The eight octants in one OBJ, in the order given. */
static void sphere_obj(sbuf *b, const octant *o, uint32_t n)
{
    for (uint32_t k = 0; k < n; k++)
        octant_obj(b, &o[k]);
}

/* A closed sphere: welded, closed, conforming, Euler 2, one vertex per
 * pole, oriented as the first octant, |volume| near 4/3 pi. */
static void check_sphere(const char *what, const octant *o, double E, int expect_mirrored, double expect_sign)
{
    octants os = {o, 8};
    sbuf b = {0};
    sphere_obj(&b, o, 8);
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(&b, what, &set)) {
        free(b.s);
        return;
    }
    if (make_model(&set, &m)) {
        tsr_pmodel_info info;
        tsr_pmodel_get_info(m, &info);
        CHECK_MSG(info.sources == 8 && info.pieces == 8, "%s: sources %u pieces %u", what, info.sources, info.pieces);
        CHECK_MSG(info.links == 24, "%s: %u linked edges, want 8 x 3", what, info.links);
        CHECK_MSG(info.collapsed_edges == 8, "%s: %u collapsed edges, want 8", what, info.collapsed_edges);
        CHECK_MSG((int)info.mirrored == expect_mirrored, "%s: %u mirrored, want %d", what, info.mirrored,
                  expect_mirrored);
        for (uint32_t k = 0; k < 8; k++) {
            tsr_psource_info si;
            CHECK(tsr_pmodel_source_info(m, k, &si));
            bool want = octant_outward(&o[k]) != octant_outward(&o[0]);
            CHECK_MSG(si.mirrored == want, "%s: source %u mirrored %d", what, k, si.mirrored);
            /* the normal tsr_pmodel_eval gives is as the mesh orients it */
            double p[3], n[3];
            CHECK(tsr_pmodel_eval(m, k, 0.3, 0.6, p, n) == TSR_OK);
            double want_p[3];
            octant_point(&o[k], 0.3, 0.6, want_p);
            CHECK(dist3(p, want_p) <= 1e-12);
            CHECK_NEAR(dot3(n, p), expect_sign, 1e-9);
        }
        tsr_ptess_options opt = {0};
        opt.max_error = E;
        opt.normals = true;
        tsr_ptess_result r;
        if (run_ptess(m, &opt, &r)) {
            check_shape(m, &r, true);
            sampling s = {octants_truth, &os, sphere_distance, NULL, NULL, 0, 0, 0, 0, 0, 0, 0, 0, {0, 0}};
            sample_result(&r, &s);
            double sl = fslack(1);
            CHECK_MSG(s.param_error <= E + sl, "%s: parametric error %g (source %u at %.9g, %.9g)", what, s.param_error,
                      r.tri_source[s.worst_tri], s.worst_uv[0], s.worst_uv[1]);
            CHECK_MSG(s.implicit_error <= E + sl, "%s: %g off the sphere", what, s.implicit_error);
            CHECK_MSG(s.corner_error <= sl + 1e-9, "%s: corner error %g", what, s.corner_error);
            tsr_validation v = validate(&r.mesh);
            describe(what, &v);
            check_conforming(what, &v);
            CHECK_MSG(v.boundary_edges == 0, "%s: %u boundary edges", what, v.boundary_edges);
            CHECK_MSG(v.euler == 2, "%s: Euler characteristic %lld", what, (long long)v.euler);
            CHECK_MSG(v.coincident_vertices == 0, "%s: %u coincident vertices (not welded)", what,
                      v.coincident_vertices);
            CHECK(tsr_validation_ok(&v));
            const double north[3] = {0, 0, 1}, south[3] = {0, 0, -1};
            CHECK_MSG(vertices_at(&r.mesh, north, 1e-6) == 1 && vertices_at(&r.mesh, south, 1e-6) == 1,
                      "%s: %u vertices at the north pole, %u at the south", what, vertices_at(&r.mesh, north, 1e-6),
                      vertices_at(&r.mesh, south, 1e-6));
            double vol = signed_volume(&r.mesh), want = 4 * PI / 3;
            CHECK_MSG(vol * expect_sign > 0, "%s: signed volume %g, want sign %g", what, vol, expect_sign);
            /* every point within E of the sphere: the volume within area * E */
            CHECK_MSG(fabs(fabs(vol) - want) <= 4 * PI * E * 1.05, "%s: |volume| %.9g vs 4/3 pi = %.9g", what,
                      fabs(vol), want);
            check_normals_agree(&r.mesh, what);
            uint32_t off = normals_off_radial(&r.mesh, expect_sign, 1e-6);
            CHECK_MSG(off == 0, "%s: %u normals not along %s p / |p|", what, off, expect_sign > 0 ? "+" : "-");
            tsr_ptess_measure_result mr;
            memset(&mr, 0, sizeof mr);
            CHECK(tsr_ptess_measure(m, &r, 9, NULL, false, NULL, &mr) == TSR_OK);
            CHECK_MSG(mr.max_error <= E + sl, "%s: measured %g", what, mr.max_error);
            CHECK_MSG(mr.uncovered == 0, "%s: %llu samples in no triangle", what, (unsigned long long)mr.uncovered);
        }
        tsr_ptess_result_free(&r);
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* All outward, some written reversed or transposed so the shared rows of
 * control points run backwards: nothing to mirror. */
/* The eight octants with every net facing outward. */
static const octant outward_octants[8] = {{1, 1, 1, false, false},   {-1, 1, 1, true, false}, {-1, -1, 1, true, true},
                                          {1, -1, 1, false, true},   {1, 1, -1, false, true}, {-1, 1, -1, false, false},
                                          {-1, -1, -1, true, false}, {1, -1, -1, true, true}};

TEST(sphere_closed_outward_nets)
{
    const octant *o = outward_octants;
    for (int k = 0; k < 8; k++)
        CHECK(octant_outward(&o[k]));
    check_sphere("sphere_outward.obj", o, 2e-3, 0, 1);
    check_sphere("sphere_outward_coarse.obj", o, 5e-2, 0, 1);
}

/* Plain mirror images: four octants face inward and are mirrored to agree
 * with the first. */
TEST(sphere_closed_mirrored_octants)
{
    octant o[8];
    for (int k = 0; k < 8; k++)
        o[k] = (octant){k & 1 ? -1 : 1, k & 2 ? -1 : 1, k & 4 ? -1 : 1, false, false};
    check_sphere("sphere_mirrors.obj", o, 1e-3, 4, 1);
}

/* The first octant faces inward: the whole sphere follows it. */
TEST(sphere_closed_first_inward)
{
    octant o[8];
    for (int k = 0; k < 8; k++)
        o[k] = (octant){k & 1 ? 1 : -1, k & 2 ? -1 : 1, k & 4 ? -1 : 1, false, false};
    CHECK(!octant_outward(&o[0]));
    check_sphere("sphere_inward.obj", o, 2e-3, 4, -1);
}

/* piece_scale tightens one piece's tolerance and no other's. */
TEST(piece_scale_tightens_one_piece)
{
    octant o[8];
    for (int k = 0; k < 8; k++)
        o[k] = (octant){k & 1 ? -1 : 1, k & 2 ? -1 : 1, k & 4 ? -1 : 1, false, false};
    octants os = {o, 8};
    sbuf b = {0};
    sphere_obj(&b, o, 8);
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(&b, "sphere_scale.obj", &set)) {
        free(b.s);
        return;
    }
    if (make_model(&set, &m)) {
        const double E = 1e-2;
        double scale[8] = {1, 1, 1, 1, 1, 1, 1, 1};
        tsr_psource_info si;
        CHECK(tsr_pmodel_source_info(m, 5, &si) && si.pieces_u == 1 && si.pieces_v == 1);
        uint32_t p5 = si.first_piece < 8 ? si.first_piece : 0;
        scale[p5] = 0.05;
        tsr_ptess_options opt = {0};
        opt.max_error = E;
        tsr_ptess_result r0, r1;
        bool ok0 = run_ptess(m, &opt, &r0);
        opt.piece_scale = scale;
        bool ok1 = run_ptess(m, &opt, &r1);
        if (ok0 && ok1) {
            double e0[8] = {0}, e1[8] = {0};
            uint32_t t0[8] = {0}, t1[8] = {0};
            sampling s0 = {octants_truth, &os, NULL, NULL, e0, 0, 0, 0, 0, 0, 0, 0, 0, {0, 0}};
            sampling s1 = {octants_truth, &os, NULL, NULL, e1, 0, 0, 0, 0, 0, 0, 0, 0, {0, 0}};
            sample_result(&r0, &s0);
            sample_result(&r1, &s1);
            for (uint32_t t = 0; t < r0.mesh.triangle_count; t++)
                t0[r0.tri_source[t] & 7]++;
            for (uint32_t t = 0; t < r1.mesh.triangle_count; t++)
                t1[r1.tri_source[t] & 7]++;
            double sl = fslack(1);
            for (int k = 0; k < 8; k++) {
                double want = k == 5 ? 0.05 * E : E;
                CHECK_MSG(e1[k] <= want + sl, "source %d: error %g, tolerance %g", k, e1[k], want);
                CHECK_MSG(e0[k] <= E + sl, "source %d: error %g", k, e0[k]);
            }
            CHECK_MSG(t1[5] >= 4 * t0[5], "source 5: %u triangles with scale 0.05, %u without", t1[5], t0[5]);
            /* still closed: the finer piece's edges are matched by its neighbours */
            tsr_validation v = validate(&r1.mesh);
            check_conforming("scaled sphere", &v);
            CHECK(v.boundary_edges == 0 && v.euler == 2);
        }
        tsr_ptess_result_free(&r0);
        tsr_ptess_result_free(&r1);
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* ---- a B-spline of several spans ----------------------------------------------------- */

#define BS_NU 6
#define BS_NV 5
static const double bs_ku[BS_NU + 4] = {0, 0, 0, 0, 0.7, 1.5, 3, 3, 3, 3};
static const double bs_kv[BS_NV + 4] = {0, 0, 0, 0, 0.8, 2, 2, 2, 2};

static void bs_ctrl(int i, int j, double p[3])
{
    double x = i, y = 1.2 * j;
    p[0] = x;
    p[1] = y;
    p[2] = 0.6 * sin(1.3 * x) * cos(0.9 * y) + 0.05 * x * y;
}

/* ctx: the control points, 3 * BS_NU * BS_NV, from bs_ctrl */
static void bs_truth(void *ctx, uint32_t src, const double *uv, uint32_t n, double *pos)
{
    const double *ctrl = ctx;
    (void)src;
    for (uint32_t k = 0; k < n; k++) {
        double Nu[4], Nv[4];
        int su = bspline_basis(bs_ku, BS_NU, 3, uv[2 * k], Nu);
        int sv = bspline_basis(bs_kv, BS_NV, 3, uv[2 * k + 1], Nv);
        double p[3] = {0, 0, 0};
        for (int b = 0; b <= 3; b++)
            for (int a = 0; a <= 3; a++) {
                const double *c = ctrl + 3 * ((sv - 3 + b) * BS_NU + (su - 3 + a));
                for (int d = 0; d < 3; d++)
                    p[d] += Nu[a] * Nv[b] * c[d];
            }
        memcpy(pos + 3 * k, p, sizeof p);
    }
}

TEST(bspline_pieces_conform)
{
    sbuf b = {0};
    double ctrl[3 * BS_NU * BS_NV];
    for (int j = 0; j < BS_NV; j++)
        for (int i = 0; i < BS_NU; i++) {
            double *p = ctrl + 3 * (j * BS_NU + i);
            bs_ctrl(i, j, p);
            sb_printf(&b, "v %.17g %.17g %.17g\n", p[0], p[1], p[2]);
        }
    sb_printf(&b, "cstype bspline\ndeg 3 3\nsurf 0 3 0 2");
    for (int k = 1; k <= BS_NU * BS_NV; k++)
        sb_printf(&b, " %d", k);
    sb_printf(&b, "\nparm u");
    for (int k = 0; k < BS_NU + 4; k++)
        sb_printf(&b, " %.17g", bs_ku[k]);
    sb_printf(&b, "\nparm v");
    for (int k = 0; k < BS_NV + 4; k++)
        sb_printf(&b, " %.17g", bs_kv[k]);
    sb_printf(&b, "\nend\n");
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(&b, "bspline.obj", &set)) {
        free(b.s);
        return;
    }
    if (make_model(&set, &m)) {
        tsr_pmodel_info info;
        tsr_pmodel_get_info(m, &info);
        /* 3 x 2 spans; 2 x 2 + 3 x 1 shared edges, each side counted */
        CHECK_MSG(info.sources == 1 && info.pieces == 6, "sources %u pieces %u", info.sources, info.pieces);
        CHECK_MSG(info.links == 14, "%u linked edges, want 14", info.links);
        CHECK(info.collapsed_edges == 0 && info.mirrored == 0);
        tsr_psource_info si;
        CHECK(tsr_pmodel_source_info(m, 0, &si));
        CHECK(si.pieces_u == 3 && si.pieces_v == 2 && si.first_piece == 0);
        CHECK(si.domain[0] == 0 && si.domain[1] == 3 && si.domain[2] == 0 && si.domain[3] == 2);
        /* (1e-4 gives some 430 000 triangles: too slow to sample here) */
        for (double E = 1e-1; E >= 0.99e-3; E /= 10)
            for (uint32_t tile = 2; tile <= 8; tile *= 2) {
                tsr_ptess_options opt = {0};
                opt.max_error = E;
                opt.tile_n = tile;
                tsr_ptess_result r;
                if (run_ptess(m, &opt, &r)) {
                    check_shape(m, &r, false);
                    sampling s = {bs_truth, ctrl, NULL, NULL, NULL, 0, 0, 0, 0, 0, 0, 0, 0, {0, 0}};
                    sample_result(&r, &s);
                    double sl = fslack(mesh_maxabs(&r.mesh));
                    CHECK_MSG(s.param_error <= E + sl, "E %g tile %u: parametric error %g at (%.9g, %.9g)", E, tile,
                              s.param_error, s.worst_uv[0], s.worst_uv[1]);
                    CHECK_MSG(s.param_error <= r.bound + sl, "E %g: error %g beyond the bound %g", E, s.param_error,
                              r.bound);
                    CHECK_MSG(s.corner_error <= sl + 1e-9, "corner error %g", s.corner_error);
                    CHECK(r.leaves >= 6);
                    tsr_validation v = validate(&r.mesh);
                    check_conforming("bspline", &v);
                    CHECK_MSG(v.boundary_loops == 1 && v.euler == 1 && v.coincident_vertices == 0,
                              "E %g tile %u: loops %u euler %lld coincident %u", E, tile, v.boundary_loops,
                              (long long)v.euler, v.coincident_vertices);
                    uint32_t bad = 0;
                    CHECK_MSG(tsr_mesh_boundary_is_rect(&r.mesh, 0, 0, BS_NU - 1, 1.2 * (BS_NV - 1), 1e-5, &bad),
                              "E %g tile %u: boundary vertex %u off the outer sides", E, tile, bad);
                    if (tile == 4 && E > 0.5e-3) {
                        tsr_ptess_measure_result mr;
                        memset(&mr, 0, sizeof mr);
                        CHECK(tsr_ptess_measure(m, &r, 9, NULL, false, NULL, &mr) == TSR_OK);
                        CHECK_MSG(mr.max_error <= E + sl, "E %g: measured %g", E, mr.max_error);
                        CHECK(mr.uncovered == 0 && mr.samples >= 6 * 81);
                    }
                }
                tsr_ptess_result_free(&r);
            }
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* Two patches sharing half of an edge are not linked: the contract keeps
 * partial overlaps apart. Two sharing a whole edge, written backwards,
 * are. */
TEST(partial_overlap_linked)
{
    sbuf b = {0};
    sb_printf(&b, "v 0 0 0\nv 2 0 0\nv 0 1 0\nv 2 1 0.5\n"
                  "cstype bezier\ndeg 1 1\nsurf 0 1 0 1 1 2 3 4\nend\n"
                  "v 3 0 0\nv 3 0.5 0\nv 2 0.5 0.25\n"
                  "surf 0 1 0 1 2 5 7 6\nend\n"
                  "v 2 2 0\nv 0 2 0.3\n"
                  "surf 0 1 0 1 8 9 4 3\nend\n");
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(&b, "overlap.obj", &set)) {
        free(b.s);
        return;
    }
    if (make_model(&set, &m)) {
        tsr_pmodel_info info;
        tsr_pmodel_get_info(m, &info);
        /* patch 2's north row (points 4, 3) is patch 0's north row (3, 4)
         * reversed, and the two agree in orientation: linked, nothing
         * mirrored. Patch 1's west edge is the lower half of patch 0's
         * east edge: patch 0 is cut at v = 1/2, and its lower piece's east
         * edge is linked to it. */
        CHECK_MSG(info.sources == 3 && info.pieces == 4 && info.links == 6 && info.conform_breaks == 1,
                  "sources %u pieces %u links %u breaks %u", info.sources, info.pieces, info.links,
                  info.conform_breaks);
        CHECK_MSG(info.mirrored == 0, "%u mirrored", info.mirrored);
        tsr_ptess_options o = {0};
        o.max_error = 1e-3;
        tsr_ptess_result r;
        if (run_ptess(m, &o, &r)) {
            tsr_validation v = validate(&r.mesh);
            check_conforming("partial overlap", &v);
            /* the three patches welded into one disc */
            CHECK_MSG(v.boundary_loops == 1 && v.euler == 1, "loops %u euler %lld", v.boundary_loops,
                      (long long)v.euler);
        }
        tsr_ptess_result_free(&r);
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* T-configurations: a bicubic sheet z = g(x) (g a cubic, x = 2u, y = v)
 * over [0, 2] x [0, 1]; above it three patches whose south edges are its
 * north edge cut at u = 0.3 and 0.7 (the middle one running backwards,
 * so mirrored), below it two whose north edges are its south edge's
 * curve over u in [-0.5, 0.4] and [0.4, 1.5] (staggered: each reaches
 * past an end of the sheet's edge). Every patch is a piece of the one
 * surface z = g(x), so the union is a height field over an L-free
 * polygon: the mesh must be one disc (one boundary loop, Euler
 * characteristic 1) whose open edges all lie on that polygon's outline,
 * and its vertical error (its parametric error: x and y are affine in u
 * and v) within the tolerance. */
static const double tc_z[4] = {0, 0.4, -0.3, 0.2};

/* The blossom of tc_z at (a, b, c): the control values of the curve
 * over [a, b] are f(a,a,a), f(a,a,b), f(a,b,b), f(b,b,b). */
static double tc_blossom(double a, double b, double c)
{
    double t[3] = {a, b, c}, w[4];
    memcpy(w, tc_z, sizeof w);
    for (int l = 0; l < 3; l++)
        for (int k = 0; k < 3 - l; k++)
            w[k] = (1 - t[l]) * w[k] + t[l] * w[k + 1];
    return w[0];
}

static double tc_g(double x)
{
    return tc_blossom(x / 2, x / 2, x / 2);
}

/* A bicubic patch over u in [u0, u1] (x = 2u; u1 < u0 runs backwards) and
 * y in [y0, y1]. */
static void tc_patch(sbuf *b, int *nv, double u0, double u1, double y0, double y1)
{
    double c[4] = {tc_blossom(u0, u0, u0), tc_blossom(u0, u0, u1), tc_blossom(u0, u1, u1), tc_blossom(u1, u1, u1)};
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++)
            sb_printf(b, "v %.17g %.17g %.17g\n", 2 * (u0 + (u1 - u0) * i / 3), y0 + (y1 - y0) * j / 3, c[i]);
    sb_printf(b, "surf 0 1 0 1");
    for (int k = 1; k <= 16; k++)
        sb_printf(b, " %d", *nv + k);
    sb_printf(b, "\nend\n");
    *nv += 16;
}

/* Whether (x, y) lies on the outline of the union (within eps). */
static bool tc_on_outline(double x, double y, double eps)
{
    bool ylo = fabs(y + 1) <= eps, yhi = fabs(y - 2) <= eps, y0 = fabs(y) <= eps;
    return ylo || yhi || fabs(x + 1) <= eps || (fabs(x - 3) <= eps && y <= eps) || (y0 && (x >= 2 - eps || x <= eps)) ||
           ((fabs(x) <= eps || fabs(x - 2) <= eps) && y >= -eps);
}

TEST(t_configurations_linked)
{
    sbuf b = {0};
    int nv = 0;
    sb_printf(&b, "cstype bezier\ndeg 3 3\n");
    tc_patch(&b, &nv, 0, 1, 0, 1);
    tc_patch(&b, &nv, 0, 0.3, 1, 2);
    tc_patch(&b, &nv, 0.7, 0.3, 1, 2);
    tc_patch(&b, &nv, 0.7, 1, 1, 2);
    tc_patch(&b, &nv, -0.5, 0.4, -1, 0);
    tc_patch(&b, &nv, 0.4, 1.5, -1, 0);
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(&b, "tconfig.obj", &set)) {
        free(b.s);
        return;
    }
    if (make_model(&set, &m)) {
        tsr_pmodel_info info;
        tsr_pmodel_get_info(m, &info);
        /* the backward patch is mirrored, in two pieces: the cut at u = 0.4
         * from below reaches it through the sheet */
        CHECK_MSG(info.mirrored == 2 && info.sources == 6, "%u mirrored", info.mirrored);
        for (int k = 0; k < 2; k++) {
            double E = k ? 1e-5 : 1e-3;
            tsr_ptess_options o = {0};
            o.max_error = E;
            tsr_ptess_result r;
            if (!run_ptess(m, &o, &r))
                continue;
            check_shape(m, &r, false);
            tsr_validation v = validate(&r.mesh);
            check_conforming("t-configurations", &v);
            CHECK_MSG(v.boundary_loops == 1 && v.euler == 1, "E %g: loops %u euler %lld", E, v.boundary_loops,
                      (long long)v.euler);
            tsr_halfedges he;
            uint32_t off = 0, first = UINT32_MAX;
            if (tsr_halfedges_build(&he, &r.mesh, NULL) == TSR_OK) {
                for (uint32_t h = 0; h < he.count; h++) {
                    if (he.twin[h] != TSR_NO_TWIN)
                        continue;
                    const float *p = r.mesh.positions + 3 * (size_t)r.mesh.indices[h];
                    const float *q = r.mesh.positions + 3 * (size_t)r.mesh.indices[3 * (h / 3) + (h % 3 + 1) % 3];
                    bool on = tc_on_outline(0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1]), 1e-5);
                    off += !on;
                    if (!on && first == UINT32_MAX)
                        first = h;
                }
                tsr_halfedges_free(&he);
            }
            CHECK_MSG(off == 0, "E %g: %u open edges inside the union, first half-edge %u", E, off, first);
            /* vertical error at the vertices and at 6 points inside every triangle */
            double worst = 0;
            static const double bary[6][3] = {{1. / 3, 1. / 3, 1. / 3}, {0.5, 0.5, 0},  {0, 0.5, 0.5}, {0.5, 0, 0.5},
                                              {0.8, 0.1, 0.1},          {0.1, 0.1, 0.8}};
            for (uint32_t t = 0; t < r.mesh.triangle_count; t++)
                for (int s = 0; s < 6; s++) {
                    double x = 0, z = 0;
                    for (int c = 0; c < 3; c++) {
                        const float *p = r.mesh.positions + 3 * (size_t)r.mesh.indices[3 * t + (uint32_t)c];
                        x += bary[s][c] * p[0];
                        z += bary[s][c] * p[2];
                    }
                    worst = fmax(worst, fabs(z - tc_g(x)));
                }
            CHECK_MSG(worst <= E + fslack(3), "E %g: vertical error %g", E, worst);
            tsr_ptess_result_free(&r);
        }
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* A brick wall: R rows of bilinear plane patches 1 high, X wide, the
 * joints of row r at x = (0.37 r mod 1) + k: every row's top edges meet
 * the next row's bottom edges staggered. */
static void wall_obj(sbuf *b, int R, int X)
{
    int nv = 0;
    sb_printf(b, "cstype bezier\ndeg 1 1\n");
    for (int r = 0; r < R; r++) {
        double o = fmod(0.37 * r, 1.0), xs[64];
        int n = 0;
        xs[n++] = 0;
        for (int k = 0; k <= X; k++)
            if (o + k > 1e-9 && o + k < X - 1e-9)
                xs[n++] = o + k;
        xs[n++] = X;
        for (int i = 0; i + 1 < n; i++) {
            sb_printf(b, "v %.17g %d 0\nv %.17g %d 0\nv %.17g %d 0\nv %.17g %d 0\n", xs[i], r, xs[i + 1], r, xs[i],
                      r + 1, xs[i + 1], r + 1);
            sb_printf(b, "surf 0 1 0 1 %d %d %d %d\nend\n", nv + 1, nv + 2, nv + 3, nv + 4);
            nv += 4;
        }
    }
}

TEST(staggered_rows_linked_or_left_whole)
{
    /* 6 rows: every staggered joint linked, one disc */
    for (int big = 0; big < 2; big++) {
        sbuf b = {0};
        wall_obj(&b, big ? 60 : 6, big ? 10 : 4);
        tsr_patch_set set;
        tsr_pmodel *m = NULL;
        if (!parse_set(&b, big ? "wall60.obj" : "wall6.obj", &set)) {
            free(b.s);
            return;
        }
        if (make_model(&set, &m)) {
            tsr_pmodel_info info;
            tsr_pmodel_get_info(m, &info);
            if (!big) {
                CHECK_MSG(info.partial_unlinked == 0 && info.conform_breaks > 0, "unlinked %u breaks %u",
                          info.partial_unlinked, info.conform_breaks);
                tsr_ptess_options o = {0};
                o.max_error = 1e-3;
                tsr_ptess_result r;
                if (run_ptess(m, &o, &r)) {
                    tsr_validation v = validate(&r.mesh);
                    check_conforming("wall", &v);
                    CHECK_MSG(v.boundary_loops == 1 && v.euler == 1, "loops %u euler %lld", v.boundary_loops,
                              (long long)v.euler);
                }
                tsr_ptess_result_free(&r);
            } else {
                /* 60 rows would spread 60 rows' joints through every row
                 * (some 36,000 breakpoints): beyond the budget, the partial
                 * overlaps are left unlinked and said to be, whole edges
                 * (none here) share as before */
                CHECK_MSG(info.partial_unlinked > 0 && info.conform_breaks < 20000 && info.pieces == set.num_patches,
                          "unlinked %u breaks %u pieces %u of %u", info.partial_unlinked, info.conform_breaks,
                          info.pieces, set.num_patches);
            }
        }
        tsr_pmodel_destroy(m);
        tsr_patch_set_free(&set);
        free(b.s);
    }
}

/* ---- view dependence --------------------------------------------------------------- */

/* A long quarter cylinder along x, seen from near its x = 0 end. */
static const double VL = 20, VR = 1;

static void vcyl_truth(void *ctx, uint32_t src, const double *uv, uint32_t n, double *pos)
{
    (void)ctx;
    (void)src;
    for (uint32_t k = 0; k < n; k++) {
        double x, y;
        qcircle(uv[2 * k], &x, &y);
        pos[3 * k] = VL * uv[2 * k + 1];
        pos[3 * k + 1] = VR * x;
        pos[3 * k + 2] = VR * y;
    }
}

/* ---- stitched tiles ----------------------------------------------------------- */

/* z = K s^2 t^7 over the unit square (a Bézier patch of degrees 2 and
 * 7): curvature along s growing fast with t, so leaves deepen along t and
 * tiles next to coarser ones are stitched along s, where a stitched
 * triangle's base (2h along s) lies farther from the surface than any
 * unstitched triangle does. */
typedef struct graded {
    double K;
} graded;

static void graded_truth(void *ctx, uint32_t src, const double *uv, uint32_t n, double *pos)
{
    const graded *g = ctx;
    (void)src;
    for (uint32_t k = 0; k < n; k++) {
        double s = uv[2 * k], t = uv[2 * k + 1];
        pos[3 * k] = s;
        pos[3 * k + 1] = t;
        pos[3 * k + 2] = g->K * s * s * pow(t, 7);
    }
}

TEST(stitched_tiles_within_bound)
{
    graded g = {0.75};
    sbuf b = {0};
    /* s^2 = B_2^2(s), t^7 = B_7^7(t), s = sum i/2 B_i^2(s), t likewise */
    for (int j = 0; j < 8; j++)
        for (int i = 0; i < 3; i++)
            sb_printf(&b, "v %.17g %.17g %.17g\n", i / 2.0, j / 7.0, i == 2 && j == 7 ? g.K : 0.0);
    sb_printf(&b, "cstype bezier\ndeg 2 7\nsurf 0 1 0 1");
    for (int k = 1; k <= 24; k++)
        sb_printf(&b, " %d", k);
    sb_printf(&b, "\nend\n");
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(&b, "graded.obj", &set)) {
        free(b.s);
        return;
    }
    if (make_model(&set, &m)) {
        double worst = 0;
        for (uint32_t tile = 2; tile <= 8; tile *= 2)
            for (double E = 3e-2; E >= 1e-5; E /= 1.7) {
                tsr_ptess_options o = {0};
                o.max_error = E;
                o.tile_n = tile;
                tsr_ptess_result r;
                if (!run_ptess(m, &o, &r)) {
                    tsr_ptess_result_free(&r);
                    continue;
                }
                sampling sm = {graded_truth, &g, NULL, NULL, NULL, 6, 0, 0, 0, 0, 0, 0, 0, {0, 0}};
                sample_result(&r, &sm);
                double sl = fslack(mesh_maxabs(&r.mesh));
                CHECK_MSG(sm.param_error <= E + sl, "tile %u E %g: error %g at (%.9g, %.9g)", tile, E, sm.param_error,
                          sm.worst_uv[0], sm.worst_uv[1]);
                CHECK_MSG(sm.param_error <= r.bound + sl && r.bound <= E, "tile %u E %g: error %g, bound %g", tile, E,
                          sm.param_error, r.bound);
                worst = fmax(worst, sm.param_error / E);
                tsr_validation v = validate(&r.mesh);
                check_conforming("graded", &v);
                tsr_ptess_result_free(&r);
            }
        fprintf(stderr, "  worst sampled error / tolerance %.3f\n", worst);
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* Linked edges of different rates: a flat patch (one root tile) beside a
 * curved one (deep leaves, its own tile size) sharing the edge x = 1.
 * The flat side's border triangles take the curved side's samples (fans),
 * so the mesh conforms; the error holds by the measurement and the bound
 * (fans lie within the triangles they split). z = K (x - 1)^2 on the
 * curved patch: u^2 = sum c_i B_i^3(u), c = 0, 0, 1/3, 1. */
TEST(linked_rates_differ_conform)
{
    const double K = 0.6, c[4] = {0, 0, 1.0 / 3, 1};
    sbuf b = {0};
    for (int side = 0; side < 2; side++)
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 4; i++)
                sb_printf(&b, "v %.17g %.17g %.17g\n", side + i / 3.0, j / 3.0, side ? K * c[i] : 0.0);
    sb_printf(&b, "cstype bezier\ndeg 3 3\n");
    for (int side = 0; side < 2; side++) {
        sb_printf(&b, "surf 0 1 0 1");
        for (int k = 1; k <= 16; k++)
            sb_printf(&b, " %d", 16 * side + k);
        sb_printf(&b, "\nend\n");
    }
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(&b, "rates.obj", &set)) {
        free(b.s);
        return;
    }
    if (make_model(&set, &m)) {
        tsr_pmodel_info info;
        tsr_pmodel_get_info(m, &info);
        CHECK_MSG(info.pieces == 2 && info.links == 2, "pieces %u links %u", info.pieces, info.links);
        uint32_t fans = 0;
        for (uint32_t tile = 2; tile <= 8; tile *= 2)
            for (double E = 1e-2; E >= 1e-5; E /= 3.3) {
                tsr_ptess_options o = {0};
                o.max_error = E;
                o.tile_n = tile;
                tsr_ptess_result r;
                if (!run_ptess(m, &o, &r)) {
                    tsr_ptess_result_free(&r);
                    continue;
                }
                tsr_validation v = validate(&r.mesh);
                check_conforming("rates", &v);
                CHECK_MSG(v.boundary_loops == 1 && v.euler == 1 && v.coincident_vertices == 0,
                          "tile %u E %g: loops %u euler %lld coincident %u", tile, E, v.boundary_loops,
                          (long long)v.euler, v.coincident_vertices);
                tsr_ptess_measure_result mr;
                memset(&mr, 0, sizeof mr);
                CHECK(tsr_ptess_measure(m, &r, 33, NULL, false, NULL, &mr) == TSR_OK);
                double sl = fslack(mesh_maxabs(&r.mesh));
                CHECK_MSG(mr.uncovered == 0, "tile %u E %g: %llu samples uncovered", tile, E,
                          (unsigned long long)mr.uncovered);
                CHECK_MSG(mr.max_error <= E + sl && mr.max_error <= r.bound + sl, "tile %u E %g: measured %g, bound %g",
                          tile, E, mr.max_error, r.bound);
                fans += r.fan_triangles;
                tsr_ptess_result_free(&r);
            }
        CHECK_MSG(fans > 0, "no fans: the two sides never differed");
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* A trimmed patch (a quarter cylinder with a hole) linked along its
 * untrimmed edge z = 0 to an untrimmed patch of another rate: the trimmed
 * side's triangulation takes the neighbour's samples on that edge too, so
 * the seam has no T-junction (found by review: it had 384 open edges). */
TEST(trimmed_linked_conform)
{
    static const char obj[] =
        "v 1 0 0 1\n"
        "v 1 1 0 0.70710678118654752\n"
        "v 0 1 0 1\n"
        "v 1 0 2\n"
        "v 1 1 2 0.70710678118654752\n"
        "v 0 1 2 1\n"
        "v 2 0 -1 1\n"
        "v 2 2 -1 0.70710678118654752\n"
        "v 0 2 -1 1\n"
        "v 1 0 -2 1\n"
        "v 1 1 -2 0.70710678118654752\n"
        "v 0 1 -2 1\n"
        "vp 0 0\n"
        "vp 1 0\n"
        "vp 1 1\n"
        "vp 0 1\n"
        "vp 0 0\n"
        "vp 0.75 0.5 1\n"
        "vp 0.75 0.75 0.70710678118654752\n"
        "vp 0.5 0.75 1\n"
        "vp 0.25 0.75 0.70710678118654752\n"
        "vp 0.25 0.5 1\n"
        "vp 0.25 0.25 0.70710678118654752\n"
        "vp 0.5 0.25 1\n"
        "vp 0.75 0.25 0.70710678118654752\n"
        "vp 0.75 0.5 1\n"
        "cstype bspline\n"
        "deg 1\n"
        "curv2 1 2 3 4 5\n"
        "parm u 0 0 1 2 3 4 4\n"
        "end\n"
        "cstype rat bspline\n"
        "deg 2\n"
        "curv2 -9 -8 -7 -6 -5 -4 -3 -2 -1\n"
        "parm u 0 0 0 1 1 2 2 3 3 4 4 4\n"
        "end\n"
        "g cylinder\n"
        "deg 2 1\n"
        "surf 0 1 0 1 1 2 3 4 5 6\n"
        "parm u 0 0 0 1 1 1\n"
        "parm v 0 0 1 1\n"
        "trim 0 4 1\n"
        "hole 0 4 -1\n"
        "end\n"
        "g below\n"
        "cstype rat bspline\n"
        "deg 2 2\n"
        "surf 0 1 0 1 1 2 3 7 8 9 10 11 12\n"
        "parm u 0 0 0 1 1 1\n"
        "parm v 0 0 0 1 1 1\n"
        "end\n"
        ;
    sbuf b = {0};
    sb_printf(&b, "%s", obj);
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(&b, "trimmed_linked.obj", &set)) {
        free(b.s);
        return;
    }
    if (make_model(&set, &m)) {
        tsr_pmodel_info info;
        tsr_pmodel_get_info(m, &info);
        CHECK_MSG(info.trimmed_sources == 1 && info.links >= 2, "trimmed %u links %u", info.trimmed_sources, info.links);
        for (uint32_t tile = 4; tile <= 8; tile *= 2)
            for (double E = 1e-2; E >= 0.9e-4; E /= 10) {
                tsr_ptess_options o = {0};
                o.max_error = E;
                o.tile_n = tile;
                tsr_ptess_result r;
                if (run_ptess(m, &o, &r)) {
                    tsr_validation v = validate(&r.mesh);
                    CHECK_MSG(v.nonmanifold_edges == 0, "tile %u E %g: %u non-manifold edges", tile, E,
                              v.nonmanifold_edges);
                    /* every seam vertex (z = 0) of the untrimmed side's
                     * triangles is a vertex of the trimmed side's (the
                     * converse is not promised: the trim loop runs along the
                     * seam and its samples are the trimmed side's own) */
                    uint32_t nv = r.mesh.vertex_count, missing = 0, seam = 0;
                    uint8_t *side = calloc(nv ? nv : 1, 1);
                    if (!side)
                        abort();
                    for (uint32_t t = 0; t < r.mesh.triangle_count; t++)
                        for (int k = 0; k < 3; k++) {
                            uint32_t x = r.mesh.indices[3 * t + k];
                            if (fabsf(r.mesh.positions[3 * (size_t)x + 2]) <= 1e-6f)
                                side[x] |= (uint8_t)(1u << (r.tri_source[t] ? 1 : 0));
                        }
                    for (uint32_t x = 0; x < nv; x++) {
                        seam += side[x] == 3;
                        missing += side[x] == 2;
                    }
                    free(side);
                    CHECK_MSG(missing == 0 && seam > 2, "tile %u E %g: %u of the untrimmed side's seam vertices not in "
                              "the trimmed side's triangles (%u shared)", tile, E, missing, seam);
                }
                tsr_ptess_result_free(&r);
            }
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* Trim loops on a flat square patch, 100 x 100 (u, v in 0..1), against
 * the exact areas of what they keep: holes without an outer loop, a hole
 * given twice, two overlapping holes (their union goes: the lens counted
 * once), an island (an outer loop inside a hole), a hole reaching past the
 * outer loop (nothing outside the outer loop). Circles are exact rational
 * quadratics; the mesh's polygons lie inside each circle by at most the
 * tolerance, so the area may differ by the loops' length times it. */
/* Parses text as an OBJ, builds its model, and calls fn with the
 * tessellation at each bound from hi down to lo, tenfold steps. */
static void over_bounds(const sbuf *text, const char *name, double hi, double lo,
                        void (*fn)(void *user, const tsr_ptess_result *r, double E), void *user)
{
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(text, name, &set))
        return;
    if (make_model(&set, &m))
        for (double E = hi; E >= 0.9 * lo; E /= 10) {
            tsr_ptess_options o = {0};
            o.max_error = E;
            tsr_ptess_result r;
            if (run_ptess(m, &o, &r))
                fn(user, &r, E);
            tsr_ptess_result_free(&r);
        }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
}

typedef struct trim_obj {
    sbuf b;
    int vp, curves;
} trim_obj;

/* A circle of centre (cx, cy), radius r in (u, v): its curve number. */
static int trim_circle(trim_obj *t, double cx, double cy, double r)
{
    static const double dir[9][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}, {-1, -1}, {0, -1}, {1, -1}, {1, 0}};
    for (int k = 0; k < 9; k++)
        sb_printf(&t->b, "vp %.17g %.17g %.17g\n", cx + r * dir[k][0], cy + r * dir[k][1], k % 2 ? H2 : 1.0);
    sb_printf(&t->b, "cstype rat bspline\ndeg 2\ncurv2");
    for (int k = 1; k <= 9; k++)
        sb_printf(&t->b, " %d", t->vp + k);
    sb_printf(&t->b, "\nparm u 0 0 0 1 1 2 2 3 3 4 4 4\nend\n");
    t->vp += 9;
    return ++t->curves;
}

/* The axis-aligned square [a, b]^2 in (u, v): its curve number. */
static int trim_square(trim_obj *t, double a, double b)
{
    sb_printf(&t->b, "vp %g %g\nvp %g %g\nvp %g %g\nvp %g %g\nvp %g %g\n", a, a, b, a, b, b, a, b, a, a);
    sb_printf(&t->b, "cstype bspline\ndeg 1\ncurv2 %d %d %d %d %d\nparm u 0 0 1 2 3 4 4\nend\n", t->vp + 1, t->vp + 2,
              t->vp + 3, t->vp + 4, t->vp + 5);
    t->vp += 5;
    return ++t->curves;
}

typedef struct trim_case {
    const char *name;
    double area, perimeter, xmin; /* what it keeps; the loops' length; no vertex left of xmin */
} trim_case;

static void trim_case_check(void *user, const tsr_ptess_result *r, double E)
{
    const trim_case *w = user;
    double area = 0, xmin = INFINITY;
    const float *P = r->mesh.positions;
    for (uint32_t f = 0; f < r->mesh.triangle_count; f++) {
        const uint32_t *v = r->mesh.indices + 3 * f;
        const float *a = P + 3 * v[0], *b = P + 3 * v[1], *d = P + 3 * v[2];
        area += 0.5 * fabs(((double)b[0] - a[0]) * ((double)d[1] - a[1]) - ((double)b[1] - a[1]) * ((double)d[0] - a[0]));
    }
    for (uint32_t i = 0; i < r->mesh.vertex_count; i++)
        xmin = fmin(xmin, P[3 * i]);
    double slack = w->perimeter * E + 1e-3;
    CHECK_MSG(fabs(area - w->area) <= slack, "%s, E %g: area %.4f, exact %.4f (slack %.4f)", w->name, E, area, w->area,
              slack);
    CHECK_MSG(xmin >= w->xmin - 1e-4, "%s: a vertex at x %g, left of %g", w->name, xmin, w->xmin);
    tsr_validation v = validate(&r->mesh);
    CHECK_MSG(v.nonmanifold_edges == 0, "%s: %u non-manifold edges", w->name, v.nonmanifold_edges);
}

TEST(trim_loops_keep_exact_areas)
{
    const double R2 = 400 * PI; /* a circle of radius 0.2: 20 model units */
    /* two circles of radius 20, centres 20 apart: their lens */
    const double lens = 2 * 400 * acos(0.5) - 10 * sqrt(1600 - 400);
    trim_case want[] = {
        {"hole only", 10000 - R2, 2 * PI * 20, 0},
        {"hole twice", 6400 - R2, 320 + 2 * PI * 20, 10},
        {"overlapping holes", 6400 - (2 * R2 - lens), 320 + 4 * PI * 20, 10},
        {"island in a hole", 10000 - 900 * PI + 100 * PI, 400 + 2 * PI * 40, 0},
        {"hole past the outer loop", 6400 - R2 / 2, 320 + 2 * PI * 20, 10},
    };
    for (int c = 0; c < 5; c++) {
        trim_obj t = {0};
        sb_printf(&t.b, "v 0 0 0\nv 100 0 0\nv 0 100 0\nv 100 100 0\n");
        char body[256] = "";
        int k1, k2;
        switch (c) {
        case 0:
            k1 = trim_circle(&t, 0.5, 0.5, 0.2);
            snprintf(body, sizeof body, "hole 0 4 %d\n", k1);
            break;
        case 1:
            k1 = trim_square(&t, 0.1, 0.9);
            k2 = trim_circle(&t, 0.5, 0.5, 0.2);
            snprintf(body, sizeof body, "trim 0 4 %d\nhole 0 4 %d\nhole 0 4 %d\n", k1, k2, k2);
            break;
        case 2:
            k1 = trim_square(&t, 0.1, 0.9);
            k2 = trim_circle(&t, 0.4, 0.5, 0.2);
            trim_circle(&t, 0.6, 0.5, 0.2);
            snprintf(body, sizeof body, "trim 0 4 %d\nhole 0 4 %d\nhole 0 4 %d\n", k1, k2, k2 + 1);
            break;
        case 3:
            k1 = trim_square(&t, 0, 1);
            k2 = trim_circle(&t, 0.5, 0.5, 0.3);
            trim_circle(&t, 0.5, 0.5, 0.1);
            snprintf(body, sizeof body, "trim 0 4 %d\nhole 0 4 %d\ntrim 0 4 %d\n", k1, k2, k2 + 1);
            break;
        default:
            k1 = trim_square(&t, 0.1, 0.9);
            k2 = trim_circle(&t, 0.1, 0.5, 0.2);
            snprintf(body, sizeof body, "trim 0 4 %d\nhole 0 4 %d\n", k1, k2);
            break;
        }
        sb_printf(&t.b, "cstype bezier\ndeg 1 1\nsurf 0 1 0 1 1 2 3 4\n%send\n", body);
        over_bounds(&t.b, want[c].name, 0.1, 0.01, trim_case_check, &want[c]);
        free(t.b.s);
    }
}

/* A trim loop meeting the lattice: a trim edge along a lattice diagonal
 * (u + v = 1 from (0.5, 0.5): every lattice point on it is a rounding off
 * the loop's samples) and a hole whose points lie a rounding from lattice
 * points (0.49999999999999994 for 0.5, as a circle made with cos and sin
 * has them). They gave slivers and zero-area triangles, one vertex twice,
 * and the measurement extrapolated a sliver far along its line (1.77 against
 * 0.014). The mesh must hold the bound as measured, with no degenerate
 * triangle and no position twice, and keep the trimmed area (the plate's
 * x and y are 10 u and 10 v). */
static int cmp_float3(const void *x, const void *y)
{
    const float *a = x, *b = y;
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k])
            return a[k] < b[k] ? -1 : 1;
    return 0;
}

/* Vertices at the position of another. */
static uint32_t same_positions(const tsr_mesh *m)
{
    uint32_t n = m->vertex_count, same = 0;
    float *p = malloc(((size_t)n + 1) * 3 * sizeof *p);
    if (!p)
        return UINT32_MAX;
    memcpy(p, m->positions, (size_t)n * 3 * sizeof *p);
    qsort(p, n, 3 * sizeof *p, cmp_float3);
    for (uint32_t k = 1; k < n; k++)
        same += !memcmp(p + 3 * k, p + 3 * (k - 1), 3 * sizeof *p);
    free(p);
    return same;
}

/* Trim loops of odd shapes on a flat 10 x 10 patch: what
 * tsr_trim_loop_check reports against figures worked out by hand, and the
 * area the tessellation keeps (an outer loop enclosing none of the domain
 * keeps nothing: it used to be dropped, and the whole patch kept). */
TEST(trim_loop_shapes)
{
    static const struct {
        const char *name, *vp, *parm, *stmt;
        double gap, area;    /* of the check: gap, area inside the domain (-1: crosses) */
        double cross_uv[2];
        double kept;         /* the mesh's area */
        double depth;        /* how far into the domain (by hand) */
        int encloses;        /* the centre inside (-1: on the loop, either) */
    } cases[] = {
        {"square",
         "0.1 0.1,0.9 0.1,0.9 0.9,0.1 0.9,0.1 0.1",
         "0 0 1 2 3 4 4",
         "trim 0 4 1",
         0,
         0.64,
         {0, 0},
         64,
         0.1,
         1},
        {"open", "0.1 0.1,0.9 0.1,0.9 0.9,0.1 0.9", "0 0 1 2 3 3", "trim 0 3 1", 0.8, 0.64, {0, 0}, 64, 0.1, 1},
        {"bowtie",
         "0.1 0.1,0.9 0.9,0.9 0.1,0.1 0.9,0.1 0.1",
         "0 0 1 2 3 4 4",
         "trim 0 4 1",
         0,
         -1,
         {0.5, 0.5},
         32,
         0.5,
         -1},
        {"outside", "2 2,3 2,3 3,2 3,2 2", "0 0 1 2 3 4 4", "trim 0 4 1", 0, 0, {0, 0}, 0, -1, 0},
        {"flat", "0.1 0.1,0.9 0.1,0.5 0.1,0.1 0.1", "0 0 1 2 3 3", "trim 0 3 1", 0, 0, {0, 0}, 0, 0.1, 0},
        {"half out",
         "0.5 0.5,1.5 0.5,1.5 1.5,0.5 1.5,0.5 0.5",
         "0 0 1 2 3 4 4",
         "trim 0 4 1",
         0,
         0.25,
         {0, 0},
         25,
         0.5,
         -1},
        {"hole out", "2 2,3 2,3 3,2 3,2 2", "0 0 1 2 3 4 4", "hole 0 4 1", 0, 0, {0, 0}, 100, -1, 0},
        /* a corner cut: deepest where the cut's middle is */
        {"corner cut", "0 0,1 0,1 0.6,0.6 1,0 1,0 0", "0 0 1 2 3 4 5 5", "trim 0 5 1", 0, 0.92, {0, 0}, 92, 0.2, 1},
        {"around", "-1 -1,2 -1,2 2,-1 2,-1 -1", "0 0 1 2 3 4 4", "trim 0 4 1", 0, 1, {0, 0}, 100, -1, 1},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        sbuf b = {0};
        sb_printf(&b, "v 0 0 0\nv 10 0 0\nv 0 10 0\nv 10 10 0\n");
        int nvp = 0;
        for (const char *q = cases[c].vp; *q; nvp++) {
            double u, v;
            int used = 0;
            if (sscanf(q, "%lf %lf%n", &u, &v, &used) != 2)
                break;
            sb_printf(&b, "vp %.17g %.17g\n", u, v);
            q += used;
            q += *q == ',';
        }
        sb_printf(&b, "cstype bspline\ndeg 1\ncurv2");
        for (int k = 1; k <= nvp; k++)
            sb_printf(&b, " %d", k);
        sb_printf(&b, "\nparm u %s\nend\ndeg 1 1\nsurf 0 1 0 1 1 2 3 4\nparm u 0 0 1 1\nparm v 0 0 1 1\n%s\nend\n",
                  cases[c].parm, cases[c].stmt);
        uint32_t stmt_line = 4 + (uint32_t)nvp + 10; /* after the v, vp, cstype .. parm v lines */
        tsr_patch_set set;
        if (!parse_set(&b, cases[c].name, &set)) {
            free(b.s);
            continue;
        }
        tsr_trim_loop_info in;
        CHECK(set.num_loops == 1 && tsr_trim_loop_check(&set, 0, 1e-9, NULL, &in) == TSR_OK);
        CHECK_MSG(set.loops[0].line == stmt_line, "%s: line %u, not %u", cases[c].name, set.loops[0].line, stmt_line);
        bool crosses = cases[c].area < 0;
        CHECK_MSG(fabs(in.gap - cases[c].gap) <= 1e-12 && in.crosses == crosses &&
                      fabs(in.area - cases[c].area) <= 1e-12 && fabs(in.domain_area - 1) <= 1e-15,
                  "%s: gap %g area %g crosses %d (want %g, %g, %d)", cases[c].name, in.gap, in.area, in.crosses,
                  cases[c].gap, cases[c].area, crosses);
        if (crosses)
            CHECK_MSG(hypot(in.cross_uv[0] - cases[c].cross_uv[0], in.cross_uv[1] - cases[c].cross_uv[1]) <= 1e-12,
                      "%s: crossing at %g %g", cases[c].name, in.cross_uv[0], in.cross_uv[1]);
        CHECK_MSG(fabs(in.depth - cases[c].depth) <= 1e-12 &&
                      (cases[c].encloses < 0 || in.encloses_centre == (cases[c].encloses == 1)),
                  "%s: depth %.17g encloses %d", cases[c].name, in.depth, in.encloses_centre);
        tsr_pmodel *m = NULL;
        if (make_model(&set, &m)) {
            tsr_ptess_options o = {0};
            o.max_error = 1e-3;
            tsr_ptess_result r;
            tsr_error e = {0};
            CHECK_MSG(tsr_ptess_run(m, &o, NULL, &r, &e) == TSR_OK, "%s: %s", cases[c].name, e.message);
            double area = 0;
            const float *P = r.mesh.positions;
            for (uint32_t f = 0; f < r.mesh.triangle_count; f++) {
                const uint32_t *t = r.mesh.indices + 3 * f;
                const float *p0 = P + 3 * t[0], *p1 = P + 3 * t[1], *p2 = P + 3 * t[2];
                area += 0.5 * (((double)p1[0] - p0[0]) * ((double)p2[1] - p0[1]) -
                               ((double)p1[1] - p0[1]) * ((double)p2[0] - p0[0]));
            }
            CHECK_MSG(fabs(area - cases[c].kept) <= 1e-4, "%s: kept %g, want %g", cases[c].name, area,
                      cases[c].kept);
            tsr_ptess_result_free(&r);
        }
        tsr_pmodel_destroy(m);
        tsr_patch_set_free(&set);
        free(b.s);
    }
}

/* Trim loops along a patch's whole border (CAD files trim every face by
 * its own boundary) trim nothing: the patch is meshed as untrimmed, the
 * same mesh to the byte as without the loop (the oracle: the untrimmed
 * run), cut across its curve as an untrimmed patch is. Loops that reach
 * into the domain beyond TSR_PMODEL_VOID_TRIM, or come with a hole, or do
 * not go around the domain, still trim. A bicubic over [2, 5] x [1, 3]. */
TEST(border_loops_trim_nothing)
{
    static const struct {
        const char *name, *curves; /* vp lines and curv2 statements */
        const char *trim;          /* trim / hole statements */
        bool nothing;
    } cases[] = {
        {"rectangle", "vp 2 1\nvp 5 1\nvp 5 3\nvp 2 3\nvp 2 1\ndeg 1\ncurv2 1 2 3 4 5\nparm u 0 0 1 2 3 4 4\nend\n",
         "trim 0 4 1\n", true},
        {"clockwise", "vp 2 1\nvp 2 3\nvp 5 3\nvp 5 1\nvp 2 1\ndeg 1\ncurv2 1 2 3 4 5\nparm u 0 0 1 2 3 4 4\nend\n",
         "trim 0 4 1\n", true},
        {"points along the sides",
         "vp 2 1\nvp 3.5 1\nvp 5 1\nvp 5 2\nvp 5 3\nvp 2 3\nvp 2 1\ndeg 1\ncurv2 1 2 3 4 5 6 7\n"
         "parm u 0 0 1 2 3 4 5 6 6\nend\n",
         "trim 0 6 1\n", true},
        /* four quadratic curves whose control points lie on the sides, one
         * run backwards */
        {"curves on the sides",
         "vp 2 1\nvp 3 1\nvp 5 1\nvp 5 2.5\nvp 5 3\nvp 4 3\nvp 2 3\nvp 2 2\nvp 2 1\ndeg 2\n"
         "curv2 1 2 3\nparm u 0 0 0 1 1 1\nend\ncurv2 3 4 5\nparm u 0 0 0 1 1 1\nend\n"
         "curv2 7 6 5\nparm u 0 0 0 1 1 1\nend\ncurv2 7 8 9\nparm u 0 0 0 1 1 1\nend\n",
         "trim 0 1 1 0 1 2 1 0 3 0 1 4\n", true},
        {"around", "vp 1 0\nvp 6 0\nvp 6 4\nvp 1 4\nvp 1 0\ndeg 1\ncurv2 1 2 3 4 5\nparm u 0 0 1 2 3 4 4\nend\n",
         "trim 0 4 1\n", true},
        {"a hair inside",
         "vp 2.000001 1.000001\nvp 4.999999 1.000001\nvp 4.999999 2.999999\nvp 2.000001 2.999999\n"
         "vp 2.000001 1.000001\ndeg 1\ncurv2 1 2 3 4 5\nparm u 0 0 1 2 3 4 4\nend\n",
         "trim 0 4 1\n", false},
        {"corner cut",
         "vp 2 1\nvp 5 1\nvp 5 2.99\nvp 4.99 3\nvp 2 3\nvp 2 1\ndeg 1\ncurv2 1 2 3 4 5 6\n"
         "parm u 0 0 1 2 3 4 5 5\nend\n",
         "trim 0 5 1\n", false},
        {"with a hole",
         "vp 2 1\nvp 5 1\nvp 5 3\nvp 2 3\nvp 2 1\nvp 3 1.5\nvp 4 1.5\nvp 4 2.5\nvp 3 2.5\nvp 3 1.5\ndeg 1\n"
         "curv2 1 2 3 4 5\nparm u 0 0 1 2 3 4 4\nend\ncurv2 6 7 8 9 10\nparm u 0 0 1 2 3 4 4\nend\n",
         "trim 0 4 1\nhole 0 4 2\n", false},
        {"along one side only", "vp 2 1\nvp 5 1\nvp 5 1\nvp 2 1\ndeg 1\ncurv2 1 2 3 4\nparm u 0 0 1 2 3 3\nend\n",
         "trim 0 3 1\n", false},
    };
    tsr_mesh plain = {0};
    for (int c = -1; c < (int)(sizeof cases / sizeof cases[0]); c++) {
        sbuf b = {0};
        if (c >= 0)
            sb_printf(&b, "cstype bspline\n%s", cases[c].curves);
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 4; i++)
                sb_printf(&b, "v %d %d %.17g\n", 10 * i, 10 * j, 12 * sin(1.7 * i) + 0.5 * j);
        sb_printf(&b, "cstype bezier\ndeg 3 3\nsurf 2 5 1 3");
        for (int k = 1; k <= 16; k++)
            sb_printf(&b, " %d", k);
        sb_printf(&b, "\nparm u 2 5\nparm v 1 3\n%send\n", c >= 0 ? cases[c].trim : "");
        const char *name = c >= 0 ? cases[c].name : "untrimmed";
        tsr_patch_set set;
        tsr_pmodel *m = NULL;
        tsr_error e = {0};
        tsr_pmodel_set_options so = {0, 0.01, 0};
        if (!parse_set(&b, name, &set)) {
            free(b.s);
            continue;
        }
        CHECK_MSG(tsr_pmodel_from_set_opts(&set, &so, NULL, &m, &e) == TSR_OK, "%s: %s", name, e.message);
        tsr_pmodel_info info;
        tsr_ptess_options o = {0};
        o.max_error = 0.01;
        tsr_ptess_result r;
        tsr_status st = m ? tsr_ptess_run(m, &o, NULL, &r, &e) : TSR_ERR_ARGUMENT;
        CHECK_MSG(st == TSR_OK, "%s: %s", name, e.message);
        if (st == TSR_OK) {
            tsr_pmodel_get_info(m, &info);
            bool nothing = c < 0 || cases[c].nothing;
            CHECK_MSG(info.trimmed_sources == (nothing ? 0u : 1u) && info.void_loops == (c >= 0 && nothing ? 1u : 0u),
                      "%s: %u trimmed, %u void loops", name, info.trimmed_sources, info.void_loops);
            if (c < 0) {
                /* the model was cut across the curve: the oracle is no single piece */
                CHECK(info.pieces > 1);
                plain = r.mesh;
                memset(&r.mesh, 0, sizeof r.mesh);
            } else if (nothing) {
                CHECK_MSG(r.mesh.vertex_count == plain.vertex_count && r.mesh.triangle_count == plain.triangle_count &&
                              !memcmp(r.mesh.positions, plain.positions, 3 * sizeof(float) * plain.vertex_count) &&
                              !memcmp(r.mesh.indices, plain.indices, 3 * sizeof(uint32_t) * plain.triangle_count),
                          "%s: %u vertices, %u triangles; untrimmed %u, %u", name, r.mesh.vertex_count,
                          r.mesh.triangle_count, plain.vertex_count, plain.triangle_count);
            }
            tsr_ptess_result_free(&r);
        }
        tsr_pmodel_destroy(m);
        tsr_patch_set_free(&set);
        free(b.s);
    }
    tsr_mesh_free(&plain);
}

/* Three patches along one edge (a fin on a plate): linked all three ways,
 * so the edge's vertices are the same in each and every mesh edge along it
 * has exactly three triangles, one of each patch; no open edge lies on it
 * (a crack). The plate's two halves (one flat, one bumped, so they refine
 * it differently) keep their common orientation: the fin's link orients
 * neither (the fin comes first: oriented through it, one half would
 * flip). The fin is curved too and runs the edge backwards. */
TEST(three_patches_share_an_edge)
{
    sbuf b = {0};
    for (int k = 0; k < 3; k++) {
        int p = (k + 2) % 3; /* the fin, then the plate's halves */
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 4; i++) {
                double x = 10.0 * i / 3, w = 10.0 * j / 3, P[3];
                if (p == 0) /* y from -10 to 0, flat */
                    P[0] = x, P[1] = w - 10, P[2] = 0;
                else if (p == 1) /* y from 0 to 10, a bump inside */
                    P[0] = x, P[1] = w, P[2] = (i % 3 && j % 3) ? 6 : 0;
                else /* the fin: up in z, x backwards, waving in y */
                    P[0] = 10 - x, P[1] = j ? 2.5 * sin(3.0 * i) : 0, P[2] = w;
                sb_printf(&b, "v %.17g %.17g %.17g\n", P[0], P[1], P[2]);
            }
        sb_printf(&b, "cstype bezier\ndeg 3 3\nsurf 0 1 0 1");
        for (int i = 1; i <= 16; i++)
            sb_printf(&b, " %d", 16 * k + i);
        sb_printf(&b, "\nend\n");
    }
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (parse_set(&b, "fin.obj", &set) && make_model(&set, &m)) {
        for (int pass = 0; pass < 2; pass++) {
            tsr_ptess_options o = {0};
            o.max_error = pass ? 0.002 : 0.05;
            tsr_ptess_result r;
            if (!run_ptess(m, &o, &r))
                break;
            const tsr_mesh *me = &r.mesh;
            uint32_t on_edge = 0, three = 0, open_on_edge = 0, plate_down = 0;
            size_t n = 3 * (size_t)me->triangle_count;
            for (size_t h = 0; h < n; h++) {
                const float *pa = me->positions + 3 * (size_t)me->indices[h],
                            *pb = me->positions + 3 * (size_t)me->indices[h - h % 3 + (h % 3 + 1) % 3];
                if (!(pa[1] == 0 && pa[2] == 0 && pb[1] == 0 && pb[2] == 0))
                    continue;
                /* a half-edge along the shared edge: how many triangles use it */
                uint32_t users = 0;
                for (size_t g = 0; g < n; g++) {
                    uint32_t a = me->indices[g], c = me->indices[g - g % 3 + (g % 3 + 1) % 3];
                    users += (a == me->indices[h] && c == me->indices[h - h % 3 + (h % 3 + 1) % 3]) ||
                             (c == me->indices[h] && a == me->indices[h - h % 3 + (h % 3 + 1) % 3]);
                }
                on_edge++;
                three += users == 3;
                open_on_edge += users == 1;
            }
            for (uint32_t t = 0; t < me->triangle_count; t++) {
                if (r.tri_source[t] == 0)
                    continue; /* the fin */
                const float *q0 = me->positions + 3 * (size_t)me->indices[3 * t],
                            *q1 = me->positions + 3 * (size_t)me->indices[3 * t + 1],
                            *q2 = me->positions + 3 * (size_t)me->indices[3 * t + 2];
                double nz = ((double)q1[0] - q0[0]) * ((double)q2[1] - q0[1]) -
                            ((double)q1[1] - q0[1]) * ((double)q2[0] - q0[0]);
                plate_down += nz < 0;
            }
            CHECK_MSG(on_edge >= 9 && three == on_edge && open_on_edge == 0 && plate_down == 0,
                      "bound %g: %u half-edges on the shared edge, %u with three triangles, %u open; %u plate "
                      "triangles facing down",
                      o.max_error, on_edge, three, open_on_edge, plate_down);
            tsr_validation v = validate(me);
            CHECK_MSG(v.nonmanifold_edges == on_edge / 3 && v.t_junctions == 0,
                      "bound %g: %u non-manifold edges (want %u), %u T-junctions", o.max_error, v.nonmanifold_edges,
                      on_edge / 3, v.t_junctions);
            tsr_ptess_result_free(&r);
        }
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* A round hole across the edge two flat patches share, crossing it at
 * v = 0.3 and 0.8 (no lattice point): each patch trims its half, and the
 * two crossings, one vertex per side before, are welded (they left a
 * crack: the open edges along x = 1 on both sides). The second patch's
 * circle is also moved by 1e-9 (a CAD file's two curves meet within its
 * tolerance, not exactly). Oracle: no open edge lies along the shared
 * edge, no two vertices coincide, no T-junction. */
TEST(hole_across_a_linked_edge)
{
    for (int moved = 0; moved < 2; moved++) {
        sbuf b = {0};
        static const double C[9][3] = {{0.25, 0, 1},      {0.25, 0.25, H2},  {0, 0.25, 1},
                                       {-0.25, 0.25, H2}, {-0.25, 0, 1},     {-0.25, -0.25, H2},
                                       {0, -0.25, 1},     {0.25, -0.25, H2}, {0.25, 0, 1}};
        for (int side = 0; side < 2; side++)
            for (int k = 0; k < 9; k++)
                sb_printf(&b, "vp %.17g %.17g %.17g\n", (side ? 0.0 : 1.0) + C[k][0],
                          0.55 + C[k][1] + (side && moved ? 1e-9 : 0), C[k][2]);
        sb_printf(&b, "cstype rat bspline\ndeg 2\n");
        for (int side = 0; side < 2; side++) {
            sb_printf(&b, "curv2");
            for (int k = 1; k <= 9; k++)
                sb_printf(&b, " %d", 9 * side + k);
            sb_printf(&b, "\nparm u 0 0 0 1 1 2 2 3 3 4 4 4\nend\n");
        }
        sb_printf(&b, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 0 0\nv 2 1 0\ncstype bezier\ndeg 1 1\n"
                      "surf 0 1 0 1 1 2 3 4\nhole 0 4 1\nend\nsurf 0 1 0 1 2 5 4 6\nhole 0 4 2\nend\n");
        tsr_patch_set set;
        tsr_pmodel *m = NULL;
        if (parse_set(&b, "hole_across.obj", &set) && make_model(&set, &m)) {
            for (int pass = 0; pass < 2; pass++) {
                tsr_ptess_options o = {0};
                o.max_error = pass ? 1e-4 : 3e-3;
                tsr_ptess_result r;
                if (!run_ptess(m, &o, &r))
                    break;
                const tsr_mesh *me = &r.mesh;
                tsr_halfedges he;
                CHECK(tsr_halfedges_build(&he, me, NULL) == TSR_OK);
                uint32_t along = 0, same = 0;
                for (uint32_t h = 0; h < he.count; h++) {
                    const float *pa = me->positions + 3 * (size_t)me->indices[h],
                                *pb = me->positions + 3 * (size_t)me->indices[h - h % 3 + (h % 3 + 1) % 3];
                    along += he.twin[h] == TSR_NO_TWIN && pa[0] == 1 && pb[0] == 1;
                }
                tsr_halfedges_free(&he);
                for (uint32_t i = 0; i < me->vertex_count; i++)
                    for (uint32_t j = i + 1; j < me->vertex_count; j++)
                        same +=
                            !memcmp(me->positions + 3 * (size_t)i, me->positions + 3 * (size_t)j, 3 * sizeof(float));
                tsr_validation v = validate(me);
                CHECK_MSG(along == 0 && same == 0 && v.t_junctions == 0 && v.nonmanifold_edges == 0,
                          "moved %d, bound %g: %u open edges along the shared edge, %u coincident vertex pairs, %u "
                          "T-junctions",
                          moved, o.max_error, along, same, v.t_junctions);
                tsr_ptess_result_free(&r);
            }
        }
        tsr_pmodel_destroy(m);
        tsr_patch_set_free(&set);
        free(b.s);
    }
}

TEST(trim_loops_meet_the_lattice)
{
    static const double hole[9][3] = {{0.75, 0.5, 1},
                                      {0.75, 0.75, H2},
                                      {0.5, 0.75, 1},
                                      {0.25000000000000006, 0.75, H2},
                                      {0.25, 0.5, 1},
                                      {0.24999999999999994, 0.25000000000000006, H2},
                                      {0.49999999999999994, 0.25, 1},
                                      {0.74999999999999989, 0.24999999999999994, H2},
                                      {0.75, 0.49999999999999994, 1}};
    for (int c = 0; c < 2; c++) {
        sbuf b = {0};
        double want;
        if (c == 0) { /* the triangle (0.1, 0.1) (0.5, 0.5) (0.1, 0.9), kept */
            sb_printf(&b, "vp %.17g %.17g\nvp 0.5 0.5\nvp %.17g %.17g\nvp %.17g %.17g\n", 0.1, 0.1, 0.1, 0.9, 0.1, 0.1);
            sb_printf(&b, "cstype bspline\ndeg 1\ncurv2 1 2 3 4\nparm u 0 0 1 2 3 3\nend\n");
            want = 100 * 0.16;
        } else { /* a hole of radius 0.25 about (0.5, 0.5) */
            for (int k = 0; k < 9; k++)
                sb_printf(&b, "vp %.17g %.17g %.17g\n", hole[k][0], hole[k][1], hole[k][2]);
            sb_printf(&b, "cstype rat bspline\ndeg 2\ncurv2 1 2 3 4 5 6 7 8 9\n"
                          "parm u 0 0 0 0.25 0.25 0.5 0.5 0.75 0.75 1 1 1\nend\n");
            want = 100 * (1 - PI / 16);
        }
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 4; i++)
                sb_printf(&b, "v %.17g %.17g %.17g\n", 10.0 * i / 3, 10.0 * j / 3, 0.5 * sin(i + 1.0) * cos(0.7 * j));
        sb_printf(&b, "cstype bezier\ndeg 3 3\nsurf 0 1 0 1 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16\n%s\nend\n",
                  c ? "hole 0 1 1" : "trim 0 3 1");
        tsr_patch_set set;
        tsr_pmodel *m = NULL;
        if (parse_set(&b, c ? "hole_off_lattice.obj" : "trim_on_diagonal.obj", &set) && make_model(&set, &m))
            for (double E = 0.1; E >= 0.9e-3; E /= 10) {
                tsr_ptess_options o = {0};
                o.max_error = E;
                tsr_ptess_result r;
                tsr_ptess_measure_result mr = {0};
                if (run_ptess(m, &o, &r) && tsr_ptess_measure(m, &r, 64, NULL, false, NULL, &mr) == TSR_OK) {
                    tsr_validation v = validate(&r.mesh);
                    double area = 0;
                    const float *P = r.mesh.positions;
                    for (uint32_t f = 0; f < r.mesh.triangle_count; f++) {
                        const uint32_t *t = r.mesh.indices + 3 * f;
                        const float *p0 = P + 3 * t[0], *p1 = P + 3 * t[1], *p2 = P + 3 * t[2];
                        area += 0.5 * fabs(((double)p1[0] - p0[0]) * ((double)p2[1] - p0[1]) -
                                           ((double)p1[1] - p0[1]) * ((double)p2[0] - p0[0]));
                    }
                    uint32_t same = same_positions(&r.mesh);
                    CHECK_MSG(mr.max_error <= E && v.degenerate_triangles == 0 && same == 0 &&
                                  fabs(area - want) <= 40 * E + 1e-3,
                              "case %d E %g: measured %g (at u %g v %g), %u degenerate, %u positions twice, area %.5f "
                              "of %.5f",
                              c, E, mr.max_error, mr.worst_uv[0], mr.worst_uv[1], v.degenerate_triangles, same, area,
                              want);
                }
                tsr_ptess_result_free(&r);
            }
        tsr_pmodel_destroy(m);
        tsr_patch_set_free(&set);
        free(b.s);
    }
}

/* The measurement and a sliver. A triangle whose corners lie within a
 * rounding of one line has edge lines passing within the tolerance of
 * points far along that line, outside the triangle; a sample there must be
 * measured on the triangle that holds it, not extrapolated on the sliver
 * (it was: 1.77 against a true 0.002, on a trimmed plate whose trim edge
 * ran along a lattice diagonal). A sliver with its corners on the surface
 * is put first among a plate's triangles: the figures must stay those of
 * the plate's own triangles (and the sliver's own edges' chords). */
TEST(measure_passes_slivers_by)
{
    sbuf b = {0};
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++)
            sb_printf(&b, "v %.17g %.17g %.17g\n", 10.0 * i / 3, 10.0 * j / 3, 0.5 * sin(i + 1.0) * cos(0.7 * j));
    sb_printf(&b, "cstype bezier\ndeg 3 3\nsurf 0 1 0 1 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16\nend\n");
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (parse_set(&b, "plate.obj", &set) && make_model(&set, &m)) {
        tsr_ptess_options o = {0};
        o.max_error = 0.01;
        tsr_ptess_result r;
        tsr_ptess_measure_result before = {0}, after = {0};
        if (run_ptess(m, &o, &r) && tsr_ptess_measure(m, &r, 64, NULL, false, NULL, &before) == TSR_OK) {
            /* the sliver (0.1, 0.9) (0.11, 0.89) (0.105, 0.895 + 1 ulp),
             * first: no sample lies within its box, many lie along its
             * line, the domain's corner (0, 1) among them */
            const double uv[6] = {0.1, 0.9, 0.11, 0.89, 0.105, nextafter(0.895, 1)};
            uint32_t v[3];
            for (int k = 0; k < 3; k++) {
                double pos[3];
                CHECK(tsr_pmodel_eval(m, 0, uv[2 * k], uv[2 * k + 1], pos, NULL) == TSR_OK);
                float f[3] = {(float)pos[0], (float)pos[1], (float)pos[2]};
                v[k] = tsr_mesh_add_vertex(&r.mesh, f, NULL, NULL);
            }
            uint32_t n = r.mesh.triangle_count;
            const tsr_allocator *a = r.alloc.realloc ? &r.alloc : NULL;
            uint32_t *src = tsr_realloc(a, r.tri_source, ((size_t)n + 1) * sizeof *src);
            double *tuv = src ? tsr_realloc(a, r.tri_uv, ((size_t)n + 1) * 6 * sizeof *tuv) : NULL;
            if (src)
                r.tri_source = src;
            if (tuv)
                r.tri_uv = tuv;
            if (tuv && tsr_mesh_add_triangle(&r.mesh, v[0], v[1], v[2])) {
                memmove(r.mesh.indices + 3, r.mesh.indices, (size_t)n * 3 * sizeof *r.mesh.indices);
                memcpy(r.mesh.indices, v, sizeof v);
                memmove(src + 1, src, (size_t)n * sizeof *src);
                src[0] = 0;
                memmove(tuv + 6, tuv, (size_t)n * 6 * sizeof *tuv);
                memcpy(tuv, uv, sizeof uv);
                /* the sliver's own edges: their chords' error, measured at
                 * their midpoints */
                double chord = 0;
                for (int k = 0; k < 3; k++) {
                    const double *p0 = uv + 2 * k, *p1 = uv + 2 * ((k + 1) % 3);
                    double mid[3], a0[3], a1[3];
                    tsr_pmodel_eval(m, 0, 0.5 * (p0[0] + p1[0]), 0.5 * (p0[1] + p1[1]), mid, NULL);
                    tsr_pmodel_eval(m, 0, p0[0], p0[1], a0, NULL);
                    tsr_pmodel_eval(m, 0, p1[0], p1[1], a1, NULL);
                    double d2 = 0;
                    for (int x = 0; x < 3; x++)
                        d2 += (mid[x] - 0.5 * (a0[x] + a1[x])) * (mid[x] - 0.5 * (a0[x] + a1[x]));
                    chord = fmax(chord, sqrt(d2));
                }
                CHECK(tsr_ptess_measure(m, &r, 64, NULL, false, NULL, &after) == TSR_OK);
                double want = fmax(before.max_error, chord) + 1e-5;
                CHECK_MSG(after.max_error <= want, "with the sliver: %g at (%g, %g), without %g, its chords %g",
                          after.max_error, after.worst_uv[0], after.worst_uv[1], before.max_error, chord);
            } else
                CHECK(!"out of memory");
        }
        tsr_ptess_result_free(&r);
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* CAD files trim every face by its own boundary. Two bicubic B-splines
 * with interior knots (several Bezier pieces each) share the edge x = 30,
 * each trimmed by a loop along its whole domain boundary: the seam must
 * weld as it does untrimmed (no open edge off the outer rectangle, no
 * T-junction, no zero-area triangle; it had 186 open edges along the seam
 * and 55 zero-area triangles). And a rational sphere (collapsed poles, a
 * seam) trimmed by its domain is closed like the untrimmed one (it had 384
 * open edges and 256 zero-area triangles at the poles). */
/* A loop around [0, 1]^2, inset by d (CAD files give it to 1e-6 .. 1e-4;
 * 0 trims nothing, TSR_PMODEL_VOID_TRIM). */
static void domain_trim(sbuf *b, int vp0, double d)
{
    sb_printf(b, "vp %.17g %.17g\nvp %.17g %.17g\nvp %.17g %.17g\nvp %.17g %.17g\nvp %.17g %.17g\n", d, d, 1 - d, d,
              1 - d, 1 - d, d, 1 - d, d, d);
    sb_printf(b, "cstype bspline\ndeg 1\ncurv2 %d %d %d %d %d\nparm u 0 0 1 2 3 4 4\nend\n", vp0 + 1, vp0 + 2, vp0 + 3,
              vp0 + 4, vp0 + 5);
}

static void pair_check(void *user, const tsr_ptess_result *r, double E)
{
    int trimmed = *(const int *)user;
    tsr_validation v = validate(&r->mesh);
    uint32_t inner = 0; /* open edges not on the outer rectangle */
    tsr_halfedges he;
    CHECK(tsr_halfedges_build(&he, &r->mesh, NULL) == TSR_OK);
    for (uint32_t h = 0; h < he.count; h++) {
        if (he.twin[h] != TSR_NO_TWIN)
            continue;
        const float *p = r->mesh.positions + 3 * (size_t)r->mesh.indices[h],
                    *q = r->mesh.positions + 3 * (size_t)r->mesh.indices[3 * (h / 3) + (h % 3 + 1) % 3];
        bool rim = (p[0] == q[0] && (p[0] == 0 || p[0] == 60)) || (p[1] == q[1] && (p[1] == 0 || p[1] == 30));
        inner += !rim;
    }
    tsr_halfedges_free(&he);
    CHECK_MSG(inner == 0 && v.t_junctions == 0 && v.degenerate_triangles == 0 && v.nonmanifold_edges == 0,
              "%s E %g: %u open edges inside, %u T-junctions, %u degenerate, %u non-manifold",
              trimmed ? "trimmed" : "untrimmed", E, inner, v.t_junctions, v.degenerate_triangles, v.nonmanifold_edges);
}

static void sphere_check(void *user, const tsr_ptess_result *r, double E)
{
    int trimmed = *(const int *)user;
    tsr_validation v = validate(&r->mesh);
    CHECK_MSG(v.boundary_edges == 0 && v.degenerate_triangles == 0 && v.nonmanifold_edges == 0 &&
                  v.misoriented_edges == 0,
              "%s sphere E %g: %u open edges, %u degenerate, %u non-manifold, %u misoriented",
              trimmed ? "trimmed" : "untrimmed", E, v.boundary_edges, v.degenerate_triangles, v.nonmanifold_edges,
              v.misoriented_edges);
}

TEST(domain_trimmed_surfaces_weld)
{
    /* trimmed: 0 no loop, 1 a loop along the border (no trim), 2 one 1e-7
     * inside it (trimmed: the loop is snapped onto the border) */
    for (int trimmed = 0; trimmed < 3; trimmed++) {
        sbuf b = {0};
        for (int side = 0; side < 2; side++) {
            if (trimmed)
                domain_trim(&b, 5 * side, trimmed == 2 ? 1e-7 : 0);
            for (int j = 0; j < 6; j++)
                for (int i = 0; i < 6; i++) {
                    double x = 30.0 * side + 6.0 * i, y = 6.0 * j;
                    sb_printf(&b, "v %.17g %.17g %.17g\n", x, y, 3 * sin(x * 0.07) * cos(y * 0.09));
                }
            sb_printf(&b, "cstype bspline\ndeg 3 3\nsurf 0 1 0 1");
            for (int k = 1; k <= 36; k++)
                sb_printf(&b, " %d", 36 * side + k);
            sb_printf(&b, "\nparm u 0 0 0 0 0.4 0.7 1 1 1 1\nparm v 0 0 0 0 0.3 0.6 1 1 1 1\n");
            if (trimmed)
                sb_printf(&b, "trim 0 4 %d\n", side + 1);
            sb_printf(&b, "end\n");
        }
        over_bounds(&b,
                    trimmed == 2 ? "pair_trimmed.obj"
                    : trimmed    ? "pair_border.obj"
                                 : "pair.obj",
                    0.1, 0.001, pair_check, &trimmed);
        free(b.s);
    }
    /* the sphere: 9 x 5 rational control points, u around (0..4), v from
     * pole to pole (0..2), trimmed by its domain */
    for (int trimmed = 0; trimmed < 3; trimmed++) {
        sbuf b = {0};
        static const double C[9][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}, {-1, -1}, {0, -1}, {1, -1}, {1, 0}};
        static const double M[5][2] = {{0, -1}, {1, -1}, {1, 0}, {1, 1}, {0, 1}};
        double d = trimmed == 2 ? 2e-7 : 0;
        if (trimmed)
            sb_printf(&b,
                      "vp %.17g %.17g\nvp %.17g %.17g\nvp %.17g %.17g\nvp %.17g %.17g\nvp %.17g %.17g\n"
                      "cstype bspline\ndeg 1\ncurv2 1 2 3 4 5\nparm u 0 0 1 2 3 4 4\nend\n",
                      d, d, 4 - d, d, 4 - d, 2 - d, d, 2 - d, d, d);
        for (int j = 0; j < 5; j++)
            for (int i = 0; i < 9; i++)
                sb_printf(&b, "v %.17g %.17g %.17g %.17g\n", 20 * C[i][0] * M[j][0], 20 * C[i][1] * M[j][0],
                          20 * M[j][1], (i % 2 ? H2 : 1.0) * (j % 2 ? H2 : 1.0));
        sb_printf(&b, "cstype rat bspline\ndeg 2 2\nsurf 0 4 0 2");
        for (int k = 1; k <= 45; k++)
            sb_printf(&b, " %d", k);
        sb_printf(&b, "\nparm u 0 0 0 1 1 2 2 3 3 4 4 4\nparm v 0 0 0 1 1 2 2 2\n%send\n", trimmed ? "trim 0 4 1\n" : "");
        over_bounds(&b,
                    trimmed == 2 ? "sphere_trimmed.obj"
                    : trimmed    ? "sphere_border.obj"
                                 : "sphere.obj",
                    0.3, 0.003, sphere_check, &trimmed);
        free(b.s);
    }
}

/* Patch edges a small gap apart (as CAD files leave them): linked and
 * welded within the link distance (default 1e-6 of the diagonal, or the
 * one given), open beyond it. Two bicubic patches meet at x = 30, the
 * second's edge control points raised by gap in z. */
static uint32_t seam_open_edges(double gap, double link_tol)
{
    sbuf b = {0};
    for (int side = 0; side < 2; side++) {
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 4; i++) {
                double x = 30.0 * side + 10.0 * i, y = 10.0 * j, z = 2 * sin(x * 0.05) * cos(y * 0.07);
                sb_printf(&b, "v %.17g %.17g %.17g\n", x, y, z + (side == 1 && i == 0 ? gap : 0));
            }
        sb_printf(&b, "cstype bezier\ndeg 3 3\nsurf 0 1 0 1");
        for (int k = 1; k <= 16; k++)
            sb_printf(&b, " %d", 16 * side + k);
        sb_printf(&b, "\nend\n");
    }
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    uint32_t inner = UINT32_MAX;
    if (parse_set(&b, "gap.obj", &set)) {
        tsr_error e = {0};
        CHECK_MSG(tsr_pmodel_from_set_tol(&set, link_tol, NULL, &m, &e) == TSR_OK, "%s", e.message);
        tsr_ptess_options o = {0};
        o.max_error = 0.01;
        tsr_ptess_result r;
        if (m && run_ptess(m, &o, &r)) {
            tsr_halfedges he;
            CHECK(tsr_halfedges_build(&he, &r.mesh, NULL) == TSR_OK);
            inner = 0;
            for (uint32_t h = 0; h < he.count; h++) {
                const float *p = r.mesh.positions + 3 * (size_t)r.mesh.indices[h],
                            *q = r.mesh.positions + 3 * (size_t)r.mesh.indices[3 * (h / 3) + (h % 3 + 1) % 3];
                inner += he.twin[h] == TSR_NO_TWIN && p[0] == q[0] && p[0] > 1 && p[0] < 59;
            }
            tsr_halfedges_free(&he);
            tsr_ptess_result_free(&r);
        }
        tsr_pmodel_destroy(m);
        tsr_patch_set_free(&set);
    }
    free(b.s);
    return inner;
}

TEST(patch_edges_a_gap_apart_weld_within_the_link_distance)
{
    double diag = sqrt(60.0 * 60 + 30 * 30 + 4 * 4); /* about; the gaps below are far from the limits */
    CHECK_MSG(seam_open_edges(0, 0) == 0, "no gap: %u open seam edges", seam_open_edges(0, 0));
    CHECK_MSG(seam_open_edges(1e-7 * diag, 0) == 0, "a 1e-7 gap, default link distance: open seam");
    CHECK_MSG(seam_open_edges(1e-4 * diag, 0) > 0, "a 1e-4 gap was linked by the default 1e-6 distance");
    CHECK_MSG(seam_open_edges(1e-4 * diag, 1e-3 * diag) == 0, "a 1e-4 gap, link distance 1e-3: open seam");
}

/* ---- edges with other knots or degrees ------------------------------------------------ */

/* Boehm's knot insertion of x into a cubic B-spline curve (n points, knots
 * n + 4): the same curve with n + 1 points and knots n + 5. */
static void insert_knot(const double *P, const double *U, int n, double x, double *Q, double *V)
{
    int k = 3;
    while (k + 1 < n && U[k + 1] <= x)
        k++;
    for (int i = 0; i <= n; i++) {
        const double *a = P + 3 * (i < n ? i : n - 1), *b = P + 3 * (i > 0 ? i - 1 : 0);
        double al = i <= k - 3 ? 1 : i > k ? 0 : (x - U[i]) / (U[i + 3] - U[i]);
        for (int c = 0; c < 3; c++)
            Q[3 * i + c] = al * a[c] + (1 - al) * b[c];
    }
    for (int i = 0, j = 0; i < n + 5; i++)
        V[i] = i == k + 1 ? x : U[j++];
}

static void put_bspline(sbuf *b, int *next, const double *P, int nu, int nv, int du, int dv, const double *ku,
                        const double *kv)
{
    for (int k = 0; k < nu * nv; k++)
        sb_printf(b, "v %.17g %.17g %.17g\n", P[3 * k], P[3 * k + 1], P[3 * k + 2]);
    sb_printf(b, "cstype %s\ndeg %d %d\nsurf 0 1 0 1", ku ? "bspline" : "bezier", du, dv);
    for (int k = 0; k < nu * nv; k++)
        sb_printf(b, " %d", *next + k);
    *next += nu * nv;
    if (ku) {
        sb_printf(b, "\nparm u");
        for (int k = 0; k < nu + du + 1; k++)
            sb_printf(b, " %.17g", ku[k]);
        sb_printf(b, "\nparm v");
        for (int k = 0; k < nv + dv + 1; k++)
            sb_printf(b, " %.17g", kv[k]);
    }
    sb_printf(b, "\nend\n");
}

/* Four patches around A, a bicubic B-spline with a knot at u = 0.3: B to
 * its north with a knot inserted at 0.75 on their common edge, D to its
 * south running the other way (mirrored) with a knot at 0.45 of its own
 * parameter (0.55 of A's), C to its east of degree 1 x 4 whose west
 * column is A's east column raised to degree 4. bump moves the middle
 * point of B's south row up. */
static void knot_scene(sbuf *b, double bump)
{
    static const double ku[9] = {0, 0, 0, 0, 0.3, 1, 1, 1, 1}, kv[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    double A[5 * 4 * 3];
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 5; i++) {
            double g = (ku[i + 1] + ku[i + 2] + ku[i + 3]) / 3, x = 4 * g, y = j;
            double *p = A + 3 * (j * 5 + i);
            p[0] = x;
            p[1] = y;
            p[2] = 0.4 * sin(1.1 * x + 0.7 * y);
        }
    int next = 1;
    put_bspline(b, &next, A, 5, 4, 3, 3, ku, kv);
    /* B: its south row is A's north row with 0.75 inserted */
    double B[6 * 4 * 3], kuB[10];
    insert_knot(A + 3 * 15, ku, 5, 0.75, B, kuB);
    B[3 * 2 + 2] += bump;
    for (int j = 1; j < 4; j++)
        for (int i = 0; i < 6; i++) {
            double *p = B + 3 * (j * 6 + i);
            p[0] = B[3 * i];
            p[1] = B[3 * i + 1] + j;
            p[2] = B[3 * i + 2] + 0.2 * j * sin(1.0 + i);
        }
    put_bspline(b, &next, B, 6, 4, 3, 3, kuB, kv);
    /* C: A's east column (a cubic Bezier in v) raised to degree 4 */
    double C[2 * 5 * 3];
    for (int j = 0; j <= 4; j++) {
        const double *lo = A + 3 * ((j > 0 ? j - 1 : 0) * 5 + 4), *hi = A + 3 * ((j < 4 ? j : 3) * 5 + 4);
        double al = j / 4.0;
        for (int c = 0; c < 3; c++)
            C[3 * (2 * j) + c] = al * lo[c] + (1 - al) * hi[c];
        C[3 * (2 * j + 1)] = C[3 * (2 * j)] + 1.5;
        C[3 * (2 * j + 1) + 1] = C[3 * (2 * j) + 1];
        C[3 * (2 * j + 1) + 2] = C[3 * (2 * j) + 2] + 0.2;
    }
    put_bspline(b, &next, C, 2, 5, 1, 4, NULL, NULL);
    /* D: A's south row backwards (knots 1 - k) with 0.45 inserted, as its
     * north row; its rows below run south */
    double rev[5 * 3], kr[9], D[6 * 4 * 3], kuD[10];
    for (int i = 0; i < 5; i++)
        memcpy(rev + 3 * i, A + 3 * (4 - i), 3 * sizeof *rev);
    for (int k = 0; k < 9; k++)
        kr[k] = 1 - ku[8 - k];
    insert_knot(rev, kr, 5, 0.45, D + 3 * 18, kuD);
    for (int j = 0; j < 3; j++)
        for (int i = 0; i < 6; i++) {
            double *p = D + 3 * (j * 6 + i);
            const double *q = D + 3 * (18 + i);
            p[0] = q[0];
            p[1] = q[1] - (3 - j);
            p[2] = q[2] + 0.15 * (3 - j) * cos(0.5 + i);
        }
    put_bspline(b, &next, D, 6, 4, 3, 3, kuD, kv);
}

TEST(edges_of_other_knots_and_degrees_link)
{
    for (int variant = 0; variant < 2; variant++) {
        sbuf b = {0};
        knot_scene(&b, variant ? 0.01 : 0);
        tsr_patch_set set;
        tsr_pmodel *m = NULL;
        if (!parse_set(&b, "knots.obj", &set)) {
            free(b.s);
            continue;
        }
        if (make_model(&set, &m)) {
            tsr_pmodel_info info;
            tsr_pmodel_get_info(m, &info);
            /* A takes 0.55 (from D) and 0.75 (from B), B 0.55, D 0.25:
             * 4 + 4 + 1 + 4 pieces; links: 3 inside each of A, B, D and
             * 4 + 4 + 1 across, each side counted. With B's row bumped it
             * shares nothing: A takes only 0.55 (3 + 3 + 1 + 3 pieces, 4 + 4 +
             * 4 links inside, 3 + 1 across). */
            uint32_t want_breaks = variant ? 1 : 4, want_pieces = variant ? 10 : 13, want_links = variant ? 20 : 36;
            CHECK_MSG(info.sources == 4 && info.pieces == want_pieces && info.conform_breaks == want_breaks,
                      "variant %d: sources %u pieces %u breaks %u", variant, info.sources, info.pieces,
                      info.conform_breaks);
            CHECK_MSG(info.links == want_links, "variant %d: %u links, want %u", variant, info.links, want_links);
            tsr_psource_info si;
            CHECK(tsr_pmodel_source_info(m, 3, &si) && si.pieces_u == (variant ? 3u : 4u) && si.mirrored);
            CHECK_MSG(info.mirrored == si.pieces_u, "%u mirrored", info.mirrored);
            for (double E = 1e-2; E >= 0.99e-3; E /= 10) {
                tsr_ptess_options o = {0};
                o.max_error = E;
                tsr_ptess_result r;
                if (!run_ptess(m, &o, &r))
                    continue;
                tsr_validation v = validate(&r.mesh);
                char what[64];
                snprintf(what, sizeof what, "variant %d E %g", variant, E);
                CHECK_MSG(v.misoriented_edges == 0 && v.nonmanifold_edges == 0 && v.degenerate_triangles == 0,
                          "%s: misoriented %u non-manifold %u degenerate %u", what, v.misoriented_edges,
                          v.nonmanifold_edges, v.degenerate_triangles);
                if (variant == 0) {
                    /* one disc: every seam closed */
                    check_conforming(what, &v);
                    CHECK_MSG(v.boundary_loops == 1 && v.euler == 1 && v.coincident_vertices == 0,
                              "%s: loops %u euler %lld coincident %u", what, v.boundary_loops, (long long)v.euler,
                              v.coincident_vertices);
                } else {
                    /* B apart, its seam with A open */
                    CHECK_MSG(v.boundary_loops == 2, "%s: %u boundary loops, want 2", what, v.boundary_loops);
                }
                tsr_ptess_measure_result mr;
                memset(&mr, 0, sizeof mr);
                CHECK(tsr_ptess_measure(m, &r, 9, NULL, false, NULL, &mr) == TSR_OK);
                double sl = fslack(mesh_maxabs(&r.mesh));
                CHECK_MSG(mr.max_error <= E + sl && mr.uncovered == 0, "%s: measured %g, %llu uncovered", what,
                          mr.max_error, (unsigned long long)mr.uncovered);
                if (v.boundary_loops != (variant ? 2u : 1u))
                    describe(what, &v);
                tsr_ptess_result_free(&r);
            }
        }
        tsr_pmodel_destroy(m);
        tsr_patch_set_free(&set);
        free(b.s);
    }
}

/* ---- pieces cut across their curve (split_error) ------------------------------------- */

/* A parabolic extrusion (degree 2 across x, straight along y) and a
 * neighbour sharing its north edge (y = 40): a longer piece of the same
 * extrusion (bicubic along y), or, with `curved`, one that bulges along y
 * too. Without cuts every piece is sampled along y as finely as along x. */
static void extrusion_scene(sbuf *b, bool curved)
{
    static const double ku[6] = {0, 0, 0, 1, 1, 1}, kv[4] = {0, 0, 1, 1}, kw[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    double A[3 * 2 * 3], B[3 * 4 * 3];
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 3; i++) {
            double *p = A + 3 * (j * 3 + i);
            p[0] = 25.0 * (i - 1);
            p[1] = 40.0 * j;
            p[2] = i == 1 ? -25 : 25;
        }
    int next = 1;
    put_bspline(b, &next, A, 3, 2, 2, 1, ku, kv);
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 3; i++) {
            double *p = B + 3 * (j * 3 + i);
            p[0] = A[3 * (3 + i)];
            p[1] = 40.0 + 10.0 * j;
            p[2] = A[3 * (3 + i) + 2] + (curved && j ? 3.0 * sin(1.0 + i + j) : 0);
        }
    put_bspline(b, &next, B, 3, 4, 2, 3, ku, kw);
}

TEST(split_error_cuts_extrusions_across_their_curve)
{
    for (int curved = 0; curved < 2; curved++) {
        sbuf b = {0};
        extrusion_scene(&b, curved);
        tsr_patch_set set;
        if (!parse_set(&b, "extrusion.obj", &set)) {
            free(b.s);
            continue;
        }
        for (double E = 1e-2; E >= 0.99e-3; E /= 10) {
            uint32_t tri[2] = {0, 0};
            for (int split = 0; split < 2; split++) {
                tsr_pmodel *m = NULL;
                tsr_error e = {0};
                tsr_pmodel_set_options mo = {0, split ? E : 0, 4};
                CHECK_MSG(tsr_pmodel_from_set_opts(&set, &mo, NULL, &m, &e) == TSR_OK, "%s", e.message);
                if (!m)
                    continue;
                tsr_pmodel_info info;
                tsr_pmodel_get_info(m, &info);
                if (split && !curved)
                    CHECK_MSG(info.split_breaks >= 4 && info.pieces >= 10, "E %g: %u cuts, %u pieces", E,
                              info.split_breaks, info.pieces);
                if (!split)
                    CHECK(info.split_breaks == 0 && info.pieces == 2);
                tsr_ptess_options o = {0};
                o.max_error = E;
                tsr_ptess_result r;
                if (run_ptess(m, &o, &r)) {
                    char what[64];
                    snprintf(what, sizeof what, "curved %d E %g split %d", curved, E, split);
                    tsr_validation v = validate(&r.mesh);
                    check_conforming(what, &v);
                    CHECK_MSG(v.boundary_loops == 1 && v.euler == 1, "%s: loops %u euler %lld", what,
                              v.boundary_loops, (long long)v.euler);
                    tsr_ptess_measure_result mr;
                    memset(&mr, 0, sizeof mr);
                    CHECK(tsr_ptess_measure(m, &r, 9, NULL, false, NULL, &mr) == TSR_OK);
                    CHECK_MSG(mr.max_error <= E + fslack(mesh_maxabs(&r.mesh)) && mr.uncovered == 0,
                              "%s: measured %g", what, mr.max_error);
                    tri[split] = r.mesh.triangle_count;
                    tsr_ptess_result_free(&r);
                }
                tsr_pmodel_destroy(m);
            }
            /* the extrusion needs (200 / 8E)^(1/2) samples across x and
             * one row along y, where an isotropic tree makes that many
             * rows; a neighbour curved along y would take the cuts too
             * (they are shared) and cost more than they save: then the
             * model is left uncut, or cut where the estimate still gains */
            if (!curved)
                CHECK_MSG(tri[1] > 0 && 4 * tri[1] <= tri[0], "E %g: %u triangles with cuts, %u without", E, tri[1],
                          tri[0]);
            else
                CHECK_MSG(tri[1] > 0 && tri[1] <= tri[0], "curved, E %g: %u triangles with cuts, %u without", E,
                          tri[1], tri[0]);
        }
        tsr_patch_set_free(&set);
        free(b.s);
    }
}

/* Rational Bézier nets with weights a product a_i b_j (as surfaces of
 * revolution and tori have) take a mixed-derivative bound of their own
 * (ptess.c, separable_mixed): random twisted nets, weights spread 20:1,
 * degrees 1..4, with and without a product form, must measure within the
 * reported bound on 64 x 64 samples and every edge midpoint. */
TEST(rational_product_weights_within_bound)
{
    uint64_t seed = 0x9e3779b97f4a7c15u;
#define RNDU() ((seed = seed * 6364136223846793005u + 1442695040888963407u) >> 11) * (1.0 / 9007199254740992.0)
    uint32_t runs = 0;
    for (int k = 0; k < 24; k++) {
        int du = 1 + k % 4, dv = 1 + (k / 4) % 4;
        bool product = k % 3 != 2;
        double a[5], bw[5];
        for (int i = 0; i <= du; i++)
            a[i] = 0.25 + 4.75 * RNDU();
        for (int j = 0; j <= dv; j++)
            bw[j] = 0.25 + 4.75 * RNDU();
        sbuf b = {0};
        for (int j = 0; j <= dv; j++)
            for (int i = 0; i <= du; i++) {
                /* a twisted sheet: bilinear twist plus noise */
                double x = i + 0.4 * RNDU(), y = j + 0.4 * RNDU(), z = 0.8 * i * j / (du * dv + 1.0) + RNDU();
                double w = product ? a[i] * bw[j] : 0.25 + 4.75 * RNDU();
                sb_printf(&b, "v %.17g %.17g %.17g %.17g\n", x, y, z, w);
            }
        sb_printf(&b, "cstype rat bezier\ndeg %d %d\nsurf 0 1 0 1", du, dv);
        for (int q = (du + 1) * (dv + 1); q > 0; q--)
            sb_printf(&b, " -%d", q);
        sb_printf(&b, "\nend\n");
        tsr_patch_set set;
        tsr_pmodel *m = NULL;
        if (parse_set(&b, "product.obj", &set) && make_model(&set, &m)) {
            for (double E = 3e-2; E >= 0.99e-3; E /= 5.5) {
                tsr_ptess_options o = {0};
                o.max_error = E;
                o.tile_n = k % 2 ? 2 : 4;
                tsr_ptess_result r;
                if (!run_ptess(m, &o, &r))
                    continue;
                tsr_ptess_measure_result mr;
                memset(&mr, 0, sizeof mr);
                CHECK(tsr_ptess_measure(m, &r, 64, NULL, false, NULL, &mr) == TSR_OK);
                double sl = fslack(mesh_maxabs(&r.mesh));
                CHECK_MSG(mr.max_error <= r.bound + sl && r.bound <= E && mr.uncovered == 0,
                          "net %d (degree %d x %d, %s weights), E %g: measured %g, bound %g", k, du, dv,
                          product ? "product" : "other", E, mr.max_error, r.bound);
                runs++;
                tsr_ptess_result_free(&r);
            }
        }
        tsr_pmodel_destroy(m);
        tsr_patch_set_free(&set);
        free(b.s);
    }
#undef RNDU
    CHECK(runs == 24 * 3);
}

/* A rational quarter cylinder cut across its curve (split_error) comes
 * near a strip: its mixed derivative is zero, so the pieces need no rows
 * along the axis beyond one tile's. The oracle: the fewest columns whose
 * chords keep within E of the circle, ceil((pi / 2) / (2 acos(1 - E /
 * R))), times 2 triangles; the parametric error the bound controls is at
 * least the chord's, and the cut pieces are single tiles of 2 x 2 quads
 * (half tiles: choose_tile), so 4 x that (one tile's two rows per column)
 * is the budget (4 x 4 tiles, without half tiles, make 5.3-6 x).
 * Measured within E. */
TEST(rational_cylinder_cut_near_its_strip)
{
    cylinder c = {0.5, -1.25, 0.25, 2, 3};
    sbuf b = {0};
    cyl_obj(&b, &c);
    tsr_patch_set set;
    if (!parse_set(&b, "cylinder.obj", &set)) {
        free(b.s);
        return;
    }
    for (double E = 1e-2; E >= 0.99e-4; E /= 10) {
        tsr_pmodel *m = NULL;
        tsr_error e = {0};
        tsr_pmodel_set_options mo = {0, E, 4};
        CHECK_MSG(tsr_pmodel_from_set_opts(&set, &mo, NULL, &m, &e) == TSR_OK, "%s", e.message);
        tsr_ptess_options o = {0};
        o.max_error = E;
        tsr_ptess_result r;
        if (m && run_ptess(m, &o, &r)) {
            double cols = ceil((PI / 2) / (2 * acos(1 - E / c.R)));
            tsr_ptess_measure_result mr;
            memset(&mr, 0, sizeof mr);
            CHECK(tsr_ptess_measure(m, &r, 16, NULL, false, NULL, &mr) == TSR_OK);
            fprintf(stderr, "  E %g: %u triangles, strip %g, measured %.3g\n", E, r.mesh.triangle_count, 2 * cols,
                    mr.max_error);
            CHECK_MSG(r.mesh.triangle_count <= 4 * 2 * cols, "E %g: %u triangles against a strip of %g", E,
                      r.mesh.triangle_count, 2 * cols);
            CHECK_MSG(mr.max_error <= E + fslack(mesh_maxabs(&r.mesh)) && mr.uncovered == 0, "E %g: measured %g", E,
                      mr.max_error);
            tsr_validation v = validate(&r.mesh);
            check_conforming("cut cylinder", &v);
            CHECK(v.boundary_loops == 1 && v.euler == 1);
            tsr_ptess_result_free(&r);
        }
        tsr_pmodel_destroy(m);
    }
    tsr_patch_set_free(&set);
    free(b.s);
}

/* The long quarter cylinder (rational, along x from 0 to VL) and a camera
 * looking along it from near its start: parsed into *set; false (after a
 * failed CHECK) when it does not parse. */
static bool long_cylinder_scene(tsr_patch_set *set, tsr_camera *cam)
{
    sbuf b = {0};
    const double A[3][2] = {{1, 0}, {1, 1}, {0, 1}}, w[3] = {1, H2, 1};
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 3; i++)
            sb_printf(&b, "v %.17g %.17g %.17g %.17g\n", VL * j, VR * A[i][0], VR * A[i][1], w[i]);
    sb_printf(&b, "cstype rat bezier\ndeg 2 1\nsurf 0 1 0 1 -6 -5 -4 -3 -2 -1\nend\n");
    bool ok = parse_set(&b, "long_cylinder.obj", set);
    free(b.s);
    if (!ok)
        return false;
    memset(cam, 0, sizeof *cam);
    const double eye[3] = {-2, 2.5, 1.8}, target[3] = {10, 0.3, 0.3};
    memcpy(cam->eye, eye, sizeof eye);
    memcpy(cam->target, target, sizeof target);
    cam->fovy_deg = 50;
    cam->width = 1024;
    cam->height = 768;
    cam->near_dist = 0.05;
    cam->pixel_error = 0.5;
    CHECK(tsr_camera_prepare(cam));
    return true;
}

TEST(camera_near_finer)
{
    tsr_patch_set set;
    tsr_camera cam;
    tsr_pmodel *m = NULL;
    if (!long_cylinder_scene(&set, &cam))
        return;
    /* fine enough that the tree is several levels deep along the axis (a
     * cylinder's bounds need no rows along it for their own sake); levels
     * come in steps of 4 in error, so near and far can land on one level
     * at some bounds (0.15 px did with tiles of 8 once the rational bound
     * was tightened) */
    cam.pixel_error = 0.1;
    /* the regions compared are in view: their corners project inside */
    const double probes[4][3] = {{1, 1, 0}, {1, 0, 1}, {20, 1, 0}, {20, 0, 1}};
    for (int k = 0; k < 4; k++) {
        double x, y, d;
        project(&cam, probes[k], &x, &y, &d);
        CHECK_MSG(x > 0 && x < cam.width && y > 0 && y < cam.height && d > cam.near_dist, "probe %d at %g %g", k, x, y);
    }
    if (make_model(&set, &m)) {
        for (int pass = 0; pass < 2; pass++) {
            tsr_ptess_options opt = {0};
            opt.camera = &cam;
            opt.tile_n = pass ? 8 : 4;
            tsr_ptess_result r;
            if (run_ptess(m, &opt, &r)) {
                check_shape(m, &r, false);
                sampling s = {vcyl_truth, NULL, NULL, &cam, NULL, 0, 0, 0, 0, 0, 0, 0, 0, {0, 0}};
                sample_result(&r, &s);
                CHECK(s.in_view > 1000);
                CHECK_MSG(s.pixel_error <= cam.pixel_error + 1e-2, "tile %u: screen error %g px > %g", opt.tile_n,
                          s.pixel_error, cam.pixel_error);
                /* density: triangles per unit of surface area, near (x in [1, 4],
                 * depth about 4) against far (x in [16, 20], depth about 20):
                 * a screen error bound makes h^2 grow with depth, so the
                 * density falls about fivefold; at least twofold is asked */
                double area[2] = {0, 0};
                uint32_t count[2] = {0, 0};
                for (uint32_t t = 0; t < r.mesh.triangle_count; t++) {
                    double cx = 0;
                    for (int k = 0; k < 3; k++)
                        cx += r.mesh.positions[3 * r.mesh.indices[3 * t + k]] / 3.0;
                    int region = cx >= 1 && cx <= 4 ? 0 : cx >= 16 && cx <= 20 ? 1 : -1;
                    if (region < 0)
                        continue;
                    double fn[3];
                    face_normal(&r.mesh, t, fn);
                    area[region] += sqrt(dot3(fn, fn)) / 2;
                    count[region]++;
                }
                double dn = count[0] / fmax(area[0], 1e-30), df = count[1] / fmax(area[1], 1e-30);
                fprintf(
                    stderr,
                    "  tile %u: %u triangles, %u leaves, screen error %.3g px; near %u (%.1f per unit area), far %u "
                    "(%.1f)\n",
                    opt.tile_n, r.mesh.triangle_count, r.leaves, s.pixel_error, count[0], dn, count[1], df);
                CHECK_MSG(count[1] > 0 && dn >= 2 * df, "near density %g, far %g", dn, df);
                tsr_validation v = validate(&r.mesh);
                check_conforming("camera", &v);
                tsr_ptess_measure_result mr;
                memset(&mr, 0, sizeof mr);
                CHECK(tsr_ptess_measure(m, &r, 9, &cam, false, NULL, &mr) == TSR_OK);
                CHECK_MSG(mr.max_error <= cam.pixel_error + 1e-2, "measured %g px", mr.max_error);
                CHECK(mr.uncovered == 0);
            }
            tsr_ptess_result_free(&r);
        }
        /* a tighter pixel error refines more */
        tsr_ptess_options opt = {0};
        opt.camera = &cam;
        tsr_ptess_result r1, r2;
        bool ok1 = run_ptess(m, &opt, &r1);
        tsr_camera cam2 = cam;
        cam2.pixel_error = 0.03;
        opt.camera = &cam2;
        bool ok2 = run_ptess(m, &opt, &r2);
        if (ok1 && ok2)
            CHECK_MSG(r2.mesh.triangle_count > r1.mesh.triangle_count, "%u triangles at 0.03 px, %u at 0.15 px",
                      r2.mesh.triangle_count, r1.mesh.triangle_count);
        tsr_ptess_result_free(&r1);
        tsr_ptess_result_free(&r2);
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
}

/* Runs share a model: the second run (tile patterns now kept with the
 * model) and two runs from two threads at once give the first run's mesh,
 * vertex for vertex. */
typedef struct shared_run {
    const tsr_pmodel *m;
    tsr_ptess_options opt;
    tsr_ptess_result r;
    tsr_status st;
} shared_run;

static int shared_run_main(void *arg)
{
    shared_run *sr = arg;
    tsr_error err = {0};
    sr->st = tsr_ptess_run(sr->m, &sr->opt, NULL, &sr->r, &err);
    return 0;
}

/* The same vertices (and normals), triangles and triangles' (u, v) and
 * sources, bit for bit. */
static bool same_mesh(const tsr_ptess_result *a, const tsr_ptess_result *b)
{
    const tsr_mesh *x = &a->mesh, *y = &b->mesh;
    size_t nv = x->vertex_count, nt = x->triangle_count;
    return nv == y->vertex_count && nt == y->triangle_count &&
           !memcmp(x->positions, y->positions, 3 * sizeof(float) * nv) &&
           !memcmp(x->indices, y->indices, 3 * sizeof(uint32_t) * nt) && !x->normals == !y->normals &&
           (!x->normals || !memcmp(x->normals, y->normals, 3 * sizeof(float) * nv)) &&
           !memcmp(a->tri_uv, b->tri_uv, 6 * sizeof(double) * nt) &&
           !memcmp(a->tri_source, b->tri_source, sizeof(uint32_t) * nt);
}

TEST(runs_share_model)
{
    tsr_patch_set set;
    tsr_camera cam;
    tsr_pmodel *m = NULL, *m2 = NULL;
    if (!long_cylinder_scene(&set, &cam))
        return;
    if (make_model(&set, &m) && make_model(&set, &m2)) {
        tsr_ptess_options opt = {0};
        opt.camera = &cam;
        tsr_ptess_result first, second;
        bool ok1 = run_ptess(m, &opt, &first), ok2 = run_ptess(m, &opt, &second);
        if (ok1 && ok2) {
            CHECK(first.mesh.triangle_count > 100);
            CHECK_MSG(same_mesh(&first, &second), "second run: %u triangles, first %u", second.mesh.triangle_count,
                      first.mesh.triangle_count);
            /* a fresh model, two threads at once */
            shared_run sr[2];
            thrd_t th[2];
            for (int k = 0; k < 2; k++) {
                memset(&sr[k], 0, sizeof sr[k]);
                sr[k].m = m2;
                sr[k].opt = opt;
                CHECK(thrd_create(&th[k], shared_run_main, &sr[k]) == thrd_success);
            }
            for (int k = 0; k < 2; k++) {
                thrd_join(th[k], NULL);
                CHECK(sr[k].st == TSR_OK);
                CHECK_MSG(sr[k].st != TSR_OK || same_mesh(&first, &sr[k].r), "thread %d: %u triangles, first %u", k,
                          sr[k].r.mesh.triangle_count, first.mesh.triangle_count);
                tsr_ptess_result_free(&sr[k].r);
            }
        }
        tsr_ptess_result_free(&first);
        tsr_ptess_result_free(&second);
    }
    tsr_pmodel_destroy(m);
    tsr_pmodel_destroy(m2);
    tsr_patch_set_free(&set);
}

/* ---- the contract's refusals ---------------------------------------------------------- */

TEST(bad_options)
{
    cylinder c = {0, 0, 0, 1, 1};
    sbuf b = {0};
    cyl_obj(&b, &c);
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(&b, "bad_options.obj", &set)) {
        free(b.s);
        return;
    }
    if (make_model(&set, &m)) {
        static const double scale_zero[1] = {0}, scale_big[1] = {1.5}, scale_nan[1] = {NAN}, scale_neg[1] = {-0.5};
        struct {
            const char *name;
            double max_error;
            uint32_t tile_n, max_level;
            const double *scale;
        } cases[] = {
            {"max_error 0", 0, 0, 0, NULL},
            {"max_error -1", -1, 0, 0, NULL},
            {"max_error NaN", NAN, 0, 0, NULL},
            {"max_error inf", INFINITY, 0, 0, NULL},
            {"tile_n 3", 1e-2, 3, 0, NULL},
            {"tile_n 1", 1e-2, 1, 0, NULL},
            {"tile_n 130", 1e-2, TSR_TILE_MAX + 2, 0, NULL},
            {"max_level 13", 1e-2, 0, 13, NULL},
            {"piece_scale 0", 1e-2, 0, 0, scale_zero},
            {"piece_scale 1.5", 1e-2, 0, 0, scale_big},
            {"piece_scale NaN", 1e-2, 0, 0, scale_nan},
            {"piece_scale -0.5", 1e-2, 0, 0, scale_neg},
        };
        for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
            tsr_ptess_options o = {0};
            o.max_error = cases[k].max_error;
            o.tile_n = cases[k].tile_n;
            o.max_level = cases[k].max_level;
            o.piece_scale = cases[k].scale;
            tsr_ptess_result r;
            memset(&r, 0xAB, sizeof r);
            tsr_error e = {0};
            tsr_status st = tsr_ptess_run(m, &o, NULL, &r, &e);
            CHECK_MSG(st == TSR_ERR_ARGUMENT, "%s: %s", cases[k].name, tsr_status_str(st));
            CHECK_MSG(e.status == TSR_ERR_ARGUMENT && e.message[0], "%s: no message", cases[k].name);
            check_zeroed_and_free(&r, cases[k].name);
        }
        /* the edges of the ranges are accepted */
        struct {
            uint32_t tile_n, max_level;
        } edges[] = {{2, 1}, {TSR_TILE_MAX, 1}, {2, 12}};
        for (size_t k = 0; k < sizeof edges / sizeof edges[0]; k++) {
            tsr_ptess_options o = {0};
            o.max_error = 1e-1;
            o.tile_n = edges[k].tile_n;
            o.max_level = edges[k].max_level;
            tsr_ptess_result r;
            tsr_error e = {0};
            CHECK_MSG(tsr_ptess_run(m, &o, NULL, &r, &e) == TSR_OK, "tile %u level %u: %s", o.tile_n, o.max_level,
                      e.message);
            tsr_ptess_result_free(&r);
        }
        /* a camera without max_error is fine; max_error is ignored then */
        tsr_camera cam;
        memset(&cam, 0, sizeof cam);
        const double eye[3] = {3, 3, 2};
        memcpy(cam.eye, eye, sizeof eye);
        cam.fovy_deg = 60;
        cam.width = 640;
        cam.height = 480;
        cam.near_dist = 0.1;
        cam.pixel_error = 1;
        CHECK(tsr_camera_prepare(&cam));
        tsr_ptess_options o = {0};
        o.camera = &cam;
        tsr_ptess_result r;
        tsr_error e = {0};
        CHECK_MSG(tsr_ptess_run(m, &o, NULL, &r, &e) == TSR_OK, "camera, max_error 0: %s", e.message);
        tsr_ptess_result_free(&r);
        /* NULL pointers */
        o.camera = NULL;
        o.max_error = 1e-2;
        memset(&r, 0xAB, sizeof r);
        CHECK(tsr_ptess_run(NULL, &o, NULL, &r, &e) == TSR_ERR_ARGUMENT);
        check_zeroed_and_free(&r, "NULL model");
        memset(&r, 0xAB, sizeof r);
        CHECK(tsr_ptess_run(m, NULL, NULL, &r, &e) == TSR_ERR_ARGUMENT);
        check_zeroed_and_free(&r, "NULL options");
        CHECK(tsr_ptess_run(m, &o, NULL, NULL, &e) == TSR_ERR_ARGUMENT);
        /* measure: per_side < 2, NULL pointers */
        CHECK(tsr_ptess_run(m, &o, NULL, &r, NULL) == TSR_OK);
        tsr_ptess_measure_result mr;
        CHECK(tsr_ptess_measure(m, &r, 1, NULL, false, NULL, &mr) == TSR_ERR_ARGUMENT);
        CHECK(tsr_ptess_measure(NULL, &r, 4, NULL, false, NULL, &mr) == TSR_ERR_ARGUMENT);
        CHECK(tsr_ptess_measure(m, NULL, 4, NULL, false, NULL, &mr) == TSR_ERR_ARGUMENT);
        CHECK(tsr_ptess_measure(m, &r, 4, NULL, false, NULL, NULL) == TSR_ERR_ARGUMENT);
        tsr_ptess_result_free(&r);
        /* source queries out of range */
        double p[3];
        tsr_psource_info si;
        CHECK(tsr_pmodel_eval(m, 7, 0, 0, p, NULL) == TSR_ERR_ARGUMENT);
        CHECK(!tsr_pmodel_source_info(m, 7, &si));
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

TEST(null_and_empty_inputs)
{
    tsr_ptess_result r;
    memset(&r, 0, sizeof r);
    tsr_ptess_result_free(&r); /* a zeroed result */
    tsr_pmodel_destroy(NULL);
    tsr_pmodel *m = NULL;
    tsr_error e = {0};
    CHECK(tsr_pmodel_from_set(NULL, NULL, &m, &e) == TSR_ERR_ARGUMENT && e.message[0]);
    tsr_patch_set empty;
    memset(&empty, 0, sizeof empty);
    uint32_t first_loop = 0;
    empty.first_loop = &first_loop;
    CHECK(tsr_pmodel_from_set(&empty, NULL, &m, &e) == TSR_ERR_EMPTY);
    CHECK(tsr_pmodel_from_subd(NULL, NULL, &m, &e) == TSR_ERR_ARGUMENT);
}

/* ---- data: the teapot ------------------------------------------------------------- */

/* A polynomial Bézier patch over [0,1]^2 by its Bernstein basis, written
 * here (the .bpt teapot's patches are all such); false for any other. */
static bool bernstein_eval(const tsr_patch *p, double u, double v, double pos[3])
{
    bool unit = (p->u0 == 0 && p->u1 == 0 && p->v0 == 0 && p->v1 == 0) ||
                (p->u0 == 0 && p->u1 == 1 && p->v0 == 0 && p->v1 == 1);
    if (p->kind != TSR_PATCH_BEZIER || p->weights || p->degree_u > 7 || p->degree_v > 7 || !unit)
        return false;
    double bu[8], bv[8];
    for (int pass = 0; pass < 2; pass++) {
        int d = pass ? p->degree_v : p->degree_u;
        double t = pass ? v : u, *b = pass ? bv : bu;
        for (int i = 0; i <= d; i++) {
            double c = 1; /* binomial (d, i) */
            for (int k = 1; k <= i; k++)
                c = c * (d - i + k) / k;
            b[i] = c * pow(t, i) * pow(1 - t, d - i);
        }
    }
    pos[0] = pos[1] = pos[2] = 0;
    for (int j = 0; j <= p->degree_v; j++)
        for (int i = 0; i <= p->degree_u; i++)
            for (int c = 0; c < 3; c++)
                pos[c] += bu[i] * bv[j] * p->ctrl[3 * (j * (p->degree_u + 1) + i) + c];
    return true;
}

typedef struct set_ctx {
    const tsr_patch_set *set;
    const tsr_pmodel *m;
} set_ctx;

static void set_truth(void *ctx, uint32_t src, const double *uv, uint32_t n, double *pos)
{
    const tsr_patch_set *set = ((const set_ctx *)ctx)->set;
    const tsr_pmodel *m = ((const set_ctx *)ctx)->m;
    tsr_psource_info si;
    bool ok = tsr_pmodel_source_info(m, src, &si) && si.patch < set->num_patches;
    const tsr_patch *p = ok ? &set->patches[si.patch] : NULL;
    for (uint32_t k = 0; k < n; k++)
        if (!ok || !bernstein_eval(p, uv[2 * k], uv[2 * k + 1], pos + 3 * k))
            pos[3 * k] = pos[3 * k + 1] = pos[3 * k + 2] = NAN;
}

/* Control row of edge e (0 south, 1 east, 2 north, 3 west) of a Bézier
 * patch: point k along the edge's parameter. */
static const double *edge_point(const tsr_patch *p, int e, uint32_t k)
{
    uint32_t nu = p->count_u, nv = p->count_v, i, j;
    switch (e) {
    case 0:
        i = k, j = 0;
        break;
    case 1:
        i = nu - 1, j = k;
        break;
    case 2:
        i = k, j = nv - 1;
        break;
    default:
        i = 0, j = k;
        break;
    }
    return p->ctrl + 3 * (j * nu + i);
}

static uint32_t edge_len(const tsr_patch *p, int e)
{
    return e == 0 || e == 2 ? p->count_u : p->count_v;
}

/* Which edges of a set of Bézier patches are open: neither collapsed nor
 * matched by another edge's row of control points (forwards or
 * reversed) within tol. open[4 * patch + e]. */
static void open_edges(const tsr_patch_set *s, double tol, bool *open)
{
    for (uint32_t p = 0; p < s->num_patches; p++)
        for (int e = 0; e < 4; e++) {
            const tsr_patch *P = &s->patches[p];
            uint32_t n = edge_len(P, e);
            bool collapsed = true;
            for (uint32_t k = 1; k < n; k++)
                collapsed = collapsed && dist3(edge_point(P, e, 0), edge_point(P, e, k)) <= tol;
            bool matched = false;
            for (uint32_t q = 0; q < s->num_patches && !matched && !collapsed; q++)
                for (int f = 0; f < 4 && !matched; f++) {
                    const tsr_patch *Q = &s->patches[q];
                    if ((q == p && f == e) || edge_len(Q, f) != n)
                        continue;
                    bool fw = true, bw = true;
                    for (uint32_t k = 0; k < n; k++) {
                        fw = fw && dist3(edge_point(P, e, k), edge_point(Q, f, k)) <= tol;
                        bw = bw && dist3(edge_point(P, e, k), edge_point(Q, f, n - 1 - k)) <= tol;
                    }
                    matched = fw || bw;
                }
            open[4 * p + e] = !collapsed && !matched;
        }
}

/* The domain side (0..3) both parameter points lie on, or -1. */
static int side_of(const double a[2], const double b[2], const double dom[4])
{
    double eu = 1e-9 * (dom[1] - dom[0]), ev = 1e-9 * (dom[3] - dom[2]);
    if (fabs(a[1] - dom[2]) <= ev && fabs(b[1] - dom[2]) <= ev)
        return 0;
    if (fabs(a[0] - dom[1]) <= eu && fabs(b[0] - dom[1]) <= eu)
        return 1;
    if (fabs(a[1] - dom[3]) <= ev && fabs(b[1] - dom[3]) <= ev)
        return 2;
    if (fabs(a[0] - dom[0]) <= eu && fabs(b[0] - dom[0]) <= eu)
        return 3;
    return -1;
}

static double seg_point_dist(const double a[3], const double b[3], const double p[3])
{
    double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, ap[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    double l = dot3(ab, ab), t = l > 0 ? fmin(1, fmax(0, dot3(ap, ab) / l)) : 0;
    double q[3] = {a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]};
    return dist3(q, p);
}

/* Boundary edges: each on an open edge of its source, and no two close
 * together (a crack would be two boundary chains along one curve). */
static void check_boundary_on_open_edges(const tsr_pmodel *m, const tsr_ptess_result *r, const bool *open,
                                         uint32_t num_patches, double crack_tol, const char *what)
{
    tsr_halfedges he;
    memset(&he, 0, sizeof he);
    if (tsr_halfedges_build(&he, &r->mesh, NULL) != TSR_OK) {
        CHECK(false);
        return;
    }
    const tsr_mesh *me = &r->mesh;
    uint32_t nb = 0, off_side = 0, on_closed = 0;
    uint32_t *bh = malloc(sizeof(uint32_t) * (he.count + 1));
    for (uint32_t h = 0; h < he.count && bh; h++) {
        if (he.twin[h] != TSR_NO_TWIN)
            continue;
        uint32_t t = h / 3, k = h % 3, k1 = (k + 1) % 3;
        if (me->indices[3 * t] == me->indices[3 * t + 1] || me->indices[3 * t + 1] == me->indices[3 * t + 2] ||
            me->indices[3 * t] == me->indices[3 * t + 2])
            continue; /* degenerate: counted by the validator */
        bh[nb++] = h;
        tsr_psource_info si;
        if (!tsr_pmodel_source_info(m, r->tri_source[t], &si)) {
            off_side++;
            continue;
        }
        int side = side_of(r->tri_uv + 6 * t + 2 * k, r->tri_uv + 6 * t + 2 * k1, si.domain);
        if (side < 0) {
            if (off_side++ == 0)
                fprintf(stderr, "  %s: boundary edge inside source %u: (%g, %g)-(%g, %g)\n", what, r->tri_source[t],
                        r->tri_uv[6 * t + 2 * k], r->tri_uv[6 * t + 2 * k + 1], r->tri_uv[6 * t + 2 * k1],
                        r->tri_uv[6 * t + 2 * k1 + 1]);
        } else if (si.patch < num_patches && !open[4 * si.patch + (uint32_t)side]) {
            if (on_closed++ == 0)
                fprintf(stderr, "  %s: boundary edge on side %d of patch %u, which has a partner\n", what, side,
                        si.patch);
        }
    }
    CHECK_MSG(off_side == 0, "%s: %u boundary edges inside a source's domain", what, off_side);
    CHECK_MSG(on_closed == 0, "%s: %u boundary edges on linked or collapsed patch edges", what, on_closed);
    /* cracks: a boundary edge's midpoint near another boundary edge that
     * shares no vertex with it */
    uint32_t cracks = 0;
    for (uint32_t a = 0; a < nb; a++) {
        uint32_t ha = bh[a], ia = me->indices[ha], ja = me->indices[3 * (ha / 3) + (ha % 3 + 1) % 3];
        double pa[3], qa[3], mid[3];
        for (int c = 0; c < 3; c++) {
            pa[c] = me->positions[3 * ia + c];
            qa[c] = me->positions[3 * ja + c];
            mid[c] = (pa[c] + qa[c]) / 2;
        }
        for (uint32_t bi = 0; bi < nb; bi++) {
            uint32_t hb = bh[bi], ib = me->indices[hb], jb = me->indices[3 * (hb / 3) + (hb % 3 + 1) % 3];
            if (ib == ia || ib == ja || jb == ia || jb == ja)
                continue;
            double pb[3], qb[3];
            for (int c = 0; c < 3; c++) {
                pb[c] = me->positions[3 * ib + c];
                qb[c] = me->positions[3 * jb + c];
            }
            if (seg_point_dist(pb, qb, mid) <= crack_tol) {
                if (cracks++ == 0)
                    fprintf(stderr, "  %s: boundary edges %u-%u and %u-%u lie together (a crack)\n", what, ia, ja, ib,
                            jb);
                break;
            }
        }
    }
    CHECK_MSG(cracks == 0, "%s: %u boundary edges along another boundary edge", what, cracks);
    free(bh);
    tsr_halfedges_free(&he);
}

TEST(data_teapot)
{
    const char *data = check_data_dir();
    if (!data)
        SKIP("no data folder");
    char path[5000];
    snprintf(path, sizeof path, "%s/patches/teapot.bpt", data);
    tsr_patch_set set;
    tsr_error e = {0};
    if (tsr_patch_set_load(path, TSR_PATCH_FORMAT_UNKNOWN, NULL, &set, &e) != TSR_OK) {
        if (e.status == TSR_ERR_NOT_FOUND)
            SKIP("%s", e.message);
        CHECK_MSG(false, "%s", e.message);
        return;
    }
    /* the size of the model: the control points' box */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t p = 0; p < set.num_patches; p++)
        for (uint32_t k = 0; k < set.patches[p].count_u * set.patches[p].count_v; k++)
            for (int c = 0; c < 3; c++) {
                lo[c] = fmin(lo[c], set.patches[p].ctrl[3 * k + c]);
                hi[c] = fmax(hi[c], set.patches[p].ctrl[3 * k + c]);
            }
    double size = dist3(lo, hi);
    bool *open = calloc(4 * (size_t)set.num_patches, sizeof(bool));
    open_edges(&set, 1e-9 * size, open);
    uint32_t n_open = 0;
    for (uint32_t k = 0; k < 4 * set.num_patches; k++)
        n_open += open[k];
    tsr_pmodel *m = NULL;
    if (make_model(&set, &m)) {
        tsr_pmodel_info info;
        tsr_pmodel_get_info(m, &info);
        CHECK(info.sources == set.num_patches && info.pieces == set.num_patches && info.trimmed_sources == 0);
        /* every edge is linked, collapsed or open: the sides the model
         * leaves unlinked are exactly the open ones and the collapsed ones */
        CHECK_MSG(info.links + info.collapsed_edges + n_open == 4 * set.num_patches,
                  "links %u + collapsed %u + open (by control rows) %u != 4 x %u", info.links, info.collapsed_edges,
                  n_open, set.num_patches);
        fprintf(stderr, "  teapot: %u patches, links %u, collapsed %u, open edges %u, mirrored %u\n", set.num_patches,
                info.links, info.collapsed_edges, n_open, info.mirrored);
        set_ctx pair = {&set, m};
        for (double E = 1e-2; E >= 0.99e-3; E /= 10) {
            tsr_ptess_options opt = {0};
            opt.max_error = E;
            opt.normals = true;
            tsr_ptess_result r;
            if (run_ptess(m, &opt, &r)) {
                check_shape(m, &r, true);
                tsr_ptess_measure_result mr;
                memset(&mr, 0, sizeof mr);
                CHECK(tsr_ptess_measure(m, &r, 8, NULL, false, NULL, &mr) == TSR_OK);
                double sl = fslack(mesh_maxabs(&r.mesh));
                CHECK_MSG(mr.max_error <= E + sl, "E %g: measured %g (source %u at %g, %g)", E, mr.max_error,
                          mr.worst_source, mr.worst_uv[0], mr.worst_uv[1]);
                CHECK_MSG(mr.uncovered == 0, "E %g: %llu uncovered samples", E, (unsigned long long)mr.uncovered);
                sampling s = {set_truth, &pair, NULL, NULL, NULL, 4, 0, 0, 0, 0, 0, 0, 0, {0, 0}};
                sample_result(&r, &s);
                CHECK_MSG(s.param_error <= E + sl, "E %g: parametric error %g (source %u at %.9g, %.9g)", E,
                          s.param_error, r.tri_source[s.worst_tri], s.worst_uv[0], s.worst_uv[1]);
                CHECK_MSG(s.param_error <= r.bound + sl, "E %g: error %g beyond the bound %g", E, s.param_error,
                          r.bound);
                CHECK_MSG(s.corner_error <= sl + 1e-8 * size, "E %g: corner error %g", E, s.corner_error);
                tsr_validation v = validate(&r.mesh);
                describe("teapot", &v);
                check_conforming("teapot", &v);
                check_boundary_on_open_edges(m, &r, open, set.num_patches, 1e-6 * size, "teapot");
                fprintf(stderr, "  teapot E %g: %u triangles, %u leaves, bound %g, measured %g, sampled %g\n", E,
                        r.mesh.triangle_count, r.leaves, r.bound, mr.max_error, s.param_error);
            }
            tsr_ptess_result_free(&r);
        }
    }
    tsr_pmodel_destroy(m);
    free(open);
    tsr_patch_set_free(&set);
}

/* ---- subdivision faces whose limit has no area ---------------------------------- */

/* Two 9-face rings of OpenSubdiv's catmark_nonman_edges: in each, the
 * middle face repeats its vertices (67 67 68 68, a curve between two
 * points; 81 81 81 82, another curve), and a lone face 110 110 110 110 (a
 * point). Bfr evaluates them, but du x dv vanishes all over: the limit is
 * a curve or a point, which no triangle can carry without zero area. */
static const char curve_faces_obj[] =
    "v -1.75 0 -0.50\nv -1.42 0 -0.50\nv -1.08 0 -0.50\nv -0.75 0 -0.50\nv -0.75 0 -0.17\nv -0.75 0 0.17\n"
    "v -0.75 0 0.50\nv -1.08 0 0.50\nv -1.42 0 0.50\nv -1.75 0 0.50\nv -1.75 0 0.17\nv -1.75 0 -0.17\n"
    "v -1.25 -0.30 -0.17\nv -1.25 -0.30 0.17\n"
    "f 1 2 13 12\nf 2 3 13 13\nf 3 4 5 13\nf 13 5 6 14\nf 14 6 7 8\nf 14 14 8 9\nf 11 14 9 10\nf 12 13 14 11\n"
    "f 13 13 14 14\n"
    "v -0.50 0 -0.50\nv -0.17 0 -0.50\nv 0.17 0 -0.50\nv 0.50 0 -0.50\nv 0.50 0 -0.17\nv 0.50 0 0.17\n"
    "v 0.50 0 0.50\nv 0.17 0 0.50\nv -0.17 0 0.50\nv -0.50 0 0.50\nv -0.50 0 0.17\nv -0.50 0 -0.17\n"
    "v 0.00 -0.30 -0.17\nv -0.17 -0.30 0.17\n"
    "f 15 16 27 26\nf 16 17 27 27\nf 17 18 19 27\nf 27 19 20 27\nf 27 20 21 22\nf 28 27 22 23\nf 25 28 23 24\n"
    "f 26 27 28 25\nf 27 27 27 28\n"
    "v -1.75 0 -1.75\nv -1.42 0 -1.75\nv -1.08 0 -1.75\nv -0.75 0 -1.75\nv -0.75 0 -1.42\nv -0.75 0 -1.08\n"
    "v -0.75 0 -0.75\nv -1.08 0 -0.75\nv -1.42 0 -0.75\nv -1.75 0 -0.75\nv -1.75 0 -1.08\nv -1.75 0 -1.42\n"
    "v -1.25 -0.30 -1.25\n"
    "f 29 30 41 40\nf 30 31 41 41\nf 31 32 33 41\nf 41 33 34 41\nf 41 34 35 36\nf 41 41 36 37\nf 39 41 37 38\n"
    "f 40 41 41 39\nf 41 41 41 41\n"
    "t interpolateboundary 1/0/0 1\n";

/* Distance from p to triangle (a, b, c), all in double. */
static double point_tri_dist(const double p[3], const double a[3], const double b[3], const double c[3])
{
    double ab[3], ac[3], n[3];
    for (int k = 0; k < 3; k++)
        ab[k] = b[k] - a[k], ac[k] = c[k] - a[k];
    cross3(ab, ac, n);
    double nn = dot3(n, n);
    if (nn > 0) { /* inside the prism over the triangle: the distance to its plane */
        double ap[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]}, q[3];
        double d = dot3(ap, n) / nn;
        for (int k = 0; k < 3; k++)
            q[k] = p[k] - d * n[k];
        double e0[3], e1[3], x[3];
        const double *v[3] = {a, b, c};
        bool inside = true;
        for (int k = 0; k < 3 && inside; k++) {
            for (int j = 0; j < 3; j++)
                e0[j] = v[(k + 1) % 3][j] - v[k][j], e1[j] = q[j] - v[k][j];
            cross3(e0, e1, x);
            inside = dot3(x, n) >= 0;
        }
        if (inside)
            return fabs(d) * sqrt(nn);
    }
    double best = INFINITY;
    const double *v[3] = {a, b, c};
    for (int k = 0; k < 3; k++) { /* the edges */
        const double *s = v[k], *t = v[(k + 1) % 3];
        double st[3] = {t[0] - s[0], t[1] - s[1], t[2] - s[2]}, sp[3] = {p[0] - s[0], p[1] - s[1], p[2] - s[2]};
        double l2 = dot3(st, st), u = l2 > 0 ? dot3(sp, st) / l2 : 0;
        u = u < 0 ? 0 : u > 1 ? 1 : u;
        double q[3] = {s[0] + u * st[0], s[1] + u * st[1], s[2] + u * st[2]};
        best = fmin(best, dist3(p, q));
    }
    return best;
}

/* Faces whose limit is a curve or a point have nothing a triangle could
 * cover without zero area: they get no source and no triangles, while
 * every face with area keeps its sources, the mesh has no degenerate
 * triangle, every sample of every source is covered within the tolerance,
 * and the curves and points themselves lie on the mesh (on the borders of
 * the faces around them) within it. */
TEST(subd_curve_faces_no_zero_area)
{
    tsr_cage cage;
    tsr_error e = {0};
    CHECK_MSG(tsr_cage_parse(curve_faces_obj, sizeof curve_faces_obj - 1, "curve_faces.obj", NULL, &cage, &e) == TSR_OK,
              "%s", e.message);
    tsr_subd *subd = NULL;
    CHECK_MSG(tsr_subd_create(&cage, TSR_SUBD_CATMARK, NULL, &subd, &e) == TSR_OK, "%s", e.message);
    tsr_cage_free(&cage);
    if (!subd)
        return;
    uint32_t nf = tsr_subd_face_count(subd);
    CHECK(nf == 27);
    tsr_pmodel *m = NULL;
    CHECK(tsr_pmodel_from_subd(subd, NULL, &m, &e) == TSR_OK);
    if (!m) {
        tsr_subd_destroy(subd);
        return;
    }
    tsr_pmodel_info info;
    tsr_pmodel_get_info(m, &info);
    double size = dist3(info.lo, info.hi), E = 1e-3 * size;
    /* which faces have area, found here from du x dv over the face */
    bool flat[27] = {false};
    for (uint32_t f = 0; f < nf && f < 27; f++) {
        CHECK(tsr_subd_face_has_limit(subd, f) && tsr_subd_face_patches(subd, f) == 1);
        double most = 0;
        for (int k = 0; k < 81; k++) {
            double uv[2] = {(k % 9 + 0.5) / 9.5, (k / 9 + 0.5) / 9.5}, pos[3], du[3], dv[3], n[3];
            CHECK(tsr_subd_eval(subd, f, 0, uv, 1, pos, du, dv) == TSR_OK);
            cross3(du, dv, n);
            most = fmax(most, sqrt(dot3(n, n)));
        }
        flat[f] = most <= 1e-12 * size * size;
    }
    CHECK(flat[8] && flat[17] && flat[26]);
    uint32_t want = 0;
    for (uint32_t f = 0; f < nf; f++)
        want += !flat[f];
    CHECK_MSG(info.sources == want && info.pieces == want, "%u sources, %u faces with area", info.sources, want);
    for (uint32_t s = 0; s < info.sources; s++) {
        tsr_psource_info si;
        CHECK(tsr_pmodel_source_info(m, s, &si) && si.patch < 27 && !flat[si.patch]);
    }
    tsr_ptess_options opt = {0};
    opt.max_error = E;
    tsr_ptess_result r;
    CHECK(run_ptess(m, &opt, &r));
    tsr_validation v = validate(&r.mesh);
    describe("curve faces", &v);
    CHECK_MSG(v.degenerate_triangles == 0, "%u degenerate triangles, first %u (source %u)", v.degenerate_triangles,
              v.first_degenerate,
              v.first_degenerate < r.mesh.triangle_count ? r.tri_source[v.first_degenerate] : UINT32_MAX);
    CHECK(v.bad_indices == 0 && v.duplicate_triangles == 0 && v.nonmanifold_edges == 0 && v.misoriented_edges == 0);
    tsr_ptess_measure_result mr;
    CHECK(tsr_ptess_measure(m, &r, 16, NULL, false, NULL, &mr) == TSR_OK);
    CHECK_MSG(mr.uncovered == 0, "%llu uncovered samples", (unsigned long long)mr.uncovered);
    /* an estimate for subd pieces (ptess.h): allow what the tool's retries would fix */
    CHECK_MSG(mr.max_error <= 2 * E, "measured %g, tolerance %g", mr.max_error, E);
    /* the flat faces' curves and points lie on the mesh */
    double far = 0;
    for (uint32_t f = 0; f < nf; f++) {
        if (!flat[f])
            continue;
        for (int k = 0; k < 25; k++) {
            double uv[2] = {(k % 5) / 4.0, (k / 5) / 4.0}, p[3];
            CHECK(tsr_subd_eval(subd, f, 0, uv, 1, p, NULL, NULL) == TSR_OK);
            double d = INFINITY;
            for (uint32_t t = 0; t < r.mesh.triangle_count; t++) {
                double c[3][3];
                for (int q = 0; q < 3; q++)
                    for (int x = 0; x < 3; x++)
                        c[q][x] = r.mesh.positions[3 * (size_t)r.mesh.indices[3 * (size_t)t + q] + x];
                d = fmin(d, point_tri_dist(p, c[0], c[1], c[2]));
            }
            far = fmax(far, d);
        }
    }
    CHECK_MSG(far <= 2 * E, "a flat face's limit lies %g from the mesh (tolerance %g)", far, E);
    tsr_ptess_result_free(&r);
    tsr_pmodel_destroy(m);
    tsr_subd_destroy(subd);
}

/* ---- data: OpenSubdiv cages -------------------------------------------------------- */

typedef struct subd_ctx {
    const tsr_subd *subd;
    const tsr_pmodel *m;
} subd_ctx;

static void subd_truth(void *ctx, uint32_t src, const double *uv, uint32_t n, double *pos)
{
    const subd_ctx *c = ctx;
    tsr_psource_info si;
    if (!tsr_pmodel_source_info(c->m, src, &si) ||
        tsr_subd_eval(c->subd, si.patch, si.sub, uv, n, pos, NULL, NULL) != TSR_OK)
        for (uint32_t k = 0; k < 3 * n; k++)
            pos[k] = NAN;
}

typedef struct cage_case {
    const char *file;
    bool closed;   /* Euler 2, no boundary, positive volume */
    bool manifold; /* conformity checks apply */
    bool smooth;   /* no sharp crease: vertex normals agree with every triangle around */
    int euler;     /* when not closed and manifold: the expected Euler characteristic, 99 unchecked */
} cage_case;

/* A house: a box with a creased ridge roof, its gable ends pentagons
 * (N-gon sub-patches), closed (allocation_failures). */
static const char house_obj[] =
    "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nv 0 0 1\nv 2 0 1\nv 2 1 1\nv 0 1 1\nv 0 0.5 1.5\nv 2 0.5 1.5\n"
    "f 1 4 3 2\nf 1 2 6 5\nf 3 4 8 7\nf 1 5 9 8 4\nf 2 3 7 10 6\nf 5 6 10 9\nf 8 9 10 7\n"
    "t crease 2/1/0 8 9 3.0\n";

/* One run of m with the failures f plans: TSR_ERR_NOMEM, soon (at most
 * 8 times the requests of the whole run, calls; refining on after a
 * failure made 18,000 times as many, and took seconds) and leaking
 * nothing, or exactly ref's mesh. Returns whether it succeeded. */
static bool failing_run(const char *what, const tsr_pmodel *m, const tsr_ptess_options *o, check_alloc f, long calls,
                        const tsr_ptess_result *ref)
{
    tsr_error e = {0};
    tsr_allocator al = {check_realloc, &f, NULL};
    tsr_ptess_result r;
    tsr_status st = tsr_ptess_run(m, o, &al, &r, &e);
    char plan[96];
    snprintf(plan, sizeof plan, "failure at allocation %ld%s%s", f.fail_at, f.sticky ? " (sticky)" : "",
             f.fail_also ? " and another" : "");
    CHECK_MSG(st == TSR_OK || st == TSR_ERR_NOMEM, "%s: %s: %s", what, plan, tsr_status_str(st));
    CHECK_MSG(st == TSR_OK || f.calls <= 8 * calls, "%s: %s: %ld requests", what, plan, f.calls);
    if (st == TSR_OK)
        CHECK_MSG(same_mesh(&r, ref), "%s: %s: another mesh", what, plan);
    tsr_ptess_result_free(&r);
    CHECK_MSG(f.live == 0, "%s: %s: %ld blocks leaked", what, plan, f.live);
    return st == TSR_OK;
}

/* Runs m at max error E (and with normals) with every allocation failing
 * in turn, once and sticky (failures of the same size after it too): a
 * run keeps what it looked up (a node's values and tile points, a point's
 * mesh vertex) where memory allows and looks it up again where it did
 * not, so every run either fails with TSR_ERR_NOMEM or gives exactly the
 * mesh of a run with all the memory it asked for (failing_run). Then,
 * after the first and the last sticky failure that left a run its mesh
 * (memory it could do without), every other request failing too: the
 * paths that look up again fail cleanly. optional: some failures leave a
 * run its mesh (subd pieces' kept tile points; Bézier pieces keep nothing
 * optional). */
static void check_allocation_failures(const char *what, const tsr_pmodel *m, double E, bool optional)
{
    tsr_error e = {0};
    for (int normals = 0; normals < 2; normals++) {
        tsr_ptess_options o = {0};
        o.max_error = E;
        o.normals = normals;
        check_alloc f = {0};
        tsr_allocator al = {check_realloc, &f, NULL};
        tsr_ptess_result ref;
        CHECK(tsr_ptess_run(m, &o, &al, &ref, &e) == TSR_OK);
        long calls = f.calls;
        CHECK_MSG(ref.mesh.triangle_count > 500 && calls > 20, "%s: %u triangles, %ld allocations", what,
                  ref.mesh.triangle_count, calls);
        tsr_validation v = validate(&ref.mesh);
        check_conforming(what, &v);
        CHECK_MSG(v.boundary_edges == 0, "%s: %u boundary edges", what, v.boundary_edges);
        long failed = 0, kept = 0, first_kept = 0, last_kept = 0;
        for (long k = 1; k <= 2 * calls; k++) {
            bool sticky = k > calls, ok = failing_run(
                                          what, m, &o, (check_alloc){.fail_at = sticky ? k - calls : k, .sticky = sticky},
                                          calls, &ref);
            failed += !ok;
            kept += ok;
            if (ok && sticky) {
                first_kept = first_kept ? first_kept : k - calls;
                last_kept = k - calls;
            }
        }
        /* both outcomes happen where some memory is optional */
        CHECK_MSG(failed > 0 && (kept > 0) == optional, "%s: %ld runs failed, %ld did not", what, failed, kept);
        for (int t = 0; t < 2 && first_kept; t++)
            for (long j = 1; j <= calls; j++)
                failing_run(what, m, &o,
                            (check_alloc){.fail_at = t ? last_kept : first_kept, .sticky = true, .fail_also = j}, calls,
                            &ref);
        /* the crease normals' copy: NOMEM and nothing left, or the same copy */
        for (int sticky = 0; normals && sticky < 2; sticky++) {
            check_alloc g = {0};
            tsr_allocator ga = {check_realloc, &g, NULL};
            tsr_mesh want;
            CHECK(tsr_ptess_crease_normals(m, &ref, 1, &ga, &want, NULL, &e) == TSR_OK);
            for (long k = 1; k <= g.calls; k++) {
                check_alloc h = {.fail_at = k, .sticky = sticky};
                tsr_allocator ha = {check_realloc, &h, NULL};
                tsr_mesh got;
                tsr_status st = tsr_ptess_crease_normals(m, &ref, 1, &ha, &got, NULL, &e);
                CHECK_MSG(st == TSR_ERR_NOMEM || (st == TSR_OK && got.vertex_count == want.vertex_count &&
                                                  !memcmp(got.indices, want.indices,
                                                          3 * (size_t)want.triangle_count * sizeof *got.indices)),
                          "%s: crease normals, failure at allocation %ld: %s", what, k, tsr_status_str(st));
                CHECK(st == TSR_OK || (got.vertex_count == 0 && got.triangle_count == 0 && !got.indices));
                tsr_mesh_free(&got);
                CHECK_MSG(h.live == 0, "%s: crease normals, failure at allocation %ld: %ld blocks leaked", what, k,
                          h.live);
            }
            tsr_mesh_free(&want);
            CHECK(g.live == 0);
        }
        tsr_ptess_result_free(&ref);
    }
}

TEST(allocation_failures)
{
    /* a subdivision surface: creased, with N-gon faces */
    tsr_cage cage;
    tsr_error e = {0};
    CHECK_MSG(tsr_cage_parse(house_obj, sizeof house_obj - 1, "house.obj", NULL, &cage, &e) == TSR_OK, "%s",
              e.message);
    tsr_subd *subd = NULL;
    CHECK_MSG(tsr_subd_create(&cage, TSR_SUBD_CATMARK, NULL, &subd, &e) == TSR_OK, "%s", e.message);
    tsr_cage_free(&cage);
    tsr_pmodel *m = NULL;
    if (subd)
        CHECK(tsr_pmodel_from_subd(subd, NULL, &m, &e) == TSR_OK);
    if (m) {
        tsr_pmodel_info info;
        tsr_pmodel_get_info(m, &info);
        CHECK(info.pieces == 5 + 2 * 5); /* 5 quads, 2 pentagons of 5 sub-patches */
        check_allocation_failures("house.obj", m, 1e-3 * dist3(info.lo, info.hi), true);
        tsr_pmodel_destroy(m);
    }
    tsr_subd_destroy(subd);
    /* rational Bézier patches: linked, with collapsed edges */
    sbuf b = {0};
    sphere_obj(&b, outward_octants, 8);
    tsr_patch_set set;
    if (parse_set(&b, "sphere.obj", &set)) {
        if (make_model(&set, &m)) {
            check_allocation_failures("sphere.obj", m, 3e-3, false);
            tsr_pmodel_destroy(m);
        }
        tsr_patch_set_free(&set);
    }
    free(b.s);
}

/* The Catmull-Clark model of the cage at path (named name in messages):
 * *subd and the model, both NULL after a failed CHECK; the caller
 * destroys both. */
static tsr_pmodel *cage_model(const char *path, const char *name, tsr_subd **subd)
{
    tsr_cage cage;
    tsr_error e = {0};
    *subd = NULL;
    if (tsr_cage_load(path, NULL, &cage, &e) != TSR_OK) {
        CHECK_MSG(false, "%s", e.message);
        return NULL;
    }
    tsr_status st = tsr_subd_create(&cage, TSR_SUBD_CATMARK, NULL, subd, &e);
    tsr_cage_free(&cage);
    CHECK_MSG(st == TSR_OK, "%s: %s", name, e.message);
    if (st != TSR_OK)
        return NULL;
    tsr_pmodel *m = NULL;
    st = tsr_pmodel_from_subd(*subd, NULL, &m, &e);
    CHECK_MSG(st == TSR_OK && m, "%s: tsr_pmodel_from_subd: %s (%s)", name, tsr_status_str(st), e.message);
    return st == TSR_OK ? m : NULL;
}

static void run_cage(const char *dir, const cage_case *cc, double E)
{
    char path[5200];
    snprintf(path, sizeof path, "%.4096s/%.1000s", dir, cc->file);
    tsr_subd *subd;
    tsr_pmodel *m = cage_model(path, cc->file, &subd);
    if (m) {
        tsr_pmodel_info info;
        tsr_pmodel_get_info(m, &info);
        uint32_t want_sources = 0;
        for (uint32_t f = 0; f < tsr_subd_face_count(subd); f++)
            want_sources += tsr_subd_face_has_limit(subd, f) ? tsr_subd_face_patches(subd, f) : 0;
        CHECK_MSG(info.sources == want_sources && info.pieces == want_sources, "%s: sources %u pieces %u, want %u",
                  cc->file, info.sources, info.pieces, want_sources);
        double size = dist3(info.lo, info.hi);
        subd_ctx ctx = {subd, m};
        double *scale = malloc(sizeof(double) * (info.pieces + 1));
        double *serr = calloc(info.sources + 1, sizeof(double));
        for (uint32_t k = 0; k < info.pieces; k++)
            scale[k] = 1;
        /* the loop the contract describes: tessellate, measure, tighten
         * the pieces found beyond the tolerance */
        bool scaled = false;
        double first_error = -1, prev_worst = INFINITY;
        for (int round = 0; round < 3; round++) {
            tsr_ptess_options opt = {0};
            opt.max_error = E;
            opt.normals = true;
            opt.piece_scale = scaled ? scale : NULL;
            tsr_ptess_result r;
            bool ok = run_ptess(m, &opt, &r);
            if (!ok) {
                tsr_ptess_result_free(&r);
                break;
            }
            memset(serr, 0, sizeof(double) * info.sources);
            sampling s = {subd_truth, &ctx, NULL, NULL, serr, 0, 0, 0, 0, 0, 0, 0, 0, {0, 0}};
            sample_result(&r, &s);
            tsr_ptess_measure_result mr;
            memset(&mr, 0, sizeof mr);
            CHECK(tsr_ptess_measure(m, &r, 6, NULL, true, NULL, &mr) == TSR_OK);
            for (uint32_t k = 0; mr.source_error && k < info.sources; k++)
                serr[k] = fmax(serr[k], mr.source_error[k]);
            double worst = fmax(s.param_error, mr.max_error);
            if (round == 0)
                first_error = worst;
            double sl = fslack(mesh_maxabs(&r.mesh));
            /* re-tessellating must make progress, else it is pointless (and
             * the meshes grow without end) */
            bool stuck = round > 0 && worst > 0.5 * prev_worst;
            prev_worst = worst;
            if (worst <= E + sl || round == 2 || stuck) {
                fprintf(stderr, "  %s E %g: %u triangles, rounds %d, first error %.3g, final %.3g\n", cc->file, E,
                        r.mesh.triangle_count, round + 1, first_error, worst);
                CHECK_MSG(worst <= E + sl, "%s E %g: error %g after %d rounds (source %u at %g, %g)", cc->file, E,
                          worst, round + 1, r.tri_source[s.worst_tri], s.worst_uv[0], s.worst_uv[1]);
                CHECK_MSG(mr.uncovered == 0, "%s: %llu uncovered samples", cc->file, (unsigned long long)mr.uncovered);
                CHECK_MSG(s.corner_error <= sl + 1e-8 * size, "%s: corner error %g", cc->file, s.corner_error);
                check_shape(m, &r, true);
                tsr_validation v = validate(&r.mesh);
                describe(cc->file, &v);
                if (cc->manifold) {
                    check_conforming(cc->file, &v);
                    if (cc->smooth)
                        check_normals_agree(&r.mesh, cc->file);
                } else
                    CHECK_MSG(v.degenerate_triangles == 0, "%s: %u degenerate triangles", cc->file,
                              v.degenerate_triangles);
                if (cc->closed) {
                    CHECK_MSG(v.boundary_edges == 0 && v.euler == 2, "%s: boundary %u, Euler %lld", cc->file,
                              v.boundary_edges, (long long)v.euler);
                    CHECK_MSG(v.coincident_vertices == 0, "%s: %u coincident vertices", cc->file,
                              v.coincident_vertices);
                    CHECK_MSG(signed_volume(&r.mesh) > 0, "%s: volume %g", cc->file, signed_volume(&r.mesh));
                } else if (cc->manifold && cc->euler != 99) {
                    CHECK_MSG(v.euler == cc->euler, "%s: Euler %lld, want %d", cc->file, (long long)v.euler, cc->euler);
                }
                tsr_free(NULL, mr.source_error);
                tsr_ptess_result_free(&r);
                break;
            }
            for (uint32_t k = 0; k < info.sources; k++) {
                tsr_psource_info si;
                if (serr[k] <= E || !tsr_pmodel_source_info(m, k, &si))
                    continue;
                for (uint32_t p = 0; p < si.pieces_u * si.pieces_v && si.first_piece + p < info.pieces; p++)
                    scale[si.first_piece + p] =
                        fmax(1e-3, scale[si.first_piece + p] * fmax(0.05, fmin(0.5, 0.9 * E / serr[k])));
            }
            scaled = true;
            tsr_free(NULL, mr.source_error);
            tsr_ptess_result_free(&r);
        }
        free(scale);
        free(serr);
        /* positions only: the vertices come from the points the selection
         * evaluated (ptess.c keeps them per lattice point), so they must
         * still be the surface's points at the corners' (u, v), and each
         * lattice point is evaluated once: a vertex is one evaluation, and
         * the selection adds the points of the leaves the mesh stitches
         * away and four cell centres per node (1.1 to 1.6 per vertex on
         * these cages; evaluating each node's tile afresh made 3.5-3.7).
         * Small trees (at most 16 tiles) are also selected with half
         * tiles (ptess.h), whose points the mesh uses only where they win:
         * up to 3.4 per vertex there, so small meshes get 3.5 and the
         * larger ones 2.5 */
        bool small = false;
        tsr_ptess_options opt = {0};
        opt.max_error = E;
        tsr_ptess_result r;
        if (run_ptess(m, &opt, &r)) {
            sampling s = {subd_truth, &ctx, NULL, NULL, NULL, 4, 0, 0, 0, 0, 0, 0, 0, {0, 0}};
            sample_result(&r, &s);
            double sl = fslack(mesh_maxabs(&r.mesh));
            CHECK_MSG(s.corner_error <= sl + 1e-8 * size, "%s positions only: corner error %g", cc->file,
                      s.corner_error);
            small = r.mesh.vertex_count < 2000;
            fprintf(stderr, "  %s: %.2f evaluations per vertex\n", cc->file,
                    (double)r.evaluations / r.mesh.vertex_count);
            CHECK_MSG(r.evaluations <= (small ? 3.5 : 2.5) * r.mesh.vertex_count,
                      "%s positions only: %u evaluations for %u vertices", cc->file, r.evaluations,
                      r.mesh.vertex_count);
        }
        tsr_ptess_result_free(&r);
    }
    tsr_pmodel_destroy(m);
    tsr_subd_destroy(subd);
}

TEST(data_osd_cages)
{
    const char *data = check_data_dir();
    if (!data)
        SKIP("no data folder");
    char dir[5000];
    snprintf(dir, sizeof dir, "%s/patches/osd", data);
    struct stat st;
    if (stat(dir, &st) != 0)
        SKIP("no %s", dir);
    static const cage_case cases[] = {
        {"catmark_cube.obj", true, true, true, 2},        {"catmark_cube_creases1.obj", true, true, false, 2},
        {"catmark_pyramid.obj", true, true, true, 2},     /* triangles next to a quad */
        {"catmark_nonquads.obj", false, true, true, 99},  /* N-gons next to quads, open */
        {"catmark_hole_test1.obj", false, true, true, 1}, /* a cube less one face: a disc */
        {"catmark_fan.obj", false, false, true, 99},      /* non-manifold: error only */
        /* faces with a repeated vertex (4 3 5 5): collapsed patch edges, whose
         * triangles must go without a gap: a conforming disc */
        {"catmark_nonman_quadpole8.obj", false, true, false, 1},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++)
        for (double E = 1e-2; E >= 0.99e-3; E /= 10)
            run_cage(dir, &cases[k], E);
}

/* The subd estimate at face corners: on these cages, at these tolerances
 * (fractions of the box diagonal), the second differences alone left the
 * first round's measured error at 1.8 and 3.2 times the tolerance, near an
 * extraordinary, creased cube corner; with the corner cells' centres
 * (ptess.h) the first round holds. A regression check of an estimate on
 * real data, measured by tsr_ptess_measure. */
TEST(data_osd_corner_estimate)
{
    const char *data = check_data_dir();
    if (!data)
        SKIP("no data folder");
    static const struct {
        const char *file;
        double frac;
    } cases[] = {{"catmark_cube_creases1.obj", 3e-3}, {"catmark_cubes_semisharp.obj", 1e-3}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        char path[5200];
        snprintf(path, sizeof path, "%.4096s/patches/osd/%s", data, cases[k].file);
        tsr_subd *subd;
        tsr_pmodel *m = cage_model(path, cases[k].file, &subd);
        if (m) {
            tsr_pmodel_info info;
            tsr_pmodel_get_info(m, &info);
            tsr_ptess_options opt = {0};
            opt.max_error = cases[k].frac * dist3(info.lo, info.hi);
            tsr_ptess_result r;
            if (run_ptess(m, &opt, &r)) {
                tsr_ptess_measure_result mr;
                memset(&mr, 0, sizeof mr);
                CHECK(tsr_ptess_measure(m, &r, 32, NULL, false, NULL, &mr) == TSR_OK);
                fprintf(stderr, "  %s at %g of the diagonal: %u triangles, measured %.3g of the tolerance\n",
                        cases[k].file, cases[k].frac, r.mesh.triangle_count, mr.max_error / opt.max_error);
                CHECK_MSG(mr.max_error <= opt.max_error, "%s: measured %g > tolerance %g at source %u (%g, %g)",
                          cases[k].file, mr.max_error, opt.max_error, mr.worst_source, mr.worst_uv[0], mr.worst_uv[1]);
                CHECK(mr.uncovered == 0);
            }
            tsr_ptess_result_free(&r);
        }
        tsr_pmodel_destroy(m);
        tsr_subd_destroy(subd);
    }
}

/* Subd pieces whose tree is small take tiles of half the size, one level
 * deeper (the same lattice), where that selection has fewer quads: on a
 * creased cube at coarse tolerances some faces are then tiles of 2 x 2
 * quads (8 triangles, 6 stitched, where a tile of 4 x 4 has 32, at least
 * 28 stitched on its two outer sides, more with fans), and the
 * first round's measured error still holds, the mesh closed. */
TEST(data_osd_half_tiles)
{
    const char *data = check_data_dir();
    if (!data)
        SKIP("no data folder");
    char path[5200];
    snprintf(path, sizeof path, "%.4096s/patches/osd/catmark_cube_creases1.obj", data);
    tsr_subd *subd;
    tsr_pmodel *m = cage_model(path, "catmark_cube_creases1.obj", &subd);
    if (!m)
        return;
    tsr_pmodel_info info;
    tsr_pmodel_get_info(m, &info);
    for (double frac = 1e-2; frac >= 2.9e-3; frac *= 0.3) {
        tsr_ptess_options opt = {0};
        opt.max_error = frac * dist3(info.lo, info.hi);
        tsr_ptess_result r;
        if (!run_ptess(m, &opt, &r))
            continue;
        tsr_ptess_measure_result mr;
        memset(&mr, 0, sizeof mr);
        CHECK(tsr_ptess_measure(m, &r, 32, NULL, false, NULL, &mr) == TSR_OK);
        fprintf(stderr, "  %g of the diagonal: %u triangles, %u tiles, measured %.3g of the tolerance\n", frac,
                r.mesh.triangle_count, r.leaves, mr.max_error / opt.max_error);
        CHECK_MSG(mr.max_error <= opt.max_error && mr.uncovered == 0, "%g: measured %g > %g", frac, mr.max_error,
                  opt.max_error);
        CHECK_MSG(r.mesh.triangle_count < 28 * r.leaves, "%g: %u triangles in %u tiles: no tile of 2 x 2", frac,
                  r.mesh.triangle_count, r.leaves);
        tsr_validation v = validate(&r.mesh);
        check_conforming("half tiles", &v);
        CHECK(v.boundary_edges == 0 && v.euler == 2);
        tsr_ptess_result_free(&r);
    }
    tsr_pmodel_destroy(m);
    tsr_subd_destroy(subd);
}

/* ---- normals at creases ---------------------------------------------------- */

/* Unit normal of triangle t of m, from its corners (0 for a degenerate one). */
static void unit_face_normal(const tsr_mesh *m, uint32_t t, double n[3])
{
    face_normal(m, t, n);
    double l = sqrt(dot3(n, n));
    for (int k = 0; k < 3; k++)
        n[k] = l > 0 ? n[k] / l : 0;
}

/* The largest angle (degrees) between a corner's normal and its triangle's
 * own normal, over the corners of triangles with area. */
static double worst_corner_angle(const tsr_mesh *m)
{
    double worst = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        double fn[3];
        unit_face_normal(m, t, fn);
        if (dot3(fn, fn) == 0)
            continue;
        for (int k = 0; k < 3; k++) {
            const float *n = m->normals + 3 * m->indices[3 * t + k];
            double nd[3] = {n[0], n[1], n[2]}, c = dot3(nd, fn) / sqrt(dot3(nd, nd));
            worst = fmax(worst, acos(fmax(-1, fmin(1, c))) * 180 / PI);
        }
    }
    return worst;
}

/* What every crease-normal copy keeps: r's triangles over the same
 * positions (corner by corner), r's vertices first, unit normals; and
 * every appended vertex a copy of one of r's. Returns, per vertex of r,
 * how many vertices of out stand at its place (copies + 1) in *copies
 * (allocated; caller frees). */
static void check_crease_copy(const tsr_ptess_result *r, const tsr_mesh *out, uint32_t added, uint32_t **copies)
{
    const tsr_mesh *in = &r->mesh;
    CHECK(out->triangle_count == in->triangle_count);
    CHECK_MSG(out->vertex_count == in->vertex_count + added, "%u vertices, %u + %u added", out->vertex_count,
              in->vertex_count, added);
    CHECK(out->normals != NULL);
    uint32_t moved = 0, not_unit = 0;
    *copies = calloc(in->vertex_count, sizeof **copies);
    uint32_t *orig = malloc((out->vertex_count + 1) * sizeof *orig);
    for (uint32_t v = 0; v < out->vertex_count; v++)
        orig[v] = v < in->vertex_count ? v : UINT32_MAX;
    for (uint32_t c = 0; c < 3 * in->triangle_count && c < 3 * out->triangle_count; c++) {
        uint32_t a = in->indices[c], b = out->indices[c];
        if (b >= out->vertex_count) {
            moved++;
            continue;
        }
        moved += memcmp(in->positions + 3 * a, out->positions + 3 * b, 3 * sizeof(float)) != 0;
        if (b >= in->vertex_count) { /* appended: a copy of a */
            moved += orig[b] != UINT32_MAX && orig[b] != a;
            orig[b] = a;
        } else {
            moved += b != a; /* a vertex of r keeps its index */
        }
    }
    for (uint32_t v = 0; v < out->vertex_count; v++) {
        const float *n = out->normals + 3 * v;
        not_unit += fabs(sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]) - 1) > 1e-5;
        if (v >= in->vertex_count) {
            moved += orig[v] == UINT32_MAX; /* used by no triangle */
            if (orig[v] != UINT32_MAX)
                (*copies)[orig[v]]++;
        }
    }
    for (uint32_t v = 0; v < in->vertex_count; v++)
        (*copies)[v]++;
    CHECK_MSG(moved == 0, "%u corners moved, renumbered or unused copies", moved);
    CHECK_MSG(not_unit == 0, "%u normals not of unit length", not_unit);
    free(orig);
}

/* A box of six bilinear patches (one written inward, so mirrored): a
 * point of the box meets as many faces as it has coordinates on the
 * box's planes, and with the crease normals there are that many vertices
 * there, each corner's normal its own face's (a plane: the triangle's). */
TEST(crease_normals_box)
{
    static const double lo[3] = {-1, 0, 0.5}, hi[3] = {1, 3, 1.25};
    sbuf b = {0};
    for (int axis = 0; axis < 3; axis++)
        for (int side = 0; side < 2; side++) {
            int u = (axis + 1) % 3, w = (axis + 2) % 3;
            for (int c = 0; c < 4; c++) {
                double p[3];
                p[axis] = side ? hi[axis] : lo[axis];
                int cu = c & 1, cw = c >> 1;
                if (side ^ (axis == 1)) /* faces written both ways round */
                    cu = !cu;
                p[u] = cu ? hi[u] : lo[u];
                p[w] = cw ? hi[w] : lo[w];
                sb_printf(&b, "v %.17g %.17g %.17g\n", p[0], p[1], p[2]);
            }
            sb_printf(&b, "cstype bezier\ndeg 1 1\nsurf 0 1 0 1 -4 -3 -2 -1\nend\n");
        }
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(&b, "box.obj", &set)) {
        free(b.s);
        return;
    }
    if (make_model(&set, &m)) {
        tsr_ptess_options o = {0};
        o.max_error = 1e-3;
        o.normals = true;
        tsr_ptess_result r;
        if (run_ptess(m, &o, &r)) {
            tsr_validation v = validate(&r.mesh);
            check_conforming("box", &v);
            CHECK(v.boundary_edges == 0 && v.euler == 2);
            /* welded, an edge's vertex has one face's normal: 90 degrees
             * off the other face's triangles */
            CHECK_MSG(worst_corner_angle(&r.mesh) > 80, "welded box: corners within %g deg of their triangles",
                      worst_corner_angle(&r.mesh));
            tsr_mesh out;
            uint32_t added = 0;
            tsr_error e = {0};
            tsr_status st = tsr_ptess_crease_normals(m, &r, 1, NULL, &out, &added, &e);
            CHECK_MSG(st == TSR_OK, "%s", e.message);
            if (st == TSR_OK) {
                uint32_t *copies = NULL, wrong = 0, want_added = 0;
                check_crease_copy(&r, &out, added, &copies);
                CHECK_MSG(worst_corner_angle(&out) < 1e-3, "a corner %g deg off its face", worst_corner_angle(&out));
                for (uint32_t i = 0; copies && i < r.mesh.vertex_count; i++) {
                    uint32_t faces = 0;
                    for (int k = 0; k < 3; k++) {
                        double x = r.mesh.positions[3 * i + k];
                        faces += (fabs(x - lo[k]) < 1e-6) + (fabs(x - hi[k]) < 1e-6);
                    }
                    wrong += copies[i] != faces;
                    want_added += faces - 1;
                }
                CHECK_MSG(wrong == 0, "%u box points whose vertices are not one per face meeting there", wrong);
                CHECK_MSG(added == want_added, "%u added, want %u", added, want_added);
                free(copies);
            }
            tsr_mesh_free(&out);
            /* 180 degrees: nothing split, the shared vertices' normals
             * their faces' mean (between the faces: on the triangles' side) */
            st = tsr_ptess_crease_normals(m, &r, 180, NULL, &out, &added, &e);
            CHECK(st == TSR_OK && added == 0 && out.vertex_count == r.mesh.vertex_count);
            if (st == TSR_OK) {
                uint32_t *copies = NULL;
                check_crease_copy(&r, &out, added, &copies);
                double w = worst_corner_angle(&out);
                CHECK_MSG(w > 50 && w < 60, "mean normals: worst corner %g deg (a cube corner's 54.7)", w);
                free(copies);
            }
            tsr_mesh_free(&out);
            /* refusals */
            CHECK(tsr_ptess_crease_normals(NULL, &r, 1, NULL, &out, NULL, &e) == TSR_ERR_ARGUMENT);
            CHECK(tsr_ptess_crease_normals(m, NULL, 1, NULL, &out, NULL, &e) == TSR_ERR_ARGUMENT);
            CHECK(tsr_ptess_crease_normals(m, &r, 1, NULL, NULL, NULL, &e) == TSR_ERR_ARGUMENT);
            CHECK(tsr_ptess_crease_normals(m, &r, -1, NULL, &out, NULL, &e) == TSR_ERR_ARGUMENT);
            CHECK(tsr_ptess_crease_normals(m, &r, 181, NULL, &out, NULL, &e) == TSR_ERR_ARGUMENT);
            CHECK(tsr_ptess_crease_normals(m, &r, NAN, NULL, &out, NULL, &e) == TSR_ERR_ARGUMENT);
            CHECK(out.vertex_count == 0 && out.triangle_count == 0);
        }
        tsr_ptess_result_free(&r);
        o.normals = false;
        if (run_ptess(m, &o, &r)) {
            tsr_mesh out;
            tsr_error e = {0};
            CHECK(tsr_ptess_crease_normals(m, &r, 1, NULL, &out, NULL, &e) == TSR_ERR_ARGUMENT);
            CHECK_MSG(strstr(e.message, "normal") != NULL, "%s", e.message);
        }
        tsr_ptess_result_free(&r);
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* The sphere of eight octants is smooth where they meet and at its poles
 * (collapsed edges): no vertex is split, the normals stay radial. */
/* m tessellated within E with normals, then split at creases of 1 degree
 * into *out (free it); false (after a failed CHECK) when either fails. */
static bool crease_run(const tsr_pmodel *m, double E, tsr_mesh *out, uint32_t *added, tsr_ptess_result *r)
{
    tsr_ptess_options o = {0};
    o.max_error = E;
    o.normals = true;
    memset(out, 0, sizeof *out);
    if (!run_ptess(m, &o, r))
        return false;
    tsr_error e = {0};
    *added = 99;
    tsr_status st = tsr_ptess_crease_normals(m, r, 1, NULL, out, added, &e);
    CHECK_MSG(st == TSR_OK, "%s", e.message);
    return st == TSR_OK;
}

TEST(crease_normals_smooth_sphere)
{
    sbuf b = {0};
    sphere_obj(&b, outward_octants, 8);
    tsr_patch_set set;
    tsr_pmodel *m = NULL;
    if (!parse_set(&b, "sphere.obj", &set)) {
        free(b.s);
        return;
    }
    if (make_model(&set, &m)) {
        tsr_ptess_result r;
        tsr_mesh out;
        uint32_t added;
        if (crease_run(m, 1e-3, &out, &added, &r)) {
            uint32_t *copies = NULL;
            check_crease_copy(&r, &out, added, &copies);
            free(copies);
            CHECK_MSG(added == 0, "%u vertices split on a smooth sphere", added);
            uint32_t off = normals_off_radial(&out, 1, 1e-6);
            CHECK_MSG(off == 0, "%u normals not radial", off);
        }
        tsr_mesh_free(&out);
        tsr_ptess_result_free(&r);
    }
    tsr_pmodel_destroy(m);
    tsr_patch_set_free(&set);
    free(b.s);
}

/* One NURBS sphere (9 x 5 rational quadratic net, double knots: C0 in its
 * parameters, smooth on the surface), at the origin and a million units
 * away: no vertex split, and the poles' normals point away from the
 * centre. Far away, the evaluator's derivatives lost their digits to the
 * coordinates, and each pole got a second vertex with its normal flipped. */
TEST(crease_normals_far_sphere)
{
    static const double cu[9][3] = {{1, 0, 1}, {1, 1, H2}, {0, 1, 1}, {-1, 1, H2}, {-1, 0, 1},
                                    {-1, -1, H2}, {0, -1, 1}, {1, -1, H2}, {1, 0, 1}};
    static const double cv[5][3] = {{0, -1, 1}, {1, -1, H2}, {1, 0, 1}, {1, 1, H2}, {0, 1, 1}};
    for (int far = 0; far < 2; far++) {
        double off = far ? 1e6 : 0;
        sbuf b = {0};
        for (int j = 0; j < 5; j++)
            for (int i = 0; i < 9; i++)
                sb_printf(&b, "v %.17g %.17g %.17g %.17g\n", off + cu[i][0] * cv[j][0], off + cu[i][1] * cv[j][0],
                          cv[j][1], cu[i][2] * cv[j][2]);
        sb_printf(&b, "cstype rat bspline\ndeg 2 2\nsurf 0 1 0 1");
        for (int k = 1; k <= 45; k++)
            sb_printf(&b, " %d", k);
        sb_printf(&b, "\nparm u 0 0 0 0.25 0.25 0.5 0.5 0.75 0.75 1 1 1\nparm v 0 0 0 0.5 0.5 1 1 1\nend\n");
        tsr_patch_set set;
        tsr_pmodel *m = NULL;
        if (parse_set(&b, "nurbs_sphere.obj", &set) && make_model(&set, &m)) {
            tsr_ptess_result r;
            tsr_mesh out;
            uint32_t added;
            if (crease_run(m, 0.25, &out, &added, &r)) {
                uint32_t poles = 0, wrong = 0;
                for (uint32_t i = 0; i < out.vertex_count; i++) {
                    const float *p = out.positions + 3 * (size_t)i, *n = out.normals + 3 * (size_t)i;
                    if (fabs(p[2]) != 1 || fabs(p[0] - off) > 1e-3 || fabs(p[1] - off) > 1e-3)
                        continue;
                    poles++;
                    wrong += !(n[2] * p[2] > 0.99);
                }
                CHECK_MSG(added == 0 && poles == 2 && wrong == 0,
                          "offset %g: %u vertices split, %u pole vertices, %u pointing inwards", off, added, poles,
                          wrong);
            }
            tsr_mesh_free(&out);
            tsr_ptess_result_free(&r);
        }
        tsr_pmodel_destroy(m);
        tsr_patch_set_free(&set);
        free(b.s);
    }
}

/* A roof: one cubic x linear B-spline whose knot u = 1 is triple, its two
 * halves planes meeting at a ridge (x = 1) at an angle. The triple knot is
 * its one kink; every ridge vertex is written twice, and each corner's
 * normal is its own half's (a plane: its triangle's). With the knot
 * simple (the surface then C2, no kink) nothing is split. */
TEST(crease_normals_bspline_kink)
{
    for (int triple = 1; triple >= 0; triple--) {
        sbuf b = {0};
        /* control columns x = 0, 1/3, ..., 2 (triple: column 3 the ridge) */
        int cols = triple ? 7 : 5;
        for (int j = 0; j < 2; j++)
            for (int i = 0; i < cols; i++) {
                double x = triple ? i / 3.0 : (i == 0 ? 0 : i == cols - 1 ? 2 : 0.5 * i);
                double z = x <= 1 ? 0.5 * x : 0.5 * (2 - x);
                sb_printf(&b, "v %.17g %.17g %.17g\n", x, 1.5 * j, triple ? z : 0.1 * x * x);
            }
        sb_printf(&b, "cstype bspline\ndeg 3 1\nsurf 0 2 0 1");
        for (int k = 2 * cols; k >= 1; k--)
            sb_printf(&b, " -%d", k);
        sb_printf(&b, triple ? "\nparm u 0 0 0 0 1 1 1 2 2 2 2\n" : "\nparm u 0 0 0 0 1 2 2 2 2\n");
        sb_printf(&b, "parm v 0 0 1 1\nend\n");
        tsr_patch_set set;
        tsr_pmodel *m = NULL;
        if (!parse_set(&b, "roof.obj", &set)) {
            free(b.s);
            return;
        }
        if (make_model(&set, &m)) {
            double k[4] = {0};
            uint32_t nk = tsr_pmodel_source_kinks(m, 0, 0, k, 4);
            CHECK_MSG(nk == (triple ? 1u : 0u) && (!triple || k[0] == 1), "%u kinks along u (first %g)", nk, k[0]);
            CHECK(tsr_pmodel_source_kinks(m, 0, 1, k, 4) == 0);
            CHECK(tsr_pmodel_source_kinks(m, 1, 0, k, 4) == 0); /* no such source */
            tsr_ptess_options o = {0};
            o.max_error = 1e-3;
            o.normals = true;
            tsr_ptess_result r;
            if (run_ptess(m, &o, &r)) {
                tsr_mesh out;
                uint32_t added = 0;
                tsr_error e = {0};
                tsr_status st = tsr_ptess_crease_normals(m, &r, 1, NULL, &out, &added, &e);
                CHECK_MSG(st == TSR_OK, "%s", e.message);
                if (st == TSR_OK) {
                    uint32_t *copies = NULL, ridge = 0, wrong = 0;
                    check_crease_copy(&r, &out, added, &copies);
                    for (uint32_t v = 0; copies && v < r.mesh.vertex_count; v++) {
                        bool on = fabs(r.mesh.positions[3 * v] - 1) < 1e-6;
                        ridge += on;
                        wrong += copies[v] != (triple && on ? 2u : 1u);
                    }
                    free(copies);
                    if (triple) {
                        CHECK_MSG(ridge >= 2 && added == ridge, "%u ridge vertices, %u added", ridge, added);
                        CHECK_MSG(worst_corner_angle(&out) < 1e-3, "a corner %g deg off its half",
                                  worst_corner_angle(&out));
                        CHECK_MSG(worst_corner_angle(&r.mesh) > 40, "welded: ridge corners within %g deg",
                                  worst_corner_angle(&r.mesh));
                    } else {
                        CHECK_MSG(added == 0, "%u vertices split on a smooth surface", added);
                    }
                    CHECK_MSG(wrong == 0, "%u vertices with the wrong number of copies", wrong);
                }
                tsr_mesh_free(&out);
            }
            tsr_ptess_result_free(&r);
        }
        tsr_pmodel_destroy(m);
        tsr_patch_set_free(&set);
        free(b.s);
    }
}

/* OpenSubdiv's cube with eleven infinitely sharp edges (and one of
 * sharpness 0.1, smooth in the limit): with crease normals, every
 * corner's normal is its own face's limit normal there (tsr_subd_normal at
 * the corner's (u, v): a face meets its neighbour across a sharp edge at
 * an angle), within the crease angle, and no corner is far from its
 * triangle's own normal; welded, corners on the sharp edges were 90
 * degrees off. */
TEST(data_osd_crease_normals)
{
    const char *data = check_data_dir();
    if (!data)
        SKIP("no data folder");
    char path[5200];
    snprintf(path, sizeof path, "%.4096s/patches/osd/catmark_cube_creases2.obj", data);
    struct stat sb;
    if (stat(path, &sb) != 0)
        SKIP("no %s", path);
    tsr_subd *subd;
    tsr_pmodel *m = cage_model(path, "catmark_cube_creases2.obj", &subd);
    if (!m)
        return;
    tsr_pmodel_info info;
    tsr_pmodel_get_info(m, &info);
    tsr_ptess_options o = {0};
    o.max_error = 1e-3 * dist3(info.lo, info.hi);
    o.normals = true;
    tsr_ptess_result r;
    if (run_ptess(m, &o, &r)) {
        double before = worst_corner_angle(&r.mesh);
        CHECK_MSG(before > 80, "welded: worst corner %g deg off its triangle", before);
        tsr_mesh out;
        uint32_t added = 0;
        tsr_error e = {0};
        const double angle = 2;
        tsr_status st = tsr_ptess_crease_normals(m, &r, angle, NULL, &out, &added, &e);
        CHECK_MSG(st == TSR_OK, "%s", e.message);
        if (st == TSR_OK) {
            uint32_t *copies = NULL, off = 0;
            check_crease_copy(&r, &out, added, &copies);
            free(copies);
            double after = worst_corner_angle(&out);
            fprintf(stderr, "  %u vertices, %u added at creases; worst corner off its triangle %.1f -> %.1f deg\n",
                    r.mesh.vertex_count, added, before, after);
            CHECK(added > 0);
            CHECK_MSG(after < 30, "a corner %g deg off its triangle", after);
            for (uint32_t t = 0; t < out.triangle_count; t++) {
                tsr_psource_info si;
                if (!tsr_pmodel_source_info(m, r.tri_source[t], &si)) {
                    off++;
                    continue;
                }
                for (int k = 0; k < 3; k++) {
                    double uv[2] = {r.tri_uv[6 * t + 2 * k], r.tri_uv[6 * t + 2 * k + 1]}, n[3];
                    if (tsr_subd_normal(subd, si.patch, si.sub, uv, n) != TSR_OK) {
                        off++;
                        continue;
                    }
                    const float *f = out.normals + 3 * out.indices[3 * t + k];
                    double c = (n[0] * f[0] + n[1] * f[1] + n[2] * f[2]) * (si.mirrored ? -1 : 1);
                    off += c < cos(angle * PI / 180) - 1e-6;
                }
            }
            CHECK_MSG(off == 0, "%u corners whose normal is not their face's within %g deg", off, angle);
        }
        tsr_mesh_free(&out);
    }
    tsr_ptess_result_free(&r);
    tsr_pmodel_destroy(m);
    tsr_subd_destroy(subd);
}

/* A Catmull-Clark cage of nu x nv quads on a torus (radii 3 and 1) whose
 * tube radius is bumped by amp sin(ku u) cos(kv v): OBJ text into b. */
static void bumpy_torus_cage(sbuf *b, int nu, int nv, double amp, int ku, int kv)
{
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            double u = 2 * PI * i / nu, v = 2 * PI * j / nv, r = 1 + amp * sin(ku * u) * cos(kv * v);
            sb_printf(b, "v %.17g %.17g %.17g\n", (3 + r * cos(v)) * cos(u), (3 + r * cos(v)) * sin(u), r * sin(v));
        }
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++)
            sb_printf(b, "f %d %d %d %d\n", j * nu + i + 1, j * nu + (i + 1) % nu + 1,
                      (j + 1) % nv * nu + (i + 1) % nu + 1, (j + 1) % nv * nu + i + 1);
}

/* Its Catmull-Clark model: *subd and the model (NULL after a failed CHECK). */
static tsr_pmodel *bumpy_torus_model(const sbuf *b, tsr_subd **subd)
{
    tsr_cage cage;
    tsr_error e = {0};
    tsr_pmodel *m = NULL;
    *subd = NULL;
    CHECK_MSG(tsr_cage_parse(b->s, b->n, "torus.obj", NULL, &cage, &e) == TSR_OK, "%s", e.message);
    CHECK_MSG(tsr_subd_create(&cage, TSR_SUBD_CATMARK, NULL, subd, &e) == TSR_OK, "%s", e.message);
    tsr_cage_free(&cage);
    if (*subd)
        CHECK_MSG(tsr_pmodel_from_subd(*subd, NULL, &m, &e) == TSR_OK, "%s", e.message);
    return m;
}

/* An allocator that keeps the peak of the bytes alive (a header before
 * each block holds its size). */
typedef struct byte_count {
    size_t live, peak;
} byte_count;

static void *count_realloc(void *user, void *ptr, size_t size)
{
    byte_count *c = user;
    size_t *h = ptr ? (size_t *)ptr - 2 : NULL, old = h ? h[0] : 0;
    if (size == 0) {
        c->live -= old;
        free(h);
        return NULL;
    }
    size_t *n = realloc(h, size + 2 * sizeof *n);
    if (!n)
        return NULL;
    n[0] = size;
    c->live += size - old;
    c->peak = c->live > c->peak ? c->live : c->peak;
    return n + 2;
}

/* A cage of many small faces (a bumpy torus of 40 x 20 quads, each face a
 * tile or two at this bound): the run's memory grows with what each face
 * selects, a few kilobytes, not with the deepest tree a face could have
 * (per-face arrays sized for 2^10 segments, point memos of 1024, made a
 * 20,000-face cage take 810 MB and 2.7 s, mostly first touches of pages). */
TEST(small_faces_small_memory)
{
    enum { NU = 40, NV = 20 };
    sbuf b = {0};
    bumpy_torus_cage(&b, NU, NV, 0.15, 7, 3);
    tsr_error e = {0};
    tsr_subd *subd = NULL;
    tsr_pmodel *m = bumpy_torus_model(&b, &subd);
    if (m) {
        tsr_pmodel_info info;
        tsr_pmodel_get_info(m, &info);
        for (double frac = 3e-3; frac >= 0.9e-3; frac /= 3) {
            byte_count bc = {0, 0};
            tsr_allocator al = {count_realloc, &bc, NULL};
            tsr_ptess_options o = {0};
            o.max_error = frac * dist3(info.lo, info.hi);
            tsr_ptess_result r;
            CHECK(tsr_ptess_run(m, &o, &al, &r, &e) == TSR_OK);
            double per_face = (double)bc.peak / (NU * NV), per_tile = (double)bc.peak / r.leaves;
            fprintf(stderr, "  %g of the diagonal: %u tiles, %u triangles, peak %.0f bytes per face, %.0f per tile\n",
                    frac, r.leaves, r.mesh.triangle_count, per_face, per_tile);
            CHECK_MSG(per_tile < 16000, "%.0f bytes per tile at its peak (about 60,000 before)", per_tile);
            tsr_validation v = validate(&r.mesh);
            CHECK(v.boundary_edges == 0 && v.euler == 0);
            tsr_ptess_result_free(&r);
            CHECK(bc.live == 0);
        }
    }
    tsr_pmodel_destroy(m);
    tsr_subd_destroy(subd);
    free(b.s);
}

typedef struct progress_log {
    uint32_t calls, backwards;
    double last;
} progress_log;

static void log_progress(void *user, double f)
{
    progress_log *p = user;
    p->backwards += f < p->last || f < 0 || f > 1;
    p->last = f;
    p->calls++;
}

/* tsr_ptess_measure on threads (alloc NULL, enough samples) and on the
 * calling thread alone (a caller's allocator) gives the same figures to
 * the bit: each source is measured on its own and merged in order. (On a
 * machine of one core both are one thread.) The progress variant reports
 * fractions that only grow, up to 1, and measures the same. */
TEST(measure_threads_same_figures)
{
    enum { NU = 24, NV = 12 };
    sbuf b = {0};
    bumpy_torus_cage(&b, NU, NV, 0.2, 5, 2);
    tsr_error e = {0};
    tsr_subd *subd = NULL;
    tsr_pmodel *m = bumpy_torus_model(&b, &subd);
    if (m) {
        tsr_pmodel_info info;
        tsr_pmodel_get_info(m, &info);
        tsr_ptess_options o = {0};
        o.max_error = 3e-3 * dist3(info.lo, info.hi);
        tsr_ptess_result r;
        if (run_ptess(m, &o, &r)) {
            tsr_ptess_measure_result a, c;
            check_alloc f = {0};
            tsr_allocator al = {check_realloc, &f, NULL};
            CHECK(tsr_ptess_measure(m, &r, 32, NULL, true, NULL, &a) == TSR_OK);
            CHECK(tsr_ptess_measure(m, &r, 32, NULL, true, &al, &c) == TSR_OK);
            CHECK_MSG(a.samples >= 32 * 32 * NU * NV, "%llu samples", (unsigned long long)a.samples);
            CHECK(a.samples == c.samples && a.uncovered == 0 && c.uncovered == 0 && a.trimmed_out == c.trimmed_out);
            CHECK_MSG(a.max_error == c.max_error && a.rms_error == c.rms_error && a.worst_source == c.worst_source &&
                          a.worst_uv[0] == c.worst_uv[0] && a.worst_uv[1] == c.worst_uv[1],
                      "threads: max %.17g rms %.17g at %u; one: max %.17g rms %.17g at %u", a.max_error, a.rms_error,
                      a.worst_source, c.max_error, c.rms_error, c.worst_source);
            uint32_t differ = 0;
            for (uint32_t s = 0; a.source_error && c.source_error && s < info.sources; s++)
                differ += a.source_error[s] != c.source_error[s];
            CHECK_MSG(differ == 0, "%u sources' errors differ", differ);
            CHECK(a.max_error > 0 && a.max_error <= o.max_error * 1.5);
            progress_log pl = {0, 0, 0};
            tsr_ptess_measure_result p;
            CHECK(tsr_ptess_measure_progress(m, &r, 32, NULL, false, NULL, log_progress, &pl, &p) == TSR_OK);
            CHECK_MSG(pl.calls >= 1 && pl.backwards == 0 && pl.last == 1, "%u calls, %u backwards, last %g", pl.calls,
                      pl.backwards, pl.last);
            CHECK(p.max_error == a.max_error && p.rms_error == a.rms_error && p.samples == a.samples);
            CHECK(!info.own_alloc);
            tsr_free(NULL, a.source_error);
            tsr_free(&al, c.source_error);
            CHECK(f.live == 0);
        }
        tsr_ptess_result_free(&r);
    }
    /* a tsr_subd made with a caller's allocator: the model says so (and
     * the measurement then keeps to the calling thread) */
    {
        check_alloc f2 = {0};
        tsr_allocator al2 = {check_realloc, &f2, NULL};
        tsr_cage c2;
        tsr_subd *s2 = NULL;
        tsr_pmodel *m2 = NULL;
        if (tsr_cage_parse(b.s, b.n, "torus.obj", NULL, &c2, &e) == TSR_OK) {
            CHECK(tsr_subd_create(&c2, TSR_SUBD_CATMARK, &al2, &s2, &e) == TSR_OK);
            tsr_cage_free(&c2);
        }
        if (s2 && tsr_pmodel_from_subd(s2, NULL, &m2, &e) == TSR_OK) {
            tsr_pmodel_info i2;
            tsr_pmodel_get_info(m2, &i2);
            CHECK(i2.own_alloc && tsr_subd_has_allocator(s2) && !tsr_subd_has_allocator(subd));
        }
        tsr_pmodel_destroy(m2);
        tsr_subd_destroy(s2);
        CHECK(f2.live == 0);
    }
    tsr_pmodel_destroy(m);
    tsr_subd_destroy(subd);
    free(b.s);
}

TEST_MAIN(T(plane_parallelogram_exact), T(plane_trapezoid_bilinear), T(quarter_cylinder_error), T(sphere_octant_pole),
          T(sphere_closed_outward_nets), T(sphere_closed_mirrored_octants), T(sphere_closed_first_inward),
          T(piece_scale_tightens_one_piece), T(bspline_pieces_conform), T(partial_overlap_linked),
          T(t_configurations_linked), T(staggered_rows_linked_or_left_whole), T(stitched_tiles_within_bound),
          T(linked_rates_differ_conform), T(trimmed_linked_conform), T(trim_loops_keep_exact_areas),
          T(trim_loops_meet_the_lattice), T(trim_loop_shapes), T(border_loops_trim_nothing),
          T(three_patches_share_an_edge), T(hole_across_a_linked_edge), T(measure_passes_slivers_by),
          T(domain_trimmed_surfaces_weld), T(patch_edges_a_gap_apart_weld_within_the_link_distance),
          T(edges_of_other_knots_and_degrees_link), T(split_error_cuts_extrusions_across_their_curve),
          T(rational_product_weights_within_bound), T(rational_cylinder_cut_near_its_strip), T(camera_near_finer),
          T(runs_share_model), T(bad_options), T(subd_curve_faces_no_zero_area), T(allocation_failures),
          T(data_osd_corner_estimate), T(data_osd_half_tiles), T(crease_normals_box), T(crease_normals_smooth_sphere),
          T(crease_normals_far_sphere), T(crease_normals_bspline_kink), T(small_faces_small_memory),
          T(measure_threads_same_figures), T(data_osd_crease_normals), T(null_and_empty_inputs), T(data_teapot),
          T(data_osd_cages))
