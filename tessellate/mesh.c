/* mesh.c: the indexed triangle mesh container. */
#include "tessellate/tessellate.h"

#include <math.h>
#include <string.h>

void tsr_mesh_init(tsr_mesh *m, unsigned attributes, const tsr_allocator *alloc)
{
    memset(m, 0, sizeof *m);
    if (alloc)
        m->alloc = *alloc;
    m->attributes = attributes & (TSR_MESH_NORMALS | TSR_MESH_UVS);
}

void tsr_mesh_free(tsr_mesh *m)
{
    tsr_allocator a = m->alloc;
    const tsr_allocator *ap = a.realloc ? &a : NULL;
    unsigned attributes = m->attributes;
    tsr_free(ap, m->positions);
    tsr_free(ap, m->normals);
    tsr_free(ap, m->uvs);
    tsr_free(ap, m->indices);
    memset(m, 0, sizeof *m);
    m->alloc = a;
    m->attributes = attributes;
}

static bool grow(const tsr_allocator *a, void **p, size_t count, size_t elem, bool dense)
{
    void *q = !*p && dense ? tsr_alloc_dense(a, count * elem) : tsr_realloc(a, *p, count * elem);
    if (!q)
        return false;
    *p = q;
    return true;
}

static tsr_status reserve(tsr_mesh *m, uint32_t vertices, uint32_t triangles, bool dense)
{
    const tsr_allocator *a = m->alloc.realloc ? &m->alloc : NULL;
    /* dense: arrays holding nothing yet are made anew rather than grown */
    if (dense && m->vertex_count == 0 && vertices > m->vertex_capacity) {
        tsr_free(a, m->positions), tsr_free(a, m->normals), tsr_free(a, m->uvs);
        m->positions = m->normals = m->uvs = NULL;
    }
    if (dense && m->triangle_count == 0 && triangles > m->triangle_capacity) {
        tsr_free(a, m->indices);
        m->indices = NULL;
    }
    if (vertices > m->vertex_capacity || !m->positions) {
        size_t cap = vertices > m->vertex_capacity ? vertices : m->vertex_capacity;
        if (cap == 0)
            cap = 16;
        if (!grow(a, (void **)&m->positions, cap, 3 * sizeof(float), dense))
            return TSR_ERR_NOMEM;
        if ((m->attributes & TSR_MESH_NORMALS) && !grow(a, (void **)&m->normals, cap, 3 * sizeof(float), dense))
            return TSR_ERR_NOMEM;
        if ((m->attributes & TSR_MESH_UVS) && !grow(a, (void **)&m->uvs, cap, 2 * sizeof(float), dense))
            return TSR_ERR_NOMEM;
        m->vertex_capacity = (uint32_t)cap;
    }
    if (triangles > m->triangle_capacity || !m->indices) {
        size_t cap = triangles > m->triangle_capacity ? triangles : m->triangle_capacity;
        if (cap == 0)
            cap = 16;
        if (!grow(a, (void **)&m->indices, cap, 3 * sizeof(uint32_t), dense))
            return TSR_ERR_NOMEM;
        m->triangle_capacity = (uint32_t)cap;
    }
    return TSR_OK;
}

tsr_status tsr_mesh_reserve(tsr_mesh *m, uint32_t vertices, uint32_t triangles)
{
    return reserve(m, vertices, triangles, false);
}

tsr_status tsr_mesh_reserve_dense(tsr_mesh *m, uint32_t vertices, uint32_t triangles)
{
    return reserve(m, vertices, triangles, true);
}

uint32_t tsr_mesh_add_vertex(tsr_mesh *m, const float p[3], const float *n, const float *uv)
{
    if (m->vertex_count == UINT32_MAX - 2)
        return UINT32_MAX;
    if (m->vertex_count >= m->vertex_capacity || !m->positions) {
        uint32_t cap = m->vertex_capacity < 16 ? 16 : m->vertex_capacity;
        while (cap <= m->vertex_count)
            cap = cap > UINT32_MAX / 2 ? UINT32_MAX - 1 : cap * 2;
        if (tsr_mesh_reserve(m, cap, m->triangle_capacity) != TSR_OK)
            return UINT32_MAX;
    }
    uint32_t i = m->vertex_count++;
    memcpy(m->positions + 3 * (size_t)i, p, 3 * sizeof(float));
    if (m->normals) {
        float z[3] = {0, 0, 1};
        memcpy(m->normals + 3 * (size_t)i, n ? n : z, 3 * sizeof(float));
    }
    if (m->uvs) {
        float z[2] = {0, 0};
        memcpy(m->uvs + 2 * (size_t)i, uv ? uv : z, 2 * sizeof(float));
    }
    return i;
}

bool tsr_mesh_add_triangle(tsr_mesh *m, uint32_t a, uint32_t b, uint32_t c)
{
    if (m->triangle_count >= m->triangle_capacity || !m->indices) {
        uint32_t cap = m->triangle_capacity < 16 ? 16 : m->triangle_capacity;
        while (cap <= m->triangle_count)
            cap = cap > UINT32_MAX / 2 ? UINT32_MAX - 1 : cap * 2;
        if (tsr_mesh_reserve(m, m->vertex_capacity, cap) != TSR_OK)
            return false;
    }
    uint32_t *t = m->indices + 3 * (size_t)m->triangle_count++;
    t[0] = a;
    t[1] = b;
    t[2] = c;
    return true;
}

tsr_status tsr_mesh_compute_normals(tsr_mesh *m)
{
    const tsr_allocator *a = m->alloc.realloc ? &m->alloc : NULL;
    if (!m->normals) {
        size_t cap = m->vertex_capacity ? m->vertex_capacity : 1;
        m->normals = tsr_alloc(a, cap * 3 * sizeof(float));
        if (!m->normals)
            return TSR_ERR_NOMEM;
        m->attributes |= TSR_MESH_NORMALS;
    }
    memset(m->normals, 0, (size_t)m->vertex_count * 3 * sizeof(float));
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *ix = m->indices + 3 * (size_t)t;
        if (ix[0] >= m->vertex_count || ix[1] >= m->vertex_count || ix[2] >= m->vertex_count)
            continue;
        const float *p0 = m->positions + 3 * (size_t)ix[0];
        const float *p1 = m->positions + 3 * (size_t)ix[1];
        const float *p2 = m->positions + 3 * (size_t)ix[2];
        double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        double e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
        for (int k = 0; k < 3; k++)
            for (int j = 0; j < 3; j++)
                m->normals[3 * (size_t)ix[k] + j] += (float)n[j];
    }
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        float *n = m->normals + 3 * (size_t)v;
        double l = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
        if (l > 0) {
            n[0] = (float)(n[0] / l);
            n[1] = (float)(n[1] / l);
            n[2] = (float)(n[2] / l);
        } else {
            n[0] = n[1] = 0;
            n[2] = 1;
        }
    }
    return TSR_OK;
}

uint32_t tsr_mesh_drop_unused(tsr_mesh *m, uint32_t first)
{
    if (first >= m->vertex_count)
        return 0;
    const tsr_allocator *a = m->alloc.realloc ? &m->alloc : NULL;
    uint32_t *to = tsr_alloc(a, ((size_t)m->vertex_count + 1) * sizeof *to);
    if (!to)
        return UINT32_MAX;
    for (uint32_t v = 0; v < m->vertex_count; v++)
        to[v] = v < first ? 0 : UINT32_MAX;
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count; i++)
        to[m->indices[i]] = 0;
    uint32_t n = 0;
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        if (to[v] == UINT32_MAX)
            continue;
        to[v] = n;
        if (n != v) {
            memcpy(m->positions + 3 * (size_t)n, m->positions + 3 * (size_t)v, 3 * sizeof *m->positions);
            if (m->normals)
                memcpy(m->normals + 3 * (size_t)n, m->normals + 3 * (size_t)v, 3 * sizeof *m->normals);
            if (m->uvs)
                memcpy(m->uvs + 2 * (size_t)n, m->uvs + 2 * (size_t)v, 2 * sizeof *m->uvs);
        }
        n++;
    }
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count; i++)
        m->indices[i] = to[m->indices[i]];
    uint32_t dropped = m->vertex_count - n;
    m->vertex_count = n;
    tsr_free(a, to);
    return dropped;
}
