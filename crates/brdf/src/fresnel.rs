//! Fresnel reflectance: dielectric, conductor with a complex index, Schlick's approximation.

use lustre_geometry::Rgb;

/// Unpolarised Fresnel reflectance of a smooth dielectric interface (Born & Wolf, *Principles of Optics*, section 1.5.2, equations 21a-b averaged over s and p).
///
/// `cos_i` is the cosine of the incident angle on the side the light comes
/// from; `eta` is the index of the far side over the index of the near side.
/// A negative `cos_i` means the light comes from the far side, and the
/// interface is flipped. Returns 1 beyond the critical angle (total internal
/// reflection).
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let (cos_i, eta) = if cos_i < 0.0 {
        (-cos_i, 1.0 / eta)
    } else {
        (cos_i, eta)
    };
    let cos_i = cos_i.min(1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// Unpolarised Fresnel reflectance of a conductor with complex index `eta + i k` (relative to the outside medium), exact (Born & Wolf section 14.2; the `a² + b²` form of Cook & Torrance 1982, appendix, and pbrt-v3 section 8.2.1).
pub fn fresnel_conductor(cos_i: f32, eta: Rgb, k: Rgb) -> Rgb {
    let c = cos_i.clamp(0.0, 1.0);
    Rgb::new(
        fresnel_conductor_scalar(c, eta.x, k.x),
        fresnel_conductor_scalar(c, eta.y, k.y),
        fresnel_conductor_scalar(c, eta.z, k.z),
    )
}

/// One channel of [`fresnel_conductor`], computed in `f64`.
fn fresnel_conductor_scalar(cos_i: f32, eta: f32, k: f32) -> f32 {
    let c = f64::from(cos_i);
    let (n, k) = (f64::from(eta), f64::from(k));
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let t0 = n * n - k * k - s2;
    let a2b2 = (t0 * t0 + 4.0 * n * n * k * k).sqrt();
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let rs_num = a2b2 + c2 - 2.0 * a * c;
    let rs_den = a2b2 + c2 + 2.0 * a * c;
    let rs = if rs_den > 0.0 { rs_num / rs_den } else { 1.0 };
    let rp_num = c2 * a2b2 + s2 * s2 - 2.0 * a * c * s2;
    let rp_den = c2 * a2b2 + s2 * s2 + 2.0 * a * c * s2;
    let rp = if rp_den > 0.0 {
        rs * rp_num / rp_den
    } else {
        rs
    };
    (0.5 * (rs + rp)) as f32
}

/// Schlick's approximation `F0 + (1 - F0)(1 - cos θ)^5` (Schlick 1994, "An inexpensive BRDF model for physically-based rendering", equation 15).
pub fn fresnel_schlick(cos_i: f32, f0: Rgb) -> Rgb {
    let m = (1.0 - cos_i.clamp(0.0, 1.0)).powi(5);
    f0 + (Rgb::ONE - f0) * m
}

/// A Fresnel term chosen at construction (the `F` factor of microfacet models, Cook & Torrance 1982 section "Fresnel term").
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fresnel {
    /// `F = 1` at every angle.
    One,
    /// A constant reflectance at every angle.
    Constant(Rgb),
    /// Smooth dielectric with relative index of refraction `eta` ([`fresnel_dielectric`]).
    Dielectric {
        /// Index of the inside over the outside.
        eta: f32,
    },
    /// Conductor with complex index `eta + i k` ([`fresnel_conductor`]).
    Conductor {
        /// Real part, per channel.
        eta: Rgb,
        /// Extinction coefficient, per channel.
        k: Rgb,
    },
    /// Schlick's approximation with normal-incidence reflectance `f0` ([`fresnel_schlick`]).
    Schlick {
        /// Reflectance at normal incidence.
        f0: Rgb,
    },
}

impl Fresnel {
    /// The reflectance at incident cosine `cos_i` (in [0, 1], from the outside).
    pub fn eval(&self, cos_i: f32) -> Rgb {
        match *self {
            Self::One => Rgb::ONE,
            Self::Constant(c) => c,
            Self::Dielectric { eta } => Rgb::splat(fresnel_dielectric(cos_i.max(0.0), eta)),
            Self::Conductor { eta, k } => fresnel_conductor(cos_i, eta, k),
            Self::Schlick { f0 } => fresnel_schlick(cos_i, f0),
        }
    }

    /// Whether the reflectance is at most one at every angle (true for all physical terms; a `Constant` above one is refused at construction).
    pub fn is_bounded_by_one(&self) -> bool {
        match *self {
            Self::Constant(c) => c.max_element() <= 1.0,
            Self::Schlick { f0 } => f0.max_element() <= 1.0,
            _ => true,
        }
    }
}
