//! Weighted linear combinations of BRDFs.

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use crate::brdf::{Brdf, BrdfSample};
use crate::error::{BrdfError, Result};

/// A boxed BRDF, as returned by [`crate::from_model`].
pub type BoxedBrdf = Box<dyn Brdf + Send + Sync>;

/// `f = Σ_j w_j f_j` with weights `w_j ≥ 0` (a convex combination when `Σ w_j ≤ 1`, as Mitsuba's `blendbsdf`; the additive form of Cook & Torrance 1982 equation 2).
///
/// Reciprocal when every component is; energy conserving when every
/// component is and `Σ w_j ≤ 1`. A component is chosen with probability
/// `w_j / Σ w`; a smooth draw is then weighted by the density of the whole
/// mixture (one-sample MIS with the balance heuristic, Veach 1997 section
/// 9.2.4), a delta draw by its own weight over its selection probability.
#[derive(Debug)]
pub struct Mixture {
    /// The weighted components.
    components: Vec<(f32, BoxedBrdf)>,
    /// The sum of the weights.
    total: f32,
}

impl Mixture {
    /// A weighted sum; errors when a weight is negative or not finite.
    pub fn new(components: Vec<(f32, BoxedBrdf)>) -> Result<Self> {
        for (w, _) in &components {
            if !crate::brdf::is_non_negative(*w) {
                return Err(BrdfError::OutOfRange {
                    model: "blend".into(),
                    param: "weight".into(),
                    value: *w,
                    expected: "finite and at least 0".into(),
                });
            }
        }
        let total = components.iter().map(|(w, _)| *w).sum();
        Ok(Self { components, total })
    }

    /// The weighted components.
    pub fn components(&self) -> &[(f32, BoxedBrdf)] {
        &self.components
    }
}

impl Brdf for Mixture {
    fn name(&self) -> &'static str {
        "blend"
    }

    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        self.components
            .iter()
            .filter(|(w, _)| *w > 0.0)
            .map(|(w, b)| *w * b.eval(wi, wo))
            .sum()
    }

    fn sample(&self, wo: Vec3, u: Vec2, u_lobe: f32) -> Option<BrdfSample> {
        if !crate::brdf::is_positive(self.total) {
            return None;
        }
        let mut target = u_lobe * self.total;
        let mut chosen = None;
        for (j, (w, _)) in self.components.iter().enumerate() {
            if *w > 0.0 {
                chosen = Some(j);
                if target < *w {
                    break;
                }
                target -= w;
            }
        }
        let j = chosen?;
        let (w, brdf) = &self.components[j];
        let p_select = w / self.total;
        // Rescale the remaining fraction of u_lobe for the component's own lobe choice.
        let u_inner = (target / w).clamp(0.0, 1.0 - f32::EPSILON);
        let s = brdf.sample(wo, u, u_inner)?;
        if s.delta {
            return Some(BrdfSample {
                weight: s.weight * (*w / p_select),
                pdf: s.pdf * p_select,
                ..s
            });
        }
        let pdf = self.pdf(s.wi, wo);
        if !crate::brdf::is_positive(pdf) {
            return None;
        }
        Some(BrdfSample {
            wi: s.wi,
            weight: self.eval(s.wi, wo) * s.wi.z.abs() / pdf,
            pdf,
            delta: false,
        })
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if !crate::brdf::is_positive(self.total) {
            return 0.0;
        }
        self.components
            .iter()
            .filter(|(w, _)| *w > 0.0)
            .map(|(w, b)| w * b.pdf(wi, wo))
            .sum::<f32>()
            / self.total
    }

    fn albedo(&self, wo: Vec3) -> Rgb {
        self.components
            .iter()
            .filter(|(w, _)| *w > 0.0)
            .map(|(w, b)| *w * b.albedo(wo))
            .sum()
    }

    fn is_reciprocal(&self) -> bool {
        self.components.iter().all(|(_, b)| b.is_reciprocal())
    }

    fn is_energy_conserving(&self) -> bool {
        self.total <= 1.0 + 1e-6
            && self
                .components
                .iter()
                .all(|(_, b)| b.is_energy_conserving())
    }

    fn has_delta(&self) -> bool {
        self.components
            .iter()
            .any(|(w, b)| *w > 0.0 && b.has_delta())
    }

    fn transmits(&self) -> bool {
        self.components
            .iter()
            .any(|(w, b)| *w > 0.0 && b.transmits())
    }

    fn is_two_sided(&self) -> bool {
        self.components
            .iter()
            .all(|(w, b)| *w <= 0.0 || b.is_two_sided())
    }
}
