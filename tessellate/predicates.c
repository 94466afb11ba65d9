/* predicates.c: orient2d and incircle with a floating-point filter and an
 * exact fallback on floating-point expansions.
 *
 * Ideas from Shewchuk, "Adaptive Precision Floating-Point Arithmetic and
 * Fast Robust Geometric Predicates" (1997) and Dekker (1971); our own
 * code. An expansion is an array of doubles, ordered by increasing
 * magnitude and non-overlapping, whose exact sum is the value; its sign is
 * the sign of its largest (last) non-zero component. Products are exact by
 * fma (x*y = p + e with e = fma(x, y, -p)); sums by Knuth's two-sum. */
#include "tessellate/tessellate.h"

#include <math.h>

static inline void two_sum(double a, double b, double *x, double *y)
{
    double s = a + b, bv = s - a, av = s - bv;
    *x = s;
    *y = (a - av) + (b - bv);
}

static inline void two_prod(double a, double b, double *x, double *y)
{
    double p = a * b;
    *x = p;
    *y = fma(a, b, -p);
}

/* h = e + b (e has n components; h may be e): returns the length of h
 * (<= n + 1). Zero components are dropped (each output index is at most
 * the input index being read, so working in place is safe). */
static int grow(int n, const double *e, double b, double *h)
{
    double q = b;
    int k = 0;
    for (int i = 0; i < n; i++) {
        double s, t;
        two_sum(q, e[i], &s, &t);
        if (t != 0)
            h[k++] = t;
        q = s;
    }
    if (q != 0 || k == 0)
        h[k++] = q;
    return k;
}

/* h = e + f, h distinct from f, capacity n + m (h may be e). */
static int add(int n, const double *e, int m, const double *f, double *h)
{
    if (h != e)
        for (int i = 0; i < n; i++)
            h[i] = e[i];
    int len = n;
    for (int j = 0; j < m; j++)
        len = grow(len, h, f[j], h);
    return len;
}

/* h = e * b; h needs 2n components. */
static int scale(int n, const double *e, double b, double *h)
{
    int k = 0;
    double q, hh;
    two_prod(e[0], b, &q, &hh);
    if (hh != 0)
        h[k++] = hh;
    for (int i = 1; i < n; i++) {
        double p1, p0, s, t;
        two_prod(e[i], b, &p1, &p0);
        two_sum(q, p0, &s, &t);
        if (t != 0)
            h[k++] = t;
        two_sum(p1, s, &q, &t);
        if (t != 0)
            h[k++] = t;
    }
    if (q != 0 || k == 0)
        h[k++] = q;
    return k;
}

#define MAXE 32 /* components of any factor scaled here */

/* h = e * f; h needs 2 n m + 1 components; n <= MAXE. */
static int mul(int n, const double *e, int m, const double *f, double *h)
{
    double t[2 * MAXE];
    int len = 1;
    h[0] = 0;
    for (int j = 0; j < m; j++) {
        int sl = scale(n, e, f[j], t);
        len = add(len, h, sl, t, h);
    }
    return len;
}

static double sign_of(int n, const double *e)
{
    for (int i = n - 1; i >= 0; i--)
        if (e[i] != 0)
            return e[i];
    return 0;
}

/* ---- orient2d --------------------------------------------------------- */

double tsr_orient2d_exact(const double a[2], const double b[2], const double c[2])
{
    /* (ax - cx)(by - cy) - (ay - cy)(bx - cx), each difference exact as a
     * two-component expansion */
    double acx[2], bcy[2], acy[2], bcx[2];
    two_sum(a[0], -c[0], &acx[1], &acx[0]);
    two_sum(b[1], -c[1], &bcy[1], &bcy[0]);
    two_sum(a[1], -c[1], &acy[1], &acy[0]);
    two_sum(b[0], -c[0], &bcx[1], &bcx[0]);
    double l[32], r[16];
    int nl = mul(2, acx, 2, bcy, l);
    int nr = mul(2, acy, 2, bcx, r);
    for (int i = 0; i < nr; i++)
        r[i] = -r[i];
    nl = add(nl, l, nr, r, l);
    return sign_of(nl, l);
}

/* Integral doubles below 2^52 in magnitude: their differences are exact
 * integers, and so is any sum of products of them that stays below 2^53.
 * When the filter cannot decide (a zero or tiny determinant) on integer
 * data, such as grids of samples, that spares the exact expansions. */
static bool integral(double x) { return fabs(x) < 4503599627370496.0 && (double)(int64_t)x == x; }

double tsr_orient2d(const double a[2], const double b[2], const double c[2])
{
    double left = (a[0] - c[0]) * (b[1] - c[1]), right = (a[1] - c[1]) * (b[0] - c[0]);
    double det = left - right;
    /* error bound of this evaluation: (3 + 16 eps) eps (|left| + |right|) */
    const double eps = 1.1102230246251565e-16; /* 2^-53 */
    double bound = (3.0 + 16.0 * eps) * eps * (fabs(left) + fabs(right));
    if (det > bound || -det > bound)
        return det;
    if (fabs(left) + fabs(right) < 9007199254740992.0 && integral(a[0]) && integral(a[1]) && integral(b[0]) &&
        integral(b[1]) && integral(c[0]) && integral(c[1]))
        return det;
    return tsr_orient2d_exact(a, b, c);
}

/* ---- incircle --------------------------------------------------------- */

double tsr_incircle_exact(const double a[2], const double b[2], const double c[2], const double d[2])
{
    double dx[3][2], dy[3][2];
    const double *p[3] = {a, b, c};
    for (int i = 0; i < 3; i++) {
        two_sum(p[i][0], -d[0], &dx[i][1], &dx[i][0]);
        two_sum(p[i][1], -d[1], &dy[i][1], &dy[i][0]);
    }
    /* det = sum over cyclic (i, j, k) of (x_i^2 + y_i^2)(x_j y_k - y_j x_k) */
    double acc[3 * 1025 + 1];
    int n = 1;
    acc[0] = 0;
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        double xx[16], yy[16], lift[32], c1[16], c2[16], cr[32], term[2 * 32 * 32 + 1];
        int nxx = mul(2, dx[i], 2, dx[i], xx);
        int nyy = mul(2, dy[i], 2, dy[i], yy);
        int nl = add(nxx, xx, nyy, yy, lift);
        int n1 = mul(2, dx[j], 2, dy[k], c1);
        int n2 = mul(2, dy[j], 2, dx[k], c2);
        for (int q = 0; q < n2; q++)
            c2[q] = -c2[q];
        int nc = add(n1, c1, n2, c2, cr);
        int nt = mul(nl, lift, nc, cr, term);
        n = add(n, acc, nt, term, acc);
    }
    return sign_of(n, acc);
}

double tsr_incircle(const double a[2], const double b[2], const double c[2], const double d[2])
{
    double adx = a[0] - d[0], ady = a[1] - d[1], bdx = b[0] - d[0], bdy = b[1] - d[1];
    double cdx = c[0] - d[0], cdy = c[1] - d[1];
    double bc = bdx * cdy - bdy * cdx, ca = cdx * ady - cdy * adx, ab = adx * bdy - ady * bdx;
    double la = adx * adx + ady * ady, lb = bdx * bdx + bdy * bdy, lc = cdx * cdx + cdy * cdy;
    double det = la * bc + lb * ca + lc * ab;
    double perm = la * (fabs(bdx * cdy) + fabs(bdy * cdx)) + lb * (fabs(cdx * ady) + fabs(cdy * adx)) +
                  lc * (fabs(adx * bdy) + fabs(ady * bdx));
    /* error bound of this evaluation: (10 + 96 eps) eps * perm */
    const double eps = 1.1102230246251565e-16;
    double bound = (10.0 + 96.0 * eps) * eps * perm;
    if (det > bound || -det > bound)
        return det;
    if (perm < 9007199254740992.0 && integral(a[0]) && integral(a[1]) && integral(b[0]) && integral(b[1]) &&
        integral(c[0]) && integral(c[1]) && integral(d[0]) && integral(d[1]))
        return det; /* every term an integer below 2^53: computed exactly */
    return tsr_incircle_exact(a, b, c, d);
}
