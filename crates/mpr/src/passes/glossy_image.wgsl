// Glossy images (Diefenbach & Badler 1997, section 3: "glossy marble"): the
// sheared specular images of a glossy face accumulated in a float target.
// Per sample, after the scene was drawn from the sheared virtual view inside
// the face's stencil mask (level k + 1):
//   fs_fog      the image blended towards the fog radiance with the distance
//               of each visible point from the face (hardware fog with its
//               minimum at the face and its maximum at f_max),
//   fs_transfer the masked HDR pixels times 1/N (the blend constant) copied
//               (sample 0) or added into the accumulation target of level k;
// after the last sample, with the face restored at level k:
//   fs_resolve  the face's pixels of the accumulation target times R added
//               into the HDR target.
//
// Notation
// | symbol | meaning                                                       | unit       |
// |--------|---------------------------------------------------------------|------------|
// | P      | world position of a point seen in the image                   | m          |
// | n, w   | the face's plane: z(P) = n.P + w, the distance from the face  | m          |
// | f_max  | fog distance: the image fully fogged at z = f_max              | m          |
// | f      | fog factor clamp(1 - z / f_max, 0, 1): 1 at the face           | 1          |
// | L_fog  | fog radiance the image fades towards                          | W/(m^2 sr) |
// | R      | the face's glossy reflectance factor                          | 1          |
// | N      | samples (sheared images) per glossy image                     | -          |

struct GlossyFace {
    // xyz: n, w: -offset (z(P) = dot(plane, (P, 1))).
    plane: vec4f,
    // rgb: L_fog; a: 1 / f_max (0: no fog).
    fog: vec4f,
    // rgb: R.
    weight: vec4f,
}

@group(1) @binding(0) var<storage, read> faces: array<GlossyFace>;
// The HDR target (fs_transfer) or the accumulation target (fs_resolve).
@group(1) @binding(1) var image: texture_2d<f32>;

struct VertexOutput {
    // Invariant, computed exactly as depth.wgsl's vs_main: the equal-depth tests need bit-identical depth.
    @builtin(position) @invariant clip: vec4f,
    @location(0) world: vec3f,
    @location(1) @interpolate(flat) face: u32,
    //clip_distances: @builtin(clip_distances) clip_distances: array<f32, 1>,
}

// The scene's vertices; the face's index in the instance index.
@vertex
fn vs_main(
    @location(0) position: vec3f,
    @builtin(instance_index) face: u32,
) -> VertexOutput {
    var out: VertexOutput;
    out.clip = view.view_projection * vec4f(position, 1.0);
    //clip_distances: out.clip_distances[0] = view_clip_distance(position);
    out.world = position;
    out.face = face;
    return out;
}

// f = clamp(1 - z / f_max, 0, 1) of the point `in` shows, z its distance
// from the face: reflected points lie in front of it, points seen through a
// slab behind it.
fn fog_factor(in: VertexOutput) -> f32 {
    let face = faces[in.face];
    let z = abs(dot(face.plane, vec4f(in.world, 1.0)));
    return clamp(1.0 - z * face.fog.w, 0.0, 1.0);
}

// Blend: dst * a + rgb, i.e. f * L_image + (1 - f) * L_fog.
@fragment
fn fs_fog(in: VertexOutput) -> @location(0) vec4f {
    let f = fog_factor(in);
    return vec4f(faces[in.face].fog.xyz * (1.0 - f), f);
}

// The same fading with L_fog left out (a frame drawn without its constant
// terms, the emitters and the recursion's limit radiance): f * L_image.
@fragment
fn fs_fog_dark(in: VertexOutput) -> @location(0) vec4f {
    return vec4f(0.0, 0.0, 0.0, fog_factor(in));
}

@fragment
fn fs_resolve(in: VertexOutput) -> @location(0) vec4f {
    let sum = textureLoad(image, vec2i(floor(in.clip.xy)), 0).xyz;
    return vec4f(sum * faces[in.face].weight.xyz, 0.0);
}

// One triangle over the viewport (the stencil picks the mask).
@vertex
fn vs_full(@builtin(vertex_index) index: u32) -> @builtin(position) vec4f {
    let x = f32((index << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(index & 2u) * 2.0 - 1.0;
    return vec4f(x, y, 0.0, 1.0);
}

@fragment
fn fs_transfer(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    return vec4f(textureLoad(image, vec2i(floor(frag.xy)), 0).xyz, 0.0);
}
