/* triangulate_internal.h: the stages tsr_triangulate shares between its
 * two methods. Not installed; used by triangulate.c and qtri.c. */
#ifndef TSR_TRIANGULATE_INTERNAL_H
#define TSR_TRIANGULATE_INTERNAL_H

#include "tessellate/tessellate.h"

/* Quadtree method (qtri.c). Fills out with every triangle of the
 * quadtree's square (no region removal yet), the constrained edges with
 * their input segment ids, vertex_of_input, input_vertices, duplicates,
 * intersections, degenerate_segments and fallback_cells; out->alloc is set.
 * Output vertex order: the distinct input points first, then Steiner
 * points. Cells that cannot become simple within opt->max_depth are
 * triangulated by tsr_triangulate with TSR_TRI_DELAUNAY. When the method
 * does not apply to the whole input it returns TSR_ERR_UNSUPPORTED with
 * out empty, and tsr_triangulate falls back (fell_back, fallback_reason). */
tsr_status tsr__tri_quadtree(const tsr_pslg *in, const tsr_tri_options *opt, tsr_triangulation *out,
                             const tsr_allocator *alloc, const char **why_not, tsr_error *err);

/* As tsr__tri_quadtree, but where it can (no hole seeds, no cell through
 * the Delaunay fallback) it also chooses the region from the cells and
 * keeps only its triangles, exactly as tsr__tri_apply_region would (each
 * constrained edge listed once, with its lowest segment id; unused Steiner
 * points dropped); *region_done says whether it did. */
tsr_status tsr__tri_quadtree_region(const tsr_pslg *in, const tsr_tri_options *opt, tsr_triangulation *out,
                                    const tsr_allocator *alloc, bool *region_done, const char **why_not,
                                    tsr_error *err);

/* Region removal on a finished triangulation (both methods): keeps the
 * triangles of opt->region and in->holes, drops the rest, drops vertices no
 * longer used by a triangle only when they are Steiner points (input
 * vertices keep their ids), and keeps the constrained edges that still
 * border a kept triangle. */
tsr_status tsr__tri_apply_region(tsr_triangulation *t, const tsr_pslg *in, const tsr_tri_options *opt);

/* Does some region of opt give a maximum area (one above 0)? */
static inline bool tsr__tri_region_areas(const tsr_tri_options *opt)
{
    for (uint32_t r = 0; r < opt->nregions; r++)
        if (opt->regions[3 * (size_t)r + 2] > 0)
            return true;
    return false;
}

#endif
