//! The Poulin-Fournier anisotropic model: parallel cylinders with self-shadowing (Poulin & Fournier 1990).

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use lustre_geometry::Rgb;

use super::phong::check_exponent;
use crate::brdf::{Brdf, BrdfSample, cosine_pdf, reflect, same_upper, sample_cosine};
use crate::error::{BrdfError, Result, check_range, check_rgb, check_sum};

/// Quadrature points over the exposed arc of one cylinder.
pub const PF_CYLINDER_POINTS: usize = 192;
/// Quadrature points over the exposed base plane between two cylinders.
pub const PF_PLANE_POINTS: usize = 48;

/// Poulin-Fournier (P. Poulin and A. Fournier, "A model for anisotropic reflection", SIGGRAPH 1990, sections 3-4): the surface is a row of parallel cylinders of radius 1 along the +Y bitangent, axes `2 + d` apart, axes at height `h` above a base plane.
///
/// Each exposed point of a cylinder (normal `n(ξ) = (sin ξ, 0, cos ξ)`) and
/// of the base plane reflects with a local BRDF `kd/π + ks (n+2)/(2π) cos^n α`
/// (modified Phong about the local normal, standing in for the paper's
/// Phong-type local term); the macro BRDF is the projected-area average over
/// one period `D = 2 + d`:
/// `f = [∫ V(i) V(o) f_loc (n·i)(n·o) dξ + ∫ V(i) V(o) f_loc (N·i)(N·o) dx] / (D cos θi cos θo)`,
/// where `V` is 1 where the point is neither self-shadowed (`n·w ≤ 0`) nor
/// shadowed/masked by a neighbouring cylinder in the cross-section plane
/// of the direction (the paper's cylinder self-shadowing: infinitely long
/// cylinders shadow in the 2D projection of the direction onto the XZ
/// plane). Light shadowed by a cylinder is lost (no interreflection), as in
/// the paper.
///
/// Simplification: the paper integrates the visible and lit angular
/// intervals in closed form for a Phong local model; here the same integral
/// is evaluated by the midpoint rule ([`PF_CYLINDER_POINTS`] points on the
/// exposed arc, [`PF_PLANE_POINTS`] on the plane) with an exact ray-circle
/// occlusion test per point. Reciprocal (the integrand is symmetric, also
/// after quadrature). Energy conserving for `kd + ks ≤ 1` (each point's
/// local albedo is at most one and the lit projected width is at most
/// `D cos θi`), up to the quadrature error. Sampled from a cosine hemisphere.
#[derive(Debug, Clone, PartialEq)]
pub struct PoulinFournier {
    /// Local diffuse reflectance kd.
    pub diffuse: Rgb,
    /// Local specular reflectance ks.
    pub specular: Rgb,
    /// Local Phong exponent n.
    pub exponent: f32,
    /// Gap d between adjacent cylinders, in radii.
    pub gap: f32,
    /// Height h of the cylinder axes above the base plane, in radii (0: half buried, 1: resting on it).
    pub height: f32,
}

impl PoulinFournier {
    /// Poulin-Fournier; errors when kd, ks leave [0, 1], kd + ks > 1, n < 0, d < 0 or h leaves [0, 1].
    pub fn new(diffuse: Rgb, specular: Rgb, exponent: f32, gap: f32, height: f32) -> Result<Self> {
        let name = "poulin-fournier";
        check_rgb(name, "diffuse", diffuse, 0.0, 1.0)?;
        check_rgb(name, "specular", specular, 0.0, 1.0)?;
        check_sum(name, diffuse, specular)?;
        check_exponent(name, exponent)?;
        if !crate::brdf::is_non_negative(gap) {
            return Err(BrdfError::OutOfRange {
                model: name.into(),
                param: "gap".into(),
                value: gap,
                expected: "finite and at least 0".into(),
            });
        }
        check_range(name, "height", height, 0.0, 1.0)?;
        Ok(Self {
            diffuse,
            specular,
            exponent,
            gap,
            height,
        })
    }

    /// The period `D = 2 + d`.
    fn period(&self) -> f32 {
        2.0 + self.gap
    }

    /// The local modified-Phong BRDF about the normal `n`, times `(n·i)(n·o)`; zero when either cosine is not positive.
    fn local_projected(&self, wi: Vec3, wo: Vec3, n: Vec3) -> Rgb {
        let ci = n.dot(wi);
        let co = n.dot(wo);
        if ci <= 0.0 || co <= 0.0 {
            return Rgb::ZERO;
        }
        let cos_alpha = reflect(wi, n).dot(wo).max(0.0);
        let e = self.exponent;
        let f = self.diffuse * FRAC_1_PI
            + self.specular * ((e + 2.0) * 0.5 * FRAC_1_PI * cos_alpha.powf(e));
        f * (ci * co)
    }

    /// Whether the point `(x, z)` of the cross-section sees along the projected direction `(a, b)` (unit, `b > 0`) without hitting a cylinder of the row.
    fn unoccluded(&self, x: f32, z: f32, a: f32, b: f32) -> bool {
        let d = self.period();
        let h = self.height;
        let base = (h - z) * a;
        let k_lo = ((x + (base - 1.0) / b) / d).ceil();
        let k_hi = ((x + (base + 1.0) / b) / d).floor();
        if !k_lo.is_finite() || !k_hi.is_finite() || k_lo > k_hi {
            return true;
        }
        for step in 0..3 {
            let k = if a >= 0.0 {
                k_hi - step as f32
            } else {
                k_lo + step as f32
            };
            if k < k_lo || k > k_hi {
                break;
            }
            let dx = k * d - x;
            let dz = h - z;
            let t_c = dx * a + dz * b;
            let dist = dx * b - dz * a;
            let disc = 1.0 - dist * dist;
            if disc > 0.0 && t_c + disc.sqrt() > 1e-4 {
                return false;
            }
        }
        true
    }
}

impl Brdf for PoulinFournier {
    fn name(&self) -> &'static str {
        "poulin-fournier"
    }

    fn eval(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if !same_upper(wi, wo) {
            return Rgb::ZERO;
        }
        let proj = |w: Vec3| {
            let l = (w.x * w.x + w.z * w.z).sqrt();
            (w.x / l, w.z / l)
        };
        let (ai, bi) = proj(wi);
        let (ao, bo) = proj(wo);
        let h = self.height;
        let d = self.period();
        let mut sum = Rgb::ZERO;
        // Exposed arc of the cylinder at x = 0: points above the plane, |ξ| ≤ acos(-h).
        let xi_max = (-h).clamp(-1.0, 1.0).acos();
        let dxi = 2.0 * xi_max / PF_CYLINDER_POINTS as f32;
        for j in 0..PF_CYLINDER_POINTS {
            let xi = -xi_max + (j as f32 + 0.5) * dxi;
            let (s, c) = xi.sin_cos();
            let n = Vec3::new(s, 0.0, c);
            let term = self.local_projected(wi, wo, n);
            if term == Rgb::ZERO {
                continue;
            }
            let (x, z) = (s, h + c);
            if self.unoccluded(x, z, ai, bi) && self.unoccluded(x, z, ao, bo) {
                sum += term * dxi;
            }
        }
        // Exposed base plane between the cylinders at 0 and D.
        let foot = (1.0 - h * h).max(0.0).sqrt();
        let width = d - 2.0 * foot;
        if width > 0.0 {
            let plane = self.local_projected(wi, wo, Vec3::Z);
            let dx = width / PF_PLANE_POINTS as f32;
            for j in 0..PF_PLANE_POINTS {
                let x = foot + (j as f32 + 0.5) * dx;
                if self.unoccluded(x, 0.0, ai, bi) && self.unoccluded(x, 0.0, ao, bo) {
                    sum += plane * dx;
                }
            }
        }
        sum / (d * wi.z * wo.z)
    }

    fn sample(&self, wo: Vec3, u: Vec2, _u_lobe: f32) -> Option<BrdfSample> {
        sample_cosine(self, wo, u)
    }

    fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        cosine_pdf(wi, wo)
    }

    fn is_reciprocal(&self) -> bool {
        true
    }

    fn is_energy_conserving(&self) -> bool {
        true
    }
}
