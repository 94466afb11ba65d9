#version 460
#include "common.glsl"

layout(location = 0) in vec2 v_ndc;
layout(location = 0) out vec4 o_colour;

void main()
{
    vec3 dir = mat3(pc.frame.inv_dir) * vec3(v_ndc, 1.0);
    o_colour = vec4(sky_colour(dir), 1.0);
}
