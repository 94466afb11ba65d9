/* cli.h: what the tessera subcommands share: the command table, strict
 * number parsing, the heightfield options of `tessera info`, and error
 * reporting. */
#ifndef TSR_CLI_H
#define TSR_CLI_H

#include "terrain/terrain.h"

#include <stdio.h>

typedef struct cli_command {
    const char *name;
    const char *summary;
    int (*run)(int argc, char **argv); /* argv[0] is the command name */
    void (*help)(FILE *f);
} cli_command;

/* Exit codes: 0 success, 1 failure on input or output, 2 bad usage, 3
 * (tessera mesh) nothing to mesh: no-data everywhere, nothing written;
 * (tessera triangulate) written, but the refinement bounds asked for are
 * not met everywhere. */
enum { CLI_OK = 0, CLI_FAIL = 1, CLI_USAGE = 2, CLI_EMPTY = 3, CLI_UNMET = 3 };

/* Prints "tessera CMD: message" to stderr. */
void cli_error(const char *cmd, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Strict parsers: the whole string must be a finite number in range. */
bool cli_parse_double(const char *s, double *out);
bool cli_parse_u32(const char *s, uint32_t min, uint32_t max, uint32_t *out);
/* Whether n is a grid tile size the terrain takes: a power of two from
 * TSR_TILE_MIN to TSR_TILE_MAX. */
bool cli_tile_size_ok(uint32_t n);

/* The heightfield options every command that reads one accepts:
 * --decode terrain-rgb, --raw W H TYPE, --nodata V, --dx S, --dy S, --dz S. */
typedef struct cli_heightfield_options {
    tsr_load_options load;
    double dx, dy, dz; /* 0: not given */
} cli_heightfield_options;

/* Called by the signal handler (after the pending atomic outputs are
 * removed) when set: a command's own clean-up of a half-done output. Only
 * async-signal-safe work. */
extern void (*volatile cli_signal_cleanup)(void);

#define CLI_HEIGHTFIELD_HELP                                                                                           \
    "  --decode terrain-rgb  decode an RGB(A) Terrain-RGB tile:\n"                                                     \
    "                        h = (R*65536 + G*256 + B) * 0.1 - 10000 (alpha 0: no-data)\n"                             \
    "  --raw W H TYPE        headerless little-endian samples, TYPE u16, i16 or f32\n"                                 \
    "  --nodata V            samples equal to V are no-data (holes); default: the file's own\n"                        \
    "                        (GeoTIFF GDAL_NODATA, a GIS format's header). V is a stored value,\n"                     \
    "                        compared before a scale and offset the file names, as GDAL does;\n"                       \
    "                        +-3.4028235e38 (the float extremes) are always no-data\n"                                 \
    "  --dx S, --dy S        sample spacing in x and y (default: a GIS file's own, in metres,\n"                       \
    "                        else 1; --dy defaults to --dx)\n"                                                         \
    "  --dz S                height scale: z = h * S (default 1)\n"

/* If argv[*i] is one of those options, consumes it and its values
 * (advancing *i) and returns 1; returns 0 if it is not; prints an error
 * and returns -1 on a bad value. */
int cli_heightfield_option(const char *cmd, int argc, char **argv, int *i, cli_heightfield_options *o);

/* The spacing the options give hf: --dx/--dy where given (--dy defaults
 * to --dx), else the georeferenced file's spacing (tsr_georef), else 1; true
 * when it came from the file. */
bool cli_spacing(const tsr_heightfield *hf, const cli_heightfield_options *o, double *dx, double *dy);

/* "DX x DY (where it came from); CRS name", for summaries. */
void cli_georef_describe(const tsr_heightfield *hf, const cli_heightfield_options *o, char *buf, size_t cap);
/* Warnings on stderr where the file's georeferencing is not what the mesh
 * follows: a rotated or sheared grid (without --dx, --dy), heights in feet
 * over ground metres (without --dz). */
void cli_georef_warnings(const char *cmd, const char *path, const tsr_heightfield *hf,
                         const cli_heightfield_options *o);

/* Adds "spacing" [dx, dy], "spacing_from" (file, options or default) and,
 * for a georeferenced file, "georef" {crs, crs_kind, origin, pixel,
 * ground_spacing, ground_spacing_varies, ground_spacing_unitless,
 * nodata_value, z_unit, z_scale, z_offset} (those the file has) to the JSON
 * object j. */
struct cJSON;
void cli_georef_json(struct cJSON *j, const tsr_heightfield *hf, const cli_heightfield_options *o);

/* Loads the heightfield with the options and applies spacing (cli_spacing);
 * prints the error and returns NULL on failure. */
tsr_heightfield *cli_load_heightfield(const char *cmd, const char *path, const cli_heightfield_options *o);

/* True when argv[*i] is -h or --help. */
bool cli_is_help(const char *arg);

/* Seconds from a monotonic clock. */
double cli_now(void);

/* A progress bar on stderr, "tessera CMD: [####....]  42%": drawn only
 * when on (not --quiet) and stderr is a terminal, once the work has taken
 * a second, at most ten times a second; cli_progress_end erases it. */
typedef struct cli_progress {
    const char *cmd;
    bool on, shown;
    double t0, last;
} cli_progress;
void cli_progress_start(cli_progress *p, const char *cmd, bool on);
/* A progress callback of the library (user: the cli_progress). */
void cli_progress_cb(void *user, double fraction);
void cli_progress_end(cli_progress *p);
/* Names the step now under way in place of the bar ("tessera mesh:
 * writing the normal map ..."), on the same terms (a terminal, after the
 * first second); cli_progress_end erases it. */
void cli_progress_phase(cli_progress *p, const char *what);

/* Checks, before long work, that outputs can be written: for each of the
 * n paths not NULL (NULL: not asked for), that a file can be made there
 * (tsr_atomic_probe); prints the error and returns false at the first
 * that cannot. */
bool cli_outputs_writable(const char *cmd, int n, const char *const *paths);

/* Reports an argument a that the command's parser did not take: "missing
 * value for" an option that its help text (printed by help) lists with a
 * value, else "unknown option", with the nearest option the help lists
 * (a unique prefix, or a few letters off) as "did you mean". sub: the
 * subcommand ("bench patch") or NULL. */
void cli_option_error(const char *cmd, const char *sub, const char *a, void (*help)(FILE *));

/* Checks, before any work, that no two of the n files (names[k] the
 * option that gives paths[k], e.g. "-o" or "the input"; NULL paths
 * skipped) are one file: by device and inode where both exist, else by
 * their folders' real paths and names. Prints the error and returns false
 * at the first pair; the caller exits with CLI_USAGE. */
bool cli_paths_distinct(const char *cmd, int n, const char *const *names, const char *const *paths);

/* Writes text to path atomically (temporary, then rename). */
tsr_status cli_write_text(const char *path, const char *text, tsr_error *err);

extern const cli_command cli_cmd_info, cli_cmd_generate, cli_cmd_mesh, cli_cmd_check, cli_cmd_bench,
    cli_cmd_triangulate, cli_cmd_fly, cli_cmd_patch;

#endif
