/* patch_cli.c: see patch_cli.h. */
#include "patch_cli.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void report_load_error(const char *cmd, const char *in, tsr_status st, const tsr_error *err)
{
    if (err->message[0] && strstr(err->message, in))
        cli_error(cmd, "%s", err->message);
    else
        cli_error(cmd, "%s: %s", in, err->message[0] ? err->message : tsr_status_str(st));
}

bool cli_patch_model_load(const char *cmd, const char *path, const char *scheme, cli_patch_model *out)
{
    return cli_patch_model_load_weld(cmd, path, scheme, 0, false, out);
}

bool cli_patch_model_load_weld(const char *cmd, const char *path, const char *scheme, double weld, bool orient,
                               cli_patch_model *out)
{
    memset(out, 0, sizeof *out);
    tsr_error err = {0};
    tsr_patch_format f = tsr_patch_format_from_path(path);
    if (f == TSR_PATCH_FORMAT_UNKNOWN) {
        cli_error(cmd, "%s: unknown patch format (use .bpt, or .obj with free-form surfaces or a polygon cage)", path);
        return false;
    }
    tsr_status st = tsr_patch_set_load(path, f, NULL, &out->set, &err);
    if (st == TSR_OK) {
        out->kind = f == TSR_PATCH_FORMAT_BPT ? "bpt" : "obj-surfaces";
        st = tsr_pmodel_from_set_tol(&out->set, weld, NULL, &out->model, &err);
    } else if (st == TSR_ERR_EMPTY && f == TSR_PATCH_FORMAT_OBJ) {
        /* no free-form surface: a polygon cage, if it has faces */
        tsr_error cerr = {0};
        tsr_status cst = tsr_cage_load(path, NULL, &out->cage, &cerr);
        if (cst != TSR_OK) {
            if (cst == TSR_ERR_EMPTY)
                report_load_error(cmd, path, st, &err); /* neither surfaces nor faces: the set loader's word */
            else
                report_load_error(cmd, path, cst, &cerr);
            cli_patch_model_free(out);
            return false;
        }
        /* faces listed against their neighbours' order make their shared
         * edges seams OpenSubdiv leaves open: reversed when asked */
        out->cage_oriented = orient;
        if (tsr_cage_orient(&out->cage, orient, &out->cage_reversed, &out->cage_first_reversed,
                            &out->cage_unorientable) != TSR_OK) {
            cli_error(cmd, "%s: out of memory", path);
            cli_patch_model_free(out);
            return false;
        }
        const char *base = strrchr(path, '/');
        base = base ? base + 1 : path;
        bool bilinear = scheme ? !strcmp(scheme, "bilinear") : !strncmp(base, "bilinear", 8);
        out->kind = bilinear ? "cage-bilinear" : "cage-catmark";
        out->is_subd = true;
        st = tsr_subd_create(&out->cage, bilinear ? TSR_SUBD_BILINEAR : TSR_SUBD_CATMARK, NULL, &out->subd, &err);
        if (st == TSR_OK)
            st = tsr_pmodel_from_subd(out->subd, NULL, &out->model, &err);
    }
    if (st != TSR_OK) {
        report_load_error(cmd, path, st, &err);
        cli_patch_model_free(out);
        return false;
    }
    tsr_pmodel_info info;
    tsr_pmodel_get_info(out->model, &info);
    double d = 0;
    for (int c = 0; c < 3; c++)
        d += (info.hi[c] - info.lo[c]) * (info.hi[c] - info.lo[c]);
    out->diag = sqrt(d);
    /* a weld as wide as half the model joins its patches' own edges: they
     * collapse, and what is left to measure makes no sense; patches that
     * small beside a reasonable weld (a CAD file's sliver fillet) are
     * warned of */
    if (weld > 0 && !out->is_subd && weld >= 0.5 * out->diag) {
        cli_error(cmd,
                  "%s: --weld %g is half the model's size or more (its box has a diagonal of %g): patches' "
                  "own edges would be welded together; give less (the default is 1e-6 of the diagonal, %g)",
                  path, weld, out->diag, 1e-6 * out->diag);
        cli_patch_model_free(out);
        return false;
    }
    uint32_t small = 0, first_small = 0;
    for (uint32_t i = 0; weld > 0 && !out->is_subd && i < out->set.num_patches; i++) {
        double lo[3], hi[3], pd = 0;
        if (tsr_patch_bounds(&out->set.patches[i], lo, hi) != TSR_OK)
            continue;
        for (int c = 0; c < 3; c++)
            pd += (hi[c] - lo[c]) * (hi[c] - lo[c]);
        if (sqrt(pd) > 0 && weld >= 0.5 * sqrt(pd) && small++ == 0)
            first_small = i;
    }
    if (small)
        fprintf(stderr,
                "tessera %s: %s: warning: %u patch%s no more than twice --weld %g across (the first: patch %u): "
                "their own edges may be welded together\n",
                cmd, path, small, small == 1 ? " is" : "es are", weld, first_small + 1);
    return true;
}

bool cli_patch_model_split(const char *cmd, const char *path, cli_patch_model *pm, double weld, double max_error,
                           uint32_t tile)
{
    if (pm->is_subd)
        return true;
    tsr_pmodel_set_options o = {weld, max_error, tile};
    tsr_pmodel *m = NULL;
    tsr_error err = {0};
    tsr_status st = tsr_pmodel_from_set_opts(&pm->set, &o, NULL, &m, &err);
    if (st != TSR_OK) {
        report_load_error(cmd, path, st, &err);
        return false;
    }
    tsr_pmodel_destroy(pm->model);
    pm->model = m;
    return true;
}

double cli_patch_float_floor(const tsr_pmodel *m, double *maxabs, double *step)
{
    tsr_pmodel_info info;
    tsr_pmodel_get_info(m, &info);
    double mx = 0;
    for (int k = 0; k < 3; k++)
        mx = fmax(mx, fmax(fabs(info.lo[k]), fabs(info.hi[k])));
    float f = (float)mx;
    double st = (double)nextafterf(f, INFINITY) - (double)f;
    if (maxabs)
        *maxabs = mx;
    if (step)
        *step = st;
    return 4 * st;
}

void cli_patch_model_free(cli_patch_model *m)
{
    tsr_pmodel_destroy(m->model);
    tsr_subd_destroy(m->subd);
    tsr_cage_free(&m->cage);
    tsr_patch_set_free(&m->set);
    memset(m, 0, sizeof *m);
}

tsr_status cli_patch_tessellate(const tsr_pmodel *m, const tsr_ptess_options *opt_in, uint32_t per_side, uint32_t rounds,
                                tsr_ptess_result *r, tsr_ptess_measure_result *meas, uint32_t *tightened,
                                cli_progress *progress, tsr_error *err)
{
    tsr_pmodel_info info;
    tsr_pmodel_get_info(m, &info);
    tsr_ptess_options opt = *opt_in;
    double *scale = NULL;
    double tol = opt.camera ? opt.camera->pixel_error : opt.max_error;
    *tightened = 0;
    memset(meas, 0, sizeof *meas);
    memset(r, 0, sizeof *r);
    tsr_status st = TSR_OK;
    double prev = INFINITY;
    for (uint32_t round = 0;; round++) {
        tsr_ptess_result_free(r);
        st = tsr_ptess_run(m, &opt, NULL, r, err);
        if (st != TSR_OK)
            break;
        tsr_free(NULL, meas->source_error);
        st = tsr_ptess_measure_progress(m, r, per_side, opt.camera, true, NULL, progress ? cli_progress_cb : NULL,
                                        progress, meas);
        if (progress)
            cli_progress_end(progress);
        if (st != TSR_OK) {
            tsr_error_set(err, st, "measuring the tessellation: %s", tsr_status_str(st));
            break;
        }
        /* stop when done, out of rounds, or when tightening stopped paying
         * (the error hardly moved: more rounds would only grow the mesh) */
        if (meas->max_error <= tol || round == rounds || (round > 0 && meas->max_error > 0.9 * prev))
            break;
        prev = meas->max_error;
        if (!scale) {
            scale = malloc((size_t)info.pieces * sizeof *scale);
            if (!scale) {
                st = tsr_error_set(err, TSR_ERR_NOMEM, "out of memory");
                break;
            }
            for (uint32_t p = 0; p < info.pieces; p++)
                scale[p] = 1;
            opt.piece_scale = scale;
        }
        for (uint32_t s = 0; s < info.sources; s++) {
            if (!(meas->source_error[s] > tol))
                continue;
            tsr_psource_info si;
            tsr_pmodel_source_info(m, s, &si);
            for (uint32_t k = 0; k < si.pieces_u * si.pieces_v; k++) {
                double f = scale[si.first_piece + k] * 0.5 * fmax(0.1, fmin(1.0, tol / meas->source_error[s]));
                scale[si.first_piece + k] = f > 0 ? f : 1e-6;
            }
        }
    }
    /* the patches tightened, each once whatever the rounds */
    for (uint32_t s = 0; scale && s < info.sources; s++) {
        tsr_psource_info si;
        tsr_pmodel_source_info(m, s, &si);
        *tightened += si.pieces_u > 0 && si.pieces_v > 0 && scale[si.first_piece] < 1;
    }
    tsr_free(NULL, meas->source_error);
    meas->source_error = NULL;
    free(scale);
    return st;
}

/* Whether the n points pts (x, y, z) lie on one line (or at one point),
 * within 1e-12 of their extent; *point says which. */
static bool points_on_a_line(const double *pts, uint32_t n, bool *point)
{
    const double *a = pts, *b = pts;
    double far = 0;
    for (uint32_t i = 1; i < n; i++) {
        const double *p = pts + 3 * i;
        double d = hypot(hypot(p[0] - a[0], p[1] - a[1]), p[2] - a[2]);
        if (d > far) {
            far = d;
            b = p;
        }
    }
    *point = far == 0;
    if (*point)
        return true;
    double u[3] = {(b[0] - a[0]) / far, (b[1] - a[1]) / far, (b[2] - a[2]) / far};
    for (uint32_t i = 1; i < n; i++) {
        const double *p = pts + 3 * i;
        double w[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
        double c[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        if (hypot(hypot(c[0], c[1]), c[2]) > 1e-12 * far)
            return false;
    }
    return true;
}

uint32_t cli_patch_flat_warnings(const char *cmd, const char *path, const cli_patch_model *pm, uint32_t max)
{
    if (pm->is_subd)
        return 0;
    uint32_t flat = 0;
    for (uint32_t i = 0; i < pm->set.num_patches; i++) {
        const tsr_patch *p = &pm->set.patches[i];
        bool point;
        if (!points_on_a_line(p->ctrl, p->count_u * p->count_v, &point))
            continue;
        if (flat++ < max)
            fprintf(stderr, "tessera %s: %s: warning: patch %u has no area (its control points lie %s): its "
                    "triangles have zero area\n", cmd, path, i + 1, point ? "at one point" : "on one line");
    }
    if (flat > max && max > 0)
        fprintf(stderr, "tessera %s: %s: warning: %u more patches with no area\n", cmd, path, flat - max);
    return flat;
}

uint32_t cli_patch_trim_warnings(const char *cmd, const char *path, const cli_patch_model *pm, uint32_t max)
{
    if (pm->is_subd)
        return 0;
    const tsr_patch_set *s = &pm->set;
    uint32_t warned = 0;
    for (uint32_t l = 0; l < s->num_loops; l++) {
        const tsr_trim_loop *L = &s->loops[l];
        double dom[4];
        if (tsr_patch_domain(&s->patches[L->patch], dom) != TSR_OK)
            continue;
        double ext = fmax(dom[1] - dom[0], dom[3] - dom[2]);
        tsr_trim_loop_info in;
        if (tsr_trim_loop_check(s, l, 1e-6 * ext, NULL, &in) != TSR_OK)
            continue;
        const char *what = L->hole ? "hole" : "trim";
        char msg[4][256];
        int nm = 0;
        if (L->reordered)
            snprintf(msg[nm++], sizeof msg[0],
                     "lists its curves out of order or backwards: they were joined end to start");
        /* the first place where a segment does not go on where the one
         * before it ended */
        double prev[2] = {0, 0}, worst = 0;
        uint32_t at = 0;
        for (uint32_t k = 0; k < L->num_segments; k++) {
            const tsr_trim_segment *g = &s->segments[L->first_segment + k];
            double a[2], z[2];
            if (tsr_curve2_eval(&s->curves[g->curve], g->t0, a, NULL) != TSR_OK ||
                tsr_curve2_eval(&s->curves[g->curve], g->t1, z, NULL) != TSR_OK)
                break;
            double d = k ? hypot(a[0] - prev[0], a[1] - prev[1]) : 0;
            if (d > 1e-6 * ext && !at) {
                worst = d;
                at = k;
            }
            prev[0] = z[0], prev[1] = z[1];
        }
        if (at && !L->reordered) /* (reordered: chained within its own tolerance) */
            snprintf(msg[nm++], sizeof msg[0],
                     "has a gap between its curves #%u and #%u (of %u, as listed; %.3g apart in (u, v)): joined by a "
                     "straight edge",
                     at, at + 1, L->num_segments, worst);
        if (in.gap > 0)
            snprintf(msg[nm++], sizeof msg[0], "is open (ends %.3g apart in (u, v)): closed by a straight edge",
                     in.gap);
        if (in.crosses)
            snprintf(msg[nm++], sizeof msg[0],
                     "crosses itself near (u, v) = (%.6g, %.6g): its inside is what an odd number of its edges "
                     "surround",
                     in.cross_uv[0], in.cross_uv[1]);
        else if (!(in.area > 1e-12 * in.domain_area))
            snprintf(msg[nm++], sizeof msg[0], "encloses none of the patch's domain [%g, %g] x [%g, %g]: %s",
                     dom[0], dom[1], dom[2], dom[3], L->hole ? "it removes nothing" : "the patch keeps nothing");
        if (!nm)
            continue;
        if (warned < max)
            for (int k = 0; k < nm; k++)
                fprintf(stderr, "tessera %s: %s:%u: warning: the %s loop of patch %u %s\n", cmd, path, L->line, what,
                        L->patch + 1, msg[k]);
        warned++;
    }
    if (warned > max)
        fprintf(stderr, "tessera %s: %s: warning: %u more trim loops as above\n", cmd, path, warned - max);
    return warned;
}

void cli_patch_model_notes(const char *cmd, const char *path, const cli_patch_model *pm)
{
    uint32_t n = pm->cage_reversed;
    if (n && pm->cage_oriented)
        fprintf(stderr,
                "tessera %s: %s: note: %u cage face%s listed against %s neighbours' order; reversed (--orient-faces), "
                "so the edges %s are joined\n",
                cmd, path, n, n == 1 ? "" : "s", n == 1 ? "its" : "their", n == 1 ? "it shares" : "they share");
    else if (n)
        fprintf(stderr,
                "tessera %s: %s: warning: %u cage face%s (the first: face %u) listed against %s neighbours' order: "
                "OpenSubdiv leaves the edges %s open, and the mesh has cracks there; --orient-faces reverses "
                "%s\n",
                cmd, path, n, n == 1 ? "" : "s", pm->cage_first_reversed + 1, n == 1 ? "its" : "their",
                n == 1 ? "it shares" : "they share", n == 1 ? "it" : "them");
    if (pm->cage_unorientable)
        fprintf(stderr,
                "tessera %s: %s: warning: %u part%s of the cage cannot be oriented (a Moebius band): the edges where "
                "faces disagree are left open\n",
                cmd, path, pm->cage_unorientable, pm->cage_unorientable == 1 ? "" : "s");
    if (pm->is_subd)
        return;
    const tsr_patch_set *s = &pm->set;
    if (s->num_unknown)
        fprintf(stderr,
                "tessera %s: %s:%u: warning: '%s' is no OBJ statement; ignored%s (a misspelling drops what it "
                "meant: a hole, a trim)\n",
                cmd, path, s->first_unknown_line, s->first_unknown,
                s->num_unknown > 1 ? ", as are the other unknown statements after it" : "");
    if (s->num_unused_freeform)
        fprintf(stderr,
                "tessera %s: %s: note: %u free-form statement%s tessera does not use (3D curves curv, special curves "
                "scrv and points sp, connectivity con) read past, the first at line %u\n",
                cmd, path, s->num_unused_freeform, s->num_unused_freeform == 1 ? "" : "s",
                s->first_unused_freeform_line);
}

void cli_patch_partial_warning(const char *cmd, const char *path, const tsr_pmodel *m)
{
    tsr_pmodel_info info;
    tsr_pmodel_get_info(m, &info);
    if (info.partial_unlinked)
        fprintf(stderr,
                "tessera %s: %s: warning: %u pairs of patch edges sharing part of their curve are left unlinked: "
                "cutting the patches where they meet passes the budget of breakpoints or pieces (staggered rows spread every "
                "row's cuts through all), so the mesh has gaps there\n",
                cmd, path, info.partial_unlinked);
}

bool cli_patch_gaps(const tsr_pmodel *m, const tsr_ptess_result *r, double eps, const bool *unlinked,
                    uint32_t *gaps, uint32_t *open)
{
    *gaps = 0;
    if (open)
        *open = 0;
    bool *gap = malloc((3 * (size_t)r->mesh.triangle_count + 1) * sizeof *gap);
    if (!gap || tsr_mesh_find_gaps(&r->mesh, eps, gap, NULL) != TSR_OK) {
        free(gap);
        return false;
    }
    /* an untrimmed patch's open edge whose gap faces only trimmed
     * patches' edges (a cylinder's rim against a cap's trim circle) is a
     * trim-curve seam too, which ptess.h does not join: found as the gaps
     * that go away with the trimmed patches' triangles left out (a second
     * search, only where an untrimmed patch has a gap at all) */
    uint32_t nt = r->mesh.triangle_count, nkeep = 0;
    tsr_pmodel_info info;
    tsr_pmodel_get_info(m, &info);
    bool *trimmed = malloc(((size_t)info.sources + 1) * sizeof *trimmed), any_trimmed = false, untrimmed_gap = false;
    uint32_t *slot = NULL, *idx = NULL;
    bool *gap2 = NULL;
    if (!trimmed) {
        free(gap);
        return false;
    }
    for (uint32_t k = 0; k < info.sources; k++) {
        tsr_psource_info si;
        trimmed[k] = tsr_pmodel_source_info(m, k, &si) && si.trimmed;
        any_trimmed |= trimmed[k];
    }
#define TRIMMED(t) (r->tri_source[t] < info.sources && trimmed[r->tri_source[t]])
    for (uint32_t h = 0; any_trimmed && !untrimmed_gap && h < 3 * nt; h++)
        untrimmed_gap = gap[h] && !TRIMMED(h / 3);
    if (untrimmed_gap) {
        slot = malloc(((size_t)nt + 1) * sizeof *slot);
        idx = malloc((3 * (size_t)nt + 1) * sizeof *idx);
        gap2 = malloc((3 * (size_t)nt + 1) * sizeof *gap2);
        bool ok = slot && idx && gap2;
        for (uint32_t t = 0; ok && t < nt; t++) {
            slot[t] = UINT32_MAX;
            if (TRIMMED(t))
                continue;
            memcpy(idx + 3 * (size_t)nkeep, r->mesh.indices + 3 * (size_t)t, 3 * sizeof *idx);
            slot[t] = nkeep++;
        }
        tsr_mesh view = r->mesh;
        view.indices = idx;
        view.triangle_count = nkeep;
        if (!ok || tsr_mesh_find_gaps(&view, eps, gap2, NULL) != TSR_OK) {
            free(slot), free(idx), free(gap2), free(gap), free(trimmed);
            return false;
        }
    }
    for (uint32_t h = 0; h < 3 * nt; h++) {
        if (!gap[h])
            continue;
        bool tr = TRIMMED(h / 3), faces_trim = untrimmed_gap && !tr && !gap2[3 * (size_t)slot[h / 3] + h % 3];
        bool unjoined = (unlinked && unlinked[h]) || tr || faces_trim;
        *gaps += !unjoined;
        if (open)
            *open += unjoined;
    }
#undef TRIMMED
    free(trimmed);
    free(slot), free(idx), free(gap2);
    free(gap);
    return true;
}
