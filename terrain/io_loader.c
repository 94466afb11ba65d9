/* io_loader.c: opens the I/O module (io_module.h) the first time an image
 * or GIS file is read or written, and forwards to it. */
#define _POSIX_C_SOURCE 200809L
#include "terrain/io_module.h"

#include <dlfcn.h>
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#ifndef TSR_IO_MODULE_BUILD_PATH
#define TSR_IO_MODULE_BUILD_PATH ""
#endif

static pthread_once_t once = PTHREAD_ONCE_INIT;
static const tsr_io_api *api;
static char why[1024]; /* where the module was looked for, when not found */

static bool try_open(const char *path)
{
    if (!path || !*path)
        return false;
    void *h = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!h) {
        const char *e = dlerror();
        size_t n = strlen(why);
        snprintf(why + n, sizeof why - n, "%s%s", n ? "; " : "", e ? e : path);
        return false;
    }
    const tsr_io_api *(*get)(void);
    void *sym = dlsym(h, TSR_IO_MODULE_SYMBOL);
    memcpy(&get, &sym, sizeof get);
    const tsr_io_api *a = sym ? get() : NULL;
    if (!a || a->version != TSR_IO_MODULE_VERSION || a->size != sizeof(tsr_io_api)) {
        size_t n = strlen(why);
        snprintf(why + n, sizeof why - n, "%s%s: not this build's module", n ? "; " : "", path);
        dlclose(h);
        return false;
    }
    api = a;
    /* an interrupted command removes the module's temporaries too */
    tsr__atomic_remove_also = a->remove_pending;
    return true;
}

static void load(void)
{
    if (try_open(getenv("TESSERA_IO_MODULE")))
        return;
    char exe[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n > 0) {
        exe[n] = '\0';
        char *slash = strrchr(exe, '/');
        char path[PATH_MAX + 32];
        if (slash) {
            *slash = '\0';
            snprintf(path, sizeof path, "%s/%s", exe, TSR_IO_MODULE_FILE);
            if (try_open(path))
                return;
        }
    }
    try_open(TSR_IO_MODULE_BUILD_PATH);
}

static const tsr_io_api *module(tsr_error *err)
{
    pthread_once(&once, load);
    if (!api)
        tsr_error_set(err, TSR_ERR_UNSUPPORTED,
                      "cannot load Tessera's image and GIS module " TSR_IO_MODULE_FILE
                      " (set TESSERA_IO_MODULE to its path): %s",
                      why[0] ? why : "not found");
    return api;
}

tsr_status tsr_image_read(const char *path, const tsr_allocator *alloc, uint64_t max_samples, float **pixels,
                          tsr_image_info *info, tsr_error *err)
{
    *pixels = NULL;
    memset(info, 0, sizeof *info);
    const tsr_io_api *a = module(err);
    return a ? a->image_read(path, alloc, max_samples, pixels, info, err) : TSR_ERR_UNSUPPORTED;
}

tsr_status tsr_image_write(const char *path, const char *tmp, uint32_t width, uint32_t height, const float *values,
                           bool as_u16, double scale, double offset, double dx, double dy, tsr_error *err)
{
    const tsr_io_api *a = module(err);
    return a ? a->image_write(path, tmp, width, height, values, as_u16, scale, offset, dx, dy, err)
             : TSR_ERR_UNSUPPORTED;
}

tsr_status tsr_image_save_check(const char *path, tsr_error *err)
{
    const tsr_io_api *a = module(err);
    return a ? a->image_save_check(path, err) : TSR_ERR_UNSUPPORTED;
}

tsr_status tsr_image_save_u8_rows(const char *path, uint32_t width, uint32_t height, uint32_t channels,
                                  void (*fill)(void *user, uint32_t y0, uint32_t y1, uint8_t *rows), void *user,
                                  tsr_error *err)
{
    const tsr_io_api *a = module(err);
    return a ? a->image_save_u8_rows(path, width, height, channels, fill, user, err) : TSR_ERR_UNSUPPORTED;
}

typedef struct whole_image {
    const uint8_t *pixels;
    size_t row;
} whole_image;

static void copy_rows(void *user, uint32_t y0, uint32_t y1, uint8_t *rows)
{
    const whole_image *w = user;
    memcpy(rows, w->pixels + (size_t)y0 * w->row, (size_t)(y1 - y0) * w->row);
}

tsr_status tsr_image_save_u8(const char *path, uint32_t width, uint32_t height, uint32_t channels,
                             const uint8_t *pixels, tsr_error *err)
{
    if (!pixels)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: nothing to write (no pixels)", path ? path : "(null)");
    whole_image w = {pixels, (size_t)width * channels};
    return tsr_image_save_u8_rows(path, width, height, channels, copy_rows, &w, err);
}

bool tsr_gdal_georef(const char *path, uint32_t w, uint32_t h, tsr_georef *g)
{
    memset(g, 0, sizeof *g);
    g->z_scale = 1;
    const tsr_io_api *a = module(NULL);
    return a ? a->gdal_georef(path, w, h, g) : false;
}

tsr_status tsr_gdal_read(const char *path, const tsr_allocator *alloc, uint64_t max_samples, float **pixels,
                         uint32_t *w, uint32_t *h, char format[64], tsr_georef *g, tsr_error *err)
{
    *pixels = NULL;
    const tsr_io_api *a = module(err);
    return a ? a->gdal_read(path, alloc, max_samples, pixels, w, h, format, g, err) : TSR_ERR_UNSUPPORTED;
}
