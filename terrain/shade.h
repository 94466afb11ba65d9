/* shade.h: images derived from a heightfield, one pixel per sample: a
 * normal map (for texturing a mesh of the terrain) and a hillshade (for
 * previews and print textures).
 *
 * Self-contained, so terrain.h may include it: it needs only the kernel's
 * status and error types and the opaque heightfield handle.
 *
 * Frame. The heightfield convention of terrain.h puts sample (c, r) at
 * x = c*dx, y = r*dy, z = h*dz, with row 0 the top line of the image. Both
 * images use the map frame of that image:
 *     east  = +x = +column = right in the image,
 *     north = -y = toward row 0 = up in the image,
 *     up    = +z.
 * The normal at a sample comes from central differences of h*dz with the
 * spacings dx and dy, one-sided at the borders and next to no-data (a
 * direction with no valid neighbour on either side counts as flat).
 *
 * Output. The format comes from the extension through OpenImageIO (.png,
 * .tif and .tiff at least; whatever else OpenImageIO writes, such as .jpg
 * or .exr, also works). The image is written under a temporary name in the
 * same folder and renamed when complete, so a failure leaves no file at
 * path (and no temporary). Errors name the path and the problem:
 * TSR_ERR_ARGUMENT for a NULL or malformed argument (spacing not positive,
 * angles out of range), TSR_ERR_UNSUPPORTED for an extension OpenImageIO
 * cannot write, TSR_ERR_IO for an unwritable or missing folder or a failed
 * write, TSR_ERR_NOMEM. err may be NULL. Thread-safe for distinct paths.
 */
#ifndef TSR_SHADE_H
#define TSR_SHADE_H

#include "tessellate/tessellate.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The same typedef as terrain.h's (a repeated identical typedef is valid
 * C11 and C++). */
typedef struct tsr_heightfield tsr_heightfield;

/* Writes an 8-bit RGB normal map, width x height pixels, pixel (c, r) for
 * sample (c, r). Each channel is round(255 * (n * 0.5 + 0.5)) of the unit
 * normal n in the map frame above:
 *     R = n_east  = n_x,   G = n_north = -n_y,   B = n_up = n_z.
 * Green points north, toward the top of the image: the "OpenGL", green-up
 * convention that glTF's normalTexture expects, for a mesh whose uv runs
 * u along columns and v along rows (v = 0 at row 0, as glTF's uv origin is
 * the image's top-left). These are the terrain's normals relative to the
 * flat xy plane (an object-space map of a height field): exact as a
 * tangent-space map on a flat or nearly flat base mesh; on a coarse 3D
 * terrain mesh the renderer would add the slope twice. A flat sample is
 * (128, 128, 255). No-data (NaN) samples are (0, 0, 0), which is no unit
 * normal, so readers can tell them apart. */
tsr_status tsr_heightfield_normal_map(const tsr_heightfield *hf, const char *path, tsr_error *err);

/* The same for the window of w x h samples from column x, row y (pixel
 * (i, j) for sample (x + i, y + j)): the window's part of the whole
 * heightfield's map, pixel for pixel (the normals at its border use the
 * samples beyond it), so the images of adjacent windows fit together.
 * A window not inside the heightfield, or empty, is TSR_ERR_ARGUMENT. */
tsr_status tsr_heightfield_normal_map_window(const tsr_heightfield *hf, uint32_t x, uint32_t y, uint32_t w,
                                             uint32_t h, const char *path, tsr_error *err);

/* The defaults of tsr_heightfield_hillshade (those of GDAL's gdaldem). */
#define TSR_HILLSHADE_AZIMUTH 315.0
#define TSR_HILLSHADE_ALTITUDE 45.0

/* Writes an 8-bit grey hillshade, width x height pixels, pixel (c, r) for
 * sample (c, r): the Lambertian shade 255 * max(0, n . L), rounded, with n
 * the unit normal (see above) and L the unit vector toward the sun,
 *     L = (cos(alt) sin(az), cos(alt) cos(az), sin(alt))  (east, north, up),
 * which is GDAL's gdaldem hillshade formula (with these differences instead
 * of Horn's 3x3 kernel, and 0..255 instead of 1..255). So flat ground is
 * 255 sin(alt), a slope facing the sun 255, one facing away 0.
 * azimuth_deg: degrees clockwise from north, north being the top of the
 * image (row 0) and east its right (+column): 315, the default, lights from
 * the top-left. Any finite value (taken modulo 360). altitude_deg: degrees
 * above the horizon, 0 to 90. NAN for either picks its default
 * (TSR_HILLSHADE_AZIMUTH, TSR_HILLSHADE_ALTITUDE). No-data (NaN) samples are
 * 0, as is full shadow; so where the heightfield has any and the format
 * keeps grey with alpha (.png, .tif, .tiff, .exr), a second channel is
 * written, alpha: 0 at no-data, 255 elsewhere (without no-data, or in
 * other formats, grey alone). The heights are used with their spacing and
 * scale (dz acts as GDAL's z factor). */
tsr_status tsr_heightfield_hillshade(const tsr_heightfield *hf, const char *path, double azimuth_deg,
                                     double altitude_deg, tsr_error *err);

/* The same for a window, as tsr_heightfield_normal_map_window (the alpha
 * channel where the window has no-data). */
tsr_status tsr_heightfield_hillshade_window(const tsr_heightfield *hf, uint32_t x, uint32_t y, uint32_t w,
                                            uint32_t h, const char *path, double azimuth_deg, double altitude_deg,
                                            tsr_error *err);

#ifdef __cplusplus
}
#endif
#endif /* TSR_SHADE_H */
