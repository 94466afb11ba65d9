/* Mesh container, normals, formats, atomic output, and the binary layouts
 * of the writers (read back here byte by byte; the independent readers,
 * assimp and the Khronos validator, run in tests/tools/writers.sh). */
#define _GNU_SOURCE /* sched_setaffinity, CPU_SET */
#include "check.h"
#include "tessellate/tessellate.h"

#include <sched.h>

#include <sys/stat.h>
#include <unistd.h>

static bool exists(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0;
}

static long file_size(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0 ? (long)st.st_size : -1;
}

/* A unit square pyramid-ish fan: 5 vertices, 4 triangles. */
static void fan(tsr_mesh *m, unsigned attrs)
{
    tsr_mesh_init(m, attrs, NULL);
    float p[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 0.5f, 0.25f}};
    float uv[5][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.5f, 0.5f}};
    for (int i = 0; i < 5; i++)
        tsr_mesh_add_vertex(m, p[i], NULL, uv[i]);
    for (uint32_t i = 0; i < 4; i++)
        tsr_mesh_add_triangle(m, i, (i + 1) % 4, 4);
}

static uint32_t rd32(const unsigned char *b) { return b[0] | b[1] << 8 | b[2] << 16 | (uint32_t)b[3] << 24; }

TEST(container_grows)
{
    tsr_mesh m;
    tsr_mesh_init(&m, TSR_MESH_NORMALS | TSR_MESH_UVS, NULL);
    for (int i = 0; i < 10000; i++) {
        float p[3] = {(float)i, 0, 0}, n[3] = {0, 0, 1}, uv[2] = {0.5f, 0.25f};
        CHECK(tsr_mesh_add_vertex(&m, p, n, uv) == (uint32_t)i);
    }
    for (int i = 0; i + 2 < 10000; i++)
        CHECK(tsr_mesh_add_triangle(&m, i, i + 1, i + 2));
    CHECK(m.vertex_count == 10000 && m.triangle_count == 9998);
    CHECK(m.positions[3 * 9999] == 9999.0f && m.uvs[2 * 9999 + 1] == 0.25f && m.normals[3 * 5000 + 2] == 1.0f);
    tsr_mesh_free(&m);
    CHECK(m.vertex_count == 0 && m.positions == NULL);
}

TEST(drop_unused_keeps_the_used_in_order)
{
    /* 12 vertices, x = i, normal z = i, uv = (i, -i); triangles use those
     * not divisible by 3: after the drop, the same triangles by position */
    tsr_mesh m;
    tsr_mesh_init(&m, TSR_MESH_NORMALS | TSR_MESH_UVS, NULL);
    for (int i = 0; i < 12; i++) {
        float p[3] = {(float)i, 0, 0}, n[3] = {0, 0, (float)i}, uv[2] = {(float)i, (float)-i};
        CHECK(tsr_mesh_add_vertex(&m, p, n, uv) == (uint32_t)i);
    }
    const uint32_t tri[3][3] = {{1, 2, 4}, {5, 7, 8}, {10, 11, 1}};
    for (int t = 0; t < 3; t++)
        CHECK(tsr_mesh_add_triangle(&m, tri[t][0], tri[t][1], tri[t][2]));
    CHECK(tsr_mesh_drop_unused(&m, 12) == 0 && m.vertex_count == 12); /* none from 12 on */
    CHECK(tsr_mesh_drop_unused(&m, 4) == 2 && m.vertex_count == 10);  /* 6 and 9 */
    CHECK(m.positions[3 * 0] == 0.0f && m.positions[3 * 3] == 3.0f);  /* 0 and 3 kept: below `first` */
    CHECK(tsr_mesh_drop_unused(&m, 0) == 2);                          /* then 0 and 3 */
    CHECK(m.vertex_count == 8 && m.triangle_count == 3);
    for (int t = 0; t < 3; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t v = m.indices[3 * t + k];
            CHECK(v < 8 && m.positions[3 * v] == (float)tri[t][k] && m.normals[3 * v + 2] == (float)tri[t][k] &&
                  m.uvs[2 * v + 1] == -(float)tri[t][k]);
        }
    for (uint32_t v = 1; v < m.vertex_count; v++) /* the order kept */
        CHECK(m.positions[3 * v] > m.positions[3 * (v - 1)]);
    CHECK(tsr_mesh_drop_unused(&m, 0) == 0 && m.vertex_count == 8);
    tsr_mesh_free(&m);
}

TEST(normals_face_up)
{
    tsr_mesh m;
    fan(&m, 0);
    CHECK(tsr_mesh_compute_normals(&m) == TSR_OK);
    CHECK(m.normals != NULL);
    for (uint32_t i = 0; i < m.vertex_count; i++) {
        const float *n = m.normals + 3 * i;
        CHECK_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0, 1e-5);
        CHECK(n[2] > 0.5f);
    }
    CHECK_NEAR(m.normals[3 * 4 + 2], 1.0, 1e-6); /* apex of a symmetric fan */
    tsr_mesh_free(&m);
}

TEST(format_from_path)
{
    CHECK(tsr_mesh_format_from_path("a/b.OBJ") == TSR_FORMAT_OBJ);
    CHECK(tsr_mesh_format_from_path("x.ply") == TSR_FORMAT_PLY);
    CHECK(tsr_mesh_format_from_path("x.stl") == TSR_FORMAT_STL);
    CHECK(tsr_mesh_format_from_path("x.glb") == TSR_FORMAT_GLB);
    CHECK(tsr_mesh_format_from_path("x.gltf") == TSR_FORMAT_UNKNOWN);
    CHECK(tsr_mesh_format_from_path("dir.obj/x") == TSR_FORMAT_UNKNOWN);
    CHECK(tsr_mesh_format_from_path("noext") == TSR_FORMAT_UNKNOWN);
}

TEST(unwritable_output_leaves_nothing)
{
    tsr_mesh m;
    fan(&m, 0);
    tsr_error err = {0};
    CHECK(tsr_mesh_write(&m, "/nonexistent-dir/x.obj", TSR_FORMAT_UNKNOWN, &err) == TSR_ERR_IO);
    CHECK(strstr(err.message, "/nonexistent-dir/x.obj") != NULL);
    CHECK(!exists("/nonexistent-dir/x.obj"));
    const char *dir = check_temp_dir();
    char path[512];
    snprintf(path, sizeof path, "%s/ro", dir);
    CHECK(mkdir(path, 0500) == 0);
    snprintf(path, sizeof path, "%s/ro/x.ply", dir);
    tsr_status s = tsr_mesh_write(&m, path, TSR_FORMAT_UNKNOWN, &err);
    if (geteuid() != 0) { /* root may write anywhere */
        CHECK(s == TSR_ERR_IO);
        CHECK(!exists(path));
    }
    /* an index out of range is refused before anything is written */
    snprintf(path, sizeof path, "%s/bad.obj", dir);
    m.indices[2] = 77;
    CHECK(tsr_mesh_write(&m, path, TSR_FORMAT_UNKNOWN, &err) == TSR_ERR_ARGUMENT);
    CHECK(!exists(path));
    /* an empty mesh is refused */
    tsr_mesh e;
    tsr_mesh_init(&e, 0, NULL);
    CHECK(tsr_mesh_write(&e, path, TSR_FORMAT_UNKNOWN, &err) == TSR_ERR_ARGUMENT);
    CHECK(!exists(path));
    tsr_mesh_free(&m);
}

/* Writes "x" to path through the atomic calls; the status. */
static tsr_status atomic_write(const char *path, tsr_error *err)
{
    char tmp[4096];
    tsr_status st = tsr_atomic_begin(path, tmp, sizeof tmp, err);
    if (st != TSR_OK)
        return st;
    FILE *f = fopen(tmp, "w");
    if (!f) {
        tsr_atomic_abort(tmp);
        return TSR_ERR_IO;
    }
    fputs("x", f);
    fclose(f);
    return tsr_atomic_commit(tmp, path, err);
}

/* Outputs through symbolic links, over files with odd modes, to names
 * that look like our temporaries, and paths too long. */
TEST(atomic_output_links_and_modes)
{
    const char *dir = check_temp_dir();
    char real[512], link[512], odd[512], sub[512], slink[512];
    struct stat st;
    tsr_error err = {0};
    /* through a link: the file it points to is written, the link stays */
    snprintf(real, sizeof real, "%s/real.obj", dir);
    snprintf(link, sizeof link, "%s/link.obj", dir);
    FILE *f = fopen(real, "w");
    if (f)
        fclose(f);
    CHECK(chmod(real, 04750) == 0);
    CHECK(symlink("real.obj", link) == 0);
    CHECK(atomic_write(link, &err) == TSR_OK);
    CHECK(lstat(link, &st) == 0 && S_ISLNK(st.st_mode));
    /* the mode is kept, but not set-uid */
    CHECK_MSG(stat(real, &st) == 0 && st.st_size == 1 && (st.st_mode & 07777) == 0750, "mode %o size %ld",
              (unsigned)(st.st_mode & 07777), (long)st.st_size);
    /* a read-only file is not replaced, through the link neither */
    CHECK(chmod(real, 0444) == 0);
    CHECK(atomic_write(link, &err) == TSR_ERR_IO && strstr(err.message, "read-only"));
    CHECK(atomic_write(real, &err) == TSR_ERR_IO);
    CHECK(chmod(real, 0644) == 0);
    /* a name holding our temporaries' marker */
    snprintf(odd, sizeof odd, "%s/a.tsr-tmp-123456.obj", dir);
    CHECK(atomic_write(odd, &err) == TSR_OK && stat(odd, &st) == 0 && st.st_size == 1);
    /* a path too long is an argument error (the message, which names
     * the path, is cut short), not a link problem */
    char longp[5000];
    memset(longp, 'a', sizeof longp - 1);
    longp[sizeof longp - 1] = '\0';
    longp[0] = '/';
    tsr_status lst = atomic_write(longp, &err);
    CHECK_MSG(lst == TSR_ERR_ARGUMENT, "%d", (int)lst);
    /* a link in a sticky folder anyone writes to, owned by another user,
     * is not followed (as root, where we can give it away) */
    snprintf(sub, sizeof sub, "%s/sticky", dir);
    snprintf(slink, sizeof slink, "%s/sticky/out.obj", dir);
    if (geteuid() == 0 && mkdir(sub, 01777) == 0 && chmod(sub, 01777) == 0 && symlink(real, slink) == 0 &&
        lchown(slink, 65534, 65534) == 0) {
        CHECK(atomic_write(slink, &err) == TSR_ERR_IO && strstr(err.message, "sticky"));
        CHECK(stat(real, &st) == 0 && st.st_size == 1);
    }
    unlink(slink);
    rmdir(sub);
    unlink(odd);
    unlink(link);
    unlink(real);
}

/* An interrupted command's temporaries: tsr_atomic_remove_pending (what
 * tessera's SIGINT / SIGTERM handler calls) removes those begun and not
 * finished, and nothing committed or aborted. */
TEST(pending_temporaries_removed)
{
    const char *dir = check_temp_dir();
    char path[512], done[512], t1[4096], t2[4096], t3[4096];
    tsr_error err = {0};
    snprintf(path, sizeof path, "%s/pending.obj", dir);
    snprintf(done, sizeof done, "%s/done.obj", dir);
    CHECK(tsr_atomic_begin(path, t1, sizeof t1, &err) == TSR_OK && exists(t1));
    CHECK(tsr_atomic_begin(done, t2, sizeof t2, &err) == TSR_OK);
    CHECK(tsr_atomic_commit(t2, done, &err) == TSR_OK && exists(done));
    CHECK(tsr_atomic_begin(path, t3, sizeof t3, &err) == TSR_OK && exists(t3));
    tsr_atomic_abort(t3);
    /* a file of the aborted temporary's name made since is not touched */
    FILE *f = fopen(t3, "w");
    CHECK(f != NULL);
    if (f)
        fclose(f);
    tsr_atomic_remove_pending();
    CHECK(!exists(t1));
    CHECK(exists(done) && exists(t3));
    remove(done);
    remove(t3);
}

TEST(binary_layouts)
{
    tsr_mesh m;
    fan(&m, TSR_MESH_UVS);
    tsr_mesh_compute_normals(&m);
    const char *dir = check_temp_dir();
    char path[512];
    tsr_error err = {0};

    snprintf(path, sizeof path, "%s/m.stl", dir);
    CHECK(tsr_mesh_write(&m, path, TSR_FORMAT_UNKNOWN, &err) == TSR_OK);
    CHECK(file_size(path) == 84 + 50 * 4);
    FILE *f = fopen(path, "rb");
    unsigned char buf[4096];
    size_t n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    CHECK(n == 284 && memcmp(buf, "solid", 5) != 0 && rd32(buf + 80) == 4);

    snprintf(path, sizeof path, "%s/m.ply", dir);
    CHECK(tsr_mesh_write(&m, path, TSR_FORMAT_UNKNOWN, &err) == TSR_OK);
    f = fopen(path, "rb");
    n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    buf[n < sizeof buf ? n : sizeof buf - 1] = 0;
    char *end = strstr((char *)buf, "end_header\n");
    CHECK(end != NULL);
    if (end) {
        size_t header = (size_t)(end - (char *)buf) + 11;
        CHECK(n == header + 5 * 8 * 4 + 4 * 13);
        CHECK(strstr((char *)buf, "element vertex 5") && strstr((char *)buf, "element face 4"));
        float x;
        memcpy(&x, buf + header + 8 * 4 * 4 + 0, 4); /* vertex 4's x */
        CHECK(x == 0.5f);
    }

    snprintf(path, sizeof path, "%s/m.glb", dir);
    CHECK(tsr_mesh_write(&m, path, TSR_FORMAT_UNKNOWN, &err) == TSR_OK);
    f = fopen(path, "rb");
    n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    CHECK(rd32(buf) == 0x46546C67u && rd32(buf + 4) == 2 && rd32(buf + 8) == n);
    uint32_t jlen = rd32(buf + 12);
    CHECK(jlen % 4 == 0 && rd32(buf + 16) == 0x4E4F534Au);
    uint32_t blen = rd32(buf + 20 + jlen);
    CHECK(blen == 5 * 12 + 5 * 12 + 5 * 8 + 4 * 12);
    CHECK(20 + jlen + 8 + blen == n);

    snprintf(path, sizeof path, "%s/m.obj", dir);
    CHECK(tsr_mesh_write(&m, path, TSR_FORMAT_UNKNOWN, &err) == TSR_OK);
    f = fopen(path, "r");
    char line[256];
    int v = 0, vt = 0, vn = 0, fc = 0;
    while (fgets(line, sizeof line, f)) {
        v += !strncmp(line, "v ", 2);
        vt += !strncmp(line, "vt ", 3);
        vn += !strncmp(line, "vn ", 3);
        fc += !strncmp(line, "f ", 2);
    }
    fclose(f);
    CHECK(v == 5 && vt == 5 && vn == 5 && fc == 4);
    tsr_mesh_free(&m);
}

TEST(status_table)
{
    for (int s = 0; s < TSR_STATUS_COUNT; s++)
        CHECK(tsr_status_str((tsr_status)s) != NULL && strlen(tsr_status_str((tsr_status)s)) > 0);
    CHECK(strcmp(tsr_status_str((tsr_status)999), "unknown status") == 0);
    tsr_error e;
    CHECK(tsr_error_set(&e, TSR_ERR_VALUE, "%s: %d", "f.png", 3) == TSR_ERR_VALUE);
    CHECK(strcmp(e.message, "f.png: 3") == 0 && e.status == TSR_ERR_VALUE);
    CHECK(tsr_error_set(NULL, TSR_ERR_IO, "x") == TSR_ERR_IO);
}

static size_t counted;
static void *counting_realloc(void *user, void *p, size_t n)
{
    (void)user;
    if (n == 0) {
        free(p);
        counted--;
        return NULL;
    }
    if (!p)
        counted++;
    return realloc(p, n);
}

TEST(custom_allocator_is_used_and_balanced)
{
    tsr_allocator a = {counting_realloc, NULL, NULL};
    tsr_mesh m;
    tsr_mesh_init(&m, TSR_MESH_NORMALS, &a);
    float p[3] = {0, 0, 0};
    for (int i = 0; i < 100; i++)
        tsr_mesh_add_vertex(&m, p, NULL, NULL);
    tsr_mesh_add_triangle(&m, 0, 1, 2);
    CHECK(counted == 3);
    tsr_validation v;
    CHECK(tsr_mesh_validate(&m, NULL, &v) == TSR_OK);
    CHECK(counted == 3);
    tsr_mesh_free(&m);
    CHECK(counted == 0);
}

static size_t dense_calls;
static void *counting_dense(void *user, size_t n)
{
    dense_calls++;
    return counting_realloc(user, NULL, n);
}

/* A caller's allocator with alloc_dense gets the blocks made to be
 * written at once (tsr_alloc_dense, a mesh's reserve_dense), and frees them
 * through its realloc; without alloc_dense, its realloc makes them. */
TEST(custom_allocator_dense_blocks)
{
    tsr_allocator a = {counting_realloc, NULL, counting_dense}, plain = {counting_realloc, NULL, NULL};
    size_t before = counted;
    void *p = tsr_alloc_dense(&a, 5000);
    CHECK(p && dense_calls == 1 && counted == before + 1);
    p = tsr_realloc(&a, p, 9000);
    CHECK(p && dense_calls == 1 && counted == before + 1);
    tsr_free(&a, p);
    p = tsr_alloc_dense(&plain, 5000);
    CHECK(p && dense_calls == 1 && counted == before + 1);
    tsr_free(&plain, p);
    tsr_mesh m;
    tsr_mesh_init(&m, TSR_MESH_NORMALS, &a);
    CHECK(tsr_mesh_reserve_dense(&m, 1000, 2000) == TSR_OK && dense_calls == 4); /* positions, normals, indices */
    float q[3] = {0, 0, 0};
    for (int i = 0; i < 1500; i++) /* (grown by realloc) */
        CHECK(tsr_mesh_add_vertex(&m, q, q, NULL) == (uint32_t)i);
    CHECK(dense_calls == 4 && counted == before + 3);
    tsr_mesh_free(&m);
    CHECK(counted == before);
}

/* tsr_keymap_clear empties the map and keeps its room: the same keys go
 * back without growing, old keys are gone. */
TEST(keymap_clear_keeps_room)
{
    tsr_keymap m = {0};
    tsr_keymap_clear(&m); /* an empty map */
    CHECK(m.count == 0 && !m.slots);
    bool found;
    for (uint64_t k = 0; k < 300; k++)
        *tsr_keymap_slot(&m, k * 7919, &found, NULL) = (uint32_t)k;
    size_t mask = m.mask;
    tsr_keymap_clear(&m);
    CHECK(m.count == 0 && m.mask == mask);
    for (uint64_t k = 0; k < 300; k++)
        CHECK(!tsr_keymap_find(&m, k * 7919));
    for (uint64_t k = 0; k < 300; k++) {
        *tsr_keymap_slot(&m, k * 7919 + 1, &found, NULL) = (uint32_t)(k + 5);
        CHECK(!found);
    }
    CHECK(m.count == 300 && m.mask == mask);
    for (uint64_t k = 0; k < 300; k++) {
        const uint32_t *v = tsr_keymap_find(&m, k * 7919 + 1);
        CHECK(v && *v == k + 5);
    }
    tsr_keymap_free(&m, NULL);
}

/* tsr_cpu_count follows the process's CPU affinity (what a Slurm job or
 * a container is given), not the machine's processor count. */
TEST(cpu_count_follows_affinity)
{
    uint32_t all = tsr_cpu_count();
    long online = sysconf(_SC_NPROCESSORS_ONLN);
    CHECK(all >= 1 && (online <= 0 || all <= (uint32_t)online));
    cpu_set_t was, one;
    if (sched_getaffinity(0, sizeof was, &was) != 0)
        SKIP("no CPU affinity here");
    int first = -1;
    for (int c = 0; c < CPU_SETSIZE && first < 0; c++)
        if (CPU_ISSET(c, &was))
            first = c;
    CPU_ZERO(&one);
    CPU_SET(first, &one);
    if (sched_setaffinity(0, sizeof one, &one) != 0)
        SKIP("cannot narrow the CPU affinity");
    CHECK_MSG(tsr_cpu_count() == 1, "%u CPUs on one", tsr_cpu_count());
    CHECK(sched_setaffinity(0, sizeof was, &was) == 0);
    CHECK(tsr_cpu_count() == all);
}

/* tsr__cpu_quota reads a CPU bandwidth limit as cgroups write it: whole
 * CPUs rounded up, 0 for none or for anything malformed. */
TEST(cpu_quota_text)
{
    static const struct {
        const char *text;
        uint32_t cpus;
    } cases[] = {
        {"max 100000\n", 0},      {"200000 100000\n", 2},     {"150000 100000", 2},   {"50000 100000\n", 1},
        {"100000 100000", 1},     {"1 100000", 1},            {"400000 50000\n", 8}, {"-1 100000", 0},
        {"", 0},                  {"abc", 0},                 {"100000", 0},          {"100000 0", 0},
        {"100000 -5", 0},         {"100000 100000 x", 0},     {"0 100000", 0},        {"12x 100000", 0},
        {"9223372036854775807 1", UINT32_MAX},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++)
        CHECK_MSG(tsr__cpu_quota(cases[k].text) == cases[k].cpus, "\"%s\": %u, want %u", cases[k].text,
                  tsr__cpu_quota(cases[k].text), cases[k].cpus);
}

/* The default allocator's three kinds of block (malloc'd, mapped when new
 * from 1 MiB, mapped from 8 MiB) keep their contents through every growth
 * and shrink between kinds (a mapped block grows in place or by mremap),
 * come back aligned to 16 bytes (malloc's) at least, and can be written to
 * the last byte; so do blocks from tsr_alloc_dense. A mesh reserved dense
 * after a small reserve (its arrays made anew) keeps what it holds. */
TEST(default_allocator_kinds)
{
    static const size_t sizes[] = {24, 4000, 700000, (size_t)1 << 20, 3000000, (size_t)9 << 20, 5000000, 100, 40 << 20,
                                   2 << 20, 1};
    size_t n = sizeof sizes / sizeof sizes[0];
    /* a block made at each size, then grown or shrunk through the others */
    for (size_t start = 0; start < 2 * n; start++) {
        size_t have = sizes[start % n];
        /* (the second round's first blocks from tsr_alloc_dense) */
        unsigned char *p = start < n ? tsr_alloc(NULL, have) : tsr_alloc_dense(NULL, have);
        CHECK_MSG(p && ((uintptr_t)p & 15) == 0, "alloc %zu", have);
        if (!p)
            continue;
        for (size_t i = 0; i < have; i++)
            p[i] = (unsigned char)(i * 7 + start);
        for (size_t k = 1; k < n; k++) {
            size_t want = sizes[(start + k) % n];
            unsigned char *q = tsr_realloc(NULL, p, want);
            CHECK_MSG(q && ((uintptr_t)q & 15) == 0, "realloc %zu -> %zu", have, want);
            if (!q)
                break;
            size_t keep = have < want ? have : want, bad = 0;
            for (size_t i = 0; i < keep; i++)
                bad += q[i] != (unsigned char)(i * 7 + start);
            CHECK_MSG(bad == 0, "realloc %zu -> %zu (start %zu): %zu bytes changed", have, want, start, bad);
            for (size_t i = keep; i < want; i++)
                q[i] = (unsigned char)(i * 7 + start);
            p = q;
            have = want;
        }
        tsr_free(NULL, p);
    }
    tsr_mesh m;
    tsr_mesh_init(&m, TSR_MESH_NORMALS, NULL);
    CHECK(tsr_mesh_reserve(&m, 4, 4) == TSR_OK && m.vertex_capacity == 4 && m.triangle_capacity == 4);
    CHECK(tsr_mesh_reserve_dense(&m, 200000, 300000) == TSR_OK && m.vertex_capacity == 200000 &&
          m.triangle_capacity == 300000);
    for (uint32_t i = 0; i < 200000; i++) {
        float p[3] = {(float)i, 1, 2}, nn[3] = {0, 0, 1};
        CHECK(tsr_mesh_add_vertex(&m, p, nn, NULL) == i);
    }
    for (uint32_t i = 0; i + 2 < 200000; i += 2)
        tsr_mesh_add_triangle(&m, i, i + 1, i + 2);
    CHECK(tsr_mesh_reserve_dense(&m, 400000, 600000) == TSR_OK); /* (grown: it holds vertices now) */
    bool same = m.vertex_count == 200000 && m.triangle_count == 99999;
    for (uint32_t i = 0; same && i < m.vertex_count; i++)
        same = m.positions[3 * i] == (float)i && m.normals[3 * i + 2] == 1;
    for (uint32_t t = 0; same && t < m.triangle_count; t++)
        same = m.indices[3 * t] == 2 * t && m.indices[3 * t + 2] == 2 * t + 2;
    CHECK_MSG(same, "the mesh changed when reserved again");
    tsr_mesh_free(&m);
}

/* Writes text to root/rel, making its folders. */
static void put_file(const char *root, const char *rel, const char *text)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", root, rel);
    for (char *c = path + strlen(root) + 1; *c; c++)
        if (*c == '/') {
            *c = 0;
            mkdir(path, 0700);
            *c = '/';
        }
    FILE *f = fopen(path, "w");
    CHECK_MSG(f != NULL, "cannot write %s", path);
    if (f) {
        fputs(text, f);
        fclose(f);
    }
}

/* tsr__cgroup_cpus on made-up cgroup trees: the smallest limit on the
 * way from the process's cgroup up to the mount's root, for v2 alone,
 * v2 under unified/ beside v1, v1's cpu controller (and not cpuset's or
 * cpuacct's files), a path that is not there (a container's namespace
 * shows the host's path: the limit at the root counts). */
TEST(cgroup_cpu_limits)
{
    char root[] = "/tmp/tsr_cgroupXXXXXX";
    if (!mkdtemp(root))
        SKIP("no temporary folder");
    char cg[600], cmd[700];
    snprintf(cg, sizeof cg, "%s/self_cgroup", root);
    static const struct {
        const char *cgroup, *files[4][2];
        uint32_t cpus;
    } cases[] = {
        /* v2: the tightest of the ancestors (3 at /a, none above or below) */
        {"0::/a/b\n", {{"v2/cpu.max", "max 100000\n"}, {"v2/a/cpu.max", "300000 100000\n"},
                       {"v2/a/b/cpu.max", "max 100000\n"}}, 3},
        {"0::/a/b\n", {{"v2/cpu.max", "100000 100000\n"}, {"v2/a/cpu.max", "300000 100000\n"}}, 1},
        /* hybrid: v2 under unified/, v1 lines without cpu */
        {"5:memory:/x\n0::/s\n", {{"v2/unified/s/cpu.max", "150000 100000\n"}}, 2},
        /* v1 cpu,cpuacct: half a CPU at /k8s, none at the pod */
        {"4:memory:/x\n3:cpu,cpuacct:/k8s/pod\n0::/\n",
         {{"v2/cpu,cpuacct/k8s/cpu.cfs_quota_us", "50000\n"}, {"v2/cpu,cpuacct/k8s/cpu.cfs_period_us", "100000\n"},
          {"v2/cpu,cpuacct/k8s/pod/cpu.cfs_quota_us", "-1\n"}, {"v2/cpu,cpuacct/k8s/pod/cpu.cfs_period_us", "100000\n"}},
         1},
        {"2:cpu:/j\n", {{"v2/cpu/j/cpu.cfs_quota_us", "250000\n"}, {"v2/cpu/j/cpu.cfs_period_us", "100000\n"}}, 3},
        /* cpuset's and cpuacct's folders are not the cpu controller's */
        {"2:cpuset:/j\n1:cpuacct:/j\n",
         {{"v2/cpuset/j/cpu.cfs_quota_us", "50000\n"}, {"v2/cpuset/j/cpu.cfs_period_us", "100000\n"},
          {"v2/cpuacct/j/cpu.cfs_quota_us", "50000\n"}, {"v2/cpuacct/j/cpu.cfs_period_us", "100000\n"}},
         0},
        /* the host's path, not in this mount: the root's limit */
        {"0::/docker/abc\n", {{"v2/cpu.max", "200000 100000\n"}}, 2},
        /* no limit anywhere, or an unreadable limit */
        {"0::/a\n", {{"v2/cpu.max", "max 100000\n"}, {"v2/a/cpu.max", "max 100000\n"}}, 0},
        {"0::/a\n", {{"v2/a/cpu.max", "lots\n"}}, 0},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        snprintf(cmd, sizeof cmd, "rm -rf '%s/v2'", root);
        CHECK(system(cmd) == 0);
        put_file(root, "self_cgroup", cases[k].cgroup);
        for (int f = 0; f < 4 && cases[k].files[f][0]; f++)
            put_file(root, cases[k].files[f][0], cases[k].files[f][1]);
        char base[600];
        snprintf(base, sizeof base, "%s/v2", root);
        mkdir(base, 0700);
        uint32_t got = tsr__cgroup_cpus(cg, base);
        CHECK_MSG(got == cases[k].cpus, "case %zu (%s): %u CPUs, want %u", k, cases[k].cgroup, got, cases[k].cpus);
    }
    snprintf(cmd, sizeof cmd, "%s/none", root);
    CHECK(tsr__cgroup_cpus(cmd, root) == 0); /* no such file */
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", root);
    CHECK(system(cmd) == 0);
}

TEST_MAIN(T(container_grows), T(drop_unused_keeps_the_used_in_order), T(normals_face_up), T(format_from_path),
          T(unwritable_output_leaves_nothing), T(pending_temporaries_removed), T(atomic_output_links_and_modes),
          T(binary_layouts), T(status_table), T(custom_allocator_is_used_and_balanced), T(keymap_clear_keeps_room),
          T(cpu_count_follows_affinity), T(cpu_quota_text), T(cgroup_cpu_limits), T(default_allocator_kinds),
          T(custom_allocator_dense_blocks))
