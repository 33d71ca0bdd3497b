// Photon splatting (Stürzlinger & Bastos 1997, sections 2.2 and 3.2): one
// textured triangle per photon hit on the plane of its surface, enclosing the
// kernel support; colour = photon power times the BRDF towards the viewer at
// the photon (evaluated once per splat), times the kernel texture over h^2
// (equation 2 with the 1/h^2 normalisation, see lustre-photon's estimator),
// added into the HDR target. Each splat is restricted to the visible part of
// its own surface either by the surface-id target (fs_splat_id*) or by the
// per-surface stencil mask of section 2.2 (fs_mask, then fs_splat_stencil*).
// On a material with a diffuse map the splat's Lambertian part is scaled by
// the map where the splat lands (the photon's triangle's texture mapping over
// its plane, trilinear with the fragment's derivatives), the rest of its BRDF
// once per splat (lustre-photon's photon_brdf). Prepended: lustre-brdf's
// BRDF twins, common/material.wgsl, common/material_storage.wgsl
// (shaders::with_materials) and common/diffuse_map.wgsl
// (shaders::with_diffuse_maps).
//
// Notation
// | symbol | meaning                                                          | unit       |
// |--------|------------------------------------------------------------------|------------|
// | x_p    | photon hit position (splat centre)                               | m          |
// | n      | surface normal at x_p, flipped to the eye's side                 | -          |
// | wi     | photon's incoming direction, away from the surface               | -          |
// | wo     | unit direction from x_p to the eye                               | -          |
// | phi    | photon power (equation 1)                                        | W          |
// | h      | kernel support of the surface (equation 3)                       | m          |
// | k      | kernel-space offset (x - x_p)/h in the tangent frame of n        | 1          |
// | K      | unit-volume kernel: its formula, or the 64x64 mip-mapped texture | 1          |
// | M      | the kernel's mass on the surface around the fragment (MassGrid)  | 1          |
// | L      | phi f_r(wi, wo) K(k) / (h^2 M), added per pixel                  | W/(m^2 sr) |
// M (lustre-photon's KernelMass, beyond the paper: its future work on the
// appearance of polygon edges) is 1 away from edges and on surfaces without a
// grid, 1/2 along an edge, 1/4 at a square corner: dividing by it undoes the
// part of each kernel that falls off the polygon.
// The triangle has its right angle at k = (-1, -1) and legs of 2 + sqrt(2)
// along the frame's axes: the smallest such triangle whose sides touch the
// unit support disc (section 3.2, figure 1; lustre_photon::splat_triangle).
// The texture covers k in [-1, 1]^2.

struct SplatUniforms {
    // x: unused (the filtering is the pipeline's fragment stage).
    // y: the kernel at the pixel centre: 0 Silverman, 1 truncated Gaussian (lustre-photon's Kernel).
    options: vec4u,
    // xy: vs_splat_low's NDC shift (-1/W, 1/H for a W x H frame), which puts each
    // low-resolution pixel centre on the centre of the full-resolution pixel
    // its guide reads (splat_lowres.wgsl); zw unused.
    low_res_offset: vec4f,
}

@group(1) @binding(0) var<uniform> uniforms: SplatUniforms;
@group(1) @binding(1) var<storage, read> materials: array<GpuMaterial>;
@group(1) @binding(2) var<storage, read> surface_materials: array<u32>;
@group(1) @binding(3) var kernel_texture: texture_2d<f32>;
@group(1) @binding(4) var kernel_sampler: sampler;
@group(1) @binding(5) var surface_ids: texture_2d<u32>;

// One surface's grid of M (GpuMassGrid in splat.rs): sample (i, j) at
// min + (i, j) spacing in the surface's (u, v) frame, values[offset + j columns + i].
struct MassGrid {
    origin: vec3f,
    // NO_MASS_GRID: no grid, M = 1.
    offset: u32,
    u_axis: vec3f,
    columns: u32,
    v_axis: vec3f,
    rows: u32,
    min: vec2f,
    spacing: vec2f,
}

@group(1) @binding(6) var<storage, read> mass_grids: array<MassGrid>;
@group(1) @binding(7) var<storage, read> mass_values: array<f32>;
// The scene's diffuse maps (crates/mpr/src/diffuse_map.rs), read where each splat lands.
@group(1) @binding(8) var diffuse_maps: texture_2d_array<f32>;
@group(1) @binding(9) var diffuse_map_sampler: sampler;

// A triangle's texture mapping over its plane (GpuUvMap in splat.rs):
// uv(x) = (u0, v0) + (du . (x - origin), dv . (x - origin)).
struct UvMap {
    origin: vec3f,
    u0: f32,
    du: vec3f,
    v0: f32,
    dv: vec3f,
    pad: f32,
}

@group(1) @binding(10) var<storage, read> uv_maps: array<UvMap>;

const NO_UV_MAP: u32 = 0xffffffffu;

const NO_MASS_GRID: u32 = 0xffffffffu;
// lustre-photon's MIN_MASS.
const MIN_MASS: f32 = 0.0625;

// The enclosing triangle's corners in kernel units (1 + sqrt 2 = 2.41421356).
const SPLAT_CORNERS = array<vec2f, 3>(
    vec2f(-1.0, -1.0),
    vec2f(2.41421356, -1.0),
    vec2f(-1.0, 2.41421356),
);

struct VertexOutput {
    @builtin(position) clip: vec4f,
    @location(0) kernel: vec2f,
    @location(1) @interpolate(flat) colour: vec3f,
    @location(2) @interpolate(flat) surface: u32,
    // World position of the fragment on the surface's plane.
    @location(3) world: vec3f,
    // The colour's part linear in kd, scaled by the diffuse map (splat_colour).
    @location(4) @interpolate(flat) diffuse: vec3f,
    // Texture coordinates where the fragment lands (the photon's triangle's mapping).
    @location(5) uv: vec2f,
    // The diffuse map's layer; 0 without one (colour alone).
    @location(6) @interpolate(flat) layer: u32,
    //clip_distances: @builtin(clip_distances) clip_distances: array<f32, 1>,
}

@vertex
fn vs_splat(
    @builtin(vertex_index) corner: u32,
    @location(0) position: vec3f,
    @location(1) surface: u32,
    @location(2) incoming: vec3f,
    @location(3) h: f32,
    @location(4) power: vec3f,
    @location(5) normal: vec3f,
    @location(6) uv_map: u32,
) -> VertexOutput {
    return splat_vertex(corner, position, surface, incoming, h, power, normal, uv_map);
}

// One corner of a splat's triangle (vs_splat and vs_splat_low).
fn splat_vertex(
    corner: u32,
    position: vec3f,
    surface: u32,
    incoming: vec3f,
    h: f32,
    power: vec3f,
    normal: vec3f,
    uv_map: u32,
) -> VertexOutput {
    var out: VertexOutput;
    let to_eye = view.eye.xyz - position;
    let wo = normalize(to_eye);
    let n = select(-normal, normal, dot(normal, to_eye) >= 0.0);
    let basis = material_basis(n);
    let k = SPLAT_CORNERS[corner];
    let world = position + h * (k.x * basis[0] + k.y * basis[1]);
    out.clip = view.view_projection * vec4f(world, 1.0);
    //clip_distances: out.clip_distances[0] = view_clip_distance(world);
    out.kernel = k;
    out.world = world;
    let mi = surface_materials[surface];
    let wi_local = material_to_local(basis, incoming);
    let wo_local = material_to_local(basis, wo);
    let f = material_brdf_at(mi, wi_local, wo_local);
    out.colour = power * f / (h * h);
    let layer = materials[mi].diffuse_map.x;
    out.layer = 0u;
    if layer != 0u && uv_map != NO_UV_MAP {
        // The part of the colour linear in kd (the Lambertian part), which
        // the fragment scales by the map at its texture coordinates.
        let kd_part = material_brdf_tinted(mi, wi_local, wo_local, vec3f(1.0))
            - material_brdf_tinted(mi, wi_local, wo_local, vec3f(0.0));
        out.diffuse = power * kd_part / (h * h);
        let m = uv_maps[uv_map];
        let d = world - m.origin;
        out.uv = vec2f(m.u0 + dot(m.du, d), m.v0 + dot(m.dv, d));
        out.layer = layer;
    }
    out.surface = surface;
    return out;
}

// vs_splat for a low-resolution target (lustre_mpr::passes::splat_lowres): the
// same splat moved by low_res_offset in NDC, so that the low-resolution pixel i
// samples the point the full-resolution pixel f i + f/2 sees.
@vertex
fn vs_splat_low(
    @builtin(vertex_index) corner: u32,
    @location(0) position: vec3f,
    @location(1) surface: u32,
    @location(2) incoming: vec3f,
    @location(3) h: f32,
    @location(4) power: vec3f,
    @location(5) normal: vec3f,
    @location(6) uv_map: u32,
) -> VertexOutput {
    var out = splat_vertex(corner, position, surface, incoming, h, power, normal, uv_map);
    out.clip = vec4f(out.clip.xy + uniforms.low_res_offset.xy * out.clip.w, out.clip.zw);
    return out;
}

// Whether a kernel-space offset lies on the texture's square [-1, 1]^2 (K is zero off it).
fn splat_inside(k: vec2f) -> bool {
    return all(abs(k) <= vec2f(1.0));
}

// K averaged over the pixel's footprint: mip-mapped, anisotropic (section 3.2).
// Must run in uniform control flow (implicit derivatives).
fn splat_kernel_filtered(k: vec2f) -> f32 {
    let uv = 0.5 * (k + 1.0);
    // Off the texture K is zero (the select below), so coordinates further
    // than a texture's width off it are clamped there, and a lane's
    // non-finite ones put at its centre: the perspective-correct offset of a
    // quad's lanes beyond a splat seen nearly edge-on can be huge or not
    // finite, and llvmpipe's anisotropic filter steps across all of the
    // footprint that makes (a frame of minutes on some views before the
    // clamp). Quads of ordinary splats keep their coordinates and derivatives.
    let near_texture = select(vec2f(0.5), clamp(uv, vec2f(-1.0), vec2f(2.0)), abs(uv) < vec2f(1.0e30));
    let value = textureSample(kernel_texture, kernel_sampler, near_texture).r;
    return select(0.0, value, splat_inside(k));
}

// Silverman's K2 = 3/pi (1 - r^2)^2 and the truncated Gaussian of sigma 1/(2 sqrt 2)
// renormalised on the unit disc (lustre-photon's Kernel::eval_r2), zero outside it.
const SPLAT_SILVERMAN: f32 = 0.954929658;
const SPLAT_GAUSSIAN_INV_2S2: f32 = 4.0;
const SPLAT_GAUSSIAN_NORM: f32 = 1.296994770;

// K evaluated exactly at the pixel centre, as the CPU estimator does (no texture:
// a texture fetch costs more than the formula on a software rasteriser).
fn splat_kernel_centre(k: vec2f) -> f32 {
    let r2 = dot(k, k);
    if !(r2 < 1.0) {
        return 0.0;
    }
    if uniforms.options.y == 1u {
        return SPLAT_GAUSSIAN_NORM * exp(-SPLAT_GAUSSIAN_INV_2S2 * r2);
    }
    let t = 1.0 - r2;
    return SPLAT_SILVERMAN * t * t;
}

// M at a world point of a surface: bilinear between the four samples around
// its (u, v), clamped to the grid, at least MIN_MASS (KernelMass::at).
fn splat_mass(surface: u32, world: vec3f) -> f32 {
    let g = mass_grids[surface];
    if g.offset == NO_MASS_GRID {
        return 1.0;
    }
    let d = world - g.origin;
    let uv = vec2f(dot(d, g.u_axis), dot(d, g.v_axis));
    let last = vec2u(g.columns, g.rows) - 1u;
    let s = clamp((uv - g.min) / g.spacing, vec2f(0.0), vec2f(last));
    let i0 = min(vec2u(floor(s)), last);
    let i1 = min(i0 + 1u, last);
    let f = s - vec2f(i0);
    let m00 = mass_values[g.offset + i0.y * g.columns + i0.x];
    let m10 = mass_values[g.offset + i0.y * g.columns + i1.x];
    let m01 = mass_values[g.offset + i1.y * g.columns + i0.x];
    let m11 = mass_values[g.offset + i1.y * g.columns + i1.x];
    let m = mix(mix(m00, m10, f.x), mix(m01, m11, f.x), f.y);
    return max(m, MIN_MASS);
}

// The splat's colour at the fragment: its Lambertian part scaled by the diffuse
// map at the fragment's texture coordinates (derivatives taken in uniform
// control flow by the caller), never below zero (lustre-photon's photon_brdf).
// (The fragment's inputs as arguments: the entry points' struct is renamed
// when clip distances are compiled in, shaders::specialise.)
fn splat_colour(colour: vec3f, diffuse: vec3f, uv: vec2f, layer: u32, duv_dx: vec2f, duv_dy: vec2f) -> vec3f {
    if layer == 0u {
        return colour;
    }
    let tint = diffuse_tint_grad(layer, uv, duv_dx, duv_dy);
    return max(colour + diffuse * (tint - vec3f(1.0)), vec3f(0.0));
}

// The four fragment stages are the two restrictions times the two
// filterings (SplatPass builds a pipeline for each): the filtering is chosen
// per pipeline, not by a uniform, because llvmpipe runs both sides of a
// branch on a uniform under a lane mask, so a pixel-centre splat paid for the
// anisotropic textureSample it never used. Its filter loop steps across the
// footprint the derivatives give; on some views that made the splat pass
// hundreds of times slower (BENCHMARKS.md, the notes after the walkthrough).

// Surface-id restriction, the kernel at the pixel centre: the splat adds only
// where its own surface is visible.
@fragment
fn fs_splat_id(in: VertexOutput) -> @location(0) vec4f {
    let duv_dx = dpdx(in.uv);
    let duv_dy = dpdy(in.uv);
    let visible = textureLoad(surface_ids, vec2i(in.clip.xy), 0).r;
    if visible != in.surface || !splat_inside(in.kernel) {
        discard;
    }
    return vec4f(splat_colour(in.colour, in.diffuse, in.uv, in.layer, duv_dx, duv_dy) * splat_kernel_centre(in.kernel) / splat_mass(in.surface, in.world), 0.0);
}

// Surface-id restriction, the kernel mip-mapped: sampled in uniform control
// flow (implicit derivatives), before the restriction discards.
@fragment
fn fs_splat_id_mip(in: VertexOutput) -> @location(0) vec4f {
    let duv_dx = dpdx(in.uv);
    let duv_dy = dpdy(in.uv);
    let visible = textureLoad(surface_ids, vec2i(in.clip.xy), 0).r;
    let value = splat_kernel_filtered(in.kernel);
    if visible != in.surface {
        discard;
    }
    return vec4f(splat_colour(in.colour, in.diffuse, in.uv, in.layer, duv_dx, duv_dy) * value / splat_mass(in.surface, in.world), 0.0);
}

// Stencil restriction, the kernel at the pixel centre: the stencil test has
// already limited the splat to its surface's mask.
@fragment
fn fs_splat_stencil(in: VertexOutput) -> @location(0) vec4f {
    let duv_dx = dpdx(in.uv);
    let duv_dy = dpdy(in.uv);
    if !splat_inside(in.kernel) {
        discard;
    }
    return vec4f(splat_colour(in.colour, in.diffuse, in.uv, in.layer, duv_dx, duv_dy) * splat_kernel_centre(in.kernel) / splat_mass(in.surface, in.world), 0.0);
}

// Stencil restriction, the kernel mip-mapped.
@fragment
fn fs_splat_stencil_mip(in: VertexOutput) -> @location(0) vec4f {
    let duv_dx = dpdx(in.uv);
    let duv_dy = dpdy(in.uv);
    return vec4f(splat_colour(in.colour, in.diffuse, in.uv, in.layer, duv_dx, duv_dy) * splat_kernel_filtered(in.kernel) / splat_mass(in.surface, in.world), 0.0);
}

// The per-surface stencil mask: the surface's triangles drawn with an equal-depth
// test (vertex stage: the depth pre-pass's vs_main); colour writes are masked off.
@fragment
fn fs_mask() -> @location(0) vec4f {
    return vec4f(0.0);
}
