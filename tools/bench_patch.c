/* bench_patch.c: `tessera bench patch`: the adaptive patch tessellator
 * (patches/ptess.h) against OpenSubdiv's Bfr on the shared data.
 *
 *  1. A ladder of error bounds (fractions of the model's box diagonal) on
 *     the Utah teapot and on OpenSubdiv cages: triangles, vertices, seconds
 *     (best of R), the measured max error (tsr_ptess_measure, not timed)
 *     and throughput in vertices and evaluations per second.
 *  2. For the cages, Bfr's uniform tessellation (tsr_subd_tessellate_uniform)
 *     at the smallest rate whose measured error is at most the adaptive
 *     row's: triangles and time side by side. Bfr's mesh carries no (u, v),
 *     so its error is measured on an equivalent mesh built here: the same
 *     points (rate r per quad, r / 2 per N-gon sub-face) and the same
 *     triangles (Bfr's ring pattern of diagonals, bfr_diagonal), checked
 *     against Bfr's own mesh triangle by triangle (centroids must match).
 *  3. Bfr's limit evaluation rate (tsr_subd_eval on a dense grid per patch,
 *     positions alone and with derivatives): the throughput baseline; for
 *     a patch set, its own evaluator's and Bfr's on the cage of 4.
 *  4. View-dependent tessellation of the teapot from cameras on an orbit,
 *     against two uniform tessellations, each at the smallest rate whose
 *     measured pixel error is at most the adaptive one's:
 *      - ours (tsr_ptess_run with one tile per piece), a stand-in;
 *      - Bfr's (the target of issue 7): every bicubic Bézier patch becomes
 *        the uniform cubic B-spline patch of the same surface, the middle
 *        face of a 4 x 4 Catmull-Clark grid (tsr_subd_cage_from_bezier,
 *        checked here against tsr_patch_eval), and
 *        tsr_subd_tessellate_uniform_faces tessellates those middle faces
 *        (Bfr::Tessellation and limit evaluation), timed; its pixel error
 *        is measured on the equivalent mesh of table 2, whose source for a
 *        middle face is the patch itself, Bfr's (u, v) being its (s, t).
 *     Skipped, with a note, when a patch is not a polynomial bicubic
 *     Bézier patch or is trimmed.
 * Every ratio compares figures measured in the same run. */
#include "bench.h"
#include "patches/ptess.h"
#include "patches/subd.h"

#include <cjson/cJSON.h>
#include <malloc.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { PER_SIDE = 32, MAX_ERRORS = 16, MAX_CAMERAS = 64 };

/* Errors below these count as equal when searching a rate: the mesh's
 * float32 positions alone are off by about 1e-7 of the coordinates, so a
 * flat model's errors are rounding noise. */
#define MODEL_ERROR_FLOOR 1e-6 /* of the box diagonal */
#define PIXEL_ERROR_FLOOR 1e-3 /* pixels */

static void help(FILE *f)
{
    fprintf(f,
            "usage: tessera bench patch [options]\n\n"
            "Benchmarks adaptive patch tessellation (tsr_ptess_run) against OpenSubdiv's Bfr and prints tables:\n"
            "  1. per model and error bound (fraction of the model's box diagonal): triangles, vertices,\n"
            "     seconds (best of R), the measured max error (tsr_ptess_measure, %u x %u samples per piece\n"
            "     and every edge midpoint; not timed), vertices and evaluations per second;\n"
            "  2. for subdivision cages, Bfr's uniform tessellation at the smallest rate whose measured error\n"
            "     is at most the adaptive one (measured on an equivalent mesh with Bfr's points and triangles,\n"
            "     checked against Bfr's mesh): triangles and time, and the ratios adaptive / Bfr;\n"
            "  3. Bfr's limit evaluation rate (tsr_subd_eval on a dense grid per patch; for the teapot also\n"
            "     on its Catmull-Clark cage of 4): points per second;\n"
            "  4. the teapot seen from cameras on an orbit (1920 x 1080, 60 deg, 1 px): view-dependent\n"
            "     tessellation against uniform ones reaching the same measured pixel error: our own\n"
            "     (tsr_ptess_run, one tile per piece; a stand-in) and Bfr's, on the Catmull-Clark cage whose\n"
            "     middle faces are exactly the teapot's bicubic patches (tsr_subd_cage_from_bezier): Bfr rate,\n"
            "     triangles, seconds (tsr_subd_tessellate_uniform_faces, best of R), measured px (on Bfr's\n"
            "     points and triangles, as in 2) and the time ratio adaptive / Bfr (the target: < 1).\n\n"
            "inputs: $TESSERA_DATA/patches/teapot.bpt and the cages catmark_cube_creases1,\n"
            "catmark_cubes_semisharp, catmark_gregory_test1, catmark_edgecorner and catmark_fan of\n"
            "$TESSERA_DATA/patches/osd (TESSERA_DATA defaults to ../shared/data, from the working folder;\n"
            "absent files are skipped).\n\n"
            "options:\n"
            "  --input FILE      only this model: .bpt or free-form .obj (Bezier/NURBS patches), else a\n"
            "                    polygon .obj cage (Catmull-Clark; bilinear when the name starts with\n"
            "                    \"bilinear\")\n"
            "  --errors LIST     bounds as fractions of the box diagonal (default 1e-2,3e-3,1e-3,3e-4,1e-4)\n"
            "  --repeat R        best of R runs for every timing (default 3)\n"
            "  --tile N          quads per tile side of the adaptive runs, even, 2..128 (default: ptess's, 4)\n"
            "  --max-rate N      largest Bfr rate searched, 2..512 (default 256; the teapot's uniform\n"
            "                    rates stop at 256)\n"
            "  --cameras N       cameras on the teapot's orbit (default 8)\n"
            "  --quick           the teapot and one cage, bounds 1e-2 and 1e-3, R = 1, 2 cameras\n"
            "  --cold            leave the C library's memory settings alone, so that every run touches\n"
            "                    fresh pages (default: freed memory is kept in the process, so the best of\n"
            "                    R times the work, not the first touch of pages, which costs about 13 us a\n"
            "                    page on the 2-core development VM)\n"
            "  --json FILE       also write the results as JSON\n"
            "  -h, --help        this help\n",
            PER_SIDE, PER_SIDE);
}

/* ---- Models ------------------------------------------------------------ */

typedef struct model {
    char name[256];
    bool is_set;
    tsr_patch_set set;
    tsr_cage cage;
    tsr_subd *subd;
    bool ngons; /* a face of the cage with a limit surface is not a quad */
    uint32_t patches;
    tsr_pmodel *pm; /* NULL when the adaptive tessellator refused the model */
    tsr_status pm_status;
    char pm_message[512];
    tsr_pmodel_info info;
    double diag;
    /* the patch set as a Catmull-Clark cage for Bfr (table 4) */
    tsr_cage bez_cage;
    tsr_subd *bez_subd; /* NULL when not built */
    uint32_t *bez_faces, bez_count;
    bool bez_tried, bez_ok; /* bez_ready's answer, kept */
    double bez_dev;
    char bez_note[600];
} model;

static const char *base_name(const char *path)
{
    const char *s = strrchr(path, '/');
    return s ? s + 1 : path;
}

static void model_free(model *m)
{
    tsr_pmodel_destroy(m->pm);
    tsr_subd_destroy(m->subd);
    tsr_subd_destroy(m->bez_subd);
    tsr_cage_free(&m->bez_cage);
    free(m->bez_faces);
    tsr_cage_free(&m->cage);
    tsr_patch_set_free(&m->set);
    memset(m, 0, sizeof *m);
}

/* Loads path: .bpt or free-form OBJ as a patch set, else polygon OBJ as a
 * cage; then the model of the adaptive tessellator. false (err says why,
 * naming the file) when the file cannot be read; a model the tessellator
 * refuses is kept (pm NULL, pm_status) so Bfr's figures still come. */
static bool model_load(const char *path, model *m, tsr_error *err)
{
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "%.200s", base_name(path));
    tsr_patch_format f = tsr_patch_format_from_path(path);
    if (f == TSR_PATCH_FORMAT_UNKNOWN) {
        tsr_error_set(err, TSR_ERR_UNSUPPORTED, "%s: unknown format (expected .bpt or .obj)", path);
        return false;
    }
    tsr_status st = tsr_patch_set_load(path, f, NULL, &m->set, err);
    if (st == TSR_OK)
        m->is_set = true;
    else if (f == TSR_PATCH_FORMAT_OBJ && st == TSR_ERR_EMPTY) { /* no free-form surface: a polygon cage */
        if (tsr_cage_load(path, NULL, &m->cage, err) != TSR_OK)
            return false;
        tsr_subd_scheme scheme = strncmp(m->name, "bilinear", 8) ? TSR_SUBD_CATMARK : TSR_SUBD_BILINEAR;
        if (tsr_subd_create(&m->cage, scheme, NULL, &m->subd, err) != TSR_OK) {
            char msg[512];
            snprintf(msg, sizeof msg, "%s", err->message);
            tsr_error_set(err, err->status, "%s: %s", path, msg);
            model_free(m);
            return false;
        }
        for (uint32_t face = 0; face < tsr_subd_face_count(m->subd); face++)
            if (tsr_subd_face_has_limit(m->subd, face)) {
                m->ngons |= tsr_subd_face_size(m->subd, face) != 4;
                m->patches += tsr_subd_face_patches(m->subd, face);
            }
    } else
        return false;
    tsr_error e = {0};
    m->pm_status =
        m->is_set ? tsr_pmodel_from_set(&m->set, NULL, &m->pm, &e) : tsr_pmodel_from_subd(m->subd, NULL, &m->pm, &e);
    if (m->pm_status != TSR_OK) {
        m->pm = NULL;
        snprintf(m->pm_message, sizeof m->pm_message, "%s", e.message[0] ? e.message : tsr_status_str(m->pm_status));
    } else {
        tsr_pmodel_get_info(m->pm, &m->info);
        double d2 = 0;
        for (int k = 0; k < 3; k++)
            d2 += (m->info.hi[k] - m->info.lo[k]) * (m->info.hi[k] - m->info.lo[k]);
        m->diag = sqrt(d2);
    }
    return true;
}

/* ---- Adaptive runs ----------------------------------------------------- */

typedef struct arow {
    bool ok;
    double rel, bound;
    uint32_t triangles, vertices, leaves;
    uint64_t evaluations;
    double seconds, err, rms;
    uint64_t uncovered;
    uint32_t worst_source; /* where the measured max error lies */
    double worst_uv[2];
} arow;

/* Runs tsr_ptess_run `repeat` times (the best time kept) and measures the
 * last result: in model units, or in pixels when cam is given. */
static tsr_status run_measured(const model *m, const tsr_ptess_options *o, uint32_t repeat, const tsr_camera *cam,
                               arow *r, tsr_error *err)
{
    r->seconds = INFINITY;
    tsr_ptess_result res;
    memset(&res, 0, sizeof res);
    for (uint32_t k = 0; k < repeat; k++) {
        tsr_ptess_result_free(&res);
        double t0 = cli_now();
        tsr_status st = tsr_ptess_run(m->pm, o, NULL, &res, err);
        double dt = cli_now() - t0;
        if (st != TSR_OK) {
            tsr_ptess_result_free(&res);
            return st;
        }
        r->seconds = fmin(r->seconds, dt);
    }
    r->triangles = res.mesh.triangle_count;
    r->vertices = res.mesh.vertex_count;
    r->leaves = res.leaves;
    r->evaluations = res.evaluations;
    tsr_ptess_measure_result mr;
    memset(&mr, 0, sizeof mr);
    tsr_status st = tsr_ptess_measure(m->pm, &res, PER_SIDE, cam, false, NULL, &mr);
    tsr_ptess_result_free(&res);
    if (st != TSR_OK)
        return tsr_error_set(err, st, "measurement: %s", tsr_status_str(st));
    r->err = mr.max_error;
    r->rms = mr.rms_error;
    r->uncovered = mr.uncovered;
    r->worst_source = mr.worst_source;
    r->worst_uv[0] = mr.worst_uv[0];
    r->worst_uv[1] = mr.worst_uv[1];
    r->ok = true;
    return TSR_OK;
}

/* ---- Searching the smallest sufficient rate ---------------------------- */

/* Indices 1..n stand for increasing rates; error(idx) is cached by the
 * caller and assumed non-increasing in idx. Returns the smallest idx whose
 * error is <= target, or 0 when even n is not enough. The first guesses
 * follow error ~ 1 / rate^2 (linear interpolation on smooth surfaces), then
 * bisection. */
typedef struct rate_search {
    uint32_t n;
    uint32_t (*rate)(uint32_t idx, void *ctx);
    double (*error)(uint32_t idx, void *ctx); /* NAN on failure */
    bool (*known)(uint32_t idx, void *ctx, double *e);
    void *ctx;
} rate_search;

static uint32_t find_rate(const rate_search *s, double target, bool *failed)
{
    uint32_t lo = 0, hi = s->n + 1, guesses = 0;
    for (uint32_t i = 1; i <= s->n; i++) {
        double e;
        if (s->known(i, s->ctx, &e) && isfinite(e)) {
            if (e <= target && i < hi)
                hi = i;
            if (e > target && i > lo)
                lo = i;
        }
    }
    if (lo >= hi) /* not monotone: trust the smallest passing one */
        lo = hi - 1;
    while (hi - lo > 1) {
        uint32_t g = lo + (hi - lo) / 2;
        if (guesses < 3) { /* the model's guess from the nearest known rate */
            double best_e = NAN;
            uint32_t best_i = 0;
            for (uint32_t i = 1; i <= s->n; i++) {
                double e;
                if (s->known(i, s->ctx, &e) && isfinite(e) && e > 0 &&
                    (!best_i || abs((int)i - (int)g) < abs((int)best_i - (int)g)))
                    best_i = i, best_e = e;
            }
            double want = best_i ? s->rate(best_i, s->ctx) * sqrt(best_e / target) : 8;
            /* the index of the smallest rate >= want */
            uint32_t w = lo + 1;
            while (w < hi - 1 && s->rate(w, s->ctx) < want)
                w++;
            g = w;
            guesses++;
        }
        double e = s->error(g, s->ctx);
        if (!isfinite(e)) {
            *failed = true;
            return 0;
        }
        if (e <= target)
            hi = g;
        else
            lo = g;
    }
    return hi <= s->n ? hi : 0;
}

/* ---- Bfr's uniform tessellation and its equivalent --------------------- */

/* The diagonal Bfr's uniform quad tessellation (Bfr::Tessellation, facet
 * size 3) gives cell (i, j) of an r x r lattice: 0 joins (i, j) to
 * (i+1, j+1), 1 joins (i+1, j) to (i, j+1). Bfr builds the quads in
 * concentric rings of four strips (bottom, right, top, left, each running
 * counter-clockwise); in a strip of R quads the first (at the ring's corner)
 * and those up to (R-2)/2 are split along the diagonal from the outer ring
 * backwards to the inner ring forwards, the rest the other way
 * (FacetStrip::connectUniformQuads); the single centre quad of an odd rate
 * along (i, j)-(i+1, j+1). An N-gon's sub-faces (even rates; Bfr's
 * qsub rings run half an edge through one sub-face, half through the next,
 * flipping the diagonal at the sub-face boundary) come out split along
 * (i, j)-(i+1, j+1) throughout: from the face's vertex towards its centre.
 * Checked against Bfr's own meshes at run time (pattern_mismatches). */
static int bfr_diagonal(uint32_t r, uint32_t i, uint32_t j)
{
    uint32_t g = i < j ? i : j, last;
    if (r - 1 - i < g)
        g = r - 1 - i;
    if (r - 1 - j < g)
        g = r - 1 - j;
    uint32_t R = r - 2 * g;
    last = r - 1 - g;
    if (R == 1)
        return 0;
    int side;
    uint32_t k;
    if (j == g && i < last)
        side = 0, k = i - g;
    else if (i == last && j < last)
        side = 1, k = j - g;
    else if (j == last && i > g)
        side = 2, k = last - i;
    else
        side = 3, k = last - j;
    int d = k <= (R - 2) / 2 ? 0 : 1;
    return (side & 1) ? 1 - d : d;
}

/* Bfr's surface of a model and the face standing for source si: the
 * cage's own (face, sub), or for a patch set the middle face of its
 * Bézier cage (bez_prepare), whose (u, v) is the patch's. */
static const tsr_subd *bfr_subd(const model *m)
{
    return m->subd ? m->subd : m->bez_subd;
}

static uint32_t bfr_face(const model *m, const tsr_psource_info *si)
{
    return m->subd ? si->patch : TSR_SUBD_BEZIER_FACE(si->patch);
}

/* The mesh Bfr's uniform tessellation at `rate` makes, as a
 * tsr_ptess_result (with tri_source and tri_uv) that tsr_ptess_measure
 * reads: per source (face, sub) (for a patch set: the source's middle
 * face, whose (u, v) spans the source's domain) the lattice of q = rate (quads) or rate / 2
 * (N-gon sub-faces; rate must then be even) quads per side, evaluated by
 * tsr_subd_eval, triangulated as bfr_diagonal says. Not welded (the
 * measurement does not need it). Free with free_equivalent. */
static tsr_status bfr_equivalent(const model *m, uint32_t rate, tsr_ptess_result *out, tsr_error *err)
{
    memset(out, 0, sizeof *out);
    tsr_mesh_init(&out->mesh, 0, NULL);
    uint64_t nv = 0, nt = 0;
    for (uint32_t s = 0; s < m->info.sources; s++) {
        tsr_psource_info si;
        if (!tsr_pmodel_source_info(m->pm, s, &si))
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "source %u has no info", s);
        uint64_t q = tsr_subd_face_size(bfr_subd(m), bfr_face(m, &si)) == 4 ? rate : rate / 2;
        nv += (q + 1) * (q + 1);
        nt += 2 * q * q;
    }
    if (nv > UINT32_MAX - 2 || nt > UINT32_MAX - 2)
        return tsr_error_set(err, TSR_ERR_TOO_LARGE, "rate %u: %llu triangles", rate, (unsigned long long)nt);
    out->tri_source = malloc(nt * sizeof *out->tri_source);
    out->tri_uv = malloc(6 * nt * sizeof *out->tri_uv);
    double *uv = malloc(2 * (size_t)(rate + 1) * (rate + 1) * sizeof *uv),
           *pos = malloc(3 * (size_t)(rate + 1) * (rate + 1) * sizeof *pos);
    if (!out->tri_source || !out->tri_uv || !uv || !pos ||
        tsr_mesh_reserve(&out->mesh, (uint32_t)nv, (uint32_t)nt) != TSR_OK) {
        free(uv);
        free(pos);
        return tsr_error_set(err, TSR_ERR_NOMEM, "rate %u: out of memory", rate);
    }
    uint32_t t = 0;
    for (uint32_t s = 0; s < m->info.sources; s++) {
        tsr_psource_info si;
        tsr_pmodel_source_info(m->pm, s, &si);
        bool quad = tsr_subd_face_size(bfr_subd(m), bfr_face(m, &si)) == 4;
        uint32_t q = quad ? rate : rate / 2, w = q + 1;
        for (uint32_t j = 0, k = 0; j <= q; j++)
            for (uint32_t i = 0; i <= q; i++, k++)
                uv[2 * k] = (double)i / q, uv[2 * k + 1] = (double)j / q;
        tsr_status st = tsr_subd_eval(bfr_subd(m), bfr_face(m, &si), si.sub, uv, w * w, pos, NULL, NULL);
        if (st != TSR_OK) {
            free(uv);
            free(pos);
            return tsr_error_set(err, st, "face %u, sub %u: evaluation failed", si.patch, si.sub);
        }
        uint32_t base = out->mesh.vertex_count;
        for (uint32_t k = 0; k < w * w; k++) {
            float p[3] = {(float)pos[3 * k], (float)pos[3 * k + 1], (float)pos[3 * k + 2]};
            tsr_mesh_add_vertex(&out->mesh, p, NULL, NULL);
        }
        double du = si.domain[1] - si.domain[0], dv = si.domain[3] - si.domain[2];
        for (uint32_t j = 0; j < q; j++)
            for (uint32_t i = 0; i < q; i++) {
                uint32_t c[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
                static const int tri[2][2][3] = {{{0, 1, 2}, {2, 3, 0}}, {{0, 1, 3}, {1, 2, 3}}};
                int d = quad ? bfr_diagonal(q, i, j) : 0;
                for (int h = 0; h < 2; h++, t++) {
                    uint32_t idx[3];
                    for (int a = 0; a < 3; a++) {
                        const uint32_t *cc = c[tri[d][h][a]];
                        idx[a] = base + cc[1] * w + cc[0];
                        out->tri_uv[6 * (size_t)t + 2 * a] = si.domain[0] + du * cc[0] / q;
                        out->tri_uv[6 * (size_t)t + 2 * a + 1] = si.domain[2] + dv * cc[1] / q;
                    }
                    out->tri_source[t] = s;
                    tsr_mesh_add_triangle(&out->mesh, idx[0], idx[1], idx[2]);
                }
            }
    }
    free(uv);
    free(pos);
    return TSR_OK;
}

static void free_equivalent(tsr_ptess_result *r)
{
    tsr_mesh_free(&r->mesh);
    free(r->tri_source);
    free(r->tri_uv);
    memset(r, 0, sizeof *r);
}

typedef struct centroid {
    uint64_t key;
    uint32_t tri;
} centroid;

static int cmp_centroid(const void *a, const void *b)
{
    const centroid *x = a, *y = b;
    return x->key < y->key ? -1 : x->key > y->key;
}

static void tri_centroid(const tsr_mesh *m, uint32_t t, double c[3])
{
    for (int k = 0; k < 3; k++)
        c[k] = 0;
    for (int a = 0; a < 3; a++)
        for (int k = 0; k < 3; k++)
            c[k] += m->positions[3 * (size_t)m->indices[3 * (size_t)t + a] + k] / 3.0;
}

/* Triangles of b whose centroid matches no triangle of a within tol (each
 * triangle of a matched once), plus the difference of the counts: 0 when
 * the two meshes have the same triangles, whatever their order and
 * welding. */
static uint64_t pattern_mismatches(const tsr_mesh *a, const tsr_mesh *b, const double lo[3], double tol)
{
    uint64_t bad = a->triangle_count > b->triangle_count ? a->triangle_count - b->triangle_count
                                                         : b->triangle_count - a->triangle_count;
    double cell = 2 * tol;
    centroid *ca = malloc((a->triangle_count + 1) * sizeof *ca);
    bool *used = calloc(a->triangle_count + 1, 1);
    if (!ca || !used) {
        free(ca);
        free(used);
        return UINT64_MAX;
    }
#define CELL_KEY(ix, iy, iz) (((uint64_t)(ix) << 42) | ((uint64_t)(iy) << 21) | (uint64_t)(iz))
    for (uint32_t t = 0; t < a->triangle_count; t++) {
        double c[3];
        tri_centroid(a, t, c);
        int64_t ix = (int64_t)floor((c[0] - lo[0]) / cell) + 1, iy = (int64_t)floor((c[1] - lo[1]) / cell) + 1,
                iz = (int64_t)floor((c[2] - lo[2]) / cell) + 1;
        ca[t].key = CELL_KEY(ix & 0x1fffff, iy & 0x1fffff, iz & 0x1fffff);
        ca[t].tri = t;
    }
    qsort(ca, a->triangle_count, sizeof *ca, cmp_centroid);
    for (uint32_t t = 0; t < b->triangle_count; t++) {
        double c[3];
        tri_centroid(b, t, c);
        int64_t ix = (int64_t)floor((c[0] - lo[0]) / cell) + 1, iy = (int64_t)floor((c[1] - lo[1]) / cell) + 1,
                iz = (int64_t)floor((c[2] - lo[2]) / cell) + 1;
        uint32_t best = UINT32_MAX;
        double best_d = tol * tol;
        for (int dx = -1; dx <= 1; dx++)
            for (int dy = -1; dy <= 1; dy++)
                for (int dz = -1; dz <= 1; dz++) {
                    uint64_t key = CELL_KEY((ix + dx) & 0x1fffff, (iy + dy) & 0x1fffff, (iz + dz) & 0x1fffff);
                    size_t l = 0, h = a->triangle_count;
                    while (l < h) {
                        size_t mid = (l + h) / 2;
                        if (ca[mid].key < key)
                            l = mid + 1;
                        else
                            h = mid;
                    }
                    for (; l < a->triangle_count && ca[l].key == key; l++) {
                        if (used[ca[l].tri])
                            continue;
                        double d[3];
                        tri_centroid(a, ca[l].tri, d);
                        double dd = (d[0] - c[0]) * (d[0] - c[0]) + (d[1] - c[1]) * (d[1] - c[1]) +
                                    (d[2] - c[2]) * (d[2] - c[2]);
                        if (dd <= best_d)
                            best_d = dd, best = ca[l].tri;
                    }
                }
        if (best == UINT32_MAX)
            bad++;
        else
            used[best] = true;
    }
#undef CELL_KEY
    free(ca);
    free(used);
    return bad;
}

typedef struct bfr_rate {
    bool timed, warned;
    uint32_t triangles, vertices;
    double seconds;
    uint64_t mismatches; /* UINT64_MAX: not checked */
} bfr_rate;

typedef struct bfr_ctx {
    model *m;
    double *err; /* per index, NAN unknown */
    bool *known;
    tsr_error *e;
} bfr_ctx;

static uint32_t bfr_idx_rate(uint32_t idx, void *ctx)
{
    return ((bfr_ctx *)ctx)->m->ngons ? 2 * idx : idx;
}

static bool bfr_known(uint32_t idx, void *ctx, double *e)
{
    bfr_ctx *c = ctx;
    *e = c->err[idx];
    return c->known[idx];
}

static double bfr_error(uint32_t idx, void *ctx)
{
    bfr_ctx *c = ctx;
    if (c->known[idx])
        return c->err[idx];
    tsr_ptess_result r;
    double e = NAN;
    if (bfr_equivalent(c->m, bfr_idx_rate(idx, ctx), &r, c->e) == TSR_OK) {
        tsr_ptess_measure_result mr;
        memset(&mr, 0, sizeof mr);
        tsr_status st = tsr_ptess_measure(c->m->pm, &r, PER_SIDE, NULL, false, NULL, &mr);
        if (st == TSR_OK)
            e = mr.max_error;
        else
            tsr_error_set(c->e, st, "measurement of Bfr's equivalent mesh: %s", tsr_status_str(st));
    }
    free_equivalent(&r);
    c->known[idx] = true;
    c->err[idx] = e;
    return e;
}

/* Times tsr_subd_tessellate_uniform at rate (best of repeat; for a patch
 * set, tsr_subd_tessellate_uniform_faces of its Bézier cage's middle
 * faces) and, when the adaptive model exists, checks that the equivalent
 * mesh has Bfr's triangles. */
static tsr_status bfr_time(model *m, uint32_t rate, uint32_t repeat, bfr_rate *out, tsr_error *err)
{
    out->seconds = INFINITY;
    out->mismatches = UINT64_MAX;
    tsr_mesh mesh;
    tsr_mesh_init(&mesh, 0, NULL);
    for (uint32_t k = 0; k < repeat; k++) {
        tsr_mesh_free(&mesh);
        tsr_mesh_init(&mesh, 0, NULL);
        double t0 = cli_now();
        tsr_status st =
            m->subd ? tsr_subd_tessellate_uniform(m->subd, rate, &mesh, err)
                    : tsr_subd_tessellate_uniform_faces(m->bez_subd, rate, m->bez_faces, m->bez_count, &mesh, err);
        double dt = cli_now() - t0;
        if (st != TSR_OK) {
            tsr_mesh_free(&mesh);
            return st;
        }
        out->seconds = fmin(out->seconds, dt);
    }
    out->triangles = mesh.triangle_count;
    out->vertices = mesh.vertex_count;
    out->timed = true;
    if (m->pm && (!m->ngons || rate % 2 == 0)) {
        tsr_ptess_result eq;
        if (bfr_equivalent(m, rate, &eq, err) == TSR_OK)
            out->mismatches = pattern_mismatches(&eq.mesh, &mesh, m->info.lo, 1e-5 * m->diag);
        free_equivalent(&eq);
    }
    tsr_mesh_free(&mesh);
    return TSR_OK;
}

/* ---- Evaluation rates -------------------------------------------------- */

typedef struct eval_rate {
    bool ok;
    uint64_t points;               /* per sweep */
    double positions, derivatives; /* points per second */
} eval_rate;

/* Points per second of the model's own evaluator on a G x G grid per
 * patch: tsr_subd_eval (one call per patch: Bfr prepares the face once)
 * for a cage, tsr_patch_eval for a patch set; with bez_cage, Bfr on a
 * patch set's Catmull-Clark cage (bez_prepare; not ok when it has none).
 * Enough sweeps per run for about a million points; best of repeat. */
static eval_rate eval_rate_of(const model *m, uint32_t repeat, bool bez_cage)
{
    enum { G = 64 };
    eval_rate r = {0};
    double *uv = malloc(2 * G * G * sizeof *uv), *pos = malloc(3 * G * G * sizeof *pos),
           *du = malloc(3 * G * G * sizeof *du), *dv = malloc(3 * G * G * sizeof *dv);
    if (!uv || !pos || !du || !dv)
        goto done;
    for (uint32_t j = 0, k = 0; j < G; j++)
        for (uint32_t i = 0; i < G; i++, k++)
            uv[2 * k] = (i + 0.5) / G, uv[2 * k + 1] = (j + 0.5) / G;
    /* bez_cage: Bfr on the patch set's Catmull-Clark cage, its middle faces */
    bool set = m->is_set && !bez_cage;
    const tsr_subd *subd = bez_cage ? m->bez_subd : m->subd;
    uint32_t units = bez_cage ? m->bez_count : m->is_set ? m->set.num_patches : m->patches;
    if (bez_cage && !subd)
        goto done;
    if (!units)
        goto done;
    r.points = (uint64_t)units * G * G;
    uint32_t sweeps = (uint32_t)(1000000 / r.points) + 1;
    volatile double sink = 0;
    for (int withd = 0; withd < 2; withd++) {
        double best = INFINITY;
        for (uint32_t rep = 0; rep < repeat; rep++) {
            double t0 = cli_now();
            for (uint32_t sw = 0; sw < sweeps; sw++) {
                if (set) {
                    for (uint32_t p = 0; p < m->set.num_patches; p++) {
                        const tsr_patch *pa = &m->set.patches[p];
                        double dom[4];
                        tsr_patch_domain(pa, dom);
                        for (uint32_t k = 0; k < G * G; k++)
                            tsr_patch_eval(pa, dom[0] + uv[2 * k] * (dom[1] - dom[0]),
                                           dom[2] + uv[2 * k + 1] * (dom[3] - dom[2]), pos + 3 * k,
                                           withd ? du + 3 * k : NULL, withd ? dv + 3 * k : NULL, NULL);
                        sink += pos[0];
                    }
                } else {
                    uint32_t nf = bez_cage ? m->bez_count : tsr_subd_face_count(subd);
                    for (uint32_t k = 0; k < nf; k++) {
                        uint32_t f = bez_cage ? m->bez_faces[k] : k;
                        if (!tsr_subd_face_has_limit(subd, f))
                            continue;
                        for (uint32_t s = 0; s < tsr_subd_face_patches(subd, f); s++) {
                            if (tsr_subd_eval(subd, f, s, uv, G * G, pos, withd ? du : NULL, withd ? dv : NULL) !=
                                TSR_OK)
                                goto done;
                            sink += pos[0];
                        }
                    }
                }
            }
            best = fmin(best, cli_now() - t0);
        }
        *(withd ? &r.derivatives : &r.positions) = (double)r.points * sweeps / best;
    }
    (void)sink;
    r.ok = true;
done:
    free(uv);
    free(pos);
    free(du);
    free(dv);
    return r;
}

/* ---- The view-dependent teapot ------------------------------------------ */

/* Camera k of n on an orbit around the model's box: 2.5 box radii from its
 * centre, 25 degrees above the horizon, 1920 x 1080, 60 degrees. */
static void orbit_camera(const model *m, uint32_t k, uint32_t n, tsr_camera *c)
{
    double ctr[3], rad = 0.5 * m->diag;
    for (int i = 0; i < 3; i++)
        ctr[i] = 0.5 * (m->info.lo[i] + m->info.hi[i]);
    double az = 0.3 + 6.283185307179586 * k / n, el = 25 * 3.141592653589793 / 180, d = 2.5 * rad;
    memset(c, 0, sizeof *c);
    c->eye[0] = ctr[0] + d * cos(el) * cos(az);
    c->eye[1] = ctr[1] + d * cos(el) * sin(az);
    c->eye[2] = ctr[2] + d * sin(el);
    memcpy(c->target, ctr, sizeof ctr);
    c->fovy_deg = 60;
    c->width = 1920;
    c->height = 1080;
    c->near_dist = 0.01 * rad;
    c->pixel_error = 1;
    tsr_camera_prepare(c);
}

/* The uniform tessellation by tsr_ptess_run: rates 2..128 (even) as one
 * tile of `rate` quads per piece that never splits (max_level 1, a bound
 * no node exceeds); beyond, multiples of 4 as tiles of rate / 2 split
 * once (a bound every curved node exceeds; flat pieces, whose bound is 0,
 * stay at rate / 2, which loses nothing). */
static uint32_t uni_idx_rate(uint32_t idx, void *ctx)
{
    (void)ctx;
    return idx <= 64 ? 2 * idx : 128 + 4 * (idx - 64);
}

static tsr_ptess_options uniform_options(uint32_t rate)
{
    tsr_ptess_options o = {0};
    o.max_level = 1;
    o.fixed_tile = true;
    if (rate <= TSR_TILE_MAX) {
        o.tile_n = rate;
        o.max_error = 1e300;
    } else {
        o.tile_n = rate / 2;
        o.max_error = 1e-300;
    }
    return o;
}

typedef struct uni_entry {
    bool known, timed;
    double *err; /* per camera, pixels */
    uint32_t triangles, vertices;
    double seconds;
} uni_entry;

typedef struct uni_ctx {
    model *m;
    const tsr_camera *cams;
    uint32_t ncam, cam; /* the camera the search is for */
    uni_entry *e;
    tsr_error *err;
} uni_ctx;

static bool uni_fill(uni_ctx *c, uint32_t idx)
{
    uni_entry *u = &c->e[idx];
    if (u->known)
        return u->err != NULL;
    u->known = true;
    tsr_ptess_options o = uniform_options(uni_idx_rate(idx, NULL));
    tsr_ptess_result r;
    if (tsr_ptess_run(c->m->pm, &o, NULL, &r, c->err) != TSR_OK) {
        tsr_ptess_result_free(&r);
        return false;
    }
    u->triangles = r.mesh.triangle_count;
    u->vertices = r.mesh.vertex_count;
    u->err = malloc(c->ncam * sizeof *u->err);
    for (uint32_t k = 0; u->err && k < c->ncam; k++) {
        tsr_ptess_measure_result mr;
        memset(&mr, 0, sizeof mr);
        tsr_status st = tsr_ptess_measure(c->m->pm, &r, PER_SIDE, &c->cams[k], false, NULL, &mr);
        if (st != TSR_OK) {
            tsr_error_set(c->err, st, "measurement: %s", tsr_status_str(st));
            free(u->err);
            u->err = NULL;
        } else
            u->err[k] = mr.max_error;
    }
    tsr_ptess_result_free(&r);
    return u->err != NULL;
}

static bool uni_known(uint32_t idx, void *ctx, double *e)
{
    uni_ctx *c = ctx;
    *e = c->e[idx].err ? c->e[idx].err[c->cam] : NAN;
    return c->e[idx].known;
}

static double uni_error(uint32_t idx, void *ctx)
{
    uni_ctx *c = ctx;
    return uni_fill(c, idx) ? c->e[idx].err[c->cam] : NAN;
}

static bool uni_time(uni_ctx *c, uint32_t idx, uint32_t repeat)
{
    uni_entry *u = &c->e[idx];
    if (u->timed)
        return true;
    tsr_ptess_options o = uniform_options(uni_idx_rate(idx, NULL));
    arow r = {0};
    r.seconds = INFINITY;
    for (uint32_t k = 0; k < repeat; k++) {
        tsr_ptess_result res;
        double t0 = cli_now();
        tsr_status st = tsr_ptess_run(c->m->pm, &o, NULL, &res, c->err);
        double dt = cli_now() - t0;
        tsr_ptess_result_free(&res);
        if (st != TSR_OK)
            return false;
        r.seconds = fmin(r.seconds, dt);
    }
    u->seconds = r.seconds;
    u->timed = true;
    return true;
}

/* ---- Bfr on the teapot ------------------------------------------------------ */

/* Builds m's Bézier cage for Bfr (tsr_subd_cage_from_bezier): every patch
 * must be a polynomial bicubic Bézier patch whose source is untrimmed and
 * covers its whole domain. Then checks the orientation the equivalent mesh
 * relies on: Bfr's middle face at (u, v) against tsr_patch_eval at the
 * patch's (s, t) = its domain at (u, v), on 7 x 7 points per patch;
 * *deviation is the largest distance over the box diagonal, refused beyond
 * 1e-9. false with note saying why (m->bez_subd NULL). */
static bool bez_prepare(model *m, double *deviation, char *note, size_t cap)
{
    const tsr_patch_set *set = &m->set;
    *deviation = NAN;
    if (m->info.sources != set->num_patches) {
        snprintf(note, cap, "%u sources for %u patches", m->info.sources, set->num_patches);
        return false;
    }
    for (uint32_t s = 0; s < m->info.sources; s++) {
        tsr_psource_info si;
        double dom[4];
        if (!tsr_pmodel_source_info(m->pm, s, &si) || si.patch >= set->num_patches) {
            snprintf(note, cap, "source %u has no patch", s);
            return false;
        }
        const tsr_patch *pa = &set->patches[si.patch];
        if (pa->kind != TSR_PATCH_BEZIER || pa->degree_u != 3 || pa->degree_v != 3 || pa->weights) {
            snprintf(note, cap, "patch %u is not a polynomial bicubic Bezier patch (%s, degrees %d x %d)", si.patch,
                     pa->kind == TSR_PATCH_BEZIER    ? (pa->weights ? "rational Bezier" : "Bezier")
                     : pa->kind == TSR_PATCH_BSPLINE ? "B-spline"
                                                     : "NURBS",
                     pa->degree_u, pa->degree_v);
            return false;
        }
        if (si.trimmed) {
            snprintf(note, cap, "patch %u is trimmed (Bfr would mesh the whole patch)", si.patch);
            return false;
        }
        tsr_patch_domain(pa, dom);
        if (memcmp(dom, si.domain, sizeof dom)) {
            snprintf(note, cap, "source %u covers part of patch %u", s, si.patch);
            return false;
        }
    }
    uint32_t n = set->num_patches;
    double *ctrl = malloc(48 * (size_t)n * sizeof *ctrl);
    m->bez_faces = malloc(n * sizeof *m->bez_faces);
    if (!ctrl || !m->bez_faces) {
        free(ctrl);
        snprintf(note, cap, "out of memory");
        return false;
    }
    for (uint32_t p = 0; p < n; p++) {
        memcpy(ctrl + 48 * (size_t)p, set->patches[p].ctrl, 48 * sizeof *ctrl);
        m->bez_faces[p] = TSR_SUBD_BEZIER_FACE(p);
    }
    m->bez_count = n;
    tsr_error e = {0};
    tsr_status st = tsr_subd_cage_from_bezier(ctrl, n, NULL, &m->bez_cage, &e);
    free(ctrl);
    if (st == TSR_OK)
        st = tsr_subd_create(&m->bez_cage, TSR_SUBD_CATMARK, NULL, &m->bez_subd, &e);
    if (st != TSR_OK) {
        snprintf(note, cap, "Bezier cage: %s", e.message);
        return false;
    }
    enum { G = 7 };
    double uv[2 * G * G], pos[3 * G * G], worst = 0;
    for (uint32_t j = 0, k = 0; j < G; j++)
        for (uint32_t i = 0; i < G; i++, k++)
            uv[2 * k] = (double)i / (G - 1), uv[2 * k + 1] = (double)j / (G - 1);
    for (uint32_t p = 0; p < n && st == TSR_OK; p++) {
        const tsr_patch *pa = &set->patches[p];
        double dom[4];
        tsr_patch_domain(pa, dom);
        st = tsr_subd_eval(m->bez_subd, m->bez_faces[p], 0, uv, G * G, pos, NULL, NULL);
        for (uint32_t k = 0; st == TSR_OK && k < G * G; k++) {
            double ref[3], d2 = 0;
            tsr_patch_eval(pa, dom[0] + uv[2 * k] * (dom[1] - dom[0]), dom[2] + uv[2 * k + 1] * (dom[3] - dom[2]), ref,
                           NULL, NULL, NULL);
            for (int c = 0; c < 3; c++)
                d2 += (pos[3 * k + c] - ref[c]) * (pos[3 * k + c] - ref[c]);
            worst = fmax(worst, sqrt(d2) / m->diag);
        }
    }
    *deviation = worst;
    if (st != TSR_OK || !(worst <= 1e-9)) {
        if (st != TSR_OK)
            snprintf(note, cap, "Bfr's evaluation of the Bezier cage failed: %s", tsr_status_str(st));
        else
            snprintf(note, cap, "Bfr's middle faces are off the patches by %.3g of the diagonal", worst);
        tsr_subd_destroy(m->bez_subd);
        m->bez_subd = NULL;
        return false;
    }
    return true;
}

/* bez_prepare once per model, its answer kept. */
static bool bez_ready(model *m)
{
    if (!m->bez_tried) {
        m->bez_tried = true;
        m->bez_ok = bez_prepare(m, &m->bez_dev, m->bez_note, sizeof m->bez_note);
    }
    return m->bez_ok;
}

/* The search of Bfr's rate per camera: rates 1..n, each measured (its
 * equivalent mesh, bfr_equivalent) from every camera at once. */
typedef struct bview_ctx {
    model *m;
    const tsr_camera *cams;
    uint32_t ncam, cam; /* the camera the search is for */
    double **err;       /* per rate: per camera, pixels; NULL unknown or failed */
    bool *known;
    bfr_rate *timed; /* per rate */
    tsr_error *e;
} bview_ctx;

static uint32_t bview_idx_rate(uint32_t idx, void *ctx)
{
    (void)ctx;
    return idx;
}

static bool bview_fill(bview_ctx *c, uint32_t idx)
{
    if (c->known[idx])
        return c->err[idx] != NULL;
    c->known[idx] = true;
    tsr_ptess_result r;
    if (bfr_equivalent(c->m, idx, &r, c->e) != TSR_OK) {
        free_equivalent(&r);
        return false;
    }
    double *e = malloc(c->ncam * sizeof *e);
    if (!e)
        tsr_error_set(c->e, TSR_ERR_NOMEM, "out of memory");
    for (uint32_t k = 0; e && k < c->ncam; k++) {
        tsr_ptess_measure_result mr;
        memset(&mr, 0, sizeof mr);
        tsr_status st = tsr_ptess_measure(c->m->pm, &r, PER_SIDE, &c->cams[k], false, NULL, &mr);
        if (st != TSR_OK) {
            tsr_error_set(c->e, st, "measurement of Bfr's equivalent mesh: %s", tsr_status_str(st));
            free(e);
            e = NULL;
        } else
            e[k] = mr.max_error;
    }
    free_equivalent(&r);
    c->err[idx] = e;
    return e != NULL;
}

static bool bview_known(uint32_t idx, void *ctx, double *e)
{
    bview_ctx *c = ctx;
    *e = c->err[idx] ? c->err[idx][c->cam] : NAN;
    return c->known[idx];
}

static double bview_error(uint32_t idx, void *ctx)
{
    bview_ctx *c = ctx;
    return bview_fill(c, idx) ? c->err[idx][c->cam] : NAN;
}

/* ---- The command --------------------------------------------------------- */

typedef struct model_result {
    char name[256];
    bool loaded, adaptive_ok, is_set;
    char note[600];
    uint32_t pieces, sources, patches;
    double diag;
    arow rows[MAX_ERRORS];
    bool bfr_found[MAX_ERRORS];
    uint32_t bfr_rate_of[MAX_ERRORS];
    double bfr_err_of[MAX_ERRORS];
    bfr_rate bfr_at[MAX_ERRORS];
    eval_rate eval;
    eval_rate bez_eval; /* a patch set: Bfr on its Catmull-Clark cage */
    bfr_rate fallback[5];  /* Bfr at rates 4..64 when there is no adaptive model */
    uint64_t bfr_max_tris; /* Bfr's triangles at the largest rate searched */
} model_result;

/* An evaluation rate as member `key` of parent. */
static void json_eval(cJSON *parent, const char *key, const char *evaluator, const eval_rate *r)
{
    cJSON *j = cJSON_AddObjectToObject(parent, key);
    cJSON_AddStringToObject(j, "evaluator", evaluator);
    cJSON_AddNumberToObject(j, "points_per_sweep", (double)r->points);
    cJSON_AddNumberToObject(j, "positions_per_second", r->positions);
    cJSON_AddNumberToObject(j, "with_derivatives_per_second", r->derivatives);
}

static cJSON *json_arow(const arow *r)
{
    cJSON *j = cJSON_CreateObject();
    cJSON_AddNumberToObject(j, "triangles", r->triangles);
    cJSON_AddNumberToObject(j, "vertices", r->vertices);
    cJSON_AddNumberToObject(j, "leaves", r->leaves);
    cJSON_AddNumberToObject(j, "evaluations", (double)r->evaluations);
    cJSON_AddNumberToObject(j, "seconds", r->seconds);
    cJSON_AddNumberToObject(j, "measured_max_error", r->err);
    cJSON_AddNumberToObject(j, "measured_rms_error", r->rms);
    cJSON_AddNumberToObject(j, "uncovered_samples", (double)r->uncovered);
    cJSON_AddNumberToObject(j, "worst_source", r->worst_source);
    cJSON *w = cJSON_AddArrayToObject(j, "worst_uv");
    cJSON_AddItemToArray(w, cJSON_CreateNumber(r->worst_uv[0]));
    cJSON_AddItemToArray(w, cJSON_CreateNumber(r->worst_uv[1]));
    return j;
}

int cli_bench_patch(int argc, char **argv)
{
    uint32_t repeat = 3, tile = 0, max_rate = 256, ncam = 8;
    bool quick = false, cold = false, repeat_given = false, errors_given = false, cams_given = false;
    const char *input = NULL, *json_path = NULL;
    double fr[MAX_ERRORS] = {1e-2, 3e-3, 1e-3, 3e-4, 1e-4};
    int nfr = 5;
    for (int i = 2; i < argc; i++) {
        const char *a = argv[i];
        bool more = i + 1 < argc, ok = true;
        if (cli_is_help(a)) {
            help(stdout);
            return CLI_OK;
        } else if (!strcmp(a, "--quick"))
            quick = true;
        else if (!strcmp(a, "--cold"))
            cold = true;
        else if (!strcmp(a, "--input") && more)
            input = argv[++i];
        else if (!strcmp(a, "--json") && more)
            json_path = argv[++i];
        else if (!strcmp(a, "--repeat") && more)
            ok = cli_parse_u32(argv[++i], 1, 1000, &repeat), repeat_given = true;
        else if (!strcmp(a, "--tile") && more)
            ok = cli_parse_u32(argv[++i], 2, TSR_TILE_MAX, &tile) && tile % 2 == 0;
        else if (!strcmp(a, "--max-rate") && more)
            ok = cli_parse_u32(argv[++i], 2, 512, &max_rate);
        else if (!strcmp(a, "--cameras") && more)
            ok = cli_parse_u32(argv[++i], 1, MAX_CAMERAS, &ncam), cams_given = true;
        else if (!strcmp(a, "--errors") && more) {
            const char *s = argv[++i];
            nfr = 0;
            errors_given = true;
            while (ok && *s) {
                char *end;
                double v = strtod(s, &end);
                if (end == s || !(v > 0) || !isfinite(v) || (*end && *end != ',') || nfr == MAX_ERRORS)
                    ok = false;
                else
                    fr[nfr++] = v;
                s = *end ? end + 1 : end;
            }
            ok = ok && nfr > 0;
        } else {
            cli_option_error("bench", "patch", a, help);
            return CLI_USAGE;
        }
        if (!ok) {
            cli_error("bench", "patch: bad value '%s' for %s (see tessera bench patch --help)", argv[i], a);
            return CLI_USAGE;
        }
    }
    if (quick) {
        if (!repeat_given)
            repeat = 1;
        if (!errors_given)
            fr[0] = 1e-2, fr[1] = 1e-3, nfr = 2;
        if (!cams_given)
            ncam = 2;
    }
    if (!cli_outputs_writable("bench patch", 1, &json_path)) /* before the runs, not after them */
        return CLI_FAIL;
    const char *data = input ? NULL : bench_data_dir("bench patch");
    static const char *const cages[] = {"catmark_cube_creases1.obj", "catmark_cubes_semisharp.obj",
                                        "catmark_gregory_test1.obj", "catmark_edgecorner.obj", "catmark_fan.obj"};
    char paths[8][4096];
    int npaths = 0;
    if (input)
        snprintf(paths[npaths++], sizeof paths[0], "%s", input);
    else {
        snprintf(paths[npaths++], sizeof paths[0], "%s/patches/teapot.bpt", data);
        for (size_t k = 0; k < (quick ? 1 : sizeof cages / sizeof cages[0]); k++)
            snprintf(paths[npaths++], sizeof paths[0], "%s/patches/osd/%s", data, cages[k]);
    }

    char cmdline[1024] = "tessera";
    for (int i = 0; i < argc; i++)
        if (strlen(cmdline) + strlen(argv[i]) + 2 < sizeof cmdline)
            strcat(strcat(cmdline, " "), argv[i]);
    /* warm: blocks up to 32 MiB come from the heap and freed memory stays
     * there (glibc frees big blocks to the kernel otherwise, and the next
     * run faults every page in again) */
    if (!cold)
        cold = !mallopt(M_MMAP_THRESHOLD, 32 << 20) || !mallopt(M_TRIM_THRESHOLD, 1 << 30);
    printf("%s\n\nbest of %u; tile %u; bounds relative to each model's box diagonal; errors measured by "
           "tsr_ptess_measure (%u x %u samples per piece + every triangle edge midpoint; not timed); positions only "
           "(no normals) on both sides; %s\n",
           cmdline, repeat, tile ? tile : 4, PER_SIDE, PER_SIDE,
           cold ? "cold memory (every run touches fresh pages)"
                : "warm memory (freed memory kept in the process: repeats reuse touched pages)");
    fflush(stdout);

    int rc = CLI_OK;
    model_result *res = calloc((size_t)npaths, sizeof *res);
    model *teapot = NULL;
    if (!res) {
        cli_error("bench", "patch: out of memory");
        return CLI_FAIL;
    }
    for (int p = 0; p < npaths; p++) {
        model_result *R = &res[p];
        /* on the heap: the adaptive model keeps pointing at the patch set */
        model *mp = calloc(1, sizeof *mp);
        tsr_error err = {0};
        snprintf(R->name, sizeof R->name, "%.200s", base_name(paths[p]));
        if (!mp) {
            cli_error("bench", "patch: out of memory");
            rc = CLI_FAIL;
            break;
        }
        if (!model_load(paths[p], mp, &err)) {
            free(mp);
            if (input) {
                cli_error("bench", "patch: %s", err.message);
                free(res);
                return CLI_FAIL;
            }
            snprintf(R->note, sizeof R->note, "skipped: %s", err.message);
            fprintf(stderr, "tessera bench patch: %s %s\n", R->name, R->note);
            continue;
        }
        R->loaded = true;
        R->is_set = mp->is_set;
        R->patches = mp->is_set ? mp->set.num_patches : mp->patches;
        fprintf(stderr, "tessera bench patch: %s...\n", R->name);
        if (!mp->pm) {
            snprintf(R->note, sizeof R->note, "adaptive tessellation unavailable: %s%s", mp->pm_message,
                     mp->pm_status == TSR_ERR_UNSUPPORTED ? " (patches/ptess.c does not support it yet)" : "");
            cli_error("bench", "patch: %s: %s", paths[p], R->note);
            rc = CLI_FAIL;
        } else {
            R->adaptive_ok = true;
            R->pieces = mp->info.pieces;
            R->sources = mp->info.sources;
            R->diag = mp->diag;
        }
        /* 3. the evaluation rate (needs only subd.h / patches.h) */
        R->eval = eval_rate_of(mp, repeat, false);
        if (mp->is_set && mp->pm && bez_ready(mp))
            R->bez_eval = eval_rate_of(mp, repeat, true);
        /* 1. the ladder */
        for (int k = 0; R->adaptive_ok && k < nfr; k++) {
            arow *r = &R->rows[k];
            r->rel = fr[k];
            r->bound = fr[k] * mp->diag;
            tsr_ptess_options o = {0};
            o.max_error = r->bound;
            o.tile_n = tile;
            if (run_measured(mp, &o, repeat, NULL, r, &err) != TSR_OK) {
                snprintf(R->note, sizeof R->note, "adaptive tessellation at %g failed: %s", fr[k], err.message);
                cli_error("bench", "patch: %s: %s", paths[p], R->note);
                R->adaptive_ok = false;
                rc = CLI_FAIL;
            } else if (r->uncovered) {
                cli_error("bench", "patch: %s: bound %g: %llu measured samples lie in no triangle (gaps)", paths[p],
                          fr[k], (unsigned long long)r->uncovered);
                rc = CLI_FAIL;
            }
        }
        /* 2. Bfr's uniform tessellation at the rate reaching the same measured error */
        if (mp->subd && R->adaptive_ok) {
            uint32_t n = mp->ngons ? max_rate / 2 : max_rate;
            for (uint32_t f = 0; f < tsr_subd_face_count(mp->subd); f++)
                if (tsr_subd_face_has_limit(mp->subd, f)) {
                    uint64_t q = tsr_subd_face_size(mp->subd, f) == 4 ? max_rate : max_rate / 2;
                    R->bfr_max_tris += 2 * q * q * tsr_subd_face_patches(mp->subd, f);
                }
            double *errs = malloc((n + 2) * sizeof *errs);
            bool *known = calloc(n + 2, 1);
            bfr_rate *timed = calloc(n + 2, sizeof *timed);
            bfr_ctx bc = {mp, errs, known, &err};
            rate_search s = {n, bfr_idx_rate, bfr_error, bfr_known, &bc};
            for (int k = 0; errs && known && timed && k < nfr; k++) {
                bool failed = false;
                uint32_t idx = find_rate(&s, fmax(R->rows[k].err, MODEL_ERROR_FLOOR * mp->diag), &failed);
                if (failed) {
                    cli_error("bench", "patch: %s: Bfr's equivalent mesh: %s", paths[p], err.message);
                    rc = CLI_FAIL;
                    break;
                }
                if (!idx)
                    continue;
                R->bfr_found[k] = true;
                R->bfr_rate_of[k] = bfr_idx_rate(idx, &bc);
                R->bfr_err_of[k] = errs[idx];
                if (!timed[idx].timed && bfr_time(mp, R->bfr_rate_of[k], repeat, &timed[idx], &err) != TSR_OK) {
                    cli_error("bench", "patch: %s: Bfr: %s", paths[p], err.message);
                    rc = CLI_FAIL;
                    R->bfr_found[k] = false;
                    continue;
                }
                R->bfr_at[k] = timed[idx];
                if (timed[idx].mismatches && timed[idx].mismatches != UINT64_MAX)
                    fprintf(stderr,
                            "tessera bench patch: %s: warning: at rate %u, %llu triangles of Bfr's mesh differ from "
                            "the equivalent mesh whose error is measured\n",
                            R->name, R->bfr_rate_of[k], (unsigned long long)timed[idx].mismatches);
            }
            free(errs);
            free(known);
            free(timed);
        } else if (mp->subd) {
            for (int k = 0; k < 5; k++)
                if (bfr_time(mp, 4u << k, repeat, &R->fallback[k], &err) != TSR_OK) {
                    cli_error("bench", "patch: %s: Bfr: %s", paths[p], err.message);
                    rc = CLI_FAIL;
                    break;
                }
        }
        if (mp->is_set && mp->pm && !teapot && R->adaptive_ok)
            teapot = mp; /* kept for the view-dependent part */
        else {
            model_free(mp);
            free(mp);
        }
    }

    cJSON *json = cJSON_CreateObject();
    cJSON_AddStringToObject(json, "command", cmdline);
    cJSON_AddNumberToObject(json, "repeat", repeat);
    cJSON_AddBoolToObject(json, "warm_memory", !cold);
    cJSON_AddNumberToObject(json, "tile", tile ? tile : 4);
    cJSON_AddNumberToObject(json, "per_side", PER_SIDE);
    cJSON *jmodels = cJSON_AddArrayToObject(json, "models");

    /* eval baselines per model, for the ratios of table 1 */
    printf("\n### 1. Adaptive tessellation (tsr_ptess_run, view-independent)\n\n"
           "| model | pieces | bound / diag | bound | triangles | vertices | leaves | seconds | measured max err | "
           "measured / bound | M vertices/s | M evaluations/s | vertices/s / eval baseline |\n"
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (int p = 0; p < npaths; p++) {
        model_result *R = &res[p];
        cJSON *jm = cJSON_CreateObject();
        cJSON_AddItemToArray(jmodels, jm);
        cJSON_AddStringToObject(jm, "name", R->name);
        if (R->note[0])
            cJSON_AddStringToObject(jm, "note", R->note);
        if (!R->loaded || !R->adaptive_ok) {
            printf("| %s | %s | | | | | | | | | | | |\n", R->name, R->note);
            continue;
        }
        cJSON_AddStringToObject(jm, "kind", R->is_set ? "patch set" : "subdivision cage");
        cJSON_AddNumberToObject(jm, "diagonal", R->diag);
        cJSON_AddNumberToObject(jm, "pieces", R->pieces);
        cJSON *jl = cJSON_AddArrayToObject(jm, "ladder");
        for (int k = 0; k < nfr; k++) {
            const arow *r = &R->rows[k];
            double vps = r->vertices / r->seconds, eps = r->evaluations / r->seconds;
            double base = R->eval.ok ? R->eval.positions : 0;
            printf("| %s | %u | %g | %.4g | %u | %u | %u | %.5f | %.4g | %.2f | %.2f | %.2f | %.2f%s |\n", R->name,
                   R->pieces, r->rel, r->bound, r->triangles, r->vertices, r->leaves, r->seconds, r->err,
                   r->err / r->bound, vps / 1e6, eps / 1e6, base > 0 ? vps / base : 0, r->uncovered ? " (GAPS)" : "");
            cJSON *jr = json_arow(r);
            cJSON_AddNumberToObject(jr, "bound_relative", r->rel);
            cJSON_AddNumberToObject(jr, "bound", r->bound);
            cJSON_AddNumberToObject(jr, "vertices_per_second", vps);
            cJSON_AddNumberToObject(jr, "evaluations_per_second", eps);
            if (R->bfr_found[k]) {
                cJSON *jb = cJSON_CreateObject();
                cJSON_AddNumberToObject(jb, "rate", R->bfr_rate_of[k]);
                cJSON_AddNumberToObject(jb, "triangles", R->bfr_at[k].triangles);
                cJSON_AddNumberToObject(jb, "vertices", R->bfr_at[k].vertices);
                cJSON_AddNumberToObject(jb, "seconds", R->bfr_at[k].seconds);
                cJSON_AddNumberToObject(jb, "measured_max_error", R->bfr_err_of[k]);
                cJSON_AddNumberToObject(jb, "triangle_ratio", (double)r->triangles / R->bfr_at[k].triangles);
                cJSON_AddNumberToObject(jb, "time_ratio", r->seconds / R->bfr_at[k].seconds);
                if (R->bfr_at[k].mismatches != UINT64_MAX)
                    cJSON_AddNumberToObject(jb, "pattern_mismatches", (double)R->bfr_at[k].mismatches);
                cJSON_AddItemToObject(jr, "bfr_uniform", jb);
            }
            cJSON_AddItemToArray(jl, jr);
        }
    }
    printf("\nThe eval baseline is the model's own evaluator on a dense grid (table 3): Bfr (tsr_subd_eval, "
           "positions) for cages, tsr_patch_eval for patch sets.\n");

    printf(
        "\n### 2. Bfr uniform tessellation at the same measured error (cages)\n\n"
        "Bfr's error is measured on an equivalent mesh: Bfr's points (rate r per quad, r/2 per N-gon sub-face, "
        "evaluated by tsr_subd_eval) and Bfr's triangles (its ring pattern of diagonals), checked against "
        "Bfr's own mesh by triangle centroids (pattern check: triangles of Bfr's mesh not matched; 0 = the "
        "same mesh). Rate = the smallest in 1..%u (even only for cages with N-gons) whose measured error is "
        "<= the adaptive row's (or 1e-6 of the diagonal, float32 rounding, whichever is larger), found by "
        "bracketing with the error assumed non-increasing in the rate.\n\n"
        "| model | bound / diag | adaptive triangles | adaptive measured | Bfr rate | Bfr measured | Bfr triangles | "
        "Bfr seconds | pattern check | triangles adaptive / Bfr (target <= 0.5) | time adaptive / Bfr |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|\n",
        max_rate);
    for (int p = 0; p < npaths; p++) {
        model_result *R = &res[p];
        if (!R->loaded || R->is_set)
            continue;
        if (!R->adaptive_ok) {
            for (int k = 0; k < 5; k++)
                if (R->fallback[k].timed)
                    printf("| %s | (no adaptive model) | | | %u | | %u | %.5f | | | |\n", R->name, 4u << k,
                           R->fallback[k].triangles, R->fallback[k].seconds);
            continue;
        }
        for (int k = 0; k < nfr; k++) {
            const arow *r = &R->rows[k];
            if (!R->bfr_found[k]) {
                printf("| %s | %g | %u | %.4g | > %u | | > %llu | | | < %.3f | |\n", R->name, r->rel, r->triangles,
                       r->err, max_rate, (unsigned long long)R->bfr_max_tris,
                       R->bfr_max_tris ? (double)r->triangles / R->bfr_max_tris : 0.0);
                continue;
            }
            const bfr_rate *b = &R->bfr_at[k];
            char check[32];
            if (b->mismatches == UINT64_MAX)
                snprintf(check, sizeof check, "n/a");
            else
                snprintf(check, sizeof check, "%llu", (unsigned long long)b->mismatches);
            printf("| %s | %g | %u | %.4g | %u | %.4g | %u | %.5f | %s | %.3f | %.3f |\n", R->name, r->rel,
                   r->triangles, r->err, R->bfr_rate_of[k], R->bfr_err_of[k], b->triangles, b->seconds, check,
                   (double)r->triangles / b->triangles, r->seconds / b->seconds);
        }
    }

    printf("\n### 3. Limit evaluation rate (the throughput baseline)\n\n"
           "| model | evaluator | patches | points per sweep | M points/s, positions | M points/s, with derivatives | "
           "best adaptive M vertices/s | adaptive / positions (target >= 1) |\n|---|---|---|---|---|---|---|---|\n");
    for (int p = 0; p < npaths; p++) {
        model_result *R = &res[p];
        if (!R->loaded || !R->eval.ok)
            continue;
        double best = 0;
        for (int k = 0; R->adaptive_ok && k < nfr; k++)
            best = fmax(best, R->rows[k].vertices / R->rows[k].seconds);
        printf("| %s | %s | %u | %llu | %.2f | %.2f | %.2f | %.2f |\n", R->name,
               R->is_set ? "tsr_patch_eval" : "Bfr (tsr_subd_eval)", R->patches, (unsigned long long)R->eval.points,
               R->eval.positions / 1e6, R->eval.derivatives / 1e6, best / 1e6, best / R->eval.positions);
        cJSON *jm = cJSON_GetArrayItem(jmodels, p);
        json_eval(jm, "evaluation", R->is_set ? "tsr_patch_eval" : "tsr_subd_eval", &R->eval);
        if (R->bez_eval.ok) {
            printf("| %s | Bfr (tsr_subd_eval) on its Catmull-Clark cage (table 4) | %u | %llu | %.2f | %.2f | %.2f | "
                   "%.2f |\n",
                   R->name, R->patches, (unsigned long long)R->bez_eval.points, R->bez_eval.positions / 1e6,
                   R->bez_eval.derivatives / 1e6, best / 1e6, best / R->bez_eval.positions);
            json_eval(jm, "bfr_evaluation", "tsr_subd_eval on tsr_subd_cage_from_bezier", &R->bez_eval);
        }
    }

    /* 4. the view-dependent teapot */
    printf("\n### 4. View-dependent tessellation of the teapot\n\n");
    if (!teapot)
        printf("not run: %s\n", input ? "the input is not a patch set with a working adaptive model (the comparison "
                                        "is meant for teapot.bpt)"
                                      : "no patch set with a working adaptive model");
    else {
        model *m = teapot;
        tsr_camera cams[MAX_CAMERAS];
        for (uint32_t k = 0; k < ncam; k++)
            orbit_camera(m, k, ncam, &cams[k]);
        uint32_t umax = max_rate < 256 ? max_rate : 256; /* tiles of at most 128, split once */
        uint32_t n = umax > 128 ? 64 + (umax - 128) / 4 : umax / 2;
        uni_entry *ue = calloc(n + 2, sizeof *ue);
        tsr_error err = {0};
        uni_ctx uc = {m, cams, ncam, 0, ue, &err};
        rate_search s = {n, uni_idx_rate, uni_error, uni_known, &uc};
        /* Bfr: rates 1..max_rate on the Bézier cage */
        char bnote[600] = "";
        bool bfr_ok = bez_ready(m);
        double bdev = m->bez_dev;
        snprintf(bnote, sizeof bnote, "%s", m->bez_note);
        double **berr = calloc(max_rate + 2, sizeof *berr);
        bool *bknown = calloc(max_rate + 2, 1);
        bfr_rate *btimed = calloc(max_rate + 2, sizeof *btimed);
        if (!berr || !bknown || !btimed) {
            bfr_ok = false;
            snprintf(bnote, sizeof bnote, "out of memory");
        }
        bview_ctx bc = {m, cams, ncam, 0, berr, bknown, btimed, &err};
        rate_search bs = {max_rate, bview_idx_rate, bview_error, bview_known, &bc};
        printf("%s: %u cameras on an orbit 2.5 box radii from the centre, 25 deg up, 1920 x 1080, 60 deg, "
               "pixel error 1; adaptive: tsr_ptess_run with the camera (best of %u); uniform: tsr_ptess_run with "
               "one tile of r quads per piece (rates <= 128; r/2 split once above), view-independent, at the "
               "smallest rate whose measured pixel error (same camera) is <= the adaptive one, and (the three "
               "columns after it) <= 1 px.\n\n",
               m->name, ncam, repeat);
        if (bfr_ok)
            printf("Bfr (the last five columns): OpenSubdiv's uniform tessellation of the teapot, "
                   "tsr_subd_tessellate_uniform_faces (Bfr::Tessellation at rate r per edge and Bfr's limit "
                   "evaluation, positions only, best of %u) of the %u middle faces of a Catmull-Clark cage whose "
                   "limit surface there is exactly the teapot's patches (tsr_subd_cage_from_bezier: each bicubic "
                   "Bezier patch as the uniform cubic B-spline patch of the same surface, a 4 x 4 grid of points; "
                   "Bfr's (u, v) = the patch's (s, t), checked at 7 x 7 points per patch: off by %.2g of the "
                   "diagonal), at the smallest rate in 1..%u whose measured pixel error (same camera, on an "
                   "equivalent mesh with Bfr's points and triangles as in table 2) is <= the adaptive one. "
                   "Time adaptive / Bfr is the target (< 1).\n\n",
                   repeat, m->bez_count, bdev, max_rate);
        else
            printf("Bfr columns skipped: %s.\n\n", bnote);
        printf("| camera | adaptive triangles | adaptive seconds | measured px | uniform rate | uniform triangles | "
               "uniform seconds | measured px | triangles adaptive / uniform | time adaptive / uniform | "
               "rate for <= 1 px | its triangles | its seconds | Bfr rate | Bfr triangles | Bfr seconds | "
               "measured px | time adaptive / Bfr "
               "|\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
        cJSON *jv = cJSON_AddObjectToObject(json, "view_dependent");
        cJSON_AddStringToObject(jv, "model", m->name);
        if (bfr_ok) {
            cJSON_AddNumberToObject(jv, "bfr_faces", m->bez_count);
            cJSON_AddNumberToObject(jv, "bfr_cage_deviation", bdev);
        } else
            cJSON_AddStringToObject(jv, "bfr_note", bnote);
        cJSON *jc = cJSON_AddArrayToObject(jv, "cameras");
        double sum_a = 0, sum_u = 0, sum_ut = 0, sum_ratio = 0;
        double sum_ab = 0, sum_b = 0, sum_bratio = 0;
        uint32_t counted = 0, counted_b = 0;
        for (uint32_t k = 0; k < ncam && ue; k++) {
            arow a = {0};
            tsr_ptess_options o = {0};
            o.camera = &cams[k];
            o.tile_n = tile;
            if (run_measured(m, &o, repeat, &cams[k], &a, &err) != TSR_OK) {
                cli_error("bench", "patch: %s: view-dependent tessellation: %s", m->name, err.message);
                rc = CLI_FAIL;
                break;
            }
            if (a.uncovered) {
                cli_error("bench", "patch: %s: camera %u: %llu measured samples lie in no triangle (gaps)", m->name, k,
                          (unsigned long long)a.uncovered);
                rc = CLI_FAIL;
            }
            uc.cam = k;
            bool failed = false;
            uint32_t idx = find_rate(&s, fmax(a.err, PIXEL_ERROR_FLOOR), &failed),
                     idx1 = failed ? 0 : find_rate(&s, cams[k].pixel_error, &failed);
            if (failed) {
                cli_error("bench", "patch: %s: uniform tessellation: %s", m->name, err.message);
                rc = CLI_FAIL;
                break;
            }
            if (idx && !uni_time(&uc, idx, repeat))
                idx = 0;
            if (idx1 && !uni_time(&uc, idx1, repeat))
                idx1 = 0;
            /* Bfr at the smallest rate reaching the adaptive error */
            uint32_t bidx = 0;
            char bcols[256] = "n/a | | | | ";
            if (bfr_ok) {
                bc.cam = k;
                bidx = find_rate(&bs, fmax(a.err, PIXEL_ERROR_FLOOR), &failed);
                if (failed) {
                    cli_error("bench", "patch: %s: Bfr's equivalent mesh: %s", m->name, err.message);
                    rc = CLI_FAIL;
                    bfr_ok = false;
                    bidx = 0;
                } else if (bidx && !btimed[bidx].timed && bfr_time(m, bidx, repeat, &btimed[bidx], &err) != TSR_OK) {
                    cli_error("bench", "patch: %s: Bfr: %s", m->name, err.message);
                    rc = CLI_FAIL;
                    bidx = 0;
                } else if (bidx && btimed[bidx].mismatches && btimed[bidx].mismatches != UINT64_MAX &&
                           !btimed[bidx].warned) {
                    fprintf(stderr,
                            "tessera bench patch: %s: warning: at Bfr rate %u, %llu triangles of Bfr's mesh differ "
                            "from the equivalent mesh whose error is measured\n",
                            m->name, bidx, (unsigned long long)btimed[bidx].mismatches);
                    btimed[bidx].warned = true;
                }
                if (bidx) {
                    const bfr_rate *b = &btimed[bidx];
                    snprintf(bcols, sizeof bcols, "%u | %u | %.5f | %.3f | %.3f ", bidx, b->triangles, b->seconds,
                             berr[bidx][k], a.seconds / b->seconds);
                } else if (bfr_ok)
                    snprintf(bcols, sizeof bcols, "> %u | | | | ", max_rate);
            }
            cJSON *jk = json_arow(&a);
            cJSON_AddItemToArray(jc, jk);
            if (bidx) {
                const bfr_rate *b = &btimed[bidx];
                cJSON *jb = cJSON_AddObjectToObject(jk, "bfr_uniform");
                cJSON_AddNumberToObject(jb, "rate", bidx);
                cJSON_AddNumberToObject(jb, "triangles", b->triangles);
                cJSON_AddNumberToObject(jb, "vertices", b->vertices);
                cJSON_AddNumberToObject(jb, "seconds", b->seconds);
                cJSON_AddNumberToObject(jb, "measured_max_error", berr[bidx][k]);
                cJSON_AddNumberToObject(jb, "triangle_ratio", (double)a.triangles / b->triangles);
                cJSON_AddNumberToObject(jb, "time_ratio", a.seconds / b->seconds);
                if (b->mismatches != UINT64_MAX)
                    cJSON_AddNumberToObject(jb, "pattern_mismatches", (double)b->mismatches);
                sum_ab += a.seconds;
                sum_b += b->seconds;
                sum_bratio += a.seconds / b->seconds;
                counted_b++;
            }
            char r1[64] = "> max", s1[64] = "";
            if (idx1) {
                snprintf(r1, sizeof r1, "%u", uni_idx_rate(idx1, NULL));
                snprintf(s1, sizeof s1, "%u | %.5f", ue[idx1].triangles, ue[idx1].seconds);
            } else
                snprintf(s1, sizeof s1, " | ");
            if (!idx) {
                printf("| %u | %u | %.5f | %.3f | > %u | | | | | | %s | %s | %s|\n", k, a.triangles, a.seconds, a.err,
                       uni_idx_rate(n, NULL), r1, s1, bcols);
                continue;
            }
            const uni_entry *u = &ue[idx];
            printf("| %u | %u | %.5f | %.3f | %u | %u | %.5f | %.3f | %.3f | %.3f | %s | %s | %s|\n", k, a.triangles,
                   a.seconds, a.err, uni_idx_rate(idx, NULL), u->triangles, u->seconds, u->err[k],
                   (double)a.triangles / u->triangles, a.seconds / u->seconds, r1, s1, bcols);
            cJSON *ju = cJSON_AddObjectToObject(jk, "uniform");
            cJSON_AddNumberToObject(ju, "rate", uni_idx_rate(idx, NULL));
            cJSON_AddNumberToObject(ju, "triangles", u->triangles);
            cJSON_AddNumberToObject(ju, "seconds", u->seconds);
            cJSON_AddNumberToObject(ju, "measured_max_error", u->err[k]);
            if (idx1) {
                cJSON_AddNumberToObject(jk, "uniform_rate_1px", uni_idx_rate(idx1, NULL));
                cJSON_AddNumberToObject(jk, "uniform_seconds_1px", ue[idx1].seconds);
                cJSON_AddNumberToObject(jk, "uniform_triangles_1px", ue[idx1].triangles);
            }
            sum_a += a.seconds;
            sum_u += u->seconds;
            sum_ratio += a.seconds / u->seconds;
            sum_ut += (double)a.triangles / u->triangles;
            counted++;
        }
        if (counted || counted_b) {
            /* the stand-in's means over its cameras, Bfr's over its own (the same unless a search failed) */
            char ucols[200] = "| | | | | | | | | | | |", bmean[200] = "| | | | |";
            if (counted)
                snprintf(ucols, sizeof ucols, "| %.5f | | | | %.5f | | %.3f | %.3f (ratio of means %.3f) | | | |",
                         sum_a / counted, sum_u / counted, sum_ut / counted, sum_ratio / counted, sum_a / sum_u);
            if (counted_b) {
                char own[64] = "";
                if (counted_b != counted)
                    snprintf(own, sizeof own, "(of %u cameras; adaptive %.5f s)", counted_b, sum_ab / counted_b);
                snprintf(bmean, sizeof bmean, " %s | | %.5f | | %.3f (ratio of means %.3f) |", own, sum_b / counted_b,
                         sum_bratio / counted_b, sum_ab / sum_b);
            }
            printf("| mean of %u | %s%s\n", counted ? counted : counted_b, ucols, bmean);
            if (counted) {
                cJSON_AddNumberToObject(jv, "mean_adaptive_seconds", sum_a / counted);
                cJSON_AddNumberToObject(jv, "mean_uniform_seconds", sum_u / counted);
                cJSON_AddNumberToObject(jv, "mean_time_ratio", sum_ratio / counted);
            }
            if (counted_b) {
                cJSON_AddNumberToObject(jv, "bfr_cameras", counted_b);
                cJSON_AddNumberToObject(jv, "mean_adaptive_seconds_bfr_cameras", sum_ab / counted_b);
                cJSON_AddNumberToObject(jv, "mean_bfr_seconds", sum_b / counted_b);
                cJSON_AddNumberToObject(jv, "mean_time_ratio_bfr", sum_bratio / counted_b);
                cJSON_AddNumberToObject(jv, "time_ratio_of_means_bfr", sum_ab / sum_b);
            }
        }
        for (uint32_t i = 0; ue && i <= n + 1; i++)
            free(ue[i].err);
        free(ue);
        for (uint32_t i = 0; berr && i <= max_rate + 1; i++)
            free(berr[i]);
        free(berr);
        free(bknown);
        free(btimed);
        model_free(m);
        free(m);
    }
    if (json_path) {
        char *txt = cJSON_Print(json);
        tsr_error err = {0};
        if (!txt || cli_write_text(json_path, txt, &err) != TSR_OK) {
            cli_error("bench", "patch: %s", txt ? err.message : "out of memory");
            rc = CLI_FAIL;
        }
        free(txt);
    }
    cJSON_Delete(json);
    free(res);
    return rc;
}
