// lustre-brdf: WGSL twins of the Rust BRDF models (crates/brdf/src/models).
//
// Notation
// | symbol        | meaning                                                        |
// |---------------|----------------------------------------------------------------|
// | wi            | unit direction towards the light, local frame, away from surface |
// | wo            | unit direction towards the viewer, local frame                 |
// | +Z            | the shading normal; +X the tangent                             |
// | f             | the BRDF in 1/sr, without the cosine factor                    |
// | h             | half vector wi + wo (normalised unless said otherwise)         |
// Every function returns zero unless wi.z > 0 and wo.z > 0 (reflection only).
// No bindings, no entry points: prepend this module to a shader that uses it.

const BRDF_PI: f32 = 3.14159265358979;
const BRDF_INV_PI: f32 = 0.318309886183791;

// Whether both directions lie strictly in the upper hemisphere.
fn brdf_same_upper(wi: vec3f, wo: vec3f) -> bool {
    return wi.z > 0.0 && wo.z > 0.0;
}

// Mirror direction of w about +Z.
fn brdf_reflect_z(w: vec3f) -> vec3f {
    return vec3f(-w.x, -w.y, w.z);
}

// x^n for x >= 0 with 0^0 = 1 and 0^n = 0 (Rust's powf on the same range).
fn brdf_pow(x: f32, n: f32) -> f32 {
    if x <= 0.0 {
        return select(0.0, 1.0, n == 0.0);
    }
    return pow(x, n);
}

// Lambert 1760: f = rho / pi.
fn brdf_lambert(wi: vec3f, wo: vec3f, reflectance: vec3f) -> vec3f {
    if !brdf_same_upper(wi, wo) {
        return vec3f(0.0);
    }
    return reflectance * BRDF_INV_PI;
}

// Lafortune & Willems 1994, equation 4: f = kd/pi + ks (n + 2)/(2 pi) cos^n(alpha),
// alpha the angle between wi and the mirror direction of wo.
fn brdf_modified_phong(wi: vec3f, wo: vec3f, kd: vec3f, ks: vec3f, n: f32) -> vec3f {
    if !brdf_same_upper(wi, wo) {
        return vec3f(0.0);
    }
    let cos_alpha = max(dot(wi, brdf_reflect_z(wo)), 0.0);
    return kd * BRDF_INV_PI + ks * ((n + 2.0) * 0.5 * BRDF_INV_PI * brdf_pow(cos_alpha, n));
}

// Diefenbach & Badler 1997, equation 6 as a BRDF:
// f = kd/pi + c (b/alpha^2) ks cos(delta)^(b/alpha^2) / cos(theta_i),
// with the paper's c = 0.0398 and b = 1.999 unless a fit gives others.
fn brdf_diefenbach_phong(wi: vec3f, wo: vec3f, kd: vec3f, ks: vec3f, alpha: f32, c: f32, b: f32) -> vec3f {
    if !brdf_same_upper(wi, wo) {
        return vec3f(0.0);
    }
    let n = b / (alpha * alpha);
    let cos_delta = clamp(normalize(wi + wo).z, 0.0, 1.0);
    let hardware = c * n * brdf_pow(cos_delta, n);
    return kd * BRDF_INV_PI + ks * (hardware / wi.z);
}

// Ward 1992, equations 4-5, isotropic, original normalisation:
// f = kd/pi + ks exp(-tan^2(theta_h)/alpha^2) / (4 pi alpha^2 sqrt(cos_i cos_o)).
fn brdf_ward_isotropic(wi: vec3f, wo: vec3f, kd: vec3f, ks: vec3f, alpha: f32) -> vec3f {
    if !brdf_same_upper(wi, wo) {
        return vec3f(0.0);
    }
    let h = wi + wo;
    let a2 = alpha * alpha;
    let e = exp(-(h.x * h.x + h.y * h.y) / (a2 * h.z * h.z));
    let norm = 1.0 / (4.0 * BRDF_PI * a2 * sqrt(wi.z * wo.z));
    return kd * BRDF_INV_PI + ks * (norm * e);
}

// Beckmann's distribution exp(-tan^2/alpha^2) / (pi alpha^2 cos^4) (Walter et al. 2007, equation 25).
fn brdf_beckmann_d(h: vec3f, alpha: f32) -> f32 {
    let c = h.z;
    if c <= 0.0 {
        return 0.0;
    }
    let c2 = c * c;
    let t2 = max(max(1.0 - c2, 0.0) / c2, 0.0);
    let a2 = alpha * alpha;
    return exp(-t2 / a2) * BRDF_INV_PI / (a2 * c2 * c2);
}

// Smith's G1 for Beckmann, rational fit (Walter et al. 2007, equation 27).
fn brdf_beckmann_smith_g1(v: vec3f, h: vec3f, alpha: f32) -> f32 {
    if dot(v, h) * v.z <= 0.0 {
        return 0.0;
    }
    let c2 = v.z * v.z;
    let t2 = max(1.0 - c2, 0.0) / c2;
    if t2 == 0.0 {
        return 1.0;
    }
    let a = 1.0 / (alpha * sqrt(t2));
    if a >= 1.6 {
        return 1.0;
    }
    return (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
}

// One channel of the exact unpolarised conductor Fresnel reflectance with complex index eta + i k
// (Born & Wolf section 14.2; the a^2 + b^2 form of pbrt-v3 section 8.2.1).
fn brdf_fresnel_conductor_scalar(cos_i: f32, eta: f32, k: f32) -> f32 {
    let c = clamp(cos_i, 0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let t0 = eta * eta - k * k - s2;
    let a2b2 = sqrt(t0 * t0 + 4.0 * eta * eta * k * k);
    let a = sqrt(max(0.5 * (a2b2 + t0), 0.0));
    let rs_den = a2b2 + c2 + 2.0 * a * c;
    var rs = 1.0;
    if rs_den > 0.0 {
        rs = (a2b2 + c2 - 2.0 * a * c) / rs_den;
    }
    let rp_den = c2 * a2b2 + s2 * s2 + 2.0 * a * c * s2;
    var rp = rs;
    if rp_den > 0.0 {
        rp = rs * (c2 * a2b2 + s2 * s2 - 2.0 * a * c * s2) / rp_den;
    }
    return 0.5 * (rs + rp);
}

// Conductor Fresnel per RGB channel.
fn brdf_fresnel_conductor(cos_i: f32, eta: vec3f, k: vec3f) -> vec3f {
    return vec3f(
        brdf_fresnel_conductor_scalar(cos_i, eta.x, k.x),
        brdf_fresnel_conductor_scalar(cos_i, eta.y, k.y),
        brdf_fresnel_conductor_scalar(cos_i, eta.z, k.z),
    );
}

// Cook & Torrance 1982 with Beckmann D, Smith G and a conductor F, normalised as Walter et al. 2007 equation 20:
// f = kd/pi + ks F(wi.h) D(h) G1(wi) G1(wo) / (4 cos_i cos_o).
fn brdf_cook_torrance_beckmann(wi: vec3f, wo: vec3f, kd: vec3f, ks: vec3f, alpha: f32, eta: vec3f, k: vec3f) -> vec3f {
    if !brdf_same_upper(wi, wo) {
        return vec3f(0.0);
    }
    let h = normalize(wi + wo);
    let d = brdf_beckmann_d(h, alpha);
    var spec = vec3f(0.0);
    if d != 0.0 {
        let g = brdf_beckmann_smith_g1(wi, h, alpha) * brdf_beckmann_smith_g1(wo, h, alpha);
        let f = brdf_fresnel_conductor(dot(wi, h), eta, k);
        spec = ks * f * (d * g / (4.0 * wi.z * wo.z));
    }
    return kd * BRDF_INV_PI + spec;
}
