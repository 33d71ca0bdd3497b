// Materials as weighted lobes (crates/mpr/src/material.rs), evaluated with the
// WGSL twins of lustre-brdf (crates/brdf/src/shaders/brdf.wgsl, prepended).
//
// Notation
// | symbol | meaning                                                         | unit |
// |--------|-----------------------------------------------------------------|------|
// | wi     | unit direction towards the light, local frame, away from surface | -    |
// | wo     | unit direction towards the viewer, local frame                  | -    |
// | +Z     | the shading normal, flipped to the viewer's side                 | -    |
// | w      | lobe weight (blend weights multiplied out)                       | 1    |
// | f      | BRDF without the cosine factor, sum of w f_lobe                 | 1/sr |
// Delta lobes (mirror, smooth dielectric) evaluate to zero, as on the CPU.

const LOBE_NONE: u32 = 0u;
const LOBE_LAMBERT: u32 = 1u;
const LOBE_MODIFIED_PHONG: u32 = 2u;
const LOBE_WARD: u32 = 3u;
const LOBE_COOK_TORRANCE: u32 = 4u;
const LOBE_COOK_TORRANCE_F1: u32 = 5u;
const LOBE_DIEFENBACH_PHONG: u32 = 6u;
const LOBE_DELTA: u32 = 7u;
const MAX_LOBES: u32 = 4u;

struct GpuLobe {
    kind: u32,
    weight: f32,
    pad: vec2f,
    kd: vec4f,
    ks: vec4f,
    params: vec4f,
    eta: vec4f,
    k: vec4f,
}

struct GpuMaterial {
    lobes: array<GpuLobe, 4>,
    // x: layer of the diffuse map in diffuse_maps (0: none, the white layer); yzw unused.
    diffuse_map: vec4u,
}

// Cook-Torrance with Beckmann D, Smith G and F = 1 (a rough mirror).
fn material_cook_torrance_f1(wi: vec3f, wo: vec3f, ks: vec3f, alpha: f32) -> vec3f {
    if !brdf_same_upper(wi, wo) {
        return vec3f(0.0);
    }
    let h = normalize(wi + wo);
    let d = brdf_beckmann_d(h, alpha);
    if d == 0.0 {
        return vec3f(0.0);
    }
    let g = brdf_beckmann_smith_g1(wi, h, alpha) * brdf_beckmann_smith_g1(wo, h, alpha);
    return ks * (d * g / (4.0 * wi.z * wo.z));
}

// One lobe's f(wi, wo).
fn material_lobe(l: GpuLobe, wi: vec3f, wo: vec3f) -> vec3f {
    return material_lobe_kd(l, l.kd.xyz, wi, wo);
}

// One lobe's f(wi, wo) with kd in place of its own (kd times a diffuse map's tint).
fn material_lobe_kd(l: GpuLobe, kd: vec3f, wi: vec3f, wo: vec3f) -> vec3f {
    switch l.kind {
        case LOBE_LAMBERT: {
            return brdf_lambert(wi, wo, kd);
        }
        case LOBE_MODIFIED_PHONG: {
            return brdf_modified_phong(wi, wo, kd, l.ks.xyz, l.params.x);
        }
        case LOBE_WARD: {
            return brdf_ward_isotropic(wi, wo, kd, l.ks.xyz, l.params.x);
        }
        case LOBE_COOK_TORRANCE: {
            return brdf_cook_torrance_beckmann(wi, wo, vec3f(0.0), l.ks.xyz, l.params.x, l.eta.xyz, l.k.xyz);
        }
        case LOBE_COOK_TORRANCE_F1: {
            return material_cook_torrance_f1(wi, wo, l.ks.xyz, l.params.x);
        }
        case LOBE_DIEFENBACH_PHONG: {
            return brdf_diefenbach_phong(wi, wo, kd, l.ks.xyz, l.params.x, l.params.y, l.params.z);
        }
        default: {
            return vec3f(0.0);
        }
    }
}

// A right-handed orthonormal basis around unit n (Duff et al. 2017), for world-to-local.
fn material_basis(n: vec3f) -> mat3x3f {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t = vec3f(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let bt = vec3f(b, s + n.y * n.y * a, -n.y);
    return mat3x3f(t, bt, n);
}

// A world direction in the local frame of basis m (columns: tangent, bitangent, normal).
fn material_to_local(m: mat3x3f, w: vec3f) -> vec3f {
    return vec3f(dot(w, m[0]), dot(w, m[1]), dot(w, m[2]));
}
