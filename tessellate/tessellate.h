/* tessellate.h: Tessera's kernel. Status codes, allocators, the indexed
 * triangle mesh and its writers, atomic file output, and mesh validation.
 *
 * The kernel knows no kind of surface and no GPU (../shared/DESIGN.md).
 *
 * Conventions used everywhere in Tessera:
 *  - Positions are float32 x, y, z with z up. Triangles are counter-clockwise
 *    seen from the side their normal points to (for a terrain, from +z).
 *  - Functions that can fail on input return a tsr_status and, when the
 *    caller passes a tsr_error, fill it with a one-line message naming the
 *    file, line or element at fault. A NULL tsr_error is allowed everywhere.
 *  - Objects take an optional allocator; NULL means the C library's
 *    malloc/realloc/free. No function keeps global state, so two meshes or
 *    heightfields may be used from two threads at once.
 *
 * Public headers compile as C11 and as C++ (checked by a test).
 */
#ifndef TSR_TESSELLATE_H
#define TSR_TESSELLATE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Status ------------------------------------------------------------ */

/* One table of codes; tsr_status_str() gives each its message. */
typedef enum tsr_status {
    TSR_OK = 0,
    TSR_ERR_ARGUMENT,     /* a caller passed an invalid argument */
    TSR_ERR_NOT_FOUND,    /* a file does not exist */
    TSR_ERR_IO,           /* reading or writing failed */
    TSR_ERR_EMPTY,        /* a file has no bytes */
    TSR_ERR_FORMAT,       /* bytes are not a file of the expected format */
    TSR_ERR_TRUNCATED,    /* a file ends before its header says it should */
    TSR_ERR_TOO_LARGE,    /* dimensions beyond what Tessera accepts */
    TSR_ERR_TOO_SMALL,    /* dimensions below what Tessera accepts */
    TSR_ERR_VALUE,        /* a value is out of range (infinite height...) */
    TSR_ERR_UNSUPPORTED,  /* a valid file using something not supported */
    TSR_ERR_NOMEM,        /* an allocation failed */
    TSR_ERR_INVALID_MESH, /* a mesh failed validation */
    TSR_STATUS_COUNT
} tsr_status;

/* A short static message for a code, never NULL. */
const char *tsr_status_str(tsr_status s);

/* The detail of a failure: the code and a one-line message such as
 * "terrain.png: truncated file (PNG read failed: ...)". */
typedef struct tsr_error {
    tsr_status status;
    char message[512];
} tsr_error;

/* Sets err (if not NULL) to status and a printf-style message; returns
 * status so callers can write `return tsr_error_set(err, ...)`. */
tsr_status tsr_error_set(tsr_error *err, tsr_status status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* ---- Allocator --------------------------------------------------------- */

/* One function in the manner of Lua's lua_Alloc: size 0 frees ptr and
 * returns NULL; otherwise it behaves like realloc (ptr NULL allocates).
 * A NULL tsr_allocator pointer anywhere means the library's default (the
 * C library's, with big blocks mapped at once). alloc_dense (optional,
 * NULL: realloc(user, NULL, size)) makes a block the caller will write
 * all of at once (tsr_alloc_dense), to be resized and freed by realloc. */
typedef struct tsr_allocator {
    void *(*realloc)(void *user, void *ptr, size_t size);
    void *user;
    void *(*alloc_dense)(void *user, size_t size);
} tsr_allocator;

void *tsr_alloc(const tsr_allocator *a, size_t size);
void *tsr_realloc(const tsr_allocator *a, void *ptr, size_t size);
/* As tsr_alloc, for a block the caller will write all of at once (a mesh
 * reserved to the size it will have, a table it clears first): the
 * default allocator maps such a block with its pages from 1 MiB on (one
 * fault per 4 KiB saved; it does so for every block from 8 MiB). Freed and
 * resized as any other. */
void *tsr_alloc_dense(const tsr_allocator *a, size_t size);
void tsr_free(const tsr_allocator *a, void *ptr);

/* The processors this process may run on: its CPU affinity (a Slurm job's
 * or a container's cpuset), else the online count, and no more than its
 * cgroups' CPU bandwidth limit allows (a container's --cpus, a systemd
 * CPUQuota: cgroup v2's cpu.max or v1's cfs quota, rounded up); at least
 * 1. What "threads 0: one per processor" means everywhere. */
uint32_t tsr_cpu_count(void);

/* (Internal, tested on its own.) The CPUs a CPU bandwidth limit allows,
 * from text as cgroup v2's cpu.max holds it, "QUOTA PERIOD" (v1's quota
 * and period files joined by a space read the same): QUOTA / PERIOD
 * rounded up; 0 for no limit ("max", a negative quota) or text that is
 * not two positive numbers. */
uint32_t tsr__cpu_quota(const char *text);

/* (Internal, tested on its own.) The smallest CPU bandwidth limit, in
 * CPUs (tsr__cpu_quota), of the cgroups a file like /proc/self/cgroup
 * names and of their ancestors, found under root as under /sys/fs/cgroup:
 * v2's cpu.max at root or root/unified, v1's cpu.cfs_quota_us and
 * cpu.cfs_period_us under root/cpu (or cpu,cpuacct); 0 when none is set
 * or nothing is readable. tsr_cpu_count calls it with those two paths. */
uint32_t tsr__cgroup_cpus(const char *cgroups, const char *root);

/* ---- Mesh -------------------------------------------------------------- */

/* An indexed triangle mesh. positions holds 3 floats per vertex; normals
 * (3 per vertex) and uvs (2 per vertex) are NULL when absent (and may be
 * NULL while the mesh has no vertex yet); indices holds
 * 3 per triangle. The arrays belong to the mesh and its allocator; fields
 * may be read freely, and written within the counts. */
typedef struct tsr_mesh {
    uint32_t vertex_count;
    uint32_t triangle_count;
    float *positions;
    float *normals;
    float *uvs;
    uint32_t *indices;
    uint32_t vertex_capacity;
    uint32_t triangle_capacity;
    unsigned attributes; /* TSR_MESH_NORMALS | TSR_MESH_UVS, set at init */
    tsr_allocator alloc;
} tsr_mesh;

enum { TSR_MESH_NORMALS = 1, TSR_MESH_UVS = 2 };

/* Initialises an empty mesh; attributes is a mask of TSR_MESH_NORMALS and
 * TSR_MESH_UVS. alloc may be NULL. */
void tsr_mesh_init(tsr_mesh *m, unsigned attributes, const tsr_allocator *alloc);
/* Frees every array and leaves an empty mesh. */
void tsr_mesh_free(tsr_mesh *m);
/* Grows capacity to at least the counts given (never shrinks). */
tsr_status tsr_mesh_reserve(tsr_mesh *m, uint32_t vertices, uint32_t triangles);
/* The same, for a mesh that will fill what it reserves now: an array
 * made here (not grown) comes from tsr_alloc_dense. */
tsr_status tsr_mesh_reserve_dense(tsr_mesh *m, uint32_t vertices, uint32_t triangles);
/* Appends a vertex (normal and uv may be NULL, read only when the mesh
 * has them) and returns its index, or UINT32_MAX when out of memory. */
uint32_t tsr_mesh_add_vertex(tsr_mesh *m, const float p[3], const float *n, const float *uv);
/* Appends a triangle a, b, c (counter-clockwise); false when out of memory. */
bool tsr_mesh_add_triangle(tsr_mesh *m, uint32_t a, uint32_t b, uint32_t c);
/* Computes area-weighted vertex normals from the triangles, allocating the
 * normal array when absent. */
tsr_status tsr_mesh_compute_normals(tsr_mesh *m);
/* Removes the vertices from index `first` on that no triangle uses, keeping
 * the others' order (their indices shift down; those below `first` stay);
 * returns how many were removed, or UINT32_MAX when out of memory (the mesh
 * unchanged). */
uint32_t tsr_mesh_drop_unused(tsr_mesh *m, uint32_t first);

/* ---- Writers ----------------------------------------------------------- */

typedef enum tsr_mesh_format {
    TSR_FORMAT_UNKNOWN = 0,
    TSR_FORMAT_OBJ,  /* Wavefront OBJ, text, 1-based indices */
    TSR_FORMAT_PLY,  /* binary little-endian PLY */
    TSR_FORMAT_STL,  /* binary STL (unindexed, facet normals) */
    TSR_FORMAT_GLB   /* glTF 2.0 binary, one mesh, uint32 indices */
} tsr_mesh_format;

/* The format named by a path's extension (case-insensitive), or UNKNOWN. */
tsr_mesh_format tsr_mesh_format_from_path(const char *path);
const char *tsr_mesh_format_name(tsr_mesh_format f);

/* Writes m to path in format f (UNKNOWN: from the extension). The file is
 * written under a temporary name in the same folder and renamed when
 * complete, so a failure leaves no file at path. A mesh without triangles
 * is refused (TSR_ERR_ARGUMENT), as are indices out of range.
 * Coordinates are written as they are (z up) except in .glb, where glTF's
 * +y-up frame is used: (x, y, z) is written as (x, z, -y), a rotation, so
 * winding and handedness are kept. */
tsr_status tsr_mesh_write(const tsr_mesh *m, const char *path, tsr_mesh_format f, tsr_error *err);

/* ---- Atomic output ----------------------------------------------------- */

/* Creates an empty temporary file beside `path`, keeping its extension
 * (libraries that pick a format from the name still work), and puts its
 * name in tmp (capacity cap). Where path is a symbolic link, beside the
 * file it points to (followed to the end), which commit replaces: the
 * link stays (a link in a sticky folder anyone may write to, owned by
 * neither us nor the folder's owner, is not followed: the kernel's
 * protected_symlinks rule). The temporary gets the permissions of the
 * file it will replace (less set-uid and set-gid), or a new file's. Fails
 * with a message naming path when the folder is not writable, path is a
 * folder or too long, a link loops, or the file exists without any write
 * permission ("read-only": not replaced, also for root). */
tsr_status tsr_atomic_begin(const char *path, char *tmp, size_t cap, tsr_error *err);
/* Renames tmp over the file begin resolved path to (read back from tmp's
 * name, so links changed meanwhile do not move it); on failure removes
 * tmp and sets err. */
tsr_status tsr_atomic_commit(const char *tmp, const char *path, tsr_error *err);
/* Removes tmp after a failed write. */
void tsr_atomic_abort(const char *tmp);
/* Removes every temporary begun and not yet committed or aborted (up to
 * 32 in flight at once; more, or paths of 4 KiB, are not kept): for a
 * handler of SIGINT or SIGTERM, so an interrupted command leaves no hidden
 * partial file. Async-signal-safe (unlink). */
void tsr_atomic_remove_pending(void);
/* Internal: another copy's tsr_atomic_remove_pending, which this one calls
 * too (the I/O module compiles its own copy of these functions, and its
 * image temporaries are pending there; terrain/io_loader.c sets it). */
extern void (*volatile tsr__atomic_remove_also)(void);
/* Whether an output could be made at path: creates the temporary that
 * tsr_atomic_begin would and removes it, leaving the disk as it was. For
 * commands to refuse an unwritable output before long work, not after. */
tsr_status tsr_atomic_probe(const char *path, tsr_error *err);

/* ---- Reading text inputs ----------------------------------------------- */

/* Reads a whole file into a buffer from alloc (NULL: malloc) with a NUL
 * after its *len bytes; the caller frees it with tsr_free. Refuses, with
 * a message naming path: no path (TSR_ERR_ARGUMENT), a missing file
 * (TSR_ERR_NOT_FOUND), a folder (TSR_ERR_ARGUMENT), an empty file
 * (TSR_ERR_EMPTY), more than max_bytes (TSR_ERR_TOO_LARGE), a failed
 * read (TSR_ERR_IO). */
tsr_status tsr_read_file(const char *path, uint64_t max_bytes, const tsr_allocator *alloc, char **buf, size_t *len,
                         tsr_error *err);

/* Writes n bytes of s into buf (cap >= 8) as error messages quote them:
 * printable ASCII as it is, other bytes and quotes as \xNN, cut with
 * "..." after 24 bytes. Returns buf. */
const char *tsr_quote_bytes(const char *s, size_t n, char *buf, size_t cap);

/* ---- Half-edge view ---------------------------------------------------- */

#define TSR_NO_TWIN UINT32_MAX        /* a boundary half-edge */
#define TSR_NONMANIFOLD (UINT32_MAX - 1) /* edge used by 3 or more triangles */

/* Half-edge h = 3*t + k runs from indices[3t+k] to indices[3t+(k+1)%3];
 * the next half-edge in its triangle is 3t + (k+1)%3. twin[h] is the
 * opposite half-edge, TSR_NO_TWIN on the boundary, TSR_NONMANIFOLD where
 * the undirected edge has more than two half-edges. Half-edges of a
 * degenerate triangle (repeated index) get TSR_NO_TWIN. */
typedef struct tsr_halfedges {
    uint32_t count; /* 3 * triangle_count */
    uint32_t *twin;
    uint32_t edge_count; /* distinct undirected edges */
    tsr_allocator alloc;
} tsr_halfedges;

tsr_status tsr_halfedges_build(tsr_halfedges *he, const tsr_mesh *m, const tsr_allocator *alloc);
void tsr_halfedges_free(tsr_halfedges *he);

/* ---- Key map ----------------------------------------------------------- */

/* A hash map from 64-bit keys (any value but UINT64_MAX) to 32-bit values,
 * open addressing with linear probing, for welding vertices by key. Zero-
 * initialise it; free with tsr_keymap_free and the same allocator. */
typedef struct tsr_keyslot {
    uint64_t key; /* key + 1; 0 = empty */
    uint32_t val;
} tsr_keyslot;

typedef struct tsr_keymap {
    tsr_keyslot *slots; /* key and value side by side: one cache line a probe */
    size_t mask;
    size_t count;
} tsr_keymap;

/* Makes room for n keys in all without growing again; false when out of
 * memory (the map is unchanged). */
bool tsr_keymap_reserve(tsr_keymap *m, size_t n, const tsr_allocator *a);
/* (internal: doubles the room; false when out of memory) */
bool tsr__keymap_grow(tsr_keymap *m, const tsr_allocator *a);

/* Union-find: the root of x's set in parent[] (parent[r] == r at a root),
 * halving the path on the way (qtri.c's faces, validate.c's shells). */
static inline uint32_t tsr__uf_find(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x)
        x = parent[x] = parent[parent[x]];
    return x;
}

/* (internal: the hash, a 64-bit finaliser) */
static inline uint64_t tsr__keymap_mix(uint64_t k)
{
    k ^= k >> 33;
    k *= 0xff51afd7ed558ccdull;
    k ^= k >> 33;
    k *= 0xc4ceb9fe1a85ec53ull;
    k ^= k >> 33;
    return k;
}

/* The value slot of key, inserted (uninitialised) when absent; *found
 * says whether it was there. NULL when out of memory. (Inline: the
 * tessellators look up a key per tile vertex.) */
static inline uint32_t *tsr_keymap_slot(tsr_keymap *m, uint64_t key, bool *found, const tsr_allocator *a)
{
    if ((m->count + 1) * 2 > m->mask + 1 && !tsr__keymap_grow(m, a))
        return NULL;
    uint64_t k = key + 1;
    size_t h = tsr__keymap_mix(k) & m->mask;
    while (m->slots[h].key && m->slots[h].key != k)
        h = (h + 1) & m->mask;
    *found = m->slots[h].key == k;
    if (!*found) {
        m->slots[h].key = k;
        m->count++;
    }
    return &m->slots[h].val;
}

/* The value of key, or NULL when absent. */
static inline uint32_t *tsr_keymap_find(const tsr_keymap *m, uint64_t key)
{
    if (!m->slots)
        return NULL;
    uint64_t k = key + 1;
    size_t h = tsr__keymap_mix(k) & m->mask;
    while (m->slots[h].key && m->slots[h].key != k)
        h = (h + 1) & m->mask;
    return m->slots[h].key == k ? &m->slots[h].val : NULL;
}
/* Removes every key, keeping the room (for a map refilled each frame). */
void tsr_keymap_clear(tsr_keymap *m);
void tsr_keymap_free(tsr_keymap *m, const tsr_allocator *a);

/* ---- Validation -------------------------------------------------------- */

typedef struct tsr_validate_options {
    /* Distance under which a vertex counts as lying on an edge or on
     * another vertex; 0 means 1e-6 of the bounding box diagonal. */
    double epsilon;
    /* When true, triangles whose normal has z <= 0 are counted as wrongly
     * oriented (a terrain's triangles all face +z). */
    bool expect_up;
    /* When true, the mesh is a height field z(x, y) (a terrain): coincident
     * vertices and T-junctions are judged in the xy plane, and a 0 epsilon
     * means 1e-6 of the xy diagonal. A terrain's crack opens vertically, so
     * in 3D its T-junction vertex lies off the long edge; and on a steep
     * terrain (heights far beyond the extent) every vertex lies within
     * 1e-6 of the 3D diagonal of some nearly vertical edge. */
    bool height_field;
} tsr_validate_options;

#define TSR_VALIDATE_MAX_LOOPS 16

/* What the checks found. Counts of zero mean a check passed; each failing
 * check also records where it first failed. */
typedef struct tsr_validation {
    uint32_t vertices;   /* referenced vertices */
    uint32_t edges;      /* distinct undirected edges */
    uint32_t triangles;
    int64_t euler;       /* vertices - edges + triangles */

    uint32_t bad_indices;          /* index >= vertex_count */
    uint32_t nonfinite_positions;  /* NaN or infinite coordinates */
    uint32_t degenerate_triangles; /* repeated index or zero area */
    uint32_t duplicate_triangles;  /* same three vertices as another */
    uint32_t nonmanifold_edges;    /* used by more than two triangles */
    uint32_t misoriented_edges;    /* two triangles traverse it the same way */
    uint32_t t_junctions;          /* vertex inside an open (one triangle) or
                                      non-manifold edge of another triangle;
                                      not inside an edge two triangles
                                      share: no gap there (coincident
                                      sheets) */
    uint32_t coincident_vertices;  /* distinct indices at one position */
    uint32_t downward_triangles;   /* normal z <= 0 (counted when expect_up) */
    uint32_t boundary_edges;
    uint32_t boundary_loops;
    uint32_t loop_length[TSR_VALIDATE_MAX_LOOPS]; /* edges per loop, first loops */

    /* Where each check first failed (UINT32_MAX where it did not). */
    uint32_t first_bad_triangle;        /* bad index or non-finite corner */
    uint32_t first_degenerate;          /* triangle */
    uint32_t first_duplicate[2];        /* triangle, its twin */
    uint32_t first_nonmanifold[2];      /* edge's vertices */
    uint32_t first_misoriented[2];      /* edge's vertices */
    uint32_t first_t_junction[3];       /* vertex, edge's vertices */
    uint32_t first_coincident[2];       /* two vertices */
    uint32_t first_downward;            /* triangle */
} tsr_validation;

/* Runs every check on m. opts may be NULL (defaults). Fails only when out
 * of memory; the findings are in *out. Cost O(T log T) plus the spatial
 * hashing of the conformity check. */
tsr_status tsr_mesh_validate(const tsr_mesh *m, const tsr_validate_options *opts, tsr_validation *out);

/* True when the mesh is an oriented, edge-manifold, conforming surface with
 * no bad, degenerate or duplicate triangles (boundaries allowed). */
bool tsr_validation_ok(const tsr_validation *v);

/* Writes a one-line summary of the failures ("ok" when none) into buf. */
void tsr_validation_describe(const tsr_validation *v, char *buf, size_t cap);

/* Whether p lies within eps of the segment ab and farther than eps from
 * both of its ends along it: the conformity test of tsr_mesh_validate (a
 * vertex inside another triangle's edge is a T-junction). */
bool tsr_point_on_open_segment(const float p[3], const float a[3], const float b[3], double eps);

/* The squared distance from p to the segment ab (to a when a = b). */
double tsr_point_segment_dist2(const float p[3], const float a[3], const float b[3]);

/* Closed shells that face inward: the triangles of m joined through shared
 * edges (halfedge twins) into components; a component with no boundary
 * and no non-manifold edge whose signed volume (sum of p0 . (p1 x p2) / 6)
 * is negative has its triangles marked in flip[t] = 1 (flip has
 * triangle_count entries; others 0). *shells (when not NULL) counts them.
 * Open sheets have no inside and are never marked. */
tsr_status tsr_mesh_find_inward_shells(const tsr_mesh *m, uint8_t *flip, uint32_t *shells);

/* Gaps: open edges facing each other. A boundary half-edge (one with no
 * twin) is in a gap when its two ends and its midpoint each lie within eps
 * of some boundary half-edge that shares no vertex with it and runs the
 * other way (their directions' dot product below -1/2), or the same way
 * (above 1/2) on another sheet (triangles joined through shared edges; as
 * where two surfaces facing opposite ways meet): two surfaces meeting
 * along a curve with different vertices leave such a crack up to eps wide
 * (a long chord of one side against the short chords of the other, or
 * both sides cut at interleaved points). Consecutive edges of one rim run
 * the same way on one sheet and are never counted; a strip narrower than
 * eps is a gap by this definition. hit (3 *
 * triangle_count entries, may be NULL) receives true at half-edge 3 t + k
 * (from corner k to k + 1 of triangle t) for those in a gap, false at the
 * others; *count (may be NULL) their number. Degenerate edges are left
 * out. O(boundary edges log) for a surface, by a sweep along x.
 * TSR_ERR_ARGUMENT for a NULL mesh or eps < 0 or NaN, TSR_ERR_NOMEM. */
tsr_status tsr_mesh_find_gaps(const tsr_mesh *m, double eps, bool *hit, uint32_t *count);

/* Reverses the winding of the triangles marked in flip and negates the
 * normals (when m has them) of the vertices they use, each once. */
void tsr_mesh_flip_marked(tsr_mesh *m, const uint8_t *flip);

/* Checks that every boundary edge of m lies on the border of the rectangle
 * [x0,x1]×[y0,y1] (within eps, in x and y) and that the boundary forms a
 * single loop: the test of "the only boundary is the domain's outer
 * rectangle". Returns true when it holds; otherwise *bad_vertex (if not
 * NULL) names a boundary vertex off the rectangle, or UINT32_MAX when the
 * failure is the number of loops. */
bool tsr_mesh_boundary_is_rect(const tsr_mesh *m, double x0, double y0, double x1, double y1,
                               double eps, uint32_t *bad_vertex);

/* ---- Solid ------------------------------------------------------------- */

/* Closes a height-field mesh into a solid (for 3D printing), in place.
 *
 * Input: every triangle counter-clockwise seen from +z, an oriented,
 * edge-manifold surface with boundary whose projection on the xy plane
 * does not overlap itself; any number of components and holes. Added:
 *  - walls: for each boundary edge a->b, the quad a, b, b', a' down to
 *    z = base_z (two triangles, facing outward, i.e. to the right of a->b
 *    seen from +z);
 *  - a bottom at z = base_z facing -z: the region bounded by the
 *    boundary loops projected on z = base_z, nesting by even-odd (outer
 *    loops, holes, islands in holes), triangulated by tsr_triangulate
 *    (constrained Delaunay, no Steiner point).
 * One new vertex per boundary corner at z = base_z, shared by its two
 * walls and the bottom; the top boundary vertices are shared with the
 * walls. So the result is closed by index (tsr_mesh_validate: no boundary
 * edge, no misoriented or non-manifold edge), and so by position (STL),
 * encloses a positive signed volume, and has no T-junction.
 * A pinch, where two boundary loops meet at one vertex (diagonal no-data
 * samples), gets one bottom vertex per loop: closed and edge-manifold by
 * index, but the two vertical edges there coincide in space (by position,
 * four faces share that segment, as in two cubes touching at an edge).
 *
 * Attributes of the new vertices, when the mesh has them: normals are the
 * unit bisector of (0, 0, -1) and the outward horizontal normal of the
 * corner (mean of its two walls'), a 45-degree bevel: vertices are shared
 * for watertightness, so walls are smooth-shaded, not flat (for drawing,
 * tsr_mesh_split_flat gives them vertices of their own), and the top's
 * normals are left as they are; uvs are copied from the top vertex above.
 *
 * base_z (world units) must be finite and, as a float, strictly below the
 * lowest referenced vertex, else TSR_ERR_ARGUMENT. A mesh without
 * triangles or with a non-finite position is TSR_ERR_ARGUMENT; a mesh that
 * is not an oriented edge-manifold with a non-overlapping projection
 * (repeated index in a triangle, an edge used by three triangles or twice
 * the same way, boundary loops crossing or touching an edge in xy) is
 * TSR_ERR_INVALID_MESH, with the vertex or edge named; a mesh without
 * boundary (already closed) is left as it is (TSR_OK). On failure the
 * mesh's content is unchanged (its capacity may have grown). Cost:
 * O(T log T) plus the triangulation of the boundary vertices. */
tsr_status tsr_mesh_add_base(tsr_mesh *mesh, double base_z, tsr_error *err);

/* Flat shading for the faces from triangle `first` on (a solid's walls and
 * bottom, added by tsr_mesh_add_base after the top's triangles), in place,
 * for drawing: at each vertex, those triangles are grouped by their own
 * unit normals (each joining the first group whose first normal is within
 * crease_deg degrees, 0..180), and each group gets a vertex of its own (a
 * copy at the same position, uv copied) with the unit mean of its
 * triangles' normals, used by its corners. Triangles before `first` keep
 * their vertices and normals; a vertex only the new faces use becomes their
 * first group's. So the walls and the bottom shade flat with sharp edges
 * between them and the top, and the mesh stays closed by position but no
 * longer by index there. The mesh must have normals; TSR_ERR_ARGUMENT for
 * NULL, a mesh without normals, first beyond the triangles or an angle out
 * of range; TSR_ERR_INVALID_MESH for an index beyond the vertices;
 * TSR_ERR_TOO_LARGE past 2^32 - 2 vertices; TSR_ERR_NOMEM (the mesh
 * unchanged but for its capacity). Triangles without area (no normal)
 * join the first group of their corner's vertex. */
tsr_status tsr_mesh_split_flat(tsr_mesh *mesh, uint32_t first, double crease_deg, tsr_error *err);

#ifdef __cplusplus
}
#endif

#include "tessellate/quadtree.h"
#include "tessellate/predicates.h"
#include "tessellate/cdt.h"
#include "tessellate/triangulate.h"

#endif /* TSR_TESSELLATE_H */
