//! Estimators of section 1.2 against the analytic irradiance of a point light over a large diffuse floor, the disc test against a sampled one, and the kd-tree against brute force.

use std::f64::consts::PI;
use std::sync::OnceLock;

use glam::{Affine3A, DVec2, DVec3, Vec2, Vec3};
use lustre_density::kdtree::{
    brute_force_nearest, brute_force_nearest_where, brute_force_nearest_within,
};
use lustre_density::{
    DensityError, Disc, ImpactMap, KdTree, NORMAL_FILTER_COSINE, PrimaryRay, RaySegment, RaySet,
    RaySetOptions, SegmentHit, detp, impact_count, photon_maps, trace_ray_set,
};
use lustre_geometry::light::PointLight;
use lustre_geometry::meshing::subdivide;
use lustre_geometry::{Bvh, Camera, Light, Material, Mesh, Object, Rgb, Scene, WorldTriangle};
use proptest::prelude::*;

/// Half-size of the floor (y = 0, facing +y).
const HALF: f32 = 3.0;
/// Height of the point light above the origin.
const HEIGHT: f64 = 1.0;
/// Intensity `I` of the point light (W/sr, every channel).
const INTENSITY: f64 = 1.0;
/// Photons of the shared ray set.
const PHOTONS: u64 = 200_000;
/// Allowed deviation from the expectation, in standard deviations of the estimator's noise.
const SIGMAS: f64 = 5.0;

/// The floor, subdivided to edges of at most 0.25 m (a 24 × 24 grid of quads), albedo 0.5, under an isotropic point light; no other geometry.
fn floor_scene() -> Scene {
    let positions = [
        Vec3::new(-HALF, 0.0, -HALF),
        Vec3::new(-HALF, 0.0, HALF),
        Vec3::new(HALF, 0.0, HALF),
        Vec3::new(HALF, 0.0, -HALF),
    ];
    let floor = Mesh::flat("floor", &positions, &[[0, 1, 2], [2, 3, 0]], 0);
    let floor = subdivide(&floor, 0.25).expect("subdivides");
    Scene::new(
        "floor",
        vec![floor],
        vec![Material::diffuse("floor", Rgb::splat(0.5))],
        vec![Object {
            name: "floor".into(),
            meshes: vec![0],
            transform: Affine3A::IDENTITY,
        }],
        vec![Light::Point(PointLight {
            position: Vec3::new(0.0, HEIGHT as f32, 0.0),
            intensity: Rgb::splat(INTENSITY as f32),
        })],
        Camera::look_at(Vec3::new(0.0, 3.0, 3.0), Vec3::ZERO, Vec3::Y, 40.0),
    )
    .expect("valid scene")
}

/// The scene and its ray set, traced once for all tests.
fn shared() -> &'static (Scene, RaySet) {
    static SHARED: OnceLock<(Scene, RaySet)> = OnceLock::new();
    SHARED.get_or_init(|| {
        let scene = floor_scene();
        let bvh = Bvh::build(&scene);
        let rays = trace_ray_set(
            &scene,
            &bvh,
            &RaySetOptions {
                photons: PHOTONS,
                seed: 7,
                max_segments: 16,
                extension: 0.0,
            },
        )
        .expect("traces");
        (scene, rays)
    })
}

/// Power of one photon, `φ = Φ / N = 4π I / N`.
fn photon_power() -> f64 {
    4.0 * PI * INTENSITY / PHOTONS as f64
}

/// The analytic irradiance `E = I cos θ / d² = I h / d³` at `(x, z)` on the floor plane.
fn analytic(p: DVec2) -> f64 {
    let d2 = p.length_squared() + HEIGHT * HEIGHT;
    INTENSITY * HEIGHT / (d2 * d2.sqrt())
}

/// The Laplacian `ΔE` and bi-Laplacian `Δ²E` at `(x, z)`: `E = I h g(s)` with `s = |p|²`, `g = (s + h²)^{-3/2}`, and in the plane `Δ G(s) = 4 s G'' + 4 G'`.
fn laplacians(p: DVec2) -> (f64, f64) {
    let h2 = HEIGHT * HEIGHT;
    let u = p.length_squared() + h2;
    // ΔE = I h (9 u^{-5/2} − 15 h² u^{-7/2}) = I h G(u).
    let g = 9.0 * u.powf(-2.5) - 15.0 * h2 * u.powf(-3.5);
    let g1 = -22.5 * u.powf(-3.5) + 52.5 * h2 * u.powf(-4.5);
    let g2 = 78.75 * u.powf(-4.5) - 236.25 * h2 * u.powf(-5.5);
    let scale = INTENSITY * HEIGHT;
    (scale * g, scale * (4.0 * (u - h2) * g2 + 4.0 * g1))
}

/// The analytic mean of `E` over a disc of radius `r` at `p` (the mean-value expansion `Σ r^{2n} Δⁿ E / (4ⁿ n! (n+1)!)`, to `n = 2`; the next term, `r⁶ Δ³E / 9216`, is below 10⁻⁶ E for the radii used here).
fn analytic_disc_mean(p: DVec2, r: f64) -> f64 {
    let (l1, l2) = laplacians(p);
    analytic(p) + r * r / 8.0 * l1 + r.powi(4) / 192.0 * l2
}

/// `∫ E dA` over a triangle of the floor plane, by the centroid rule on `4^depth` congruent sub-triangles.
fn triangle_integral(t: [DVec2; 3], depth: u32) -> f64 {
    if depth == 0 {
        let area = 0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]).abs();
        return area * analytic((t[0] + t[1] + t[2]) / 3.0);
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
    .map(|s| triangle_integral(s, depth - 1))
    .sum()
}

/// `∫ E dA` over the disc of radius `r` at `c` on the floor plane (polar midpoint rule).
fn disc_integral(c: DVec2, r: f64) -> f64 {
    let (nr, na) = (48, 96);
    let mut sum = 0.0;
    for i in 0..nr {
        let rho = (i as f64 + 0.5) / nr as f64 * r;
        for j in 0..na {
            let a = (j as f64 + 0.5) / na as f64 * 2.0 * PI;
            sum += analytic(c + rho * DVec2::new(a.cos(), a.sin())) * rho;
        }
    }
    sum * (r / nr as f64) * (2.0 * PI / na as f64)
}

/// Floor coordinates `(x, z)` of a vertex.
fn xz(p: Vec3) -> DVec2 {
    DVec2::new(p.x as f64, p.z as f64)
}

#[test]
fn power_reaching_the_floor_matches_its_solid_angle() {
    let (_, rays) = shared();
    assert_eq!(rays.emitted(), PHOTONS);
    assert_eq!(rays.rays.len() as u64, PHOTONS);
    let emitted: f64 = rays.rays.iter().map(|r| r.segments[0].power.x as f64).sum();
    assert!((emitted - 4.0 * PI * INTENSITY).abs() < 1e-3, "{emitted}");
    // Every segment starts where its predecessor hit (within the offset).
    for r in &rays.rays {
        for w in r.segments.windows(2) {
            let hit = w[0].hit.expect("only the last segment may miss");
            assert!(hit.position.distance(w[1].origin) < 1e-3);
        }
    }
    // Solid angle of the floor from the light: Ω = 4 asin(a² / (a² + h²)).
    let a2 = (HALF as f64).powi(2);
    let omega = 4.0 * (a2 / (a2 + HEIGHT * HEIGHT)).asin();
    let fraction = omega / (4.0 * PI);
    let first_hits = rays
        .rays
        .iter()
        .filter(|r| r.segments[0].hit.is_some())
        .count() as f64
        / PHOTONS as f64;
    let sigma = (fraction * (1.0 - fraction) / PHOTONS as f64).sqrt();
    eprintln!("first-hit fraction {first_hits:.5}, expected {fraction:.5} ± {sigma:.5}");
    assert!((first_hits - fraction).abs() < SIGMAS * sigma);
}

#[test]
fn impact_count_converges_to_the_analytic_irradiance() {
    let (scene, rays) = shared();
    let e = impact_count(scene, rays);
    let mesh = &scene.meshes()[0];
    let positions = scene.world_positions(0);
    let mut worst: f64 = 0.0;
    let mut worst_bias: f64 = 0.0;
    for (v, &p) in positions.iter().enumerate() {
        // Expectation: the mean of E over the vertex's star (the estimator's bias is that mean minus E).
        let (mut integral, mut area) = (0.0, 0.0);
        for idx in mesh.indices.iter().filter(|idx| idx.contains(&(v as u32))) {
            let t = idx.map(|i| xz(positions[i as usize]));
            integral += triangle_integral(t, 4);
            area += 0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]).abs();
        }
        let mean = integral / area;
        // Noise: the impact count in the star is Poisson with mean ∫E/φ, each impact of power φ.
        let sigma = (photon_power() * integral).sqrt() / area;
        let exact = analytic(xz(p));
        let got = e[0][v].x as f64;
        let z = (got - mean) / sigma;
        worst = worst.max(z.abs());
        assert!(
            z.abs() <= SIGMAS,
            "vertex {v} at {p}: {got} against its expectation {mean} (σ {sigma}, E = {exact})"
        );
        // The bias against its analytic value: `∫_T E dA = I Ω_T`, the solid angle of the triangle seen from the light (Van Oosterom & Strackee 1983: `tan(Ω/2) = |a·(b×c)| / (abc + (a·b)c + (a·c)b + (b·c)a)`), so the expectation is `I Σ Ω_t / Σ A_t` exactly; the centroid-rule quadrature agrees within 10⁻⁴ E.
        let light = DVec3::new(0.0, HEIGHT, 0.0);
        let solid_angle: f64 = mesh
            .indices
            .iter()
            .filter(|idx| idx.contains(&(v as u32)))
            .map(|idx| {
                let [a, b, c] = idx.map(|i| positions[i as usize].as_dvec3() - light);
                let (la, lb, lc) = (a.length(), b.length(), c.length());
                let num = a.dot(b.cross(c)).abs();
                let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
                2.0 * num.atan2(den)
            })
            .sum();
        let bias = mean - exact;
        let analytic_bias = INTENSITY * solid_angle / area - exact;
        worst_bias = worst_bias.max((bias - analytic_bias).abs() / exact);
        assert!(
            (bias - analytic_bias).abs() <= 1e-4 * exact,
            "vertex {v} at {p}: bias {bias} against the analytic {analytic_bias} (E = {exact})"
        );
    }
    eprintln!(
        "impact count: {} vertices, worst |z| = {worst:.2}, worst |bias − analytic| / E = {worst_bias:.2e}",
        positions.len()
    );
}

#[test]
fn photon_maps_converge_to_the_analytic_irradiance_inside_the_floor() {
    let (scene, rays) = shared();
    let k = 400usize;
    let e = photon_maps(scene, rays, k).expect("k > 0");
    let kf = k as f64;
    // With λ impacts per m², π r_k² λ ~ Gamma(k, 1): E[Σ_k φ / (π r_k²)] = E k/(k-1), relative σ = k/((k-1)√(k-2)).
    let rel_sigma = kf / ((kf - 1.0) * (kf - 2.0).sqrt());
    let mut checked = 0;
    let mut worst: f64 = 0.0;
    for (v, &p) in scene.world_positions(0).iter().enumerate() {
        let c = xz(p);
        if c.x.abs() > 1.5 || c.y.abs() > 1.5 {
            continue; // the border bias 1 - α/2π (section 2.9.1) is tested below
        }
        // Radius where the expected impact count reaches k.
        let (mut lo, mut hi) = (0.0, 1.5);
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if disc_integral(c, mid) / photon_power() < kf {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        assert!(
            c.x.abs().max(c.y.abs()) + hi < HALF as f64,
            "disc leaves the floor"
        );
        let mean = kf / (kf - 1.0) * disc_integral(c, hi) / (PI * hi * hi);
        let exact = analytic(c);
        let sigma = rel_sigma * mean;
        let got = e[0][v].x as f64;
        worst = worst.max(((got - mean) / sigma).abs());
        assert!(
            (got - mean).abs() <= SIGMAS * sigma,
            "vertex {v} at {p}: {got} against its expectation {mean} (σ {sigma}, E = {exact}, r {hi})"
        );
        // The bias, k/(k−1) times the disc mean less E, against its analytic value (the quadrature's 10⁻⁴ E as for DETP).
        let analytic_bias = kf / (kf - 1.0) * analytic_disc_mean(c, hi) - exact;
        assert!(
            ((mean - exact) - analytic_bias).abs() <= 1e-4 * exact,
            "vertex {v} at {p}: bias {} against the analytic {analytic_bias}",
            mean - exact
        );
        checked += 1;
    }
    eprintln!("photon maps k = {k}: {checked} vertices, worst |z| = {worst:.2}");
    assert!(checked > 100);
    // A corner vertex (α = π/2). The normal filter (Jensen 2001) changes nothing here: every impact lies on the floor and arrives from above, so its normal turned to the photon's side is +y, the vertex normal, cosine 1 ≥ NORMAL_FILTER_COSINE; it removes other surfaces' impacts, it does not fill the missing part of the disc. The k nearest impacts lie in the quarter disc inside the floor, so r_k is where the expected count in the quarter disc, ∫_quarter E dA / φ, reaches k; π r_k² λ / 4 ~ Gamma(k, 1). García et al.'s `Σ_k φ / (π r_k²)` would be ¼ · k/(k−1) · (mean of E over the quarter disc), the border bias α/2π = ¼; the boundary correction (`lustre_density::boundary`) divides by the area of the disc on the floor, ¼ π r_k² here up to rounding (the probe directions are symmetric under quarter turns and none runs along the floor's edges), so the estimate's mean is k/(k−1) times the quarter disc's mean of E, as inside the floor.
    let corner = scene
        .world_positions(0)
        .iter()
        .position(|p| p.x == HALF && p.z == HALF)
        .expect("corner vertex");
    let c = DVec2::splat(HALF as f64);
    let quarter = |r: f64| {
        // Polar midpoint rule over the quadrant towards −x, −z.
        let (nr, na) = (48, 48);
        let mut sum = 0.0;
        for i in 0..nr {
            let rho = (i as f64 + 0.5) / nr as f64 * r;
            for j in 0..na {
                let a = PI + (j as f64 + 0.5) / na as f64 * 0.5 * PI;
                sum += analytic(c + rho * DVec2::new(a.cos(), a.sin())) * rho;
            }
        }
        sum * (r / nr as f64) * (0.5 * PI / na as f64)
    };
    let (mut lo, mut hi) = (0.0, 2.0);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if quarter(mid) / photon_power() < kf {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let quarter_mean = quarter(hi) / (0.25 * PI * hi * hi);
    let expected = kf / (kf - 1.0) * quarter_mean;
    let got = e[0][corner].x as f64;
    let exact = analytic(c);
    eprintln!(
        "photon maps at the corner: {:.4} of E, expected {:.4} ± {:.4} (r_k {hi:.3} m)",
        got / exact,
        expected / exact,
        rel_sigma * expected / exact
    );
    assert!(
        (got - expected).abs() <= SIGMAS * rel_sigma * expected,
        "corner: {got} against {expected} (E = {exact})"
    );
    // The same impacts over π r_k² (no surfaces to probe): exactly a quarter of it.
    let plain = ImpactMap::build(rays)
        .irradiance(None, scene.world_positions(0)[corner], Vec3::Y, k)
        .x;
    assert!(
        (plain / got - 0.25).abs() <= 1e-6,
        "the plain corner estimate {plain} is not a quarter of {got}"
    );
}

/// A floor (y = 0) meeting a wall (x = 0) along the z axis, with impacts on the floor from above, on the floor from below, and on the wall from +x, the wall's geometric normal wound towards −x; one primary ray per impact, power 1 + j mod 3.
fn corner_impacts() -> (RaySet, Vec<(Vec3, Vec3, bool)>) {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut rays = Vec::new();
    // (position, arrival side, on the floor from above)
    let mut truth = Vec::new();
    for j in 0..3000u64 {
        let (a, b) = (next(), 2.0 * next() - 1.0);
        let kind = j % 3;
        let (position, direction, normal) = match kind {
            0 => (Vec3::new(a, 0.0, b), Vec3::NEG_Y, Vec3::Y),
            1 => (Vec3::new(a, 0.0, b), Vec3::Y, Vec3::Y),
            _ => (Vec3::new(0.0, a, b), Vec3::NEG_X, Vec3::NEG_X),
        };
        let origin = position - direction;
        let hit = SegmentHit {
            triangle: 0,
            mesh: 0,
            mobile: false,
            position,
            normal,
            distance: 1.0,
        };
        let power = Rgb::splat(1.0 + (j % 3) as f32);
        rays.push(PrimaryRay {
            light: 0,
            index: j,
            segments: vec![RaySegment::new(origin, direction, Some(hit), power)],
        });
        let side = if normal.dot(direction) > 0.0 {
            -normal
        } else {
            normal
        };
        truth.push((position, side, kind == 0));
    }
    (
        RaySet {
            rays,
            emitted_per_light: vec![3000],
        },
        truth,
    )
}

/// Jensen's normal filter (Jensen 2001, radiance estimate; beyond section 1.2): at a vertex near the floor/wall edge the estimate counts only the impacts on its own surface arriving from its front, checked against a brute-force estimate over exactly those impacts; and at the edge itself the filtered estimate of a uniform floor density sees only the half disc, the border bias α/2π = ½ of section 2.9.1, instead of gathering the wall.
#[test]
fn normal_filter_keeps_the_impacts_of_the_vertex_surface() {
    let (rays, truth) = corner_impacts();
    let map = ImpactMap::build(&rays);
    let positions: Vec<Vec3> = truth.iter().map(|t| t.0).collect();
    let powers: Vec<f64> = (0..truth.len()).map(|j| 1.0 + (j % 3) as f64).collect();
    let k = 20;
    let brute = |x: Vec3, n: Vec3| {
        let found = brute_force_nearest_where(&positions, x, k, |j| {
            truth[j as usize].1.dot(n) >= NORMAL_FILTER_COSINE
        });
        let r2 = found.last().unwrap().distance_squared as f64;
        found.iter().map(|f| powers[f.index as usize]).sum::<f64>() / (PI * r2)
    };
    for (x, n) in [
        (Vec3::new(0.02, 0.0, 0.1), Vec3::Y),
        (Vec3::new(0.3, 0.0, -0.4), Vec3::Y),
        (Vec3::new(0.0, 0.05, 0.2), Vec3::X),
        (Vec3::new(0.0, 0.02, 0.0), Vec3::NEG_Y),
    ] {
        let got = map.irradiance(None, x, n, k).x;
        let want = brute(x, n);
        assert!(
            (got - want).abs() <= 1e-6 * want,
            "at {x} normal {n}: {got} against brute force {want}"
        );
    }
    // The floor impacts from above (j ≡ 0 mod 3, power 1): 1000 over 2 m², λ = 500 per m², so E = 500 W/m² on the floor. At the edge, vertex normal +y, the filter keeps only them; the k nearest fill a half disc (r_k ≈ 0.5 m, inside the 1 m × 2 m floor), π r_k² λ / 2 ≈ k, so the plain estimate k / (π r_k²) ≈ λ/2 = E/2 with relative σ ≈ 1/√k: the border bias α/2π = ½. Unfiltered, the sphere holds three half discs of density 500 each (the floor from above, power 1; from below, power 2; the wall, power 3): k impacts in 1.5 π r² of mean power 2, so ≈ 2 · 1.5 · 500 = 3 E. With the floor and the wall to probe, the boundary correction divides by the half disc on the floor (up to rounding: the probe directions are point symmetric), so the estimate is twice the plain one, ≈ E.
    let k = 200;
    let origin = Vec3::new(0.0, 0.0, 0.0);
    let edge = map.irradiance(None, origin, Vec3::Y, k).x / 500.0;
    let unfiltered = map.irradiance(None, origin, Vec3::ZERO, k).x / 500.0;
    let surfaces = floor_and_wall();
    let corrected = map.irradiance(Some(&surfaces), origin, Vec3::Y, k).x / 500.0;
    eprintln!(
        "edge: filtered {edge:.3} E, unfiltered {unfiltered:.3} E, corrected {corrected:.3} E"
    );
    assert!(
        (edge - 0.5).abs() <= 5.0 * 0.5 / (k as f64).sqrt(),
        "{edge}"
    );
    assert!(
        (unfiltered - 3.0).abs() <= 5.0 * 3.0 / (k as f64).sqrt(),
        "{unfiltered}"
    );
    assert!(
        (corrected / edge - 2.0).abs() <= 1e-6,
        "{corrected} / {edge}"
    );
    // On the wall the filter keeps its impacts (power 3, 1000 over 2 m²: E = 1500 W/m²); the vertex on its foot sees half a disc of them too.
    let wall = map
        .irradiance(Some(&surfaces), Vec3::new(0.0, 0.0, 0.3), Vec3::X, k)
        .x
        / 1500.0;
    assert!(
        (wall - 1.0).abs() <= 5.0 / (k as f64).sqrt(),
        "wall foot: {wall} E"
    );
}

/// The geometry of [`corner_impacts`]: the floor `0 ≤ x ≤ 1`, `|z| ≤ 1` at `y = 0` and the wall `0 ≤ y ≤ 1`, `|z| ≤ 1` at `x = 0`, two triangles each.
fn floor_and_wall() -> Bvh {
    let quad = |corners: [Vec3; 4], normal: Vec3| {
        [[0, 1, 2], [2, 3, 0]].map(|idx: [usize; 3]| WorldTriangle {
            positions: idx.map(|i| corners[i]),
            normals: [normal; 3],
            uvs: [Vec2::ZERO; 3],
            surface: 0,
            material: 0,
        })
    };
    let floor = quad(
        [
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(0.0, 0.0, 1.0),
        ],
        Vec3::Y,
    );
    let wall = quad(
        [
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(0.0, 1.0, -1.0),
            Vec3::new(0.0, 1.0, 1.0),
            Vec3::new(0.0, 0.0, 1.0),
        ],
        Vec3::NEG_X,
    );
    Bvh::from_triangles(floor.into_iter().chain(wall).collect())
}

#[test]
fn detp_converges_to_the_analytic_irradiance_everywhere() {
    let (scene, rays) = shared();
    let r = 0.2;
    let e = detp(scene, rays, r as f32).expect("valid radius");
    let mut worst: f64 = 0.0;
    let positions = scene.world_positions(0);
    for (v, &p) in positions.iter().enumerate() {
        let c = xz(p);
        // Rays crossing the disc outside the floor leave the scene but still count, so even border vertices estimate the disc mean of E.
        let integral = disc_integral(c, r);
        let area = PI * r * r;
        let mean = integral / area;
        let sigma = (photon_power() * integral).sqrt() / area;
        let exact = analytic(c);
        let got = e[0][v].x as f64;
        let z = (got - mean) / sigma;
        worst = worst.max(z.abs());
        assert!(
            z.abs() <= SIGMAS,
            "vertex {v} at {p}: {got} against its expectation {mean} (σ {sigma}, E = {exact})"
        );
        // The bias of the quadrature against the mean-value expansion (10⁻⁴ E: the polar midpoint rule's error, measured 10⁻⁵).
        let bias = mean - exact;
        let analytic_bias = analytic_disc_mean(c, r) - exact;
        assert!(
            (bias - analytic_bias).abs() <= 1e-4 * exact,
            "vertex {v} at {p}: bias {bias} against the analytic {analytic_bias}"
        );
    }
    eprintln!(
        "DETP r = {r}: {} vertices, worst |z| = {worst:.2}",
        positions.len()
    );
}

#[test]
fn invalid_options_are_errors() {
    let (scene, rays) = shared();
    let bvh = Bvh::build(scene);
    let bad = RaySetOptions {
        max_segments: 0,
        ..RaySetOptions::default()
    };
    assert!(matches!(
        trace_ray_set(scene, &bvh, &bad),
        Err(DensityError::InvalidOption { .. })
    ));
    assert!(photon_maps(scene, rays, 0).is_err());
    for r in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        assert!(detp(scene, rays, r).is_err());
    }
    assert!(KdTree::build(&[Vec3::ZERO, Vec3::NAN]).is_err());
    assert!(KdTree::build_oriented(&[Vec3::ZERO], &[]).is_err());
    assert!(KdTree::build_oriented(&[Vec3::ZERO], &[Vec3::NAN]).is_err());
    // An empty ray set gives zero everywhere.
    let empty = RaySet::default();
    assert!(
        impact_count(scene, &empty)[0]
            .iter()
            .all(|e| *e == Rgb::ZERO)
    );
    assert!(
        photon_maps(scene, &empty, 5).unwrap()[0]
            .iter()
            .all(|e| *e == Rgb::ZERO)
    );
}

/// Whether the segment crosses the disc from the front, by marching: a step whose samples go from the front to the back of the plane, with the sample nearest the plane inside the disc.
fn marched_crossing(disc: &Disc, s: &RaySegment, steps: usize) -> bool {
    let length = s.length();
    let side = |t: f32| (s.origin + t * s.direction - disc.centre).dot(disc.normal);
    for i in 0..steps {
        let (t0, t1) = (
            length * i as f32 / steps as f32,
            length * (i + 1) as f32 / steps as f32,
        );
        if side(t0) > 0.0 && side(t1) <= 0.0 {
            let t = if side(t0).abs() < side(t1).abs() {
                t0
            } else {
                t1
            };
            let p = s.origin + t * s.direction;
            return p.distance(disc.centre) <= disc.radius;
        }
    }
    false
}

fn unit(v: [f32; 3]) -> Option<Vec3> {
    let v = Vec3::from(v);
    (v.length() > 0.1).then(|| v.normalize())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn disc_test_agrees_with_marching(
        centre in prop::array::uniform3(-1.0f32..1.0),
        normal in prop::array::uniform3(-1.0f32..1.0),
        radius in 0.05f32..1.0,
        origin in prop::array::uniform3(-2.0f32..2.0),
        direction in prop::array::uniform3(-1.0f32..1.0),
        length in 0.1f32..5.0,
    ) {
        let (Some(normal), Some(direction)) = (unit(normal), unit(direction)) else {
            return Ok(());
        };
        let disc = Disc { centre: Vec3::from(centre), normal, radius, mesh: None };
        let segment = RaySegment {
            origin: Vec3::from(origin),
            direction,
            hit: Some(SegmentHit { triangle: 0, mesh: 0, mobile: false, position: Vec3::from(origin) + length * direction, normal: Vec3::Y, distance: length }),
            power: Rgb::ONE,
            extension: 0.0,
        };
        let steps = 20_000;
        let step = length / steps as f32;
        // Skip the cases the marching cannot decide: the crossing within a few steps of the rim, of either end, or a grazing ray.
        let denom = direction.dot(normal);
        if denom.abs() > 0.05 {
            let t = (disc.centre - segment.origin).dot(normal) / denom;
            let rim = (segment.origin + t * direction).distance(disc.centre) - radius;
            if rim.abs() < 4.0 * step / denom.abs() || t.abs() < 4.0 * step || (t - length).abs() < 4.0 * step {
                return Ok(());
            }
        } else {
            return Ok(());
        }
        prop_assert_eq!(disc.is_crossed_by(&segment, 0.0), marched_crossing(&disc, &segment, steps));
        let expected = if disc.is_crossed_by(&segment, 0.0) { 1.0 / (std::f32::consts::PI * radius * radius) } else { 0.0 };
        prop_assert_eq!(disc.irradiance_of(&segment, 0.0).x, expected);
    }

    #[test]
    fn kd_tree_agrees_with_brute_force(
        points in prop::collection::vec(prop::array::uniform3(-10.0f32..10.0), 0..300),
        query in prop::array::uniform3(-12.0f32..12.0),
        k in 1usize..40,
        grid in any::<bool>(),
    ) {
        // Snapping to a coarse grid makes many equal distances, to exercise the ties.
        let points: Vec<Vec3> = points.iter().map(|&p| {
            let p = Vec3::from(p);
            if grid { p.round() } else { p }
        }).collect();
        let tree = KdTree::build(&points).unwrap();
        prop_assert_eq!(tree.len(), points.len());
        let query = Vec3::from(query);
        prop_assert_eq!(tree.nearest(query, k), brute_force_nearest(&points, query, k));
    }

    #[test]
    fn filtered_kd_tree_agrees_with_brute_force(
        points in prop::collection::vec(prop::array::uniform3(-10.0f32..10.0), 0..300),
        query in prop::array::uniform3(-12.0f32..12.0),
        k in 1usize..40,
        modulus in 1u32..5,
        max_squared in 0.0f32..200.0,
        grid in any::<bool>(),
    ) {
        // A predicate that rejects most points, so the pruning must look past rejected subtrees' roots.
        let points: Vec<Vec3> = points.iter().map(|&p| {
            let p = Vec3::from(p);
            if grid { p.round() } else { p }
        }).collect();
        let tree = KdTree::build(&points).unwrap();
        let query = Vec3::from(query);
        let keep = |i: u32| (i * 7 + 3).is_multiple_of(modulus);
        prop_assert_eq!(tree.nearest_where(query, k, keep), brute_force_nearest_where(&points, query, k, keep));
        prop_assert_eq!(
            tree.nearest_within(query, k, max_squared, keep),
            brute_force_nearest_within(&points, query, k, max_squared, keep)
        );
    }

    #[test]
    fn facing_kd_tree_agrees_with_brute_force(
        points in prop::collection::vec(
            (prop::array::uniform3(-10.0f32..10.0), 0usize..8, prop::array::uniform3(-1.0f32..1.0)),
            0..300,
        ),
        query in prop::array::uniform3(-12.0f32..12.0),
        normal in prop::array::uniform3(-1.0f32..1.0),
        k in 1usize..40,
        factor in 1.0f32..4.0,
        grid in any::<bool>(),
    ) {
        // Impacts on planes (axis normals, many equal coordinates when snapped) and on curved surfaces (random normals), so the normal boxes are tight on some subtrees and loose on others.
        let positions: Vec<Vec3> = points.iter().map(|&(p, _, _)| {
            let p = Vec3::from(p);
            if grid { p.round() } else { p }
        }).collect();
        let normals: Vec<Vec3> = points.iter().map(|&(_, axis, random)| match axis {
            0..6 => Vec3::AXES[axis % 3] * if axis < 3 { 1.0 } else { -1.0 },
            _ => Vec3::from(random).try_normalize().unwrap_or(Vec3::Y),
        }).collect();
        let normal = Vec3::from(normal).try_normalize().unwrap_or(Vec3::Y);
        let tree = KdTree::build_oriented(&positions, &normals).unwrap();
        let got = tree.nearest_facing(query.into(), k, factor * factor, normal, NORMAL_FILTER_COSINE);
        let all = brute_force_nearest(&positions, query.into(), k);
        let max_squared = all.last().map_or(0.0, |n| factor * factor * n.distance_squared);
        // The tree keeps its normals normalised (a no-op here but for rounding).
        let found = brute_force_nearest_within(&positions, query.into(), k, max_squared, |j| {
            normals[j as usize].normalize_or_zero().dot(normal) >= NORMAL_FILTER_COSINE
        });
        prop_assert_eq!(got.unfiltered, all.len());
        prop_assert_eq!(got.max_squared, max_squared);
        prop_assert_eq!(got.found, found);
    }
}
