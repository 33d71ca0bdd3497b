// Specular images (Diefenbach & Badler 1997, sections 3 and 7.1): a mirror
// face masked in the stencil (mask_face), the depth inside the mask reset so
// the virtual camera's image can be drawn there, then the face restored (its
// depth and surface id written back, the stencil popped to the outer level)
// while the image drawn inside it is scaled by the mirror's reflectance.
// At the recursion limit the face shows R times the limit radiance instead.
//
// Notation
// | symbol | meaning                                                        | unit       |
// |--------|----------------------------------------------------------------|------------|
// | P      | world position of a face vertex (the scene's own vertex buffer) | m          |
// | s      | the face's SurfaceId                                           | -          |
// | R      | the mirror's reflectance, per surface                          | 1          |
// | L_lim  | radiance shown by a face at the recursion limit                | W/(m^2 sr) |

struct Face {
    // rgb: R for an eye in front of `plane`; a: 1 where the surface is a specular face.
    reflectance: vec4f,
    // rgb: R for an eye behind `plane` (the other side of a single interface).
    behind: vec4f,
    // The plane (n, -offset) that tells the sides apart; zero for one-sided faces.
    plane: vec4f,
}

struct SpecularUniforms {
    // rgb: L_lim.
    limit_radiance: vec4f,
}

@group(1) @binding(0) var<storage, read> faces: array<Face>;
@group(1) @binding(1) var<uniform> specular: SpecularUniforms;

struct VertexOutput {
    // Invariant, computed exactly as depth.wgsl's vs_main: the mask's equal-depth test needs bit-identical depth.
    @builtin(position) @invariant clip: vec4f,
    @location(0) @interpolate(flat) surface: u32,
    //clip_distances: @builtin(clip_distances) clip_distances: array<f32, 1>,
}

@vertex
fn vs_main(@location(0) position: vec3f, @location(1) surface: u32) -> VertexOutput {
    var out: VertexOutput;
    out.clip = view.view_projection * vec4f(position, 1.0);
    out.surface = surface;
    //clip_distances: out.clip_distances[0] = view_clip_distance(position);
    return out;
}

// One triangle over the viewport at depth 0 (reverse Z: infinitely far), for the depth reset.
@vertex
fn vs_far(@builtin(vertex_index) index: u32) -> @builtin(position) vec4f {
    let x = f32((index << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(index & 2u) * 2.0 - 1.0;
    return vec4f(x, y, 0.0, 1.0);
}

struct Restored {
    // Multiplies the HDR image inside the face (blend Zero, Src).
    @location(0) reflectance: vec4f,
    @location(1) surface: u32,
}

// R of surface s as the view's eye sees it.
fn face_factor(s: u32) -> vec3f {
    if dot(faces[s].plane, vec4f(view.eye.xyz, 1.0)) >= 0.0 {
        return faces[s].reflectance.xyz;
    }
    return faces[s].behind.xyz;
}

@fragment
fn fs_restore(in: VertexOutput) -> Restored {
    var out: Restored;
    out.reflectance = vec4f(face_factor(in.surface), 1.0);
    out.surface = in.surface;
    return out;
}

// A glossy image's sample restored: its image, accumulated elsewhere, cleared (multiplied by zero).
@fragment
fn fs_restore_zero(in: VertexOutput) -> Restored {
    var out: Restored;
    out.reflectance = vec4f(0.0, 0.0, 0.0, 1.0);
    out.surface = in.surface;
    return out;
}

@fragment
fn fs_limit(in: VertexOutput) -> @location(0) vec4f {
    return vec4f(face_factor(in.surface) * specular.limit_radiance.xyz, 0.0);
}
