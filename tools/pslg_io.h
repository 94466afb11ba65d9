/* pslg_io.h: planar straight-line graphs in and triangulations out, for
 * `tessera triangulate`.
 *
 * Readers (each gives one error line naming the file and the line, or the
 * JSON position, and the problem; nothing is returned on failure):
 *  - Triangle's .node (`n dim nattr nbound`, then `i x y [attrs] [bmark]`;
 *    up to 64 attributes, kept, and integer markers, kept) and .poly (a
 *    node section, which may say 0 points, meaning "read the .node file of
 *    the same name"; `nseg nbound`, `i a b [bmark]`, markers kept;
 *    `nholes`, `i x y`; then, if present, the regional attributes:
 *    `nregions`, `i x y attribute [maximum-area]`).
 *    `#` starts a comment, blank lines are skipped, and the index base (0
 *    or 1) is the first point's index; indices must then be consecutive.
 *  - JSON rings (an array of rings, each an array of [x, y]; the first
 *    outer, the others holes): each ring becomes a closed loop of segments
 *    (a ring of one point is a lone point; a last point equal to the first
 *    is dropped, so closed and open spellings agree).
 *  - The `nV nE` text of the CDT test inputs: nV lines `x y`, then nE lines
 *    `i j` (0-based).
 * Coordinates must be finite decimal numbers; counts are checked against
 * the file's size before anything is allocated.
 *
 * Writers: Triangle's .node/.ele/.poly (all three, from one name), and the
 * mesh formats of tsr_mesh_write (z = 0, coordinates rounded to float32).
 * Each file is written under a temporary name and renamed when complete. */
#ifndef TSR_PSLG_IO_H
#define TSR_PSLG_IO_H

#include "tessellate/tessellate.h"

typedef enum cli_pslg_format {
    CLI_PSLG_UNKNOWN = 0,
    CLI_PSLG_NODE,
    CLI_PSLG_POLY,
    CLI_PSLG_JSON, /* rings */
    CLI_PSLG_TXT   /* nV nE */
} cli_pslg_format;

/* An input graph and where it came from. Arrays are owned (malloc). */
typedef struct cli_pslg {
    double *xy; /* 2 per point */
    uint32_t nv;
    uint32_t *seg; /* 2 point indices per segment, 0-based */
    uint32_t nseg;
    double *holes; /* 2 per hole seed */
    uint32_t nholes;
    double *attr; /* .node attributes: nattr per point, or NULL */
    uint32_t nattr;
    int32_t *marker;     /* .node boundary markers, one per point, or NULL */
    int32_t *seg_marker; /* .poly segment markers, one per segment, or NULL */
    double *regions;     /* .poly regional attributes: x, y, attribute, maximum area (< 0: none) each */
    uint32_t nregions;
    char *points_file;    /* the .node a .poly of 0 points read its points from, or NULL */
    uint32_t first_index; /* Triangle's files: the input's numbering base (0 or 1), kept by the output; else 1 */
    cli_pslg_format format;
    uint32_t rings; /* JSON: rings read (including one-point rings) */
} cli_pslg;

/* The format named by a path's extension (.node, .poly, .json, .txt;
 * case-insensitive), or UNKNOWN. */
cli_pslg_format cli_pslg_format_from_path(const char *path);
/* "node", "poly", "json" or "txt" to a format; UNKNOWN otherwise. */
cli_pslg_format cli_pslg_format_parse(const char *name);
const char *cli_pslg_format_name(cli_pslg_format f);

/* Reads path in format f (UNKNOWN: from the extension; an unknown
 * extension is an error). On failure *out is empty. Errors: NOT_FOUND, IO,
 * EMPTY, FORMAT (malformed text or JSON), TRUNCATED (fewer records than the
 * counts say), TOO_LARGE (counts that cannot fit in the file, or beyond
 * 2^32 - 1), TOO_SMALL (no points), VALUE (non-finite coordinate, index out
 * of range), UNSUPPORTED (dimension other than 2). */
tsr_status cli_pslg_read(const char *path, cli_pslg_format f, cli_pslg *out, tsr_error *err);
void cli_pslg_free(cli_pslg *p);
/* A view of p for tsr_triangulate (pointers into p). */
tsr_pslg cli_pslg_view(const cli_pslg *p);

/* Output formats of a path: Triangle's files, or a mesh (tsr_mesh_write). */
typedef enum cli_tri_output { CLI_OUT_UNKNOWN = 0, CLI_OUT_TRIANGLE, CLI_OUT_MESH } cli_tri_output;
cli_tri_output cli_tri_output_from_path(const char *path);

/* The three files cli_tri_write_triangle writes for path (BASE.node,
 * BASE.ele, BASE.poly); false when a name does not fit in 4096 bytes. */
bool cli_tri_output_names(const char *path, char (*names)[4096]);

/* The .node file a .poly of 0 points reads its points from (BASE.node). */
void cli_pslg_node_path(const char *poly, char *buf, size_t cap);

/* For a path ending in .node, .ele or .poly, writes BASE.node, BASE.ele
 * (triangles) and BASE.poly, all three to temporary files first, renamed
 * only when all are complete.
 *  - BASE.node: vertices, numbered from g->first_index: g's points first, in input order (the
 *    k-th is vertex k, a repeated one too though no triangle uses it, as
 *    Triangle keeps them), then the Steiner points; with g's attributes,
 *    carried to the Steiner points by vals (t->nv rows of g->nattr, from
 *    tsr_tri_interpolate; NULL when g has none); and a boundary marker, by
 *    Triangle's rules: a point's own marker when not 0, else the marker
 *    (not 0) of an input segment it lies on, else 1 on the triangulation's
 *    boundary, else 0.
 *  - BASE.ele: with g's regional attributes, one attribute per triangle:
 *    that of the region it lies in (tsr_tri_regions; a later seed in the
 *    same region wins), 0 in none.
 *  - BASE.poly: 0 points (meaning BASE.node), the constrained edges as
 *    segments, g's hole seeds and g's regions. An edge's marker is its input segment's
 *    marker when g has segment markers (1 for a 0 on the boundary, as
 *    Triangle does), else the input segment's index + 1 (whatever the
 *    numbering base: a marker of 0 means none).
 * Every section is numbered from g->first_index, as Triangle keeps its
 * input's numbering. */
tsr_status cli_tri_write_triangle(const char *path, const tsr_triangulation *t, const cli_pslg *g, const double *vals,
                                  tsr_error *err);

/* Writes t as a mesh in the format of path's extension: z = 0, or, with
 * vals (t->nv rows of nvals), z = vals[v * nvals + z_col]. */
tsr_status cli_tri_write_mesh(const char *path, const tsr_triangulation *t, const double *vals, uint32_t nvals,
                              uint32_t z_col, tsr_error *err);

#endif
