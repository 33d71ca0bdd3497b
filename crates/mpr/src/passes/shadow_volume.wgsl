// Shadow volumes (Diefenbach & Badler 1997, section 4.1; z-fail counting,
// far vertices at infinity so the pivot jitter of section 4.4 is exact) and
// the stencil bookkeeping of section 7.3 (full-screen triangles). Compiled
// after the view block (shaders::with_view): the volumes are drawn through
// the view of group 0 and clipped by its clip plane like every scene pass.
//
// Notation
// | symbol | meaning                                                       | unit |
// |--------|---------------------------------------------------------------|------|
// | P      | world position of a volume vertex                             | m    |
// | w      | 1 for a finite vertex, 0 for one extruded to infinity         | -    |
// | L      | light position of this pass (jittered for soft shadows, 4.4)  | m    |
// | M      | affine map after extrusion (faces passed, 4.3; else identity) | -    |
// | VP     | the view's view-projection, reverse Z, infinite far plane     | -    |
// | (P-L,0)| the point at infinity in direction P - L: depth 0            | -    |

// One light of the pass, one block per light at a dynamic offset.
struct VolumeLight {
    // xyz: L; w unused.
    position: vec4f,
    // Affine map applied after the extrusion (identity for a real light;
    // the specular faces' transforms for a virtual light's volumes, 4.3).
    transform: mat4x4f,
}

@group(1) @binding(0) var<uniform> volume_light: VolumeLight;

struct VertexOutput {
    @builtin(position) clip: vec4f,
    //clip_distances: @builtin(clip_distances) clip_distances: array<f32, 1>,
}

// A finite vertex at (P, 1); an extruded one at (P - L, 0) (section 4.4). The
// clip distance is the plane's value at the homogeneous point, (n, w)·(x, w'),
// which clipping interpolates linearly like the position: view_clip_distance
// of the xyz part, less the plane's w where w' = 0.
@vertex
fn vs_volume(@location(0) v: vec4f) -> VertexOutput {
    var world = vec4f(v.xyz, 1.0);
    if v.w == 0.0 {
        world = vec4f(v.xyz - volume_light.position.xyz, 0.0);
    }
    world = volume_light.transform * world;
    var out: VertexOutput;
    out.clip = view.view_projection * world;
    //clip_distances: out.clip_distances[0] = view_clip_distance(world.xyz) - (1.0 - world.w) * view.clip_plane.w;
    return out;
}

// One triangle covering the viewport, at depth 0 (the stencil passes test
// depth Always).
@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
    let x = f32((i << 1u) & 2u);
    let y = f32(i & 2u);
    return vec4f(2.0 * x - 1.0, 2.0 * y - 1.0, 0.0, 1.0);
}

// The lit mask of the tests: 1 where the stencil test (== SHAD_ZERO) passes;
// the stencil passes use it with colour writes off.
@fragment
fn fs_mask() -> @location(0) vec4f {
    return vec4f(1.0);
}
