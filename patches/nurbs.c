/* nurbs.c: tensor-product Bézier, B-spline and NURBS patches and planar
 * trimming curves: evaluation with derivatives, limit normals at
 * degenerate points, bounds, splitting, Bézier extraction, trim-loop
 * sampling.
 *
 * - One evaluator for every kind: a Bézier patch is the B-spline whose
 *   knot vector is its domain's ends, each degree + 1 times, whose basis
 *   is exactly the Bernstein basis over the domain.
 * - Basis functions and their derivatives: Piegl & Tiller, "The NURBS
 *   Book", 2nd ed., A2.1 (FindSpan, here a binary search that also picks
 *   the span ending at the domain's upper end) and A2.3 (DersBasisFuns).
 * - Rational derivatives from the homogeneous ones: Piegl & Tiller A4.4
 *   (RatSurfaceDerivs), up to second order, which the limit normals need.
 * - Limit normals where S_u x S_v vanishes: the Taylor expansion of the
 *   normal field, N(x + h d) = T0 + h T1 + h^2 T2 + ..., with
 *   T0 = S_u x S_v, T1 = S_u x B + A x S_v, T2 = A x B, A = d_u S_uu +
 *   d_v S_uv, B = d_u S_uv + d_v S_vv; the first term that does not vanish
 *   gives the limit direction from d (cf. Farin, "Curves and Surfaces for
 *   CAGD", 5th ed., 19.5 on degenerate patches). Second derivatives of
 *   a B-spline of degree p are those of the span's polynomial, exact for
 *   p >= 2 and zero for p = 1, where the bilinear case needs only S_uv.
 * - Bézier pieces of a span [a, b] are the blossom values
 *   f(a^(p-k), b^k) (Ramshaw, "Blossoms are polar forms", CAGD 6, 1989),
 *   computed by de Boor's algorithm with one argument per level: the
 *   points that inserting a and b p times each by Boehm's algorithm
 *   (Boehm, "Inserting new knots into B-spline curves", CAD 12, 1980)
 *   leaves over the span, obtained locally without growing the net, for
 *   clamped and unclamped knot vectors alike.
 * - Splitting: de Casteljau's algorithm in homogeneous coordinates.
 */
#include "patches/patches.h"
#include "tessellate/predicates.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAXD TSR_PATCH_MAX_DEGREE
#define MAXN (MAXD + 1)

/* ---- One direction of a patch (or a curve) ------------------------------------ */

typedef struct dir {
    int deg;
    uint32_t count;
    const double *knots; /* count + deg + 1 values */
    double lo, hi;       /* the domain along this direction */
    double local[2 * MAXN];
} dir;

static bool finite_range(double a, double b)
{
    return isfinite(a) && isfinite(b) && a < b;
}

/* The direction `axis` of p with O(1) checks; false when they fail. The
 * dir must not be copied (knots may point into it). */
static bool dir_init(const tsr_patch *p, int axis, dir *d)
{
    d->deg = axis ? p->degree_v : p->degree_u;
    d->count = axis ? p->count_v : p->count_u;
    if (d->deg < 1 || d->deg > MAXD)
        return false;
    bool zero = p->u0 == 0 && p->u1 == 0 && p->v0 == 0 && p->v1 == 0;
    double lo = axis ? p->v0 : p->u0, hi = axis ? p->v1 : p->u1;
    if (p->kind == TSR_PATCH_BEZIER) {
        if (d->count != (uint32_t)d->deg + 1)
            return false;
        if (zero)
            lo = 0, hi = 1;
        if (!finite_range(lo, hi))
            return false;
        for (int i = 0; i <= d->deg; i++)
            d->local[i] = lo, d->local[d->deg + 1 + i] = hi;
        d->knots = d->local;
    } else {
        d->knots = axis ? p->knots_v : p->knots_u;
        if (!d->knots || d->count < (uint32_t)d->deg + 1 || d->count > TSR_PATCH_MAX_COUNT)
            return false;
        double a = d->knots[d->deg], b = d->knots[d->count];
        if (!finite_range(a, b))
            return false;
        if (zero)
            lo = a, hi = b;
        if (!finite_range(lo, hi) || lo < a || hi > b)
            return false;
    }
    d->lo = lo, d->hi = hi;
    return true;
}

/* The O(1) checks shared by every entry point. */
static bool patch_init(const tsr_patch *p, dir *du, dir *dv)
{
    if (!p || !p->ctrl || (unsigned)p->kind > TSR_PATCH_NURBS)
        return false;
    if (p->kind == TSR_PATCH_BSPLINE && p->weights)
        return false;
    if (p->kind == TSR_PATCH_NURBS && !p->weights)
        return false;
    if (!dir_init(p, 0, du) || !dir_init(p, 1, dv))
        return false;
    return (uint64_t)du->count * dv->count <= TSR_PATCH_MAX_POINTS;
}

static bool curve_init(const tsr_curve2 *c, dir *d)
{
    if (!c || !c->ctrl || !c->knots || c->degree < 1 || c->degree > MAXD || c->count < (uint32_t)c->degree + 1 ||
        c->count > TSR_PATCH_MAX_COUNT)
        return false;
    d->deg = c->degree;
    d->count = c->count;
    d->knots = c->knots;
    d->lo = c->knots[c->degree], d->hi = c->knots[c->count];
    return finite_range(d->lo, d->hi);
}

static double clampd(double t, double lo, double hi)
{
    return t >= lo ? (t <= hi ? t : hi) : lo;
} /* NaN: lo */

/* The span k (deg <= k < count) holding t, t in [lo, hi]: the largest k
 * with knots[k] <= t, except that t = hi takes the span ending there
 * (the largest k with knots[k] < t), so the derivatives at the domain's
 * upper end are those of the inside. */
static uint32_t find_span(const dir *d, double t)
{
    uint32_t a = (uint32_t)d->deg, b = d->count - 1; /* answer in [a, b] */
    bool upper = t >= d->hi;
    while (a < b) {
        uint32_t m = a + (b - a + 1) / 2;
        double k = d->knots[m];
        if (upper ? k < t : k <= t)
            a = m;
        else
            b = m - 1;
    }
    return a;
}

/* The knots one span's basis functions read (knots[k-deg+1 .. k+deg])
 * non-decreasing and the span itself non-empty. */
static bool span_ok(const dir *d, uint32_t k)
{
    for (uint32_t i = k + 1 - (uint32_t)d->deg; i < k + (uint32_t)d->deg; i++)
        if (!(d->knots[i] <= d->knots[i + 1]))
            return false;
    return d->knots[k] < d->knots[k + 1];
}

/* Piegl & Tiller A2.3: the deg + 1 basis functions N_{k-deg..k} at t and
 * their derivatives up to order n (n <= 2; orders above deg are zero). */
static void ders_basis(const dir *d, uint32_t k, double t, int n, double ders[3][MAXN])
{
    const double *U = d->knots;
    int p = d->deg;
    double ndu[MAXN][MAXN], left[MAXN], right[MAXN], a[2][MAXN];
    ndu[0][0] = 1;
    for (int j = 1; j <= p; j++) {
        left[j] = t - U[k + 1 - (uint32_t)j];
        right[j] = U[k + (uint32_t)j] - t;
        double saved = 0;
        for (int r = 0; r < j; r++) {
            ndu[j][r] = right[r + 1] + left[j - r];
            double temp = ndu[r][j - 1] / ndu[j][r];
            ndu[r][j] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        ndu[j][j] = saved;
    }
    for (int j = 0; j <= p; j++)
        ders[0][j] = ndu[j][p];
    int nn = n < p ? n : p;
    for (int q = nn + 1; q <= n; q++)
        for (int j = 0; j <= p; j++)
            ders[q][j] = 0;
    for (int r = 0; r <= p; r++) {
        int s1 = 0, s2 = 1;
        a[0][0] = 1;
        for (int q = 1; q <= nn; q++) {
            double dd = 0;
            int rk = r - q, pk = p - q;
            if (r >= q) {
                a[s2][0] = a[s1][0] / ndu[pk + 1][rk];
                dd = a[s2][0] * ndu[rk][pk];
            }
            int j1 = rk >= -1 ? 1 : -rk;
            int j2 = r - 1 <= pk ? q - 1 : p - r;
            for (int j = j1; j <= j2; j++) {
                a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][rk + j];
                dd += a[s2][j] * ndu[rk + j][pk];
            }
            if (r <= pk) {
                a[s2][q] = -a[s1][q - 1] / ndu[pk + 1][r];
                dd += a[s2][q] * ndu[r][pk];
            }
            ders[q][r] = dd;
            int s = s1;
            s1 = s2, s2 = s;
        }
    }
    double f = p;
    for (int q = 1; q <= nn; q++) {
        for (int j = 0; j <= p; j++)
            ders[q][j] *= f;
        f *= p - q;
    }
}

/* ---- Patch evaluation ------------------------------------------------------------- */

static void cross3(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static double norm3(const double a[3])
{
    return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}

/* What one evaluation yields: S[k][l] = d^(k+l) S / du^k dv^l for
 * k + l <= 2 (S[0][0] the position), the span widths, and the size of the
 * span's control net (its box's diagonal). */
typedef struct jet {
    double S[3][3][3];
    double wu, wv, size;
} jet;

/* Evaluates the jet at (u, v), already clamped into the domain; false
 * when a knot or weight the span reads breaks the rules. */
static bool eval_jet(const tsr_patch *p, const dir *du, const dir *dv, double u, double v, int order, jet *J)
{
    uint32_t ku = find_span(du, u), kv = find_span(dv, v);
    if (!span_ok(du, ku) || !span_ok(dv, kv))
        return false;
    double Nu[3][MAXN], Nv[3][MAXN];
    ders_basis(du, ku, u, order, Nu);
    ders_basis(dv, kv, v, order, Nv);
    int pu = du->deg, pv = dv->deg;
    /* homogeneous derivatives A[k][l] = (w x, w y, w z, w) */
    double A[3][3][4];
    memset(A, 0, sizeof A);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    /* about the span's first control point: far from the origin (a part at
     * 1e6) the derivatives are differences of nearby points, and would
     * lose their digits to the coordinates' (a pole's normal flipped) */
    const double *c0 = p->ctrl + 3 * ((size_t)(kv - (uint32_t)pv) * du->count + ku - (uint32_t)pu);
    double ref[3] = {c0[0], c0[1], c0[2]};
    for (int j = 0; j <= pv; j++) {
        size_t row = (size_t)(kv - (uint32_t)pv + (uint32_t)j) * du->count;
        /* this row's u-contractions: R[k] = sum_i Nu[k][i] Pw_i */
        double R[3][4];
        memset(R, 0, sizeof R);
        for (int i = 0; i <= pu; i++) {
            size_t idx = row + ku - (uint32_t)pu + (uint32_t)i;
            const double *P = p->ctrl + 3 * idx;
            double w = p->weights ? p->weights[idx] : 1.0;
            if (!(w > 0) || !(w < INFINITY))
                return false;
            for (int c = 0; c < 3; c++) {
                lo[c] = P[c] < lo[c] ? P[c] : lo[c];
                hi[c] = P[c] > hi[c] ? P[c] : hi[c];
            }
            double pw[4] = {w * (P[0] - ref[0]), w * (P[1] - ref[1]), w * (P[2] - ref[2]), w};
            for (int k = 0; k <= order; k++)
                for (int c = 0; c < 4; c++)
                    R[k][c] += Nu[k][i] * pw[c];
        }
        for (int k = 0; k <= order; k++)
            for (int l = 0; k + l <= order; l++)
                for (int c = 0; c < 4; c++)
                    A[k][l][c] += Nv[l][j] * R[k][c];
    }
    /* Piegl & Tiller A4.4, with binomials of at most 2 */
    static const double binom[3][3] = {{1, 0, 0}, {1, 1, 0}, {1, 2, 1}};
    for (int k = 0; k <= order; k++)
        for (int l = 0; k + l <= order; l++) {
            double s[3] = {A[k][l][0], A[k][l][1], A[k][l][2]};
            for (int j = 1; j <= l; j++)
                for (int c = 0; c < 3; c++)
                    s[c] -= binom[l][j] * A[0][j][3] * J->S[k][l - j][c];
            for (int i = 1; i <= k; i++) {
                for (int c = 0; c < 3; c++)
                    s[c] -= binom[k][i] * A[i][0][3] * J->S[k - i][l][c];
                for (int j = 1; j <= l; j++)
                    for (int c = 0; c < 3; c++)
                        s[c] -= binom[k][i] * binom[l][j] * A[i][j][3] * J->S[k - i][l - j][c];
            }
            for (int c = 0; c < 3; c++)
                J->S[k][l][c] = s[c] / A[0][0][3];
        }
    for (int c = 0; c < 3; c++)
        J->S[0][0][c] += ref[c];
    J->wu = du->knots[ku + 1] - du->knots[ku];
    J->wv = dv->knots[kv + 1] - dv->knots[kv];
    double dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    J->size = sqrt(dx * dx + dy * dy + dz * dz);
    return true;
}

#define VANISH 1e-10

/* du x dv at the jet scaled to the span (units of length squared), and
 * whether it is non-vanishing against the net's size. */
static bool plain_normal(const jet *J, double n[3])
{
    double su[3], sv[3];
    for (int c = 0; c < 3; c++)
        su[c] = J->S[1][0][c] * J->wu, sv[c] = J->S[0][1][c] * J->wv;
    cross3(su, sv, n);
    double l = norm3(n);
    if (!(l > VANISH * J->size * J->size) || !isfinite(l))
        return false;
    for (int c = 0; c < 3; c++)
        n[c] /= l;
    return true;
}

/* The limit normal from (u, v) along the parameter direction (eu, ev)
 * (in units of the span widths): the first non-vanishing Taylor term. */
static bool taylor_normal(const jet *J, double eu, double ev, double n[3])
{
    double su[3], sv[3], A[3], B[3], T[3], t2[3];
    for (int c = 0; c < 3; c++) {
        su[c] = J->S[1][0][c] * J->wu, sv[c] = J->S[0][1][c] * J->wv;
        double suu = J->S[2][0][c] * J->wu * J->wu, suv = J->S[1][1][c] * J->wu * J->wv;
        double svv = J->S[0][2][c] * J->wv * J->wv;
        A[c] = eu * suu + ev * suv;
        B[c] = eu * suv + ev * svv;
    }
    double eps = VANISH * J->size * J->size;
    cross3(su, B, T);
    cross3(A, sv, t2);
    for (int c = 0; c < 3; c++)
        T[c] += t2[c];
    double l = norm3(T);
    if (!(l > eps) || !isfinite(l)) {
        cross3(A, B, T);
        l = norm3(T);
        if (!(l > eps) || !isfinite(l))
            return false;
    }
    for (int c = 0; c < 3; c++)
        n[c] = T[c] / l;
    return true;
}

static bool limit_normal(const tsr_patch *p, const dir *du, const dir *dv, double u, double v, const jet *J,
                         double n[3])
{
    double su = du->hi - du->lo, sv = dv->hi - dv->lo;
    double cu = 0.5 * (du->lo + du->hi), cv = 0.5 * (dv->lo + dv->hi);
    /* towards the centre, in the span's normalised units */
    double eu = (cu - u) / su, ev = (cv - v) / sv;
    double l = hypot(eu, ev);
    if (l > 0) {
        eu = eu / l * su / J->wu, ev = ev / l * sv / J->wv;
        double m = hypot(eu, ev);
        if (taylor_normal(J, eu / m, ev / m, n))
            return true;
    }
    /* numerically: the normal at nearby points, nearest first, towards the
     * centre and then each corner */
    static const double steps[3] = {1e-6, 1e-4, 1e-2};
    double targets[5][2] = {{cu, cv}, {du->lo, dv->lo}, {du->hi, dv->lo}, {du->lo, dv->hi}, {du->hi, dv->hi}};
    for (int s = 0; s < 3; s++)
        for (int t = 0; t < 5; t++) {
            double x = u + steps[s] * (targets[t][0] - u), y = v + steps[s] * (targets[t][1] - v);
            if (x == u && y == v)
                continue;
            jet K;
            if (eval_jet(p, du, dv, clampd(x, du->lo, du->hi), clampd(y, dv->lo, dv->hi), 1, &K) && plain_normal(&K, n))
                return true;
        }
    return false;
}

tsr_status tsr_patch_eval(const tsr_patch *p, double u, double v, double pos[3], double du_out[3], double dv_out[3],
                          double normal[3])
{
    dir du, dv;
    if (!patch_init(p, &du, &dv))
        return TSR_ERR_ARGUMENT;
    u = clampd(u, du.lo, du.hi);
    v = clampd(v, dv.lo, dv.hi);
    jet J;
    if (!eval_jet(p, &du, &dv, u, v, normal ? 2 : 1, &J))
        return TSR_ERR_ARGUMENT;
    if (normal) {
        double n[3];
        if (!plain_normal(&J, n) && !limit_normal(p, &du, &dv, u, v, &J, n))
            n[0] = 0, n[1] = 0, n[2] = 1; /* no tangent plane near (u, v) */
        memcpy(normal, n, sizeof n);
    }
    if (pos)
        memcpy(pos, J.S[0][0], 3 * sizeof(double));
    if (du_out)
        memcpy(du_out, J.S[1][0], 3 * sizeof(double));
    if (dv_out)
        memcpy(dv_out, J.S[0][1], 3 * sizeof(double));
    return TSR_OK;
}

tsr_status tsr_patch_domain(const tsr_patch *p, double dom[4])
{
    dir du, dv;
    if (!patch_init(p, &du, &dv)) {
        dom[0] = 0, dom[1] = 1, dom[2] = 0, dom[3] = 1;
        return TSR_ERR_ARGUMENT;
    }
    dom[0] = du.lo, dom[1] = du.hi, dom[2] = dv.lo, dom[3] = dv.hi;
    return TSR_OK;
}

/* ---- Checks ---------------------------------------------------------------------- */

static const char *const kind_names[3] = {"Bézier", "B-spline", "NURBS"};

static tsr_status check_knots(const char *who, const char *name, const double *k, uint32_t count, int deg,
                              tsr_error *err)
{
    uint32_t m = count + (uint32_t)deg + 1, run = 1;
    for (uint32_t i = 0; i < m; i++) {
        if (!(fabs(k[i]) <= TSR_PATCH_MAX_ABS))
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: %s[%u] = %g is not within +-%g", who, name, i, k[i],
                                 TSR_PATCH_MAX_ABS);
        if (i > 0 && k[i] < k[i - 1])
            return tsr_error_set(err, TSR_ERR_ARGUMENT,
                                 "%s: %s[%u] = %g is below %s[%u] = %g (knots must not decrease)", who, name, i, k[i],
                                 name, i - 1, k[i - 1]);
        if (i > 0 && k[i] > k[i - 1] && k[i] - k[i - 1] < TSR_PATCH_MIN_SPAN)
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: the span %s[%u..%u] = [%g, %g] is narrower than %g", who,
                                 name, i - 1, i, k[i - 1], k[i], TSR_PATCH_MIN_SPAN);
        run = i > 0 && k[i] == k[i - 1] ? run + 1 : 1;
        if (run > (uint32_t)deg + 1)
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: %s[%u] = %g repeats more than degree + 1 = %d times", who,
                                 name, i, k[i], deg + 1);
    }
    if (!(k[deg] < k[count]))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: empty parameter range %s[%d] = %s[%u] = %g", who, name, deg,
                             name, count, k[deg]);
    return TSR_OK;
}

static tsr_status check_weights(const char *who, const double *w, size_t n, tsr_error *err)
{
    for (size_t i = 0; i < n; i++)
        if (!(w[i] >= TSR_PATCH_MIN_WEIGHT && w[i] <= TSR_PATCH_MAX_WEIGHT))
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: weight %zu is %g, outside [%g, %g]", who, i, w[i],
                                 TSR_PATCH_MIN_WEIGHT, TSR_PATCH_MAX_WEIGHT);
    return TSR_OK;
}

tsr_status tsr_patch_check(const tsr_patch *p, tsr_error *err)
{
    const char *who = "patch";
    if (!p)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: NULL", who);
    if ((unsigned)p->kind > TSR_PATCH_NURBS)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: unknown kind %d", who, (int)p->kind);
    const char *kind = kind_names[p->kind];
    int degs[2] = {p->degree_u, p->degree_v};
    uint32_t counts[2] = {p->count_u, p->count_v};
    for (int a = 0; a < 2; a++) {
        if (degs[a] < 1 || degs[a] > MAXD)
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: degree_%c %d is outside 1..%d", who, "uv"[a], degs[a],
                                 MAXD);
        if (p->kind == TSR_PATCH_BEZIER && counts[a] != (uint32_t)degs[a] + 1)
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: a %s patch of degree_%c %d needs count_%c %d, not %u", who,
                                 kind, "uv"[a], degs[a], "uv"[a], degs[a] + 1, counts[a]);
        if (p->kind != TSR_PATCH_BEZIER && (counts[a] < (uint32_t)degs[a] + 1 || counts[a] > TSR_PATCH_MAX_COUNT))
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: count_%c %u is outside %d..%u for degree_%c %d", who,
                                 "uv"[a], counts[a], degs[a] + 1, TSR_PATCH_MAX_COUNT, "uv"[a], degs[a]);
    }
    uint64_t n = (uint64_t)p->count_u * p->count_v;
    if (n > TSR_PATCH_MAX_POINTS)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: %llu control points, beyond the %u accepted", who,
                             (unsigned long long)n, TSR_PATCH_MAX_POINTS);
    if (!p->ctrl)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: no control points (ctrl NULL)", who);
    for (size_t i = 0; i < 3 * n; i++)
        if (!(fabs(p->ctrl[i]) <= TSR_PATCH_MAX_ABS))
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: control point %zu has a coordinate %g, not within +-%g",
                                 who, i / 3, p->ctrl[i], TSR_PATCH_MAX_ABS);
    if (p->kind == TSR_PATCH_BSPLINE && p->weights)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: a polynomial B-spline with weights (use TSR_PATCH_NURBS)",
                             who);
    if (p->kind == TSR_PATCH_NURBS && !p->weights)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: a NURBS patch without weights", who);
    if (p->weights) {
        tsr_status s = check_weights(who, p->weights, (size_t)n, err);
        if (s != TSR_OK)
            return s;
    }
    if (p->kind != TSR_PATCH_BEZIER) {
        if (!p->knots_u || !p->knots_v)
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: a %s patch without knots_%c", who, kind,
                                 p->knots_u ? 'v' : 'u');
        tsr_status s = check_knots(who, "knots_u", p->knots_u, p->count_u, p->degree_u, err);
        if (s == TSR_OK)
            s = check_knots(who, "knots_v", p->knots_v, p->count_v, p->degree_v, err);
        if (s != TSR_OK)
            return s;
    } else if (p->knots_u || p->knots_v) {
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: a Bézier patch takes no knots", who);
    }
    dir du, dv;
    if (!patch_init(p, &du, &dv))
        return tsr_error_set(err, TSR_ERR_ARGUMENT,
                             "%s: domain [%g, %g] x [%g, %g] is empty, not finite or outside the parameter range", who,
                             p->u0, p->u1, p->v0, p->v1);
    if (!(fabs(du.lo) <= TSR_PATCH_MAX_ABS && fabs(du.hi) <= TSR_PATCH_MAX_ABS && fabs(dv.lo) <= TSR_PATCH_MAX_ABS &&
          fabs(dv.hi) <= TSR_PATCH_MAX_ABS) ||
        du.hi - du.lo < TSR_PATCH_MIN_SPAN || dv.hi - dv.lo < TSR_PATCH_MIN_SPAN)
        return tsr_error_set(err, TSR_ERR_ARGUMENT,
                             "%s: domain [%g, %g] x [%g, %g] is not within +-%g or narrower than %g", who, du.lo, du.hi,
                             dv.lo, dv.hi, TSR_PATCH_MAX_ABS, TSR_PATCH_MIN_SPAN);
    return TSR_OK;
}

tsr_status tsr_curve2_check(const tsr_curve2 *c, tsr_error *err)
{
    const char *who = "curve";
    if (!c)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: NULL", who);
    if (c->degree < 1 || c->degree > MAXD)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: degree %d is outside 1..%d", who, c->degree, MAXD);
    if (c->count < (uint32_t)c->degree + 1 || c->count > TSR_PATCH_MAX_COUNT)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: count %u is outside %d..%u for degree %d", who, c->count,
                             c->degree + 1, TSR_PATCH_MAX_COUNT, c->degree);
    if (!c->ctrl || !c->knots)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: no %s", who, c->ctrl ? "knots" : "control points");
    for (size_t i = 0; i < 2 * (size_t)c->count; i++)
        if (!(fabs(c->ctrl[i]) <= TSR_PATCH_MAX_ABS))
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: control point %zu has a coordinate %g, not within +-%g",
                                 who, i / 2, c->ctrl[i], TSR_PATCH_MAX_ABS);
    if (c->weights) {
        tsr_status s = check_weights(who, c->weights, c->count, err);
        if (s != TSR_OK)
            return s;
    }
    return check_knots(who, "knots", c->knots, c->count, c->degree, err);
}

/* ---- Bounds ------------------------------------------------------------------- */

/* The control point indices along d whose basis functions reach into the
 * domain: [first, last]. */
static void support(const dir *d, uint32_t *first, uint32_t *last)
{
    uint32_t a = find_span(d, d->lo);
    uint32_t b = find_span(d, d->hi); /* the span ending at hi */
    *first = a - (uint32_t)d->deg;
    *last = b;
}

tsr_status tsr_patch_bounds(const tsr_patch *p, double lo[3], double hi[3])
{
    dir du, dv;
    if (!patch_init(p, &du, &dv))
        return TSR_ERR_ARGUMENT;
    uint32_t i0, i1, j0, j1;
    support(&du, &i0, &i1);
    support(&dv, &j0, &j1);
    double l[3] = {INFINITY, INFINITY, INFINITY}, h[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t j = j0; j <= j1; j++)
        for (uint32_t i = i0; i <= i1; i++) {
            const double *P = p->ctrl + 3 * ((size_t)j * du.count + i);
            for (int c = 0; c < 3; c++) {
                l[c] = P[c] < l[c] ? P[c] : l[c];
                h[c] = P[c] > h[c] ? P[c] : h[c];
            }
        }
    memcpy(lo, l, sizeof l);
    memcpy(hi, h, sizeof h);
    return TSR_OK;
}

/* ---- Splitting -------------------------------------------------------------------- */

tsr_status tsr_patch_split(const tsr_patch *p, int axis, double t, tsr_patch *lo, double *lo_ctrl, double *lo_weights,
                           tsr_patch *hi, double *hi_ctrl, double *hi_weights)
{
    dir du, dv;
    if (!patch_init(p, &du, &dv) || p->kind != TSR_PATCH_BEZIER || (axis != 0 && axis != 1) || !lo || !hi || !lo_ctrl ||
        !hi_ctrl || (p->weights && (!lo_weights || !hi_weights)))
        return TSR_ERR_ARGUMENT;
    const dir *d = axis ? &dv : &du;
    if (!(t > d->lo && t < d->hi))
        return TSR_ERR_ARGUMENT;
    double s = (t - d->lo) / (d->hi - d->lo);
    int nu = du.deg + 1, nv = dv.deg + 1, n = axis ? nv : nu, lines = axis ? nu : nv;
    double L[TSR_BEZIER_MAX_POINTS][4], H[TSR_BEZIER_MAX_POINTS][4];
    for (int line = 0; line < lines; line++) {
        double w[MAXN][4];
        for (int k = 0; k < n; k++) {
            int idx = axis ? k * nu + line : line * nu + k;
            double wt = p->weights ? p->weights[idx] : 1.0;
            if (!(wt > 0) || !(wt < INFINITY))
                return TSR_ERR_ARGUMENT;
            for (int c = 0; c < 3; c++)
                w[k][c] = wt * p->ctrl[3 * idx + c];
            w[k][3] = wt;
        }
        for (int r = 0; r < n; r++) {
            /* after r steps w[0] is the r-th lower point and w[n-1-r] the
             * r-th upper one, counted from the far end */
            int li = axis ? r * nu + line : line * nu + r;
            int hk = n - 1 - r, hidx = axis ? hk * nu + line : line * nu + hk;
            memcpy(L[li], w[0], sizeof w[0]);
            memcpy(H[hidx], w[n - 1 - r], sizeof w[0]);
            for (int k = 0; k < n - 1 - r; k++)
                for (int c = 0; c < 4; c++)
                    w[k][c] = (1 - s) * w[k][c] + s * w[k + 1][c];
        }
    }
    tsr_patch base = *p;
    for (int i = 0; i < nu * nv; i++) {
        for (int c = 0; c < 3; c++) {
            lo_ctrl[3 * i + c] = L[i][c] / L[i][3];
            hi_ctrl[3 * i + c] = H[i][c] / H[i][3];
        }
        if (base.weights)
            lo_weights[i] = L[i][3], hi_weights[i] = H[i][3];
    }
    base.u0 = du.lo, base.u1 = du.hi, base.v0 = dv.lo, base.v1 = dv.hi;
    *lo = base, *hi = base;
    lo->ctrl = lo_ctrl, hi->ctrl = hi_ctrl;
    lo->weights = base.weights ? lo_weights : NULL;
    hi->weights = base.weights ? hi_weights : NULL;
    if (axis)
        lo->v1 = t, hi->v0 = t;
    else
        lo->u1 = t, hi->u0 = t;
    return TSR_OK;
}

/* ---- Spans and Bézier pieces --------------------------------------------------------- */

/* The breakpoint after b along d (the next distinct knot above b, or hi);
 * *cursor walks the knots forwards (start it at find_span(d, lo) + 1). */
static double next_break(const dir *d, double b, uint32_t *cursor)
{
    while (*cursor < d->count && !(d->knots[*cursor] > b))
        (*cursor)++;
    double k = *cursor < d->count ? d->knots[*cursor] : d->hi;
    return k < d->hi ? k : d->hi;
}

static uint32_t count_spans(const dir *d, double *breaks, uint32_t cap)
{
    uint32_t n = 0, cursor = find_span(d, d->lo) + 1;
    double b = d->lo;
    if (cap > 0)
        breaks[0] = b;
    while (b < d->hi) {
        b = next_break(d, b, &cursor);
        n++;
        if (n < cap)
            breaks[n] = b;
    }
    return n;
}

uint32_t tsr_patch_spans(const tsr_patch *p, int axis, double *breaks, uint32_t cap)
{
    dir du, dv;
    if (!patch_init(p, &du, &dv) || (axis != 0 && axis != 1))
        return 0;
    return count_spans(axis ? &dv : &du, breaks, breaks ? cap : 0);
}

/* de Boor's algorithm on the deg + 1 points pts (dim doubles each) of span
 * k with argument x[r-1] at level r: the blossom f(x[0], ..., x[deg-1]). */
static void blossom(const dir *d, uint32_t k, const double *pts, int dim, const double *x, double *out)
{
    int p = d->deg;
    double w[MAXN][4];
    for (int i = 0; i <= p; i++)
        for (int c = 0; c < dim; c++)
            w[i][c] = pts[i * dim + c];
    for (int r = 1; r <= p; r++)
        for (int i = p; i >= r; i--) {
            uint32_t g = k - (uint32_t)p + (uint32_t)i;
            double a = (x[r - 1] - d->knots[g]) / (d->knots[g + (uint32_t)(p + 1 - r)] - d->knots[g]);
            for (int c = 0; c < dim; c++)
                w[i][c] = (1 - a) * w[i - 1][c] + a * w[i][c];
        }
    for (int c = 0; c < dim; c++)
        out[c] = w[p][c];
}

/* The Bézier points over [a, b] (inside span k) of deg + 1 homogeneous
 * points, in place. */
static void to_bezier_1d(const dir *d, uint32_t k, double a, double b, double *pts, int dim)
{
    double out[MAXN][4], x[MAXD];
    for (int m = 0; m <= d->deg; m++) {
        for (int r = 0; r < d->deg; r++)
            x[r] = r < d->deg - m ? a : b;
        blossom(d, k, pts, dim, x, out[m]);
    }
    for (int m = 0; m <= d->deg; m++)
        for (int c = 0; c < dim; c++)
            pts[m * dim + c] = out[m][c];
}

/* The span holding [a, b] (a < b, no knot strictly inside, within the
 * domain), or false. */
static bool piece_span(const dir *d, double a, double b, uint32_t *k)
{
    if (!(a < b) || a < d->lo || b > d->hi)
        return false;
    *k = find_span(d, a);
    return span_ok(d, *k) && d->knots[*k] <= a && d->knots[*k + 1] >= b;
}

static bool bezier_piece(const tsr_patch *p, const dir *du, const dir *dv, double ua, double ub, double va, double vb,
                         double *ctrl, double *weights, tsr_patch *piece)
{
    uint32_t ku, kv;
    if (!piece_span(du, ua, ub, &ku) || !piece_span(dv, va, vb, &kv))
        return false;
    int nu = du->deg + 1, nv = dv->deg + 1;
    double H[TSR_BEZIER_MAX_POINTS * 4], line[MAXN * 4];
    for (int j = 0; j < nv; j++) {
        size_t row = (size_t)(kv - (uint32_t)dv->deg + (uint32_t)j) * du->count;
        for (int i = 0; i < nu; i++) {
            size_t idx = row + ku - (uint32_t)du->deg + (uint32_t)i;
            double w = p->weights ? p->weights[idx] : 1.0;
            if (!(w > 0) || !(w < INFINITY))
                return false;
            for (int c = 0; c < 3; c++)
                H[4 * (j * nu + i) + c] = w * p->ctrl[3 * idx + c];
            H[4 * (j * nu + i) + 3] = w;
        }
        to_bezier_1d(du, ku, ua, ub, H + 4 * j * nu, 4);
    }
    for (int i = 0; i < nu; i++) {
        for (int j = 0; j < nv; j++)
            memcpy(line + 4 * j, H + 4 * (j * nu + i), 4 * sizeof(double));
        to_bezier_1d(dv, kv, va, vb, line, 4);
        for (int j = 0; j < nv; j++)
            memcpy(H + 4 * (j * nu + i), line + 4 * j, 4 * sizeof(double));
    }
    for (int i = 0; i < nu * nv; i++) {
        for (int c = 0; c < 3; c++)
            ctrl[3 * i + c] = H[4 * i + c] / H[4 * i + 3];
        if (p->weights)
            weights[i] = H[4 * i + 3];
    }
    tsr_patch q = {TSR_PATCH_BEZIER,
                   du->deg,
                   dv->deg,
                   (uint32_t)nu,
                   (uint32_t)nv,
                   ctrl,
                   p->weights ? weights : NULL,
                   NULL,
                   NULL,
                   ua,
                   ub,
                   va,
                   vb};
    *piece = q;
    return true;
}

tsr_status tsr_patch_bezier_piece(const tsr_patch *p, double ua, double ub, double va, double vb, double *ctrl,
                                  double *weights, tsr_patch *piece)
{
    dir du, dv;
    if (!patch_init(p, &du, &dv) || !ctrl || !piece || (p->weights && !weights))
        return TSR_ERR_ARGUMENT;
    return bezier_piece(p, &du, &dv, ua, ub, va, vb, ctrl, weights, piece) ? TSR_OK : TSR_ERR_ARGUMENT;
}

tsr_status tsr_patch_to_bezier(const tsr_patch *p, tsr_patch *pieces, uint32_t cap, double *ctrl, double *weights,
                               uint32_t *count)
{
    dir du, dv;
    if (!count || !patch_init(p, &du, &dv))
        return TSR_ERR_ARGUMENT;
    uint32_t su = count_spans(&du, NULL, 0), sv = count_spans(&dv, NULL, 0);
    if ((uint64_t)su * sv > UINT32_MAX)
        return TSR_ERR_ARGUMENT;
    *count = su * sv;
    if (!pieces)
        return TSR_OK;
    if (cap < *count || !ctrl || (p->weights && !weights))
        return TSR_ERR_ARGUMENT;
    size_t N = (size_t)(du.deg + 1) * (size_t)(dv.deg + 1);
    uint32_t cv = find_span(&dv, dv.lo) + 1;
    double va = dv.lo;
    for (uint32_t b = 0; b < sv; b++) {
        double vb = next_break(&dv, va, &cv);
        uint32_t cu = find_span(&du, du.lo) + 1;
        double ua = du.lo;
        for (uint32_t a = 0; a < su; a++) {
            double ub = next_break(&du, ua, &cu);
            size_t at = (size_t)b * su + a;
            if (!bezier_piece(p, &du, &dv, ua, ub, va, vb, ctrl + 3 * N * at, weights ? weights + N * at : NULL,
                              &pieces[at]))
                return TSR_ERR_ARGUMENT;
            ua = ub;
        }
        va = vb;
    }
    return TSR_OK;
}

/* ---- Curves ---------------------------------------------------------------------- */

tsr_status tsr_curve2_eval(const tsr_curve2 *c, double t, double uv[2], double d[2])
{
    dir dc;
    if (!curve_init(c, &dc))
        return TSR_ERR_ARGUMENT;
    t = clampd(t, dc.lo, dc.hi);
    uint32_t k = find_span(&dc, t);
    if (!span_ok(&dc, k))
        return TSR_ERR_ARGUMENT;
    double N[3][MAXN], A[2][3] = {{0, 0, 0}, {0, 0, 0}};
    ders_basis(&dc, k, t, 1, N);
    for (int i = 0; i <= dc.deg; i++) {
        uint32_t idx = k - (uint32_t)dc.deg + (uint32_t)i;
        double w = c->weights ? c->weights[idx] : 1.0;
        if (!(w > 0) || !(w < INFINITY))
            return TSR_ERR_ARGUMENT;
        for (int q = 0; q < 2; q++) {
            A[q][0] += N[q][i] * w * c->ctrl[2 * idx];
            A[q][1] += N[q][i] * w * c->ctrl[2 * idx + 1];
            A[q][2] += N[q][i] * w;
        }
    }
    double x = A[0][0] / A[0][2], y = A[0][1] / A[0][2];
    uv[0] = x, uv[1] = y;
    if (d) {
        d[0] = (A[1][0] - A[1][2] * x) / A[0][2];
        d[1] = (A[1][1] - A[1][2] * y) / A[0][2];
    }
    return TSR_OK;
}

/* ---- Trim loops ------------------------------------------------------------------- */

#define MAX_DEPTH 24

typedef struct sampler {
    double *uv;
    uint32_t cap;
    uint64_t n;
    double tol;
    bool any;
    double first[2], last[2];
} sampler;

/* Points go out one step late, so the loop's closing point can be
 * dropped when it comes back to the first. */
static void emit(sampler *s, const double pt[2])
{
    if (!s->any) {
        s->any = true;
        s->first[0] = pt[0], s->first[1] = pt[1];
    } else {
        if (s->n < s->cap)
            s->uv[2 * s->n] = s->last[0], s->uv[2 * s->n + 1] = s->last[1];
        s->n++;
    }
    s->last[0] = pt[0], s->last[1] = pt[1];
}

static double seg_dist(const double p[2], const double a[2], const double b[2])
{
    double ex = b[0] - a[0], ey = b[1] - a[1], l2 = ex * ex + ey * ey;
    double t = l2 > 0 ? ((p[0] - a[0]) * ex + (p[1] - a[1]) * ey) / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return hypot(p[0] - a[0] - t * ex, p[1] - a[1] - t * ey);
}

/* Emits the end of a rational Bézier (homogeneous u w, v w, w) once flat,
 * subdividing at the middle until then. */
static void flatten(sampler *s, const double *h, int p, int depth)
{
    double e[MAXN][2] = {{0, 0}};
    for (int i = 0; i <= p; i++)
        e[i][0] = h[3 * i] / h[3 * i + 2], e[i][1] = h[3 * i + 1] / h[3 * i + 2];
    bool flat = depth >= MAX_DEPTH;
    if (!flat) {
        flat = true;
        for (int i = 1; i < p && flat; i++)
            flat = seg_dist(e[i], e[0], e[p]) <= s->tol;
    }
    if (flat) {
        emit(s, e[p]);
        return;
    }
    double left[MAXN * 3], right[MAXN * 3], w[MAXN][3];
    memcpy(w, h, sizeof(double) * 3 * (size_t)(p + 1));
    for (int r = 0; r <= p; r++) {
        memcpy(left + 3 * r, w[0], sizeof w[0]);
        memcpy(right + 3 * (p - r), w[p - r], sizeof w[0]);
        for (int k = 0; k < p - r; k++)
            for (int c = 0; c < 3; c++)
                w[k][c] = 0.5 * (w[k][c] + w[k + 1][c]);
    }
    flatten(s, left, p, depth + 1);
    flatten(s, right, p, depth + 1);
}

/* Samples curve c from t0 to t1 (either way round) into s. */
static bool sample_segment(sampler *s, const tsr_curve2 *c, double t0, double t1)
{
    dir d;
    if (!curve_init(c, &d) || !(t0 >= d.lo && t0 <= d.hi && t1 >= d.lo && t1 <= d.hi))
        return false;
    double start[2];
    if (tsr_curve2_eval(c, t0, start, NULL) != TSR_OK)
        return false;
    if (!s->any || hypot(start[0] - s->last[0], start[1] - s->last[1]) > s->tol)
        emit(s, start);
    if (t0 == t1)
        return true;
    bool back = t1 < t0;
    double lo = back ? t1 : t0, hi = back ? t0 : t1;
    /* the spans of [lo, hi], walked in the loop's direction */
    dir sub = d;
    sub.knots = c->knots, sub.lo = lo, sub.hi = hi;
    uint32_t fwd = find_span(&sub, lo) + 1, bwd = find_span(&sub, hi);
    double a = back ? hi : lo, b = a;
    while (back ? a > lo : b < hi) {
        if (back) { /* the span below a: down to the largest knot under it */
            b = a;
            while (bwd > (uint32_t)d.deg && !(sub.knots[bwd] < b))
                bwd--;
            a = sub.knots[bwd] > lo ? sub.knots[bwd] : lo;
        } else {
            a = b;
            b = next_break(&sub, a, &fwd);
        }
        uint32_t k;
        if (!piece_span(&sub, a, b, &k))
            return false;
        double h[MAXN * 3];
        for (int i = 0; i <= d.deg; i++) {
            uint32_t idx = k - (uint32_t)d.deg + (uint32_t)i;
            double w = c->weights ? c->weights[idx] : 1.0;
            if (!(w > 0) || !(w < INFINITY))
                return false;
            h[3 * i] = w * c->ctrl[2 * idx], h[3 * i + 1] = w * c->ctrl[2 * idx + 1], h[3 * i + 2] = w;
        }
        to_bezier_1d(&sub, k, a, b, h, 3);
        if (back)
            for (int i = 0; i < (d.deg + 1) / 2; i++)
                for (int cc = 0; cc < 3; cc++) {
                    double tmp = h[3 * i + cc];
                    h[3 * i + cc] = h[3 * (d.deg - i) + cc];
                    h[3 * (d.deg - i) + cc] = tmp;
                }
        flatten(s, h, d.deg, 0);
    }
    return true;
}

tsr_status tsr_trim_loop_sample(const tsr_patch_set *set, uint32_t loop, double tol, double *uv, uint32_t cap,
                                uint32_t *count)
{
    if (!set || !count || loop >= set->num_loops || !(tol > 0) || !isfinite(tol) || (!uv && cap))
        return TSR_ERR_ARGUMENT;
    const tsr_trim_loop *L = &set->loops[loop];
    if ((uint64_t)L->first_segment + L->num_segments > set->num_segments)
        return TSR_ERR_ARGUMENT;
    sampler s = {uv, cap, 0, tol, false, {0, 0}, {0, 0}};
    for (uint32_t i = 0; i < L->num_segments; i++) {
        const tsr_trim_segment *g = &set->segments[L->first_segment + i];
        if (g->curve >= set->num_curves || !sample_segment(&s, &set->curves[g->curve], g->t0, g->t1))
            return TSR_ERR_ARGUMENT;
    }
    /* the pending last point, unless it closes the loop */
    if (s.any && (s.n == 0 || hypot(s.last[0] - s.first[0], s.last[1] - s.first[1]) > tol)) {
        if (s.n < s.cap)
            s.uv[2 * s.n] = s.last[0], s.uv[2 * s.n + 1] = s.last[1];
        s.n++;
    }
    if (s.n > UINT32_MAX)
        return TSR_ERR_ARGUMENT;
    *count = (uint32_t)s.n;
    return TSR_OK;
}

/* ---- Checking a trim loop's shape ------------------------------------------- */

typedef struct xseg {
    double lo; /* the smaller u of its ends */
    uint32_t k; /* edge k: point k to point k + 1 (mod n) */
} xseg;

static int xseg_cmp(const void *a, const void *b)
{
    double x = ((const xseg *)a)->lo, y = ((const xseg *)b)->lo;
    return x < y ? -1 : x > y;
}

/* Whether edges pq and rs cross at a point inside both (exact signs). */
static bool edges_cross(const double *p, const double *q, const double *r, const double *s)
{
    double o1 = tsr_orient2d(p, q, r), o2 = tsr_orient2d(p, q, s);
    double o3 = tsr_orient2d(r, s, p), o4 = tsr_orient2d(r, s, q);
    return ((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0));
}

/* Signed area of the polygon pts (n points) clipped to the rectangle dom
 * (Sutherland-Hodgman, one side at a time); NAN when out of memory. */
static double clipped_area(const double *pts, uint32_t n, const double dom[4], const tsr_allocator *alloc)
{
    size_t m = n;
    double *cur = tsr_alloc(alloc, sizeof(double) * 2 * m);
    if (!cur)
        return NAN;
    memcpy(cur, pts, sizeof(double) * 2 * m);
    for (int side = 0; side < 4 && m > 0; side++) {
        int ax = side >> 1;            /* 0: u, 1: v */
        double lim = dom[side];        /* u0, u1, v0, v1 */
        bool keep_above = !(side & 1); /* u >= u0, u <= u1, v >= v0, v <= v1 */
        double *nxt = tsr_alloc(alloc, sizeof(double) * 4 * m); /* at most two points per edge */
        if (!nxt) {
            tsr_free(alloc, cur);
            return NAN;
        }
        size_t o = 0;
        for (size_t k = 0; k < m; k++) {
            const double *a = cur + 2 * k, *b = cur + 2 * ((k + 1) % m);
            bool ina = keep_above ? a[ax] >= lim : a[ax] <= lim, inb = keep_above ? b[ax] >= lim : b[ax] <= lim;
            if (ina) {
                nxt[2 * o] = a[0], nxt[2 * o + 1] = a[1];
                o++;
            }
            if (ina != inb) {
                double t = (lim - a[ax]) / (b[ax] - a[ax]);
                nxt[2 * o + ax] = lim;
                nxt[2 * o + 1 - ax] = a[1 - ax] + t * (b[1 - ax] - a[1 - ax]);
                o++;
            }
        }
        tsr_free(alloc, cur);
        cur = nxt;
        m = o;
    }
    double area = 0;
    for (size_t k = 0; k < m; k++) {
        const double *a = cur + 2 * k, *b = cur + 2 * ((k + 1) % m);
        area += a[0] * b[1] - a[1] * b[0];
    }
    tsr_free(alloc, cur);
    return 0.5 * area;
}

/* The largest depth (tsr_trim_loop_info) of the points of segment a-b:
 * the minimum of four functions linear along it is concave, so its
 * maximum is at an end or where two of them cross. */
static double edge_depth(const double *a, const double *b, const double dom[4])
{
    double W = dom[1] - dom[0], H = dom[3] - dom[2];
    /* depth_k(t) = c[k] + d[k] t */
    double c[4] = {(a[0] - dom[0]) / W, (dom[1] - a[0]) / W, (a[1] - dom[2]) / H, (dom[3] - a[1]) / H};
    double d[4] = {(b[0] - a[0]) / W, -(b[0] - a[0]) / W, (b[1] - a[1]) / H, -(b[1] - a[1]) / H};
    double ts[8] = {0, 1};
    int nt = 2;
    for (int i = 0; i < 4; i++)
        for (int j = i + 1; j < 4; j++)
            if (d[i] != d[j]) {
                double t = (c[j] - c[i]) / (d[i] - d[j]);
                if (t > 0 && t < 1 && nt < 8)
                    ts[nt++] = t;
            }
    double best = -INFINITY;
    for (int k = 0; k < nt; k++) {
        double m = INFINITY;
        for (int i = 0; i < 4; i++)
            m = fmin(m, c[i] + d[i] * ts[k]);
        best = fmax(best, m);
    }
    return best;
}

tsr_status tsr_trim_loop_check(const tsr_patch_set *set, uint32_t loop, double tol, const tsr_allocator *alloc,
                               tsr_trim_loop_info *info)
{
    if (!info)
        return TSR_ERR_ARGUMENT;
    memset(info, 0, sizeof *info);
    uint32_t n = 0;
    tsr_status st = tsr_trim_loop_sample(set, loop, tol, NULL, 0, &n);
    if (st != TSR_OK)
        return st;
    const tsr_trim_loop *L = &set->loops[loop];
    double dom[4];
    if (L->patch >= set->num_patches || tsr_patch_domain(&set->patches[L->patch], dom) != TSR_OK)
        return TSR_ERR_ARGUMENT;
    info->domain_area = (dom[1] - dom[0]) * (dom[3] - dom[2]);
    info->points = n;
    /* the gaps: each segment's start against the previous one's end */
    for (uint32_t i = 0; i < L->num_segments; i++) {
        const tsr_trim_segment *g = &set->segments[L->first_segment + i];
        const tsr_trim_segment *h = &set->segments[L->first_segment + (i + L->num_segments - 1) % L->num_segments];
        double a[2], b[2];
        if (tsr_curve2_eval(&set->curves[h->curve], h->t1, a, NULL) != TSR_OK ||
            tsr_curve2_eval(&set->curves[g->curve], g->t0, b, NULL) != TSR_OK)
            return TSR_ERR_ARGUMENT;
        double d = hypot(a[0] - b[0], a[1] - b[1]);
        if (d > tol && d > info->gap)
            info->gap = d;
    }
    if (n < 3)
        return TSR_OK; /* no area, no crossing */
    double *pts = tsr_alloc(alloc, sizeof(double) * 2 * n);
    xseg *xs = tsr_alloc(alloc, sizeof *xs * n);
    if (!pts || !xs) {
        tsr_free(alloc, pts);
        tsr_free(alloc, xs);
        return TSR_ERR_NOMEM;
    }
    tsr_trim_loop_sample(set, loop, tol, pts, n, &n);
    /* crossings: edges sorted by their lower u, each against those that
     * begin before it ends */
    for (uint32_t k = 0; k < n; k++) {
        const double *a = pts + 2 * k, *b = pts + 2 * ((k + 1) % n);
        xs[k] = (xseg){a[0] < b[0] ? a[0] : b[0], k};
    }
    qsort(xs, n, sizeof *xs, xseg_cmp);
    for (uint32_t i = 0; i < n && !info->crosses; i++) {
        uint32_t k = xs[i].k;
        const double *a = pts + 2 * k, *b = pts + 2 * ((k + 1) % n);
        double hi = a[0] > b[0] ? a[0] : b[0];
        double vlo = a[1] < b[1] ? a[1] : b[1], vhi = a[1] > b[1] ? a[1] : b[1];
        for (uint32_t j = i + 1; j < n && xs[j].lo <= hi; j++) {
            uint32_t l = xs[j].k;
            if (l == (k + 1) % n || k == (l + 1) % n)
                continue; /* neighbours share an end */
            const double *c = pts + 2 * l, *d = pts + 2 * ((l + 1) % n);
            if ((c[1] < vlo && d[1] < vlo) || (c[1] > vhi && d[1] > vhi))
                continue;
            if (edges_cross(a, b, c, d)) {
                info->crosses = true;
                /* where: the intersection of the two lines */
                double den = (b[0] - a[0]) * (d[1] - c[1]) - (b[1] - a[1]) * (d[0] - c[0]);
                double t = den != 0 ? ((c[0] - a[0]) * (d[1] - c[1]) - (c[1] - a[1]) * (d[0] - c[0])) / den : 0.5;
                info->cross_uv[0] = a[0] + t * (b[0] - a[0]);
                info->cross_uv[1] = a[1] + t * (b[1] - a[1]);
                break;
            }
        }
    }
    /* depth, and the centre's crossing number */
    double cu = 0.5 * (dom[0] + dom[1]), cv = 0.5 * (dom[2] + dom[3]);
    bool in = false;
    info->depth = -INFINITY;
    for (uint32_t k = 0; k < n; k++) {
        const double *a = pts + 2 * k, *b = pts + 2 * ((k + 1) % n);
        info->depth = fmax(info->depth, edge_depth(a, b, dom));
        if ((a[1] > cv) != (b[1] > cv) && cu < a[0] + (cv - a[1]) / (b[1] - a[1]) * (b[0] - a[0]))
            in = !in;
    }
    info->encloses_centre = in;
    /* a simple polygon's area inside the domain; a crossing one's signed
     * area is no area of its inside: left unknown */
    info->area = info->crosses ? -1 : fabs(clipped_area(pts, n, dom, alloc));
    tsr_free(alloc, pts);
    tsr_free(alloc, xs);
    return isnan(info->area) ? TSR_ERR_NOMEM : TSR_OK;
}
