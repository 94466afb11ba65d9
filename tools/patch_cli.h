/* patch_cli.h: what the patch commands (patch, check patches, bench patch)
 * share: loading a model from a .bpt, a free-form OBJ or a polygon OBJ
 * cage, and the tessellate-measure-tighten loop that makes the stated
 * bound hold on the measurement. */
#ifndef TSR_TOOLS_PATCH_CLI_H
#define TSR_TOOLS_PATCH_CLI_H

#include "cli.h"
#include "patches/ptess.h"

typedef struct cli_patch_model {
    tsr_patch_set set;   /* when loaded from .bpt or free-form OBJ */
    tsr_cage cage;       /* when loaded from a polygon OBJ */
    tsr_subd *subd;
    tsr_pmodel *model;
    bool is_subd;
    const char *kind;    /* "bpt", "obj-surfaces", "cage-catmark" or "cage-bilinear" */
    double diag;         /* model box diagonal */
    uint32_t cage_reversed;       /* cage faces against their neighbours (tsr_cage_orient): reversed when asked */
    uint32_t cage_first_reversed; /* the first of them, 0-based */
    bool cage_oriented;           /* they were reversed (--orient-faces) */
    uint32_t cage_unorientable;   /* parts of the cage no orientation agrees across (left as they are) */
} cli_patch_model;

/* Loads path: .bpt, or .obj with free-form surfaces (cstype/surf), else
 * .obj polygons as a subdivision cage (scheme: "catmark", "bilinear", or
 * NULL: bilinear when the file name starts with "bilinear", else
 * catmark). An OBJ with neither surfaces nor faces gets the surface
 * loader's message. Prints "tessera CMD: message" naming the file and
 * returns false on failure (nothing to free then). */
bool cli_patch_model_load(const char *cmd, const char *path, const char *scheme, cli_patch_model *out);
/* The same with the distance within which patch edges are linked and
 * welded (tsr_pmodel_from_set_tol; model units, 0: the default), and for
 * a cage, orient: reverse the faces listed against their neighbours
 * (tsr_cage_orient; otherwise only counted, for cli_patch_model_notes). */
bool cli_patch_model_load_weld(const char *cmd, const char *path, const char *scheme, double weld, bool orient,
                               cli_patch_model *out);

/* The --orient-faces option's help, shared by patch and check. */
#define CLI_ORIENT_HELP                                                                                                \
    "  --orient-faces        reverse cage faces listed against their neighbours' order (OpenSubdiv\n"                  \
    "                        leaves the edges they share open: a crack); without it they are\n"                        \
    "                        only warned of\n"

/* The --weld option's help, shared by patch and check. */
#define CLI_WELD_HELP                                                                                  \
    "  --weld D              link (and weld) free-form patch edges that lie within D of each other,\n" \
    "                        model units, whatever their knots and degrees (default 1e-6 of the box\n" \
    "                        diagonal; CAD files often leave gaps of 1e-6 to 1e-3)\n"
void cli_patch_model_free(cli_patch_model *m);

/* Warns, on stderr, of trim loops whose shape the file may not mean (open,
 * crossing themselves, enclosing none of their patch's domain), naming
 * the line and saying what the tessellation makes of each; at most `max`
 * lines, then a count of the rest. Returns how many loops were warned of. */
uint32_t cli_patch_trim_warnings(const char *cmd, const char *path, const cli_patch_model *pm, uint32_t max);

/* Warns of patches with no area: all control points on one line or at one
 * point (the surface lies in their convex hull, so it is that line or
 * point), whose triangles have zero area; at most `max` lines. Returns how
 * many such patches there are (0 for a cage). */
uint32_t cli_patch_flat_warnings(const char *cmd, const char *path, const cli_patch_model *pm, uint32_t max);

/* Rebuilds a free-form model (not a cage) for tessellation at max_error
 * with tiles of `tile` (tsr_pmodel_set_options.split_error: knot spans
 * curved one way and straight the other cut across the curve). false
 * after printing an error (the old model kept). */
/* Prints on stderr what loading changed or found: cage faces against
 * their neighbours (reversed: a note; else a warning naming the first and
 * --orient-faces), parts that cannot be oriented (a warning); in a
 * free-form OBJ, statements no OBJ keyword names (a warning with the
 * first's line: a misspelt `hole` drops a hole) and free-form geometry
 * read past untessellated (curv, scrv, sp, con: a note). */
void cli_patch_model_notes(const char *cmd, const char *path, const cli_patch_model *pm);

/* Gaps of r's mesh within eps (tsr_mesh_find_gaps), split into *gaps
 * (failures: between untrimmed patches along linked edges) and *open
 * (may be NULL: along a half-edge marked in unlinked, which may be NULL,
 * or on a trimmed patch, whose trim curves are not joined). false when out
 * of memory. */
bool cli_patch_gaps(const tsr_pmodel *m, const tsr_ptess_result *r, double eps, const bool *unlinked,
                    uint32_t *gaps, uint32_t *open);

/* Warns on stderr when m left partial overlaps unlinked
 * (tsr_pmodel_info.partial_unlinked). */
void cli_patch_partial_warning(const char *cmd, const char *path, const tsr_pmodel *m);

/* The smallest error the float32 mesh of m can hold: 4 steps of a float at
 * the model's largest coordinate (*maxabs), one step being *step. A bound
 * below it can be neither written nor measured. */
double cli_patch_float_floor(const tsr_pmodel *m, double *maxabs, double *step);

bool cli_patch_model_split(const char *cmd, const char *path, cli_patch_model *pm, double weld, double max_error,
                           uint32_t tile);

/* Tessellates with opt, measures (tsr_ptess_measure, per_side samples per
 * piece, with opt->camera when set), and where a source measures beyond
 * the tolerance (max_error, or the camera's pixel_error) re-tessellates
 * with its pieces' tolerance halved, up to `rounds` times. The result is
 * in *r and its measurement in *meas (source_error freed). Returns the
 * status of the last run; *tightened counts the sources tightened.
 * progress (may be NULL): a bar for each round's measurement, the long
 * part of the work on a big model. */
tsr_status cli_patch_tessellate(const tsr_pmodel *m, const tsr_ptess_options *opt, uint32_t per_side, uint32_t rounds,
                                tsr_ptess_result *r, tsr_ptess_measure_result *meas, uint32_t *tightened,
                                cli_progress *progress, tsr_error *err);

#endif
