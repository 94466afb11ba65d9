/* grid.c: the regular-grid mesh of a heightfield (every step-th sample). */
#include "terrain_internal.h"

#include <math.h>
#include <string.h>

void tsr_heightfield_normal_at(const tsr_heightfield *hf, uint32_t c, uint32_t r, float n[3])
{
    const float *d = hf->data;
    uint32_t w = hf->width, h = hf->height;
    float here = d[(size_t)r * w + c];
    /* central differences, one-sided at borders and next to no-data */
    double gx = 0, gy = 0;
    float l = c > 0 ? d[(size_t)r * w + c - 1] : NAN, rt = c + 1 < w ? d[(size_t)r * w + c + 1] : NAN;
    float u = r > 0 ? d[(size_t)(r - 1) * w + c] : NAN, dn = r + 1 < h ? d[(size_t)(r + 1) * w + c] : NAN;
    if (!isnan(l) && !isnan(rt))
        gx = (rt - l) / (2 * hf->dx);
    else if (!isnan(rt))
        gx = (rt - here) / hf->dx;
    else if (!isnan(l))
        gx = (here - l) / hf->dx;
    if (!isnan(u) && !isnan(dn))
        gy = (dn - u) / (2 * hf->dy);
    else if (!isnan(dn))
        gy = (dn - here) / hf->dy;
    else if (!isnan(u))
        gy = (here - u) / hf->dy;
    double nx = -gx * hf->dz, ny = -gy * hf->dz, nz = 1;
    double len = sqrt(nx * nx + ny * ny + nz * nz);
    n[0] = (float)(nx / len);
    n[1] = (float)(ny / len);
    n[2] = (float)(nz / len);
}

tsr_status tsr_terrain_grid_mesh(const tsr_heightfield *hf, uint32_t step, bool normals, tsr_mesh *mesh,
                                 tsr_error *err)
{
    if (step == 0)
        step = 1;
    uint32_t w = hf->width, h = hf->height;
    uint32_t nc = (w - 1 + step - 1) / step + 1, nr = (h - 1 + step - 1) / step + 1;
    const tsr_allocator *a = hf->alloc.realloc ? &hf->alloc : NULL;
    uint32_t *cols = tsr_alloc(a, (size_t)nc * sizeof *cols);
    uint32_t *rows = tsr_alloc(a, (size_t)nr * sizeof *rows);
    uint32_t *map = tsr_alloc(a, (size_t)nc * nr * sizeof *map);
    if (!cols || !rows || !map) {
        tsr_free(a, cols);
        tsr_free(a, rows);
        tsr_free(a, map);
        return tsr_error_set(err, TSR_ERR_NOMEM, "grid mesh: out of memory");
    }
    for (uint32_t i = 0; i < nc; i++)
        cols[i] = i + 1 == nc ? w - 1 : i * step;
    for (uint32_t i = 0; i < nr; i++)
        rows[i] = i + 1 == nr ? h - 1 : i * step;
    if ((uint64_t)nc * nr >= UINT32_MAX || 2ull * (nc - 1) * (nr - 1) >= UINT32_MAX / 3) {
        tsr_free(a, cols);
        tsr_free(a, rows);
        tsr_free(a, map);
        return tsr_error_set(err, TSR_ERR_TOO_LARGE, "grid mesh: %ux%u vertices exceed 32-bit indices; use a larger step",
                             nc, nr);
    }
    tsr_status s = tsr_mesh_reserve(mesh, nc * nr, 2 * (nc - 1) * (nr - 1));
    if (s == TSR_OK && normals && !(mesh->attributes & TSR_MESH_NORMALS))
        s = TSR_ERR_ARGUMENT;
    for (uint32_t j = 0; j < nr && s == TSR_OK; j++)
        for (uint32_t i = 0; i < nc; i++) {
            float hv = hf->data[(size_t)rows[j] * w + cols[i]];
            if (isnan(hv)) {
                map[(size_t)j * nc + i] = UINT32_MAX;
                continue;
            }
            float p[3] = {(float)(cols[i] * hf->dx), (float)(rows[j] * hf->dy), (float)(hv * hf->dz)}, n[3];
            if (normals)
                tsr_heightfield_normal_at(hf, cols[i], rows[j], n);
            map[(size_t)j * nc + i] = tsr_mesh_add_vertex(mesh, p, normals ? n : NULL, NULL);
        }
    /* two triangles per cell along the a-d diagonal, counter-clockwise from
     * +z; with one corner missing, the triangle of the other three */
    for (uint32_t j = 0; j + 1 < nr && s == TSR_OK; j++)
        for (uint32_t i = 0; i + 1 < nc; i++) {
            uint32_t va = map[(size_t)j * nc + i], vb = map[(size_t)j * nc + i + 1];
            uint32_t vc = map[(size_t)(j + 1) * nc + i], vd = map[(size_t)(j + 1) * nc + i + 1];
            int missing = (va == UINT32_MAX) + (vb == UINT32_MAX) + (vc == UINT32_MAX) + (vd == UINT32_MAX);
            bool ok = true;
            if (missing == 0) {
                ok = tsr_mesh_add_triangle(mesh, va, vb, vd) && tsr_mesh_add_triangle(mesh, va, vd, vc);
            } else if (missing == 1) {
                if (va == UINT32_MAX)
                    ok = tsr_mesh_add_triangle(mesh, vb, vd, vc);
                else if (vb == UINT32_MAX)
                    ok = tsr_mesh_add_triangle(mesh, va, vd, vc);
                else if (vc == UINT32_MAX)
                    ok = tsr_mesh_add_triangle(mesh, va, vb, vd);
                else
                    ok = tsr_mesh_add_triangle(mesh, va, vb, vc);
            }
            if (!ok)
                s = TSR_ERR_NOMEM;
        }
    tsr_free(a, cols);
    tsr_free(a, rows);
    tsr_free(a, map);
    if (s == TSR_ERR_ARGUMENT)
        return tsr_error_set(err, s, "grid mesh: normals asked but the mesh was initialised without them");
    if (s != TSR_OK)
        return tsr_error_set(err, s, "grid mesh: out of memory");
    return TSR_OK;
}
