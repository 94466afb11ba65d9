/* pslg_io.h: planar straight-line graphs in and triangulations out, for
 * `tessera triangulate`.
 *
 * Readers (each gives one error line naming the file and the line, or the
 * JSON position, and the problem; nothing is returned on failure):
 *  - Triangle's .node (`n dim nattr nbound`, then `i x y [attrs] [bmark]`)
 *    and .poly (a node section, which may say 0 points, meaning "read the
 *    .node file of the same name"; `nseg nbound`, `i a b [bmark]`;
 *    `nholes`, `i x y`; a regional attribute section, if any, is ignored).
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

/* For a path ending in .node, .ele or .poly, writes BASE.node (vertices,
 * 1-based: the ninput input points first, in input order (the k-th is
 * vertex k), a duplicate too though no triangle uses it, as Triangle keeps
 * them;
 * then the Steiner points), BASE.ele (triangles) and BASE.poly (0 points,
 * meaning BASE.node; the constrained edges as segments with marker =
 * input segment id + 1; the hole seeds given). All three are written to
 * temporary files first and renamed only when all are complete. */
tsr_status cli_tri_write_triangle(const char *path, const tsr_triangulation *t, uint32_t ninput, const double *holes,
                                  uint32_t nholes, tsr_error *err);

/* Writes t as a mesh (z = 0) in the format of path's extension. */
tsr_status cli_tri_write_mesh(const char *path, const tsr_triangulation *t, tsr_error *err);

#endif
