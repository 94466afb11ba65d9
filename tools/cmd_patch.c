/* cmd_patch.c: `tessera patch IN -o OUT`: Bézier, B-spline, NURBS and
 * Catmull-Clark surfaces to a crack-free mesh within a stated error
 * (model units, or pixels for a camera), measured after building. */
#include "camera.h"
#include "patch_cli.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static void help(FILE *f)
{
    fprintf(f,
            "usage: tessera patch IN -o OUT [options]\n\n"
            "Tessellates the surfaces of IN into a welded, crack-free triangle mesh, adaptively on one\n"
            "restricted quadtree per patch. IN is a Bézier patch file (.bpt), an OBJ with free-form\n"
            "surfaces (cstype bezier|bspline|rat bspline, surf, parm, trim, hole) or a polygon OBJ, read\n"
            "as a subdivision cage (Catmull-Clark; OpenSubdiv's crease, corner and hole tags). OUT's\n"
            "extension picks the format: .obj, .ply, .stl or .glb (with --normals, a vertex where\n"
            "surfaces meet at an angle is written once per side).\n\n"
            "The error is the distance between the true surface S(u,v) and the mesh's point at the same\n"
            "(u,v). After building, it is measured on 64 x 64 samples per patch plus every edge midpoint\n"
            "(on every core; a progress bar on a terminal); patches that measure beyond the tolerance\n"
            "are tessellated again, finer, so the figure printed is a measurement, and it holds.\n\n"
            "options:\n"
            "  -o, --output OUT      output mesh (required)\n"
            "  --max-error E         largest distance allowed, model units (default 1e-3 of the model's\n"
            "                        bounding-box diagonal)\n"
            "  --pixel-error T       view-dependent instead: the screen error allowed, pixels (needs --camera)\n"
            "  --camera EX,EY,EZ,TX,TY,TZ  the eye and the point it looks at (+z up)\n"
            "  --width W, --height H viewport in pixels (default 1920 x 1080)\n"
            "  --fov DEG             vertical field of view (default 60)\n"
            "  --near D              near plane distance (default 1e-3 of the model's diagonal)\n"
            "  --tile N              quads per tile side, even, 2..128 (default 4); Bezier patches\n"
            "                        choose theirs in N..4N-2 (one-tile ones also N/2, when even), the\n"
            "                        one giving the fewest quads; cage faces needing few tiles N or N/2\n"
            "                        (when even), likewise\n"
            "  --max-level L         quadtree depth per patch, 1..12 (default 10; where the measured\n"
            "                        error stays above the tolerance at 10, once more at 12)\n"
            "  --scheme S            catmark or bilinear, for a polygon cage (default: bilinear when the\n"
            "                        file name starts with \"bilinear\", else catmark)\n" CLI_WELD_HELP CLI_ORIENT_HELP
            "  --normals             per-vertex normals of the true surface; where surfaces meet at an\n"
            "                        angle (sharp creases and corners of a cage, faces of a box of\n"
            "                        patches) the vertex is written once per side, each with its side's\n"
            "                        normal, so renderers draw the crease (not in .stl: facet normals)\n"
            "  --crease-angle DEG    sides whose normals differ by more than DEG degrees are split so\n"
            "                        (default 1; 180: never, one vertex with the sides' mean normal)\n"
            "  --no-verify           skip the measurement (and the re-tessellation it may ask for);\n"
            "                        warns when the Bezier patches' bound is above the tolerance\n"
            "  --stats FILE.json     patches, pieces, triangles, vertices, measured max_error and\n"
            "                        rms_error, bound (model units, also with a camera; null for a\n"
            "                        subdivision surface, whose pieces have estimates), seconds,\n"
            "                        the options used, the mesh's boundary_edges, t_junctions,\n"
            "                        degenerate_triangles and gaps (open edges along another within\n"
            "                        the tolerance: a crack), linked_edges (piece edges sampled\n"
            "                        alike with a neighbour's) and shared_breakpoints (knots a patch\n"
            "                        took from a neighbour sharing all or part of an edge, so their\n"
            "                        pieces meet piece to piece); with\n"
            "                        --normals also vertices_written and crease_vertices (the copies\n"
            "                        written at creases)\n"
            "  --quiet               print nothing on success\n"
            "  -h, --help            this help\n");
}

static int write_stats(const char *path, const char *in, const cli_patch_model *pm, const tsr_ptess_result *r,
                       const tsr_ptess_measure_result *meas, bool verified, const tsr_ptess_options *opt,
                       uint32_t tightened, double secs, const tsr_validation *val, uint32_t gaps,
                       const tsr_mesh *written)
{
    tsr_pmodel_info info;
    tsr_pmodel_get_info(pm->model, &info);
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "input", in);
    cJSON_AddStringToObject(j, "kind", pm->is_subd ? "subdivision" : "patches");
    cJSON_AddNumberToObject(j, "patches", info.sources);
    cJSON_AddNumberToObject(j, "pieces", info.pieces);
    cJSON_AddNumberToObject(j, "linked_edges", info.links);
    if (!pm->is_subd) {
        cJSON_AddNumberToObject(j, "shared_breakpoints", info.conform_breaks);
        cJSON_AddNumberToObject(j, "split_breakpoints", info.split_breaks);
    }
    cJSON_AddNumberToObject(j, "triangles", r->mesh.triangle_count);
    cJSON_AddNumberToObject(j, "vertices", r->mesh.vertex_count);
    cJSON_AddNumberToObject(j, "tiles", r->leaves);
    if (written) { /* --normals: vertices written once per side of a crease */
        cJSON_AddNumberToObject(j, "vertices_written", written->vertex_count);
        cJSON_AddNumberToObject(j, "crease_vertices", written->vertex_count - r->mesh.vertex_count);
    }
    if (verified) {
        cJSON_AddNumberToObject(j, "max_error", meas->max_error);
        cJSON_AddNumberToObject(j, "rms_error", meas->rms_error);
        cJSON_AddNumberToObject(j, "samples", (double)meas->samples);
        cJSON_AddNumberToObject(j, "uncovered_samples", (double)meas->uncovered);
        cJSON_AddNumberToObject(j, "tightened_patches", tightened);
    }
    if (val) {
        cJSON_AddNumberToObject(j, "boundary_edges", val->boundary_edges);
        cJSON_AddNumberToObject(j, "t_junctions", val->t_junctions);
        if (!pm->is_subd && !opt->camera)
            cJSON_AddNumberToObject(j, "gaps", gaps);
        cJSON_AddNumberToObject(j, "degenerate_triangles", val->degenerate_triangles);
    }
    cJSON_AddStringToObject(j, "error_units", opt->camera ? "pixels" : "model");
    if (opt->camera)
        cJSON_AddNumberToObject(j, "pixel_error", opt->camera->pixel_error);
    else
        cJSON_AddNumberToObject(j, "requested_max_error", opt->max_error);
    if (pm->is_subd) /* a subdivision surface's pieces have estimates, no bound */
        cJSON_AddNullToObject(j, "bound");
    else
        cJSON_AddNumberToObject(j, "bound", r->bound); /* model units, also with a camera */
    cJSON_AddStringToObject(j, "bound_units", "model");
    cJSON_AddNumberToObject(j, "tile", opt->tile_n);
    cJSON_AddNumberToObject(j, "seconds", secs);
    cJSON_AddNumberToObject(j, "tessellate_seconds", r->seconds);
    char *txt = cJSON_Print(j);
    cJSON_Delete(j);
    tsr_error err = {0};
    tsr_status st = txt ? cli_write_text(path, txt, &err) : TSR_ERR_NOMEM;
    free(txt);
    if (st != TSR_OK) {
        cli_error("patch", "%s", txt ? err.message : "out of memory");
        return CLI_FAIL;
    }
    return CLI_OK;
}

static int run(int argc, char **argv)
{
    const char *in = NULL, *out = NULL, *stats = NULL, *cam_arg = NULL, *scheme = NULL;
    double weld = 0;
    bool orient = false;
    double max_error = 0;
    view_options v = {60, 1920, 1080, 0, 0};
    uint32_t tile = 4, max_level = 10;
    bool normals = false, quiet = false, verify = true, max_level_given = false;
    double crease = -1;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        bool has_value = i + 1 < argc;
        int vo;
        if (cli_is_help(a)) {
            help(stdout);
            return CLI_OK;
        } else if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && has_value)
            out = argv[++i];
        else if (!strcmp(a, "--stats") && has_value)
            stats = argv[++i];
        else if (!strcmp(a, "--camera") && has_value)
            cam_arg = argv[++i];
        else if (!strcmp(a, "--weld") && has_value) {
            if (!cli_parse_double(argv[++i], &weld) || !(weld > 0)) {
                cli_error("patch", "--weld %s: must be a positive distance", argv[i]);
                return CLI_USAGE;
            }
        } else if (!strcmp(a, "--scheme") && has_value) {
            scheme = argv[++i];
            if (strcmp(scheme, "catmark") && strcmp(scheme, "bilinear")) {
                cli_error("patch", "--scheme %s: use catmark or bilinear", scheme);
                return CLI_USAGE;
            }
        } else if (!strcmp(a, "--normals"))
            normals = true;
        else if (!strcmp(a, "--orient-faces"))
            orient = true;
        else if (!strcmp(a, "--crease-angle") && has_value) {
            if (!cli_parse_double(argv[++i], &crease) || !(crease >= 0 && crease <= 180)) {
                cli_error("patch", "--crease-angle %s: must be an angle in 0..180 degrees", argv[i]);
                return CLI_USAGE;
            }
        }
        else if (!strcmp(a, "--quiet") || !strcmp(a, "-q"))
            quiet = true;
        else if (!strcmp(a, "--no-verify"))
            verify = false;
        else if ((!strcmp(a, "--tile") || !strcmp(a, "--max-level")) && has_value) {
            uint32_t u;
            bool tile_opt = !strcmp(a, "--tile");
            if (!cli_parse_u32(argv[++i], tile_opt ? 2 : 1, tile_opt ? 128 : 12, &u) || (tile_opt && (u & 1))) {
                cli_error("patch", "%s %s: %s", a, argv[i],
                          tile_opt ? "must be an even number in 2..128" : "must be a whole number in 1..12");
                return CLI_USAGE;
            }
            *(tile_opt ? &tile : &max_level) = u;
            max_level_given |= !tile_opt;
        } else if (!strcmp(a, "--max-error") && has_value) {
            if (!cli_parse_double(argv[++i], &max_error) || !(max_error > 0)) {
                cli_error("patch", "%s %s: must be a positive number", a, argv[i]);
                return CLI_USAGE;
            }
        } else if ((vo = view_option("patch", a, has_value ? argv[i + 1] : NULL, &v)) != 0) {
            if (vo < 0)
                return CLI_USAGE;
            i++;
        } else if (a[0] == '-' && a[1] != '\0') {
            cli_option_error("patch", NULL, a, help);
            return CLI_USAGE;
        } else if (in) {
            cli_error("patch", "one input at a time ('%s' and '%s' given)", in, a);
            return CLI_USAGE;
        } else
            in = a;
    }
    if (!in) {
        cli_error("patch", "no input file (see tessera patch --help)");
        return CLI_USAGE;
    }
    if (!out) {
        cli_error("patch", "no output: give -o OUT (.obj, .ply, .stl or .glb)");
        return CLI_USAGE;
    }
    if (tsr_mesh_format_from_path(out) == TSR_FORMAT_UNKNOWN) {
        cli_error("patch", "%s: unknown mesh format (use .obj, .ply, .stl or .glb)", out);
        return CLI_USAGE;
    }
    if (crease >= 0 && !normals) {
        cli_error("patch", "--crease-angle needs --normals");
        return CLI_USAGE;
    }
    tsr_camera cam_syntax;
    view_options vs = v; /* the syntax alone: the near plane is not known yet */
    vs.near_dist = vs.pixel_error = 1;
    if (cam_arg && !parse_camera(cam_arg, &vs, &cam_syntax)) { /* before the pairing, which it would hide */
        cli_error("patch", "--camera %s: expected EX,EY,EZ,TX,TY,TZ with eye != target", cam_arg);
        return CLI_USAGE;
    }
    if ((v.pixel_error > 0) != (cam_arg != NULL)) {
        cli_error("patch", "--pixel-error and --camera go together");
        return CLI_USAGE;
    }
    if (cam_arg && max_error > 0) {
        cli_error("patch", "give either --max-error or --pixel-error with --camera, not both");
        return CLI_USAGE;
    }
    const char *names[3] = {"the input", "-o", "--stats"}, *files[3] = {in, out, stats};
    if (!cli_paths_distinct("patch", 3, names, files))
        return CLI_USAGE;
    const char *outputs[2] = {out, stats}; /* checked before the work, not after it */
    if (!cli_outputs_writable("patch", 2, outputs))
        return CLI_FAIL;
    double t0 = cli_now();
    cli_patch_model pm;
    if (!cli_patch_model_load_weld("patch", in, scheme, weld, orient, &pm))
        return CLI_FAIL;
    if (!quiet && !pm.is_subd && pm.set.num_polygons)
        fprintf(stderr,
                "tessera patch: %s: note: %u polygon, line and point statements (f, l, p) beside the free-form "
                "surfaces are not tessellated, the first at line %u (a file without surfaces is read as a "
                "subdivision cage)\n",
                in, pm.set.num_polygons, pm.set.first_polygon_line);
    uint32_t flat = cli_patch_flat_warnings("patch", in, &pm, quiet ? 0 : 5);
    if (!quiet) {
        cli_patch_trim_warnings("patch", in, &pm, 5);
        cli_patch_model_notes("patch", in, &pm);
    }
    if (!quiet && pm.is_subd && pm.cage.num_skipped_tags)
        fprintf(stderr,
                "tessera patch: %s: note: %u tags OpenSubdiv does not use (hierarchical edits, unknown names) "
                "ignored, the first at line %u\n",
                in, pm.cage.num_skipped_tags, pm.cage.first_skipped_tag_line);
    if (!(pm.diag > 0)) {
        cli_error("patch", "%s: the model has no extent: every control point lies at one place", in);
        cli_patch_model_free(&pm);
        return CLI_FAIL;
    }
    /* The mesh is float32: a bound below a few of its steps at the
     * model's largest coordinate can be neither written nor measured, and
     * chasing it only grows the mesh until memory runs out. */
    double maxabs, step, floor_err = cli_patch_float_floor(pm.model, &maxabs, &step);
    if (max_error > 0 && max_error < floor_err) {
        cli_error("patch", "%s: --max-error %g is below what the float32 mesh can hold: coordinates up to %g are "
                  "stored in steps of %.3g; give at least %.3g",
                  in, max_error, maxabs, step, floor_err);
        cli_patch_model_free(&pm);
        return CLI_USAGE;
    }
    if (cam_arg && v.pixel_error < 0.01) {
        cli_error("patch", "--pixel-error %g: below 0.01 px, finer than a rasteriser places vertices", v.pixel_error);
        cli_patch_model_free(&pm);
        return CLI_USAGE;
    }
    tsr_camera cam;
    tsr_ptess_options opt = {0};
    opt.tile_n = tile;
    opt.max_level = max_level;
    opt.normals = normals;
    if (cam_arg) {
        if (!(v.near_dist > 0))
            v.near_dist = 1e-3 * pm.diag;
        if (!parse_camera(cam_arg, &v, &cam)) {
            cli_error("patch", "--camera %s: expected EX,EY,EZ,TX,TY,TZ with eye != target", cam_arg);
            cli_patch_model_free(&pm);
            return CLI_USAGE;
        }
        opt.camera = &cam;
    } else {
        opt.max_error = max_error > 0 ? max_error : 1e-3 * pm.diag;
        if (opt.max_error < floor_err) {
            if (!quiet)
                fprintf(stderr, "tessera patch: %s: note: the default bound %.3g is below what the float32 mesh "
                        "holds this far from the origin (coordinates up to %g); using %.3g\n",
                        in, opt.max_error, maxabs, floor_err);
            opt.max_error = floor_err;
        }
        /* cut pieces curved one way only across their curve, for this bound */
        if (!cli_patch_model_split("patch", in, &pm, weld, opt.max_error, tile)) {
            cli_patch_model_free(&pm);
            return CLI_FAIL;
        }
    }
    if (!quiet && !pm.is_subd)
        cli_patch_partial_warning("patch", in, pm.model);
    tsr_ptess_result r;
    tsr_ptess_measure_result meas;
    uint32_t tightened = 0;
    tsr_error err = {0};
    tsr_status st;
    double tol = opt.camera ? v.pixel_error : opt.max_error;
    if (verify) {
        cli_progress pr;
        cli_progress_start(&pr, "patch: measuring", !quiet);
        st = cli_patch_tessellate(pm.model, &opt, 64, 6, &r, &meas, &tightened, &pr, &err);
        cli_progress_end(&pr);
        if (st == TSR_OK && meas.max_error > tol && !max_level_given && opt.max_level < 12) {
            /* the default depth did not reach the tolerance: once more,
             * as deep as the quadtree goes (features narrower than the
             * finest tiles at depth 10, such as a weight far above the
             * others, need it) */
            if (!quiet)
                fprintf(stderr,
                        "tessera patch: %s: measured error %.6g is above %.6g at --max-level %u: again with "
                        "--max-level 12\n",
                        in, meas.max_error, tol, opt.max_level);
            tsr_ptess_result_free(&r);
            opt.max_level = 12;
            cli_progress_start(&pr, "patch: measuring", !quiet);
            st = cli_patch_tessellate(pm.model, &opt, 64, 6, &r, &meas, &tightened, &pr, &err);
            cli_progress_end(&pr);
        }
    } else {
        memset(&meas, 0, sizeof meas);
        st = tsr_ptess_run(pm.model, &opt, NULL, &r, &err);
    }
    int rc = CLI_OK;
    if (st != TSR_OK) {
        cli_error("patch", "%s: %s", in, err.message);
        rc = CLI_FAIL;
    }
    if (rc == CLI_OK && verify && meas.max_error > tol) {
        uint32_t ml = opt.max_level ? opt.max_level : 10;
        /* with a camera, float32 positions may be what fails: a step of
         * them at the model's nearest point, in pixels */
        char why[256] = "";
        if (opt.camera) {
            tsr_pmodel_info bi;
            tsr_pmodel_get_info(pm.model, &bi);
            double d2 = 0;
            for (int k = 0; k < 3; k++) {
                double e = opt.camera->eye[k], dd = e < bi.lo[k] ? bi.lo[k] - e : e > bi.hi[k] ? e - bi.hi[k] : 0;
                d2 += dd * dd;
            }
            double px = step * opt.camera->K / fmax(sqrt(d2), opt.camera->near_dist);
            if (px >= 0.25 * tol)
                snprintf(why, sizeof why,
                         "; coordinates as large as %g are stored in float32 steps of %.3g, about %.3g px from this "
                         "camera: move the model nearer the origin",
                         maxabs, step, px);
        }
        /* a weld as wide as the error moved vertices that far: refining
         * cannot undo it */
        if (!opt.camera && weld > 0 && weld >= 0.5 * meas.max_error)
            snprintf(why, sizeof why,
                     "; --weld %g joins patch edges up to that far apart, moving their vertices by as much: give "
                     "--weld below the tolerance to keep the mesh within it",
                     weld);
        cli_error("patch",
                  "%s: measured error %.6g is above %.6g even after re-tessellating %u patch%s finer "
                  "(down to --max-level %u%s)%s",
                  in, meas.max_error, tol, tightened, tightened == 1 ? "" : "es", ml,
                  ml < 12 ? "; --max-level 12 lets each patch's quadtree go deeper, where features narrower than "
                            "its finest tiles (a weight far above the others) need it"
                          : "; the deepest it goes",
                  why);
        rc = CLI_FAIL;
    } else if (rc == CLI_OK && verify && meas.uncovered) {
        cli_error("patch",
                  "%s: %llu of %llu measured samples of untrimmed patches fall on no triangle of the mesh "
                  "(a gap, or triangles with no area: coordinates as large as %g leave float32 no room for small "
                  "features), even after re-tessellating %u patch%s finer",
                  in, (unsigned long long)meas.uncovered, (unsigned long long)meas.samples, maxabs, tightened,
                  tightened == 1 ? "" : "es");
        rc = CLI_FAIL;
    }
    if (rc == CLI_OK && r.mesh.triangle_count == 0) {
        tsr_pmodel_info ni;
        tsr_pmodel_get_info(pm.model, &ni);
        cli_error("patch", "%s: the tessellation has no triangle%s", in,
                  ni.trimmed_sources ? ": the trim loops and holes leave no part of any patch (a hole around a "
                                       "whole patch, or an outer loop around nothing)"
                                     : "");
        rc = CLI_FAIL;
    }
    /* What the measurement does not see: vertices left unwelded where
     * surfaces meet (edges farther apart than --weld, a different knot
     * vector along a shared edge, a trim curve across it), T-junctions,
     * zero-area triangles. Reported, not fatal: the surfaces may simply
     * not meet there. */
    tsr_validation val;
    bool validated = rc == CLI_OK && verify && tsr_mesh_validate(&r.mesh, NULL, &val) == TSR_OK;
    /* a cage's non-manifold edges are left open by contract (ptess.h), and
     * another sheet's vertices may lie on them: no T-junction counts there */
    uint32_t tj = validated && !pm.is_subd ? val.t_junctions : 0, zero = validated ? val.degenerate_triangles : 0;
    /* gaps: open edges along another within the tolerance, running the
     * other way, or the same way on another sheet (a crack narrower than the
     * tolerance where surfaces meet with different vertices); on untrimmed patches of a set only (a
     * cage's open edges are open by contract, trim curves are not joined) */
    uint32_t gaps = 0, trim_seams = 0;
    if (validated && !pm.is_subd && !opt.camera)
        cli_patch_gaps(pm.model, &r, opt.max_error, NULL, &gaps, &trim_seams);
    /* normals: a vertex where surfaces meet at an angle is written once
     * per side (the welded mesh above is what was validated and measured) */
    tsr_mesh split;
    memset(&split, 0, sizeof split);
    uint32_t crease_added = 0;
    bool splitting = rc == CLI_OK && normals && tsr_mesh_format_from_path(out) != TSR_FORMAT_STL;
    if (splitting && tsr_ptess_crease_normals(pm.model, &r, crease >= 0 ? crease : 1, NULL, &split, &crease_added,
                                              &err) != TSR_OK) {
        cli_error("patch", "%s: %s", in, err.message);
        rc = CLI_FAIL;
    }
    /* A closed shell facing inward (its patches all mirrored, or the
     * orientation taken from a mirrored first patch) is turned outward, as
     * a solid's normals should point; the split copy has r's triangles */
    uint32_t inward = 0;
    if (rc == CLI_OK) {
        uint8_t *flip = malloc((size_t)r.mesh.triangle_count + 1);
        if (flip && tsr_mesh_find_inward_shells(&r.mesh, flip, &inward) == TSR_OK && inward) {
            tsr_mesh_flip_marked(&r.mesh, flip);
            if (splitting && split.triangle_count == r.mesh.triangle_count)
                tsr_mesh_flip_marked(&split, flip);
            if (!quiet)
                fprintf(stderr, "tessera patch: %s: note: %u closed shell%s faced inward (negative volume); turned "
                        "outward\n", in, inward, inward == 1 ? "" : "s");
        }
        free(flip);
    }
    if (rc == CLI_OK && tsr_mesh_write(splitting ? &split : &r.mesh, out, TSR_FORMAT_UNKNOWN, &err) != TSR_OK) {
        cli_error("patch", "%s", err.message);
        rc = CLI_FAIL;
    }
    double secs = cli_now() - t0;
    if (rc == CLI_OK && stats)
        rc = write_stats(stats, in, &pm, &r, &meas, verify, &opt, tightened, secs, validated ? &val : NULL, gaps,
                         splitting ? &split : NULL);
    if (rc == CLI_OK && !quiet) {
        tsr_pmodel_info info;
        tsr_pmodel_get_info(pm.model, &info);
        char crease_note[64] = "";
        if (crease_added)
            snprintf(crease_note, sizeof crease_note, " (%u more written at creases)", crease_added);
        if (verify)
            fprintf(stderr,
                    "tessera patch: %s: %u patch%s, %u triangles, %u vertices%s; max error %.4g %s (asked %.4g, "
                    "measured at %llu samples%s), %.2f s\n",
                    in, info.sources, info.sources == 1 ? "" : "es", r.mesh.triangle_count, r.mesh.vertex_count,
                    crease_note, meas.max_error, opt.camera ? "px" : "units", tol, (unsigned long long)meas.samples,
                    tightened ? ", some patches re-tessellated" : "", secs);
        else
            fprintf(stderr, "tessera patch: %s: %u patch%s, %u triangles, %u vertices%s, not measured, %.2f s\n", in,
                    info.sources, info.sources == 1 ? "" : "es", r.mesh.triangle_count, r.mesh.vertex_count,
                    crease_note, secs);
        if (!verify && !opt.camera && !(r.bound <= tol))
            fprintf(stderr,
                    "tessera patch: %s: warning: the a-priori bound %.4g of the Bezier patches is above the "
                    "tolerance %.4g (--max-level %u stops their refinement): run without --no-verify to measure "
                    "and re-tessellate, or raise --max-level\n",
                    in, r.bound, tol, opt.max_level ? opt.max_level : 10);
        if (trim_seams)
            fprintf(stderr,
                    "tessera patch: %s: note: %u open edges lie along a trimmed patch's boundary within the "
                    "tolerance: trim curves are not joined to the patches they meet, so the mesh is open there "
                    "(tessera check patches counts them as unjoined-gaps)\n",
                    in, trim_seams);
        if (validated && val.misoriented_edges)
            fprintf(stderr,
                    "tessera patch: %s: warning: %u edges where the triangles on the two sides face opposite ways: "
                    "joined surfaces disagree on which side is out (a Moebius band cannot agree; otherwise reverse "
                    "a patch's u or v, or --orient-faces for a cage); tessera check patches locates them\n",
                    in, val.misoriented_edges);
        if (tj || zero || gaps)
            fprintf(stderr,
                    "tessera patch: %s: warning: %u T-junctions, %u open edges along another within the tolerance "
                    "(gaps) and %u zero-area triangles, where surfaces meet without matching edges (farther apart "
                    "than --weld, parameterised differently, sharing part of an edge, a trim curve across it, a "
                    "degenerate trim)%s; tessera check patches locates them\n",
                    in, tj, gaps, zero, flat ? ", or on the patches with no area above" : "");
    }
    tsr_mesh_free(&split);
    tsr_ptess_result_free(&r);
    cli_patch_model_free(&pm);
    return rc;
}

const cli_command cli_cmd_patch = {"patch", "Bézier, NURBS and subdivision surfaces to a crack-free mesh within an error",
                                   run, help};
