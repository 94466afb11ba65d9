#version 460
#include "common.glsl"

layout(location = 0) in vec3 v_pos;
layout(location = 1) in vec3 v_normal;
layout(location = 2) in vec2 v_local;
layout(location = 3) in float v_valid;
layout(location = 0) out vec4 o_colour;

void main()
{
    if (v_valid < 0.999)
        discard; // a triangle with a no-data corner is a hole
    vec3 nrm = normalize(v_normal);
    if ((pc.frame.flags & 4u) != 0u) { // TSR_HW_FRAME_NORMALS
        o_colour = vec4(0.5 * nrm + 0.5, 1.0);
        return;
    }
    float zr = pc.frame.ramp.y - pc.frame.ramp.x;
    float t = zr > 0.0 ? clamp((v_pos.z - pc.frame.ramp.x) / zr, 0.0, 1.0) : 0.5;
    float slope = 1.0 - nrm.z; // 0 flat, 1 vertical

    // Colour ramp by height, then rock on steep slopes, snow on high flats.
    vec3 low = vec3(0.22, 0.40, 0.18), mid = vec3(0.45, 0.50, 0.28), high = vec3(0.50, 0.43, 0.34);
    vec3 c = t < 0.45 ? mix(low, mid, t / 0.45) : mix(mid, high, (t - 0.45) / 0.55);
    vec3 rock = vec3(0.46, 0.44, 0.42);
    c = mix(c, rock, smoothstep(0.18, 0.35, slope));
    float snow = smoothstep(0.72, 0.85, t) * (1.0 - smoothstep(0.15, 0.3, slope));
    c = mix(c, vec3(0.95, 0.96, 0.98), snow);

    // One load of the whole vec4: Mesa's lavapipe (22.3) returned 0 for
    // .w when .xyz and .w were read separately through the buffer
    // reference, so it drew no fog where a real GPU did.
    vec4 sun_fog = pc.frame.sun_fog;
    vec3 sun = sun_fog.xyz;
    float diffuse = max(dot(nrm, sun), 0.0);
    float sky_light = 0.5 + 0.5 * nrm.z;
    c *= 0.25 * sky_light + 0.85 * diffuse;

    float fog = sun_fog.w;
    if (fog > 0.0) {
        float f = 1.0 - exp(-length(v_pos) / fog);
        c = mix(c, pc.frame.sky_horizon.rgb, f);
    }
    o_colour = vec4(c, 1.0);
}
