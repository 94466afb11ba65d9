/* status.c: the one table of status codes and messages, and allocators. */
#include "tessellate/tessellate.h"

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

static void *default_realloc(void *user, void *ptr, size_t size)
{
    (void)user;
    if (size == 0) {
        free(ptr);
        return NULL;
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
