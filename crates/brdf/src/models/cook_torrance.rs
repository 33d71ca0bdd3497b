//! The Cook-Torrance microfacet model (Cook & Torrance 1982).

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use super::specular::check_fresnel;
use crate::brdf::{
    Brdf, BrdfSample, diffuse_or_pdf, diffuse_probability, reflect, same_upper, sample_diffuse_or,
};
use crate::error::{Result, check_rgb};
use crate::fresnel::Fresnel;
use crate::microfacet::{Distribution, Shadowing};

/// Cook-Torrance `f = d/π + s F(i·h) D(h) G / (4 cos θi cos θo)` (R. L. Cook and K. E. Torrance, "A reflectance model for computer graphics", ACM TOG 1(1), 1982, equations 3-6, 12-13).
///
/// The paper writes `F D G / (π cos θi cos θo)` with an unnormalised `D`;
/// with `D` normalised so that `∫ D cos θh dω = 1` the consistent
/// denominator is `4 cos θi cos θo` (Walter et al. 2007, equation 20), which
/// is what is used here and what Mitsuba's `roughconductor` computes.
/// Reciprocal. Energy conserving when `d + s ≤ 1` per channel, F ≤ 1 and
/// the distribution is Beckmann or GGX (single scattering loses energy, it
/// never creates it); the Gaussian with Smith G borrows Beckmann's G1, so it
/// is not claimed. Sampling: `h` from `D cos θh` (Walter et al. 2007,
/// section 5.3), reflected, mixed with a cosine hemisphere for `d`.
#[derive(Debug, Clone, PartialEq)]
pub struct CookTorrance {
    /// Diffuse reflectance d.
    pub diffuse: Rgb,
    /// Scale s of the specular lobe.
    pub specular: Rgb,
    /// The facet slope distribution D.
    pub distribution: Distribution,
    /// The geometric attenuation G.
    pub shadowing: Shadowing,
    /// The Fresnel term F.
    pub fresnel: Fresnel,
    /// Probability of sampling the diffuse lobe.
    p_diffuse: f32,
    /// Name reported by [`Brdf::name`].
    name: &'static str,
}

impl CookTorrance {
    /// Cook-Torrance; errors when d or s leaves [0, 1] or the Fresnel parameters are invalid.
    pub fn new(
        diffuse: Rgb,
        specular: Rgb,
        distribution: Distribution,
        shadowing: Shadowing,
        fresnel: Fresnel,
    ) -> Result<Self> {
        Self::named(
            "cook-torrance",
            diffuse,
            specular,
            distribution,
            shadowing,
            fresnel,
        )
    }

    /// As [`CookTorrance::new`] under another model name (used by Torrance-Sparrow and rough conductors).
    pub(crate) fn named(
        name: &'static str,
        diffuse: Rgb,
        specular: Rgb,
        distribution: Distribution,
        shadowing: Shadowing,
        fresnel: Fresnel,
    ) -> Result<Self> {
        check_rgb(name, "diffuse", diffuse, 0.0, 1.0)?;
        check_rgb(name, "specular", specular, 0.0, 1.0)?;
        check_fresnel(name, &fresnel)?;
        Ok(Self {
            diffuse,
            specular,
            distribution,
            shadowing,
            fresnel,
            p_diffuse: diffuse_probability(diffuse, specular),
            name,
        })
    }

    /// The specular term alone, `s F D G / (4 cos θi cos θo)`.
    pub fn specular_term(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        let h = (wi + wo).normalize();
        let d = self.distribution.d(h);
        if d == 0.0 {
            return Rgb::ZERO;
        }
        let g = self.shadowing.g(&self.distribution, wi, wo, h);
        let f = self.fresnel.eval(wi.dot(h));
        self.specular * f * (d * g / (4.0 * wi.z * wo.z))
    }
}

impl Brdf for CookTorrance {
    fn name(&self) -> &'static str {
        self.name
    }

    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        self.diffuse * FRAC_1_PI + self.specular_term(wi, wo)
    }

    fn sample(&self, wo: Vec3, u: Vec2, u_lobe: f32) -> Option<BrdfSample> {
        sample_diffuse_or(self, wo, u, u_lobe, self.p_diffuse, |u| {
            let h = self.distribution.sample_h(u);
            if h.dot(wo) <= 0.0 {
                return None;
            }
            Some(reflect(wo, h))
        })
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if !same_upper(wi, wo) {
            return 0.0;
        }
        let h = (wi + wo).normalize();
        let lobe = self.distribution.pdf_h(h) / (4.0 * wo.dot(h));
        diffuse_or_pdf(wi, self.p_diffuse, lobe)
    }

    fn is_reciprocal(&self) -> bool {
        true
    }

    fn is_energy_conserving(&self) -> bool {
        let gaussian_smith = matches!(self.distribution, Distribution::Gaussian { .. })
            && self.shadowing == Shadowing::Smith;
        let sum_ok = (self.diffuse + self.specular).max_element() <= 1.0 + 1e-6;
        !gaussian_smith && sum_ok && self.fresnel.is_bounded_by_one()
    }
}
