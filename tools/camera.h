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

/* The terrain's unit of clearance: one (a metre), or a thousandth of the
 * terrain's size (its width, depth or relief) where that is less, so a
 * terrain a few units across, or in kilometres, gets the same views and
 * near plane as one in metres. */
double terrain_unit(const tsr_terrain *t);

/* A random camera: over the terrain, above the ground by a random
 * altitude, looking in a random direction downwards; every third one is a
 * low, grazing view (a few terrain units up, nearly horizontal). */
void random_camera(const tsr_terrain *t, uint64_t *rng, int index, const view_options *v, tsr_camera *c);

/* Frame f of n of a smooth closed flight over the terrain (a Lissajous
 * curve), kept above the ground by picking. */
void flight_camera(const tsr_terrain *t, int f, int n, const view_options *v, tsr_camera *c);

/* If a is --pixel-error, --width, --height, --fov or --near, parses its
 * value (NULL: missing) into v and returns 1: a positive number, --fov
 * below 179; returns 0 when a is none of them; prints cmd's error and
 * returns -1 on a bad value. */
int view_option(const char *cmd, const char *a, const char *value, view_options *v);

/* Parses "EX,EY,EZ,TX,TY,TZ"; false when malformed. */
bool parse_camera(const char *s, const view_options *v, tsr_camera *c);

#endif
