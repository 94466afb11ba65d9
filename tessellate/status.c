/* status.c: the one table of status codes and messages, and allocators. */
#define _GNU_SOURCE /* madvise, MADV_HUGEPAGE */
#include "tessellate/tessellate.h"

#include <sys/mman.h>

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

/* Large fresh blocks (pyramids, heightfields) are aligned to 2 MiB and
 * marked for transparent huge pages: on virtual machines a 4 KiB page
 * fault can cost ~10 us, which made first touch dominate the pyramid
 * build (a 32 MiB array: 8192 faults, against 16 with huge pages). */
static void *default_realloc(void *user, void *ptr, size_t size)
{
    (void)user;
    if (size == 0) {
        free(ptr);
        return NULL;
    }
    const size_t huge = (size_t)2 << 20;
    if (!ptr && size >= 2 * huge) {
        void *p = NULL;
        if (posix_memalign(&p, huge, size) != 0)
            return NULL;
#ifdef MADV_HUGEPAGE
        madvise(p, size, MADV_HUGEPAGE); /* advice only: failure is harmless */
#endif
        return p;
    }
    return realloc(ptr, size);
}

void *tsr_alloc(const tsr_allocator *a, size_t size)
{
    if (size == 0)
        size = 1;
    return a && a->realloc ? a->realloc(a->user, NULL, size) : default_realloc(NULL, NULL, size);
}

void *tsr_realloc(const tsr_allocator *a, void *ptr, size_t size)
{
    if (size == 0)
        size = 1;
    return a && a->realloc ? a->realloc(a->user, ptr, size) : default_realloc(NULL, ptr, size);
}

void tsr_free(const tsr_allocator *a, void *ptr)
{
    if (!ptr)
        return;
    if (a && a->realloc)
        a->realloc(a->user, ptr, 0);
    else
        free(ptr);
}
