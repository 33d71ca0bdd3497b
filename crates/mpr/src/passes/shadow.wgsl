// Omnidirectional shadow map of a point light (Stürzlinger & Bastos 1997,
// section 2.2.1, after Segal et al. 1992; cube maps for point lights): the
// scene drawn into one cube face at a time with a 90-degree perspective from
// the light, storing per texel the distance from the light to the nearest
// surface. A reverse-Z depth buffer picks the nearest surface; the colour
// face keeps its distance, which the direct pass compares with its own.
//
// Notation
// | symbol | meaning                                                           | unit |
// |--------|-------------------------------------------------------------------|------|
// | P      | world position of a vertex or fragment                            | m    |
// | L      | world position of the light                                       | m    |
// | d      | P - L, the direction the cube map is sampled with                 | m    |
// | F      | face matrix: d to clip (sc, -tc, near, ma) of the face's axis     | -    |
// | ma     | d along the face's major axis (the face's view depth)             | m    |
// | |d|    | stored value: Euclidean distance from the light to the surface    | m    |

struct ShadowFace {
    // World-to-clip of this face: F applied to P - L.
    view_projection: mat4x4f,
    // xyz: L; w: the near distance (unused here, kept for the layout).
    light: vec4f,
}

@group(0) @binding(0) var<uniform> face: ShadowFace;

struct VertexOutput {
    @builtin(position) clip: vec4f,
    @location(0) world: vec3f,
}

@vertex
fn vs_main(@location(0) position: vec3f) -> VertexOutput {
    var out: VertexOutput;
    out.clip = face.view_projection * vec4f(position, 1.0);
    out.world = position;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) f32 {
    return length(in.world - face.light.xyz);
}
