// subd.cpp: the one bridge from Tessera's C to OpenSubdiv's C++ API, for
// subdivision surfaces evaluated per base face.
//
// Algorithms: Catmull and Clark, "Recursively generated B-spline surfaces
// on arbitrary topological meshes" (CAD 1978), with the semi-sharp creases
// of DeRose, Kass and Truong, "Subdivision surfaces in character
// animation" (SIGGRAPH 1998), as OpenSubdiv 3.5 implements them; limit
// evaluation by Bfr (OpenSubdiv's "base face representation"): exact
// bicubic B-spline patches (Stam's observation that a regular face's limit
// is the uniform B-spline of its 16 control points) and, around irregular
// features, a tree of patches refined towards them and capped by Gregory
// patches (Loop, Schaefer, Ni and Castano, "Approximating subdivision
// surfaces with Gregory patches for hardware tessellation", 2009).
//
// Nothing here throws into C: every extern "C" function catches
// everything, and bad input is found before OpenSubdiv sees it, so that
// OpenSubdiv's global error and warning callbacks (which print to stdout
// by default) are never reached for input Tessera accepts or refuses.
#include "patches/subd.h"

#include <opensubdiv/bfr/refinerSurfaceFactory.h>
#include <opensubdiv/bfr/surface.h>
#include <opensubdiv/bfr/surfaceFactoryCache.h>
#include <opensubdiv/bfr/tessellation.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

#include <algorithm>
#include <cfloat>
#include <climits>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <new>
#include <shared_mutex>
#include <vector>

using namespace OpenSubdiv;

namespace
{

// std::allocator over a tsr_allocator, so Tessera's own tables come from
// the caller's allocator.
template <class T> struct Alloc {
    using value_type = T;
    tsr_allocator a;
    explicit Alloc(const tsr_allocator &x) : a(x) {}
    template <class U> Alloc(const Alloc<U> &o) : a(o.a) {}
    T *allocate(size_t n)
    {
        if (n > SIZE_MAX / sizeof(T))
            throw std::bad_alloc();
        void *p = tsr_alloc(a.realloc ? &a : nullptr, n * sizeof(T));
        if (!p)
            throw std::bad_alloc();
        return static_cast<T *>(p);
    }
    void deallocate(T *p, size_t) { tsr_free(a.realloc ? &a : nullptr, p); }
    template <class U> bool operator==(const Alloc<U> &o) const
    {
        return a.realloc == o.a.realloc && a.user == o.a.user;
    }
    template <class U> bool operator!=(const Alloc<U> &o) const { return !(*this == o); }
};

template <class T> using Vec = std::vector<T, Alloc<T>>;

typedef Bfr::RefinerSurfaceFactory<Bfr::SurfaceFactoryCacheThreaded<
    std::shared_mutex, std::shared_lock<std::shared_mutex>, std::unique_lock<std::shared_mutex>>>
    Factory;
typedef Bfr::Surface<double> Surface;
typedef Surface::PointDescriptor Desc;

const uint32_t NONE = UINT32_MAX;
// Faces around one vertex: each adds at most two edges there, and
// OpenSubdiv's limit on a vertex's edges is 65535 (Vtr::VALENCE_LIMIT).
const uint32_t MAX_VERTEX_FACES = 16384;

// A face's Bfr surface and the patch points it evaluates from.
struct Prepared {
    int64_t face = -1;
    Surface surf;
    Vec<double> pts;
    explicit Prepared(const tsr_allocator &a) : pts(Alloc<double>(a)) {}
};

} // namespace

struct tsr_subd {
    tsr_allocator alloc;
    Sdc::SchemeType scheme;
    uint32_t num_faces;
    Vec<double> points;       // 3 per cage point
    Vec<uint32_t> face_off;   // num_faces + 1 offsets into verts
    Vec<uint32_t> verts;      // face vertices
    Vec<uint32_t> slot_face;  // per face-vertex slot: its face
    Vec<uint32_t> slot_edge;  // per slot i of a face: the edge from vertex i to i+1
    Vec<uint32_t> slot_twin;  // per slot: the opposite slot of a manifold edge, else NONE
    Vec<uint32_t> edge_first; // per edge: its lower vertex (the canonical start)
    Vec<uint8_t> has_limit;   // per face
    std::unique_ptr<Far::TopologyRefiner> refiner;
    std::unique_ptr<Factory> factory;
    mutable std::mutex mu; // guards `cache`
    mutable Prepared cache;

    explicit tsr_subd(const tsr_allocator &a)
        : alloc(a), scheme(Sdc::SCHEME_CATMARK), num_faces(0), points(Alloc<double>(a)), face_off(Alloc<uint32_t>(a)),
          verts(Alloc<uint32_t>(a)), slot_face(Alloc<uint32_t>(a)), slot_edge(Alloc<uint32_t>(a)),
          slot_twin(Alloc<uint32_t>(a)), edge_first(Alloc<uint32_t>(a)), has_limit(Alloc<uint8_t>(a)), cache(a)
    {
    }
};

namespace
{

uint32_t face_size(const tsr_subd *s, uint32_t f)
{
    return s->face_off[f + 1] - s->face_off[f];
}

// Initialises the face's surface and its patch points into p (kept when p
// already holds the face).
bool prepare(const tsr_subd *s, uint32_t face, Prepared &p)
{
    if (p.face == (int64_t)face)
        return true;
    p.face = -1;
    if (!s->factory->InitVertexSurface<double>((int)face, &p.surf))
        return false;
    p.pts.resize((size_t)p.surf.GetNumPatchPoints() * 3);
    p.surf.PreparePatchPoints(s->points.data(), Desc(3), p.pts.data(), Desc(3));
    p.face = face;
    return true;
}

// Runs fn(prepared) with the shared cache when it is free, else with a
// private preparation, so concurrent callers never wait on each other.
template <class Fn> tsr_status with_face(const tsr_subd *s, uint32_t face, Fn fn)
{
    std::unique_lock<std::mutex> lock(s->mu, std::try_to_lock);
    if (lock.owns_lock()) {
        if (!prepare(s, face, s->cache))
            return TSR_ERR_ARGUMENT;
        return fn(s->cache);
    }
    Prepared local(s->alloc);
    if (!prepare(s, face, local))
        return TSR_ERR_ARGUMENT;
    return fn(local);
}

bool patch_ok(const tsr_subd *s, uint32_t face, uint32_t sub)
{
    if (face >= s->num_faces || !s->has_limit[face])
        return false;
    uint32_t n = face_size(s, face);
    return sub < (n == 4 ? 1u : n);
}

double clamp01(double x)
{
    return std::fmin(std::fmax(x, 0.0), 1.0);
} // NaN -> 0

// Patch (sub, st) to the face's Bfr coordinate.
void face_coord(const Bfr::Parameterization &param, uint32_t sub, const double st[2], double uv[2])
{
    double c[2] = {clamp01(st[0]), clamp01(st[1])};
    if (param.HasSubFaces())
        param.ConvertNormalizedSubFaceToCoord<double>((int)sub, c, uv);
    else
        uv[0] = c[0], uv[1] = c[1];
}

// Unit du x dv; false where it vanishes or is tiny against |du| |dv|.
bool unit_cross(const double a[3], const double b[3], double n[3])
{
    double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    double len = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    double lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    if (!(len > 1e-10 * la * lb) || !std::isfinite(len) || len == 0)
        return false;
    for (int k = 0; k < 3; k++)
        n[k] = c[k] / len;
    return true;
}

// The normal of patch (sub, st) with the fallback towards the centre.
bool normal_at(const Prepared &p, uint32_t sub, const double st[2], double n[3])
{
    Bfr::Parameterization param = p.surf.GetParameterization();
    static const double step[] = {0, 1e-7, 1e-5, 1e-3};
    double c[2] = {clamp01(st[0]), clamp01(st[1])};
    for (double h : step) {
        double q[2], uv[2], P[3], Du[3], Dv[3];
        for (int k = 0; k < 2; k++)
            q[k] = c[k] + (c[k] < 0.5 ? h : c[k] > 0.5 ? -h : 0);
        face_coord(param, sub, q, uv);
        p.surf.Evaluate(uv, p.pts.data(), Desc(3), P, Du, Dv);
        if (unit_cross(Du, Dv, n))
            return true;
    }
    n[0] = n[1] = n[2] = 0;
    return false;
}

// Where edge e of a patch lies on its face's boundary: face edge i, with
// w = alpha + beta t the position along the face edge (0 at vertex i, 1 at
// vertex i+1); false for the edges inside an N-gon.
bool on_face_edge(uint32_t n, uint32_t sub, uint32_t e, uint32_t *i, double *alpha, double *beta)
{
    if (n == 4) {
        // south v0->v1 and east v1->v2 run with t; north v2->v3 and west
        // v3->v0 against it.
        *i = e;
        *alpha = e < 2 ? 0.0 : 1.0;
        *beta = e < 2 ? 1.0 : -1.0;
        return true;
    }
    if (e == 0) { // first half of edge sub, from its vertex sub
        *i = sub, *alpha = 0.0, *beta = 0.5;
        return true;
    }
    if (e == 3) { // second half of edge sub-1, vertex sub at t = 0
        *i = (sub + n - 1) % n, *alpha = 1.0, *beta = -0.5;
        return true;
    }
    return false;
}

// The patch edges along face edge i: (sub, edge, alpha, beta) as above.
struct Piece {
    uint32_t sub, edge;
    double alpha, beta;
};

int edge_pieces(uint32_t n, uint32_t i, Piece out[2])
{
    if (n == 4) {
        out[0] = {0, i, i < 2 ? 0.0 : 1.0, i < 2 ? 1.0 : -1.0};
        return 1;
    }
    out[0] = {i, 0, 0.0, 0.5};
    out[1] = {(i + 1) % n, 3, 1.0, -0.5};
    return 2;
}

// The cage's edges: sorted (lower vertex, upper vertex) records.
struct HalfEdge {
    uint32_t lo, hi, slot;
    bool operator<(const HalfEdge &o) const { return lo != o.lo ? lo < o.lo : hi != o.hi ? hi < o.hi : slot < o.slot; }
};

tsr_status build_edges(tsr_subd *s, Vec<HalfEdge> &he)
{
    size_t nslots = s->verts.size();
    he.resize(nslots);
    s->slot_face.resize(nslots);
    for (uint32_t f = 0; f < s->num_faces; f++) {
        uint32_t o = s->face_off[f], n = face_size(s, f);
        for (uint32_t i = 0; i < n; i++) {
            uint32_t a = s->verts[o + i], b = s->verts[o + (i + 1) % n];
            he[o + i] = {std::min(a, b), std::max(a, b), o + i};
            s->slot_face[o + i] = f;
        }
    }
    std::sort(he.begin(), he.end());
    s->slot_edge.assign(nslots, NONE);
    s->slot_twin.assign(nslots, NONE);
    s->edge_first.clear();
    for (size_t k = 0; k < nslots;) {
        size_t m = k;
        while (m < nslots && he[m].lo == he[k].lo && he[m].hi == he[k].hi)
            m++;
        uint32_t e = (uint32_t)s->edge_first.size();
        s->edge_first.push_back(he[k].lo);
        for (size_t j = k; j < m; j++)
            s->slot_edge[he[j].slot] = e;
        // Manifold: two slots, a proper edge, traversed both ways.
        if (m - k == 2 && he[k].lo != he[k].hi) {
            uint32_t a = he[k].slot, b = he[k + 1].slot;
            if (s->verts[a] != s->verts[b]) {
                s->slot_twin[a] = b;
                s->slot_twin[b] = a;
            }
        }
        k = m;
    }
    return TSR_OK;
}

bool has_edge(const Vec<HalfEdge> &he, uint32_t a, uint32_t b)
{
    HalfEdge key = {std::min(a, b), std::max(a, b), 0};
    auto it = std::lower_bound(he.begin(), he.end(), key);
    return it != he.end() && it->lo == key.lo && it->hi == key.hi;
}

tsr_status create(const tsr_cage *c, tsr_subd_scheme scheme, const tsr_allocator *alloc, tsr_subd **out, tsr_error *err)
{
    if (!c)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "subdivision cage: NULL cage");
    if (scheme != TSR_SUBD_CATMARK && scheme != TSR_SUBD_BILINEAR)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "subdivision cage: unknown scheme %d", (int)scheme);
    if (c->boundary_interp < 0 || c->boundary_interp > 2)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "subdivision cage: boundary interpolation %d is not 0, 1 or 2",
                             c->boundary_interp);
    if (c->fvar_interp < 0 || c->fvar_interp > 5)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "subdivision cage: face-varying interpolation %d is not 0..5",
                             c->fvar_interp);
    if (c->crease_method < 0 || c->crease_method > 1 || c->triangle_subdiv < 0 || c->triangle_subdiv > 1)
        return tsr_error_set(err, TSR_ERR_ARGUMENT,
                             "subdivision cage: creasing method %d or triangle rule %d is not 0 or 1", c->crease_method,
                             c->triangle_subdiv);
    if (c->num_points == 0 || c->num_faces == 0)
        return tsr_error_set(err, TSR_ERR_EMPTY, "subdivision cage: empty (%u points, %u faces)", c->num_points,
                             c->num_faces);
    if (c->num_points > INT_MAX / 3 || c->num_faces > INT_MAX)
        return tsr_error_set(err, TSR_ERR_TOO_LARGE,
                             "subdivision cage: %u points and %u faces exceed OpenSubdiv's limits", c->num_points,
                             c->num_faces);
    if (!c->points || !c->face_sizes || !c->face_verts)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "subdivision cage: NULL points or faces");
    if ((c->num_creases && (!c->crease_verts || !c->crease_sharpness)) ||
        (c->num_corners && (!c->corner_verts || !c->corner_sharpness)) || (c->num_holes && !c->hole_faces))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "subdivision cage: NULL crease, corner or hole arrays");
    for (uint32_t p = 0; p < c->num_points; p++)
        for (int k = 0; k < 3; k++)
            if (!std::isfinite(c->points[3 * (size_t)p + k]))
                return tsr_error_set(err, TSR_ERR_VALUE, "subdivision cage: point %u has a non-finite coordinate", p);
    uint64_t total = 0;
    for (uint32_t f = 0; f < c->num_faces; f++) {
        uint32_t n = c->face_sizes[f];
        if (n < 3)
            return tsr_error_set(err, TSR_ERR_VALUE, "subdivision cage: face %u has %u vertices (at least 3 needed)", f,
                                 n);
        if (n > TSR_SUBD_MAX_FACE_SIZE)
            return tsr_error_set(err, TSR_ERR_VALUE, "subdivision cage: face %u has %u vertices (at most %u)", f, n,
                                 TSR_SUBD_MAX_FACE_SIZE);
        total += n;
    }
    if (total > INT_MAX)
        return tsr_error_set(err, TSR_ERR_TOO_LARGE, "subdivision cage: %llu face vertices exceed OpenSubdiv's limits",
                             (unsigned long long)total);

    tsr_allocator a = alloc ? *alloc : tsr_allocator{nullptr, nullptr, nullptr};
    Alloc<uint32_t> ua(a);
    Vec<uint32_t> valence(c->num_points, 0, ua);
    {
        uint64_t o = 0;
        for (uint32_t f = 0; f < c->num_faces; f++)
            for (uint32_t i = 0; i < c->face_sizes[f]; i++, o++) {
                uint32_t v = c->face_verts[o];
                if (v >= c->num_points)
                    return tsr_error_set(err, TSR_ERR_VALUE,
                                         "subdivision cage: face %u names vertex %u, but there are %u points", f, v,
                                         c->num_points);
                if (++valence[v] > MAX_VERTEX_FACES)
                    return tsr_error_set(err, TSR_ERR_VALUE, "subdivision cage: vertex %u is in more than %u faces", v,
                                         MAX_VERTEX_FACES);
            }
    }
    for (uint32_t k = 0; k < c->num_corners; k++) {
        if (c->corner_verts[k] >= c->num_points)
            return tsr_error_set(err, TSR_ERR_VALUE,
                                 "subdivision cage: corner %u names vertex %u, but there are %u points", k,
                                 c->corner_verts[k], c->num_points);
        if (!(c->corner_sharpness[k] >= 0))
            return tsr_error_set(err, TSR_ERR_VALUE, "subdivision cage: corner %u has sharpness %g (must be >= 0)", k,
                                 (double)c->corner_sharpness[k]);
    }
    for (uint32_t k = 0; k < c->num_holes; k++)
        if (c->hole_faces[k] >= c->num_faces)
            return tsr_error_set(err, TSR_ERR_VALUE, "subdivision cage: hole %u names face %u, but there are %u faces",
                                 k, c->hole_faces[k], c->num_faces);

    void *mem = tsr_alloc(alloc, sizeof(tsr_subd));
    if (!mem)
        return tsr_error_set(err, TSR_ERR_NOMEM, "subdivision cage: out of memory");
    std::unique_ptr<tsr_subd, void (*)(tsr_subd *)> s(new (mem) tsr_subd(a), tsr_subd_destroy);
    s->scheme = scheme == TSR_SUBD_BILINEAR ? Sdc::SCHEME_BILINEAR : Sdc::SCHEME_CATMARK;
    s->num_faces = c->num_faces;
    s->points.assign(c->points, c->points + 3 * (size_t)c->num_points);
    s->verts.assign(c->face_verts, c->face_verts + total);
    s->face_off.resize((size_t)c->num_faces + 1);
    s->face_off[0] = 0;
    for (uint32_t f = 0; f < c->num_faces; f++)
        s->face_off[f + 1] = s->face_off[f] + c->face_sizes[f];

    Vec<HalfEdge> he{Alloc<HalfEdge>(a)};
    build_edges(s.get(), he);
    for (uint32_t k = 0; k < c->num_creases; k++) {
        uint32_t v0 = c->crease_verts[2 * (size_t)k], v1 = c->crease_verts[2 * (size_t)k + 1];
        if (v0 >= c->num_points || v1 >= c->num_points || v0 == v1 || !has_edge(he, v0, v1))
            return tsr_error_set(err, TSR_ERR_VALUE, "subdivision cage: crease %u (%u, %u) is not an edge of the cage",
                                 k, v0, v1);
        if (!(c->crease_sharpness[k] >= 0))
            return tsr_error_set(err, TSR_ERR_VALUE, "subdivision cage: crease %u has sharpness %g (must be >= 0)", k,
                                 (double)c->crease_sharpness[k]);
    }

    // OpenSubdiv takes int indices; everything was range-checked above.
    Vec<int> sizes(c->face_sizes, c->face_sizes + c->num_faces, Alloc<int>(a));
    Vec<int> fverts(c->face_verts, c->face_verts + total, Alloc<int>(a));
    Vec<int> creases(c->crease_verts, c->crease_verts + 2 * (size_t)c->num_creases, Alloc<int>(a));
    Vec<int> corners(c->corner_verts, c->corner_verts + c->num_corners, Alloc<int>(a));
    Vec<int> holes(c->hole_faces, c->hole_faces + c->num_holes, Alloc<int>(a));
    Far::TopologyDescriptor desc;
    desc.numVertices = (int)c->num_points;
    desc.numFaces = (int)c->num_faces;
    desc.numVertsPerFace = sizes.data();
    desc.vertIndicesPerFace = fverts.data();
    desc.numCreases = (int)c->num_creases;
    desc.creaseVertexIndexPairs = creases.data();
    desc.creaseWeights = c->crease_sharpness;
    desc.numCorners = (int)c->num_corners;
    desc.cornerVertexIndices = corners.data();
    desc.cornerWeights = c->corner_sharpness;
    desc.numHoles = (int)c->num_holes;
    desc.holeIndices = holes.data();

    Sdc::Options sdc;
    sdc.SetVtxBoundaryInterpolation((Sdc::Options::VtxBoundaryInterpolation)c->boundary_interp);
    sdc.SetFVarLinearInterpolation((Sdc::Options::FVarLinearInterpolation)c->fvar_interp);
    sdc.SetCreasingMethod(c->crease_method ? Sdc::Options::CREASE_CHAIKIN : Sdc::Options::CREASE_UNIFORM);
    sdc.SetTriangleSubdivision(c->triangle_subdiv ? Sdc::Options::TRI_SUB_SMOOTH : Sdc::Options::TRI_SUB_CATMARK);
    typedef Far::TopologyRefinerFactory<Far::TopologyDescriptor> RefinerFactory;
    s->refiner.reset(RefinerFactory::Create(desc, RefinerFactory::Options(s->scheme, sdc)));
    if (!s->refiner)
        return tsr_error_set(err, TSR_ERR_INVALID_MESH, "subdivision cage: OpenSubdiv refused its topology");
    s->factory.reset(new Factory(*s->refiner));

    s->has_limit.assign(c->num_faces, 0);
    Surface probe;
    for (uint32_t f = 0; f < c->num_faces; f++)
        s->has_limit[f] =
            s->factory->FaceHasLimitSurface((int)f) && s->factory->InitVertexSurface<double>((int)f, &probe);
    *out = s.release();
    return TSR_OK;
}

// The faces listed (faces NULL: all, in order), as
// tsr_subd_tessellate_uniform_faces says.
tsr_status tessellate(const tsr_subd *s, uint32_t rate, const uint32_t *faces, uint32_t num_faces, tsr_mesh *m,
                      tsr_error *err)
{
    if (!faces)
        num_faces = s->num_faces;
    Bfr::Tessellation::Options topt;
    topt.SetFacetSize(3);

    // Sizes first, so the mesh grows once and nothing is added on failure.
    uint64_t nv = 0, nt = 0;
    {
        std::vector<std::pair<uint32_t, std::pair<uint64_t, uint64_t>>> per_size; // face size -> coords, facets
        for (uint32_t q = 0; q < num_faces; q++) {
            uint32_t f = faces ? faces[q] : q;
            if (!s->has_limit[f])
                continue;
            uint32_t n = face_size(s, f);
            auto it = std::find_if(per_size.begin(), per_size.end(), [n](const auto &x) { return x.first == n; });
            if (it == per_size.end()) {
                Bfr::Tessellation t(Bfr::Parameterization(s->scheme, (int)n), (int)rate, topt);
                if (!t.IsValid())
                    return tsr_error_set(err, TSR_ERR_UNSUPPORTED,
                                         "uniform tessellation: Bfr cannot tessellate a %u-gon", n);
                per_size.push_back({n, {(uint64_t)t.GetNumCoords(), (uint64_t)t.GetNumFacets()}});
                it = per_size.end() - 1;
            }
            nv += it->second.first; // an upper bound: shared points counted per face
            nt += it->second.second;
        }
    }
    if (nv + m->vertex_count > UINT32_MAX - 1 || nt + m->triangle_count > UINT32_MAX - 1)
        return tsr_error_set(
            err, TSR_ERR_TOO_LARGE,
            "uniform tessellation: rate %u could give %llu vertices and %llu triangles (at most 2^32-2)", rate,
            (unsigned long long)nv, (unsigned long long)nt);
    uint32_t v0 = m->vertex_count, t0 = m->triangle_count;
    if (tsr_mesh_reserve(m, (uint32_t)(v0 + nv), (uint32_t)(t0 + nt)) != TSR_OK)
        return tsr_error_set(err, TSR_ERR_NOMEM, "uniform tessellation: out of memory for %llu triangles",
                             (unsigned long long)nt);

    Alloc<uint32_t> ua(s->alloc);
    size_t per_edge = rate - 1;
    Vec<uint32_t> vert_at((size_t)s->points.size() / 3, NONE, ua);
    Vec<uint32_t> edge_at(s->edge_first.size() * per_edge, NONE, ua);
    Vec<uint32_t> local(ua);
    Vec<double> coords{Alloc<double>(s->alloc)};
    std::vector<int> facets;
    Prepared p(s->alloc);
    bool normals = (m->attributes & TSR_MESH_NORMALS) != 0;
    const float zero_uv[2] = {0, 0};

    for (uint32_t q = 0; q < num_faces; q++) {
        uint32_t f = faces ? faces[q] : q;
        if (!s->has_limit[f])
            continue;
        if (!prepare(s, f, p)) {
            m->vertex_count = v0, m->triangle_count = t0;
            return tsr_error_set(err, TSR_ERR_UNSUPPORTED, "uniform tessellation: Bfr cannot evaluate face %u", f);
        }
        Bfr::Parameterization param = p.surf.GetParameterization();
        Bfr::Tessellation tess(param, (int)rate, topt);
        uint32_t n = face_size(s, f), o = s->face_off[f];
        int nc = tess.GetNumCoords(), nb = tess.GetNumBoundaryCoords();
        coords.resize(2 * (size_t)nc);
        tess.GetCoords(coords.data());
        facets.resize(3 * (size_t)tess.GetNumFacets());
        tess.GetFacets(facets.data());
        local.assign((size_t)nc, NONE);
        // Boundary points come vertex 0, the points inside edge 0, vertex 1,
        // ...: rate per edge. Each maps to its cage vertex or edge point.
        for (int b = 0; b < nc; b++) {
            uint32_t *slot = nullptr;
            if (b < nb && (uint32_t)nb == n * rate) {
                uint32_t i = (uint32_t)b / rate, j = (uint32_t)b % rate;
                uint32_t vi = s->verts[o + i];
                if (j == 0) {
                    slot = &vert_at[vi];
                } else {
                    uint32_t e = s->slot_edge[o + i];
                    uint32_t vn = s->verts[o + (i + 1) % n];
                    if (vi != vn)
                        slot = &edge_at[(size_t)e * per_edge + (vi == s->edge_first[e] ? j : rate - j) - 1];
                }
            }
            if (slot && *slot != NONE) {
                local[(size_t)b] = *slot;
                continue;
            }
            double P[3], Du[3], Dv[3], nrm[3] = {0, 0, 0};
            const double *uv = &coords[2 * (size_t)b];
            p.surf.Evaluate(uv, p.pts.data(), Desc(3), P, Du, Dv);
            if (normals && !unit_cross(Du, Dv, nrm)) {
                double st[2];
                int sub = 0;
                if (param.HasSubFaces())
                    sub = param.ConvertCoordToNormalizedSubFace<double>(uv, st);
                else
                    st[0] = uv[0], st[1] = uv[1];
                normal_at(p, (uint32_t)sub, st, nrm);
            }
            float pf[3] = {(float)P[0], (float)P[1], (float)P[2]};
            float nf[3] = {(float)nrm[0], (float)nrm[1], (float)nrm[2]};
            uint32_t id = tsr_mesh_add_vertex(m, pf, nf, zero_uv);
            if (id == UINT32_MAX) {
                m->vertex_count = v0, m->triangle_count = t0;
                return tsr_error_set(err, TSR_ERR_NOMEM, "uniform tessellation: out of memory");
            }
            local[(size_t)b] = id;
            if (slot)
                *slot = id;
        }
        for (size_t t = 0; t < facets.size(); t += 3)
            if (!tsr_mesh_add_triangle(m, local[(size_t)facets[t]], local[(size_t)facets[t + 1]],
                                       local[(size_t)facets[t + 2]])) {
                m->vertex_count = v0, m->triangle_count = t0;
                return tsr_error_set(err, TSR_ERR_NOMEM, "uniform tessellation: out of memory");
            }
    }
    return TSR_OK;
}

} // namespace

// ---- C interface -------------------------------------------------------

extern "C" tsr_status tsr_subd_create(const tsr_cage *cage, tsr_subd_scheme scheme, const tsr_allocator *alloc,
                                      tsr_subd **out, tsr_error *err)
{
    if (!out)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "subdivision cage: NULL output");
    *out = nullptr;
    try {
        return create(cage, scheme, alloc, out, err);
    } catch (const std::bad_alloc &) {
        return tsr_error_set(err, TSR_ERR_NOMEM, "subdivision cage: out of memory");
    } catch (const std::exception &e) {
        return tsr_error_set(err, TSR_ERR_INVALID_MESH, "subdivision cage: OpenSubdiv failed (%s)", e.what());
    } catch (...) {
        return tsr_error_set(err, TSR_ERR_INVALID_MESH, "subdivision cage: OpenSubdiv failed");
    }
}

extern "C" void tsr_subd_destroy(tsr_subd *s)
{
    if (!s)
        return;
    tsr_allocator a = s->alloc;
    s->~tsr_subd();
    tsr_free(a.realloc ? &a : nullptr, s);
}

extern "C" uint32_t tsr_subd_face_count(const tsr_subd *s)
{
    return s ? s->num_faces : 0;
}

extern "C" bool tsr_subd_has_allocator(const tsr_subd *s)
{
    return s && s->alloc.realloc != nullptr;
}

extern "C" uint32_t tsr_subd_face_size(const tsr_subd *s, uint32_t face)
{
    return s && face < s->num_faces ? face_size(s, face) : 0;
}

extern "C" bool tsr_subd_face_has_limit(const tsr_subd *s, uint32_t face)
{
    return s && face < s->num_faces && s->has_limit[face];
}

extern "C" uint32_t tsr_subd_face_patches(const tsr_subd *s, uint32_t face)
{
    if (!s || face >= s->num_faces)
        return 0;
    uint32_t n = face_size(s, face);
    return n == 4 ? 1 : n;
}

extern "C" uint32_t tsr_subd_patch_neighbours(const tsr_subd *s, uint32_t face, uint32_t sub, uint32_t edge,
                                              tsr_subd_link out[2])
{
    if (!s || !out || edge > 3 || !patch_ok(s, face, sub))
        return 0;
    uint32_t n = face_size(s, face);
    uint32_t i;
    double alpha, beta;
    if (!on_face_edge(n, sub, edge, &i, &alpha, &beta)) {
        // Inside an N-gon: east of k is north of k+1, and north of k is
        // east of k-1; both run from the edge midpoint to the centre.
        uint32_t k = edge == 1 ? (sub + 1) % n : (sub + n - 1) % n;
        out[0] = {face, k, edge == 1 ? 2u : 1u, false, 0.0, 1.0, 0.0, 1.0};
        return 1;
    }
    uint32_t slot = s->face_off[face] + i, twin = s->slot_twin[slot];
    if (twin == NONE)
        return 0;
    uint32_t g = s->slot_face[twin], j = twin - s->face_off[g];
    if (!s->has_limit[g])
        return 0;
    // Along the shared edge, w on this face is 1 - w on the other.
    double wa = std::min(alpha, alpha + beta), wb = std::max(alpha, alpha + beta);
    Piece pc[2];
    int np = edge_pieces(face_size(s, g), j, pc);
    uint32_t count = 0;
    for (int q = 0; q < np; q++) {
        double ga = 1 - std::max(pc[q].alpha, pc[q].alpha + pc[q].beta);
        double gb = 1 - std::min(pc[q].alpha, pc[q].alpha + pc[q].beta);
        double lo = std::max(wa, ga), hi = std::min(wb, gb);
        if (!(hi > lo))
            continue;
        double ta = (lo - alpha) / beta, tb = (hi - alpha) / beta;
        double sa = ((1 - lo) - pc[q].alpha) / pc[q].beta, sb = ((1 - hi) - pc[q].alpha) / pc[q].beta;
        if (ta > tb)
            std::swap(ta, tb), std::swap(sa, sb);
        out[count++] = {g, pc[q].sub, pc[q].edge, sb < sa, ta, tb, sa, sb};
    }
    if (count == 2 && out[1].t0 < out[0].t0)
        std::swap(out[0], out[1]);
    return count;
}

extern "C" tsr_status tsr_subd_eval(const tsr_subd *s, uint32_t face, uint32_t sub, const double *uv, uint32_t count,
                                    double *pos, double *du, double *dv)
{
    if (!s || !patch_ok(s, face, sub) || (count && (!uv || !pos)))
        return TSR_ERR_ARGUMENT;
    if (!count)
        return TSR_OK;
    try {
        return with_face(s, face, [&](const Prepared &p) {
            Bfr::Parameterization param = p.surf.GetParameterization();
            double scale = param.HasSubFaces() ? 0.5 : 1.0;
            for (uint32_t k = 0; k < count; k++) {
                double fuv[2], Du[3], Dv[3];
                face_coord(param, sub, uv + 2 * (size_t)k, fuv);
                double *P = pos + 3 * (size_t)k;
                if (!du && !dv) {
                    p.surf.Evaluate(fuv, p.pts.data(), Desc(3), P);
                    continue;
                }
                p.surf.Evaluate(fuv, p.pts.data(), Desc(3), P, Du, Dv);
                for (int c = 0; c < 3; c++) {
                    if (du)
                        du[3 * (size_t)k + c] = Du[c] * scale;
                    if (dv)
                        dv[3 * (size_t)k + c] = Dv[c] * scale;
                }
            }
            return TSR_OK;
        });
    } catch (const std::bad_alloc &) {
        return TSR_ERR_NOMEM;
    } catch (...) {
        return TSR_ERR_ARGUMENT;
    }
}

extern "C" tsr_status tsr_subd_normal(const tsr_subd *s, uint32_t face, uint32_t sub, const double uv[2], double n[3])
{
    if (!s || !patch_ok(s, face, sub) || !uv || !n)
        return TSR_ERR_ARGUMENT;
    try {
        return with_face(s, face, [&](const Prepared &p) { return normal_at(p, sub, uv, n) ? TSR_OK : TSR_ERR_VALUE; });
    } catch (const std::bad_alloc &) {
        return TSR_ERR_NOMEM;
    } catch (...) {
        return TSR_ERR_ARGUMENT;
    }
}

// (u, v) of parameter t along edge e of a patch: 0 south (t, 0), 1 east
// (1, t), 2 north (t, 1), 3 west (0, t).
static void edge_uv(uint32_t e, double t, double uv[2])
{
    uv[0] = e == 1 ? 1 : e == 3 ? 0 : t;
    uv[1] = e == 0 ? 0 : e == 2 ? 1 : t;
}

extern "C" tsr_status tsr_subd_link_gap(const tsr_subd *s, double *gap, tsr_subd_gap_at *at)
{
    if (!s || !gap)
        return TSR_ERR_ARGUMENT;
    *gap = 0;
    uint32_t nf = tsr_subd_face_count(s);
    for (uint32_t f = 0; f < nf; f++) {
        if (!tsr_subd_face_has_limit(s, f))
            continue;
        for (uint32_t k = 0; k < tsr_subd_face_patches(s, f); k++)
            for (uint32_t e = 0; e < 4; e++) {
                tsr_subd_link l[2];
                uint32_t n = tsr_subd_patch_neighbours(s, f, k, e, l);
                for (uint32_t i = 0; i < n; i++)
                    for (int q = 0; q <= 8; q++) {
                        // the link maps t0..t1 here onto s0..s1 there
                        // (s1 < s0 when reversed)
                        double t = l[i].t0 + (l[i].t1 - l[i].t0) * q / 8.0;
                        double sn = l[i].s0 + (l[i].s1 - l[i].s0) * q / 8.0;
                        double a[2], b[2], pa[3], pb[3];
                        edge_uv(e, t, a);
                        edge_uv(l[i].edge, sn, b);
                        tsr_status st = tsr_subd_eval(s, f, k, a, 1, pa, nullptr, nullptr);
                        if (st == TSR_OK)
                            st = tsr_subd_eval(s, l[i].face, l[i].sub, b, 1, pb, nullptr, nullptr);
                        if (st != TSR_OK)
                            return st;
                        double d = std::sqrt((pa[0] - pb[0]) * (pa[0] - pb[0]) + (pa[1] - pb[1]) * (pa[1] - pb[1]) +
                                             (pa[2] - pb[2]) * (pa[2] - pb[2]));
                        if (d > *gap) {
                            *gap = d;
                            if (at)
                                *at = {f, k, l[i].face, l[i].sub, {a[0], a[1]}, {b[0], b[1]}};
                        }
                    }
            }
    }
    return TSR_OK;
}

// Why the box of the patch points bounds the surface: Bfr evaluates a
// face as one patch (regular faces) or as the leaves of a patch tree
// (irregular ones), each leaf a weighted sum of the prepared patch points.
// Every basis involved has non-negative weights that sum to one: uniform
// bicubic B-splines (and their boundary and corner variants, which
// replace a missing row by the reflection 2 P0 - P1 and still give
// weights (2 B0 + B1, B2 - B0, B3) >= 0 on [0,1]), Gregory patches
// (Bernstein weights times the rational blends u / (u + v) of the
// interior points), and bilinear ones (bilinear scheme, N-gon sub-faces,
// non-manifold fall-backs). So every evaluated point is a convex
// combination of patch points and lies in their box. The patch points are
// the face's control points followed by the points Bfr computes from
// them (refined points and Gregory points, which may lie outside the
// control points' hull), so all of them are taken, not only the control
// points. The pad covers the rounding of a sum of at most a few hundred
// terms.
extern "C" tsr_status tsr_subd_face_bounds(const tsr_subd *s, uint32_t face, uint32_t sub, double lo[3], double hi[3])
{
    if (!s || !patch_ok(s, face, sub) || !lo || !hi)
        return TSR_ERR_ARGUMENT;
    try {
        return with_face(s, face, [&](const Prepared &p) {
            for (int c = 0; c < 3; c++)
                lo[c] = INFINITY, hi[c] = -INFINITY;
            double big = 0;
            for (size_t k = 0; k < p.pts.size(); k += 3)
                for (int c = 0; c < 3; c++) {
                    lo[c] = std::fmin(lo[c], p.pts[k + c]);
                    hi[c] = std::fmax(hi[c], p.pts[k + c]);
                    big = std::fmax(big, std::fabs(p.pts[k + c]));
                }
            double pad = 1024 * DBL_EPSILON * big;
            for (int c = 0; c < 3; c++)
                lo[c] -= pad, hi[c] += pad;
            return TSR_OK;
        });
    } catch (const std::bad_alloc &) {
        return TSR_ERR_NOMEM;
    } catch (...) {
        return TSR_ERR_ARGUMENT;
    }
}

/* tessellate() with a face list checked first (faces not NULL: each below
 * the face count, none twice), C++ failures turned into statuses and the
 * mesh's counts restored. */
static tsr_status uniform_guarded(const tsr_subd *s, uint32_t rate, const uint32_t *faces, uint32_t num_faces,
                                  tsr_mesh *out, tsr_error *err)
{
    uint32_t v0 = out->vertex_count, t0 = out->triangle_count;
    try {
        if (faces) {
            Vec<uint8_t> listed(s->num_faces, 0, Alloc<uint8_t>(s->alloc));
            for (uint32_t q = 0; q < num_faces; q++) {
                uint32_t f = faces[q];
                if (f >= s->num_faces)
                    return tsr_error_set(err, TSR_ERR_ARGUMENT,
                                         "uniform tessellation: face %u (list entry %u) is not "
                                         "below the face count %u",
                                         f, q, s->num_faces);
                if (listed[f])
                    return tsr_error_set(err, TSR_ERR_ARGUMENT,
                                         "uniform tessellation: face %u is listed twice (entry %u)", f, q);
                listed[f] = 1;
            }
        }
        return tessellate(s, rate, faces, num_faces, out, err);
    } catch (const std::bad_alloc &) {
        out->vertex_count = v0, out->triangle_count = t0;
        return tsr_error_set(err, TSR_ERR_NOMEM, "uniform tessellation: out of memory");
    } catch (...) {
        out->vertex_count = v0, out->triangle_count = t0;
        return tsr_error_set(err, TSR_ERR_UNSUPPORTED, "uniform tessellation: OpenSubdiv failed");
    }
}

extern "C" tsr_status tsr_subd_tessellate_uniform(const tsr_subd *s, uint32_t rate, tsr_mesh *out, tsr_error *err)
{
    if (!s || !out)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "uniform tessellation: NULL surface or mesh");
    if (rate < 1 || rate > TSR_SUBD_MAX_RATE)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "uniform tessellation: rate %u outside 1..%u", rate,
                             TSR_SUBD_MAX_RATE);
    return uniform_guarded(s, rate, nullptr, 0, out, err);
}

extern "C" tsr_status tsr_subd_tessellate_uniform_faces(const tsr_subd *s, uint32_t rate, const uint32_t *faces,
                                                        uint32_t num_faces, tsr_mesh *out, tsr_error *err)
{
    if (!s || !out || (num_faces && !faces))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "uniform tessellation: NULL surface, mesh or face list");
    if (rate < 1 || rate > TSR_SUBD_MAX_RATE)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "uniform tessellation: rate %u outside 1..%u", rate,
                             TSR_SUBD_MAX_RATE);
    if (!num_faces)
        return TSR_OK;
    return uniform_guarded(s, rate, faces, num_faces, out, err);
}

// The basis change, per direction, from Bézier points b to the uniform
// cubic B-spline points Q of the same cubic on [0,1]: the inverse of
// b = M Q with M = [1 4 1 0; 0 4 2 0; 0 2 4 0; 0 1 4 1] / 6 (the B-spline
// segment's Bézier points). Rows sum to 1, so a repeated point stays put
// (the teapot's collapsed edges stay collapsed).
static const double BEZIER_TO_BSPLINE[4][4] = {{6, -7, 2, 0}, {0, 2, -1, 0}, {0, -1, 2, 0}, {0, 2, -7, 6}};

extern "C" tsr_status tsr_subd_cage_from_bezier(const double *ctrl, uint32_t num_patches, const tsr_allocator *alloc,
                                                tsr_cage *out, tsr_error *err)
{
    if (!out)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "Bezier cage: NULL output");
    memset(out, 0, sizeof *out);
    if (!ctrl)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "Bezier cage: NULL control points");
    if (!num_patches)
        return tsr_error_set(err, TSR_ERR_EMPTY, "Bezier cage: no patches");
    if (num_patches > UINT32_MAX / 36)
        return tsr_error_set(err, TSR_ERR_TOO_LARGE, "Bezier cage: %u patches (at most %u)", num_patches,
                             UINT32_MAX / 36);
    const tsr_allocator *a = alloc && alloc->realloc ? alloc : nullptr;
    size_t np = 16 * (size_t)num_patches, nf = 9 * (size_t)num_patches;
    double *pts = static_cast<double *>(tsr_alloc(a, 3 * np * sizeof(double)));
    uint32_t *sizes = static_cast<uint32_t *>(tsr_alloc(a, nf * sizeof(uint32_t)));
    uint32_t *verts = static_cast<uint32_t *>(tsr_alloc(a, 4 * nf * sizeof(uint32_t)));
    if (!pts || !sizes || !verts) {
        tsr_free(a, pts), tsr_free(a, sizes), tsr_free(a, verts);
        return tsr_error_set(err, TSR_ERR_NOMEM, "Bezier cage: out of memory for %u patches", num_patches);
    }
    for (uint32_t p = 0; p < num_patches; p++) {
        const double *b = ctrl + 48 * (size_t)p;
        double *q = pts + 48 * (size_t)p;
        bool finite = true;
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 4; i++)
                for (int c = 0; c < 3; c++) {
                    // Q = B2S b B2S^T, rows and columns alike
                    double sum = 0;
                    for (int l = 0; l < 4; l++)
                        for (int k = 0; k < 4; k++)
                            sum += BEZIER_TO_BSPLINE[i][k] * BEZIER_TO_BSPLINE[j][l] * b[3 * (4 * l + k) + c];
                    q[3 * (4 * j + i) + c] = sum;
                    finite = finite && std::isfinite(sum) && std::isfinite(b[3 * (4 * j + i) + c]);
                }
        if (!finite) {
            tsr_free(a, pts), tsr_free(a, sizes), tsr_free(a, verts);
            return tsr_error_set(err, TSR_ERR_VALUE,
                                 "Bezier cage: patch %u: a control point or its B-spline point is not finite", p);
        }
        for (uint32_t j = 0; j < 3; j++)
            for (uint32_t i = 0; i < 3; i++) {
                size_t f = 9 * (size_t)p + 3 * j + i;
                uint32_t v = 16 * p + 4 * j + i;
                sizes[f] = 4;
                verts[4 * f] = v;
                verts[4 * f + 1] = v + 1;
                verts[4 * f + 2] = v + 5;
                verts[4 * f + 3] = v + 4;
            }
    }
    out->num_points = (uint32_t)np;
    out->points = pts;
    out->num_faces = (uint32_t)nf;
    out->face_sizes = sizes;
    out->face_verts = verts;
    out->num_face_verts = (uint32_t)(4 * nf);
    out->boundary_interp = 0;
    out->fvar_interp = 0;
    if (a)
        out->alloc = *a;
    return TSR_OK;
}
