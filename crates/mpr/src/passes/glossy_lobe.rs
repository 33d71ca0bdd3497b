//! The glossy lobe of a glossy image (Diefenbach & Badler 1997, section 3,
//! "glossy marble"; derivations in [`crate::passes::glossy_image`]): a
//! material's glossy part as one roughness α and reflectance factor, the
//! `N` stratified shears `Δ = 2m` of its facet slopes, their microfacet
//! variant at a face's centroid, and the paper's linear fog factor. Plain
//! CPU functions; the GPU pass reads their output.

use glam::{Vec2, Vec3};
use lustre_brdf::{ALBEDO_STRATA, sampled_albedo};
use lustre_geometry::Rgb;
use lustre_geometry::light::hammersley_centred;
use lustre_geometry::material::{ConductorFresnel, MaterialModel};

/// The glossy part of a material as one lobe: its roughness `α` (RMS slope)
/// and its reflectance factor `R` (section 3's scattering reflective surface).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlossyLobe {
    /// RMS slope of the facet normals.
    pub alpha: f32,
    /// What the face passes of its image: the lobe's reflectance at normal incidence.
    pub factor: Vec3,
}

/// Phong's exponent `n` as a Beckmann roughness: `α = √(2/(n + 2))`.
pub fn phong_alpha(exponent: f32) -> f32 {
    (2.0 / (exponent.max(0.0) + 2.0)).sqrt()
}

/// Schlick-free Fresnel reflectance of a conductor at normal incidence, `((η−1)² + k²)/((η+1)² + k²)`.
fn conductor_f0(fresnel: &ConductorFresnel) -> Vec3 {
    match fresnel {
        ConductorFresnel::None => Vec3::ONE,
        ConductorFresnel::Complex { eta, k } => {
            let (eta, k) = (*eta, *k);
            ((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k)
        }
    }
}

/// The glossy lobe of `model`, if it has one ([`GlossyLobe`]): a rough
/// conductor's `α` and `specular · F(0)`, Phong's `Ks` and `α² = 2/(n+2)`,
/// Ward's `ρ_s` and `√(α_x α_y)`; a blend's lobes weighted, `α` the
/// reflectance-weighted mean of its sides'. `None` for Lambertian, mirror,
/// dielectric and named models.
pub fn glossy_lobe(model: &MaterialModel) -> Option<GlossyLobe> {
    let lobe = match model {
        MaterialModel::RoughConductor {
            alpha,
            fresnel,
            specular,
            ..
        } => GlossyLobe {
            alpha: *alpha,
            factor: *specular * conductor_f0(fresnel),
        },
        MaterialModel::Phong {
            specular, exponent, ..
        } => GlossyLobe {
            alpha: phong_alpha(*exponent),
            factor: *specular,
        },
        MaterialModel::Ward {
            specular,
            alpha_x,
            alpha_y,
            ..
        } => GlossyLobe {
            alpha: (alpha_x * alpha_y).abs().sqrt(),
            factor: *specular,
        },
        MaterialModel::Blend {
            weight,
            first,
            second,
        } => {
            let sides = [
                glossy_lobe(first).map(|l| (l, 1.0 - weight)),
                glossy_lobe(second).map(|l| (l, *weight)),
            ];
            let mut factor = Vec3::ZERO;
            let (mut alpha_sum, mut mass) = (0.0, 0.0);
            for (lobe, w) in sides.into_iter().flatten() {
                factor += lobe.factor * w;
                let m = (lobe.factor * w).element_sum();
                alpha_sum += lobe.alpha * m;
                mass += m;
            }
            if mass <= 0.0 {
                return None;
            }
            GlossyLobe {
                alpha: alpha_sum / mass,
                factor,
            }
        }
        _ => return None,
    };
    (lobe.alpha.is_finite()
        && lobe.alpha > 0.0
        && lobe.factor.is_finite()
        && lobe.factor.max_element() > 0.0)
        .then_some(lobe)
}

/// The directional albedo `∫ f_s cos θ_l dω_l` of `model`'s glossy part
/// (the lobes [`glossy_lobe`] gathers; Lambertian lobes and diffuse terms
/// left out) for a view at `cos θ` from the normal, estimated by
/// [`sampled_albedo`] over lustre-brdf's model: the reflectance that a
/// uniform incident radiance of 1 leaves towards the viewer.
pub fn glossy_albedo(model: &MaterialModel, cos_theta: f32) -> Result<Rgb, lustre_brdf::BrdfError> {
    let c = cos_theta.clamp(1e-4, 1.0);
    let wo = Vec3::new((1.0 - c * c).sqrt(), 0.0, c);
    let albedo = |m: &MaterialModel| -> Result<Rgb, lustre_brdf::BrdfError> {
        Ok(sampled_albedo(
            lustre_brdf::from_model(m)?.as_ref(),
            wo,
            ALBEDO_STRATA,
        ))
    };
    match model {
        MaterialModel::RoughConductor { .. } => albedo(model),
        MaterialModel::Phong {
            specular, exponent, ..
        } => albedo(&MaterialModel::Phong {
            diffuse: Rgb::ZERO,
            specular: *specular,
            exponent: *exponent,
        }),
        MaterialModel::Ward {
            specular,
            alpha_x,
            alpha_y,
            ..
        } => albedo(&MaterialModel::Ward {
            diffuse: Rgb::ZERO,
            specular: *specular,
            alpha_x: *alpha_x,
            alpha_y: *alpha_y,
        }),
        MaterialModel::Blend {
            weight,
            first,
            second,
        } => Ok(glossy_albedo(first, c)? * (1.0 - weight) + glossy_albedo(second, c)? * *weight),
        _ => Ok(Rgb::ZERO),
    }
}

/// The `N` shear slopes `Δ = 2m` of a lobe of roughness `α` (module docs):
/// stratified over [`hammersley_centred`], radius `2α √(−ln(1 − u))`
/// (the Rayleigh radius of a Gaussian with variance `2α²` per axis), angle
/// `2π v`. One sample is no shear (the mirror image).
pub fn shear_slopes(alpha: f32, samples: u32) -> Vec<Vec2> {
    if samples <= 1 {
        return vec![Vec2::ZERO; samples as usize];
    }
    (0..samples)
        .map(|i| {
            let u = hammersley_centred(i, samples);
            let radius = 2.0 * alpha * (-(1.0 - u.x).ln()).sqrt();
            let angle = std::f32::consts::TAU * u.y;
            Vec2::new(angle.cos(), angle.sin()) * radius
        })
        .collect()
}

/// Smith's masking `G₁` of the Beckmann distribution for a direction `cos θ`
/// from the normal (Walter et al. 2007's rational fit, within 0.35 %).
fn beckmann_g1(cos_theta: f32, alpha: f32) -> f32 {
    let cos = cos_theta.clamp(1e-6, 1.0);
    let tan = (1.0 - cos * cos).max(0.0).sqrt() / cos;
    let a = 1.0 / (alpha * tan).max(1e-12);
    if a >= 1.6 {
        1.0
    } else {
        (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    }
}

/// The `N` (shear, weight) pairs of a Beckmann lobe of roughness `alpha` at
/// the face point `centroid` of `plane` seen from `eye`: facet slopes `m`
/// from the stratified samples of [`shear_slopes`] (`m = Δ/2`, the slope
/// distribution `P₂₂`, i.e. half vectors drawn ∝ `D(h) cos θ_h`), the eye ray
/// reflected about each facet, the shear its slope minus the mirror
/// direction's, and the weight of the half-vector estimator
/// `G(i, o) |o·h| / (|i·n| (h·n))` (Walter et al. 2007, F taken out into the
/// face's factor); weight 0 where the facet is turned away from the eye or
/// reflects below the face. Near normal incidence and for small α this is
/// the isotropic `Δ ≈ 2m` with weights ≈ 1; at incidence θ the shear in the
/// plane of incidence grows by about `1/cos²θ`.
pub fn microfacet_shears(
    alpha: f32,
    samples: u32,
    eye: Vec3,
    plane: &lustre_geometry::Plane,
    centroid: Vec3,
) -> Vec<(Vec2, f32)> {
    let n = plane.normal.normalize();
    let (t, b) = crate::view::face_frame(plane);
    let to_eye = (eye - centroid).normalize();
    let i = -to_eye;
    let reflect = |h: Vec3| i - 2.0 * i.dot(h) * h;
    let slope = |v: Vec3| Vec2::new(v.dot(t), v.dot(b)) / v.dot(n);
    let mirror = slope(reflect(n));
    let cos_i = to_eye.dot(n);
    if !(cos_i > 0.0) {
        return vec![(Vec2::ZERO, 0.0); samples as usize];
    }
    let count = samples.max(1);
    let slopes = if count == 1 {
        vec![Vec2::ZERO]
    } else {
        shear_slopes(alpha, count)
    };
    slopes
        .into_iter()
        .map(|s| {
            let m = 0.5 * s;
            let h = (n + t * m.x + b * m.y).normalize();
            let o = reflect(h);
            let (cos_o, cos_h, o_h) = (o.dot(n), h.dot(n), o.dot(h));
            if !(cos_o > 1e-4) || to_eye.dot(h) <= 0.0 {
                return (Vec2::ZERO, 0.0);
            }
            let g = beckmann_g1(cos_i, alpha) * beckmann_g1(cos_o, alpha);
            (slope(o) - mirror, g * o_h.abs() / (cos_i * cos_h))
        })
        .collect()
}

/// The fog factor `f = clamp(1 − z / f_max, 0, 1)` of a point `z` m from the face (1: no fog).
pub fn fog_factor(z: f32, f_max: f32) -> f32 {
    if !f_max.is_finite() {
        return 1.0;
    }
    (1.0 - z.max(0.0) / f_max).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shear_slopes_have_the_lobes_second_moment() {
        // E|Δ|² = 4α² for Δ = 2m, E|m|² = α² (module docs); stratified, so close at N = 256.
        let alpha = 0.05;
        let slopes = shear_slopes(alpha, 256);
        let second = slopes.iter().map(|s| s.length_squared()).sum::<f32>() / 256.0;
        assert!(
            (second / (4.0 * alpha * alpha) - 1.0).abs() < 0.05,
            "{second}"
        );
        let mean = slopes.iter().copied().sum::<Vec2>() / 256.0;
        assert!(mean.length() < 0.05 * alpha, "{mean}");
        assert_eq!(shear_slopes(alpha, 1), vec![Vec2::ZERO]);
    }

    #[test]
    fn lobes_map_to_alpha() {
        // Phong n = 198: α² = 2/200.
        assert!((phong_alpha(198.0) - 0.1).abs() < 1e-6);
        let floor = lustre_geometry::builtin::glosbox();
        let glossy: Vec<GlossyLobe> = floor
            .materials()
            .iter()
            .filter_map(|m| glossy_lobe(&m.model))
            .collect();
        // Gold (α 0.1, F0 of gold) and the floor's 0.3 of a rough mirror (α 0.05, F = 1).
        assert_eq!(glossy.len(), 2);
        assert!((glossy[0].alpha - 0.1).abs() < 1e-6);
        assert!(glossy[0].factor.x > 0.8 && glossy[0].factor.z < 0.5);
        assert!((glossy[1].alpha - 0.05).abs() < 1e-6);
        assert!((glossy[1].factor - Vec3::splat(0.3)).abs().max_element() < 1e-6);
        assert!(
            glossy_lobe(&MaterialModel::Diffuse {
                reflectance: Vec3::ONE
            })
            .is_none()
        );
    }

    #[test]
    fn microfacet_shears_are_the_isotropic_ones_at_normal_incidence_and_stretch_at_grazing() {
        let plane = lustre_geometry::Plane::from_point_normal(Vec3::ZERO, Vec3::Y);
        let alpha = 0.02;
        let iso = shear_slopes(alpha, 64);
        let normal = microfacet_shears(alpha, 64, Vec3::new(0.0, 2.0, 0.0), &plane, Vec3::ZERO);
        for ((s, w), d) in normal.iter().zip(&iso) {
            // Δ = 2m to first order: the error is O(m²) relative.
            assert!((*s - *d).length() < 0.02 * d.length() + 1e-6, "{s} vs {d}");
            assert!((w - 1.0).abs() < 0.01, "{w}");
        }
        // At 70° incidence the in-plane spread grows by about 1/cos²70° ≈ 8.5.
        let theta = 70f32.to_radians();
        let eye = 2.0 * Vec3::new(0.0, theta.cos(), theta.sin());
        let (t, b) = crate::view::face_frame(&plane);
        let grazing = microfacet_shears(alpha, 64, eye, &plane, Vec3::ZERO);
        let along = |v: Vec2| (t * v.x + b * v.y).z;
        let across = |v: Vec2| (t * v.x + b * v.y).x;
        let rms = |f: &dyn Fn(Vec2) -> f32, set: &[Vec2]| {
            (set.iter().map(|v| f(*v).powi(2)).sum::<f32>() / set.len() as f32).sqrt()
        };
        let g: Vec<Vec2> = grazing.iter().map(|(s, _)| *s).collect();
        let stretch = rms(&along, &g) / rms(&along, &iso);
        let side = rms(&across, &g) / rms(&across, &iso);
        let expected = 1.0 / theta.cos().powi(2);
        assert!(
            (stretch / expected - 1.0).abs() < 0.1,
            "{stretch} vs {expected}"
        );
        assert!((side - 1.0).abs() < 0.1, "{side}");
    }

    #[test]
    fn fog_is_linear_from_the_face_to_f_max() {
        assert_eq!(fog_factor(0.0, 2.0), 1.0);
        assert_eq!(fog_factor(1.0, 2.0), 0.5);
        assert_eq!(fog_factor(3.0, 2.0), 0.0);
        assert_eq!(fog_factor(3.0, f32::INFINITY), 1.0);
    }

    /// The glossy albedo leaves the Lambertian side out, scales a blend's
    /// glossy side by its weight, and is the lobe's reflectance: near 1 for
    /// a smooth rough mirror with F = 1 (a little less at grazing, where
    /// Smith's masking takes its share), never above 1.
    #[test]
    fn glossy_albedo_is_the_glossy_sides_reflectance() {
        use lustre_geometry::material::MicrofacetDistribution;
        let mirror = MaterialModel::RoughConductor {
            distribution: MicrofacetDistribution::Beckmann,
            alpha: 0.05,
            fresnel: ConductorFresnel::None,
            specular: Vec3::ONE,
        };
        let white = MaterialModel::Diffuse {
            reflectance: Vec3::splat(0.8),
        };
        assert_eq!(glossy_albedo(&white, 0.5).unwrap(), Vec3::ZERO);
        let floor = MaterialModel::Blend {
            weight: 0.3,
            first: Box::new(white),
            second: Box::new(mirror.clone()),
        };
        for c in [1.0f32, 0.5, 0.2, 0.05] {
            let a = glossy_albedo(&mirror, c).unwrap();
            let b = glossy_albedo(&floor, c).unwrap();
            assert!(
                (b - a * 0.3).abs().max_element() < 1e-5,
                "{c}: {b} vs 0.3 × {a}"
            );
            assert!(a.max_element() <= 1.0 + 1e-3, "{c}: {a}");
            let floor_value = if c >= 0.2 { 0.97 } else { 0.6 };
            assert!(a.min_element() > floor_value, "{c}: {a}");
        }
    }
}
