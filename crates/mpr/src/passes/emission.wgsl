// Emitted radiance of light-source surfaces (the area lights' own meshes seen
// by the camera): the scene redrawn with an equal-depth test against the
// depth pre-pass, adding Le on the emitting side into the HDR target
// (DESIGN.md "Data flow": the passes add light into one HDR target).
//
// Notation
// | symbol | meaning                                                    | unit       |
// |--------|------------------------------------------------------------|------------|
// | P      | world position of the shaded point                         | m          |
// | E      | the view's eye                                             | m          |
// | n      | interpolated vertex normal: the emitting side              | -          |
// | Le     | emitted radiance of the triangle's material (zero if none) | W/(m^2 sr) |
// One-sided like Mitsuba's area emitter: Le is seen only where (E - P) . n > 0.

@group(1) @binding(0) var<storage, read> emission: array<vec4f>;

struct VertexOutput {
    // Invariant, computed exactly as depth.wgsl's vs_main: the equal-depth test needs bit-identical depth.
    @builtin(position) @invariant clip: vec4f,
    @location(0) world: vec3f,
    @location(1) normal: vec3f,
    @location(2) @interpolate(flat) material: u32,
    //clip_distances: @builtin(clip_distances) clip_distances: array<f32, 1>,
}

@vertex
fn vs_main(
    @location(0) position: vec3f,
    @location(2) normal: vec3f,
    @location(3) material: u32,
) -> VertexOutput {
    var out: VertexOutput;
    out.clip = view.view_projection * vec4f(position, 1.0);
    //clip_distances: out.clip_distances[0] = view_clip_distance(position);
    out.world = position;
    out.normal = normal;
    out.material = material;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4f {
    // level.z: the sheared views of a glossy image hide emitters (the direct pass adds their highlight).
    if view.level.z != 0u {
        discard;
    }
    let le = emission[in.material].xyz;
    if all(le == vec3f(0.0)) || dot(view.eye.xyz - in.world, in.normal) <= 0.0 {
        discard;
    }
    return vec4f(le, 0.0);
}
