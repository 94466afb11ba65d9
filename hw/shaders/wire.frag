#version 460
#include "common.glsl"

layout(location = 0) in vec3 v_pos;
layout(location = 1) in vec3 v_normal;
layout(location = 2) in vec2 v_local;
layout(location = 3) in float v_valid;
layout(location = 0) out vec4 o_colour;

// Edges coloured by LOD level (a hue per level); tile borders white.
void main()
{
    if (v_valid < 0.999)
        discard;
    float n = float(pc.n);
    bool border = v_local.x < 1e-3 || v_local.y < 1e-3 || v_local.x > n - 1e-3 || v_local.y > n - 1e-3;
    if (border) {
        o_colour = vec4(1.0, 1.0, 1.0, 1.0);
        return;
    }
    float level = float((pc.bits >> 8u) & 255u);
    float hue = fract(level * 0.17);
    vec3 k = clamp(abs(fract(vec3(hue) + vec3(0.0, 2.0 / 3.0, 1.0 / 3.0)) * 6.0 - 3.0) - 1.0, 0.0, 1.0);
    o_colour = vec4(mix(k, vec3(1.0), 0.2), 1.0);
}
