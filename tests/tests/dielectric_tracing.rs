//! Particle tracing through a smooth dielectric, in lustre-photon's tracer
//! (Stürzlinger & Bastos section 2.1) and DETP's ray set (García et al.
//! section 2.3), against the Fresnel equations: a photon inside the medium
//! meets the interface from its inside, with η's inverse and total internal
//! reflection.

use glam::Vec3;
use lustre_density::{RaySetOptions, trace_ray_set};
use lustre_geometry::light::PointLight;
use lustre_geometry::{Bvh, Camera, Light, Material, MaterialModel, Mesh, Object, Rgb, Scene};
use lustre_photon::{NoProgress, TraceOptions, trace_photons};

/// Index of refraction of the medium below the interface.
const IOR: f32 = 1.33;

/// Unpolarised Fresnel reflectance for light inside a medium of index `n`
/// meeting its interface with air at `cos_i` (Born & Wolf): 1 beyond the
/// critical angle.
fn reflectance_from_inside(cos_i: f64, n: f64) -> f64 {
    let sin_t = n * (1.0 - cos_i * cos_i).max(0.0).sqrt();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = (n * cos_i - cos_t) / (n * cos_i + cos_t);
    let rp = (cos_i - n * cos_t) / (cos_i + n * cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// A 100 × 100 m interface at y = 0 (its wound normal +y: air above, the
/// medium below), black catchers at y = ±1, an isotropic point light at
/// y = −0.5 inside the medium.
fn submerged_light() -> Scene {
    let water = Material::new(
        "water",
        MaterialModel::Dielectric {
            ior: IOR,
            transmittance: Rgb::ONE,
        },
    );
    let black = Material::diffuse("black", Rgb::ZERO);
    let square = |y: f32, half: f32| {
        [
            Vec3::new(-half, y, -half),
            Vec3::new(-half, y, half),
            Vec3::new(half, y, half),
            Vec3::new(half, y, -half),
        ]
    };
    let triangles = [[0, 1, 2], [0, 2, 3]];
    let meshes = vec![
        Mesh::flat("interface", &square(0.0, 50.0), &triangles, 0),
        Mesh::flat("above", &square(1.0, 500.0), &triangles, 1),
        Mesh::flat("below", &square(-1.0, 500.0), &triangles, 1),
    ];
    let objects = Object::one_per_mesh(&meshes);
    let light = Light::Point(PointLight {
        position: Vec3::new(0.0, -0.5, 0.0),
        intensity: Rgb::ONE,
    });
    let camera = Camera::look_at(Vec3::new(0.0, 3.0, 3.0), Vec3::ZERO, Vec3::Y, 40.0);
    Scene::new(
        "submerged",
        meshes,
        vec![water, black],
        objects,
        vec![light],
        camera,
    )
    .unwrap()
}

/// The share of photons meeting the interface from below that the Fresnel
/// equations reflect back into the medium (total internal reflection beyond
/// 48.8°): photons from an isotropic point source meet the plane with
/// `cos θ` uniform on `(cos θ_max, 1]` (the quad's edge, 50 m away, seen
/// from 0.5 m below its centre), so the share is the mean of `R(cos θ)`
/// there, 0.68.
fn expected_reflected_share() -> f64 {
    let mu_min = 0.5 / (0.5f64 * 0.5 + 50.0 * 50.0).sqrt();
    let steps = 100_000;
    (0..steps)
        .map(|i| {
            let mu = mu_min + (1.0 - mu_min) * (i as f64 + 0.5) / steps as f64;
            reflectance_from_inside(mu, f64::from(IOR))
        })
        .sum::<f64>()
        / steps as f64
}

/// Checks `reflected` of `met` against [`expected_reflected_share`] within 5 σ.
fn check_share(what: &str, reflected: u64, met: u64, photons: u64) {
    assert!(met > photons / 3, "{what}: {met} photons met the interface");
    let expected = expected_reflected_share();
    let share = reflected as f64 / met as f64;
    let sigma = (expected * (1.0 - expected) / met as f64).sqrt();
    eprintln!("{what}: reflected {share:.4} of {met}, expected {expected:.4} (sigma {sigma:.4})");
    assert!(
        (share - expected).abs() <= 5.0 * sigma,
        "{what}: reflected {share} where Fresnel gives {expected}"
    );
}

/// lustre-photon: the tracer that met every dielectric as if from the air
/// (its frame flipped to the photon's side) reflected 0.17.
#[test]
fn photons_inside_a_dielectric_are_totally_reflected_beyond_the_critical_angle() {
    let scene = submerged_light();
    let surface_of = |mesh: &str| {
        let m = scene.meshes().iter().position(|m| m.name == mesh).unwrap() as u32;
        scene.surfaces().iter().position(|s| s.mesh == m).unwrap() as u32
    };
    let (interface, above, below) = (
        surface_of("interface"),
        surface_of("above"),
        surface_of("below"),
    );
    let n = 200_000u64;
    let options = TraceOptions {
        photons: n,
        seed: 5,
        ..TraceOptions::default()
    };
    let map = trace_photons(&scene, &Bvh::build(&scene), &options, &NoProgress).unwrap();
    let (mut reflected, mut met) = (0u64, 0u64);
    for pair in map.records().windows(2) {
        if pair[0].bounce == 1 && pair[0].surface == interface && pair[1].bounce == 2 {
            if pair[1].surface == below {
                reflected += 1;
                met += 1;
            } else if pair[1].surface == above {
                met += 1;
            }
        }
    }
    check_share("photons", reflected, met, n);
}

/// DETP's ray set: the same, its segments after one on the interface.
#[test]
fn detp_rays_inside_a_dielectric_are_totally_reflected_beyond_the_critical_angle() {
    let scene = submerged_light();
    let mesh = |name: &str| scene.meshes().iter().position(|m| m.name == name).unwrap() as u32;
    let (interface, above, below) = (mesh("interface"), mesh("above"), mesh("below"));
    let n = 200_000u64;
    let options = RaySetOptions {
        photons: n,
        seed: 5,
        ..RaySetOptions::default()
    };
    let rays = trace_ray_set(&scene, &Bvh::build(&scene), &options).unwrap();
    let (mut reflected, mut met) = (0u64, 0u64);
    for ray in &rays.rays {
        let hits: Vec<u32> = ray
            .segments
            .iter()
            .filter_map(|s| s.hit.map(|h| h.mesh))
            .collect();
        if hits.len() >= 2 && hits[0] == interface {
            if hits[1] == below {
                reflected += 1;
                met += 1;
            } else if hits[1] == above {
                met += 1;
            }
        }
    }
    check_share("DETP rays", reflected, met, n);
}
