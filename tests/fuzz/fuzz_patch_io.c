/* fuzz_patch_io.c: the readers of patches/patch_io.c: .bpt Bézier patch
 * files, OBJ free-form surfaces with trim loops, and polygon OBJ cages
 * with OpenSubdiv tags.
 *
 * Input: byte 0 picks the reader, (b & 3) % 3: 0 .bpt, 1 OBJ free-form,
 * 2 cage ('0', '1', '2' as ASCII); bit 2 ('4', '5', '6') reads through a
 * temporary file (tsr_*_load) instead of from memory (tsr_*_parse). The
 * rest is the file.
 *
 * Checked: no single allocation above 1 MiB + 64 bytes per input byte
 * (a surf may reference one 4-double vertex with every 2-byte index);
 * a failure returns a status with its message, which names the file, and
 * leaves the output zeroed; a patch set has at least one patch, every
 * patch passes tsr_patch_check and evaluates at a 3x3 grid of its domain
 * to finite positions and derivatives and a unit normal, inside
 * tsr_patch_bounds; small patches convert to Bézier pieces with finite
 * control points and positive weights; loop and segment indices are in
 * range, every curve passes tsr_curve2_check, segment parameters lie in
 * their curve's range, and each loop samples to finite points (loops
 * up to 100000 curve points in all, at a tolerance of 1/100 of their
 * curves' extent); a cage
 * has faces of 3 or more vertices whose sizes add up, indices in range,
 * finite non-negative sharpness and its enums in range. A patch set also
 * builds its tessellation model (pieces cut at shared breakpoints, edges
 * linked): success with a piece per patch at least, or a failure with its
 * message. */
#include "fuzz.h"
#include "patches/patches.h"
#include "patches/ptess.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void check_failure(tsr_status s, const tsr_error *err, const char *name, const char *what)
{
    if (s >= TSR_STATUS_COUNT || err->status != s || !err->message[0])
        fuzz_fail("patch_io: %s: failure %d without its message", what, (int)s);
    if (strncmp(err->message, name, strlen(name)) != 0)
        fuzz_fail("patch_io: %s: message '%s' does not name %s", what, err->message, name);
}

static bool finite3(const double *x)
{
    return isfinite(x[0]) && isfinite(x[1]) && isfinite(x[2]);
}

static void check_patch(const tsr_patch *p, uint32_t i)
{
    tsr_error e = {0};
    if (tsr_patch_check(p, &e) != TSR_OK)
        fuzz_fail("patch_io: patch %u fails its check: %s", i, e.message);
    double dom[4], lo[3], hi[3];
    if (tsr_patch_domain(p, dom) != TSR_OK || tsr_patch_bounds(p, lo, hi) != TSR_OK)
        fuzz_fail("patch_io: patch %u: no domain or bounds", i);
    for (int k = 0; k < 9; k++) {
        double u = dom[0] + (dom[1] - dom[0]) * (k % 3) / 2, v = dom[2] + (dom[3] - dom[2]) * (k / 3) / 2;
        double pos[3], du[3], dv[3], n[3];
        if (tsr_patch_eval(p, u, v, pos, du, dv, n) != TSR_OK)
            fuzz_fail("patch_io: patch %u refuses evaluation at (%g, %g)", i, u, v);
        if (!finite3(pos) || !finite3(du) || !finite3(dv) || !finite3(n))
            fuzz_fail("patch_io: patch %u: non-finite evaluation at (%g, %g)", i, u, v);
        if (fabs(sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1) > 1e-9)
            fuzz_fail("patch_io: patch %u: normal of length %g at (%g, %g)", i,
                      sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), u, v);
        for (int c = 0; c < 3; c++) {
            double slack = 1e-9 * (fabs(lo[c]) + fabs(hi[c])) + 1e-300;
            if (pos[c] < lo[c] - slack || pos[c] > hi[c] + slack)
                fuzz_fail("patch_io: patch %u: point %g outside its bounds [%g, %g] at (%g, %g)", i, pos[c], lo[c],
                          hi[c], u, v);
        }
    }
    uint32_t count = 0;
    if (tsr_patch_to_bezier(p, NULL, 0, NULL, NULL, &count) != TSR_OK || count == 0)
        fuzz_fail("patch_io: patch %u: no Bézier pieces", i);
    if (count <= 16) {
        size_t N = (size_t)(p->degree_u + 1) * (size_t)(p->degree_v + 1);
        tsr_patch pieces[16];
        double *ctrl = malloc(3 * N * count * sizeof(double)), *w = malloc(N * count * sizeof(double));
        if (!ctrl || !w)
            abort();
        if (tsr_patch_to_bezier(p, pieces, 16, ctrl, w, &count) != TSR_OK)
            fuzz_fail("patch_io: patch %u: Bézier conversion failed", i);
        for (size_t k = 0; k < N * count; k++)
            if (!finite3(ctrl + 3 * k) || (p->weights && !(w[k] > 0 && isfinite(w[k]))))
                fuzz_fail("patch_io: patch %u: Bézier piece point %zu is not finite", i, k);
        free(ctrl);
        free(w);
    }
}

static void check_set(const tsr_patch_set *s)
{
    if (s->num_patches == 0 || !s->patches || !s->first_loop)
        fuzz_fail("patch_io: success with no patch");
    if (s->first_loop[0] != 0 || s->first_loop[s->num_patches] != s->num_loops)
        fuzz_fail("patch_io: first_loop does not span the loops");
    for (uint32_t i = 0; i < s->num_patches; i++) {
        if (s->first_loop[i] > s->first_loop[i + 1])
            fuzz_fail("patch_io: first_loop decreases at %u", i);
        for (uint32_t l = s->first_loop[i]; l < s->first_loop[i + 1]; l++)
            if (s->loops[l].patch != i)
                fuzz_fail("patch_io: loop %u is listed under patch %u but names %u", l, i, s->loops[l].patch);
        check_patch(&s->patches[i], i);
    }
    for (uint32_t c = 0; c < s->num_curves; c++) {
        tsr_error e = {0};
        if (tsr_curve2_check(&s->curves[c], &e) != TSR_OK)
            fuzz_fail("patch_io: curve %u fails its check: %s", c, e.message);
    }
    for (uint32_t g = 0; g < s->num_segments; g++) {
        const tsr_trim_segment *t = &s->segments[g];
        if (t->curve >= s->num_curves)
            fuzz_fail("patch_io: segment %u names curve %u of %u", g, t->curve, s->num_curves);
        const tsr_curve2 *c = &s->curves[t->curve];
        double lo = c->knots[c->degree], hi = c->knots[c->count];
        if (!(t->t0 >= lo && t->t0 <= hi && t->t1 >= lo && t->t1 <= hi))
            fuzz_fail("patch_io: segment %u runs [%g, %g] outside its curve's [%g, %g]", g, t->t0, t->t1, lo, hi);
    }
    /* sampling costs at least one step per span of every segment: stop
     * once the loops read so far reach 100000 control points in all (a few
     * bytes of trim statements may name one long curve many times) */
    uint64_t work = 0;
    for (uint32_t l = 0; l < s->num_loops && work < 100000; l++) {
        const tsr_trim_loop *L = &s->loops[l];
        if (L->num_segments == 0 || (uint64_t)L->first_segment + L->num_segments > s->num_segments)
            fuzz_fail("patch_io: loop %u has segments %u + %u of %u", l, L->first_segment, L->num_segments,
                      s->num_segments);
        /* a tolerance of 1/100 of the extent of the loop's curves: few points */
        double ext = 0;
        for (uint32_t g = 0; g < L->num_segments; g++) {
            const tsr_curve2 *c = &s->curves[s->segments[L->first_segment + g].curve];
            for (uint32_t k = 0; k < 2 * c->count; k++)
                ext = fmax(ext, fabs(c->ctrl[k]));
            work += c->count;
        }
        double tol = 1e-2 * ext + 1e-300;
        uint32_t n = 0;
        if (tsr_trim_loop_sample(s, l, tol, NULL, 0, &n) != TSR_OK || n == 0)
            fuzz_fail("patch_io: loop %u does not sample", l);
        if (n > 1000000)
            continue;
        double *uv = malloc(2 * sizeof(double) * n);
        uint32_t n2 = 0;
        if (!uv)
            abort();
        if (tsr_trim_loop_sample(s, l, tol, uv, n, &n2) != TSR_OK || n2 != n)
            fuzz_fail("patch_io: loop %u samples to %u points, then %u", l, n, n2);
        for (uint32_t k = 0; k < 2 * n; k++)
            if (!isfinite(uv[k]))
                fuzz_fail("patch_io: loop %u: sample %u is not finite", l, k / 2);
        free(uv);
        /* its shape's figures: finite, the area within the domain's */
        tsr_trim_loop_info in;
        if (n > 20000 || tsr_trim_loop_check(s, l, tol, NULL, &in) != TSR_OK)
            continue;
        bool area_ok = in.crosses || in.area <= in.domain_area * (1 + 1e-9) + 1e-300;
        if (!(in.gap >= 0) || !isfinite(in.gap) || !area_ok)
            fuzz_fail("patch_io: loop %u: gap %g, area %g of the domain's %g", l, in.gap, in.area, in.domain_area);
    }
}

static void check_cage(const tsr_cage *c)
{
    if (c->num_faces == 0 || c->num_points == 0)
        fuzz_fail("patch_io: cage with %u faces, %u points", c->num_faces, c->num_points);
    uint64_t sum = 0;
    for (uint32_t f = 0; f < c->num_faces; f++) {
        if (c->face_sizes[f] < 3)
            fuzz_fail("patch_io: cage face %u has %u vertices", f, c->face_sizes[f]);
        sum += c->face_sizes[f];
    }
    if (sum != c->num_face_verts)
        fuzz_fail("patch_io: face sizes add up to %llu, not %u", (unsigned long long)sum, c->num_face_verts);
    for (uint32_t i = 0; i < c->num_face_verts; i++)
        if (c->face_verts[i] >= c->num_points || (c->face_uvs && c->face_uvs[i] >= c->num_uvs))
            fuzz_fail("patch_io: face corner %u out of range", i);
    for (size_t i = 0; i < 3 * (size_t)c->num_points; i++)
        if (!isfinite(c->points[i]))
            fuzz_fail("patch_io: cage point %zu not finite", i / 3);
    for (uint32_t i = 0; i < c->num_creases; i++)
        if (c->crease_verts[2 * i] >= c->num_points || c->crease_verts[2 * i + 1] >= c->num_points ||
            !(c->crease_sharpness[i] >= 0) || !isfinite(c->crease_sharpness[i]))
            fuzz_fail("patch_io: crease %u invalid", i);
    for (uint32_t i = 0; i < c->num_corners; i++)
        if (c->corner_verts[i] >= c->num_points || !(c->corner_sharpness[i] >= 0) || !isfinite(c->corner_sharpness[i]))
            fuzz_fail("patch_io: corner %u invalid", i);
    for (uint32_t i = 0; i < c->num_holes; i++)
        if (c->hole_faces[i] >= c->num_faces)
            fuzz_fail("patch_io: hole %u names face %u of %u", i, c->hole_faces[i], c->num_faces);
    if (c->boundary_interp < 0 || c->boundary_interp > 2 || c->fvar_interp < 0 || c->fvar_interp > 5 ||
        c->crease_method < 0 || c->crease_method > 1 || c->triangle_subdiv < 0 || c->triangle_subdiv > 1)
        fuzz_fail("patch_io: cage options out of range");
}

int fuzz_patch_io(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    int reader = (data[0] & 3) % 3;
    bool file = data[0] & 4;
    const uint8_t *body = data + 1;
    size_t n = size - 1;
    size_t limit = ((size_t)1 << 20) + 64 * size;
    tsr_allocator alloc;
    fuzz_limited_allocator(&alloc, &limit);
    tsr_error err = {0};
    const char *name = reader == 0 ? "in.bpt" : "in.obj";
    if (file)
        name = fuzz_write_temp(name, body, n);
    char shown_name[4096];
    snprintf(shown_name, sizeof shown_name, "%s", name);
    if (reader == 2) {
        tsr_cage c;
        tsr_status s =
            file ? tsr_cage_load(shown_name, &alloc, &c, &err) : tsr_cage_parse(body, n, shown_name, &alloc, &c, &err);
        if (s == TSR_OK) {
            check_cage(&c);
        } else {
            check_failure(s, &err, shown_name, "cage");
            if (c.num_faces || c.face_sizes || c.points)
                fuzz_fail("patch_io: a failed cage load left data");
        }
        tsr_cage_free(&c);
        return 0;
    }
    tsr_patch_format f = reader == 0 ? TSR_PATCH_FORMAT_BPT : TSR_PATCH_FORMAT_OBJ;
    tsr_patch_set set;
    tsr_status s = file ? tsr_patch_set_load(shown_name, f, &alloc, &set, &err)
                        : tsr_patch_set_parse(body, n, shown_name, f, &alloc, &set, &err);
    if (s == TSR_OK) {
        check_set(&set);
        tsr_pmodel *m = NULL;
        tsr_error merr = {0};
        tsr_status ms = tsr_pmodel_from_set(&set, &alloc, &m, &merr);
        if (ms == TSR_OK) {
            tsr_pmodel_info info;
            tsr_pmodel_get_info(m, &info);
            if (info.sources != set.num_patches || info.pieces < info.sources)
                fuzz_fail("patch_io: model of %u patches has %u sources, %u pieces", set.num_patches, info.sources,
                          info.pieces);
        } else if (ms >= TSR_STATUS_COUNT || merr.status != ms || !merr.message[0] || m) {
            fuzz_fail("patch_io: model failure %d without its message", (int)ms);
        }
        tsr_pmodel_destroy(m);
    } else {
        check_failure(s, &err, shown_name, reader == 0 ? "bpt" : "obj");
        if (set.num_patches || set.patches || set.values)
            fuzz_fail("patch_io: a failed load left data");
    }
    tsr_patch_set_free(&set);
    return 0;
}

#ifdef TSR_LIBFUZZER
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_patch_io(data, size);
}
#endif
