//! Duvenhage's glossy scatter distribution: a normalised 2D Gaussian over the scatter angle and its volume over a triangular domain (B. Duvenhage, K. Bouatouch and D. G. Kourie, "Exploring the use of glossy light volumes for interactive global illumination", Afrigraph 2010, sections 1.2 and 4.2).
//!
//! **The distribution** (section 4.2). `ρ(φ) = exp(-|φ|² / (2σ²)) / (2πσ²)`
//! over the 2D scatter angle φ (radians, the offset from the specular
//! direction), whose peak is the paper's `P_O = 1/(2πσ²)` (figure 11); σ² is
//! the per-axis variance of the scattered direction's angle.
//!
//! **Relation to Beckmann's α.** Section 1.2 takes micro-facet gradients
//! (slopes) Gaussian about the mean normal. Beckmann's distribution is
//! exactly that: its slope density is `exp(-(sx² + sy²)/α²) / (π α²)`, per
//! axis a Gaussian of variance `σs² = α²/2`. At normal incidence a facet
//! tilted by a small angle t ≈ |s| reflects the incoming direction by `2t`
//! (the reflected vector turns twice as far as the mirror), so the scatter
//! angle is `φ ≈ 2 s` and its per-axis variance is
//! `σ² = 4 σs² = 2 α²`, i.e. `σ = √2 α` ([`ScatterDistribution::from_beckmann_alpha`]).
//! Corrections are relative `O(α²)` (`tan`, and the `2 atan(s)` of the
//! exact reflection) and grow away from normal incidence, where the lobe
//! is also no longer circular.
//!
//! **The triangle volume** (section 4.2.2). With the fragment at the origin O
//! and the triangular domain ABC (vertices at angular distances φa, φb, φc),
//! the volume is approximated by planar facets through the Gaussian's values
//! at their corners, each contributing its area times the average of its
//! three corner values (equation 5): when O is inside ABC the facets are
//! AOB, BOC, COA (figure 11); when O is outside, beyond one edge, the edge
//! is split at D where the line from O to the opposite vertex crosses it,
//! and the facets are the two triangles on either side of CD (figure 12;
//! the paper's second `P_CAD` there is read as `P_CBD`); when O lies beyond
//! two edges (a vertex is nearer than any split point) ABC is one facet.
//! The result is clamped to one. [`ScatterDistribution::triangle_volume_exact`]
//! integrates the Gaussian over the triangle numerically for comparison.

use glam::Vec2;

use crate::error::{BrdfError, Result};

/// The normalised, rotationally symmetric 2D Gaussian over the scatter angle (Duvenhage et al. 2010, section 4.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScatterDistribution {
    /// Per-axis variance σ² of the scatter angle, radians².
    pub variance: f32,
}

impl ScatterDistribution {
    /// The distribution with per-axis variance σ²; errors unless it is positive and finite.
    pub fn new(variance: f32) -> Result<Self> {
        if !crate::brdf::is_positive(variance) {
            return Err(BrdfError::OutOfRange {
                model: "scatter-distribution".into(),
                param: "variance".into(),
                value: variance,
                expected: "positive and finite".into(),
            });
        }
        Ok(Self { variance })
    }

    /// From the micro-facet slope variance σs² per axis: σ² = 4 σs² (the reflected direction turns twice the facet tilt; module documentation).
    pub fn from_slope_variance(slope_variance: f32) -> Result<Self> {
        Self::new(4.0 * slope_variance)
    }

    /// From Beckmann's roughness α: slope variance α²/2, so σ² = 2α² (module documentation).
    pub fn from_beckmann_alpha(alpha: f32) -> Result<Self> {
        Self::new(2.0 * alpha * alpha)
    }

    /// Through one rough interface of relative index η (far side over near side, the convention of [`crate::fresnel_dielectric`]), from Beckmann's α: near normal incidence a facet tilted by `s` turns the refracted direction by `(1 - 1/η) s`, so `σ² = (1 - 1/η)² α²/2` (the transmissive twin of [`ScatterDistribution::from_beckmann_alpha`]; Duvenhage et al. 2010, section 4.4, figure 13). Errors for η = 1 (no spread: a specular beam).
    pub fn from_beckmann_alpha_refracted(alpha: f32, eta: f32) -> Result<Self> {
        let k = 1.0 - 1.0 / eta;
        Self::new(k * k * alpha * alpha / 2.0)
    }

    /// Through a thin slab of index η with both faces rough (Beckmann α each, independent): the entry facet turns the ray by `(1 - 1/η) s₁` inside, which leaves the slab multiplied by η, and the exit facet adds `(1 - η) s₂`, so the scatter angle is `(η - 1)(s₁ - s₂)` and `σ² = (η - 1)² α²` (a stained-glass pane lit from behind, Duvenhage et al. 2010, figures 1 and 13). Errors for η = 1.
    pub fn from_beckmann_alpha_thin_slab(alpha: f32, eta: f32) -> Result<Self> {
        let k = eta - 1.0;
        Self::new(k * k * alpha * alpha)
    }

    /// The peak `P_O = 1/(2πσ²)` at the specular direction (Duvenhage et al. 2010, figure 11, step 1).
    pub fn peak(&self) -> f32 {
        1.0 / (2.0 * std::f32::consts::PI * self.variance)
    }

    /// `ρ(φ) = exp(-|φ|²/(2σ²)) / (2πσ²)` (Duvenhage et al. 2010, section 4.2).
    pub fn density(&self, phi: Vec2) -> f32 {
        self.peak() * (-phi.length_squared() / (2.0 * self.variance)).exp()
    }

    /// The volume under ρ over the triangle ABC of scatter angles, the fragment at the origin, by the paper's planar-facet approximation clamped to one (Duvenhage et al. 2010, section 4.2.2, figures 11 and 12).
    pub fn triangle_volume(&self, a: Vec2, b: Vec2, c: Vec2) -> f32 {
        self.triangle_volume_split(a, b, c, |_, _, d| d)
    }

    /// [`ScatterDistribution::triangle_volume`] with the split point D of the outside case chosen by the caller: `split(k, s, d)` gets the vertex `k` opposite the split edge, the parameter `s` in [0, 1] of D along that edge from vertex `k + 1` to `k + 2`, and that point `d` of the domain, and returns the D to use (Duvenhage et al. 2010, figure 12, step 3, recompute it from the world-space point `D_W` on the scatterer).
    pub fn triangle_volume_split(
        &self,
        a: Vec2,
        b: Vec2,
        c: Vec2,
        split: impl Fn(usize, f32, Vec2) -> Vec2,
    ) -> f32 {
        let facet = |p: Vec2, q: Vec2, r: Vec2| {
            0.5 * (q - p).perp_dot(r - p).abs()
                * (self.density(p) + self.density(q) + self.density(r))
                / 3.0
        };
        let v = [a, b, c];
        // Which side of each edge (opposite vertex k) the origin lies on.
        let orient = (b - a).perp_dot(c - a);
        if orient == 0.0 || !orient.is_finite() {
            return 0.0;
        }
        let outside: [bool; 3] = std::array::from_fn(|k| {
            let (p, q) = (v[(k + 1) % 3], v[(k + 2) % 3]);
            // Origin and vertex k on opposite sides of edge pq.
            (q - p).perp_dot(-p) * orient < 0.0
        });
        let o = Vec2::ZERO;
        let volume = match outside.iter().filter(|&&x| x).count() {
            0 => facet(a, o, b) + facet(b, o, c) + facet(c, o, a),
            1 => {
                let k = outside.iter().position(|&x| x).unwrap_or(0);
                let (vk, p, q) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
                // D: where the line from O through the opposite vertex crosses edge pq.
                let e = q - p;
                let denom = vk.perp_dot(e);
                if denom == 0.0 {
                    facet(a, b, c)
                } else {
                    let s = vk.perp_dot(-p) / denom;
                    let s = s.clamp(0.0, 1.0);
                    let d = split(k, s, p + e * s);
                    facet(vk, p, d) + facet(vk, d, q)
                }
            }
            _ => facet(a, b, c),
        };
        volume.min(1.0)
    }

    /// The volume under ρ over the triangle ABC, the Gaussian integrated instead of the paper's planar facets (its section 4.2.2 asks for "a better approximation" of the volume; the facets clamped to one widen a glossy beam by about σ at full strength and do not conserve energy): a fan of triangles from the origin, each `∫ (1 - exp(-r(θ)²/(2σ²))) dθ / (2π)` in polar coordinates, by 8-point Gauss-Legendre on [`INTEGRATED_PANELS`] panels in f32 (the GPU beam pass's twin). Within 1e-3 of [`ScatterDistribution::triangle_volume_exact`] (`tests`).
    pub fn triangle_volume_integrated(&self, a: Vec2, b: Vec2, c: Vec2) -> f32 {
        let s2 = self.variance;
        let edge = |p: Vec2, q: Vec2| -> f32 {
            let cross = p.perp_dot(q);
            let e = q - p;
            let len2 = e.length_squared();
            if cross == 0.0 || len2 == 0.0 || p == Vec2::ZERO || q == Vec2::ZERO {
                return 0.0;
            }
            let t0 = p.y.atan2(p.x);
            let sweep = cross.atan2(p.dot(q));
            // Distance from O to the line pq and the direction of its foot.
            let dist = cross.abs() / len2.sqrt();
            let foot = p - e * (p.dot(e) / len2);
            let tn = foot.y.atan2(foot.x);
            let h = sweep / INTEGRATED_PANELS as f32;
            let mut sum = 0.0;
            for panel in 0..INTEGRATED_PANELS {
                let mid = t0 + (panel as f32 + 0.5) * h;
                for k in 0..4 {
                    let (x, w) = (GL8_X[k] as f32, GL8_W[k] as f32);
                    for t in [mid - 0.5 * h * x, mid + 0.5 * h * x] {
                        let r = dist / (t - tn).cos();
                        sum += w * (1.0 - (-r * r / (2.0 * s2)).exp());
                    }
                }
            }
            sum * 0.5 * h / (2.0 * std::f32::consts::PI)
        };
        (edge(a, b) + edge(b, c) + edge(c, a)).abs().min(1.0)
    }

    /// The volume under ρ over the triangle ABC, integrated numerically in f64: a fan of triangles from the origin, each done in polar coordinates as `∫ (1 - exp(-r(θ)²/(2σ²))) dθ / (2π)` by composite 8-point Gauss-Legendre on 64 panels (the reference for [`ScatterDistribution::triangle_volume`]).
    pub fn triangle_volume_exact(&self, a: Vec2, b: Vec2, c: Vec2) -> f64 {
        let s2 = f64::from(self.variance);
        let edge = |p: Vec2, q: Vec2| -> f64 {
            let (px, py) = (f64::from(p.x), f64::from(p.y));
            let (qx, qy) = (f64::from(q.x), f64::from(q.y));
            let cross = px * qy - py * qx;
            let (lp, lq) = ((px * px + py * py).sqrt(), (qx * qx + qy * qy).sqrt());
            if cross == 0.0 || lp == 0.0 || lq == 0.0 {
                return 0.0;
            }
            let t0 = py.atan2(px);
            let sweep = cross.atan2(px * qx + py * qy);
            // Distance from O to the line pq and the direction of its foot.
            let (ex, ey) = (qx - px, qy - py);
            let len = (ex * ex + ey * ey).sqrt();
            let dist = cross.abs() / len;
            let along = (px * ex + py * ey) / (len * len);
            let (fx, fy) = (px - along * ex, py - along * ey);
            let tn = fy.atan2(fx);
            let g = |t: f64| {
                let r = dist / (t - tn).cos();
                1.0 - (-r * r / (2.0 * s2)).exp()
            };
            gauss_legendre(&g, t0, t0 + sweep, 64) / (2.0 * std::f64::consts::PI)
        };
        let signed = edge(a, b) + edge(b, c) + edge(c, a);
        signed.abs()
    }
}

/// Panels per fan edge of [`ScatterDistribution::triangle_volume_integrated`].
pub const INTEGRATED_PANELS: usize = 4;
/// 8-point Gauss-Legendre nodes, the positive half (Abramowitz & Stegun 25.4.30).
const GL8_X: [f64; 4] = [
    0.183_434_642_495_649_8,
    0.525_532_409_916_329,
    0.796_666_477_413_626_7,
    0.960_289_856_497_536_2,
];
/// Their weights.
const GL8_W: [f64; 4] = [
    0.362_683_783_378_362,
    0.313_706_645_877_887_3,
    0.222_381_034_453_374_5,
    0.101_228_536_290_376_3,
];

/// `∫ₐᵇ g` by composite 8-point Gauss-Legendre on `panels` equal panels ([`GL8_X`], [`GL8_W`]).
fn gauss_legendre(g: &dyn Fn(f64) -> f64, a: f64, b: f64, panels: usize) -> f64 {
    let h = (b - a) / panels as f64;
    let mut sum = 0.0;
    for p in 0..panels {
        let mid = a + (p as f64 + 0.5) * h;
        let half = 0.5 * h;
        for k in 0..4 {
            sum += GL8_W[k] * (g(mid - half * GL8_X[k]) + g(mid + half * GL8_X[k]));
        }
    }
    sum * 0.5 * h
}
