//! Lafortune's generalised cosine lobes (Lafortune et al. 1997).

use std::f32::consts::{FRAC_1_PI, PI};

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;
use lustre_geometry::sampling::sample_cosine_hemisphere;

use super::phong::check_exponent;
use crate::brdf::{
    Brdf, BrdfSample, cos_power_lobe_pdf, finish_sample, mean, same_upper, sample_cos_power_lobe,
};
use crate::error::{BrdfError, Result, check_rgb};

/// One generalised cosine lobe `ρ (Cx ix ox + Cy iy oy + Cz iz oz)^n` (Lafortune et al. 1997, equation 5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CosineLobe {
    /// The diagonal of the lobe's matrix: `(Cx, Cy, Cz)`; `(-1, -1, 1)` with `ρ (n+2)/(2π)` is the modified Phong lobe.
    pub c: Vec3,
    /// Exponent n ≥ 0.
    pub exponent: f32,
    /// Per-channel scale ρ ≥ 0.
    pub scale: Rgb,
}

/// Lafortune's model `f = ρd/π + Σ_j ρ_j max(0, Cx,j ix ox + Cy,j iy oy + Cz,j iz oz)^{n_j}` (E. P. F. Lafortune, S.-C. Foo, K. E. Torrance, D. P. Greenberg, "Non-linear approximation of reflectance functions", SIGGRAPH 1997, equations 4-6).
///
/// Reciprocal (the form is symmetric in `wi` and `wo`). Not claimed energy
/// conserving: the parameters are fitted freely and nothing bounds the
/// albedo. Lobe `j` is sampled as a `cos^n` lobe about `(Cx ox, Cy oy, Cz oz)`
/// normalised (section 4 of the paper), chosen with probability
/// proportional to `mean(ρ_j) |C∘wo|^n 2π/(n+1)`; the diffuse term with a
/// cosine hemisphere.
#[derive(Debug, Clone, PartialEq)]
pub struct Lafortune {
    /// Diffuse reflectance ρd.
    pub diffuse: Rgb,
    /// The lobes.
    pub lobes: Vec<CosineLobe>,
}

impl Lafortune {
    /// Lafortune's model; errors when ρd leaves [0, 1], a scale is negative or an exponent negative, or a coefficient is not finite.
    pub fn new(diffuse: Rgb, lobes: Vec<CosineLobe>) -> Result<Self> {
        check_rgb("lafortune", "diffuse", diffuse, 0.0, 1.0)?;
        for lobe in &lobes {
            check_rgb("lafortune", "lobe scale", lobe.scale, 0.0, f32::MAX)?;
            check_exponent("lafortune", lobe.exponent)?;
            if !lobe.c.is_finite() {
                return Err(BrdfError::OutOfRange {
                    model: "lafortune".into(),
                    param: "lobe C".into(),
                    value: f32::NAN,
                    expected: "finite coefficients".into(),
                });
            }
        }
        Ok(Self { diffuse, lobes })
    }

    /// Selection weights: the diffuse term first, then each lobe's approximate albedo given `wo`.
    fn selection(&self, wo: Vec3) -> (Vec<f32>, f32) {
        let mut w = Vec::with_capacity(self.lobes.len() + 1);
        w.push(mean(self.diffuse));
        for lobe in &self.lobes {
            let axis = lobe.c * wo;
            let s = axis.length();
            w.push(mean(lobe.scale) * s.powf(lobe.exponent) * 2.0 * PI / (lobe.exponent + 1.0));
        }
        let total: f32 = w.iter().sum();
        (w, total)
    }
}

impl Brdf for Lafortune {
    fn name(&self) -> &'static str {
        "lafortune"
    }

    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        let mut f = self.diffuse * FRAC_1_PI;
        for lobe in &self.lobes {
            let d = (lobe.c * wi * wo).element_sum();
            if d > 0.0 {
                f += lobe.scale * d.powf(lobe.exponent);
            }
        }
        f
    }

    fn sample(&self, wo: Vec3, u: Vec2, u_lobe: f32) -> Option<BrdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let (w, total) = self.selection(wo);
        if !crate::brdf::is_positive(total) {
            return None;
        }
        let mut target = u_lobe * total;
        let mut chosen = w.len() - 1;
        for (j, wj) in w.iter().enumerate() {
            if target < *wj {
                chosen = j;
                break;
            }
            target -= wj;
        }
        let wi = if chosen == 0 {
            sample_cosine_hemisphere(u)
        } else {
            let lobe = &self.lobes[chosen - 1];
            let axis = (lobe.c * wo).try_normalize()?;
            sample_cos_power_lobe(axis, lobe.exponent, u)
        };
        finish_sample(self, wi, wo)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if !same_upper(wi, wo) {
            return 0.0;
        }
        let (w, total) = self.selection(wo);
        if !crate::brdf::is_positive(total) {
            return 0.0;
        }
        let mut p = w[0] * wi.z * FRAC_1_PI;
        for (lobe, wj) in self.lobes.iter().zip(&w[1..]) {
            if let Some(axis) = (lobe.c * wo).try_normalize() {
                p += wj * cos_power_lobe_pdf(axis.dot(wi), lobe.exponent);
            }
        }
        p / total
    }

    fn is_reciprocal(&self) -> bool {
        true
    }

    fn is_energy_conserving(&self) -> bool {
        false
    }
}
