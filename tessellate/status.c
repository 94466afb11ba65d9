/* status.c: the one table of status codes and messages, and allocators. */
#define _GNU_SOURCE /* madvise, MADV_HUGEPAGE */
#include "tessellate/tessellate.h"

#include <errno.h>
#include <stdint.h>
#include <string.h>
#include <sched.h>
#include <sys/mman.h>
#include <unistd.h>

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

static const char *const status_messages[TSR_STATUS_COUNT] = {
    [TSR_OK] = "ok",
    [TSR_ERR_ARGUMENT] = "invalid argument",
    [TSR_ERR_NOT_FOUND] = "no such file",
    [TSR_ERR_IO] = "input/output error",
    [TSR_ERR_EMPTY] = "empty file",
    [TSR_ERR_FORMAT] = "not a recognised file format",
    [TSR_ERR_TRUNCATED] = "truncated file",
    [TSR_ERR_TOO_LARGE] = "too large",
    [TSR_ERR_TOO_SMALL] = "too small",
    [TSR_ERR_VALUE] = "value out of range",
    [TSR_ERR_UNSUPPORTED] = "unsupported",
    [TSR_ERR_NOMEM] = "out of memory",
    [TSR_ERR_INVALID_MESH] = "invalid mesh",
};

const char *tsr_status_str(tsr_status s)
{
    if ((unsigned)s >= TSR_STATUS_COUNT)
        return "unknown status";
    return status_messages[s];
}

tsr_status tsr_error_set(tsr_error *err, tsr_status status, const char *fmt, ...)
{
    if (err) {
        err->status = status;
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return status;
}

/* The default allocator. Blocks of 8 MiB and more (pyramids,
 * heightfields, meshes), and from 1 MiB blocks made to be written at once
 * (tsr_alloc_dense), are mapped and populated at once: on virtual machines a
 * first-touch page fault can cost ~10 us per 4 KiB page, which made
 * faults, not work, dominate the pyramid build. Where the kernel allows,
 * the mapping asks for transparent huge pages first and is then populated
 * for writing (MADV_POPULATE_WRITE, Linux 5.14): 512 times fewer faults,
 * and measured here 3-8x faster than MAP_POPULATE alone, whose pages were
 * still slow on first write. Elsewhere, MAP_POPULATE. Every block carries
 * a small header saying how it was made, so realloc and free take the
 * matching path. */
typedef struct block_header {
    size_t size;   /* usable bytes */
    size_t mapped; /* mapping length when mmap'd, else 0 */
    size_t pad[2]; /* the user pointer: 32-byte aligned in a mapping, as malloc's (16) otherwise */
} block_header;

#define BIG_BLOCK ((size_t)8 << 20)
/* A new block its caller will write at once (tsr_alloc_dense) is mapped
 * from this size on, saving a fault per 4 KiB page; others stay with
 * malloc up to BIG_BLOCK (mapping and populating every new block from 1
 * MiB made the patch tessellator 1.5x slower in its bench, whose runs
 * reuse a warm heap: a few blocks of 1-2 MiB a run were mapped, populated
 * and unmapped each time instead). */
#define MEDIUM_BLOCK ((size_t)1 << 20)

static void *map_populated(size_t len)
{
#if defined(MADV_HUGEPAGE) && defined(MADV_POPULATE_WRITE)
    void *m = mmap(NULL, len, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (m == MAP_FAILED)
        return NULL;
    (void)madvise(m, len, MADV_HUGEPAGE); /* (a hint: refused where THP is off) */
    if (madvise(m, len, MADV_POPULATE_WRITE) == 0)
        return m;
    int e = errno;
    munmap(m, len);
    if (e == ENOMEM) /* out of memory (MAP_POPULATE would not say so) */
        return NULL;
#endif /* (a kernel before 5.14, or a sandbox refusing the advice: the plain way) */
    void *p = mmap(NULL, len, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_POPULATE, -1, 0);
    return p == MAP_FAILED ? NULL : p;
}

/* A block of size bytes, mapped from map_from on. */
static void *block_new(size_t size, size_t map_from)
{
    if (size > SIZE_MAX - sizeof(block_header) - 4096)
        return NULL;
    block_header *h;
    if (size >= map_from) {
        size_t len = (size + sizeof *h + 4095) & ~(size_t)4095;
        void *m = map_populated(len);
        if (!m)
            return NULL;
        h = m;
        h->mapped = len;
    } else {
        h = malloc(sizeof *h + size);
        if (!h)
            return NULL;
        h->mapped = 0;
    }
    h->size = size;
    return h + 1;
}

static void block_free(void *ptr)
{
    block_header *h = (block_header *)ptr - 1;
    if (h->mapped)
        munmap(h, h->mapped);
    else
        free(h);
}

static void *default_realloc(void *user, void *ptr, size_t size)
{
    (void)user;
    if (size == 0) {
        if (ptr)
            block_free(ptr);
        return NULL;
    }
    if (!ptr)
        return block_new(size, BIG_BLOCK);
    block_header *h = (block_header *)ptr - 1;
    if (!h->mapped && size < BIG_BLOCK) {
        block_header *n = realloc(h, sizeof *n + size);
        if (!n)
            return NULL;
        n->size = size;
        return n + 1;
    }
    if (h->mapped && size + sizeof *h <= h->mapped && size >= h->mapped / 2) {
        h->size = size; /* fits in the mapping */
        return ptr;
    }
#ifdef MREMAP_MAYMOVE
    if (h->mapped && size > h->size) { /* grown in the page tables, not copied */
        size_t len = (size + sizeof *h + 4095) & ~(size_t)4095;
        void *m = mremap(h, h->mapped, len, MREMAP_MAYMOVE);
        if (m != MAP_FAILED) {
            char *tail = (char *)m + ((block_header *)m)->mapped;
            size_t more = len - ((block_header *)m)->mapped;
#if defined(MADV_HUGEPAGE) && defined(MADV_POPULATE_WRITE)
            (void)madvise(tail, more, MADV_HUGEPAGE);
            (void)madvise(tail, more, MADV_POPULATE_WRITE); /* (else faulted as written) */
#else
            (void)tail, (void)more;
#endif
            h = m;
            h->mapped = len;
            h->size = size;
            return h + 1;
        }
    }
#endif
    void *q = block_new(size, BIG_BLOCK);
    if (!q)
        return NULL;
    memcpy(q, ptr, h->size < size ? h->size : size);
    block_free(ptr);
    return q;
}

void *tsr_alloc(const tsr_allocator *a, size_t size)
{
    if (size == 0)
        size = 1;
    return a && a->realloc ? a->realloc(a->user, NULL, size) : default_realloc(NULL, NULL, size);
}

void *tsr_alloc_dense(const tsr_allocator *a, size_t size)
{
    if (size == 0)
        size = 1;
    if (a && a->realloc)
        return a->alloc_dense ? a->alloc_dense(a->user, size) : a->realloc(a->user, NULL, size);
    return block_new(size, MEDIUM_BLOCK);
}

void *tsr_realloc(const tsr_allocator *a, void *ptr, size_t size)
{
    if (size == 0)
        size = 1;
    return a && a->realloc ? a->realloc(a->user, ptr, size) : default_realloc(NULL, ptr, size);
}

uint32_t tsr__cpu_quota(const char *text)
{
    /* "QUOTA PERIOD" in microseconds; "max" or a negative quota: none */
    char *end;
    errno = 0;
    long long quota = strtoll(text, &end, 10);
    if (end == text || errno || quota <= 0)
        return 0;
    long long period = strtoll(end, &end, 10);
    if (errno || period <= 0)
        return 0;
    while (*end == ' ' || *end == '\t' || *end == '\n')
        end++;
    if (*end)
        return 0;
    long long n = quota / period + (quota % period != 0);
    return n > UINT32_MAX ? UINT32_MAX : (uint32_t)n;
}

/* The tighter of two CPU limits, 0 meaning none. */
static uint32_t tighter(uint32_t a, uint32_t b)
{
    return a && (!b || a < b) ? a : b;
}

/* The first line of a file, NUL-terminated; false when unreadable. */
static bool read_line(const char *path, char *buf, size_t size)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return false;
    bool ok = fgets(buf, (int)size, f) != NULL;
    fclose(f);
    return ok;
}

/* The smallest CPU limit (tsr__cpu_quota) of the cgroup at path under
 * the mount at base and of its ancestors up to base: v2's cpu.max, or
 * v1's cfs quota and period; 0 where none is set. */
static uint32_t quota_up(const char *base, const char *path, bool v2)
{
    char dir[512], file[600], a[64], b[64], text[160];
    if (snprintf(dir, sizeof dir, "%s%s", base, strcmp(path, "/") ? path : "") >= (int)sizeof dir)
        return 0;
    uint32_t best = 0;
    size_t root = strlen(base);
    for (;;) {
        uint32_t n = 0;
        if (v2) {
            snprintf(file, sizeof file, "%s/cpu.max", dir);
            if (read_line(file, text, sizeof text))
                n = tsr__cpu_quota(text);
        } else {
            snprintf(file, sizeof file, "%s/cpu.cfs_quota_us", dir);
            bool got = read_line(file, a, sizeof a);
            snprintf(file, sizeof file, "%s/cpu.cfs_period_us", dir);
            if (got && read_line(file, b, sizeof b)) {
                a[strcspn(a, "\n")] = 0;
                snprintf(text, sizeof text, "%s %s", a, b);
                n = tsr__cpu_quota(text);
            }
        }
        best = tighter(n, best);
        char *slash = strrchr(dir, '/');
        if (!slash || (size_t)(slash - dir) < root)
            break;
        *slash = 0;
    }
    return best;
}

uint32_t tsr__cgroup_cpus(const char *cgroups, const char *root)
{
    FILE *f = fopen(cgroups, "r");
    if (!f)
        return 0;
    char line[512];
    uint32_t best = 0;
    while (fgets(line, sizeof line, f)) {
        line[strcspn(line, "\n")] = 0;
        /* "ID:CONTROLLERS:PATH"; v2's is "0::PATH" */
        char *c1 = strchr(line, ':'), *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
        if (!c2 || c2[1] != '/')
            continue;
        *c2 = 0;
        const char *ctl = c1 + 1, *path = c2 + 1;
        uint32_t n = 0;
        char base[256];
        if (!*ctl) { /* at the root (v2 alone) or under unified/ (hybrid) */
            n = quota_up(root, path, true);
            snprintf(base, sizeof base, "%s/unified", root);
            n = tighter(quota_up(base, path, true), n);
        } else {
            bool cpu = false; /* "cpu" among the comma-separated controllers */
            for (const char *t = ctl; *t;) {
                size_t len = strcspn(t, ",");
                cpu = cpu || (len == 3 && !strncmp(t, "cpu", 3));
                t += len + (t[len] == ',');
            }
            if (!cpu)
                continue;
            static const char *const mounts[] = {"cpu", "cpu,cpuacct", "cpuacct,cpu"};
            for (size_t k = 0; k < sizeof mounts / sizeof mounts[0]; k++) {
                snprintf(base, sizeof base, "%s/%s", root, mounts[k]);
                n = tighter(quota_up(base, path, false), n);
            }
        }
        best = tighter(n, best);
    }
    fclose(f);
    return best;
}

uint32_t tsr_cpu_count(void)
{
    uint32_t n = 0;
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) == 0)
        n = (uint32_t)CPU_COUNT(&set);
    if (n == 0) {
        long online = sysconf(_SC_NPROCESSORS_ONLN);
        n = online > 0 ? (uint32_t)online : 1;
    }
    uint32_t quota = tsr__cgroup_cpus("/proc/self/cgroup", "/sys/fs/cgroup");
    return tighter(quota, n);
}

void tsr_free(const tsr_allocator *a, void *ptr)
{
    if (!ptr)
        return;
    if (a && a->realloc)
        a->realloc(a->user, ptr, 0);
    else
        default_realloc(NULL, ptr, 0);
}
