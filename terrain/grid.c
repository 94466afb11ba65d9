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

/* The triangles a cell may have: along the a-d diagonal (a top left, b top
 * right, c bottom left, d bottom right) abd and adc; with one corner
 * no-data, the triangle of the other three. */
enum { CELL_ABD = 1, CELL_ADC = 2, CELL_BDC = 4, CELL_ABC = 8 };

/* The triangles of cell [x0, x1] x [y0, y1] that no no-data sample touches
 * (closed: a no-data sample on an edge rules the triangle out): with a step
 * above 1 the cell holds samples between its corners, and a triangle over
 * one would cover no-data. */
static unsigned cell_triangles(const tsr_heightfield *hf, uint32_t x0, uint32_t y0, uint32_t x1, uint32_t y1,
                               unsigned want)
{
    if (!want || (x1 - x0 <= 1 && y1 - y0 <= 1))
        return want;
    int64_t cw = x1 - x0, ch = y1 - y0;
    for (uint32_t y = y0; y <= y1 && want; y++) {
        const float *row = hf->data + (size_t)y * hf->width;
        for (uint32_t x = x0; x <= x1; x++) {
            if (!isnan(row[x]))
                continue;
            int64_t u = (int64_t)(x - x0) * ch, v = (int64_t)(y - y0) * cw, area = cw * ch;
            if (u >= v)
                want &= ~(unsigned)CELL_ABD;
            if (u <= v)
                want &= ~(unsigned)CELL_ADC;
            if (u + v >= area)
                want &= ~(unsigned)CELL_BDC;
            if (u + v <= area)
                want &= ~(unsigned)CELL_ABC;
        }
    }
    return want;
}

tsr_status tsr_terrain_grid_mesh(const tsr_heightfield *hf, uint32_t step, bool normals, tsr_mesh *mesh,
                                 tsr_error *err)
{
    if (step == 0)
        step = 1;
    uint32_t w = hf->width, h = hf->height;
    uint32_t nc = (w - 1 + step - 1) / step + 1, nr = (h - 1 + step - 1) / step + 1;
    if ((uint64_t)nc * nr >= UINT32_MAX || 2ull * (nc - 1) * (nr - 1) >= UINT32_MAX / 3)
        return tsr_error_set(err, TSR_ERR_TOO_LARGE, "grid mesh: %ux%u vertices exceed 32-bit indices; use a larger step",
                             nc, nr);
    if (normals && !(mesh->attributes & TSR_MESH_NORMALS))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "grid mesh: normals asked but the mesh was initialised without them");
    const tsr_allocator *a = hf->alloc.realloc ? &hf->alloc : NULL;
    uint32_t *cols = tsr_alloc(a, (size_t)nc * sizeof *cols);
    uint32_t *rows = tsr_alloc(a, (size_t)nr * sizeof *rows);
    uint32_t *map = tsr_alloc(a, (size_t)nc * nr * sizeof *map);
    unsigned char *tris = tsr_alloc(a, (size_t)(nc - 1) * (nr - 1) + 1);
    tsr_status s = cols && rows && map && tris ? TSR_OK : TSR_ERR_NOMEM;
    if (s == TSR_OK) {
        for (uint32_t i = 0; i < nc; i++)
            cols[i] = i + 1 == nc ? w - 1 : i * step;
        for (uint32_t i = 0; i < nr; i++)
            rows[i] = i + 1 == nr ? h - 1 : i * step;
        /* first the triangles of each cell, marking the lattice samples they
         * use (0 unused, then the vertex index + 1), so that no vertex is
         * written that no triangle references */
        memset(map, 0, (size_t)nc * nr * sizeof *map);
        uint32_t nv = 0, nt = 0;
        for (uint32_t j = 0; j + 1 < nr; j++)
            for (uint32_t i = 0; i + 1 < nc; i++) {
                const float *r0 = hf->data + (size_t)rows[j] * w, *r1 = hf->data + (size_t)rows[j + 1] * w;
                bool ha = !isnan(r0[cols[i]]), hb = !isnan(r0[cols[i + 1]]);
                bool hc = !isnan(r1[cols[i]]), hd = !isnan(r1[cols[i + 1]]);
                unsigned want = ha && hb && hc && hd ? CELL_ABD | CELL_ADC
                                : !ha && hb && hc && hd ? CELL_BDC
                                : ha && !hb && hc && hd ? CELL_ADC
                                : ha && hb && !hc && hd ? CELL_ABD
                                : ha && hb && hc && !hd ? CELL_ABC
                                                        : 0;
                want = cell_triangles(hf, cols[i], rows[j], cols[i + 1], rows[j + 1], want);
                tris[(size_t)j * (nc - 1) + i] = (unsigned char)want;
                size_t ia = (size_t)j * nc + i, ic = ia + nc;
                if (want & (CELL_ABD | CELL_ADC | CELL_ABC))
                    map[ia] = 1;
                if (want & (CELL_ABD | CELL_BDC | CELL_ABC))
                    map[ia + 1] = 1;
                if (want & (CELL_ADC | CELL_BDC | CELL_ABC))
                    map[ic] = 1;
                if (want & (CELL_ABD | CELL_ADC | CELL_BDC))
                    map[ic + 1] = 1;
                nt += (uint32_t)__builtin_popcount(want);
            }
        for (size_t k = 0; k < (size_t)nc * nr; k++)
            nv += map[k];
        s = tsr_mesh_reserve(mesh, nv, nt);
    }
    for (uint32_t j = 0; j < nr && s == TSR_OK; j++)
        for (uint32_t i = 0; i < nc; i++) {
            uint32_t *m = &map[(size_t)j * nc + i];
            if (!*m)
                continue;
            float hv = hf->data[(size_t)rows[j] * w + cols[i]];
            float p[3] = {(float)(cols[i] * hf->dx), (float)(rows[j] * hf->dy), (float)(hv * hf->dz)}, n[3];
            if (normals)
                tsr_heightfield_normal_at(hf, cols[i], rows[j], n);
            *m = tsr_mesh_add_vertex(mesh, p, normals ? n : NULL, NULL) + 1;
        }
    /* counter-clockwise from +z */
    for (uint32_t j = 0; j + 1 < nr && s == TSR_OK; j++)
        for (uint32_t i = 0; i + 1 < nc; i++) {
            unsigned t = tris[(size_t)j * (nc - 1) + i];
            size_t ia = (size_t)j * nc + i, ic = ia + nc;
            uint32_t va = map[ia] - 1, vb = map[ia + 1] - 1, vc = map[ic] - 1, vd = map[ic + 1] - 1;
            bool ok = true;
            if (t & CELL_ABD)
                ok = ok && tsr_mesh_add_triangle(mesh, va, vb, vd);
            if (t & CELL_ADC)
                ok = ok && tsr_mesh_add_triangle(mesh, va, vd, vc);
            if (t & CELL_BDC)
                ok = ok && tsr_mesh_add_triangle(mesh, vb, vd, vc);
            if (t & CELL_ABC)
                ok = ok && tsr_mesh_add_triangle(mesh, va, vb, vc);
            if (!ok)
                s = TSR_ERR_NOMEM;
        }
    tsr_free(a, cols);
    tsr_free(a, rows);
    tsr_free(a, map);
    tsr_free(a, tris);
    if (s != TSR_OK)
        return tsr_error_set(err, s, "grid mesh: out of memory");
    return TSR_OK;
}
