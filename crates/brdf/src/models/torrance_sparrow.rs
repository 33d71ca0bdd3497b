//! The Torrance-Sparrow off-specular model (Torrance & Sparrow 1967).

use lustre_geometry::Rgb;
use lustre_geometry::material::MicrofacetDistribution;

use super::cook_torrance::CookTorrance;
use crate::error::Result;
use crate::fresnel::Fresnel;
use crate::microfacet::{Distribution, Shadowing};

/// Torrance-Sparrow `f = d/π + s F(θ'i) G P(α) / (4 cos θi cos θo)` with `P(α) = c exp(-(α/m)²)`, V-groove G and the dielectric Fresnel at the facet angle (K. E. Torrance and E. M. Sparrow, "Theory for off-specular reflection from roughened surfaces", JOSA 57(9), 1967, equations 19, 23, 25-27).
///
/// Built as a [`CookTorrance`] with the Gaussian distribution (`c`
/// normalised numerically), [`Shadowing::VCavity`] and
/// [`Fresnel::Dielectric`]. Reciprocal; energy conserving when `d + s ≤ 1`.
/// Sampled with a Beckmann proposal of α = m (the Gaussian has no
/// closed-form inverse), mixed with a cosine hemisphere.
pub fn torrance_sparrow(diffuse: Rgb, specular: Rgb, m: f32, ior: f32) -> Result<CookTorrance> {
    let distribution = Distribution::new(MicrofacetDistribution::Gaussian, m, "torrance-sparrow")?;
    CookTorrance::named(
        "torrance-sparrow",
        diffuse,
        specular,
        distribution,
        Shadowing::VCavity,
        Fresnel::Dielectric { eta: ior },
    )
}
