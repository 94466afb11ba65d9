/* io_module.h: the image and GIS readers and writers, built as a module of
 * their own (libtessera_io.so: image_io.cpp over OpenImageIO, gdal_io.c
 * over GDAL) that the terrain library opens the first time it needs one.
 * OpenImageIO and GDAL pull in about 250 shared libraries, and loading
 * them costs a process about 0.4 s on the development machine: linked
 * into tessera, every command paid it, `tessera patch`, `triangulate` and
 * `--help` included, which read no image.
 *
 * The module exports one symbol, tsr_io_module_api, returning the table
 * below; terrain/io_loader.c opens the module and implements the
 * tsr_image_* and tsr_gdal_* functions of terrain_internal.h (and
 * terrain.h's tsr_image_save_u8, tsr_image_save_check) through it. The
 * module looks for: $TESSERA_IO_MODULE, then libtessera_io.so beside the
 * running executable, then the build tree's copy. */
#ifndef TSR_IO_MODULE_H
#define TSR_IO_MODULE_H

#include "terrain/terrain_internal.h"

#ifdef __cplusplus
extern "C" {
#endif

#define TSR_IO_MODULE_FILE "libtessera_io.so"
#define TSR_IO_MODULE_SYMBOL "tsr_io_module_api"
#define TSR_IO_MODULE_VERSION 4

typedef struct tsr_io_api {
    int version; /* TSR_IO_MODULE_VERSION */
    size_t size; /* sizeof(tsr_io_api): loader and module built together */
    tsr_status (*image_read)(const char *path, const tsr_allocator *alloc, uint64_t max_samples, float **pixels,
                             tsr_image_info *info, tsr_error *err);
    tsr_status (*image_write)(const char *path, const char *tmp, uint32_t width, uint32_t height,
                              const float *values, bool as_u16, double scale, double offset, double dx, double dy,
                              tsr_error *err);
    tsr_status (*image_save_check)(const char *path, tsr_error *err);
    tsr_status (*image_save_u8_rows)(const char *path, uint32_t width, uint32_t height, uint32_t channels,
                                     void (*fill)(void *user, uint32_t y0, uint32_t y1, uint8_t *rows), void *user,
                                     tsr_error *err);
    bool (*gdal_georef)(const char *path, uint32_t w, uint32_t h, tsr_georef *g);
    tsr_status (*gdal_read)(const char *path, const tsr_allocator *alloc, uint64_t max_samples, float **pixels,
                            uint32_t *w, uint32_t *h, char format[64], tsr_georef *g, tsr_error *err);
    /* the module's own tsr_atomic_remove_pending (its image temporaries):
     * async-signal-safe, for the command's signal handler */
    void (*remove_pending)(void);
} tsr_io_api;

/* The module's implementations (not exported; reached through the table). */
tsr_status tsr_io_image_read(const char *path, const tsr_allocator *alloc, uint64_t max_samples, float **pixels,
                             tsr_image_info *info, tsr_error *err);
tsr_status tsr_io_image_write(const char *path, const char *tmp, uint32_t width, uint32_t height,
                              const float *values, bool as_u16, double scale, double offset, double dx, double dy,
                              tsr_error *err);
tsr_status tsr_io_image_save_check(const char *path, tsr_error *err);
tsr_status tsr_io_image_save_u8_rows(const char *path, uint32_t width, uint32_t height, uint32_t channels,
                                     void (*fill)(void *user, uint32_t y0, uint32_t y1, uint8_t *rows), void *user,
                                     tsr_error *err);
bool tsr_io_gdal_georef(const char *path, uint32_t w, uint32_t h, tsr_georef *g);
tsr_status tsr_io_gdal_read(const char *path, const tsr_allocator *alloc, uint64_t max_samples, float **pixels,
                            uint32_t *w, uint32_t *h, char format[64], tsr_georef *g, tsr_error *err);

#ifdef __cplusplus
}
#endif
#endif
