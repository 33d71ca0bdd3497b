//! Particle tracing on diffuse texture maps (section 2.1 with `Material::diffuse_map`): the power a textured floor reflects at first hits against a brute-force integral of the texture over the light's footprint, and a uniform map against the untextured material it equals.

use std::sync::Arc;

use glam::{Vec2, Vec3};
use lustre_geometry::light::PointLight;
use lustre_geometry::material::MaterialModel;
use lustre_geometry::texture::Texture;
use lustre_geometry::{Bvh, Camera, Light, Material, Mesh, Object, Rgb, Scene};
use lustre_photon::{NoProgress, PhotonMap, TraceOptions, trace_photons};

/// Where the isotropic point light sits inside the box.
const LIGHT: Vec3 = Vec3::new(0.1, 0.3, -0.2);

/// The closed box [-1, 1]³ with inward faces: black walls and ceiling (material 0) and a floor y = −1 of `floor` (material 1) whose texture coordinates are `u = (x + 1)/2`, `v = (1 − z)/2`; an isotropic point light at [`LIGHT`].
fn box_with_floor(floor: Material) -> Scene {
    let p = Vec3::new;
    let corners = [
        p(-1.0, -1.0, -1.0),
        p(1.0, -1.0, -1.0),
        p(1.0, 1.0, -1.0),
        p(-1.0, 1.0, -1.0),
        p(-1.0, -1.0, 1.0),
        p(1.0, -1.0, 1.0),
        p(1.0, 1.0, 1.0),
        p(-1.0, 1.0, 1.0),
    ];
    let quads = [
        [0, 1, 2, 3],
        [5, 4, 7, 6],
        [4, 0, 3, 7],
        [1, 5, 6, 2],
        [3, 2, 6, 7],
    ];
    let mut indices = Vec::new();
    for q in quads {
        indices.push([q[0], q[1], q[2]]);
        indices.push([q[2], q[3], q[0]]);
    }
    let walls = Mesh::flat("walls", &corners, &indices, 0);
    let floor_corners = [corners[4], corners[5], corners[1], corners[0]];
    let uvs: Vec<Vec2> = floor_corners.iter().map(|c| floor_uv(*c)).collect();
    let floor_mesh = Mesh::flat_with_uvs("floor", &floor_corners, &uvs, &[[0, 1, 2], [2, 3, 0]], 1);
    assert!(
        floor_mesh.geometric_normal(0).y > 0.99,
        "the floor faces up"
    );
    let meshes = vec![walls, floor_mesh];
    let objects = Object::one_per_mesh(&meshes);
    Scene::new(
        "textured-floor-box",
        meshes,
        vec![Material::diffuse("black", Rgb::ZERO), floor],
        objects,
        vec![Light::Point(PointLight {
            position: LIGHT,
            intensity: Rgb::ONE,
        })],
        Camera::look_at(Vec3::ZERO, -Vec3::Z, Vec3::Y, 60.0),
    )
    .expect("valid scene")
}

/// The floor's texture coordinates at a point of the plane y = −1.
fn floor_uv(p: Vec3) -> Vec2 {
    Vec2::new((p.x + 1.0) / 2.0, (1.0 - p.z) / 2.0)
}

/// An `n × n` checker of 0.2 and 0.9 grey, the top-left texel 0.9, with a red-to-blue ramp across rows so that a transposed or flipped lookup changes the answer.
fn checker(n: u32) -> Texture {
    let texels = (0..n * n)
        .map(|i| {
            let (x, y) = (i % n, i / n);
            let g = if (x + y) % 2 == 0 { 0.9 } else { 0.2 };
            let ramp = y as f32 / (n - 1) as f32;
            Rgb::new(g * (1.0 - 0.5 * ramp), g, g * (0.5 + 0.5 * ramp))
        })
        .collect();
    Texture::new("checker", n, n, texels).unwrap()
}

/// `E[1_floor · tint(uv)]` over the isotropic light's directions, by a stratified brute-force ray count against the plane y = −1, independent of the BVH and the tracer.
fn floor_tint_integral(tint: impl Fn(Vec2) -> Rgb, strata: usize) -> [f64; 3] {
    let mut sum = [0.0f64; 3];
    for i in 0..strata {
        for j in 0..strata {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / strata as f64;
            let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / strata as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            // Uniform on the sphere, with y the height.
            let (dx, dy, dz) = (r * phi.cos(), z, r * phi.sin());
            if dy >= 0.0 {
                continue;
            }
            let t = (-1.0 - f64::from(LIGHT.y)) / dy;
            let (x, zz) = (f64::from(LIGHT.x) + t * dx, f64::from(LIGHT.z) + t * dz);
            if x.abs() > 1.0 || zz.abs() > 1.0 {
                continue;
            }
            let c = tint(floor_uv(Vec3::new(x as f32, -1.0, zz as f32)));
            for k in 0..3 {
                sum[k] += f64::from(c[k]);
            }
        }
    }
    sum.map(|s| s / (strata * strata) as f64)
}

/// Traces `n` photons and returns the map, the power of its second hits (all the power the floor reflects at first hits: the walls are black and the box closed) and that power's standard deviation, from the second moment of the per-photon contributions.
fn reflected_power(scene: &Scene, n: u64, seed: u64) -> (PhotonMap, [f64; 3], [f64; 3]) {
    let bvh = Bvh::build(scene);
    let options = TraceOptions {
        photons: n,
        seed,
        ..TraceOptions::default()
    };
    let map = trace_photons(scene, &bvh, &options, &NoProgress).unwrap();
    let mut sum = [0.0f64; 3];
    let mut sq = [0.0f64; 3];
    for r in map.records().iter().filter(|r| r.bounce == 2) {
        let p = map.photon_power(r);
        for c in 0..3 {
            sum[c] += f64::from(p[c]);
            sq[c] += f64::from(p[c]).powi(2);
        }
    }
    let sigma = std::array::from_fn(|c| (sq[c] - sum[c] * sum[c] / n as f64).max(0.0).sqrt());
    (map, sum, sigma)
}

#[test]
fn textured_floor_reflects_the_texture_weighted_power() {
    let rho = Rgb::new(0.8, 0.6, 0.7);
    for n in [2, 8] {
        let texture = Arc::new(checker(n));
        let floor = Material::diffuse("floor", rho).with_diffuse_map(texture.clone());
        let scene = box_with_floor(floor);
        let (_, got, sigma) = reflected_power(&scene, 200_000, 7);
        let integral = floor_tint_integral(|uv| texture.sample(uv), 1024);
        let phi = scene.total_power();
        for c in 0..3 {
            let expected = f64::from(phi[c]) * f64::from(rho[c]) * integral[c];
            let tolerance = 5.0 * sigma[c] + 1e-3 * expected;
            eprintln!(
                "{n}×{n} checker, channel {c}: reflected {:.5} W, expected {expected:.5} W ± {tolerance:.5}",
                got[c]
            );
            assert!((got[c] - expected).abs() <= tolerance);
        }
        // The texture matters: an untextured floor would reflect Φ ρ E[1_floor], well outside the tolerance.
        let untextured = floor_tint_integral(|_| Rgb::ONE, 1024);
        let plain = f64::from(phi[0]) * f64::from(rho[0]) * untextured[0];
        assert!((got[0] - plain).abs() > 20.0 * sigma[0]);
    }
}

#[test]
fn uniform_texture_equals_the_scaled_reflectance() {
    let c = Rgb::new(0.5, 0.75, 0.25);
    let uniform = Arc::new(Texture::new("uniform", 1, 1, vec![c]).unwrap());
    let n = 100_000;
    // Lambertian: the same draws, so the same power up to rounding.
    let rho = Rgb::new(0.9, 0.8, 0.6);
    let textured =
        box_with_floor(Material::diffuse("floor", rho).with_diffuse_map(uniform.clone()));
    let scaled = box_with_floor(Material::diffuse("floor", rho * c));
    let (a, pa, _) = reflected_power(&textured, n, 3);
    let (b, pb, _) = reflected_power(&scaled, n, 3);
    assert_eq!(a.len(), b.len());
    for k in 0..3 {
        assert!(
            (pa[k] - pb[k]).abs() <= 1e-4 * pb[k],
            "channel {k}: {} vs {}",
            pa[k],
            pb[k]
        );
    }
    // Phong: the textured floor keeps the untextured lobe choice, so the draws differ; the powers agree within their errors.
    let phong = |diffuse: Rgb| MaterialModel::Phong {
        diffuse,
        specular: Rgb::splat(0.3),
        exponent: 20.0,
    };
    let kd = Rgb::new(0.6, 0.5, 0.4);
    let textured = box_with_floor(Material::new("floor", phong(kd)).with_diffuse_map(uniform));
    let scaled = box_with_floor(Material::new("floor", phong(kd * c)));
    let (_, pa, sa) = reflected_power(&textured, n, 5);
    let (_, pb, sb) = reflected_power(&scaled, n, 6);
    for k in 0..3 {
        let tolerance = 5.0 * (sa[k] * sa[k] + sb[k] * sb[k]).sqrt();
        eprintln!(
            "phong, channel {k}: {:.5} vs {:.5} ± {tolerance:.5}",
            pa[k], pb[k]
        );
        assert!((pa[k] - pb[k]).abs() <= tolerance);
    }
}

/// Silverman's unit-volume kernel `3/π (1 − r²)²` on the unit disc, scaled to support `h` (`K(d/h)/h²`), written out here rather than taken from the crate.
fn silverman(d2: f32, h: f32) -> f32 {
    let r2 = d2 / (h * h);
    if r2 >= 1.0 {
        return 0.0;
    }
    3.0 / std::f32::consts::PI * (1.0 - r2).powi(2) / (h * h)
}

#[test]
fn splats_read_the_diffuse_map_where_they_land() {
    let rho = Rgb::new(0.8, 0.6, 0.7);
    let texture = Arc::new(checker(8));
    let scene = box_with_floor(Material::diffuse("floor", rho).with_diffuse_map(texture.clone()));
    let (map, _, _) = reflected_power(&scene, 50_000, 11);
    let estimator = lustre_photon::SplatEstimator::build(&scene, &map, Default::default()).unwrap();
    let floor = scene
        .surfaces()
        .iter()
        .position(|s| s.material == 1)
        .unwrap() as u32;
    let splats: Vec<_> = estimator
        .splats()
        .into_iter()
        .filter(|s| s.surface == floor)
        .collect();
    assert!(splats.len() > 1000, "{} floor splats", splats.len());
    // Each splat's texture mapping is the floor's, at its photon and across the floor (both triangles share one affine mapping).
    for s in &splats {
        let map = s.uv_map.expect("the floor is textured");
        for p in [
            s.position,
            Vec3::new(0.7, -1.0, -0.9),
            Vec3::new(-0.95, -1.0, 0.4),
        ] {
            let (got, expected) = (map.at(p), floor_uv(p));
            assert!(
                (got - expected).abs().max_element() < 1e-5,
                "splat at {}: uv {got} at {p}, expected {expected}",
                s.position
            );
        }
    }
    // Equation 2 with the textured Lambertian BRDF rho t(uv(x)) / pi at the
    // point x where the splats land, summed here over every floor splat.
    let eye = Vec3::new(0.0, 0.5, 0.9);
    let h = splats[0].h;
    for x in [
        Vec3::new(0.1, -1.0, 0.2),
        Vec3::new(-0.55, -1.0, -0.3),
        Vec3::new(0.4, -1.0, 0.6),
    ] {
        let mut expected = Rgb::ZERO;
        for s in &splats {
            let f = rho * texture.sample(floor_uv(x)) / std::f32::consts::PI;
            expected += f * s.power * silverman((s.position - x).length_squared(), h);
        }
        let got = estimator.radiance_splatted(floor, x, Vec3::Y, eye);
        let untextured = splats.iter().fold(Rgb::ZERO, |sum, s| {
            sum + rho / std::f32::consts::PI
                * s.power
                * silverman((s.position - x).length_squared(), h)
        });
        eprintln!("x {x}: splatted {got}, brute force {expected}, untextured {untextured}");
        assert!(
            (got - expected).abs().max_element() <= 1e-4 * expected.max_element(),
            "at {x}: {got} vs {expected}"
        );
        // The map matters here: the untextured estimate is far off.
        assert!((untextured - expected).abs().max_element() > 0.1 * expected.max_element());
        // The estimate at x itself reads the same maps.
        let at = estimator.radiance(floor, x, Vec3::Y, (eye - x).normalize());
        assert!((at - expected).abs().max_element() <= 1e-4 * expected.max_element());
    }
}
