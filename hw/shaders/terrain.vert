#version 460
#include "common.glsl"

layout(location = 0) out vec3 v_pos;   // world - eye
layout(location = 1) out vec3 v_normal;
layout(location = 2) out vec2 v_local; // (i, j) in the tile
layout(location = 3) out float v_valid;

// Where sample k of a tile's store lies: its 32-bit word (U16: two a word,
// after `first` halves).
uint word_of(uint k, uint bits, uint first)
{
    return (bits & 1u) != 0u ? (k + first) >> 1u : k;
}

// Sample k from its word; true when it is not no-data.
bool decode(uint word, uint k, uint bits, uint first, float z_base, float z_step, out precise float h)
{
    if ((bits & 1u) != 0u) {
        uint code = ((k + first) & 1u) != 0u ? word >> 16u : word & 0xFFFFu;
        h = z_base + z_step * float(code);
        return code != 0xFFFFu;
    }
    float s = uintBitsToFloat(word);
    h = z_base + z_step * s;
    return !isnan(s);
}

// Sample (i, j) of the tile, true when it is not no-data.
bool fetch(int i, int j, out float h)
{
    uint k = uint(j) * (pc.n + 1u) + uint(i);
    return decode(pc.samples.w[word_of(k, pc.bits, pc.first)], k, pc.bits, pc.first, pc.z_base, pc.z_step, h);
}

// The draw across edge e (TSR_EDGE_* order: 0 south, 1 east, 2 north,
// 3 west) at position `along` of it, plus one; 0: none.
uint neighbour(uint e, int along)
{
    return pc.tiles.t[pc.draw_no].nb[2u * e + (2 * along > int(pc.n) ? 1u : 0u)];
}

// World x, y (relative to the eye) of vertex (i, j) of this tile, before
// the clamp onto the extent (the lattice goes on beyond it).
vec2 world(int i, int j)
{
    return pc.origin + vec2(float(i), float(j)) * pc.spacing;
}

// Where point p (as world()) lies on the lattice of draw `rec`: false when
// it is not one of that tile's vertices (points off the lattice are half a
// step away or more, so a quarter step of float rounding is tolerated).
// Written so that NaN fails.
bool lattice_of(uint rec, vec2 p, out ivec2 k)
{
    vec2 q = (p - pc.tiles.t[rec].origin) / pc.tiles.t[rec].spacing;
    vec2 qr = round(q);
    k = ivec2(0);
    if (!(all(lessThanEqual(abs(q - qr), vec2(0.25))) && all(greaterThanEqual(qr, vec2(0.0))) &&
          all(lessThanEqual(qr, vec2(float(pc.tiles.t[rec].n))))))
        return false;
    k = ivec2(qr);
    return true;
}

// The height at (i, j) of this tile's lattice, which may lie beyond one
// edge: then the neighbour's sample there, if it has one. False when
// there is none or it is no-data.
bool height_at(int i, int j, out float h)
{
    int n = int(pc.n);
    if (i >= 0 && j >= 0 && i <= n && j <= n)
        return fetch(i, j, h);
    uint e = j < 0 ? 0u : i > n ? 1u : j > n ? 2u : 3u;
    int along = (e & 1u) == 0u ? i : j;
    if (along < 0 || along > n)
        return false; /* beyond a corner: never asked */
    uint nb = neighbour(e, along);
    ivec2 k;
    if (nb == 0u || !lattice_of(nb - 1u, world(i, j), k))
        return false;
    nb -= 1u;
    uint m = pc.tiles.t[nb].n, bits = pc.tiles.t[nb].bits, first = pc.tiles.t[nb].first;
    uint q = uint(k.y) * (m + 1u) + uint(k.x);
    uint word = pc.tiles.t[nb].samples.w[word_of(q, bits, first)];
    return decode(word, q, bits, first, pc.tiles.t[nb].z_base, pc.tiles.t[nb].z_step, h);
}

// Draw nb's spacing (1 + its number; 0: none) over this one's, at least 1.
float coarser(uint nb)
{
    return nb == 0u ? 1.0 : max(1.0, pc.tiles.t[nb - 1u].spacing.x / pc.spacing.x);
}

// The step at vertex `along` of edge e (not a corner): 2 when the draw
// across is coarser than this one, else 1.
int edge_ratio(uint e, int along)
{
    return int(coarser(neighbour(e, along)) + 0.5);
}

// The step at corner (ci, cj) (each 0 or n): the coarsest spacing among
// the tiles that meet there, in this tile's (1, 2 or 4): this one, the two
// across its edges, and the one across the corner, found through the
// first of those two that is drawn (across its edge at the corner, or that
// tile itself where the corner lies inside its edge). Every tile at the
// corner finds the same tiles, so all take the same step.
// The draw across corner (ci, cj) (1 + its number, 0: none), found
// through a (across the vertical edge there) or else b (the horizontal
// one): across that tile's edge at the corner, or that tile itself where
// the corner lies inside its edge.
uint diagonal(int ci, int cj, uint a, uint b, vec2 v)
{
    uint eh = cj == 0 ? 0u : 2u, ev = ci == 0 ? 3u : 1u;
    ivec2 k;
    if (a != 0u && lattice_of(a - 1u, v, k)) {
        int m = int(pc.tiles.t[a - 1u].n);
        bool on = eh == 0u ? k.y == 0 : k.y == m;
        return on ? pc.tiles.t[a - 1u].nb[2u * eh + (2 * k.x > m ? 1u : 0u)] : a;
    }
    if (b != 0u && lattice_of(b - 1u, v, k)) {
        int m = int(pc.tiles.t[b - 1u].n);
        bool on = ev == 3u ? k.x == 0 : k.x == m;
        return on ? pc.tiles.t[b - 1u].nb[2u * ev + (2 * k.y > m ? 1u : 0u)] : b;
    }
    return 0u;
}

int corner_ratio(int ci, int cj)
{
    uint eh = cj == 0 ? 0u : 2u, ev = ci == 0 ? 3u : 1u;
    uint a = neighbour(ev, cj), b = neighbour(eh, ci);
    uint d = diagonal(ci, cj, a, b, world(ci, cj));
    return int(max(max(coarser(a), coarser(b)), coarser(d)) + 0.5);
}

// Whether draw `rec` (1 + its number; 0: none) has point v (as world())
// among its vertices and outranks the best so far: the coarsest, then
// the lowest draw number.
void consider(uint rec, vec2 v, inout uint best, inout ivec2 bk)
{
    ivec2 k;
    if (rec == 0u || !lattice_of(rec - 1u, v, k))
        return;
    rec -= 1u;
    float s = pc.tiles.t[rec].spacing.x, bs = pc.tiles.t[best].spacing.x;
    if (s > bs || (s == bs && rec < best)) {
        best = rec;
        bk = k;
    }
}

// The draw whose stored sample places border vertex (i, j) (hw.h,
// "Watertight borders"), and the vertex's (i, j) in it: of the drawn tiles
// that have the vertex, the coarsest, then the lowest draw number. At a
// vertex inside an edge, this tile and the draws across that half edge (at
// its middle, both halves: two finer tiles meet there); at a corner, the
// draws across its two edges and the one across the corner. Every tile at
// the vertex finds the same ones (one per quadrant around the vertex), so
// all put it at the same position, to the bit.
uint canonical(int i, int j, out ivec2 k)
{
    int n = int(pc.n);
    uint best = pc.draw_no;
    k = ivec2(i, j);
    vec2 v = world(i, j);
    bool on_i = i == 0 || i == n, on_j = j == 0 || j == n;
    if (on_i && on_j) {
        uint eh = j == 0 ? 0u : 2u, ev = i == 0 ? 3u : 1u;
        uint a = neighbour(ev, j), b = neighbour(eh, i);
        consider(a, v, best, k);
        consider(b, v, best, k);
        consider(diagonal(i, j, a, b, v), v, best, k);
    } else {
        uint e = j == 0 ? 0u : i == n ? 1u : j == n ? 2u : 3u;
        consider(pc.tiles.t[pc.draw_no].nb[2u * e], v, best, k);
        consider(pc.tiles.t[pc.draw_no].nb[2u * e + 1u], v, best, k);
    }
    return best;
}

// dz per world unit along (di, dj) at (i, j), from the heights r steps
// either side: central where both are there, else one-sided, else 0.
float slope(int i, int j, int di, int dj, int r, float h, float step)
{
    float ha, hb;
    bool a = height_at(i - r * di, j - r * dj, ha), b = height_at(i + r * di, j + r * dj, hb);
    int span = (a ? r : 0) + (b ? r : 0);
    return span > 0 ? ((b ? hb : h) - (a ? ha : h)) / (float(span) * step) : 0.0;
}

// The parent tile's normal at even vertex (i, j) of this one (height h):
// differences at twice this tile's step.
vec3 parent_normal(int i, int j, float h)
{
    return normalize(vec3(-slope(i, j, 1, 0, 2, h, pc.spacing.x), -slope(i, j, 0, 1, 2, h, pc.spacing.y), 1.0));
}

void main()
{
    uint idx = uint(gl_VertexIndex);
    int n = int(pc.n);
    int i = int(idx % (pc.n + 1u)), j = int(idx / (pc.n + 1u));
    bool on_i = i == 0 || i == n, on_j = j == 0 || j == n;
    float h;
    bool ok;
    // A border vertex is placed by one of the tiles that share it, the same
    // for all of them (canonical()): from its record, its stored sample and
    // its origin and spacing, by the same instructions, so every tile puts
    // the vertex at the same float position and no pinhole opens between
    // them (their samples may be quantised differently, and their origins
    // are rounded apart). Inside the tile, the tile's own.
    precise vec2 xy;
    if (on_i || on_j) {
        ivec2 kc;
        uint c = canonical(i, j, kc);
        uint m = pc.tiles.t[c].n, bits = pc.tiles.t[c].bits, first = pc.tiles.t[c].first;
        uint q = uint(kc.y) * (m + 1u) + uint(kc.x);
        ok = decode(pc.tiles.t[c].samples.w[word_of(q, bits, first)], q, bits, first, pc.tiles.t[c].z_base,
                    pc.tiles.t[c].z_step, h);
        xy = pc.tiles.t[c].origin + vec2(kc) * pc.tiles.t[c].spacing;
        if (!ok)
            h = pc.tiles.t[c].z_base; /* (no-data: its triangles are discarded anyway) */
    } else {
        ok = fetch(i, j, h);
        xy = world(i, j);
        if (!ok)
            h = pc.z_base;
    }

    // Normal from central differences (hw.h): across an edge with the
    // neighbour's samples, at the coarser spacing of the two, so that the
    // tiles sharing a vertex shade it alike.
    int r = on_i && on_j ? corner_ratio(i, j)
          : on_j         ? edge_ratio(j == 0 ? 0u : 2u, i)
          : on_i         ? edge_ratio(i == 0 ? 3u : 1u, j)
                         : 1;
    float gx = slope(i, j, 1, 0, r, h, pc.spacing.x);
    float gy = slope(i, j, 0, 1, r, h, pc.spacing.y);
    vec3 nrm = normalize(vec3(-gx, -gy, 1.0));

    // Geomorph: vertices inside the tile move towards what the parent tile
    // draws there. Odd ones: the height to the mean of the two even
    // neighbours along the parent's edge or (at a parent quad's centre) its
    // union-jack diagonal, and the normal to the mean of the parent's
    // normals at those two (what the parent's triangle interpolates); even
    // ones keep their height and take the parent's normal (differences at
    // twice the step, its spacing). The blended normal is not renormalised
    // (the fragment shader normalises after interpolating, as for the
    // parent), so at morph 1 the tile lights as its parent does.
    if ((pc.frame.flags & 2u) != 0u && pc.morph > 0.0 && ok && !on_i && !on_j) {
        vec3 target;
        if (((i | j) & 1) == 0) {
            target = parent_normal(i, j, h);
        } else {
            int ai, aj, bi, bj;
            if ((j & 1) == 0) {
                ai = i - 1; aj = j; bi = i + 1; bj = j;
            } else if ((i & 1) == 0) {
                ai = i; aj = j - 1; bi = i; bj = j + 1;
            } else {
                uint parity = (pc.bits >> 16u) & 3u;
                int pqi = int(parity & 1u) * (n / 2) + (i - 1) / 2;
                int pqj = int(parity >> 1u) * (n / 2) + (j - 1) / 2;
                if (((pqi + pqj) & 1) == 0) {
                    ai = i - 1; aj = j - 1; bi = i + 1; bj = j + 1;
                } else {
                    ai = i + 1; aj = j - 1; bi = i - 1; bj = j + 1;
                }
            }
            float ha, hb;
            bool oka = fetch(ai, aj, ha), okb = fetch(bi, bj, hb);
            target = oka && okb ? 0.5 * (parent_normal(ai, aj, ha) + parent_normal(bi, bj, hb)) : nrm;
            if (oka && okb)
                h = mix(h, 0.5 * (ha + hb), pc.morph);
        }
        nrm = mix(nrm, target, pc.morph);
    }

    vec3 p = vec3(min(xy, pc.limit), h);
    v_pos = p;
    v_normal = nrm;
    v_local = vec2(float(i), float(j));
    v_valid = ok ? 1.0 : 0.0;
    gl_Position = pc.frame.view_proj * vec4(p, 1.0);
}
