// Precomputed diffuse textures (Stürzlinger & Bastos 1997, section 2.2.1:
// diffuse surfaces are "displayed using ... textured surfaces" whose photon
// contributions were precomputed). The scene is redrawn with an equal-depth
// test against the depth pre-pass; fragments of textured surfaces look up
// L = rho/pi sum phi K/h^2 in the atlas, bilinearly between the samples
// around (u, v), on the layer of the viewer's side, and add it One/One into
// HDR. Fragments of other surfaces (left to the splat pass) are discarded.
// A surface whose material has a diffuse map stores L with the untextured
// rho; the lookup is multiplied by the map at the fragment's uv (common/
// diffuse_map.wgsl), irradiance times albedo, as a light map is drawn.
//
// Notation
// | symbol  | meaning                                                               | unit       |
// |---------|-----------------------------------------------------------------------|------------|
// | P       | world position of the fragment                                        | m          |
// | E       | camera position                                                       | m          |
// | O, U, V | surface frame: origin, unit u and v axes (PlanarFrame)                | m, -, -    |
// | N       | unit plane normal (winding side); E on its side reads the front layer | -          |
// | uv      | ((P - O).U, (P - O).V)                                                | m          |
// | uv_min  | lower corner of the surface's (u, v) bounding rectangle               | m          |
// | t       | sample spacing along u and v; sample (i, j) lies at uv_min + (i, j) t | m          |
// | s       | (uv - uv_min) / t, clamped to [0, size - 1]: continuous sample index  | 1          |
// | L       | bilinear mix of the 4 samples around s (textureLoad, no sampler)      | W/(m^2 sr) |
// | tint    | the material's diffuse map at the vertices' interpolated uv (1: none) | 1          |

// No layer on this side: no photon arrived there, the radiance is zero.
const NO_LAYER: u32 = 0xffffffffu;

// One surface's texture record (GpuDiffuseSurface in diffuse_texture.rs).
struct DiffuseSurface {
    origin: vec3f,
    // 1: rendered by this pass (planar, Lambertian); 0: left to the splat pass.
    textured: u32,
    u_axis: vec3f,
    // Samples along u.
    columns: u32,
    v_axis: vec3f,
    // Samples along v.
    rows: u32,
    normal: vec3f,
    // Layer of the material's diffuse map (0: none).
    diffuse_map: u32,
    uv_min: vec2f,
    spacing: vec2f,
    // Atlas texel of sample (0, 0): xy front layer, zw back layer (NO_LAYER: none).
    layers: vec4u,
}

@group(1) @binding(0) var<storage, read> surfaces: array<DiffuseSurface>;
@group(1) @binding(1) var atlas: texture_2d<f32>;
@group(1) @binding(2) var diffuse_maps: texture_2d_array<f32>;
@group(1) @binding(3) var diffuse_map_sampler: sampler;

struct VertexOutput {
    // Invariant, computed exactly as depth.wgsl's vs_main: the equal-depth test needs bit-identical depth.
    @builtin(position) @invariant clip: vec4f,
    //clip_distances: @builtin(clip_distances) clip_distances: array<f32, 1>,
    @location(0) world: vec3f,
    @location(1) @interpolate(flat) surface: u32,
    @location(2) uv: vec2f,
}

@vertex
fn vs_main(@location(0) position: vec3f, @location(1) surface: u32, @location(6) uv: vec2f) -> VertexOutput {
    var out: VertexOutput;
    out.clip = view.view_projection * vec4f(position, 1.0);
    //clip_distances: out.clip_distances[0] = view_clip_distance(position);
    out.world = position;
    out.surface = surface;
    out.uv = uv;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4f {
    // Derivatives in uniform control flow, before any discard.
    let duv_dx = dpdx(in.uv);
    let duv_dy = dpdy(in.uv);
    let rec = surfaces[in.surface];
    if rec.textured == 0u {
        discard;
    }
    let front = dot(view.eye.xyz - in.world, rec.normal) >= 0.0;
    let base = select(rec.layers.zw, rec.layers.xy, front);
    if base.x == NO_LAYER {
        discard;
    }
    let d = in.world - rec.origin;
    let uv = vec2f(dot(d, rec.u_axis), dot(d, rec.v_axis));
    let last = vec2u(rec.columns, rec.rows) - 1u;
    let s = clamp((uv - rec.uv_min) / rec.spacing, vec2f(0.0), vec2f(last));
    let i0 = min(vec2u(floor(s)), last);
    let i1 = min(i0 + 1u, last);
    let f = s - vec2f(i0);
    let l00 = textureLoad(atlas, base + i0, 0).rgb;
    let l10 = textureLoad(atlas, base + vec2u(i1.x, i0.y), 0).rgb;
    let l01 = textureLoad(atlas, base + vec2u(i0.x, i1.y), 0).rgb;
    let l11 = textureLoad(atlas, base + i1, 0).rgb;
    let l = mix(mix(l00, l10, f.x), mix(l01, l11, f.x), f.y);
    if rec.diffuse_map != 0u {
        return vec4f(l * diffuse_tint_grad(rec.diffuse_map, in.uv, duv_dx, duv_dy), 0.0);
    }
    return vec4f(l, 0.0);
}
