// Direct light from point lights (Stürzlinger & Bastos 1997, section 2.2.1,
// "Optimized Rendering Phase": per light, the scene redrawn with per-pixel
// Phong-style shading and a shadow map, added into the framebuffer). The
// scene is redrawn with an equal-depth test against the depth pre-pass, so
// only the visible surface is shaded, and blended One/One into HDR radiance:
//   L += f_r(wi, wo) I(wi) cos(theta_i) / d^2 V.
// Needs the BRDF and material modules before it, material_storage.wgsl
// and diffuse_map.wgsl among them (shaders::with_diffuse_maps). A material
// with a diffuse map has every lobe's kd scaled by the map at the
// fragment's interpolated uv (trilinear, from the uv derivatives).
//
// Notation
// | symbol  | meaning                                                           | unit      |
// |---------|-------------------------------------------------------------------|-----------|
// | P       | world position of the shaded point                                | m         |
// | E       | camera position                                                   | m         |
// | Lp      | light position                                                    | m         |
// | n       | interpolated shading normal, flipped to the viewer's side         | -         |
// | wo, wi  | unit directions P->E and P->Lp (world; local in the n frame)      | -         |
// | d       | |Lp - P|                                                          | m         |
// | I(w)    | intensity towards direction w = -wi, as lustre-geometry's lights  | W/sr      |
// | f_r     | material BRDF, sum of weighted lobes, kd times the diffuse map    | 1/sr      |
// | V       | 1 if d - bias <= the cube map's stored distance along P - Lp     | 1         |
// | bias    | d (c + k (2/size) min(tan theta_i, t_max)), slope-scaled          | m         |
// | L       | radiance added to the HDR target                                  | W/(m² sr) |

const LIGHT_POINT: u32 = 0u;
const LIGHT_ORIENTED_POINT: u32 = 1u;
const LIGHT_SPOT: u32 = 2u;

// Whether V comes from the light's shadow cube. The variant drawn under the
// stencil of shadow volumes (Diefenbach & Badler 1997, sections 4.1 and
// 7.2) is compiled with `false` (direct.rs replaces this exact line): the
// stencil test alone decides visibility, V = 1 wherever it passes.
const SHADOW_MAPS: bool = true;

// Whether the light may pass a window (section 4.5). Lights without one use
// the variant compiled with `false` (direct.rs replaces this exact line):
// llvmpipe runs both sides of a branch on a uniform under a lane mask, so
// every fragment paid for the window's projective texture otherwise.
const WINDOWS: bool = true;

// One point light and its shadow-map lookup parameters (GpuLight in direct.rs).
struct DirectLight {
    position: vec3f,
    kind: u32,
    intensity: vec3f,
    cutoff_angle: f32,
    axis: vec3f,
    beam_width: f32,
    // c: bias relative to d.
    constant_bias: f32,
    // k (2/size): the slope term per unit tan(theta_i).
    slope_bias: f32,
    // t_max: the largest tan(theta_i) the slope term follows.
    max_slope: f32,
    pad: f32,
    window: WindowProjector,
}

// A virtual light through a stained-glass window (Diefenbach & Badler 1997,
// section 4.5; GpuWindow in direct.rs): the slide projector M = M33^-1 P_L
// taking P (in the space the light arrives in) to homogeneous texture
// coordinates (s q, t q, _, q), the window's rectangle X = origin + s u + t v
// and the light it is lit from, in the window's own space.
struct WindowProjector {
    projector: mat4x4f,
    // w: the panes' index of refraction.
    origin: vec4f,
    // w: the texture layer; negative without a window.
    u: vec4f,
    v: vec4f,
    source: vec4f,
}

@group(1) @binding(0) var<storage, read> materials: array<GpuMaterial>;
@group(1) @binding(1) var<uniform> light: DirectLight;
@group(1) @binding(2) var shadow_cube: texture_cube<f32>;
@group(1) @binding(3) var shadow_sampler: sampler;
@group(1) @binding(4) var window_textures: texture_2d_array<f32>;
@group(1) @binding(5) var window_sampler: sampler;
@group(1) @binding(6) var diffuse_maps: texture_2d_array<f32>;
@group(1) @binding(7) var diffuse_map_sampler: sampler;

struct VertexOutput {
    // Invariant, computed exactly as depth.wgsl's vs_main: the equal-depth test needs bit-identical depth.
    @builtin(position) @invariant clip: vec4f,
    //clip_distances: @builtin(clip_distances) clip_distances: array<f32, 1>,
    @location(0) world: vec3f,
    @location(1) normal: vec3f,
    @location(2) @interpolate(flat) material: u32,
    @location(3) uv: vec2f,
}

@vertex
fn vs_main(
    @location(0) position: vec3f,
    @location(2) normal: vec3f,
    @location(3) material: u32,
    @location(6) uv: vec2f,
) -> VertexOutput {
    var out: VertexOutput;
    out.clip = view.view_projection * vec4f(position, 1.0);
    //clip_distances: out.clip_distances[0] = view_clip_distance(position);
    out.world = position;
    out.normal = normal;
    out.material = material;
    out.uv = uv;
    return out;
}

// Mitsuba's spot fall-off: 1 inside the beam width, linear in angle to 0 at the cut-off.
fn spot_falloff(theta: f32) -> f32 {
    if theta <= light.beam_width {
        return 1.0;
    }
    if theta >= light.cutoff_angle {
        return 0.0;
    }
    return (light.cutoff_angle - theta) / (light.cutoff_angle - light.beam_width);
}

// I(w) for the emitted direction w (unit, from the light towards P), as Light::sample_direct.
fn light_intensity(w: vec3f) -> vec3f {
    switch light.kind {
        case LIGHT_ORIENTED_POINT: {
            return light.intensity * max(dot(w, light.axis), 0.0);
        }
        case LIGHT_SPOT: {
            // atan2 of sine and cosine: better conditioned than acos near the axis, and
            // more accurate than some drivers' acos (llvmpipe's is off by ~1e-3 rad).
            let theta = atan2(length(cross(w, light.axis)), dot(w, light.axis));
            return light.intensity * spot_falloff(theta);
        }
        default: {
            return light.intensity;
        }
    }
}

// V: whether P at distance d from the light, lit at cos(theta_i), is nearer than the stored occluder.
fn shadow_visibility(to_point: vec3f, d: f32, cos_i: f32) -> f32 {
    let tan_i = sqrt(max(1.0 - cos_i * cos_i, 0.0)) / cos_i;
    let bias = d * (light.constant_bias + light.slope_bias * min(tan_i, light.max_slope));
    let stored = textureSampleLevel(shadow_cube, shadow_sampler, to_point, 0.0).r;
    return select(0.0, 1.0, d - bias <= stored);
}

// Fresnel reflectance of a smooth dielectric interface of relative index
// eta at |cos theta_i| (lustre-brdf's fresnel_dielectric).
fn window_fresnel(cos_i: f32, eta: f32) -> f32 {
    let c = clamp(abs(cos_i), 0.0, 1.0);
    let sin_t2 = (1.0 - c * c) / (eta * eta);
    if sin_t2 >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt(1.0 - sin_t2);
    let rs = (c - eta * cos_t) / (c + eta * cos_t);
    let rp = (eta * c - cos_t) / (eta * c + cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// What the window passes of the light reaching P (section 4.5): its
// transmittance texture at the texture coordinates P projects to, times the
// thin slab's T = (1 - F)/(1 + F) at the angle the light crossed it.
fn window_transmission(p: vec3f) -> vec3f {
    let w = light.window;
    let h = w.projector * vec4f(p, 1.0);
    if !(h.w > 0.0) {
        return vec3f(0.0);
    }
    let st = h.xy / h.w;
    let texel = textureSampleLevel(window_textures, window_sampler, st, i32(w.u.w), 0.0);
    let x = w.origin.xyz + st.x * w.u.xyz + st.y * w.v.xyz;
    let n = normalize(cross(w.u.xyz, w.v.xyz));
    let cos_i = dot(normalize(x - w.source.xyz), n);
    let f = window_fresnel(cos_i, w.origin.w);
    return texel.rgb * ((1.0 - f) / (1.0 + f));
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4f {
    // Derivatives in uniform control flow, before any early return.
    let duv_dx = dpdx(in.uv);
    let duv_dy = dpdy(in.uv);
    let wo_world = normalize(view.eye.xyz - in.world);
    var n = normalize(in.normal);
    if dot(n, wo_world) < 0.0 {
        n = -n;
    }
    let to_light = light.position - in.world;
    let d = length(to_light);
    let wi_world = to_light / d;
    let cos_i = dot(n, wi_world);
    if !(cos_i > 0.0) {
        return vec4f(0.0);
    }
    var intensity = light_intensity(-wi_world);
    if WINDOWS {
        if light.window.u.w >= 0.0 {
            intensity *= window_transmission(in.world);
        }
    }
    if all(intensity == vec3f(0.0)) {
        return vec4f(0.0);
    }
    var v = 1.0;
    if SHADOW_MAPS {
        v = shadow_visibility(-to_light, d, cos_i);
    }
    let basis = material_basis(n);
    let wi = material_to_local(basis, wi_world);
    let wo = material_to_local(basis, wo_world);
    // One BRDF evaluation: the tint is exactly 1 without a map, and
    // kd * 1 is kd, so this is material_brdf_at bit for bit there
    // (llvmpipe runs both sides of a branch, so two evaluations cost two).
    let layer = materials[in.material].diffuse_map.x;
    let tint = diffuse_tint_grad(layer, in.uv, duv_dx, duv_dy);
    let f = material_brdf_tinted(in.material, wi, wo, tint);
    return vec4f(f * intensity * (cos_i * v / (d * d)), 0.0);
}
