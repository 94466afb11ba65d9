/* predicates.h: (included by tessellate.h) robust geometric predicates in
 * double precision: the sign is always that of the exact determinant of
 * the inputs as given (no rounding of intermediate results can flip it).
 * A floating-point filter answers almost every call; the rest are
 * evaluated exactly with floating-point expansions (sums of non-
 * overlapping doubles, Priest 1991 and Shewchuk 1997). Thread-safe, no
 * allocation. Inputs must be finite and of magnitude below 2^250 (so no
 * product of four coordinates overflows). */
#ifndef TSR_PREDICATES_H
#define TSR_PREDICATES_H

#ifdef __cplusplus
extern "C" {
#endif

/* > 0 when a, b, c turn counter-clockwise, < 0 clockwise, 0 collinear.
 * The value's magnitude is an approximation of twice the signed area. */
double tsr_orient2d(const double a[2], const double b[2], const double c[2]);

/* > 0 when d lies inside the circle through a, b, c (counter-clockwise),
 * < 0 outside, 0 on it. */
double tsr_incircle(const double a[2], const double b[2], const double c[2], const double d[2]);

/* The same, always through the exact path (for tests and benchmarks of
 * the filter). The sign is exact; the magnitude is approximate. */
double tsr_orient2d_exact(const double a[2], const double b[2], const double c[2]);
double tsr_incircle_exact(const double a[2], const double b[2], const double c[2], const double d[2]);

#ifdef __cplusplus
}
#endif
#endif
