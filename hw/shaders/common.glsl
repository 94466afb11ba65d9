// common.glsl: what the terrain shaders share with hw/vulkan.c. The
// layouts here must match struct vk_frame_data and struct vk_push there.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_scalar_block_layout : require

layout(buffer_reference, scalar, buffer_reference_align = 16) readonly buffer Frame {
    mat4 view_proj;   // (world - eye, 1) -> clip, reversed infinite depth
    mat4 inv_dir;     // columns 0..2: clip (x, y, 1) -> view ray direction (world)
    vec4 sun_fog;     // xyz: unit vector to the sun; w: fog distance (0 none)
    vec4 ramp;        // x: zmin - eye z, y: zmax - eye z, z: finest spacing, w: unused
    vec4 sky_zenith;  // rgb
    vec4 sky_horizon; // rgb; also the fog colour
    uint flags;       // 1 wireframe, 2 geomorph, 4 normals as colours
};

layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer Samples {
    uint w[];
};

// What a draw's neighbours need to read its samples: one per draw of the
// frame, in draw order (struct vk_tile_rec).
struct TileRec {
    Samples samples;
    vec2 origin;
    vec2 spacing;
    float z_base;
    float z_step;
    uint n;
    uint bits;
    uint first;
    uint nb[8];       // 1 + the draw across each half edge (2 edge + half), 0 none
    uint pad;
};

layout(buffer_reference, scalar, buffer_reference_align = 8) readonly buffer Tiles {
    TileRec t[];
};

layout(push_constant, scalar) uniform Push {
    Frame frame;
    Samples samples;
    vec2 origin;      // world x, y of vertex (0, 0) minus the eye's
    vec2 spacing;
    vec2 limit;       // vertices beyond are clamped onto it
    float z_base;     // relative to the eye's z
    float z_step;
    float morph;
    uint n;           // quads per side
    uint bits;        // bit 0: U16 format; bits 8..15: level; bits 16..17: parity
    uint first;       // U16: sample 0 is the high half of the first word
    Tiles tiles;      // the frame's draws
    uint draw_no;     // this draw's record in tiles
} pc;

vec3 sky_colour(vec3 dir)
{
    float e = clamp(normalize(dir).z, 0.0, 1.0);
    return mix(pc.frame.sky_horizon.rgb, pc.frame.sky_zenith.rgb, pow(e, 0.6));
}
