//! Particle tracing with a non-reciprocal BRDF (Phong 1975) against an
//! independent brute-force path tracer of the same scene: photons must
//! scatter with the adjoint BSDF `f*(ω_out, ω_in) = f(ω_in, ω_out)` (Veach
//! 1997, sections 3.7.6 and 5.3.2), and the splat estimator must gather
//! with `f(ω_photon, ω_eye)` (Stürzlinger & Bastos 1997, equation 2).
//!
//! The scene: a Phong floor (no diffuse term, `ks = 0.4`, `n = 1`, so the
//! lobe is broad and `1/cos θi` matters) in `y = 0`, a vertical diffuse wall
//! at `x = 1`, and an isotropic point light. The path tracer uses only
//! lustre-geometry's BVH, the light's position and intensity and
//! lustre-brdf's `eval` in the radiance order `f(wi = to light, wo = to
//! viewer)`.

use glam::Vec3;
use lustre_brdf::{BoxedBrdf, from_model};
use lustre_geometry::light::PointLight;
use lustre_geometry::material::MaterialModel;
use lustre_geometry::sampling::{Frame, sample_cosine_hemisphere};
use lustre_geometry::{Bvh, Camera, Light, Material, Mesh, Object, Ray, Rgb, Scene};
use lustre_photon::{
    BounceSelection, EstimatorOptions, Kernel, NoProgress, SplatEstimator, Support, TraceOptions,
    photon_stream, trace_photons,
};

/// Position of the point light.
const LIGHT: Vec3 = Vec3::new(-0.6, 0.8, 0.0);
/// Radiant intensity of the point light in W/sr.
const INTENSITY: f32 = 10.0;

/// Phong's original model with a broad lobe (non-reciprocal through `1/cos θi`).
fn phong() -> MaterialModel {
    MaterialModel::Named {
        model: "phong".into(),
        params: [
            ("diffuse".to_owned(), vec![0.0]),
            ("specular".to_owned(), vec![0.4]),
            ("exponent".to_owned(), vec![1.0]),
        ]
        .into_iter()
        .collect(),
    }
}

/// The floor (surface 0, Phong) and the wall (surface 1, diffuse) under the point light.
fn scene() -> Scene {
    let floor = Mesh::flat(
        "floor",
        &[
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(-1.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, -1.0),
        ],
        &[[0, 1, 2], [2, 3, 0]],
        0,
    );
    let wall = Mesh::flat(
        "wall",
        &[
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(1.0, 2.0, 1.0),
            Vec3::new(1.0, 2.0, -1.0),
        ],
        &[[0, 1, 2], [2, 3, 0]],
        1,
    );
    let meshes = vec![floor, wall];
    let objects = Object::one_per_mesh(&meshes);
    Scene::new(
        "phong-floor",
        meshes,
        vec![
            Material::new("phong", phong()),
            Material::diffuse("wall", Rgb::splat(0.5)),
        ],
        objects,
        vec![Light::Point(PointLight {
            position: LIGHT,
            intensity: Rgb::splat(INTENSITY),
        })],
        Camera::look_at(Vec3::new(-2.0, 1.5, 0.0), Vec3::ZERO, Vec3::Y, 60.0),
    )
    .expect("valid scene")
}

/// The floor's local frame (normal +y, the side the light is on).
fn floor_frame() -> Frame {
    Frame::from_normal(Vec3::Y)
}

/// Radiance leaving the floor point `y` towards `to_viewer` from the light's direct illumination: `I/d² cos θi f(wi, wo)`, with `f(wi, wo)` in the radiance order, or `f(wo, wi)` when `swap` is set.
fn floor_radiance(bvh: &Bvh, brdf: &BoxedBrdf, y: Vec3, to_viewer: Vec3, swap: bool) -> f64 {
    let to_light = LIGHT - y;
    let d2 = to_light.length_squared();
    let wi = to_light / d2.sqrt();
    let frame = floor_frame();
    let (wi_l, wo_l) = (frame.to_local(wi), frame.to_local(to_viewer));
    if wi_l.z <= 0.0 || wo_l.z <= 0.0 {
        return 0.0;
    }
    let shadow = Ray::segment(y + 1e-4 * Vec3::Y, wi, 0.0, d2.sqrt() - 2e-4);
    if bvh.any_hit(&shadow) {
        return 0.0;
    }
    let f = if swap {
        brdf.eval(wo_l, wi_l)
    } else {
        brdf.eval(wi_l, wo_l)
    };
    f64::from(INTENSITY * wi_l.z / d2 * f.x)
}

/// Flux reaching the wall after exactly one reflection on the floor, by path tracing from the wall: `x` uniform on the wall (area 4), `ω` cosine distributed, estimator `A π L_floor(y → x)`. Returns the mean and its standard error.
fn path_traced_wall_flux(bvh: &Bvh, brdf: &BoxedBrdf, samples: u64, swap: bool) -> (f64, f64) {
    let mut rng = photon_stream(99, 0, 0);
    let frame = Frame::from_normal(-Vec3::X);
    let (mut s1, mut s2) = (0.0f64, 0.0f64);
    for _ in 0..samples {
        let u = rng.next_vec2();
        let x = Vec3::new(1.0, 2.0 * u.x, 2.0 * u.y - 1.0);
        let dir = frame.to_world(sample_cosine_hemisphere(rng.next_vec2()));
        let mut value = 0.0;
        if let Some(hit) = bvh.closest_hit(&Ray::new(x - 1e-4 * Vec3::X, dir)) {
            if hit.surface == 0 {
                value = 4.0
                    * std::f64::consts::PI
                    * floor_radiance(bvh, brdf, hit.position, -dir, swap);
            }
        }
        s1 += value;
        s2 += value * value;
    }
    let n = samples as f64;
    let mean = s1 / n;
    (mean, ((s2 / n - mean * mean).max(0.0) / n).sqrt())
}

/// Photons scattered once by the Phong floor carry onto the wall the flux the path tracer finds with `f(wi, wo)` in the radiance order, and not the flux of the swapped order (the non-adjoint tracing).
#[test]
fn particle_tracing_uses_the_adjoint_of_a_non_reciprocal_brdf() {
    let scene = scene();
    let bvh = Bvh::build(&scene);
    let brdf = from_model(&phong()).unwrap();
    assert!(!brdf.is_reciprocal());
    let photons = 400_000u64;
    let options = TraceOptions {
        photons,
        seed: 7,
        max_bounces: 2,
        ..TraceOptions::default()
    };
    let map = trace_photons(&scene, &bvh, &options, &NoProgress).unwrap();
    // Each photon leaves at most one second-bounce record, so the per-photon contributions are independent.
    let (mut s1, mut s2) = (0.0f64, 0.0f64);
    for r in map.records() {
        if r.surface == 1 && r.bounce == 2 {
            let phi = f64::from(map.photon_power(r).x);
            s1 += phi;
            s2 += phi * phi;
        }
    }
    let n = photons as f64;
    let particle = s1;
    let particle_err = (s2 - s1 * s1 / n).max(0.0).sqrt();
    let (path, path_err) = path_traced_wall_flux(&bvh, &brdf, 400_000, false);
    let (swapped, swapped_err) = path_traced_wall_flux(&bvh, &brdf, 400_000, true);
    let sigma = (particle_err.powi(2) + path_err.powi(2)).sqrt();
    let sigma_swapped = (particle_err.powi(2) + swapped_err.powi(2)).sqrt();
    println!(
        "flux onto the wall after one Phong bounce: particle {particle:.5} ± {particle_err:.5} W, path traced {path:.5} ± {path_err:.5} W, swapped order {swapped:.5} ± {swapped_err:.5} W"
    );
    assert!(
        (particle - path).abs() < 4.0 * sigma,
        "particle {particle} vs path traced {path}: {:.1} σ",
        (particle - path).abs() / sigma
    );
    // The test can tell the two orders apart.
    assert!(
        (particle - swapped).abs() > 8.0 * sigma_swapped,
        "particle {particle} vs swapped order {swapped}: only {:.1} σ apart",
        (particle - swapped).abs() / sigma_swapped
    );
}

/// Silverman's unit-volume 2D kernel `3/π (1 - r²)²` on the unit disc (written out here, independent of lustre-photon's `Kernel`).
fn silverman(r2: f64) -> f64 {
    if r2 < 1.0 {
        3.0 / std::f64::consts::PI * (1.0 - r2) * (1.0 - r2)
    } else {
        0.0
    }
}

/// The splat estimator gathers first-bounce photons on the Phong floor with `f(ω_photon, ω_eye)`: its value at a point equals the kernel-weighted direct radiance computed by quadrature, within its own standard error.
#[test]
fn splat_estimate_gathers_with_the_photon_direction_as_wi() {
    let scene = scene();
    let bvh = Bvh::build(&scene);
    let brdf = from_model(&phong()).unwrap();
    let photons = 400_000u64;
    let options = TraceOptions {
        photons,
        seed: 11,
        max_bounces: 1,
        ..TraceOptions::default()
    };
    let map = trace_photons(&scene, &bvh, &options, &NoProgress).unwrap();
    let h = 0.25f32;
    let estimator = SplatEstimator::build(
        &scene,
        &map,
        EstimatorOptions {
            kernel: Kernel::Silverman,
            support: Support::Fixed(h),
            selection: BounceSelection::Direct,
            edges: lustre_photon::Edges::Truncated,
        },
    )
    .unwrap();
    let x0 = Vec3::new(0.3, 0.0, 0.2);
    // A grazing view (cos θo ≈ 0.38) under a steeper light (cos θi ≈ 0.64 at x0).
    let wo = Vec3::new(1.0, 0.45, 0.5).normalize();
    let estimate = f64::from(estimator.radiance(0, x0, Vec3::Y, wo).x);
    // Its standard error from the photons' own contributions (at most one first hit each).
    let frame = floor_frame();
    let (mut s1, mut s2) = (0.0f64, 0.0f64);
    for s in estimator.splats().iter().filter(|s| s.surface == 0) {
        let r2 = f64::from((s.position - x0).length_squared() / (h * h));
        let f = brdf.eval(frame.to_local(s.incoming), frame.to_local(wo)).x;
        let c = f64::from(s.power.x * f) * silverman(r2) / f64::from(h * h);
        s1 += c;
        s2 += c * c;
    }
    let err = (s2 - s1 * s1 / photons as f64).max(0.0).sqrt();
    // The expectation by the midpoint rule on a polar grid over the kernel's disc.
    let expected = |swap: bool| {
        let (nr, na) = (200, 400);
        let mut sum = 0.0f64;
        for i in 0..nr {
            let r = (i as f64 + 0.5) / nr as f64;
            for j in 0..na {
                let a = (j as f64 + 0.5) / na as f64 * std::f64::consts::TAU;
                let y = x0 + h * Vec3::new((r * a.cos()) as f32, 0.0, (r * a.sin()) as f32);
                let area = r / nr as f64 * std::f64::consts::TAU / na as f64;
                sum += silverman(r * r) * area * floor_radiance(&bvh, &brdf, y, wo, swap);
            }
        }
        sum
    };
    let (right, swapped) = (expected(false), expected(true));
    println!(
        "radiance towards a grazing eye: estimator {estimate:.5} ± {err:.5}, quadrature f(wi, wo) {right:.5}, swapped {swapped:.5}"
    );
    assert!(
        (estimate - right).abs() < 4.0 * err + 1e-3 * right,
        "estimator {estimate} ± {err} vs quadrature {right}"
    );
    assert!((estimate - swapped).abs() > 8.0 * err);
}
