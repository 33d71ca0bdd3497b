//! Beam construction (Duvenhage et al. 2010, sections 3.1 and 4.3): scatter directions, flux split, skipped and refused input.

mod support;

use glam::Vec3;
use lustre_beams::{
    BeamError, BeamKind, BeamSet, BuildOptions, PointSource, ScatterMaterial, Scatterer, reflect,
    refract, solid_angle,
};
use lustre_brdf::fresnel_dielectric;
use lustre_geometry::{Aabb, Rgb};
use proptest::prelude::*;
use support::{bounds, mirror_triangle};

fn unit(v: [f32; 3]) -> Option<Vec3> {
    let v = Vec3::from(v);
    (v.length() > 0.1).then(|| v.normalize())
}

proptest! {
    #[test]
    fn refraction_obeys_snell(w in prop::array::uniform3(-1.0f32..1.0), n in prop::array::uniform3(-1.0f32..1.0), eta in 0.5f32..2.0) {
        let (Some(w), Some(n)) = (unit(w), unit(n)) else { return Ok(()) };
        let n = if w.dot(n) > 0.0 { -n } else { n };
        prop_assume!(w.dot(n) < -0.05);
        let sin_i = w.cross(n).length();
        match refract(w, n, eta) {
            Some(t) => {
                prop_assert!(sin_i / eta < 1.0 + 1e-5);
                // η sin θt = sin θi, t on the far side, in the plane of w and n.
                prop_assert!((eta * t.cross(n).length() - sin_i).abs() < 1e-4);
                prop_assert!(t.dot(n) < 0.0);
                prop_assert!(t.dot(w.cross(n)).abs() < 1e-4);
            }
            None => prop_assert!(sin_i / eta > 1.0 - 1e-5),
        }
        let r = reflect(w, n);
        prop_assert!((r.dot(n) + w.dot(n)).abs() < 1e-5);
        prop_assert!((r.length() - 1.0).abs() < 1e-5);
    }

    #[test]
    fn solid_angles_of_a_closed_octahedron_sum_to_four_pi(p in prop::array::uniform3(-0.3f32..0.3)) {
        let p = Vec3::from(p);
        let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
        let mut sum = 0.0f64;
        for sx in [-1.0f32, 1.0] {
            for sy in [-1.0f32, 1.0] {
                for sz in [-1.0f32, 1.0] {
                    sum += f64::from(solid_angle(p, [x * sx, y * sy, z * sz]));
                }
            }
        }
        prop_assert!((sum - 4.0 * std::f64::consts::PI).abs() < 1e-4, "{}", sum);
    }
}

fn water(ior: f32) -> Scatterer {
    Scatterer::flat(
        [
            Vec3::new(-0.5, 0.0, 0.5),
            Vec3::new(0.5, 0.0, 0.5),
            Vec3::new(0.0, 0.0, -0.5),
        ],
        ScatterMaterial::Interface {
            ior,
            transmittance: Rgb::ONE,
            roughness: 0.0,
        },
    )
}

#[test]
fn a_dielectric_splits_the_flux_by_fresnel_and_conserves_it() {
    let light = Vec3::new(0.1, 2.0, 0.2);
    let tri = water(1.33);
    assert!(tri.normals[0].y > 0.0);
    let set = BeamSet::build(
        &[PointSource::isotropic(light, Rgb::ONE)],
        &[tri],
        bounds(),
        &BuildOptions::default(),
    )
    .unwrap();
    let kinds: Vec<BeamKind> = set.beams().iter().map(|b| b.kind).collect();
    assert_eq!(
        kinds,
        [BeamKind::Reflected, BeamKind::Refracted, BeamKind::Shadow]
    );
    let [r, t, s] = [0, 1, 2].map(|i| set.beams()[i].flux.x);
    let omega = solid_angle(light, tri.vertices);
    let centroid = (tri.vertices[0] + tri.vertices[1] + tri.vertices[2]) / 3.0;
    let cos = (light - centroid).normalize().y;
    let f = fresnel_dielectric(cos, 1.33);
    assert!((r - f * omega).abs() < 1e-6 * omega);
    assert!((r + t + s).abs() < 1e-6 * omega, "{r} + {t} + {s}");
    // The refracted rays bend towards the normal (Snell, into water).
    let beam = set.beams()[1];
    for i in 0..3 {
        let w = (tri.vertices[i] - light).normalize();
        let d = beam.directions[i];
        assert!(d.y < 0.0 && d.cross(Vec3::Y).length() < w.cross(Vec3::Y).length());
        assert!((1.33 * d.cross(Vec3::Y).length() - w.cross(Vec3::Y).length()).abs() < 1e-5);
    }
}

#[test]
fn total_internal_reflection_leaves_out_the_refracted_beam() {
    // Under water (the light on the back, inside), at grazing incidence
    // beyond the critical angle asin(1/1.33) ≈ 48.8°.
    let light = Vec3::new(4.0, -0.5, 0.0);
    let set = BeamSet::build(
        &[PointSource::isotropic(light, Rgb::ONE)],
        &[water(1.33)],
        bounds(),
        &BuildOptions::default(),
    )
    .unwrap();
    let kinds: Vec<BeamKind> = set.beams().iter().map(|b| b.kind).collect();
    assert_eq!(kinds, [BeamKind::Reflected, BeamKind::Shadow]);
    assert_eq!(set.stats().total_internal_reflection, 1);
    // All of the light is reflected: F = 1 beyond the critical angle.
    let [r, s] = [0, 1].map(|i| set.beams()[i].flux.x);
    assert!((r + s).abs() < 1e-7, "{r} {s}");
    // Reflected downwards, back into the water.
    assert!(set.beams()[0].directions.iter().all(|d| d.y < 0.0));
}

#[test]
fn mirrors_scatter_from_the_front_only() {
    let set = BeamSet::build(
        &[PointSource::isotropic(Vec3::new(0.0, -2.0, 0.0), Rgb::ONE)],
        &[mirror_triangle(0.0)],
        bounds(),
        &BuildOptions::default(),
    )
    .unwrap();
    assert_eq!(set.stats().back_facing, 1);
    let kinds: Vec<BeamKind> = set.beams().iter().map(|b| b.kind).collect();
    assert_eq!(kinds, [BeamKind::Shadow]);
}

#[test]
fn degenerate_triangles_are_skipped_and_counted() {
    let mut flat = mirror_triangle(0.0);
    flat.vertices[2] = (flat.vertices[0] + flat.vertices[1]) * 0.5;
    let set = BeamSet::build(
        &[PointSource::isotropic(Vec3::new(0.0, 2.0, 0.0), Rgb::ONE)],
        &[flat, mirror_triangle(0.0), flat],
        bounds(),
        &BuildOptions::default(),
    )
    .unwrap();
    assert_eq!(set.stats().degenerate, 2);
    assert_eq!(set.stats().pairs, 1);
    assert_eq!(set.beams().len(), 2);
    assert!(set.beams().iter().all(|b| b.scatterer == 1));
}

#[test]
fn bad_input_is_refused_with_typed_errors() {
    let options = BuildOptions::default();
    let light = PointSource::isotropic(Vec3::Y, Rgb::ONE);
    assert!(matches!(
        BeamSet::build(&[], &[mirror_triangle(0.0)], bounds(), &options),
        Err(BeamError::NoPointLight { .. })
    ));
    let mut nan = mirror_triangle(0.0);
    nan.vertices[1].x = f32::NAN;
    assert!(matches!(
        BeamSet::build(&[light], &[nan], bounds(), &options),
        Err(BeamError::InvalidInput { .. })
    ));
    let negative = PointSource::isotropic(Vec3::Y, Rgb::new(1.0, -1.0, 1.0));
    assert!(matches!(
        BeamSet::build(&[negative], &[mirror_triangle(0.0)], bounds(), &options),
        Err(BeamError::InvalidInput { .. })
    ));
    assert!(matches!(
        BeamSet::build(&[light], &[mirror_triangle(-0.1)], bounds(), &options),
        Err(BeamError::InvalidInput { .. })
    ));
    assert!(matches!(
        BeamSet::build(&[light], &[mirror_triangle(0.0)], Aabb::EMPTY, &options),
        Err(BeamError::InvalidInput { .. })
    ));
}

#[test]
fn cosine_and_spot_lights_scale_the_flux_by_their_profile_over_the_scatterer() {
    use lustre_beams::Emission;
    use lustre_geometry::light::SpotLight;
    let tri = mirror_triangle(0.0);
    let position = Vec3::new(0.3, 2.0, 0.1);
    let centroid = (tri.vertices[0] + tri.vertices[1] + tri.vertices[2]) / 3.0;
    let towards = (centroid - position).normalize();
    let flux = |emission: Emission| {
        let light = PointSource {
            position,
            intensity: Rgb::ONE,
            emission,
        };
        BeamSet::build(&[light], &[tri], bounds(), &BuildOptions::default())
            .unwrap()
            .beams()
            .iter()
            .find(|b| b.kind == BeamKind::Reflected)
            .map_or(0.0, |b| b.flux.x)
    };
    let iso = flux(Emission::Isotropic);
    let want_iso = support::REFLECTANCE.x * solid_angle(position, tri.vertices);
    assert!((iso - want_iso).abs() < 1e-6 * want_iso);
    let normal = Vec3::new(0.2, -1.0, 0.3).normalize();
    let cosine = flux(Emission::Cosine { normal });
    let want_cosine =
        support::REFLECTANCE.x * brute_force_projected(position, normal, tri.vertices);
    assert!(
        (cosine - want_cosine).abs() < 1e-3 * want_cosine,
        "{cosine} against {want_cosine}"
    );
    // Facing away: no light, no beam.
    assert_eq!(flux(Emission::Cosine { normal: -normal }), 0.0);
    let spot = SpotLight {
        position,
        direction: -Vec3::Y,
        intensity: Rgb::ONE,
        cutoff_angle: 0.5,
        beam_width: 0.1,
    };
    let theta = towards.dot(-Vec3::Y).acos();
    assert!(theta > 0.1 && theta < 0.5, "{theta}");
    let want = iso * (0.5 - theta) / 0.4;
    assert!((flux(Emission::Spot(spot)) - want).abs() < 1e-5 * iso);
}

/// `∫ max(0, n · ω) dω` over the triangle seen from `o`, by the midpoint
/// rule over its area (`cos θ_light cos θ_triangle / r² dA`) on a grid of
/// 250,000 sub-triangles.
fn brute_force_projected(o: Vec3, n: Vec3, [a, b, c]: [Vec3; 3]) -> f32 {
    let k = 500;
    let normal = (b - a).cross(c - a);
    let area = 0.5 * normal.length() as f64 / (k * k) as f64;
    let normal = normal.normalize();
    let mut sum = 0.0f64;
    let mut add = |u: f64, v: f64| {
        let p = a + (b - a) * u as f32 + (c - a) * v as f32;
        let d = p - o;
        let r2 = d.length_squared() as f64;
        let w = d.normalize();
        let cos_light = f64::from(n.dot(w).max(0.0));
        let cos_tri = f64::from(normal.dot(w).abs());
        sum += cos_light * cos_tri / r2 * area;
    };
    let h = 1.0 / k as f64;
    for i in 0..k {
        for j in 0..k - i {
            // The upward sub-triangle's centroid, and the downward one's.
            add((i as f64 + 1.0 / 3.0) * h, (j as f64 + 1.0 / 3.0) * h);
            if i + j + 1 < k {
                add((i as f64 + 2.0 / 3.0) * h, (j as f64 + 2.0 / 3.0) * h);
            }
        }
    }
    sum as f32
}

/// The exact flux of a cosine light through a triangle against brute force,
/// with the light in front of it, beside it (the triangle straddling the
/// light's horizon) and close to its plane, where the intensity towards the
/// centroid times the solid angle is far off.
#[test]
fn a_cosine_lights_flux_through_a_triangle_is_its_cosine_integrated_over_it() {
    use lustre_beams::{projected_solid_angle, solid_angle};
    let tri = [
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, -0.5),
        Vec3::new(0.0, 0.0, 1.0),
    ];
    let cases = [
        (
            Vec3::new(0.1, 1.0, 0.0),
            Vec3::new(0.2, -1.0, 0.1).normalize(),
        ),
        (Vec3::new(0.0, 0.5, 0.0), Vec3::X),
        (
            Vec3::new(0.3, 0.4, -0.2),
            Vec3::new(1.0, -0.3, 0.5).normalize(),
        ),
        (Vec3::new(-0.2, 0.05, 0.1), -Vec3::Y),
        (Vec3::new(0.0, 1.0, 0.0), Vec3::Y),
    ];
    for (o, n) in cases {
        let exact = projected_solid_angle(o, n, tri);
        let brute = brute_force_projected(o, n, tri);
        assert!(
            (exact - brute).abs() < 2e-3 * brute.max(1e-3),
            "{o} {n}: {exact} against {brute}"
        );
        assert!(exact <= solid_angle(o, tri) + 1e-6, "{o} {n}");
    }
    // Facing away, nothing.
    assert_eq!(
        projected_solid_angle(Vec3::new(0.0, 1.0, 0.0), Vec3::Y, tri),
        0.0
    );
}

#[test]
fn beams_wider_than_a_flux_plane_can_cut_are_left_out_and_counted() {
    // A mirror 100 m across, the light 1 cm above it: the vertex rays leave
    // almost horizontally, 120° apart, so no plane crosses all three.
    let huge = Scatterer::flat(
        [
            Vec3::new(100.0, 0.0, 0.0),
            Vec3::new(-50.0, 0.0, -86.6),
            Vec3::new(-50.0, 0.0, 86.6),
        ],
        mirror_triangle(0.0).material,
    );
    assert!(huge.normals[0].y > 0.0);
    let set = BeamSet::build(
        &[PointSource::isotropic(Vec3::new(0.0, 0.01, 0.0), Rgb::ONE)],
        &[huge],
        bounds(),
        &BuildOptions::default(),
    )
    .unwrap();
    assert_eq!(set.stats().too_wide, 2, "{:?}", set.stats());
    assert!(set.beams().is_empty());
}
