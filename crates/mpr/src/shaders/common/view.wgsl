// The view every scene pass draws under (Diefenbach & Badler 1997, sections 3
// and 7.1): group 0, one block per view read at a dynamic offset.
//
// Notation
// | symbol     | meaning                                                  | unit |
// |------------|----------------------------------------------------------|------|
// | VP         | world to clip, reverse Z (a virtual camera's: view * R)  | -    |
// | eye        | eye the view shades for (virtual behind specular faces)  | m    |
// | clip_plane | world plane (n, w); points with n·p + w < 0 are removed  | m    |
// | level      | x: recursion level, y: stencil reference, z: 1 where the | -    |
// |            | view hides emitters (a glossy image's sheared view)      |      |
//
// A pass's `VertexOutput` may carry a commented field declaring the
// clip_distances builtin and its vertex stage a commented line setting it from
// view_clip_distance(world), both marked with the prefix "clip_distances:"
// after the comment slashes; `shaders::specialise` uncomments them where the
// device has user clip distances (and gives fragment stages the varyings
// without it); elsewhere the projection carries an oblique near plane.

struct View {
    view_projection: mat4x4f,
    eye: vec4f,
    clip_plane: vec4f,
    level: vec4u,
}

@group(0) @binding(0) var<uniform> view: View;

// Signed distance of world point p from the view's clip plane (kept where >= 0).
fn view_clip_distance(p: vec3f) -> f32 {
    return dot(view.clip_plane, vec4f(p, 1.0));
}
