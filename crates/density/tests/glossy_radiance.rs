//! The view-dependent glossy estimates of Impact Count and Photon Maps (section 2.10 with section 1.2's estimators) on a Phong plane under a point light, against their expected values computed by quadrature of equation 2.1's integrand, and against DETP's glossy estimate on the same rays.
//!
//! The plane `y = 0` reflects with Phong's original, non-reciprocal model
//! (`f = kd/π + ks cos^n α / cos θi`, α between `ωi` and the mirror of `ωo`),
//! written out here independently of `lustre-brdf`, so that the estimators
//! must evaluate `f_r(ωi = light side, ωo = eye side)` in that order.
//!
//! Each estimator is a sum over impacts `Σ w(y_j) φ` with a fixed weight
//! `w(y) = f_r(ωi(y), ωo) / A` over a region `R` (Impact Count's star of
//! triangles, DETP's disc), so with the impacts a Poisson process of density
//! `E(y)/φ` its mean is `∫_R f_r E dA / A` and its variance
//! `φ ∫_R f_r² E dA / A²`. Photon Maps' radius is random: with `λ` impacts per
//! m² near `x`, `π r_k² λ ~ Gamma(k, 1)`, so `E[Σ_k f_r φ / (π r_k²)] = k/(k−1)`
//! times the mean of `f_r E` over the disc holding `k` expected impacts, with
//! relative σ `k / ((k−1) √(k−2))`. The photons are emitted quasi-randomly,
//! which only lowers the variance, so these σ are upper bounds.

use std::f64::consts::PI;
use std::sync::OnceLock;

use glam::{Affine3A, DVec2, DVec3, Vec3};
use lustre_density::glossy::{GlossyMode, GlossyVertices};
use lustre_density::{
    Estimator, QuasiStatic, QuasiStaticOptions, RaySet, RaySetOptions, impact_count_radiance,
    photon_maps_radiance, trace_ray_set,
};
use lustre_geometry::light::PointLight;
use lustre_geometry::meshing::subdivide;
use lustre_geometry::{Bvh, Camera, Light, Material, MaterialModel, Mesh, Object, Rgb, Scene};

/// Half-size of the plane.
const HALF: f32 = 3.0;
/// Height of the point light above the origin.
const HEIGHT: f64 = 1.0;
/// Intensity `I` of the point light (W/sr).
const INTENSITY: f64 = 1.0;
/// Photons of the ray set.
const PHOTONS: u64 = 200_000;
/// Phong's diffuse reflectance `kd`.
const KD: f64 = 0.1;
/// Phong's specular coefficient `ks`.
const KS: f64 = 0.5;
/// Phong's exponent `n`.
const EXPONENT: f64 = 10.0;
/// Allowed deviation, in standard deviations.
const SIGMAS: f64 = 5.0;
/// The eye: off to the side, so that `cos θi ≠ cos θo` and the argument order of the non-reciprocal BRDF matters.
const EYE: Vec3 = Vec3::new(-2.0, 1.2, 0.5);

/// The Phong plane, subdivided to 0.25 m edges, under the point light.
fn plane_scene() -> Scene {
    let positions = [
        Vec3::new(-HALF, 0.0, -HALF),
        Vec3::new(-HALF, 0.0, HALF),
        Vec3::new(HALF, 0.0, HALF),
        Vec3::new(HALF, 0.0, -HALF),
    ];
    let plane = Mesh::flat("plane", &positions, &[[0, 1, 2], [2, 3, 0]], 0);
    let plane = subdivide(&plane, 0.25).expect("subdivides");
    let params = [
        ("diffuse".to_string(), vec![KD as f32]),
        ("specular".to_string(), vec![KS as f32]),
        ("exponent".to_string(), vec![EXPONENT as f32]),
    ]
    .into_iter()
    .collect();
    let material = Material::new(
        "phong",
        MaterialModel::Named {
            model: "phong".into(),
            params,
        },
    );
    Scene::new(
        "phong-plane",
        vec![plane],
        vec![material],
        vec![Object {
            name: "plane".into(),
            meshes: vec![0],
            transform: Affine3A::IDENTITY,
        }],
        vec![Light::Point(PointLight {
            position: Vec3::new(0.0, HEIGHT as f32, 0.0),
            intensity: Rgb::splat(INTENSITY as f32),
        })],
        Camera::look_at(EYE, Vec3::ZERO, Vec3::Y, 40.0),
    )
    .expect("valid scene")
}

fn shared() -> &'static (Scene, RaySet) {
    static SHARED: OnceLock<(Scene, RaySet)> = OnceLock::new();
    SHARED.get_or_init(|| {
        let scene = plane_scene();
        let bvh = Bvh::build(&scene);
        let options = RaySetOptions {
            photons: PHOTONS,
            seed: 11,
            max_segments: 4,
            extension: 0.0,
        };
        let rays = trace_ray_set(&scene, &bvh, &options).expect("traces");
        (scene, rays)
    })
}

/// Power of one photon, `φ = 4π I / N`.
fn photon_power() -> f64 {
    4.0 * PI * INTENSITY / PHOTONS as f64
}

/// The point on the plane at `(x, z)`.
fn point(p: DVec2) -> DVec3 {
    DVec3::new(p.x, 0.0, p.y)
}

/// Irradiance of the point light at `(x, z)`: `E = I h / d³`.
fn irradiance(p: DVec2) -> f64 {
    let d2 = p.length_squared() + HEIGHT * HEIGHT;
    INTENSITY * HEIGHT / (d2 * d2.sqrt())
}

/// Phong's BRDF (Phong 1975 as a BRDF): `kd/π + ks cos^n α / cos θi`, `wi` towards the light, `wo` towards the eye, normal +y.
fn phong(wi: DVec3, wo: DVec3) -> f64 {
    if wi.y <= 0.0 || wo.y <= 0.0 {
        return 0.0;
    }
    let mirror = DVec3::new(-wo.x, wo.y, -wo.z);
    KD / PI + KS * wi.dot(mirror).max(0.0).powf(EXPONENT) / wi.y
}

/// `f_r(ωi(y), ωo)` for an impact at `y` seen from a vertex whose eye direction is `wo`.
fn weight(y: DVec2, wo: DVec3) -> f64 {
    let wi = (DVec3::new(0.0, HEIGHT, 0.0) - point(y)).normalize();
    phong(wi, wo)
}

/// `(∫ f_r E dA, ∫ f_r² E dA)` over a triangle by the centroid rule on `4^depth` sub-triangles.
fn triangle_moments(t: [DVec2; 3], wo: DVec3, depth: u32) -> (f64, f64) {
    if depth == 0 {
        let area = 0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]).abs();
        let c = (t[0] + t[1] + t[2]) / 3.0;
        let (f, e) = (weight(c, wo), irradiance(c));
        return (area * f * e, area * f * f * e);
    }
    let m01 = (t[0] + t[1]) / 2.0;
    let m12 = (t[1] + t[2]) / 2.0;
    let m20 = (t[2] + t[0]) / 2.0;
    [
        [t[0], m01, m20],
        [m01, t[1], m12],
        [m20, m12, t[2]],
        [m01, m12, m20],
    ]
    .into_iter()
    .map(|s| triangle_moments(s, wo, depth - 1))
    .fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// `(∫ E dA, ∫ f_r E dA, ∫ f_r² E dA)` over the disc of radius `r` at `c` (polar midpoint rule).
fn disc_moments(c: DVec2, r: f64, wo: DVec3) -> (f64, f64, f64) {
    let (nr, na) = (40, 80);
    let (mut e0, mut e1, mut e2) = (0.0, 0.0, 0.0);
    for i in 0..nr {
        let rho = (i as f64 + 0.5) / nr as f64 * r;
        for j in 0..na {
            let a = (j as f64 + 0.5) / na as f64 * 2.0 * PI;
            let y = c + rho * DVec2::new(a.cos(), a.sin());
            let (f, e) = (weight(y, wo), irradiance(y));
            e0 += e * rho;
            e1 += f * e * rho;
            e2 += f * f * e * rho;
        }
    }
    let da = (r / nr as f64) * (2.0 * PI / na as f64);
    (e0 * da, e1 * da, e2 * da)
}

/// A vertex's expected estimate and its standard deviation.
#[derive(Debug, Clone, Copy)]
struct Expected {
    mean: f64,
    sigma: f64,
}

/// Impact Count's expectation at vertex `v`: the star's `∫ f_r E dA / A`, σ² = `φ ∫ f_r² E dA / A²`.
fn impact_count_expected(scene: &Scene, v: usize, wo: DVec3) -> Expected {
    let positions = scene.world_positions(0);
    let xz = |p: Vec3| DVec2::new(p.x as f64, p.z as f64);
    let (mut m1, mut m2, mut area) = (0.0, 0.0, 0.0);
    for idx in scene.meshes()[0]
        .indices
        .iter()
        .filter(|idx| idx.contains(&(v as u32)))
    {
        let t = idx.map(|i| xz(positions[i as usize]));
        let (a, b) = triangle_moments(t, wo, 5);
        m1 += a;
        m2 += b;
        area += 0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]).abs();
    }
    Expected {
        mean: m1 / area,
        sigma: (photon_power() * m2).sqrt() / area,
    }
}

/// DETP's expectation with discs of radius `r`: `∫_disc f_r E dA / (π r²)`, σ² = `φ ∫_disc f_r² E dA / (π r²)²`.
fn detp_expected(c: DVec2, r: f64, wo: DVec3) -> Expected {
    let (_, m1, m2) = disc_moments(c, r, wo);
    let area = PI * r * r;
    Expected {
        mean: m1 / area,
        sigma: (photon_power() * m2).sqrt() / area,
    }
}

/// Photon Maps' expectation with `k` impacts: `k/(k−1)` times the mean of `f_r E` over the disc holding `k` expected impacts, relative σ `k/((k−1)√(k−2))`.
fn photon_maps_expected(c: DVec2, k: usize, wo: DVec3) -> Expected {
    let kf = k as f64;
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if disc_moments(c, mid, wo).0 / photon_power() < kf {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let (_, m1, _) = disc_moments(c, hi, wo);
    let mean = kf / (kf - 1.0) * m1 / (PI * hi * hi);
    Expected {
        mean,
        sigma: mean * kf / ((kf - 1.0) * (kf - 2.0).sqrt()),
    }
}

/// The exact radiance towards the eye, equation 2.1 for a point light: `f_r(ωi, ωo) E`.
fn exact(c: DVec2, wo: DVec3) -> f64 {
    weight(c, wo) * irradiance(c)
}

/// The vertices checked: within 1.5 m of the centre, picked greedily at least 0.55 m apart (stars reach at most one 0.25 m edge, discs and `k`-neighbourhoods about 0.1 m, so no two share an impact and their errors are independent).
fn checked_vertices(scene: &Scene) -> Vec<(usize, DVec2, DVec3)> {
    let eye = EYE.as_dvec3();
    let mut picked: Vec<(usize, DVec2, DVec3)> = Vec::new();
    for (v, p) in scene.world_positions(0).iter().enumerate() {
        let c = DVec2::new(p.x as f64, p.z as f64);
        if c.x.abs() > 1.5 || c.y.abs() > 1.5 || picked.iter().any(|q| q.1.distance(c) < 0.55) {
            continue;
        }
        picked.push((v, c, (eye - point(c)).normalize()));
    }
    picked
}

/// Checks per-vertex estimates against their expectations: each within `SIGMAS` σ, and the mean of the `z` scores (independent vertices) within `SIGMAS / √M`; prints the largest bias `|mean − exact| / exact`.
fn check(name: &str, got: &[f64], expected: &[Expected], exacts: &[f64]) {
    let m = got.len() as f64;
    let mut z_sum = 0.0;
    let mut worst: f64 = 0.0;
    let mut worst_bias: f64 = 0.0;
    for ((&g, e), &x) in got.iter().zip(expected).zip(exacts) {
        let z = (g - e.mean) / e.sigma;
        assert!(
            z.abs() <= SIGMAS,
            "{name}: {g} against the expected {} (σ {}, exact {x})",
            e.mean,
            e.sigma
        );
        z_sum += z;
        worst = worst.max(z.abs());
        worst_bias = worst_bias.max((e.mean - x).abs() / x);
    }
    let z_mean = z_sum / m;
    eprintln!(
        "{name}: {m} vertices, worst |z| {worst:.2}, mean z {z_mean:.3}, largest kernel bias {:.2} %",
        100.0 * worst_bias
    );
    assert!(
        z_mean.abs() <= SIGMAS / m.sqrt(),
        "{name}: the mean z score {z_mean} over {m} independent vertices is off"
    );
}

#[test]
fn impact_count_glossy_estimate_matches_its_expectation() {
    let (scene, rays) = shared();
    let l = impact_count_radiance(scene, rays, EYE).expect("radiance");
    let vertices = checked_vertices(scene);
    assert!(vertices.len() >= 25, "{}", vertices.len());
    let got: Vec<f64> = vertices.iter().map(|&(v, ..)| l[0][v].x as f64).collect();
    let expected: Vec<Expected> = vertices
        .iter()
        .map(|&(v, _, wo)| impact_count_expected(scene, v, wo))
        .collect();
    let exacts: Vec<f64> = vertices.iter().map(|&(_, c, wo)| exact(c, wo)).collect();
    check("impact count", &got, &expected, &exacts);
}

#[test]
fn photon_maps_glossy_estimate_matches_its_expectation() {
    let (scene, rays) = shared();
    let k = 400;
    let l = photon_maps_radiance(scene, rays, k, EYE).expect("radiance");
    let vertices = checked_vertices(scene);
    let got: Vec<f64> = vertices.iter().map(|&(v, ..)| l[0][v].x as f64).collect();
    let expected: Vec<Expected> = vertices
        .iter()
        .map(|&(_, c, wo)| photon_maps_expected(c, k, wo))
        .collect();
    let exacts: Vec<f64> = vertices.iter().map(|&(_, c, wo)| exact(c, wo)).collect();
    check("photon maps", &got, &expected, &exacts);
}

/// DETP's glossy estimate (section 2.10) and the two new ones on the same rays: their differences match the differences of their expectations within the sum of their σ (a bound on the σ of a difference whatever the correlation).
#[test]
fn impact_count_and_photon_maps_agree_with_detp_glossy() {
    let (scene, rays) = shared();
    let (r, k) = (0.1, 400);
    let brdfs = lustre_photon::trace::scene_brdfs(scene).expect("brdfs");
    let detp = GlossyVertices::build(scene, rays, r as f32, GlossyMode::List, &[0])
        .expect("glossy vertices")
        .radiance(&brdfs, EYE)
        .expect("radiance");
    let ic = impact_count_radiance(scene, rays, EYE).expect("radiance");
    let pm = photon_maps_radiance(scene, rays, k, EYE).expect("radiance");
    let vertices = checked_vertices(scene);
    let detp_expected: Vec<Expected> = vertices
        .iter()
        .map(|&(_, c, wo)| detp_expected(c, r, wo))
        .collect();
    let exacts: Vec<f64> = vertices.iter().map(|&(_, c, wo)| exact(c, wo)).collect();
    let detp_got: Vec<f64> = vertices
        .iter()
        .map(|&(v, ..)| detp[0][v].x as f64)
        .collect();
    check("DETP glossy", &detp_got, &detp_expected, &exacts);
    for (name, l) in [("impact count", &ic), ("photon maps", &pm)] {
        let mut worst: f64 = 0.0;
        for (i, &(v, c, wo)) in vertices.iter().enumerate() {
            let e = if name == "photon maps" {
                photon_maps_expected(c, k, wo)
            } else {
                impact_count_expected(scene, v, wo)
            };
            let d = e.mean - detp_expected[i].mean;
            let got = l[0][v].x as f64 - detp_got[i];
            let bound = e.sigma + detp_expected[i].sigma;
            worst = worst.max(((got - d) / bound).abs());
            assert!(
                (got - d).abs() <= SIGMAS * bound,
                "{name} − DETP at {c}: {got}, expected {d} ± {bound}"
            );
        }
        eprintln!("{name} against DETP: worst |difference − expected| / (σ + σ_DETP) {worst:.2}");
    }
}

/// The modified Phong plane's diffuse reflectance, specular coefficient and exponent (`MaterialModel::Phong`: `kd/π + ks (n+2)/(2π) cos^n α`).
const MODIFIED: (f64, f64, f64) = (0.3, 0.4, 20.0);

/// The plane of [`plane_scene`] with `MaterialModel::Phong`, whose diffuse part `kd` the glossy estimate takes from the diffuse discs.
fn modified_phong_scene() -> Scene {
    let scene = plane_scene();
    let (kd, ks, n) = MODIFIED;
    let material = Material::new(
        "modified-phong",
        MaterialModel::Phong {
            diffuse: Rgb::splat(kd as f32),
            specular: Rgb::splat(ks as f32),
            exponent: n as f32,
        },
    );
    Scene::new(
        "modified-phong-plane",
        scene.meshes().to_vec(),
        vec![material],
        scene.objects().to_vec(),
        scene.lights().to_vec(),
        *scene.camera(),
    )
    .expect("valid scene")
}

/// The non-diffuse part of the modified Phong BRDF, `ks (n+2)/(2π) cos^n α`, written out independently of `lustre-brdf`.
fn modified_lobe(wi: DVec3, wo: DVec3) -> f64 {
    let (_, ks, n) = MODIFIED;
    if wi.y <= 0.0 || wo.y <= 0.0 {
        return 0.0;
    }
    let mirror = DVec3::new(-wo.x, wo.y, -wo.z);
    ks * (n + 2.0) / (2.0 * PI) * wi.dot(mirror).max(0.0).powf(n)
}

/// Where a segment crosses the plane `y = 0` from above, within its length (plus a slack for the segments that end on it), written out independently of `Disc`.
fn plane_crossing(s: &lustre_density::RaySegment) -> Option<DVec2> {
    let (o, d) = (s.origin.as_dvec3(), s.direction.as_dvec3());
    if !(d.y < 0.0) {
        return None;
    }
    let t = -o.y / d.y;
    (t >= 0.0 && t <= s.length() as f64 + 1e-3).then(|| DVec2::new(o.x + t * d.x, o.z + t * d.z))
}

/// DETP's glossy estimate with a glossy disc larger than the diffuse one (section 2.10 with `QuasiStaticOptions::glossy_radius`): `kd/π E` on discs of radius `r_d` plus `Σ f_lobe φ / (π r_g²)` on discs of `r_g`. Against a brute-force sum over the ray set's segments (each vertex, up to rounding), and against the expectation of both sums by quadrature (`(kd/π)·∫_d E dA / (π r_d²) + ∫_g f_lobe E dA / (π r_g²)`, σ at most the sum of the two sums' σ).
#[test]
fn detp_glossy_radius_splits_the_diffuse_part_from_the_lobe() {
    let scene = modified_phong_scene();
    let (r_d, r_g) = (0.08f64, 0.25f64);
    let mut options = QuasiStaticOptions::new(Estimator::Detp { radius: r_d as f32 }, PHOTONS);
    options.rays.seed = 11;
    options.rays.max_segments = 4;
    options.glossy = Some(GlossyMode::List);
    options.glossy_radius = Some(r_g as f32);
    let sim = QuasiStatic::new(scene.clone(), &[], options).expect("simulation");
    let l = sim
        .glossy_radiance(EYE)
        .expect("radiance")
        .expect("glossy on");
    let vertices = checked_vertices(&scene);
    assert!(vertices.len() >= 25, "{}", vertices.len());
    let (kd, ..) = MODIFIED;
    let crossings: Vec<(DVec2, DVec3, f64)> = sim
        .rays()
        .segments()
        .filter_map(|s| plane_crossing(s).map(|p| (p, -s.direction.as_dvec3(), s.power.x as f64)))
        .collect();
    let eye = EYE.as_dvec3();
    let (mut got, mut expected, mut exacts) = (Vec::new(), Vec::new(), Vec::new());
    for &(v, c, wo) in &vertices {
        // Brute force over the segments.
        let (mut diffuse, mut lobe) = (0.0, 0.0);
        for &(p, wi, phi) in &crossings {
            let d = p.distance(c);
            if d <= r_d {
                diffuse += phi;
            }
            if d <= r_g {
                lobe += modified_lobe(wi, (eye - point(c)).normalize()) * phi;
            }
        }
        let brute = kd / PI * diffuse / (PI * r_d * r_d) + lobe / (PI * r_g * r_g);
        let g = l[0][v].x as f64;
        assert!(
            (g - brute).abs() <= 1e-4 * brute,
            "vertex at {c}: {g} against the brute-force sum {brute}"
        );
        // Expectation by quadrature of the two discs.
        let (e_d, _, _) = disc_moments(c, r_d, wo);
        let phong_weight = |y: DVec2| {
            let wi = (DVec3::new(0.0, HEIGHT, 0.0) - point(y)).normalize();
            modified_lobe(wi, (eye - point(y)).normalize())
        };
        let (nr, na) = (40, 80);
        let (mut m1, mut m2) = (0.0, 0.0);
        for i in 0..nr {
            let rho = (i as f64 + 0.5) / nr as f64 * r_g;
            for j in 0..na {
                let a = (j as f64 + 0.5) / na as f64 * 2.0 * PI;
                let y = c + rho * DVec2::new(a.cos(), a.sin());
                let (f, e) = (phong_weight(y), irradiance(y));
                m1 += f * e * rho;
                m2 += f * f * e * rho;
            }
        }
        let da = (r_g / nr as f64) * (2.0 * PI / na as f64);
        let (area_d, area_g) = (PI * r_d * r_d, PI * r_g * r_g);
        let mean = kd / PI * e_d / area_d + m1 * da / area_g;
        let sigma = (photon_power() * e_d).sqrt() * kd / PI / area_d
            + (photon_power() * m2 * da).sqrt() / area_g;
        got.push(g);
        expected.push(Expected { mean, sigma });
        exacts.push(
            kd / PI * irradiance(c)
                + modified_lobe((DVec3::new(0.0, HEIGHT, 0.0) - point(c)).normalize(), wo)
                    * irradiance(c),
        );
    }
    check("DETP glossy, split radii", &got, &expected, &exacts);
}
