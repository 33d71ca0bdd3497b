// Gouraud pass (García Hernández, Ureña & Lastra 2003, section 2.4): the
// outgoing radiance computed at mesh vertices, L_r = rho/pi E (equation 2.2),
// interpolated inside each triangle and added into the HDR target after an
// equal-depth redraw of the scene against the depth pre-pass. On a surface
// with a diffuse map the corners carry rho_d/pi E with the untextured rho_d
// and each fragment scales it by the map at its own uv (the corner's layer),
// so that the texture is as sharp as the image, not as the lighting mesh.
//
// Notation
// | symbol | meaning                                                       | unit       |
// |--------|---------------------------------------------------------------|------------|
// | P      | world position of the shaded point                            | m          |
// | E      | the view's eye                                                | m          |
// | n      | interpolated vertex normal: the side the estimate belongs to  | -          |
// | Lv     | outgoing radiance at a triangle corner (per-vertex, eq. 2.2)  | W/(m^2 sr) |
// | L      | Lv interpolated perspective-correctly at the pixel centre     | W/(m^2 sr) |
// | layer  | the diffuse map scaling L at the fragment; 0 (white) for none  | -          |
// One-sided like the estimators' tangent-plane side: L is seen only where (E - P) . n > 0.

struct VertexOutput {
    // Invariant, computed exactly as depth.wgsl's vs_main: the equal-depth test needs bit-identical depth.
    @builtin(position) @invariant clip: vec4f,
    @location(0) world: vec3f,
    @location(1) normal: vec3f,
    // Perspective-correct (the WGSL default), so L is linear in world space across the triangle.
    @location(2) @interpolate(perspective, center) radiance: vec3f,
    @location(3) uv: vec2f,
    @location(4) @interpolate(flat) layer: u32,
    //clip_distances: @builtin(clip_distances) clip_distances: array<f32, 1>,
}

@vertex
fn vs_main(
    @location(0) position: vec3f,
    @location(2) normal: vec3f,
    @location(6) uv: vec2f,
    @location(4) radiance: vec3f,
    @location(5) layer: u32,
) -> VertexOutput {
    var out: VertexOutput;
    out.clip = view.view_projection * vec4f(position, 1.0);
    //clip_distances: out.clip_distances[0] = view_clip_distance(position);
    out.world = position;
    out.normal = normal;
    out.radiance = radiance;
    out.uv = uv;
    out.layer = layer;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4f {
    // Derivatives in uniform control flow, before the discard.
    let duv_dx = dpdx(in.uv);
    let duv_dy = dpdy(in.uv);
    if dot(view.eye.xyz - in.world, in.normal) <= 0.0 {
        discard;
    }
    return vec4f(in.radiance * diffuse_tint_grad(in.layer, in.uv, duv_dx, duv_dy), 0.0);
}

@group(1) @binding(0) var diffuse_maps: texture_2d_array<f32>;
@group(1) @binding(1) var diffuse_map_sampler: sampler;
