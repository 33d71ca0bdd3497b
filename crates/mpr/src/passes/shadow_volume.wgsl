// Shadow volumes (Diefenbach & Badler 1997, section 4.1; z-fail counting,
// far vertices at infinity so the pivot jitter of section 4.4 is exact) and
// the stencil bookkeeping of section 7.3 (full-screen triangles).
//
// Notation
// | symbol | meaning                                                       | unit |
// |--------|---------------------------------------------------------------|------|
// | P      | world position of a volume vertex                             | m    |
// | w      | 1 for a finite vertex, 0 for one extruded to infinity         | -    |
// | L      | light position of this pass (jittered for soft shadows, 4.4)  | m    |
// | VP     | camera view-projection, reverse Z, infinite far plane         | -    |
// | (P-L,0)| the point at infinity in direction P - L: depth 0            | -    |

struct VolumeUniforms {
    view_projection: mat4x4f,
    // xyz: L; w unused.
    light: vec4f,
}

@group(0) @binding(0) var<uniform> u: VolumeUniforms;

// A finite vertex at (P, 1); an extruded one at (P - L, 0) (section 4.4).
@vertex
fn vs_volume(@location(0) v: vec4f) -> @builtin(position) vec4f {
    if v.w == 0.0 {
        return u.view_projection * vec4f(v.xyz - u.light.xyz, 0.0);
    }
    return u.view_projection * vec4f(v.xyz, 1.0);
}

// One triangle covering the viewport, at depth 0 (the stencil passes test
// depth Always).
@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
    let x = f32((i << 1u) & 2u);
    let y = f32(i & 2u);
    return vec4f(2.0 * x - 1.0, 2.0 * y - 1.0, 0.0, 1.0);
}

// The lit mask of the tests: 1 where the stencil test (== SHAD_ZERO) passes.
@fragment
fn fs_mask() -> @location(0) vec4f {
    return vec4f(1.0);
}
