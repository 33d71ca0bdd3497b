// Depth pre-pass (Diefenbach & Badler 1997, section 7.2: later passes redraw
// with an equal-depth test, so the visible surface is fixed here): world
// triangles through the view's reverse-Z view-projection into depth and a
// surface-id target, only where the stencil holds the view's reference.
//
// Notation
// | symbol | meaning                                                    | unit |
// |--------|------------------------------------------------------------|------|
// | P      | world position of a vertex                                 | m    |
// | VP     | the view's view-projection, reverse Z, infinite far plane  | -    |
// | z/w    | stored depth: 1 at the near plane, 0 at infinity           | 1    |
// | s      | scene SurfaceId of the triangle (flat)                     | -    |

struct VertexOutput {
    // Invariant: passes that redraw the scene with an equal-depth test reuse this vertex stage.
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

@fragment
fn fs_main(in: VertexOutput) -> @location(0) u32 {
    return in.surface;
}
