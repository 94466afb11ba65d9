/* Robust predicates against exact big-integer evaluation written here:
 * inputs are dyadic rationals k * 2^-s, so scaling by 2^s makes them
 * integers and the determinants become integer polynomials. */
#include "check.h"
#include "tessellate/tessellate.h"

#include <stdint.h>

/* 512-bit two's complement integers, 16 limbs of 32 bits, little end first */
typedef struct big {
    uint32_t w[16];
} big;

static big big_from(int64_t v)
{
    big r;
    uint64_t u = (uint64_t)v;
    r.w[0] = (uint32_t)u;
    r.w[1] = (uint32_t)(u >> 32);
    for (int i = 2; i < 16; i++)
        r.w[i] = v < 0 ? 0xFFFFFFFFu : 0;
    return r;
}

static big big_add(big a, big b)
{
    big r;
    uint64_t carry = 0;
    for (int i = 0; i < 16; i++) {
        uint64_t s = (uint64_t)a.w[i] + b.w[i] + carry;
        r.w[i] = (uint32_t)s;
        carry = s >> 32;
    }
    return r;
}

static big big_neg(big a)
{
    for (int i = 0; i < 16; i++)
        a.w[i] = ~a.w[i];
    return big_add(a, big_from(1));
}

static int big_sign(big a)
{
    if (a.w[15] >> 31)
        return -1;
    for (int i = 0; i < 16; i++)
        if (a.w[i])
            return 1;
    return 0;
}

static big big_mul(big a, big b)
{
    int neg = 0;
    if (big_sign(a) < 0) {
        a = big_neg(a);
        neg ^= 1;
    }
    if (big_sign(b) < 0) {
        b = big_neg(b);
        neg ^= 1;
    }
    uint32_t r[16] = {0};
    for (int i = 0; i < 16; i++) {
        uint64_t carry = 0;
        for (int j = 0; i + j < 16; j++) {
            uint64_t t = (uint64_t)a.w[i] * b.w[j] + r[i + j] + carry;
            r[i + j] = (uint32_t)t;
            carry = t >> 32;
        }
    }
    big out;
    memcpy(out.w, r, sizeof r);
    return neg ? big_neg(out) : out;
}

static big big_sub(big a, big b) { return big_add(a, big_neg(b)); }

/* x * 2^s as an integer; the test only builds values for which it is one */
static int64_t scaled(double x, int s)
{
    double v = ldexp(x, s);
    CHECK(v == floor(v) && fabs(v) < 9.2e18);
    return (int64_t)v;
}

static int exact_orient(const double a[2], const double b[2], const double c[2], int s)
{
    big ax = big_from(scaled(a[0], s)), ay = big_from(scaled(a[1], s)), bx = big_from(scaled(b[0], s)),
        by = big_from(scaled(b[1], s)), cx = big_from(scaled(c[0], s)), cy = big_from(scaled(c[1], s));
    big d = big_sub(big_mul(big_sub(ax, cx), big_sub(by, cy)), big_mul(big_sub(ay, cy), big_sub(bx, cx)));
    return big_sign(d);
}

static int exact_incircle(const double a[2], const double b[2], const double c[2], const double d[2], int s)
{
    const double *p[3] = {a, b, c};
    big dx[3], dy[3], lift[3];
    big ddx = big_from(scaled(d[0], s)), ddy = big_from(scaled(d[1], s));
    for (int i = 0; i < 3; i++) {
        dx[i] = big_sub(big_from(scaled(p[i][0], s)), ddx);
        dy[i] = big_sub(big_from(scaled(p[i][1], s)), ddy);
        lift[i] = big_add(big_mul(dx[i], dx[i]), big_mul(dy[i], dy[i]));
    }
    big det = big_from(0);
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        big cr = big_sub(big_mul(dx[j], dy[k]), big_mul(dy[j], dx[k]));
        det = big_add(det, big_mul(lift[i], cr));
    }
    return big_sign(det);
}

static int sgn(double v) { return v > 0 ? 1 : v < 0 ? -1 : 0; }

static uint64_t rs = 0x1234567;
static int64_t rnd(int64_t range)
{
    rs = rs * 6364136223846793005ull + 1442695040888963407ull;
    return (int64_t)((rs >> 11) % (uint64_t)(2 * range + 1)) - range;
}

TEST(known_answers)
{
    double o[2] = {0, 0}, x[2] = {1, 0}, y[2] = {0, 1}, xy[2] = {1, 1}, far[2] = {2, 2};
    CHECK(tsr_orient2d(o, x, y) > 0);
    CHECK(tsr_orient2d(o, y, x) < 0);
    CHECK(tsr_orient2d(o, xy, far) == 0);
    /* the unit square's corners are cocircular; its centre is inside */
    double ctr[2] = {0.5, 0.5}, out[2] = {2, 0.5};
    CHECK(tsr_incircle(o, x, xy, y) == 0);
    CHECK(tsr_incircle(o, x, xy, ctr) > 0);
    CHECK(tsr_incircle(o, x, xy, out) < 0);
    /* Pythagorean points on a circle of radius 5 (integers): cocircular */
    double p1[2] = {5, 0}, p2[2] = {3, 4}, p3[2] = {-4, 3}, p4[2] = {0, -5};
    CHECK(tsr_incircle(p1, p2, p3, p4) == 0);
    CHECK(tsr_incircle_exact(p1, p2, p3, p4) == 0);
}

TEST(near_collinear_grid)
{
    /* points 0.5 + i ulp, 0.5 + j ulp against the line through (12, 12)
     * and (24, 24): the textbook double formula is wrong on many, the
     * robust one must match the exact sign on all */
    double b[2] = {12, 12}, c[2] = {24, 24};
    int naive_wrong = 0, wrong = 0, zeros = 0;
    for (int i = 0; i < 256; i++)
        for (int j = 0; j < 256; j++) {
            double a[2] = {0.5 + i * ldexp(1, -53), 0.5 + j * ldexp(1, -53)};
            int ex = exact_orient(a, b, c, 53);
            double naive = (a[0] - c[0]) * (b[1] - c[1]) - (a[1] - c[1]) * (b[0] - c[0]);
            naive_wrong += sgn(naive) != ex;
            wrong += sgn(tsr_orient2d(a, b, c)) != ex;
            zeros += ex == 0;
        }
    fprintf(stderr, "  65536 near-collinear points: naive formula wrong on %d, robust wrong on %d, %d exactly on the line\n",
            naive_wrong, wrong, zeros);
    CHECK(naive_wrong > 1000); /* the test would catch a naive predicate */
    CHECK(wrong == 0);
    CHECK(zeros == 256);
}

TEST(near_cocircular)
{
    /* the radius-5 Pythagorean circle scaled by 2^20, d moved by a few
     * units of 2^-40 in each direction */
    int wrong = 0, naive_wrong = 0;
    double p1[2] = {5 * 1048576.0, 0}, p2[2] = {3 * 1048576.0, 4 * 1048576.0}, p3[2] = {-4 * 1048576.0, 3 * 1048576.0};
    for (int i = -8; i <= 8; i++)
        for (int j = -8; j <= 8; j++) {
            double d[2] = {0 + i * ldexp(1, -40), -5 * 1048576.0 + j * ldexp(1, -40)};
            int ex = exact_incircle(p1, p2, p3, d, 40);
            double adx = p1[0] - d[0], ady = p1[1] - d[1], bdx = p2[0] - d[0], bdy = p2[1] - d[1], cdx = p3[0] - d[0],
                   cdy = p3[1] - d[1];
            double naive = (adx * adx + ady * ady) * (bdx * cdy - bdy * cdx) +
                           (bdx * bdx + bdy * bdy) * (cdx * ady - cdy * adx) +
                           (cdx * cdx + cdy * cdy) * (adx * bdy - ady * bdx);
            naive_wrong += sgn(naive) != ex;
            wrong += sgn(tsr_incircle(p1, p2, p3, d)) != ex;
        }
    fprintf(stderr, "  289 near-cocircular points: naive wrong on %d, robust wrong on %d\n", naive_wrong, wrong);
    CHECK(wrong == 0);
    CHECK(naive_wrong > 0);
}

TEST(random_against_exact)
{
    /* random dyadic points (k * 2^-20, |k| < 2^40), some in general
     * position, some snapped to make degenerate configurations likely */
    int disagreements = 0, degenerate = 0;
    for (int t = 0; t < 20000; t++) {
        double p[4][2];
        int64_t range = t % 3 == 0 ? 8 : t % 3 == 1 ? 1000 : ((int64_t)1 << 40);
        for (int k = 0; k < 4; k++)
            for (int q = 0; q < 2; q++)
                p[k][q] = ldexp((double)rnd(range), -20);
        int eo = exact_orient(p[0], p[1], p[2], 20), ei = exact_incircle(p[0], p[1], p[2], p[3], 20);
        degenerate += eo == 0 || ei == 0;
        disagreements += sgn(tsr_orient2d(p[0], p[1], p[2])) != eo;
        disagreements += sgn(tsr_orient2d_exact(p[0], p[1], p[2])) != eo;
        disagreements += sgn(tsr_incircle(p[0], p[1], p[2], p[3])) != ei;
        disagreements += sgn(tsr_incircle_exact(p[0], p[1], p[2], p[3])) != ei;
    }
    fprintf(stderr, "  20000 random sets: %d degenerate, %d disagreements\n", degenerate, disagreements);
    CHECK(disagreements == 0);
    CHECK(degenerate > 100); /* the exact zero cases are exercised */
}

TEST(wide_exponent_range)
{
    /* coordinates spanning 2^-60 .. 2^60 in one configuration */
    int wrong = 0;
    for (int t = 0; t < 2000; t++) {
        double p[4][2];
        for (int k = 0; k < 4; k++)
            for (int q = 0; q < 2; q++) {
                int e = (int)rnd(30) - 30; /* -60 .. 0 */
                p[k][q] = ldexp((double)rnd(1 << 20), e + (t % 2 ? 40 : 0));
            }
        /* a common scale 2^80 makes every coordinate an integer < 2^100:
         * too big for int64, so compare the filter and the exact path,
         * and check the sign is invariant under swapping (antisymmetry) */
        double o1 = tsr_orient2d(p[0], p[1], p[2]), o2 = tsr_orient2d(p[1], p[0], p[2]);
        double i1 = tsr_incircle(p[0], p[1], p[2], p[3]), i2 = tsr_incircle(p[1], p[0], p[2], p[3]);
        wrong += sgn(o1) != -sgn(o2) || sgn(i1) != -sgn(i2);
        wrong += sgn(o1) != sgn(tsr_orient2d_exact(p[0], p[1], p[2]));
        wrong += sgn(i1) != sgn(tsr_incircle_exact(p[0], p[1], p[2], p[3]));
    }
    CHECK(wrong == 0);
}

TEST_MAIN(T(known_answers), T(near_collinear_grid), T(near_cocircular), T(random_against_exact), T(wide_exponent_range))
