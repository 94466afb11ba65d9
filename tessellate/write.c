/* write.c: mesh writers (OBJ, binary PLY, binary STL, glTF 2.0 .glb) and
 * atomic file output. Binary formats are written byte by byte in little
 * endian, so the files are the same on any host. */
#define _GNU_SOURCE /* mkstemps */
#include "tessellate/tessellate.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- Atomic output ---------------------------------------------------- */

/* The temporaries begun and not yet committed or aborted, for
 * tsr_atomic_remove_pending: a slot is claimed (1), its path written, then
 * marked ready (2); a signal handler reads only ready slots. */
enum { PENDING = 32, PENDING_PATH = 4096 };
static char pending_path[PENDING][PENDING_PATH];
static atomic_int pending_state[PENDING];

static void pending_add(const char *tmp)
{
    if (strlen(tmp) >= PENDING_PATH)
        return;
    for (int k = 0; k < PENDING; k++) {
        int free_slot = 0;
        if (atomic_compare_exchange_strong(&pending_state[k], &free_slot, 1)) {
            memcpy(pending_path[k], tmp, strlen(tmp) + 1);
            atomic_store(&pending_state[k], 2);
            return;
        }
    }
}

static void pending_drop(const char *tmp)
{
    for (int k = 0; k < PENDING; k++)
        if (atomic_load(&pending_state[k]) == 2 && !strcmp(pending_path[k], tmp)) {
            atomic_store(&pending_state[k], 0);
            return;
        }
}

void (*volatile tsr__atomic_remove_also)(void);

void tsr_atomic_remove_pending(void)
{
    for (int k = 0; k < PENDING; k++)
        if (atomic_load(&pending_state[k]) == 2)
            unlink(pending_path[k]);
    void (*also)(void) = tsr__atomic_remove_also;
    if (also)
        also();
}

/* The file an output to path lands in: path itself, or, where path is a
 * symbolic link, the file it points to (followed to the end, also when
 * that file does not exist yet), so the link stays a link. As the
 * kernel's protected_symlinks does, a link in a sticky folder anyone may
 * write to (/tmp) is followed only when it belongs to us or to the
 * folder's owner. 0, or 1 when the links go round, 2 when a path is too
 * long, 3 for a link not followed. */
static int output_target(const char *path, char *out, size_t cap)
{
    char cur[4096], link[4096];
    if (strlen(path) >= sizeof cur)
        return 2;
    strcpy(cur, path);
    for (int hops = 0; hops < 40; hops++) {
        struct stat st;
        if (lstat(cur, &st) != 0 || !S_ISLNK(st.st_mode)) {
            if (strlen(cur) >= cap)
                return 2;
            strcpy(out, cur);
            return 0;
        }
        const char *slash = strrchr(cur, '/');
        size_t dir = slash ? (size_t)(slash - cur) + 1 : 0;
        char folder[4096];
        snprintf(folder, sizeof folder, "%.*s", dir ? (int)dir : 1, dir ? cur : ".");
        struct stat ds;
        if (stat(folder, &ds) == 0 && (ds.st_mode & S_ISVTX) && (ds.st_mode & S_IWOTH) && st.st_uid != geteuid() &&
            st.st_uid != ds.st_uid)
            return 3;
        ssize_t n = readlink(cur, link, sizeof link - 1);
        if (n < 0)
            return 1;
        link[n] = '\0';
        if (link[0] == '/') {
            strcpy(cur, link);
        } else { /* relative to the link's folder */
            if (dir + (size_t)n >= sizeof cur)
                return 2;
            memmove(cur + dir, link, (size_t)n + 1);
        }
    }
    return 1;
}

tsr_status tsr_atomic_begin(const char *path, char *tmp, size_t cap, tsr_error *err)
{
    char target[4096];
    int t = output_target(path, target, sizeof target);
    if (t == 2)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: output path too long", path);
    if (t == 1)
        return tsr_error_set(err, TSR_ERR_IO, "%s: cannot write: a symbolic link that loops", path);
    if (t == 3)
        return tsr_error_set(err, TSR_ERR_IO,
                             "%s: cannot write: a symbolic link in a shared sticky folder, owned by "
                             "someone else (not followed)",
                             path);
    const char *slash = strrchr(target, '/');
    const char *base = slash ? slash + 1 : target;
    const char *dot = strrchr(base, '.');
    const char *ext = dot ? dot : "";
    size_t dirlen = (size_t)(base - target);
    int n = snprintf(tmp, cap, "%.*s.%.*s.tsr-tmp-XXXXXX%s", (int)dirlen, target,
                     (int)(dot ? (size_t)(dot - base) : strlen(base)), base, ext);
    if (*base == '\0')
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: output path names a folder, not a file", path);
    if (n < 0 || (size_t)n >= cap)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: output path too long", path);
    /* an existing file keeps its permissions (not set-uid or set-gid);
     * one without any write permission is not replaced (as opening it for
     * writing would fail, also for root) */
    struct stat old;
    bool exists = stat(target, &old) == 0;
    if (exists && S_ISDIR(old.st_mode))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: output path names a folder, not a file", path);
    /* a device, pipe or socket (also behind a link) would be replaced by
     * the rename, not written into: refused, left as it is */
    if (exists && !S_ISREG(old.st_mode))
        return tsr_error_set(err, TSR_ERR_IO, "%s: cannot write: not a regular file (a device, pipe or socket)",
                             path);
    if (exists && !(old.st_mode & (S_IWUSR | S_IWGRP | S_IWOTH)))
        return tsr_error_set(err, TSR_ERR_IO, "%s: cannot write: the file is read-only", path);
    /* made and registered with signals held, so a signal between the two
     * cannot leave the temporary behind */
    sigset_t all, old_mask;
    sigfillset(&all);
    pthread_sigmask(SIG_BLOCK, &all, &old_mask);
    int fd = mkstemps(tmp, (int)strlen(ext));
    int e = errno;
    if (fd >= 0)
        pending_add(tmp);
    pthread_sigmask(SIG_SETMASK, &old_mask, NULL);
    if (fd < 0)
        return tsr_error_set(err, TSR_ERR_IO, "%s: cannot write: %s", path, strerror(e));
    /* mkstemps makes the file 0600; the output gets the permissions of the
     * file it replaces, else those any new file would (0666 less the
     * umask) */
    mode_t mask = umask(0);
    umask(mask);
    fchmod(fd, exists ? old.st_mode & 01777 : 0666 & ~mask);
    close(fd);
    return TSR_OK;
}

/* The file tsr_atomic_begin resolved path to, rebuilt from the temporary's
 * name (".STEM.tsr-tmp-XXXXXX.EXT" beside it), so that commit renames into
 * the folder the temporary is in, whatever links changed meanwhile. */
static bool target_of_tmp(const char *tmp, char *out, size_t cap)
{
    const char *slash = strrchr(tmp, '/');
    const char *base = slash ? slash + 1 : tmp;
    const char *mark = NULL; /* the last one: the name itself may hold the marker */
    for (const char *m = strstr(base, ".tsr-tmp-"); m; m = strstr(m + 1, ".tsr-tmp-"))
        mark = m;
    size_t dirlen = (size_t)(base - tmp);
    if (base[0] != '.' || !mark || strlen(mark) < 15)
        return false;
    const char *ext = mark + 15; /* past ".tsr-tmp-XXXXXX" */
    int n = snprintf(out, cap, "%.*s%.*s%s", (int)dirlen, tmp, (int)(mark - base - 1), base + 1, ext);
    return n > 0 && (size_t)n < cap;
}

tsr_status tsr_atomic_commit(const char *tmp, const char *path, tsr_error *err)
{
    char target[4096];
    if (!target_of_tmp(tmp, target, sizeof target)) {
        remove(tmp);
        pending_drop(tmp);
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: cannot write: '%s' is not a temporary of ours", path, tmp);
    }
    if (rename(tmp, target) != 0) {
        int e = errno;
        remove(tmp);
        pending_drop(tmp);
        return tsr_error_set(err, TSR_ERR_IO, "%s: cannot write: %s", path, strerror(e));
    }
    pending_drop(tmp);
    return TSR_OK;
}

void tsr_atomic_abort(const char *tmp)
{
    remove(tmp);
    pending_drop(tmp);
}

tsr_status tsr_atomic_probe(const char *path, tsr_error *err)
{
    char tmp[4096];
    tsr_status s = tsr_atomic_begin(path, tmp, sizeof tmp, err);
    if (s == TSR_OK)
        tsr_atomic_abort(tmp);
    return s;
}

/* ---- Reading text inputs ------------------------------------------------ */

tsr_status tsr_read_file(const char *path, uint64_t max_bytes, const tsr_allocator *alloc, char **buf, size_t *len,
                         tsr_error *err)
{
    *buf = NULL, *len = 0;
    if (!path)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "no input file given");
    struct stat st;
    if (stat(path, &st) != 0)
        return tsr_error_set(err, errno == ENOENT ? TSR_ERR_NOT_FOUND : TSR_ERR_IO, "%s: %s", path, strerror(errno));
    if (S_ISDIR(st.st_mode))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: is a folder, not a file", path);
    if (!S_ISREG(st.st_mode))
        return tsr_error_set(err, TSR_ERR_ARGUMENT,
                             "%s: not a regular file (a pipe or device): inputs are read from files; save it to one "
                             "first",
                             path);
    if (st.st_size == 0)
        return tsr_error_set(err, TSR_ERR_EMPTY, "%s: empty file (0 bytes)", path);
    if ((uint64_t)st.st_size > max_bytes || (uint64_t)st.st_size >= SIZE_MAX)
        return tsr_error_set(err, TSR_ERR_TOO_LARGE, "%s: %llu bytes, beyond the %llu this reader accepts", path,
                             (unsigned long long)st.st_size, (unsigned long long)max_bytes);
    FILE *f = fopen(path, "rb");
    if (!f)
        return tsr_error_set(err, TSR_ERR_IO, "%s: %s", path, strerror(errno));
    size_t n = (size_t)st.st_size;
    char *b = tsr_alloc(alloc, n + 1);
    if (!b) {
        fclose(f);
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory for %zu bytes", path, n);
    }
    size_t got = fread(b, 1, n, f);
    bool bad = ferror(f);
    fclose(f);
    if (bad || got == 0) {
        tsr_free(alloc, b);
        return tsr_error_set(err, TSR_ERR_IO, "%s: read failed", path);
    }
    b[got] = '\0';
    *buf = b, *len = got;
    return TSR_OK;
}

const char *tsr_quote_bytes(const char *s, size_t n, char *buf, size_t cap)
{
    size_t o = 0;
    for (size_t i = 0; i < n && o + 8 < cap; i++) {
        unsigned char c = (unsigned char)s[i];
        if (i == 24) {
            o += (size_t)snprintf(buf + o, cap - o, "...");
            break;
        }
        if (c >= 32 && c < 127 && c != '\'')
            buf[o++] = (char)c;
        else
            o += (size_t)snprintf(buf + o, cap - o, "\\x%02x", c);
    }
    buf[o] = '\0';
    return buf;
}

/* ---- Formats ---------------------------------------------------------- */

tsr_mesh_format tsr_mesh_format_from_path(const char *path)
{
    const char *dot = strrchr(path, '.');
    if (!dot || strchr(dot, '/'))
        return TSR_FORMAT_UNKNOWN;
    if (!strcasecmp(dot, ".obj"))
        return TSR_FORMAT_OBJ;
    if (!strcasecmp(dot, ".ply"))
        return TSR_FORMAT_PLY;
    if (!strcasecmp(dot, ".stl"))
        return TSR_FORMAT_STL;
    if (!strcasecmp(dot, ".glb"))
        return TSR_FORMAT_GLB;
    return TSR_FORMAT_UNKNOWN;
}

const char *tsr_mesh_format_name(tsr_mesh_format f)
{
    switch (f) {
    case TSR_FORMAT_OBJ: return "obj";
    case TSR_FORMAT_PLY: return "ply";
    case TSR_FORMAT_STL: return "stl";
    case TSR_FORMAT_GLB: return "glb";
    default: return "unknown";
    }
}

/* A buffered little-endian writer that remembers the first failure. */
typedef struct out {
    FILE *f;
    unsigned char buf[1 << 16];
    size_t n;
    bool failed;
} out;

static void out_flush(out *o)
{
    if (o->n && !o->failed && fwrite(o->buf, 1, o->n, o->f) != o->n)
        o->failed = true;
    o->n = 0;
}

static void out_bytes(out *o, const void *p, size_t n)
{
    const unsigned char *s = p;
    while (n) {
        if (o->n == sizeof o->buf)
            out_flush(o);
        size_t k = sizeof o->buf - o->n;
        if (k > n)
            k = n;
        memcpy(o->buf + o->n, s, k);
        o->n += k;
        s += k;
        n -= k;
    }
}

static void out_u32(out *o, uint32_t v)
{
    unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16),
                          (unsigned char)(v >> 24)};
    out_bytes(o, b, 4);
}

static void out_u16(out *o, uint16_t v)
{
    unsigned char b[2] = {(unsigned char)v, (unsigned char)(v >> 8)};
    out_bytes(o, b, 2);
}

static void out_f32(out *o, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    out_u32(o, u);
}

static void out_printf(out *o, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static void out_printf(out *o, const char *fmt, ...)
{
    char line[256];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    if (n > 0)
        out_bytes(o, line, (size_t)n < sizeof line ? (size_t)n : sizeof line - 1);
}

/* ---- OBJ ---- */
static void write_obj(out *o, const tsr_mesh *m)
{
    out_printf(o, "# Tessera mesh: %u vertices, %u triangles\n", m->vertex_count, m->triangle_count);
    for (uint32_t i = 0; i < m->vertex_count; i++) {
        const float *p = m->positions + 3 * (size_t)i;
        out_printf(o, "v %.9g %.9g %.9g\n", p[0], p[1], p[2]);
    }
    if (m->uvs)
        for (uint32_t i = 0; i < m->vertex_count; i++)
            out_printf(o, "vt %.9g %.9g\n", m->uvs[2 * (size_t)i], m->uvs[2 * (size_t)i + 1]);
    if (m->normals)
        for (uint32_t i = 0; i < m->vertex_count; i++) {
            const float *n = m->normals + 3 * (size_t)i;
            out_printf(o, "vn %.9g %.9g %.9g\n", n[0], n[1], n[2]);
        }
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *ix = m->indices + 3 * (size_t)t;
        uint32_t a = ix[0] + 1, b = ix[1] + 1, c = ix[2] + 1;
        if (m->normals && m->uvs)
            out_printf(o, "f %u/%u/%u %u/%u/%u %u/%u/%u\n", a, a, a, b, b, b, c, c, c);
        else if (m->normals)
            out_printf(o, "f %u//%u %u//%u %u//%u\n", a, a, b, b, c, c);
        else if (m->uvs)
            out_printf(o, "f %u/%u %u/%u %u/%u\n", a, a, b, b, c, c);
        else
            out_printf(o, "f %u %u %u\n", a, b, c);
    }
}

/* ---- PLY ---- */
static void write_ply(out *o, const tsr_mesh *m)
{
    out_printf(o, "ply\nformat binary_little_endian 1.0\ncomment Tessera\nelement vertex %u\n"
                  "property float x\nproperty float y\nproperty float z\n",
               m->vertex_count);
    if (m->normals)
        out_printf(o, "property float nx\nproperty float ny\nproperty float nz\n");
    if (m->uvs)
        out_printf(o, "property float s\nproperty float t\n");
    out_printf(o, "element face %u\nproperty list uchar uint vertex_indices\nend_header\n",
               m->triangle_count);
    for (uint32_t i = 0; i < m->vertex_count; i++) {
        for (int k = 0; k < 3; k++)
            out_f32(o, m->positions[3 * (size_t)i + k]);
        if (m->normals)
            for (int k = 0; k < 3; k++)
                out_f32(o, m->normals[3 * (size_t)i + k]);
        if (m->uvs)
            for (int k = 0; k < 2; k++)
                out_f32(o, m->uvs[2 * (size_t)i + k]);
    }
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        unsigned char three = 3;
        out_bytes(o, &three, 1);
        for (int k = 0; k < 3; k++)
            out_u32(o, m->indices[3 * (size_t)t + k]);
    }
}

/* ---- STL ---- */
static void write_stl(out *o, const tsr_mesh *m)
{
    char header[80] = {0};
    /* Must not begin with "solid": readers would take it for ASCII STL. */
    snprintf(header, sizeof header, "Tessera binary STL");
    out_bytes(o, header, 80);
    out_u32(o, m->triangle_count);
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *ix = m->indices + 3 * (size_t)t;
        const float *p[3] = {m->positions + 3 * (size_t)ix[0], m->positions + 3 * (size_t)ix[1],
                             m->positions + 3 * (size_t)ix[2]};
        double e1[3], e2[3], n[3];
        for (int k = 0; k < 3; k++) {
            e1[k] = (double)p[1][k] - p[0][k];
            e2[k] = (double)p[2][k] - p[0][k];
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; k++)
            out_f32(o, l > 0 ? (float)(n[k] / l) : 0.0f);
        for (int v = 0; v < 3; v++)
            for (int k = 0; k < 3; k++)
                out_f32(o, p[v][k]);
        out_u16(o, 0);
    }
}

/* ---- GLB ---- */
static cJSON *json_vec(const float *v, int n)
{
    cJSON *a = cJSON_CreateArray();
    for (int i = 0; i < n; i++)
        cJSON_AddItemToArray(a, cJSON_CreateNumber((double)v[i]));
    return a;
}

static int add_view(cJSON *views, size_t offset, size_t length, int target)
{
    cJSON *v = cJSON_CreateObject();
    cJSON_AddNumberToObject(v, "buffer", 0);
    cJSON_AddNumberToObject(v, "byteOffset", (double)offset);
    cJSON_AddNumberToObject(v, "byteLength", (double)length);
    cJSON_AddNumberToObject(v, "target", target);
    cJSON_AddItemToArray(views, v);
    return cJSON_GetArraySize(views) - 1;
}

static int add_accessor(cJSON *accs, int view, int ctype, uint32_t count, const char *type,
                        const float *mn, const float *mx, int n)
{
    cJSON *a = cJSON_CreateObject();
    cJSON_AddNumberToObject(a, "bufferView", view);
    cJSON_AddNumberToObject(a, "componentType", ctype);
    cJSON_AddNumberToObject(a, "count", count);
    cJSON_AddStringToObject(a, "type", type);
    if (mn) {
        cJSON_AddItemToObject(a, "min", json_vec(mn, n));
        cJSON_AddItemToObject(a, "max", json_vec(mx, n));
    }
    cJSON_AddItemToArray(accs, a);
    return cJSON_GetArraySize(accs) - 1;
}

/* glTF is +y up; Tessera is +z up: (x, y, z) -> (x, z, -y). */
static void to_gltf(const float *p, float *q)
{
    q[0] = p[0];
    q[1] = p[2];
    q[2] = p[1] == 0.0f ? 0.0f : -p[1];
}

static tsr_status write_glb(out *o, const tsr_mesh *m)
{
    size_t nv = m->vertex_count, nt = m->triangle_count;
    size_t pos_off = 0, pos_len = nv * 12;
    size_t nrm_off = pos_off + pos_len, nrm_len = m->normals ? nv * 12 : 0;
    size_t uv_off = nrm_off + nrm_len, uv_len = m->uvs ? nv * 8 : 0;
    size_t idx_off = uv_off + uv_len, idx_len = nt * 12;
    size_t bin_len = idx_off + idx_len; /* every part is a multiple of 4 */

    float mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < nv; i++) {
        float q[3];
        to_gltf(m->positions + 3 * i, q);
        for (int k = 0; k < 3; k++) {
            mn[k] = q[k] < mn[k] ? q[k] : mn[k];
            mx[k] = q[k] > mx[k] ? q[k] : mx[k];
        }
    }

    cJSON *root = cJSON_CreateObject();
    cJSON *asset = cJSON_AddObjectToObject(root, "asset");
    cJSON_AddStringToObject(asset, "version", "2.0");
    cJSON_AddStringToObject(asset, "generator", "Tessera");
    cJSON_AddNumberToObject(root, "scene", 0);
    cJSON *scenes = cJSON_AddArrayToObject(root, "scenes");
    cJSON *scene = cJSON_CreateObject();
    cJSON *nodes_ix = cJSON_AddArrayToObject(scene, "nodes");
    cJSON_AddItemToArray(nodes_ix, cJSON_CreateNumber(0));
    cJSON_AddItemToArray(scenes, scene);
    cJSON *nodes = cJSON_AddArrayToObject(root, "nodes");
    cJSON *node = cJSON_CreateObject();
    cJSON_AddNumberToObject(node, "mesh", 0);
    cJSON_AddItemToArray(nodes, node);

    cJSON *views = cJSON_AddArrayToObject(root, "bufferViews");
    cJSON *accs = cJSON_AddArrayToObject(root, "accessors");
    cJSON *attrs = cJSON_CreateObject();
    int v = add_view(views, pos_off, pos_len, 34962);
    cJSON_AddNumberToObject(attrs, "POSITION", add_accessor(accs, v, 5126, (uint32_t)nv, "VEC3", mn, mx, 3));
    if (m->normals) {
        v = add_view(views, nrm_off, nrm_len, 34962);
        cJSON_AddNumberToObject(attrs, "NORMAL", add_accessor(accs, v, 5126, (uint32_t)nv, "VEC3", NULL, NULL, 0));
    }
    if (m->uvs) {
        v = add_view(views, uv_off, uv_len, 34962);
        cJSON_AddNumberToObject(attrs, "TEXCOORD_0", add_accessor(accs, v, 5126, (uint32_t)nv, "VEC2", NULL, NULL, 0));
    }
    v = add_view(views, idx_off, idx_len, 34963);
    int ia = add_accessor(accs, v, 5125, (uint32_t)(3 * nt), "SCALAR", NULL, NULL, 0);

    cJSON *meshes = cJSON_AddArrayToObject(root, "meshes");
    cJSON *mesh = cJSON_CreateObject();
    cJSON *prims = cJSON_AddArrayToObject(mesh, "primitives");
    cJSON *prim = cJSON_CreateObject();
    cJSON_AddItemToObject(prim, "attributes", attrs);
    cJSON_AddNumberToObject(prim, "indices", ia);
    cJSON_AddNumberToObject(prim, "mode", 4);
    cJSON_AddItemToArray(prims, prim);
    cJSON_AddItemToArray(meshes, mesh);
    cJSON *buffers = cJSON_AddArrayToObject(root, "buffers");
    cJSON *buf = cJSON_CreateObject();
    cJSON_AddNumberToObject(buf, "byteLength", (double)bin_len);
    cJSON_AddItemToArray(buffers, buf);

    char *json = cJSON_PrintUnformatted(root);
    cJSON_Delete(root);
    if (!json)
        return TSR_ERR_NOMEM;
    size_t jlen = strlen(json), jpad = (4 - jlen % 4) % 4;
    uint64_t total = 12 + 8 + jlen + jpad + 8 + bin_len;
    if (total > UINT32_MAX) {
        free(json);
        return TSR_ERR_TOO_LARGE;
    }
    out_u32(o, 0x46546C67u); /* "glTF" */
    out_u32(o, 2);
    out_u32(o, (uint32_t)total);
    out_u32(o, (uint32_t)(jlen + jpad));
    out_u32(o, 0x4E4F534Au); /* "JSON" */
    out_bytes(o, json, jlen);
    out_bytes(o, "    ", jpad);
    free(json);
    out_u32(o, (uint32_t)bin_len);
    out_u32(o, 0x004E4942u); /* "BIN\0" */
    for (size_t i = 0; i < nv; i++) {
        float q[3];
        to_gltf(m->positions + 3 * i, q);
        for (int k = 0; k < 3; k++)
            out_f32(o, q[k]);
    }
    if (m->normals)
        for (size_t i = 0; i < nv; i++) {
            float q[3];
            to_gltf(m->normals + 3 * i, q);
            for (int k = 0; k < 3; k++)
                out_f32(o, q[k]);
        }
    if (m->uvs)
        for (size_t i = 0; i < 2 * nv; i++)
            out_f32(o, m->uvs[i]);
    for (size_t i = 0; i < 3 * nt; i++)
        out_u32(o, m->indices[i]);
    return TSR_OK;
}

tsr_status tsr_mesh_write(const tsr_mesh *m, const char *path, tsr_mesh_format f, tsr_error *err)
{
    if (f == TSR_FORMAT_UNKNOWN)
        f = tsr_mesh_format_from_path(path);
    if (f == TSR_FORMAT_UNKNOWN)
        return tsr_error_set(err, TSR_ERR_ARGUMENT,
                             "%s: unknown mesh format (use .obj, .ply, .stl or .glb)", path);
    if (m->triangle_count == 0)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: the mesh has no triangles; nothing written", path);
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count; i++)
        if (m->indices[i] >= m->vertex_count)
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: triangle %zu has vertex index %u of %u",
                                 path, i / 3, m->indices[i], m->vertex_count);
    char tmp[4096];
    tsr_status s = tsr_atomic_begin(path, tmp, sizeof tmp, err);
    if (s != TSR_OK)
        return s;
    out *o = malloc(sizeof *o);
    if (!o) {
        tsr_atomic_abort(tmp);
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory", path);
    }
    o->n = 0;
    o->failed = false;
    o->f = fopen(tmp, "wb");
    if (!o->f) {
        int e = errno;
        free(o);
        tsr_atomic_abort(tmp);
        return tsr_error_set(err, TSR_ERR_IO, "%s: cannot write: %s", path, strerror(e));
    }
    s = TSR_OK;
    switch (f) {
    case TSR_FORMAT_OBJ: write_obj(o, m); break;
    case TSR_FORMAT_PLY: write_ply(o, m); break;
    case TSR_FORMAT_STL: write_stl(o, m); break;
    default: s = write_glb(o, m); break;
    }
    out_flush(o);
    int e = o->failed ? errno : 0;
    if (fclose(o->f) != 0 && !e)
        e = errno ? errno : EIO;
    bool failed = o->failed || e;
    free(o);
    if (s != TSR_OK || failed) {
        tsr_atomic_abort(tmp);
        if (s == TSR_ERR_TOO_LARGE)
            return tsr_error_set(err, s, "%s: mesh too large for a .glb (over 4 GiB)", path);
        if (s != TSR_OK)
            return tsr_error_set(err, s, "%s: %s", path, tsr_status_str(s));
        return tsr_error_set(err, TSR_ERR_IO, "%s: write failed: %s", path, strerror(e ? e : EIO));
    }
    return tsr_atomic_commit(tmp, path, err);
}
