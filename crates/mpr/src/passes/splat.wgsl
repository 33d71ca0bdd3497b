// Photon splatting (Stürzlinger & Bastos 1997, sections 2.2 and 3.2): one
// textured triangle per photon hit on the plane of its surface, enclosing the
// kernel support; colour = photon power times the BRDF towards the viewer at
// the photon (evaluated once per splat), times the kernel texture over h^2
// (equation 2 with the 1/h^2 normalisation, see lustre-photon's estimator),
// added into the HDR target. Each splat is restricted to the visible part of
// its own surface either by the surface-id target (fs_splat_id) or by the
// per-surface stencil mask of section 2.2 (fs_mask, then fs_splat_stencil).
// Prepended: lustre-brdf's BRDF twins and common/material.wgsl.
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
// | K      | unit-volume kernel, sampled from the 64x64 mip-mapped texture    | 1          |
// | L      | phi f_r(wi, wo) K(k) / h^2, added per pixel                      | W/(m^2 sr) |
// The triangle has its right angle at k = (-1, -1) and legs of 2 + sqrt(2)
// along the frame's axes: the smallest such triangle whose sides touch the
// unit support disc (section 3.2, figure 1). The texture covers k in [-1, 1]^2.

struct SplatUniforms {
    view_projection: mat4x4f,
    eye: vec4f,
    // x: 1 to filter the kernel with mip-maps and anisotropy (section 3.2), 0 to point-sample level 0.
    options: vec4u,
}

@group(0) @binding(0) var<uniform> uniforms: SplatUniforms;
@group(0) @binding(1) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(2) var<storage, read> surface_materials: array<u32>;
@group(0) @binding(3) var kernel_texture: texture_2d<f32>;
@group(0) @binding(4) var kernel_sampler: sampler;
@group(0) @binding(5) var surface_ids: texture_2d<u32>;
@group(0) @binding(6) var kernel_point_sampler: sampler;

// The enclosing triangle's corners in kernel units (1 + sqrt 2 = 2.41421356).
const SPLAT_CORNERS = array<vec2f, 3>(
    vec2f(-1.0, -1.0),
    vec2f(2.41421356, -1.0),
    vec2f(-1.0, 2.41421356),
);

struct SplatOut {
    @builtin(position) clip: vec4f,
    @location(0) kernel: vec2f,
    @location(1) @interpolate(flat) colour: vec3f,
    @location(2) @interpolate(flat) surface: u32,
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
) -> SplatOut {
    var out: SplatOut;
    let to_eye = uniforms.eye.xyz - position;
    let wo = normalize(to_eye);
    let n = select(-normal, normal, dot(normal, to_eye) >= 0.0);
    let basis = material_basis(n);
    let k = SPLAT_CORNERS[corner];
    let world = position + h * (k.x * basis[0] + k.y * basis[1]);
    out.clip = uniforms.view_projection * vec4f(world, 1.0);
    out.kernel = k;
    let m = materials[surface_materials[surface]];
    let f = material_brdf(m, material_to_local(basis, incoming), material_to_local(basis, wo));
    out.colour = power * f / (h * h);
    out.surface = surface;
    return out;
}

// Whether a kernel-space offset lies on the texture's square [-1, 1]^2 (K is zero off it).
fn splat_inside(k: vec2f) -> bool {
    return all(abs(k) <= vec2f(1.0));
}

// K averaged over the pixel's footprint: mip-mapped, anisotropic (section 3.2).
// Must run in uniform control flow (implicit derivatives).
fn splat_kernel_filtered(k: vec2f) -> f32 {
    let value = textureSample(kernel_texture, kernel_sampler, 0.5 * (k + 1.0)).r;
    return select(0.0, value, splat_inside(k));
}

// K at the pixel centre: bilinear from level 0, as the CPU estimator evaluates it.
fn splat_kernel_centre(k: vec2f) -> f32 {
    let value = textureSampleLevel(kernel_texture, kernel_point_sampler, 0.5 * (k + 1.0), 0.0).r;
    return select(0.0, value, splat_inside(k));
}

// Surface-id restriction: the splat adds only where its own surface is visible.
// The filtering choice is uniform, so the mip-mapped branch may use derivatives;
// the centre branch rejects other surfaces before it reads the texture.
@fragment
fn fs_splat_id(in: SplatOut) -> @location(0) vec4f {
    let visible = textureLoad(surface_ids, vec2i(in.clip.xy), 0).r;
    if uniforms.options.x != 0u {
        let value = splat_kernel_filtered(in.kernel);
        if visible != in.surface {
            discard;
        }
        return vec4f(in.colour * value, 0.0);
    }
    if visible != in.surface || !splat_inside(in.kernel) {
        discard;
    }
    return vec4f(in.colour * splat_kernel_centre(in.kernel), 0.0);
}

// Stencil restriction: the stencil test has already limited the splat to its surface's mask.
@fragment
fn fs_splat_stencil(in: SplatOut) -> @location(0) vec4f {
    if uniforms.options.x != 0u {
        return vec4f(in.colour * splat_kernel_filtered(in.kernel), 0.0);
    }
    if !splat_inside(in.kernel) {
        discard;
    }
    return vec4f(in.colour * splat_kernel_centre(in.kernel), 0.0);
}

// The per-surface stencil mask: the surface's triangles drawn with an equal-depth
// test (vertex stage: the depth pre-pass's vs_main); colour writes are masked off.
@fragment
fn fs_mask() -> @location(0) vec4f {
    return vec4f(0.0);
}
