//! Light power, emission sampling and direct-light sampling against analytic results.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};
use lustre_geometry::light::{
    AreaLight, AreaShape, Light, OrientedPointLight, PointLight, SpotLight,
};

/// A tiny deterministic generator for the tests (SplitMix64), independent of the crate's samplers.
struct SplitMix(u64);
impl SplitMix {
    fn next_f32(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 40) as f32 / (1u64 << 24) as f32
    }
    fn vec2(&mut self) -> Vec2 {
        Vec2::new(self.next_f32(), self.next_f32())
    }
}

/// Radiant intensity of a light toward direction `w` (unit), written from the definitions.
fn intensity(light: &Light, w: Vec3) -> Vec3 {
    match light {
        Light::Point(p) => p.intensity,
        Light::OrientedPoint(p) => p.intensity * w.dot(p.normal).max(0.0),
        Light::Spot(s) => {
            let theta = w.dot(s.direction).clamp(-1.0, 1.0).acos();
            let f = if theta < s.beam_width {
                1.0
            } else if theta > s.cutoff_angle {
                0.0
            } else {
                1.0 - (theta - s.beam_width) / (s.cutoff_angle - s.beam_width)
            };
            s.intensity * f
        }
        Light::Area(_) => unreachable!(),
    }
}

/// ∫ I(ω) dω by the midpoint rule on a fine (θ, φ) grid.
fn integrate_intensity(light: &Light) -> Vec3 {
    let (nt, np) = (1000, 1000);
    let mut sum = Vec3::ZERO;
    for i in 0..nt {
        let theta = (i as f32 + 0.5) / nt as f32 * PI;
        for j in 0..np {
            let phi = (j as f32 + 0.5) / np as f32 * 2.0 * PI;
            let w = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            sum += intensity(light, w) * theta.sin() * (PI / nt as f32) * (2.0 * PI / np as f32);
        }
    }
    sum
}

fn point_lights() -> Vec<Light> {
    vec![
        Light::Point(PointLight {
            position: Vec3::ONE,
            intensity: Vec3::new(1.0, 2.0, 3.0),
        }),
        Light::OrientedPoint(OrientedPointLight {
            position: Vec3::ZERO,
            normal: Vec3::new(0.3, -1.0, 0.2).normalize(),
            intensity: Vec3::new(2.0, 1.0, 0.5),
        }),
        Light::Spot(SpotLight {
            position: Vec3::ZERO,
            direction: -Vec3::Y,
            intensity: Vec3::splat(10.0),
            cutoff_angle: 30f32.to_radians(),
            beam_width: 20f32.to_radians(),
        }),
        Light::Spot(SpotLight {
            position: Vec3::ZERO,
            direction: Vec3::X,
            intensity: Vec3::splat(1.0),
            cutoff_angle: 50f32.to_radians(),
            beam_width: 50f32.to_radians(),
        }),
    ]
}

fn rect_light() -> Light {
    Light::Area(AreaLight {
        mesh: None,
        shape: AreaShape::Rectangle {
            origin: Vec3::new(-0.23, 0.99, -0.18),
            edge_u: Vec3::new(0.46, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 0.38),
        },
        radiance: Vec3::new(18.387, 13.9873, 6.75357),
    })
}

fn triangle_light() -> Light {
    Light::Area(AreaLight {
        mesh: None,
        shape: AreaShape::triangles(vec![
            // Wound to face down (-Y).
            [
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(0.5, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.5),
            ],
            [
                Vec3::new(-0.5, 1.0, 0.0),
                Vec3::new(-0.2, 1.0, 0.0),
                Vec3::new(-0.5, 1.0, 0.2),
            ],
        ]),
        radiance: Vec3::splat(5.0),
    })
}

fn close(a: Vec3, b: Vec3, rel: f32) -> bool {
    (a - b).abs().max_element() <= rel * b.abs().max_element()
}

#[test]
fn point_light_power_equals_integrated_intensity() {
    for light in point_lights() {
        let numeric = integrate_intensity(&light);
        assert!(
            close(light.power(), numeric, 1e-3),
            "{light:?}: {} vs {numeric}",
            light.power()
        );
    }
}

#[test]
fn area_light_power_is_pi_l_a() {
    let l = rect_light();
    let area = 0.46 * 0.38;
    assert!(close(
        l.power(),
        PI * area * Vec3::new(18.387, 13.9873, 6.75357),
        1e-5
    ));
    let t = triangle_light();
    let area = 0.5 * 0.5 * 0.5 + 0.5 * 0.3 * 0.2;
    assert!(close(t.power(), Vec3::splat(PI * 5.0 * area), 1e-5));
    // The far-field cosine point light keeps the power.
    let Light::Area(a) = &l else { unreachable!() };
    let point = Light::OrientedPoint(a.to_oriented_point());
    assert!(close(point.power(), l.power(), 1e-5));
}

/// Monte Carlo mean of the emission weight equals the power; the weighted
/// histogram of directions equals the intensity integrated over each θ band.
#[test]
fn emission_samples_carry_the_power_and_the_intensity_distribution() {
    let n = 200_000;
    for light in point_lights()
        .into_iter()
        .chain([rect_light(), triangle_light()])
    {
        let mut rng = SplitMix(7);
        let bands = 12;
        let mut hist = vec![Vec3::ZERO; bands];
        let mut mean = Vec3::ZERO;
        let axis = match &light {
            Light::OrientedPoint(p) => p.normal,
            Light::Spot(s) => s.direction,
            _ => -Vec3::Y,
        };
        for _ in 0..n {
            let s = light.sample_emission(rng.vec2(), rng.vec2());
            assert!((s.direction.length() - 1.0).abs() < 1e-4);
            assert!(s.pdf_direction > 0.0 && s.pdf_position > 0.0);
            mean += s.weight / n as f32;
            let theta = s.direction.dot(axis).clamp(-1.0, 1.0).acos();
            let band = ((theta / PI * bands as f32) as usize).min(bands - 1);
            hist[band] += s.weight / n as f32;
        }
        assert!(
            close(mean, light.power(), 0.01),
            "{light:?}: mean weight {mean} vs power {}",
            light.power()
        );
        if matches!(light, Light::Area(_)) {
            // Area lights: cosine distribution about the normal.
            for (b, h) in hist.iter().enumerate() {
                let (t0, t1) = (
                    b as f32 / bands as f32 * PI,
                    (b + 1) as f32 / bands as f32 * PI,
                );
                // ∫ cos θ sin θ dθ dφ / π over the band (upper hemisphere only).
                let share = if t1 <= 0.5 * PI {
                    t1.sin().powi(2) - t0.sin().powi(2)
                } else {
                    0.0
                };
                let expected = light.power() * share;
                assert!(
                    (*h - expected).abs().max_element() <= 0.01 * light.power().max_element(),
                    "band {b}: {h} vs {expected}"
                );
            }
        } else {
            for (b, h) in hist.iter().enumerate() {
                let (t0, t1) = (
                    b as f32 / bands as f32 * PI,
                    (b + 1) as f32 / bands as f32 * PI,
                );
                let steps = 400;
                let mut expected = Vec3::ZERO;
                for k in 0..steps {
                    let theta = t0 + (k as f32 + 0.5) / steps as f32 * (t1 - t0);
                    let frame = lustre_geometry::sampling::Frame::from_normal(axis);
                    let w = frame.to_world(Vec3::new(theta.sin(), 0.0, theta.cos()));
                    // Every light here is symmetric about its axis.
                    expected +=
                        intensity(&light, w) * 2.0 * PI * theta.sin() * (t1 - t0) / steps as f32;
                }
                assert!(
                    (*h - expected).abs().max_element() <= 0.01 * light.power().max_element(),
                    "{light:?} band {b}: {h} vs {expected}"
                );
            }
        }
    }
}

/// Irradiance from a Lambertian polygon at a point, by Lambert's contour
/// integral: E = L/2 Σ Θᵢ (n · ĉᵢ), ĉᵢ the unit normal of the plane through
/// the point and edge i, Θᵢ the angle the edge subtends.
fn polygon_irradiance(radiance: f32, polygon: &[Vec3], p: Vec3, n: Vec3) -> f32 {
    let mut sum = 0.0;
    for i in 0..polygon.len() {
        let a = (polygon[i] - p).normalize();
        let b = (polygon[(i + 1) % polygon.len()] - p).normalize();
        let theta = a.dot(b).clamp(-1.0, 1.0).acos();
        let c = a.cross(b).normalize();
        sum += theta * n.dot(c);
    }
    // The polygon winds counter-clockwise seen from its lit side, so the sum is negative.
    (0.5 * radiance * sum).abs()
}

#[test]
fn direct_sampling_estimates_polygon_irradiance() {
    let receivers = [
        (Vec3::new(0.0, -1.0, 0.0), Vec3::Y),
        (
            Vec3::new(0.7, -0.5, 0.3),
            Vec3::new(-0.3, 1.0, 0.1).normalize(),
        ),
        (
            Vec3::new(-0.9, 0.5, -0.9),
            Vec3::new(1.0, 0.2, 0.3).normalize(),
        ),
    ];
    let light = rect_light();
    let polygon = [
        Vec3::new(-0.23, 0.99, -0.18),
        Vec3::new(-0.23, 0.99, 0.20),
        Vec3::new(0.23, 0.99, 0.20),
        Vec3::new(0.23, 0.99, -0.18),
    ];
    let tri = triangle_light();
    let tri_polys = [
        [
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.5),
            Vec3::new(0.5, 1.0, 0.0),
        ],
        [
            Vec3::new(-0.5, 1.0, 0.0),
            Vec3::new(-0.5, 1.0, 0.2),
            Vec3::new(-0.2, 1.0, 0.0),
        ],
    ];
    for (p, n) in receivers {
        let mut rng = SplitMix(3);
        let samples = 100_000;
        let (mut e_rect, mut e_tri) = (0.0f32, 0.0f32);
        for _ in 0..samples {
            let u = rng.vec2();
            if let Some(s) = light.sample_direct(p, u) {
                assert!(!s.is_delta && s.pdf > 0.0);
                assert!(((s.position - p).length() - s.distance).abs() < 1e-4);
                e_rect += s.weight.x * s.direction.dot(n).max(0.0) / samples as f32;
            }
            if let Some(s) = tri.sample_direct(p, u) {
                e_tri += s.weight.x * s.direction.dot(n).max(0.0) / samples as f32;
            }
        }
        let expected_rect = polygon_irradiance(18.387, &polygon, p, n);
        let expected_tri: f32 = tri_polys
            .iter()
            .map(|t| polygon_irradiance(5.0, t, p, n))
            .sum();
        assert!(
            (e_rect - expected_rect).abs() <= 0.01 * expected_rect,
            "{e_rect} vs {expected_rect}"
        );
        assert!(
            (e_tri - expected_tri).abs() <= 0.01 * expected_tri,
            "{e_tri} vs {expected_tri}"
        );
    }
}

#[test]
fn point_direct_samples_follow_inverse_square() {
    let p = Vec3::new(0.0, -1.0, 0.5);
    for light in point_lights() {
        let pos = match &light {
            Light::Point(l) => l.position,
            Light::OrientedPoint(l) => l.position,
            Light::Spot(l) => l.position,
            Light::Area(_) => unreachable!(),
        };
        let Some(s) = light.sample_direct(p, Vec2::ZERO) else {
            // Only a light that sends nothing toward p may return no sample.
            assert_eq!(
                intensity(&light, (p - pos).normalize()),
                Vec3::ZERO,
                "{light:?}"
            );
            continue;
        };
        let d = pos - p;
        assert!(s.is_delta);
        let expected = intensity(&light, -d.normalize()) / d.length_squared();
        assert!(
            close(s.weight, expected, 1e-4),
            "{light:?}: {} vs {expected}",
            s.weight
        );
    }
    // A receiver behind an area light gets nothing.
    assert!(
        rect_light()
            .sample_direct(Vec3::new(0.0, 2.0, 0.0), Vec2::splat(0.5))
            .is_none()
    );
}

#[test]
fn invalid_lights_are_rejected() {
    let zero = Light::Point(PointLight {
        position: Vec3::ZERO,
        intensity: Vec3::ZERO,
    });
    assert!(zero.validate("zero").is_err());
    let nan = Light::Point(PointLight {
        position: Vec3::ZERO,
        intensity: Vec3::new(f32::NAN, 1.0, 1.0),
    });
    assert!(nan.validate("nan").is_err());
    let spot = Light::Spot(SpotLight {
        position: Vec3::ZERO,
        direction: Vec3::Y,
        intensity: Vec3::ONE,
        cutoff_angle: 0.2,
        beam_width: 0.5,
    });
    assert!(spot.validate("spot").is_err());
    let flat = Light::Area(AreaLight {
        mesh: None,
        shape: AreaShape::Rectangle {
            origin: Vec3::ZERO,
            edge_u: Vec3::X,
            edge_v: Vec3::X,
        },
        radiance: Vec3::ONE,
    });
    assert!(flat.validate("flat").is_err());
}

/// Diefenbach & Badler's jittered point lights (section 4.4): `k` cosine
/// point lights on the shape, facing its normal, sharing the power equally;
/// `k = 1` is the paper's single point light of equal power.
#[test]
fn jittered_points_lie_on_the_light_share_its_power_and_reduce_to_the_centroid() {
    for light in [rect_light(), triangle_light()] {
        let Light::Area(area) = &light else {
            unreachable!()
        };
        assert_eq!(
            area.jittered_points(1, Vec2::ZERO),
            vec![area.to_oriented_point()]
        );
        for k in [2u32, 5, 16, 64] {
            for rotation in [Vec2::ZERO, Vec2::new(0.3, 0.8)] {
                let points = light.as_point_lights(k, rotation);
                assert_eq!(points.len(), k as usize);
                let total: Vec3 = points.iter().map(Light::power).sum();
                assert!(
                    close(total, light.power(), 1e-5),
                    "{total} vs {}",
                    light.power()
                );
                for p in &points {
                    let Light::OrientedPoint(p) = p else {
                        panic!("{p:?} is not a cosine point light")
                    };
                    assert!((p.normal - area.shape.mean_normal()).length() < 1e-5);
                    // On the plane of the light and within its bounds.
                    assert!(
                        (p.position.y - 0.99).abs() < 1e-5 || (p.position.y - 1.0).abs() < 1e-5
                    );
                    assert!(p.position.x >= -0.5 - 1e-5 && p.position.x <= 0.5 + 1e-5);
                }
            }
        }
        // The centred rectangle's stratified points average to its centroid.
        if let AreaShape::Rectangle { .. } = area.shape {
            let points = area.jittered_points(16, Vec2::ZERO);
            let mean = points.iter().map(|p| p.position).sum::<Vec3>() / 16.0;
            assert!((mean - area.shape.centroid()).length() < 1e-5, "{mean}");
        }
    }
    // Point lights pass through unchanged.
    for light in point_lights() {
        assert_eq!(light.as_point_lights(8, Vec2::ZERO), vec![light.clone()]);
    }
}

/// The centred Hammersley pattern: one point per x stratum for every n,
/// one per y stratum for powers of two, the centre for n = 1.
#[test]
fn centred_hammersley_is_stratified() {
    use lustre_geometry::light::hammersley_centred;
    assert_eq!(hammersley_centred(0, 1), Vec2::splat(0.5));
    for n in [1u32, 2, 3, 4, 7, 8, 16, 64] {
        let mut xs = vec![0; n as usize];
        let mut ys = vec![0; n as usize];
        for i in 0..n {
            let p = hammersley_centred(i, n);
            assert!(p.x > 0.0 && p.x < 1.0 && p.y > 0.0 && p.y < 1.0, "{p}");
            xs[(p.x * n as f32) as usize] += 1;
            ys[(p.y * n as f32) as usize] += 1;
        }
        assert!(xs.iter().all(|&c| c == 1), "n = {n}: x strata {xs:?}");
        if n.is_power_of_two() {
            assert!(ys.iter().all(|&c| c == 1), "n = {n}: y strata {ys:?}");
        }
    }
}

#[test]
fn pivot_lights_put_each_jittered_light_at_its_area_lights_centroid() {
    let rect = rect_light();
    let Light::Area(area) = &rect else {
        panic!("rect_light is an area light");
    };
    let centroid = area.shape.centroid();
    let point = point_lights().remove(0);
    let lights = vec![rect.clone(), point.clone()];
    for k in [1, 4, 16] {
        let jittered = lustre_geometry::light::jittered_point_lights(&lights, k, Vec2::ZERO);
        let pivots = lustre_geometry::light::pivot_point_lights(&lights, k);
        // One pivot per direct light, in the same order: k for the area light, the point light itself.
        assert_eq!(pivots.len(), jittered.len(), "k = {k}");
        for p in &pivots[..k as usize] {
            let Light::OrientedPoint(p) = p else {
                panic!("an area light's pivot is an oriented point light");
            };
            assert!((p.position - centroid).length() < 1e-6, "k = {k}");
        }
        assert_eq!(pivots[k as usize], point, "k = {k}");
    }
}
