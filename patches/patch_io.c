/* patch_io.c: the readers of patches/: Bézier patch files (.bpt), the
 * free-form part of Wavefront OBJ (cstype, deg, surf, curv2, parm, trim,
 * hole, end; "Object Files (.obj)", Wavefront Advanced Visualizer manual,
 * appendix B1), and polygon OBJ cages with OpenSubdiv's tag lines
 * (regression/common/shape_utils and far_utils of OpenSubdiv 3.5).
 *
 * Every reader works on the whole file in memory, statement by statement,
 * and stops at the first problem with "file:line: what". Arrays grow by
 * doubling, and every element they hold costs at least one byte of the
 * file, so memory stays within a small multiple of the file's size
 * whatever its counts claim; the one count that would size an allocation
 * up front (a .bpt header's) is weighed against the bytes left first. */
#define _POSIX_C_SOURCE 200809L
#include "patches/patches.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* ---- Growable arrays ------------------------------------------------------------- */

typedef struct vec {
    void *data;
    size_t n, cap; /* in elements */
} vec;

static bool vec_reserve(const tsr_allocator *a, vec *v, size_t elem, size_t more)
{
    if (v->n + more <= v->cap)
        return true;
    size_t cap = v->cap ? v->cap : 16;
    while (cap < v->n + more) {
        if (cap > SIZE_MAX / 2 / elem)
            return false;
        cap *= 2;
    }
    void *d = tsr_realloc(a, v->data, cap * elem);
    if (!d)
        return false;
    v->data = d, v->cap = cap;
    return true;
}

static bool push_u32(const tsr_allocator *a, vec *v, uint32_t x)
{
    if (!vec_reserve(a, v, sizeof x, 1))
        return false;
    ((uint32_t *)v->data)[v->n++] = x;
    return true;
}

static bool push_f64(const tsr_allocator *a, vec *v, double x)
{
    if (!vec_reserve(a, v, sizeof x, 1))
        return false;
    ((double *)v->data)[v->n++] = x;
    return true;
}

static bool push_f32(const tsr_allocator *a, vec *v, float x)
{
    if (!vec_reserve(a, v, sizeof x, 1))
        return false;
    ((float *)v->data)[v->n++] = x;
    return true;
}

static bool push_any(const tsr_allocator *a, vec *v, size_t elem, const void *x)
{
    if (!vec_reserve(a, v, elem, 1))
        return false;
    memcpy((char *)v->data + v->n * elem, x, elem);
    v->n++;
    return true;
}

static void vec_free(const tsr_allocator *a, vec *v)
{
    tsr_free(a, v->data);
    v->data = NULL, v->n = v->cap = 0;
}

#define F64(v) ((double *)(v).data)
#define U32(v) ((uint32_t *)(v).data)

/* ---- Whole files ------------------------------------------------------------------ */

/* ---- Statements and tokens ------------------------------------------------------- */

typedef struct token {
    const char *s;
    size_t n;
    uint32_t line;
} token;

typedef struct lexer {
    const char *name;
    const char *p, *end;
    uint32_t line;      /* where p is */
    uint32_t stmt_line; /* where the current statement began */
    tsr_error *err;
} lexer;

static bool blank(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

static bool next_token(lexer *L, struct token *t);

/* Moves to the first token of the next statement (skipping blank lines,
 * comments and statements of nothing but continuations); false at the
 * end of the file. A true return guarantees next_token finds a token. */
static bool next_statement(lexer *L)
{
    while (L->p < L->end) {
        char c = *L->p;
        if (c == '\n') {
            L->p++, L->line++;
        } else if (blank(c)) {
            L->p++;
        } else if (c == '#') {
            while (L->p < L->end && *L->p != '\n')
                L->p++;
        } else {
            L->stmt_line = L->line;
            lexer peek = *L;
            struct token t;
            if (next_token(&peek, &t))
                return true;
            *L = peek; /* only continuations: read past them */
        }
    }
    return false;
}

/* The next token of the current statement; false at its end (a line end
 * not preceded by a lone backslash, or the end of the file). */
static bool next_token(lexer *L, token *t)
{
    for (;;) {
        while (L->p < L->end && blank(*L->p))
            L->p++;
        if (L->p >= L->end || *L->p == '\n')
            return false;
        if (*L->p == '#') {
            while (L->p < L->end && *L->p != '\n')
                L->p++;
            return false;
        }
        if (*L->p == '\\') { /* a continuation when nothing but blanks follows on the line */
            const char *q = L->p + 1;
            while (q < L->end && blank(*q))
                q++;
            if (q >= L->end) {
                L->p = q;
                return false;
            }
            if (*q == '\n') {
                L->p = q + 1, L->line++;
                continue;
            }
        }
        t->s = L->p, t->line = L->line;
        while (L->p < L->end && *L->p != '\n' && *L->p != '#' && !blank(*L->p))
            L->p++;
        t->n = (size_t)(L->p - t->s);
        return true;
    }
}

static void skip_statement(lexer *L)
{
    token t;
    while (next_token(L, &t)) {
    }
}

/* How many tokens are left in the statement (consumes them). */
static uint32_t count_rest(lexer *L)
{
    token t;
    uint32_t n = 0;
    while (next_token(L, &t))
        n++;
    return n;
}

static bool tok_is(const token *t, const char *word)
{
    return t->n == strlen(word) && !memcmp(t->s, word, t->n);
}

/* A token as messages show it. */
static const char *shown(const token *k, char *buf, size_t cap) { return tsr_quote_bytes(k->s, k->n, buf, cap); }

static tsr_status fail(const lexer *L, uint32_t line, tsr_status s, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static tsr_status fail(const lexer *L, uint32_t line, tsr_status s, const char *fmt, ...)
{
    char msg[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (line)
        return tsr_error_set(L->err, s, "%s:%u: %s", L->name, line, msg);
    return tsr_error_set(L->err, s, "%s: %s", L->name, msg);
}

static tsr_status nomem(const lexer *L)
{
    return fail(L, 0, TSR_ERR_NOMEM, "out of memory");
}

static bool lower_eq(const char *s, const char *word, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        char c = s[i] >= 'A' && s[i] <= 'Z' ? (char)(s[i] - 'A' + 'a') : s[i];
        if (c != word[i])
            return false;
    }
    return true;
}

/* A finite decimal number. */
static tsr_status parse_number(const lexer *L, const token *k, const char *what, double *v)
{
    char buf[128], sb[128];
    bool syntax = k->n > 0 && k->n < sizeof buf;
    for (size_t i = 0; syntax && i < k->n; i++)
        syntax = k->s[i] != '\0' && strchr("0123456789+-.eE", k->s[i]) != NULL;
    if (syntax) {
        memcpy(buf, k->s, k->n);
        buf[k->n] = '\0';
        char *end;
        *v = strtod(buf, &end);
        if (end != buf + k->n)
            syntax = false;
        else if (!isfinite(*v))
            return fail(L, k->line, TSR_ERR_VALUE, "%s '%s' is not a finite number", what, shown(k, sb, sizeof sb));
    }
    if (!syntax) {
        const char *s = k->s;
        size_t n = k->n;
        if (n > 0 && (*s == '-' || *s == '+'))
            s++, n--;
        bool word = n >= 3 && (lower_eq(s, "nan", 3) || lower_eq(s, "inf", 3));
        return fail(L, k->line, word ? TSR_ERR_VALUE : TSR_ERR_FORMAT, "%s '%s' is not %s", what,
                    shown(k, sb, sizeof sb), word ? "a finite number" : "a number");
    }
    return TSR_OK;
}

/* A non-negative decimal integer below 2^32. */
static tsr_status parse_u32(const lexer *L, const token *k, const char *what, uint32_t *v)
{
    char sb[128];
    bool digits = k->n > 0;
    for (size_t i = 0; digits && i < k->n; i++)
        digits = k->s[i] >= '0' && k->s[i] <= '9';
    if (!digits)
        return fail(L, k->line, TSR_ERR_FORMAT, "%s '%s' is not a non-negative integer", what, shown(k, sb, sizeof sb));
    uint64_t x = 0;
    for (size_t i = 0; i < k->n; i++) {
        x = x * 10 + (uint64_t)(k->s[i] - '0');
        if (x > UINT32_MAX)
            return fail(L, k->line, TSR_ERR_TOO_LARGE, "%s '%s' is beyond 4294967295", what, shown(k, sb, sizeof sb));
    }
    *v = (uint32_t)x;
    return TSR_OK;
}

/* An OBJ reference: the first field of v, v/vt, v//vn, v/vt/vn, resolved
 * against the n elements read so far (1-based; negative counts back).
 * *second gets the vt field (0 when absent). */
static tsr_status parse_ref(const lexer *L, const token *k, const char *what, uint32_t n, uint32_t *out,
                            int64_t *second)
{
    char sb[128];
    int64_t f[3] = {0, 0, 0};
    int nf = 0;
    size_t i = 0;
    bool ok = true;
    while (ok && nf < 3) {
        bool neg = i < k->n && k->s[i] == '-';
        i += neg;
        size_t start = i;
        int64_t x = 0;
        while (i < k->n && k->s[i] >= '0' && k->s[i] <= '9' && i - start < 12)
            x = x * 10 + (k->s[i++] - '0');
        bool empty = i == start;
        if (empty && (nf != 1 || neg)) /* only vt may be empty (v//vn) */
            ok = false;
        f[nf++] = neg ? -x : x;
        if (i < k->n && k->s[i] == '/')
            i++;
        else
            break;
    }
    if (!ok || i != k->n)
        return fail(L, k->line, TSR_ERR_FORMAT, "%s reference '%s' is not an index (v, v/vt, v//vn or v/vt/vn)", what,
                    shown(k, sb, sizeof sb));
    int64_t r = f[0];
    if (r == 0)
        return fail(L, k->line, TSR_ERR_VALUE, "%s index 0 is not valid (OBJ counts from 1)", what);
    int64_t abs0 = r > 0 ? r - 1 : (int64_t)n + r;
    if (abs0 < 0 || abs0 >= (int64_t)n)
        return fail(L, k->line, TSR_ERR_VALUE, "%s %lld is not defined (%u so far)", what, (long long)r, n);
    *out = (uint32_t)abs0;
    if (second)
        *second = nf > 1 ? f[1] : 0;
    return TSR_OK;
}

/* Keywords are printable ASCII; anything else means this is not text of
 * the expected kind. */
static tsr_status check_keyword(const lexer *L, const token *k, const char *kind)
{
    char sb[128];
    for (size_t i = 0; i < k->n; i++) {
        unsigned char c = (unsigned char)k->s[i];
        if (c < 33 || c > 126)
            return fail(L, k->line, TSR_ERR_FORMAT, "'%s' is not %s statement", shown(k, sb, sizeof sb), kind);
    }
    return TSR_OK;
}

/* ---- Patch sets under construction ----------------------------------------------- */

#define NONE SIZE_MAX

typedef struct patch_rec {
    tsr_patch p;                            /* pointers unset */
    size_t ctrl, weights, knots_u, knots_v; /* offsets into values, NONE when absent */
} patch_rec;

typedef struct curve_rec {
    tsr_curve2 c;
    size_t ctrl, weights, knots;
} curve_rec;

typedef struct builder {
    const tsr_allocator *a;
    vec values;   /* double */
    vec patches;  /* patch_rec */
    vec curves;   /* curve_rec */
    vec loops;    /* tsr_trim_loop */
    vec segments; /* tsr_trim_segment */
    uint32_t skipped, first_skipped;
    uint32_t polygons, first_polygon;
    uint32_t unknown, first_unknown_line, unused, first_unused;
    char first_unknown[40];
} builder;

static void builder_free(builder *b)
{
    vec_free(b->a, &b->values);
    vec_free(b->a, &b->patches);
    vec_free(b->a, &b->curves);
    vec_free(b->a, &b->loops);
    vec_free(b->a, &b->segments);
}

static void skipped(builder *b, uint32_t line)
{
    if (b->skipped++ == 0)
        b->first_skipped = line;
}

/* Appends n doubles to values, returning their offset (NONE: no memory). */
static size_t add_values(builder *b, const double *x, size_t n)
{
    if (!vec_reserve(b->a, &b->values, sizeof(double), n))
        return NONE;
    size_t at = b->values.n;
    memcpy(F64(b->values) + at, x, n * sizeof(double));
    b->values.n += n;
    return at;
}

/* Reserves n doubles in values; *at gets their offset. */
static double *grow_values(builder *b, size_t n, size_t *at)
{
    if (!vec_reserve(b->a, &b->values, sizeof(double), n))
        return NULL;
    *at = b->values.n;
    b->values.n += n;
    return F64(b->values) + *at;
}

static const double *at_or_null(const builder *b, size_t off)
{
    return off == NONE ? NULL : F64(b->values) + off;
}

static tsr_patch view_patch(const builder *b, const patch_rec *r)
{
    tsr_patch p = r->p;
    p.ctrl = at_or_null(b, r->ctrl);
    p.weights = at_or_null(b, r->weights);
    p.knots_u = at_or_null(b, r->knots_u);
    p.knots_v = at_or_null(b, r->knots_v);
    return p;
}

static tsr_curve2 view_curve(const builder *b, const curve_rec *r)
{
    tsr_curve2 c = r->c;
    c.ctrl = at_or_null(b, r->ctrl);
    c.weights = at_or_null(b, r->weights);
    c.knots = at_or_null(b, r->knots);
    return c;
}

/* Moves the builder's arrays into the set, fixing every view. */
static tsr_status finish_set(builder *b, const lexer *L, tsr_patch_set *out)
{
    const tsr_allocator *a = b->a;
    uint32_t np = (uint32_t)b->patches.n, nc = (uint32_t)b->curves.n;
    tsr_patch *patches = tsr_alloc(a, (np ? np : 1) * sizeof *patches);
    tsr_curve2 *curves = tsr_alloc(a, (nc ? nc : 1) * sizeof *curves);
    uint32_t *first = tsr_alloc(a, ((size_t)np + 1) * sizeof *first);
    if (!patches || !curves || !first) {
        tsr_free(a, patches), tsr_free(a, curves), tsr_free(a, first);
        return nomem(L);
    }
    const patch_rec *pr = b->patches.data;
    const curve_rec *cr = b->curves.data;
    for (uint32_t i = 0; i < np; i++)
        patches[i] = view_patch(b, &pr[i]);
    for (uint32_t i = 0; i < nc; i++)
        curves[i] = view_curve(b, &cr[i]);
    const tsr_trim_loop *loops = b->loops.data;
    uint32_t nl = (uint32_t)b->loops.n, l = 0;
    for (uint32_t i = 0; i <= np; i++) {
        first[i] = l;
        while (l < nl && loops[l].patch == i)
            l++;
    }
    memset(out, 0, sizeof *out);
    out->num_patches = np, out->patches = patches, out->first_loop = first;
    out->num_loops = nl, out->loops = b->loops.data;
    out->num_segments = (uint32_t)b->segments.n, out->segments = b->segments.data;
    out->num_curves = nc, out->curves = curves;
    out->num_skipped = b->skipped, out->first_skipped_line = b->first_skipped;
    out->num_polygons = b->polygons, out->first_polygon_line = b->first_polygon;
    out->num_unknown = b->unknown, out->first_unknown_line = b->first_unknown_line;
    memcpy(out->first_unknown, b->first_unknown, sizeof out->first_unknown);
    out->num_unused_freeform = b->unused, out->first_unused_freeform_line = b->first_unused;
    out->values = b->values.data, out->num_values = b->values.n;
    out->alloc = a ? *a : (tsr_allocator){NULL, NULL, NULL};
    b->loops.data = b->segments.data = b->values.data = NULL;
    vec_free(a, &b->patches);
    vec_free(a, &b->curves);
    return TSR_OK;
}

void tsr_patch_set_free(tsr_patch_set *s)
{
    if (!s)
        return;
    const tsr_allocator *a = s->alloc.realloc ? &s->alloc : NULL;
    tsr_free(a, s->patches);
    tsr_free(a, s->first_loop);
    tsr_free(a, s->loops);
    tsr_free(a, s->segments);
    tsr_free(a, s->curves);
    tsr_free(a, s->values);
    memset(s, 0, sizeof *s);
}

/* ---- .bpt -------------------------------------------------------------------------- */

/* The fewest bytes one patch can take: "1 1\n" and four "0 0 0\n". */
#define BPT_MIN_PATCH_BYTES 24

static tsr_status parse_bpt(lexer *L, builder *b)
{
    token t = {NULL, 0, 0};
    if (!next_statement(L) || !next_token(L, &t))
        return fail(L, 0, TSR_ERR_EMPTY, "no patch count (the file has only blank lines and comments)");
    uint32_t n;
    tsr_status s = parse_u32(L, &t, "patch count", &n);
    if (s != TSR_OK)
        return s;
    uint32_t extra = count_rest(L);
    if (extra)
        return fail(L, L->stmt_line, TSR_ERR_FORMAT,
                    "expected the patch count alone on the first line, found %u more values", extra);
    if (n == 0)
        return fail(L, L->stmt_line, TSR_ERR_EMPTY, "the patch count is 0");
    uint64_t left = (uint64_t)(L->end - L->p);
    if ((uint64_t)n > left / BPT_MIN_PATCH_BYTES + 1)
        return fail(L, L->stmt_line, TSR_ERR_TOO_LARGE, "%u patches cannot fit in the %llu bytes left in the file", n,
                    (unsigned long long)left);
    for (uint32_t i = 0; i < n; i++) {
        if (!next_statement(L))
            return fail(L, L->line, TSR_ERR_TRUNCATED, "the file ends after %u of %u patches", i, n);
        uint32_t deg[2], got = 0;
        while (next_token(L, &t)) {
            if (got < 2 && (s = parse_u32(L, &t, got ? "degree in v" : "degree in u", &deg[got])) != TSR_OK)
                return s;
            got++;
        }
        if (got != 2)
            return fail(L, L->stmt_line, TSR_ERR_FORMAT, "expected 2 degrees (du dv) for patch %u, found %u values",
                        i + 1, got);
        for (int k = 0; k < 2; k++) {
            if (deg[k] == 0)
                return fail(L, L->stmt_line, TSR_ERR_VALUE, "patch %u: degree 0 (degrees are 1..%d)", i + 1,
                            TSR_PATCH_MAX_DEGREE);
            if (deg[k] > TSR_PATCH_MAX_DEGREE)
                return fail(L, L->stmt_line, TSR_ERR_UNSUPPORTED, "patch %u: degree %u is beyond the supported 1..%d",
                            i + 1, deg[k], TSR_PATCH_MAX_DEGREE);
        }
        uint32_t np = (deg[0] + 1) * (deg[1] + 1);
        size_t at;
        double *ctrl = grow_values(b, 3 * (size_t)np, &at);
        if (!ctrl)
            return nomem(L);
        for (uint32_t k = 0; k < np; k++) {
            if (!next_statement(L))
                return fail(L, L->line, TSR_ERR_TRUNCATED,
                            "the file ends after %u of the %u control points of patch %u", k, np, i + 1);
            uint32_t c = 0;
            while (next_token(L, &t)) {
                if (c < 3 && (s = parse_number(L, &t, "coordinate", &ctrl[3 * k + c])) != TSR_OK)
                    return s;
                if (c < 3 && !(fabs(ctrl[3 * k + c]) <= TSR_PATCH_MAX_ABS))
                    return fail(L, t.line, TSR_ERR_VALUE, "coordinate %g is beyond +-%g", ctrl[3 * k + c],
                                TSR_PATCH_MAX_ABS);
                c++;
            }
            if (c != 3)
                return fail(L, L->stmt_line, TSR_ERR_FORMAT, "expected 3 coordinates, found %u", c);
        }
        patch_rec r = {
            {TSR_PATCH_BEZIER, (int)deg[0], (int)deg[1], deg[0] + 1, deg[1] + 1, NULL, NULL, NULL, NULL, 0, 1, 0, 1},
            at,
            NONE,
            NONE,
            NONE};
        if (!push_any(b->a, &b->patches, sizeof r, &r))
            return nomem(L);
    }
    if (next_statement(L))
        return fail(L, L->stmt_line, TSR_ERR_FORMAT, "unexpected data after the %u patches the file announces", n);
    return TSR_OK;
}

/* ---- OBJ free-form ------------------------------------------------------------------ */

enum { CS_NONE, CS_BEZIER, CS_BSPLINE, CS_OTHER };
enum { EL_NONE, EL_SURF, EL_CURV2, EL_SKIP };

typedef struct element {
    int kind;
    uint32_t line;
    int type; /* CS_* at the element */
    bool rational;
    uint32_t type_line;
    int du, dv; /* 0: not given */
    double range[4];
    vec refs;    /* uint32: resolved indices */
    vec parm[2]; /* double */
    bool has_parm[2];
    const char *keyword;
} element;

typedef struct obj_state {
    builder *b;
    vec v;  /* 4 doubles each: x y z w */
    vec vp; /* 3 doubles each: u v w */
    int type;
    bool rational;
    uint32_t type_line;
    int du, dv;
    element el;
} obj_state;

static void obj_state_free(obj_state *o)
{
    const tsr_allocator *a = o->b->a;
    vec_free(a, &o->v);
    vec_free(a, &o->vp);
    vec_free(a, &o->el.refs);
    vec_free(a, &o->el.parm[0]);
    vec_free(a, &o->el.parm[1]);
}

/* Numbers of the statement into x (at most max); returns how many, or an
 * error. */
static tsr_status read_numbers(lexer *L, const char *what, double *x, uint32_t max, uint32_t *n)
{
    token t;
    *n = 0;
    tsr_status s;
    while (next_token(L, &t)) {
        double v;
        if ((s = parse_number(L, &t, what, &v)) != TSR_OK)
            return s;
        if (*n < max)
            x[*n] = v;
        (*n)++;
    }
    return TSR_OK;
}

static const char *type_name(int type)
{
    return type == CS_BEZIER ? "bezier" : type == CS_BSPLINE ? "bspline" : "unsupported";
}

/* The knot vector of one direction of an element: bspline parm values as
 * they are; bezier breakpoints t_0 < ... < t_K as t_0 (deg + 1 times),
 * interior ones deg times, t_K (deg + 1 times). *count gets the control
 * points it implies. */
static tsr_status element_knots(lexer *L, builder *b, const element *e, int axis, int deg, size_t *knots_at,
                                uint32_t *count)
{
    static const double unit[2] = {0, 1};
    const double *parm = e->has_parm[axis] ? F64(e->parm[axis]) : unit;
    size_t np = e->has_parm[axis] ? e->parm[axis].n : 2;
    const char *dirn = axis ? "v" : "u";
    if (e->type == CS_BSPLINE) {
        if (!e->has_parm[axis])
            return fail(L, e->line, TSR_ERR_FORMAT, "%s: a bspline needs its knots in 'parm %s'", e->keyword, dirn);
        if (np < 2 * (size_t)deg + 2)
            return fail(L, e->line, TSR_ERR_FORMAT, "%s: degree %d needs at least %d knots in parm %s, found %zu",
                        e->keyword, deg, 2 * deg + 2, dirn, np);
        if (np - (size_t)deg - 1 > TSR_PATCH_MAX_COUNT)
            return fail(L, e->line, TSR_ERR_TOO_LARGE,
                        "%s: %zu knots in parm %s, beyond the %u control points accepted", e->keyword, np, dirn,
                        TSR_PATCH_MAX_COUNT);
        *count = (uint32_t)(np - (size_t)deg - 1);
        *knots_at = add_values(b, parm, np);
        return *knots_at == NONE ? nomem(L) : TSR_OK;
    }
    if (np < 2)
        return fail(L, e->line, TSR_ERR_FORMAT, "%s: a bezier needs at least 2 values in parm %s", e->keyword, dirn);
    size_t spans = np - 1;
    if (spans > (TSR_PATCH_MAX_COUNT - 1) / (size_t)deg)
        return fail(L, e->line, TSR_ERR_TOO_LARGE, "%s: %zu spans in parm %s, beyond the %u control points accepted",
                    e->keyword, spans, dirn, TSR_PATCH_MAX_COUNT);
    *count = (uint32_t)(spans * (size_t)deg + 1);
    size_t m = (size_t)*count + (size_t)deg + 1;
    double *k = grow_values(b, m, knots_at);
    if (!k)
        return nomem(L);
    size_t o = 0;
    for (size_t i = 0; i < np; i++) {
        int mult = i == 0 || i == np - 1 ? deg + 1 : deg;
        for (int r = 0; r < mult; r++)
            k[o++] = parm[i];
    }
    return TSR_OK;
}

static tsr_status finish_surf(lexer *L, obj_state *o)
{
    builder *b = o->b;
    element *e = &o->el;
    size_t ku, kv;
    uint32_t nu, nv;
    tsr_status s = element_knots(L, b, e, 0, e->du, &ku, &nu);
    if (s == TSR_OK)
        s = element_knots(L, b, e, 1, e->dv, &kv, &nv);
    if (s != TSR_OK)
        return s;
    if ((uint64_t)nu * nv != e->refs.n)
        return fail(L, e->line, TSR_ERR_FORMAT,
                    "surf has %zu control vertices, but a %s of degrees %d %d with %u x %u control points needs %llu",
                    e->refs.n, type_name(e->type), e->du, e->dv, nu, nv, (unsigned long long)nu * nv);
    if ((uint64_t)nu * nv > TSR_PATCH_MAX_POINTS)
        return fail(L, e->line, TSR_ERR_TOO_LARGE, "surf has %llu control points, beyond the %u accepted",
                    (unsigned long long)nu * nv, TSR_PATCH_MAX_POINTS);
    size_t n = e->refs.n, ca, wa = NONE;
    double *ctrl = grow_values(b, 3 * n, &ca);
    if (!ctrl)
        return nomem(L);
    const double *V = F64(o->v);
    for (size_t i = 0; i < n; i++)
        memcpy(ctrl + 3 * i, V + 4 * (size_t)U32(e->refs)[i], 3 * sizeof(double));
    if (e->rational) {
        double *w = grow_values(b, n, &wa);
        if (!w)
            return nomem(L);
        for (size_t i = 0; i < n; i++) {
            w[i] = V[4 * (size_t)U32(e->refs)[i] + 3];
            if (!(w[i] > 0))
                return fail(L, e->line, TSR_ERR_VALUE,
                            "control vertex %zu (v %u) has weight %g; a rational surface needs positive weights", i + 1,
                            U32(e->refs)[i] + 1, w[i]);
        }
    }
    patch_rec r = {{TSR_PATCH_BSPLINE, e->du, e->dv, nu, nv, NULL, NULL, NULL, NULL, e->range[0], e->range[1],
                    e->range[2], e->range[3]},
                   ca,
                   wa,
                   ku,
                   kv};
    if (e->rational)
        r.p.kind = TSR_PATCH_NURBS;
    const double *K = F64(b->values);
    if (e->type == CS_BEZIER && nu == (uint32_t)e->du + 1 && nv == (uint32_t)e->dv + 1 && K[ku] == e->range[0] &&
        K[ku + nu] == e->range[1] && K[kv] == e->range[2] && K[kv + nv] == e->range[3]) {
        r.p.kind = TSR_PATCH_BEZIER; /* one span each way, all of it */
        r.knots_u = r.knots_v = NONE;
    }
    /* the domain against the parameter range, before the general checks */
    const double lo[2] = {K[ku + (size_t)e->du], K[kv + (size_t)e->dv]}, hi[2] = {K[ku + nu], K[kv + nv]};
    for (int a = 0; a < 2; a++)
        if (e->range[2 * a] < lo[a] || e->range[2 * a + 1] > hi[a])
            return fail(L, e->line, TSR_ERR_VALUE, "surf's %s range [%g, %g] leaves the parameter range [%g, %g]",
                        a ? "t" : "s", e->range[2 * a], e->range[2 * a + 1], lo[a], hi[a]);
    /* a range below a billionth of the parameters': a surface with (next
     * to) no area, which the float32 mesh cannot hold apart (it gave half a
     * million zero-area triangles) */
    for (int a = 0; a < 2; a++)
        if (e->range[2 * a + 1] - e->range[2 * a] < 1e-9 * (hi[a] - lo[a]))
            return fail(L, e->line, TSR_ERR_VALUE,
                        "surf's %s range [%.17g, %.17g] is under a billionth of the parameter range [%g, %g]: the "
                        "surface has no area to tessellate",
                        a ? "t" : "s", e->range[2 * a], e->range[2 * a + 1], lo[a], hi[a]);
    /* a knot repeated degree + 1 times inside the range ends one run of
     * control points and starts the next: the surface breaks apart there
     * unless the two runs' last and first rows coincide (exporters write
     * split Bézier pieces so); broken, its pieces need not meet, and no
     * mesh of it can be both joined and within the error */
    const double *C = F64(b->values) + ca;
    double clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            clo[c] = fmin(clo[c], C[3 * i + c]);
            chi[c] = fmax(chi[c], C[3 * i + c]);
        }
    double gap_tol = 1e-9 * (1 + hypot(hypot(chi[0] - clo[0], chi[1] - clo[1]), chi[2] - clo[2]));
    for (int a = 0; a < 2; a++) {
        const double *k = K + (a ? kv : ku);
        int deg = a ? e->dv : e->du;
        size_t cnt = a ? nv : nu, other = a ? nu : nv, nk = cnt + (size_t)deg + 1;
        for (size_t i = 0; i < nk;) {
            size_t j = i;
            while (j < nk && k[j] == k[i])
                j++;
            if (j - i == (size_t)deg + 1 && k[i] > e->range[2 * a] && k[i] < e->range[2 * a + 1] && i >= 1 && i < cnt) {
                double worst = 0;
                for (size_t r = 0; r < other; r++) {
                    size_t p0 = a ? (i - 1) * nu + r : r * nu + i - 1, p1 = a ? i * nu + r : r * nu + i;
                    worst = fmax(worst, hypot(hypot(C[3 * p0] - C[3 * p1], C[3 * p0 + 1] - C[3 * p1 + 1]),
                                              C[3 * p0 + 2] - C[3 * p1 + 2]));
                }
                if (!(worst <= gap_tol))
                    return fail(L, e->line, TSR_ERR_VALUE,
                                "surf: knot %g of parm %s appears %zu times, more than the degree %d, and the control "
                                "points on either side of it are %g apart: the surface is discontinuous there "
                                "(split it into two surfaces)",
                                k[i], a ? "v" : "u", j - i, deg, worst);
            }
            i = j;
        }
    }
    tsr_patch view = view_patch(b, &r);
    tsr_error pe = {0};
    if (tsr_patch_check(&view, &pe) != TSR_OK)
        return fail(L, e->line, TSR_ERR_VALUE, "surf: %s", pe.message);
    if (!push_any(b->a, &b->patches, sizeof r, &r))
        return nomem(L);
    return TSR_OK;
}

static tsr_status finish_curv2(lexer *L, obj_state *o)
{
    builder *b = o->b;
    element *e = &o->el;
    size_t ka;
    uint32_t n;
    tsr_status s = element_knots(L, b, e, 0, e->du, &ka, &n);
    if (s != TSR_OK)
        return s;
    if (n != e->refs.n)
        return fail(L, e->line, TSR_ERR_FORMAT,
                    "curv2 has %zu control points, but a %s of degree %d over its parm u needs %u", e->refs.n,
                    type_name(e->type), e->du, n);
    size_t ca, wa = NONE;
    double *ctrl = grow_values(b, 2 * (size_t)n, &ca);
    if (!ctrl)
        return nomem(L);
    const double *P = F64(o->vp);
    for (uint32_t i = 0; i < n; i++)
        memcpy(ctrl + 2 * i, P + 3 * (size_t)U32(e->refs)[i], 2 * sizeof(double));
    if (e->rational) {
        double *w = grow_values(b, n, &wa);
        if (!w)
            return nomem(L);
        for (uint32_t i = 0; i < n; i++) {
            w[i] = P[3 * (size_t)U32(e->refs)[i] + 2];
            if (!(w[i] > 0))
                return fail(L, e->line, TSR_ERR_VALUE,
                            "control point %u (vp %u) has weight %g; a rational curve needs positive weights", i + 1,
                            U32(e->refs)[i] + 1, w[i]);
        }
    }
    curve_rec r = {{e->du, n, NULL, NULL, NULL}, ca, wa, ka};
    tsr_curve2 view = view_curve(b, &r);
    tsr_error ce = {0};
    if (tsr_curve2_check(&view, &ce) != TSR_OK)
        return fail(L, e->line, TSR_ERR_VALUE, "curv2: %s", ce.message);
    if (!push_any(b->a, &b->curves, sizeof r, &r))
        return nomem(L);
    return TSR_OK;
}

/* Is kw a statement of the OBJ format (geometry, free-form, grouping,
 * display and rendering attributes)? Those we do not use are read past;
 * any other word is a misspelling worth a warning. */
static bool obj_keyword(const token *kw)
{
    static const char *const words[] = {"v",        "vt",   "vn",     "vp",     "cstype",     "deg",       "bmat",
                                        "step",     "p",    "l",      "f",      "fo",         "curv",      "curv2",
                                        "surf",     "parm", "trim",   "hole",   "scrv",       "sp",        "end",
                                        "con",      "g",    "s",      "mg",     "o",          "bevel",     "c_interp",
                                        "d_interp", "lod",  "usemtl", "mtllib", "shadow_obj", "trace_obj", "ctech",
                                        "stech",    "call", "csh",    "maplib", "usemap",     "res"};
    for (size_t i = 0; i < sizeof words / sizeof words[0]; i++)
        if (tok_is(kw, words[i]))
            return true;
    return false;
}

/* surf / curv2 / curv: opens an element. */
static tsr_status begin_element(lexer *L, obj_state *o, const token *kw, int kind)
{
    element *e = &o->el;
    if (e->kind != EL_NONE)
        return fail(L, L->stmt_line, TSR_ERR_FORMAT, "%.*s inside the %s begun at line %u (missing end)", (int)kw->n,
                    kw->s, e->keyword, e->line);
    e->kind = kind;
    e->line = L->stmt_line;
    e->keyword = kind == EL_SURF ? "surf" : kind == EL_CURV2 ? "curv2" : "curv";
    e->refs.n = e->parm[0].n = e->parm[1].n = 0;
    e->has_parm[0] = e->has_parm[1] = false;
    e->type = o->type, e->rational = o->rational, e->type_line = o->type_line;
    e->du = o->du, e->dv = o->dv;
    if (kind == EL_SKIP) {
        skipped(o->b, L->stmt_line);
        if (o->b->unused++ == 0)
            o->b->first_unused = L->stmt_line;
        skip_statement(L);
        return TSR_OK;
    }
    if (o->type == CS_NONE)
        return fail(L, e->line, TSR_ERR_FORMAT, "%s before any cstype", e->keyword);
    if (o->type == CS_OTHER)
        return fail(L, e->line, TSR_ERR_UNSUPPORTED,
                    "%s: the cstype of line %u is not supported (only bezier and bspline are)", e->keyword,
                    o->type_line);
    if (o->du == 0 || (kind == EL_SURF && o->dv == 0))
        return fail(L, e->line, TSR_ERR_FORMAT, "%s needs %s before it", e->keyword,
                    kind == EL_SURF ? "'deg du dv'" : "'deg du'");
    token t;
    tsr_status s;
    if (kind == EL_SURF) {
        for (int i = 0; i < 4; i++) {
            if (!next_token(L, &t))
                return fail(L, e->line, TSR_ERR_FORMAT, "surf needs s0 s1 t0 t1 and its control vertices");
            if ((s = parse_number(L, &t, "surf parameter", &e->range[i])) != TSR_OK)
                return s;
        }
        if (!(e->range[0] < e->range[1]) || !(e->range[2] < e->range[3]))
            return fail(L, e->line, TSR_ERR_VALUE, "surf range [%g, %g] x [%g, %g] is empty or inverted", e->range[0],
                        e->range[1], e->range[2], e->range[3]);
    }
    uint32_t have = (uint32_t)(kind == EL_SURF ? o->v.n / 4 : o->vp.n / 3);
    while (next_token(L, &t)) {
        uint32_t idx;
        if ((s = parse_ref(L, &t, kind == EL_SURF ? "control vertex" : "parameter vertex", have, &idx, NULL)) != TSR_OK)
            return s;
        if (!push_u32(o->b->a, &e->refs, idx))
            return nomem(L);
    }
    return TSR_OK;
}

static tsr_status obj_parm(lexer *L, obj_state *o)
{
    element *e = &o->el;
    token t;
    if (e->kind == EL_NONE)
        return fail(L, L->stmt_line, TSR_ERR_FORMAT, "parm outside a surf or curv2 element");
    if (e->kind == EL_SKIP) {
        skip_statement(L);
        return TSR_OK;
    }
    if (!next_token(L, &t) || !(tok_is(&t, "u") || tok_is(&t, "v")))
        return fail(L, L->stmt_line, TSR_ERR_FORMAT, "parm needs a direction, u or v");
    int axis = tok_is(&t, "v");
    if (axis && e->kind == EL_CURV2)
        return fail(L, L->stmt_line, TSR_ERR_FORMAT, "parm v in a curv2 (curves have u only)");
    if (e->has_parm[axis])
        return fail(L, L->stmt_line, TSR_ERR_FORMAT, "a second parm %s for the %s of line %u", axis ? "v" : "u",
                    e->keyword, e->line);
    e->has_parm[axis] = true;
    vec *pv = &e->parm[axis];
    tsr_status s;
    while (next_token(L, &t)) {
        double x;
        if ((s = parse_number(L, &t, "parameter value", &x)) != TSR_OK)
            return s;
        if (pv->n > 0) {
            double prev = F64(*pv)[pv->n - 1];
            if (x < prev || (e->type == CS_BEZIER && x == prev))
                return fail(L, t.line, TSR_ERR_VALUE, "parm %s value %g after %g: values must %s", axis ? "v" : "u", x,
                            prev, e->type == CS_BEZIER ? "increase" : "not decrease");
        }
        if (!push_f64(o->b->a, pv, x))
            return nomem(L);
    }
    if (pv->n == 0)
        return fail(L, L->stmt_line, TSR_ERR_FORMAT, "parm %s without values", axis ? "v" : "u");
    /* an interior knot repeated beyond degree + 1 leaves the basis a gap
     * (runs at the ends are the control point count's business) */
    int deg = e->kind == EL_SURF && axis ? e->dv : e->du;
    const double *k = F64(*pv);
    for (size_t i = 0, j; e->type == CS_BSPLINE && deg > 0 && i < pv->n; i = j) {
        for (j = i + 1; j < pv->n && k[j] == k[i]; j++)
            ;
        if (i > 0 && j < pv->n && j - i > (size_t)deg + 1)
            return fail(L, L->stmt_line, TSR_ERR_VALUE,
                        "parm %s: knot %g appears %zu times, more than degree + 1 (%d): the basis has a gap there",
                        axis ? "v" : "u", k[i], j - i, deg + 1);
    }
    return TSR_OK;
}

/* A loop's segments put end to start where the file lists them out of
 * order or some of them backwards (a CAD exporter's loop given as a set
 * of edges): from the first, each next segment is the only one left with
 * an end within 1e-6 of the loop's extent of where the chain has got to
 * (turned when that is its end). Left as listed when they already meet in
 * order, or when some step finds no such segment or more than one (then
 * straight edges join them, as tsr_trim_loop_sample says). True when
 * reordered. No allocation: at most 64 segments are looked at. */
#define CHAIN_MAX 64u
static bool chain_segments(const builder *b, tsr_trim_segment *g, uint32_t n)
{
    if (n < 2 || n > CHAIN_MAX)
        return false;
    double ends[CHAIN_MAX][2][2], lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (uint32_t i = 0; i < n; i++) {
        tsr_curve2 c = view_curve(b, &((const curve_rec *)b->curves.data)[g[i].curve]);
        if (tsr_curve2_eval(&c, g[i].t0, ends[i][0], NULL) != TSR_OK ||
            tsr_curve2_eval(&c, g[i].t1, ends[i][1], NULL) != TSR_OK)
            return false;
        for (int e = 0; e < 2; e++)
            for (int k = 0; k < 2; k++) {
                lo[k] = fmin(lo[k], ends[i][e][k]);
                hi[k] = fmax(hi[k], ends[i][e][k]);
            }
    }
    double tol = 1e-6 * fmax(hi[0] - lo[0], hi[1] - lo[1]);
#define NEAR(p, q) (fabs((p)[0] - (q)[0]) <= tol && fabs((p)[1] - (q)[1]) <= tol)
    bool in_order = true;
    for (uint32_t i = 0; i + 1 < n && in_order; i++)
        in_order = NEAR(ends[i][1], ends[i + 1][0]);
    if (in_order || !(tol > 0))
        return false;
    uint32_t order[CHAIN_MAX];
    bool turned[CHAIN_MAX] = {false}, used[CHAIN_MAX] = {false};
    order[0] = 0;
    used[0] = true;
    const double *at = ends[0][1];
    for (uint32_t k = 1; k < n; k++) {
        uint32_t found = 0, pick = 0;
        bool turn = false;
        for (uint32_t j = 0; j < n; j++)
            for (int e = 0; e < 2 && !used[j]; e++)
                if (NEAR(ends[j][e], at)) {
                    found++;
                    pick = j;
                    turn = e == 1;
                }
        if (found != 1)
            return false;
        order[k] = pick;
        turned[pick] = turn;
        used[pick] = true;
        at = ends[pick][turn ? 0 : 1];
    }
#undef NEAR
    tsr_trim_segment copy[CHAIN_MAX];
    memcpy(copy, g, n * sizeof *g);
    for (uint32_t k = 0; k < n; k++) {
        g[k] = copy[order[k]];
        if (turned[order[k]]) {
            double t = g[k].t0;
            g[k].t0 = g[k].t1;
            g[k].t1 = t;
        }
    }
    return true;
}

/* trim / hole u0 u1 curv2 ... inside a surf: one loop. */
static tsr_status obj_loop(lexer *L, obj_state *o, bool hole)
{
    element *e = &o->el;
    builder *b = o->b;
    const char *kw = hole ? "hole" : "trim";
    if (e->kind != EL_SURF)
        return fail(L, L->stmt_line, TSR_ERR_FORMAT, "%s outside a surf element", kw);
    tsr_trim_loop loop = {(uint32_t)b->patches.n, hole, (uint32_t)b->segments.n, 0, L->stmt_line, false};
    token t;
    tsr_status s;
    for (;;) {
        double t01[2];
        uint32_t got = 0;
        while (got < 2 && next_token(L, &t)) {
            if ((s = parse_number(L, &t, "curve parameter", &t01[got])) != TSR_OK)
                return s;
            got++;
        }
        if (got == 0 && loop.num_segments > 0)
            break;
        uint32_t c;
        if (got < 2 || !next_token(L, &t))
            return fail(L, L->stmt_line, TSR_ERR_FORMAT, "%s expects triples u0 u1 curv2", kw);
        if ((s = parse_ref(L, &t, "curv2", (uint32_t)b->curves.n, &c, NULL)) != TSR_OK)
            return s;
        tsr_curve2 cv = view_curve(b, &((const curve_rec *)b->curves.data)[c]);
        double lo = cv.knots[cv.degree], hi = cv.knots[cv.count];
        for (int k = 0; k < 2; k++)
            if (t01[k] < lo || t01[k] > hi)
                return fail(L, t.line, TSR_ERR_VALUE, "%s: parameter %g is outside curv2 %u's range [%g, %g]", kw,
                            t01[k], c + 1, lo, hi);
        tsr_trim_segment g = {c, t01[0], t01[1]};
        if (!push_any(b->a, &b->segments, sizeof g, &g))
            return nomem(L);
        loop.num_segments++;
    }
    loop.reordered = chain_segments(b, (tsr_trim_segment *)b->segments.data + loop.first_segment, loop.num_segments);
    if (!push_any(b->a, &b->loops, sizeof loop, &loop))
        return nomem(L);
    return TSR_OK;
}

static tsr_status obj_statement(lexer *L, obj_state *o)
{
    token kw = {NULL, 0, 0};
    if (!next_token(L, &kw))
        return TSR_OK;
    tsr_status s = check_keyword(L, &kw, "an OBJ");
    if (s != TSR_OK)
        return s;
    builder *b = o->b;
    double x[8];
    uint32_t n;
    if (tok_is(&kw, "v")) {
        if ((s = read_numbers(L, "coordinate", x, 8, &n)) != TSR_OK)
            return s;
        if (n != 3 && n != 4 && n != 6)
            return fail(L, L->stmt_line, TSR_ERR_FORMAT,
                        "expected 3 coordinates and an optional weight, found %u values", n);
        double w[4] = {x[0], x[1], x[2], n == 4 ? x[3] : 1.0};
        if (!vec_reserve(b->a, &o->v, sizeof(double), 4))
            return nomem(L);
        memcpy(F64(o->v) + o->v.n, w, sizeof w);
        o->v.n += 4;
        if (o->v.n / 4 > UINT32_MAX - 1)
            return fail(L, L->stmt_line, TSR_ERR_TOO_LARGE, "too many vertices");
    } else if (tok_is(&kw, "vp")) {
        if ((s = read_numbers(L, "parameter", x, 3, &n)) != TSR_OK)
            return s;
        if (n < 1 || n > 3)
            return fail(L, L->stmt_line, TSR_ERR_FORMAT, "expected 1 to 3 values (u [v [w]]), found %u", n);
        double p[3] = {x[0], n > 1 ? x[1] : 0.0, n > 2 ? x[2] : 1.0};
        if (!vec_reserve(b->a, &o->vp, sizeof(double), 3))
            return nomem(L);
        memcpy(F64(o->vp) + o->vp.n, p, sizeof p);
        o->vp.n += 3;
        if (o->vp.n / 3 > UINT32_MAX - 1)
            return fail(L, L->stmt_line, TSR_ERR_TOO_LARGE, "too many parameter vertices");
    } else if (tok_is(&kw, "vt") || tok_is(&kw, "vn")) {
        skip_statement(L);
    } else if (tok_is(&kw, "cstype")) {
        token t = {NULL, 0, 0};
        bool rat = false, have = next_token(L, &t);
        if (have && tok_is(&t, "rat")) {
            rat = true;
            have = next_token(L, &t);
        }
        if (!have)
            return fail(L, L->stmt_line, TSR_ERR_FORMAT, "cstype needs a type (bezier or bspline)");
        int type = tok_is(&t, "bezier")                                                      ? CS_BEZIER
                   : tok_is(&t, "bspline")                                                   ? CS_BSPLINE
                   : tok_is(&t, "bmatrix") || tok_is(&t, "cardinal") || tok_is(&t, "taylor") ? CS_OTHER
                                                                                             : CS_NONE;
        char sb[128];
        if (type == CS_NONE)
            return fail(L, L->stmt_line, TSR_ERR_FORMAT,
                        "cstype '%s' is not bezier, bspline, bmatrix, cardinal or taylor", shown(&t, sb, sizeof sb));
        if (count_rest(L))
            return fail(L, L->stmt_line, TSR_ERR_FORMAT, "unexpected values after cstype");
        o->type = type, o->rational = rat, o->type_line = L->stmt_line;
    } else if (tok_is(&kw, "deg")) {
        token t;
        uint32_t d[2] = {0, 0}, got = 0;
        while (next_token(L, &t)) {
            if (got < 2 && (s = parse_u32(L, &t, "degree", &d[got])) != TSR_OK)
                return s;
            got++;
        }
        if (got < 1 || got > 2)
            return fail(L, L->stmt_line, TSR_ERR_FORMAT, "deg expects 1 or 2 degrees, found %u", got);
        for (uint32_t k = 0; k < got; k++) {
            if (d[k] == 0)
                return fail(L, L->stmt_line, TSR_ERR_VALUE, "degree 0 (degrees are 1..%d)", TSR_PATCH_MAX_DEGREE);
            if (d[k] > TSR_PATCH_MAX_DEGREE)
                return fail(L, L->stmt_line, TSR_ERR_UNSUPPORTED, "degree %u is beyond the supported 1..%d", d[k],
                            TSR_PATCH_MAX_DEGREE);
        }
        o->du = (int)d[0], o->dv = (int)d[1];
    } else if (tok_is(&kw, "surf")) {
        return begin_element(L, o, &kw, EL_SURF);
    } else if (tok_is(&kw, "curv2")) {
        return begin_element(L, o, &kw, EL_CURV2);
    } else if (tok_is(&kw, "curv")) {
        return begin_element(L, o, &kw, EL_SKIP);
    } else if (tok_is(&kw, "parm")) {
        return obj_parm(L, o);
    } else if (tok_is(&kw, "trim") || tok_is(&kw, "hole")) {
        if (o->el.kind == EL_SKIP) {
            skip_statement(L);
            return TSR_OK;
        }
        return obj_loop(L, o, tok_is(&kw, "hole"));
    } else if (tok_is(&kw, "end")) {
        if (count_rest(L))
            return fail(L, L->stmt_line, TSR_ERR_FORMAT, "unexpected values after end");
        int kind = o->el.kind;
        if (kind == EL_NONE)
            return fail(L, L->stmt_line, TSR_ERR_FORMAT, "end without a surf or curv2 before it");
        s = kind == EL_SURF ? finish_surf(L, o) : kind == EL_CURV2 ? finish_curv2(L, o) : TSR_OK;
        o->el.kind = EL_NONE;
        return s;
    } else {
        /* scrv, sp, con, bmat, step, polygons, groups, display attributes,
         * anything else: read past */
        skipped(b, L->stmt_line);
        if ((tok_is(&kw, "f") || tok_is(&kw, "fo") || tok_is(&kw, "l") || tok_is(&kw, "p")) && b->polygons++ == 0)
            b->first_polygon = L->stmt_line;
        if ((tok_is(&kw, "scrv") || tok_is(&kw, "sp") || tok_is(&kw, "con")) && b->unused++ == 0)
            b->first_unused = L->stmt_line;
        if (!obj_keyword(&kw) && b->unknown++ == 0) {
            b->first_unknown_line = L->stmt_line;
            shown(&kw, b->first_unknown, sizeof b->first_unknown);
        }
        skip_statement(L);
    }
    return TSR_OK;
}

static tsr_status parse_obj(lexer *L, builder *b)
{
    obj_state o;
    memset(&o, 0, sizeof o);
    o.b = b;
    tsr_status s = TSR_OK;
    while (s == TSR_OK && next_statement(L))
        s = obj_statement(L, &o);
    if (s == TSR_OK && o.el.kind != EL_NONE)
        s = fail(L, o.el.line, TSR_ERR_TRUNCATED, "the %s begun here has no end", o.el.keyword);
    if (s == TSR_OK && b->patches.n == 0)
        s = fail(L, 0, TSR_ERR_EMPTY, "no free-form surface (surf) in the file");
    obj_state_free(&o);
    return s;
}

/* ---- Patch set entry points ------------------------------------------------------- */

tsr_patch_format tsr_patch_format_from_path(const char *path)
{
    if (!path)
        return TSR_PATCH_FORMAT_UNKNOWN;
    const char *slash = strrchr(path, '/'), *dot = strrchr(path, '.');
    if (!dot || (slash && dot < slash))
        return TSR_PATCH_FORMAT_UNKNOWN;
    size_t n = strlen(dot);
    if (n == 4 && lower_eq(dot, ".bpt", 4))
        return TSR_PATCH_FORMAT_BPT;
    if (n == 4 && lower_eq(dot, ".obj", 4))
        return TSR_PATCH_FORMAT_OBJ;
    return TSR_PATCH_FORMAT_UNKNOWN;
}

/* Past a UTF-8 byte order mark (editors on Windows write one). */
static const char *skip_bom(const void *data, size_t size)
{
    const unsigned char *d = data;
    return (const char *)(size >= 3 && d[0] == 0xEF && d[1] == 0xBB && d[2] == 0xBF ? d + 3 : d);
}

tsr_status tsr_patch_set_parse(const void *data, size_t size, const char *name, tsr_patch_format f,
                               const tsr_allocator *alloc, tsr_patch_set *out, tsr_error *err)
{
    if (!name)
        name = "<memory>";
    if (!out)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: no set to load into", name);
    memset(out, 0, sizeof *out);
    if (f != TSR_PATCH_FORMAT_BPT && f != TSR_PATCH_FORMAT_OBJ)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: unknown patch format (use .bpt or .obj)", name);
    if (!data && size)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: no data", name);
    if (size == 0)
        return tsr_error_set(err, TSR_ERR_EMPTY, "%s: empty file (0 bytes)", name);
    lexer L = {name, skip_bom(data, size), (const char *)data + size, 1, 1, err};
    builder b;
    memset(&b, 0, sizeof b);
    b.a = alloc;
    tsr_status s = f == TSR_PATCH_FORMAT_BPT ? parse_bpt(&L, &b) : parse_obj(&L, &b);
    if (s == TSR_OK)
        s = finish_set(&b, &L, out);
    builder_free(&b);
    return s;
}

tsr_status tsr_patch_set_load(const char *path, tsr_patch_format f, const tsr_allocator *alloc, tsr_patch_set *out,
                              tsr_error *err)
{
    if (out)
        memset(out, 0, sizeof *out);
    if (f == TSR_PATCH_FORMAT_UNKNOWN)
        f = tsr_patch_format_from_path(path);
    if (f == TSR_PATCH_FORMAT_UNKNOWN)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: unknown patch format (use .bpt or .obj)",
                             path ? path : "(null)");
    char *buf;
    size_t len;
    tsr_status s = tsr_read_file(path, TSR_PATCH_MAX_FILE_BYTES, alloc, &buf, &len, err);
    if (s != TSR_OK)
        return s;
    s = tsr_patch_set_parse(buf, len, path, f, alloc, out, err);
    tsr_free(alloc, buf);
    return s;
}

/* ---- Cages -------------------------------------------------------------------------- */

typedef struct cage_build {
    const tsr_allocator *a;
    vec points, uvs;                            /* double */
    vec face_sizes, face_verts, face_uvs;       /* uint32 */
    vec crease_verts, corner_verts, hole_faces; /* uint32 */
    vec crease_sharp, corner_sharp;             /* float */
    vec ints;                                   /* uint32 scratch */
    vec floats;                                 /* float scratch */
    bool all_uvs;
} cage_build;

static void cage_build_free(cage_build *c)
{
    vec *all[] = {&c->points,       &c->uvs,        &c->face_sizes,   &c->face_verts,   &c->face_uvs, &c->crease_verts,
                  &c->corner_verts, &c->hole_faces, &c->crease_sharp, &c->corner_sharp, &c->ints,     &c->floats};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
        vec_free(c->a, all[i]);
}

static tsr_status cage_face(lexer *L, cage_build *c)
{
    token t;
    uint32_t n = 0, np = (uint32_t)(c->points.n / 3), nt = (uint32_t)(c->uvs.n / 2);
    tsr_status s;
    while (next_token(L, &t)) {
        uint32_t v;
        int64_t vt;
        if ((s = parse_ref(L, &t, "face vertex", np, &v, &vt)) != TSR_OK)
            return s;
        uint32_t uv = UINT32_MAX;
        if (vt != 0) {
            int64_t a = vt > 0 ? vt - 1 : (int64_t)nt + vt;
            if (a < 0 || a >= (int64_t)nt)
                return fail(L, t.line, TSR_ERR_VALUE, "texture vertex %lld is not defined (%u so far)", (long long)vt,
                            nt);
            uv = (uint32_t)a;
        } else {
            c->all_uvs = false;
        }
        if (!push_u32(c->a, &c->face_verts, v) || !push_u32(c->a, &c->face_uvs, uv))
            return nomem(L);
        n++;
    }
    if (n < 3)
        return fail(L, L->stmt_line, TSR_ERR_FORMAT, "a face needs at least 3 vertices, found %u", n);
    if (c->face_sizes.n >= UINT32_MAX - 1 || c->face_verts.n >= UINT32_MAX - 1)
        return fail(L, L->stmt_line, TSR_ERR_TOO_LARGE, "too many faces");
    if (!push_u32(c->a, &c->face_sizes, n))
        return nomem(L);
    return TSR_OK;
}

/* A sharpness: finite, >= 0, representable as a float. */
static tsr_status sharpness(const lexer *L, const token *t, float *out)
{
    double x;
    tsr_status s = parse_number(L, t, "sharpness", &x);
    if (s != TSR_OK)
        return s;
    if (x < 0 || x > FLT_MAX)
        return fail(L, t->line, TSR_ERR_VALUE, "sharpness %g is outside 0..%g", x, (double)FLT_MAX);
    *out = (float)x;
    return TSR_OK;
}

static tsr_status cage_tag(lexer *L, cage_build *c, tsr_cage *out)
{
    token name, t;
    char sb[128];
    if (!next_token(L, &name))
        return fail(L, L->stmt_line, TSR_ERR_FORMAT, "a tag needs a name");
    enum {
        CREASE,
        CORNER,
        HOLE,
        INTERP,
        FVAR,
        CREASEMETHOD,
        SMOOTHTRI,
        OTHER
    } kind = tok_is(&name, "crease")                           ? CREASE
             : tok_is(&name, "corner")                         ? CORNER
             : tok_is(&name, "hole")                           ? HOLE
             : tok_is(&name, "interpolateboundary")            ? INTERP
             : tok_is(&name, "facevaryinginterpolateboundary") ? FVAR
             : tok_is(&name, "creasemethod")                   ? CREASEMETHOD
             : tok_is(&name, "smoothtriangles")                ? SMOOTHTRI
                                                               : OTHER;
    if (kind == OTHER) {
        if (out->num_skipped_tags++ == 0)
            out->first_skipped_tag_line = L->stmt_line;
        skip_statement(L);
        return TSR_OK;
    }
    /* nints/nfloats/nstrings */
    if (!next_token(L, &t))
        return fail(L, L->stmt_line, TSR_ERR_FORMAT, "tag %.*s needs its counts nints/nfloats/nstrings", (int)name.n,
                    name.s);
    uint32_t cnt[3];
    size_t pos = 0;
    for (int k = 0; k < 3; k++) {
        size_t start = pos;
        while (pos < t.n && t.s[pos] != '/')
            pos++;
        token part = {t.s + start, pos - start, t.line};
        if ((k < 2 && pos >= t.n) || (k == 2 && pos != t.n))
            return fail(L, t.line, TSR_ERR_FORMAT, "tag counts '%s' are not nints/nfloats/nstrings",
                        shown(&t, sb, sizeof sb));
        tsr_status s = parse_u32(L, &part, "tag count", &cnt[k]);
        if (s != TSR_OK)
            return s;
        pos++;
    }
    uint64_t want = (uint64_t)cnt[0] + cnt[1] + cnt[2];
    uint64_t left = (uint64_t)(L->end - L->p);
    if (want > left / 2 + 1)
        return fail(L, L->stmt_line, TSR_ERR_TOO_LARGE,
                    "tag %.*s announces %llu values, more than the %llu bytes left can hold", (int)name.n, name.s,
                    (unsigned long long)want, (unsigned long long)left);
    c->ints.n = c->floats.n = 0;
    uint32_t np = (uint32_t)(c->points.n / 3), nf = (uint32_t)c->face_sizes.n;
    uint64_t got = 0;
    tsr_status s;
    int str_value = -1;
    while (next_token(L, &t)) {
        if (got >= want)
            return fail(L, t.line, TSR_ERR_FORMAT, "tag %.*s has more values than its counts %u/%u/%u", (int)name.n,
                        name.s, cnt[0], cnt[1], cnt[2]);
        if (got < cnt[0]) {
            uint32_t x;
            if ((s = parse_u32(L, &t, "tag integer", &x)) != TSR_OK)
                return s;
            uint32_t limit = kind == HOLE ? nf : np;
            if ((kind == HOLE || kind == CREASE || kind == CORNER) && x >= limit)
                return fail(L, t.line, TSR_ERR_VALUE, "%s %u is not defined (%u so far)",
                            kind == HOLE     ? "hole face"
                            : kind == CREASE ? "crease vertex"
                                             : "corner vertex",
                            x, limit);
            if (!push_u32(c->a, &c->ints, x))
                return nomem(L);
        } else if (got < (uint64_t)cnt[0] + cnt[1]) {
            float x = 0;
            if (kind == CREASE || kind == CORNER) {
                if ((s = sharpness(L, &t, &x)) != TSR_OK)
                    return s;
            } else {
                double d;
                if ((s = parse_number(L, &t, "tag value", &d)) != TSR_OK)
                    return s;
                x = (float)d;
            }
            if (!push_f32(c->a, &c->floats, x))
                return nomem(L);
        } else if (got == (uint64_t)cnt[0] + cnt[1]) { /* the first string */
            if (kind == CREASEMETHOD)
                str_value = tok_is(&t, "normal") ? 0 : tok_is(&t, "chaikin") ? 1 : -2;
            if (kind == SMOOTHTRI)
                str_value = tok_is(&t, "catmark") ? 0 : tok_is(&t, "smooth") ? 1 : -2;
            if (str_value == -2)
                return fail(L, t.line, TSR_ERR_VALUE, "tag %.*s: unknown value '%s'", (int)name.n, name.s,
                            shown(&t, sb, sizeof sb));
        }
        got++;
    }
    if (got < want)
        return fail(L, L->stmt_line, TSR_ERR_FORMAT, "tag %.*s expects %llu values after %u/%u/%u, found %llu",
                    (int)name.n, name.s, (unsigned long long)want, cnt[0], cnt[1], cnt[2], (unsigned long long)got);
    const uint32_t *I = U32(c->ints);
    const float *F = c->floats.data;
    uint32_t ni = cnt[0], nfl = cnt[1];
    switch (kind) {
    case CREASE:
        if (ni == 0 || ni % 2 || (nfl != 1 && nfl != ni / 2))
            return fail(L, L->stmt_line, TSR_ERR_FORMAT,
                        "crease expects vertex pairs and 1 sharpness or one per pair, found %u/%u", ni, nfl);
        for (uint32_t k = 0; k < ni / 2; k++)
            if (!push_u32(c->a, &c->crease_verts, I[2 * k]) || !push_u32(c->a, &c->crease_verts, I[2 * k + 1]) ||
                !push_f32(c->a, &c->crease_sharp, F[nfl == 1 ? 0 : k]))
                return nomem(L);
        break;
    case CORNER:
        if (ni == 0 || (nfl != 1 && nfl != ni))
            return fail(L, L->stmt_line, TSR_ERR_FORMAT,
                        "corner expects vertices and 1 sharpness or one each, found %u/%u", ni, nfl);
        for (uint32_t k = 0; k < ni; k++)
            if (!push_u32(c->a, &c->corner_verts, I[k]) || !push_f32(c->a, &c->corner_sharp, F[nfl == 1 ? 0 : k]))
                return nomem(L);
        break;
    case HOLE:
        for (uint32_t k = 0; k < ni; k++)
            if (!push_u32(c->a, &c->hole_faces, I[k]))
                return nomem(L);
        break;
    case INTERP:
    case FVAR:
        if (ni != 1)
            return fail(L, L->stmt_line, TSR_ERR_FORMAT, "%.*s expects 1 integer, found %u", (int)name.n, name.s, ni);
        if (kind == INTERP) {
            if (I[0] > 2)
                return fail(L, L->stmt_line, TSR_ERR_VALUE, "interpolateboundary %u is not 0, 1 or 2", I[0]);
            static const int map[3] = {0, 2, 1}; /* RenderMan's numbers to Sdc's */
            out->boundary_interp = map[I[0]];
        } else {
            if (I[0] > 5)
                return fail(L, L->stmt_line, TSR_ERR_VALUE, "facevaryinginterpolateboundary %u is not 0..5", I[0]);
            out->fvar_interp = (int)I[0];
        }
        break;
    case CREASEMETHOD:
    case SMOOTHTRI:
        if (cnt[2] < 1)
            return fail(L, L->stmt_line, TSR_ERR_FORMAT, "%.*s expects a string", (int)name.n, name.s);
        if (kind == CREASEMETHOD)
            out->crease_method = str_value;
        else
            out->triangle_subdiv = str_value;
        break;
    default:
        break;
    }
    return TSR_OK;
}

static tsr_status cage_statement(lexer *L, cage_build *c, tsr_cage *out)
{
    token kw = {NULL, 0, 0};
    if (!next_token(L, &kw))
        return TSR_OK;
    tsr_status s = check_keyword(L, &kw, "an OBJ");
    if (s != TSR_OK)
        return s;
    double x[8];
    uint32_t n;
    if (tok_is(&kw, "v")) {
        if ((s = read_numbers(L, "coordinate", x, 8, &n)) != TSR_OK)
            return s;
        if (n != 3 && n != 4 && n != 6 && n != 7)
            return fail(L, L->stmt_line, TSR_ERR_FORMAT, "expected 3 coordinates, found %u values", n);
        if (c->points.n / 3 >= UINT32_MAX - 1)
            return fail(L, L->stmt_line, TSR_ERR_TOO_LARGE, "too many vertices");
        for (int k = 0; k < 3; k++)
            if (!push_f64(c->a, &c->points, x[k]))
                return nomem(L);
    } else if (tok_is(&kw, "vt")) {
        if ((s = read_numbers(L, "texture coordinate", x, 3, &n)) != TSR_OK)
            return s;
        if (n < 1 || n > 3)
            return fail(L, L->stmt_line, TSR_ERR_FORMAT, "expected 1 to 3 texture coordinates, found %u", n);
        if (c->uvs.n / 2 >= UINT32_MAX - 1)
            return fail(L, L->stmt_line, TSR_ERR_TOO_LARGE, "too many texture vertices");
        if (!push_f64(c->a, &c->uvs, x[0]) || !push_f64(c->a, &c->uvs, n > 1 ? x[1] : 0.0))
            return nomem(L);
    } else if (tok_is(&kw, "f")) {
        return cage_face(L, c);
    } else if (tok_is(&kw, "t")) {
        return cage_tag(L, c, out);
    } else {
        skip_statement(L); /* vn, g, s, o, usemtl, mtllib, l, p, ... */
    }
    return TSR_OK;
}

typedef struct cage_edge {
    uint32_t lo, hi, face;
    bool forward; /* the face runs it lo -> hi */
} cage_edge;

static int cmp_cage_edge(const void *x, const void *y)
{
    const cage_edge *a = x, *b = y;
    if (a->lo != b->lo)
        return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi)
        return a->hi < b->hi ? -1 : 1;
    return a->face < b->face ? -1 : a->face > b->face;
}

/* The direction from edge (a, b) into face f: its centroid's offset from
 * the edge's line, across the edge. */
static void face_side(const tsr_cage *c, const uint32_t *first, uint32_t f, uint32_t a, uint32_t b, double out[3])
{
    const double *A = c->points + 3 * (size_t)a, *B = c->points + 3 * (size_t)b;
    double cen[3] = {0, 0, 0}, d[3], dd = 0, t = 0;
    uint32_t n = c->face_sizes[f];
    for (uint32_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            cen[k] += c->points[3 * (size_t)c->face_verts[first[f] + i] + k] / n;
    for (int k = 0; k < 3; k++) {
        d[k] = B[k] - A[k];
        dd += d[k] * d[k];
        t += d[k] * (cen[k] - A[k]);
    }
    t = dd > 0 ? t / dd : 0;
    for (int k = 0; k < 3; k++)
        out[k] = cen[k] - A[k] - t * d[k];
}

tsr_status tsr_cage_orient(tsr_cage *c, bool apply, uint32_t *reversed, uint32_t *first_rev, uint32_t *unorientable)
{
    if (reversed)
        *reversed = 0;
    if (first_rev)
        *first_rev = UINT32_MAX;
    if (unorientable)
        *unorientable = 0;
    if (!c || c->num_faces == 0)
        return TSR_OK;
    uint32_t nf = c->num_faces, nc = c->num_face_verts;
    const tsr_allocator *a = c->alloc.realloc ? &c->alloc : NULL;
    cage_edge *e = tsr_alloc(a, (size_t)nc * sizeof *e);
    uint32_t *first = tsr_alloc(a, ((size_t)nf + 1) * sizeof *first);
    /* adjacency through manifold edges: (neighbour, same) pairs per face */
    uint32_t *adj_n = tsr_alloc(a, (size_t)nc * 2 * sizeof *adj_n), *deg = tsr_alloc(a, ((size_t)nf + 1) * sizeof *deg);
    uint32_t *part = tsr_alloc(a, (size_t)nf * sizeof *part), *queue = tsr_alloc(a, (size_t)nf * sizeof *queue);
    uint8_t *flip = tsr_alloc(a, (size_t)nf), *bad_part = tsr_alloc(a, (size_t)nf);
    tsr_status st = e && first && adj_n && deg && part && queue && flip && bad_part ? TSR_OK : TSR_ERR_NOMEM;
    uint32_t ne = 0;
    if (st == TSR_OK) {
        uint32_t k = 0;
        for (uint32_t f = 0; f < nf; f++) {
            first[f] = k;
            uint32_t n = c->face_sizes[f];
            for (uint32_t i = 0; i < n; i++) {
                uint32_t u = c->face_verts[k + i], v = c->face_verts[k + (i + 1) % n];
                if (u != v)
                    e[ne++] = (cage_edge){u < v ? u : v, u < v ? v : u, f, u < v};
            }
            k += n;
        }
        first[nf] = k;
        qsort(e, ne, sizeof *e, cmp_cage_edge);
        memset(deg, 0, ((size_t)nf + 1) * sizeof *deg);
        /* count, then fill: each manifold edge (two uses, two faces) links
         * its faces; same direction means one of them must turn */
        for (int pass = 0; pass < 2; pass++) {
            if (pass == 1) {
                uint32_t sum = 0;
                for (uint32_t f = 0; f <= nf; f++) {
                    uint32_t d = deg[f];
                    deg[f] = sum;
                    sum += d;
                }
            }
            for (uint32_t i = 0; i < ne;) {
                uint32_t j = i;
                while (j < ne && e[j].lo == e[i].lo && e[j].hi == e[i].hi)
                    j++;
                uint32_t f = e[i].face, g = j - i == 2 ? e[i + 1].face : f, same = 0;
                if (f != g && e[i].forward == e[i + 1].forward) {
                    /* run the same way: a face listed backwards, unless
                     * the two fold onto each other (less than 60 degrees
                     * apart about the edge, overlapping): that edge is
                     * read as OpenSubdiv reads it, a seam */
                    double sd[2][3], dot = 0, l0 = 0, l1 = 0;
                    for (int q = 0; q < 2; q++)
                        face_side(c, first, q ? g : f, e[i].lo, e[i].hi, sd[q]);
                    for (int k = 0; k < 3; k++) {
                        dot += sd[0][k] * sd[1][k];
                        l0 += sd[0][k] * sd[0][k];
                        l1 += sd[1][k] * sd[1][k];
                    }
                    same = dot > 0.5 * sqrt(l0 * l1) ? 2 : 1;
                }
                if (f != g && same != 2) {
                    if (pass == 0) {
                        deg[f]++;
                        deg[g]++;
                    } else {
                        adj_n[2 * deg[f]] = g;
                        adj_n[2 * deg[f]++ + 1] = same;
                        adj_n[2 * deg[g]] = f;
                        adj_n[2 * deg[g]++ + 1] = same;
                    }
                }
                i = j;
            }
        }
        /* deg[f] is now the end of f's list; its start is deg[f - 1] */
        for (uint32_t f = 0; f < nf; f++)
            part[f] = UINT32_MAX;
        memset(bad_part, 0, nf);
        uint32_t nparts = 0;
        for (uint32_t s = 0; s < nf; s++) {
            if (part[s] != UINT32_MAX)
                continue;
            uint32_t head = 0, tail = 0, flips = 0, size = 0;
            part[s] = nparts;
            flip[s] = 0;
            queue[tail++] = s;
            while (head < tail) {
                uint32_t f = queue[head++];
                size++;
                flips += flip[f];
                for (uint32_t q = f ? deg[f - 1] : 0; q < deg[f]; q++) {
                    uint32_t g = adj_n[2 * q];
                    uint8_t want = (uint8_t)(flip[f] ^ adj_n[2 * q + 1]);
                    if (part[g] == UINT32_MAX) {
                        part[g] = nparts;
                        flip[g] = want;
                        queue[tail++] = g;
                    } else if (flip[g] != want) {
                        bad_part[nparts] = 1;
                    }
                }
            }
            /* the majority keeps its orientation */
            if (2 * flips > size)
                for (uint32_t q = 0; q < tail; q++)
                    flip[queue[q]] ^= 1;
            nparts++;
        }
        for (uint32_t p = 0; p < nparts && unorientable; p++)
            *unorientable += bad_part[p];
        for (uint32_t f = 0; f < nf; f++) {
            if (!flip[f] || bad_part[part[f]])
                continue;
            if (reversed)
                (*reversed)++;
            if (first_rev && *first_rev == UINT32_MAX)
                *first_rev = f;
            uint32_t k = first[f], n = c->face_sizes[f];
            for (uint32_t i = 1, j = n - 1; apply && i < j; i++, j--) {
                uint32_t t = c->face_verts[k + i];
                c->face_verts[k + i] = c->face_verts[k + j];
                c->face_verts[k + j] = t;
                if (c->face_uvs) {
                    t = c->face_uvs[k + i];
                    c->face_uvs[k + i] = c->face_uvs[k + j];
                    c->face_uvs[k + j] = t;
                }
            }
        }
    }
    tsr_free(a, e);
    tsr_free(a, first);
    tsr_free(a, adj_n);
    tsr_free(a, deg);
    tsr_free(a, part);
    tsr_free(a, queue);
    tsr_free(a, flip);
    tsr_free(a, bad_part);
    return st;
}

void tsr_cage_free(tsr_cage *c)
{
    if (!c)
        return;
    const tsr_allocator *a = c->alloc.realloc ? &c->alloc : NULL;
    void *all[] = {c->points,       c->face_sizes,       c->face_verts, c->crease_verts, c->crease_sharpness,
                   c->corner_verts, c->corner_sharpness, c->hole_faces, c->uvs,          c->face_uvs};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
        tsr_free(a, all[i]);
    memset(c, 0, sizeof *c);
}

tsr_status tsr_cage_parse(const void *data, size_t size, const char *name, const tsr_allocator *alloc, tsr_cage *out,
                          tsr_error *err)
{
    if (!name)
        name = "<memory>";
    if (!out)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: no cage to load into", name);
    memset(out, 0, sizeof *out);
    if (!data && size)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: no data", name);
    if (size == 0)
        return tsr_error_set(err, TSR_ERR_EMPTY, "%s: empty file (0 bytes)", name);
    lexer L = {name, skip_bom(data, size), (const char *)data + size, 1, 1, err};
    cage_build c;
    memset(&c, 0, sizeof c);
    c.a = alloc;
    c.all_uvs = true;
    out->boundary_interp = 1; /* OpenSubdiv's regression default: edge only */
    out->fvar_interp = 5;     /* Sdc's default: linear all */
    tsr_status s = TSR_OK;
    while (s == TSR_OK && next_statement(&L))
        s = cage_statement(&L, &c, out);
    if (s == TSR_OK && c.face_sizes.n == 0)
        s = fail(&L, 0, TSR_ERR_EMPTY, "no face (f) in the file");
    if (s != TSR_OK) {
        cage_build_free(&c);
        memset(out, 0, sizeof *out);
        return s;
    }
    out->alloc = alloc ? *alloc : (tsr_allocator){NULL, NULL, NULL};
    out->num_points = (uint32_t)(c.points.n / 3), out->points = c.points.data;
    out->num_faces = (uint32_t)c.face_sizes.n, out->face_sizes = c.face_sizes.data;
    out->num_face_verts = (uint32_t)c.face_verts.n, out->face_verts = c.face_verts.data;
    out->num_creases = (uint32_t)(c.crease_verts.n / 2), out->crease_verts = c.crease_verts.data;
    out->crease_sharpness = c.crease_sharp.data;
    out->num_corners = (uint32_t)c.corner_verts.n, out->corner_verts = c.corner_verts.data;
    out->corner_sharpness = c.corner_sharp.data;
    out->num_holes = (uint32_t)c.hole_faces.n, out->hole_faces = c.hole_faces.data;
    out->num_uvs = (uint32_t)(c.uvs.n / 2), out->uvs = c.uvs.data;
    if (c.all_uvs) {
        out->face_uvs = c.face_uvs.data;
        c.face_uvs.data = NULL;
    }
    c.points.data = c.face_sizes.data = c.face_verts.data = c.crease_verts.data = c.crease_sharp.data = NULL;
    c.corner_verts.data = c.corner_sharp.data = c.hole_faces.data = c.uvs.data = NULL;
    cage_build_free(&c);
    return TSR_OK;
}

tsr_status tsr_cage_load(const char *path, const tsr_allocator *alloc, tsr_cage *out, tsr_error *err)
{
    if (out)
        memset(out, 0, sizeof *out);
    char *buf;
    size_t len;
    tsr_status s = tsr_read_file(path, TSR_PATCH_MAX_FILE_BYTES, alloc, &buf, &len, err);
    if (s != TSR_OK)
        return s;
    s = tsr_cage_parse(buf, len, path, alloc, out, err);
    tsr_free(alloc, buf);
    return s;
}
