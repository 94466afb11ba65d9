#version 460
#include "common.glsl"

layout(location = 0) out vec3 v_pos;   // world - eye
layout(location = 1) out vec3 v_normal;
layout(location = 2) out vec2 v_local; // (i, j) in the tile
layout(location = 3) out float v_valid;

// Sample (i, j) of the tile, true when it is not no-data.
bool fetch(int i, int j, out float h)
{
    uint k = uint(j) * (pc.n + 1u) + uint(i);
    if ((pc.bits & 1u) != 0u) {
        k += pc.first;
        uint word = pc.samples.w[k >> 1u];
        uint code = (k & 1u) != 0u ? word >> 16u : word & 0xFFFFu;
        h = pc.z_base + pc.z_step * float(code);
        return code != 0xFFFFu;
    }
    float s = uintBitsToFloat(pc.samples.w[k]);
    h = pc.z_base + pc.z_step * s;
    return !isnan(s);
}

float height_or(int i, int j, float fallback)
{
    int n = int(pc.n);
    if (i < 0 || j < 0 || i > n || j > n)
        return fallback;
    float h;
    return fetch(i, j, h) ? h : fallback;
}

void main()
{
    uint idx = uint(gl_VertexIndex);
    int n = int(pc.n);
    int i = int(idx % (pc.n + 1u)), j = int(idx / (pc.n + 1u));
    float h;
    bool ok = fetch(i, j, h);
    if (!ok)
        h = pc.z_base;

    // Normal from the tile's own samples: central differences inside,
    // one-sided at the tile's edges.
    int il = max(i - 1, 0), ir = min(i + 1, n), jd = max(j - 1, 0), ju = min(j + 1, n);
    float hl = height_or(il, j, h), hr = height_or(ir, j, h);
    float hd = height_or(i, jd, h), hu = height_or(i, ju, h);
    float gx = (hr - hl) / (float(ir - il) * pc.spacing.x);
    float gy = (hu - hd) / (float(ju - jd) * pc.spacing.y);
    vec3 nrm = normalize(vec3(-gx, -gy, 1.0));

    // Geomorph: odd vertices inside the tile move towards the parent's
    // surface, the mean of the two even neighbours along the parent's edge
    // or (at a parent quad's centre) its union-jack diagonal.
    if ((pc.frame.flags & 2u) != 0u && pc.morph > 0.0 && ok && i > 0 && j > 0 && i < n && j < n &&
        ((i & 1) != 0 || (j & 1) != 0)) {
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
        if (fetch(ai, aj, ha) && fetch(bi, bj, hb))
            h = mix(h, 0.5 * (ha + hb), pc.morph);
    }

    vec3 p = vec3(min(pc.origin + vec2(float(i), float(j)) * pc.spacing, pc.limit), h);
    v_pos = p;
    v_normal = nrm;
    v_local = vec2(float(i), float(j));
    v_valid = ok ? 1.0 : 0.0;
    gl_Position = pc.frame.view_proj * vec4(p, 1.0);
}
