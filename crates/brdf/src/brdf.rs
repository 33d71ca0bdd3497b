//! The [`Brdf`] trait, its sample record and the helpers shared by the models.
//!
//! All directions are unit vectors in the local shading frame (+Z is the
//! normal, +X the tangent that anisotropic models align with) and both point
//! away from the surface: `wi` towards the light, `wo` towards the viewer
//! (Nicodemus et al. 1977, "Geometrical considerations and nomenclature for
//! reflectance", NBS monograph 160).

use std::fmt::Debug;

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;
use lustre_geometry::sampling::{Frame, cosine_hemisphere_pdf, sample_cosine_hemisphere};

/// One direction drawn by [`Brdf::sample`] (Veach 1997, section 9.2: the estimator `f cos / pdf`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrdfSample {
    /// The sampled incident direction, local frame, pointing away from the surface.
    pub wi: Vec3,
    /// `f(wi, wo) |cos θi| / pdf` for a smooth lobe; for a delta lobe the lobe's reflectance (or transmittance) divided by the discrete probability `pdf`.
    pub weight: Rgb,
    /// Solid-angle density of `wi` for a smooth lobe; for a delta lobe the discrete probability of having chosen it.
    pub pdf: f32,
    /// Whether `wi` comes from a Dirac delta lobe (perfect mirror or refraction), which [`Brdf::eval`] and [`Brdf::pdf`] leave out.
    pub delta: bool,
}

/// A bidirectional reflectance (or scattering) distribution function in the local shading frame (Nicodemus et al. 1977, equation 3).
///
/// `eval` and `pdf` describe only the smooth part of the function; Dirac
/// lobes (perfect mirrors and refraction) are reached through `sample` alone,
/// which flags them with [`BrdfSample::delta`]. Implementations never panic
/// on any direction: directions on the wrong side give zero.
pub trait Brdf: Debug + Send + Sync {
    /// The model's kebab-case name, as accepted by `MaterialModel::Named` (see [`crate::from_model`]).
    fn name(&self) -> &'static str;

    /// `f(wi, wo)` in 1/sr, without the cosine factor; zero for directions the smooth part does not reach (Nicodemus et al. 1977, equation 3).
    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb;

    /// Draws `wi` given `wo` from two uniform numbers `u` for the direction and one `u_lobe` for the choice of lobe; `None` when the draw lands where the BRDF is zero (Veach 1997, section 9.2).
    fn sample(&self, wo: Vec3, u: Vec2, u_lobe: f32) -> Option<BrdfSample>;

    /// Solid-angle density with which [`Brdf::sample`] draws the smooth direction `wi` given `wo` (delta lobes excluded) (Veach 1997, section 9.2).
    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32;

    /// Draws the direction `wo` into which light arriving from `wi` scatters, for particle tracing: the adjoint BSDF `f*(wo, wi) = f(wi, wo)` (Veach 1997, sections 3.7.6 and 5.3.2).
    ///
    /// The returned record's `wi` field holds the sampled *outgoing*
    /// direction `wo`, and `weight = f(wi, wo) |cos θo| / pdf`, so that
    /// `E[weight] = ∫ f(wi, wo) |cos θo| dωo`, the fraction of the power
    /// arriving from `wi` that the surface scatters. The proposal is
    /// [`Brdf::sample`] with the roles swapped (its `pdf` is the density of
    /// the drawn direction); a reciprocal model keeps its weight, a
    /// non-reciprocal one is reweighted with `f(wi, wo)` in the radiance
    /// order. Delta lobes are returned as drawn (refraction's `η²` scaling
    /// of radiance is not applied).
    fn sample_adjoint(&self, wi: Vec3, u: Vec2, u_lobe: f32) -> Option<BrdfSample> {
        let s = self.sample(wi, u, u_lobe)?;
        if s.delta || self.is_reciprocal() {
            return Some(s);
        }
        if !is_positive(s.pdf) {
            return None;
        }
        Some(BrdfSample {
            weight: self.eval(wi, s.wi) * s.wi.z.abs() / s.pdf,
            ..s
        })
    }

    /// Directional albedo `∫ f(wi, wo) |cos θi| dωi`, delta lobes included, by stratified quasi-Monte Carlo integration of [`Brdf::sample`] (Nicodemus et al. 1977, directional-hemispherical reflectance).
    fn albedo(&self, wo: Vec3) -> Rgb {
        sampled_albedo(self, wo, ALBEDO_STRATA)
    }

    /// Whether `f(wi, wo) = f(wo, wi)` holds for the smooth part (Helmholtz reciprocity).
    fn is_reciprocal(&self) -> bool;

    /// Whether the albedo is at most one for every `wo` whenever the parameters pass construction (energy conservation).
    fn is_energy_conserving(&self) -> bool;

    /// Whether the function has a Dirac delta lobe, reachable only through [`Brdf::sample`].
    fn has_delta(&self) -> bool {
        false
    }

    /// Whether the function scatters into the lower hemisphere (refraction), so `wi.z < 0` can be returned.
    fn transmits(&self) -> bool {
        false
    }

    /// Whether the surface scatters alike seen from either side, so a tracer may turn the frame to the side light arrives from; false for a model that tells the medium's inside (`z < 0`) from its outside, as a smooth dielectric does.
    fn is_two_sided(&self) -> bool {
        true
    }
}

/// Number of strata per axis of [`sampled_albedo`] (32 × 32 = 1024 samples).
pub const ALBEDO_STRATA: usize = 32;

/// Directional albedo estimated with `strata²` stratified samples of `brdf.sample` (Veach 1997, section 2.7 stratified sampling); `u_lobe` follows a golden-ratio sequence.
pub fn sampled_albedo<B: Brdf + ?Sized>(brdf: &B, wo: Vec3, strata: usize) -> Rgb {
    let strata = strata.max(1);
    let n = strata * strata;
    let mut sum = Rgb::ZERO;
    let golden = 0.618_034_f32;
    for j in 0..strata {
        for i in 0..strata {
            let k = j * strata + i;
            let u = Vec2::new(
                (i as f32 + 0.5) / strata as f32,
                (j as f32 + 0.5) / strata as f32,
            );
            let u_lobe = ((k as f32 + 0.5) * golden).fract();
            if let Some(s) = brdf.sample(wo, u, u_lobe) {
                if s.weight.is_finite() {
                    sum += s.weight;
                }
            }
        }
    }
    sum / n as f32
}

/// Luminance-like scalar of an RGB weight, used to pick lobes: the mean of the channels.
pub(crate) fn mean(c: Rgb) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

/// Mirror direction of `w` about the normal `n` (`2 (w·n) n - w`), Phong 1975.
pub(crate) fn reflect(w: Vec3, n: Vec3) -> Vec3 {
    2.0 * w.dot(n) * n - w
}

/// Mirror direction of `w` about +Z.
pub(crate) fn reflect_z(w: Vec3) -> Vec3 {
    Vec3::new(-w.x, -w.y, w.z)
}

/// Density of [`sample_cos_power_lobe`]: `(n + 1) / (2π) cos^n α` for `cos α > 0`, else 0.
pub(crate) fn cos_power_lobe_pdf(cos_alpha: f32, exponent: f32) -> f32 {
    if cos_alpha <= 0.0 {
        return 0.0;
    }
    (exponent + 1.0) * 0.5 * std::f32::consts::FRAC_1_PI * cos_alpha.powf(exponent)
}

/// Direction around the unit `axis` with density `(n + 1)/(2π) cos^n α` (Lafortune & Willems 1994, section 4: `cos α = u^(1/(n+1))`).
pub(crate) fn sample_cos_power_lobe(axis: Vec3, exponent: f32, u: Vec2) -> Vec3 {
    let cos_alpha = u.x.powf(1.0 / (exponent + 1.0));
    let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u.y;
    let local = Vec3::new(sin_alpha * phi.cos(), sin_alpha * phi.sin(), cos_alpha);
    Frame::from_normal(axis).to_world(local).normalize()
}

/// Whether both directions lie strictly in the upper hemisphere (reflection-only models).
pub(crate) fn same_upper(wi: Vec3, wo: Vec3) -> bool {
    wi.z > 0.0 && wo.z > 0.0
}

/// Cosine-weighted hemisphere sampling for models without a closed-form
/// inverse (Malley's method): `None` below the horizon, else the sample with
/// weight `eval · cos / pdf` from [`finish_sample`].
pub(crate) fn sample_cosine<B: Brdf + ?Sized>(brdf: &B, wo: Vec3, u: Vec2) -> Option<BrdfSample> {
    if wo.z <= 0.0 {
        return None;
    }
    finish_sample(brdf, sample_cosine_hemisphere(u), wo)
}

/// The density of [`sample_cosine`]: cos θi / π when both directions are above the surface.
pub(crate) fn cosine_pdf(wi: Vec3, wo: Vec3) -> f32 {
    if !same_upper(wi, wo) {
        return 0.0;
    }
    cosine_hemisphere_pdf(wi.z)
}

/// Finishes a smooth sample: rejects the lower hemisphere and zero densities, and sets weight = `eval · cos / pdf` from the full model (the one-sample mixture estimator of Veach 1997, section 9.2.4).
pub(crate) fn finish_sample<B: Brdf + ?Sized>(brdf: &B, wi: Vec3, wo: Vec3) -> Option<BrdfSample> {
    if wi.z <= 0.0 || !wi.is_finite() {
        return None;
    }
    let pdf = brdf.pdf(wi, wo);
    if !is_positive(pdf) {
        return None;
    }
    let weight = brdf.eval(wi, wo) * wi.z / pdf;
    Some(BrdfSample {
        wi,
        weight,
        pdf,
        delta: false,
    })
}

/// Samples the mixture "cosine hemisphere with probability `p_diffuse`, else `lobe`": chooses with `u_lobe`, then weights by the whole model (Veach 1997, section 9.2.4).
pub(crate) fn sample_diffuse_or<B: Brdf + ?Sized>(
    brdf: &B,
    wo: Vec3,
    u: Vec2,
    u_lobe: f32,
    p_diffuse: f32,
    lobe: impl FnOnce(Vec2) -> Option<Vec3>,
) -> Option<BrdfSample> {
    if wo.z <= 0.0 {
        return None;
    }
    let wi = if u_lobe < p_diffuse {
        sample_cosine_hemisphere(u)
    } else {
        lobe(u)?
    };
    finish_sample(brdf, wi, wo)
}

/// Density of the mixture drawn by [`sample_diffuse_or`]: `p_d cos θi / π + (1 - p_d) p_lobe`.
pub(crate) fn diffuse_or_pdf(wi: Vec3, p_diffuse: f32, lobe_pdf: f32) -> f32 {
    p_diffuse * cosine_hemisphere_pdf(wi.z) + (1.0 - p_diffuse) * lobe_pdf
}

/// The cosine hemisphere mixed with a cosⁿ lobe about the mirror direction
/// of `wo` (Phong's lobe, sampled as in Lafortune & Willems 1994): the sample.
pub(crate) fn sample_mirror_lobe_mixture<B: Brdf + ?Sized>(
    brdf: &B,
    wo: Vec3,
    u: Vec2,
    u_lobe: f32,
    p_diffuse: f32,
    exponent: f32,
) -> Option<BrdfSample> {
    sample_diffuse_or(brdf, wo, u, u_lobe, p_diffuse, |u| {
        Some(sample_cos_power_lobe(reflect_z(wo), exponent, u))
    })
}

/// Density of [`sample_mirror_lobe_mixture`].
pub(crate) fn mirror_lobe_mixture_pdf(wi: Vec3, wo: Vec3, p_diffuse: f32, exponent: f32) -> f32 {
    if !same_upper(wi, wo) {
        return 0.0;
    }
    let lobe = cos_power_lobe_pdf(wi.dot(reflect_z(wo)), exponent);
    diffuse_or_pdf(wi, p_diffuse, lobe)
}

/// The cosine hemisphere mixed with a cosⁿ lobe of half vectors about the
/// normal, reflected into `wi` (Blinn's lobe): the sample.
pub(crate) fn sample_half_vector_mixture<B: Brdf + ?Sized>(
    brdf: &B,
    wo: Vec3,
    u: Vec2,
    u_lobe: f32,
    p_diffuse: f32,
    exponent: f32,
) -> Option<BrdfSample> {
    sample_diffuse_or(brdf, wo, u, u_lobe, p_diffuse, |u| {
        let h = sample_cos_power_lobe(Vec3::Z, exponent, u);
        if h.dot(wo) <= 0.0 {
            return None;
        }
        Some(reflect(wo, h))
    })
}

/// Density of [`sample_half_vector_mixture`]: the half-vector density times the Jacobian `1 / (4 wo·h)`.
pub(crate) fn half_vector_mixture_pdf(wi: Vec3, wo: Vec3, p_diffuse: f32, exponent: f32) -> f32 {
    if !same_upper(wi, wo) {
        return 0.0;
    }
    let h = (wi + wo).normalize();
    let lobe = cos_power_lobe_pdf(h.z, exponent) / (4.0 * wo.dot(h));
    diffuse_or_pdf(wi, p_diffuse, lobe)
}

/// Probability of choosing the diffuse lobe given the mean diffuse and lobe reflectances (a balance heuristic on albedo, Veach 1997 section 9.2).
pub(crate) fn diffuse_probability(diffuse: Rgb, lobe: Rgb) -> f32 {
    let d = mean(diffuse).max(0.0);
    let s = mean(lobe).max(0.0);
    if d + s <= 0.0 { 1.0 } else { d / (d + s) }
}

/// Whether `v` is finite and strictly positive (false for NaN).
pub(crate) fn is_positive(v: f32) -> bool {
    v.is_finite() && v > 0.0
}

/// Whether `v` is finite and at least zero (false for NaN).
pub(crate) fn is_non_negative(v: f32) -> bool {
    v.is_finite() && v >= 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::Phong;

    /// `∫ f(wi, wo) cos θo dωo` over the upper hemisphere by the midpoint rule in (θo, φo).
    fn adjoint_albedo_quadrature(brdf: &dyn Brdf, wi: Vec3) -> Rgb {
        let (nt, np) = (600, 1200);
        let (dt, dp) = (
            std::f64::consts::FRAC_PI_2 / nt as f64,
            std::f64::consts::TAU / np as f64,
        );
        let mut sum = [0.0f64; 3];
        for i in 0..nt {
            let t = (i as f64 + 0.5) * dt;
            for j in 0..np {
                let p = (j as f64 + 0.5) * dp;
                let wo = Vec3::new(
                    (t.sin() * p.cos()) as f32,
                    (t.sin() * p.sin()) as f32,
                    t.cos() as f32,
                );
                let f = brdf.eval(wi, wo);
                let w = t.cos() * t.sin() * dt * dp;
                for c in 0..3 {
                    sum[c] += f64::from(f[c]) * w;
                }
            }
        }
        Rgb::new(sum[0] as f32, sum[1] as f32, sum[2] as f32)
    }

    /// Mean and standard error of the red channel of `draw`'s weights over stratified numbers.
    fn mean_weight(draw: impl Fn(Vec2, f32) -> Option<BrdfSample>) -> (f64, f64) {
        let strata = 256;
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        for j in 0..strata {
            for i in 0..strata {
                let k = j * strata + i;
                let u = Vec2::new(
                    (i as f32 + 0.5) / strata as f32,
                    (j as f32 + 0.5) / strata as f32,
                );
                let u_lobe = ((k as f32 + 0.5) * 0.618_034).fract();
                let w = draw(u, u_lobe).map_or(0.0, |s| f64::from(s.weight.x));
                s1 += w;
                s2 += w * w;
            }
        }
        let n = (strata * strata) as f64;
        let mean = s1 / n;
        (mean, ((s2 / n - mean * mean).max(0.0) / n).sqrt())
    }

    /// The adjoint sampler's weights average to `∫ f(wi, wo) cos θo dωo` (Veach 1997, section 3.7.6) for Phong's non-reciprocal model, which the plain sampler (weighting with `f(wo, wi)`) misses.
    #[test]
    fn adjoint_sampling_integrates_the_radiance_order_brdf() {
        let phong = Phong::new(Rgb::splat(0.1), Rgb::splat(0.5), 2.0).unwrap();
        let theta = 60f32.to_radians();
        let wi = Vec3::new(theta.sin(), 0.0, theta.cos());
        let expected = f64::from(adjoint_albedo_quadrature(&phong, wi).x);
        let (adjoint, adjoint_err) = mean_weight(|u, l| phong.sample_adjoint(wi, u, l));
        let (plain, plain_err) = mean_weight(|u, l| phong.sample(wi, u, l));
        // Stratified draws have a smaller error than the i.i.d. standard error used here.
        assert!(
            (adjoint - expected).abs() < 4.0 * adjoint_err + 1e-3 * expected,
            "adjoint {adjoint} ± {adjoint_err}, quadrature {expected}"
        );
        assert!(
            (plain - expected).abs() > 10.0 * plain_err,
            "the plain sampler {plain} ± {plain_err} should miss {expected}"
        );
    }
}
