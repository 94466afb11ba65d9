/* camera.h: camera placement over a terrain for `check` and `bench`
 * (tools only): random views, a smooth flight, and --camera parsing. */
#ifndef TSR_TOOLS_CAMERA_H
#define TSR_TOOLS_CAMERA_H

#include "cli.h"

typedef struct view_options {
    double fovy_deg, width, height, near_dist, pixel_error;
} view_options;

/* Height of the terrain's surface at world (x, y) by picking straight
 * down; NAN over a hole or outside. */
double ground_height(const tsr_terrain *t, double x, double y);

/* A random camera: over the terrain, above the ground by a random
 * altitude, looking in a random direction downwards; every third one is a
 * low, grazing view (a few metres up, nearly horizontal). */
void random_camera(const tsr_terrain *t, uint64_t *rng, int index, const view_options *v, tsr_camera *c);

/* Frame f of n of a smooth closed flight over the terrain (a Lissajous
 * curve), kept above the ground by picking. */
void flight_camera(const tsr_terrain *t, int f, int n, const view_options *v, tsr_camera *c);

/* Parses "EX,EY,EZ,TX,TY,TZ"; false when malformed. */
bool parse_camera(const char *s, const view_options *v, tsr_camera *c);

#endif
