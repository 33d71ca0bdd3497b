//! The CPU twin of the splat pass (equation 2, [`SplatEstimator::radiance_splatted`]) at the pixel centres of a built-in scene's glossy surfaces, for studies of the kernel support (equation 3).
//!
//! `cargo run --release -p lustre-photon --example glossy_error -- SCENE PHOTONS scaled|silverman VALUE SEED SIZE OUT`
//! writes `SIZE × SIZE` RGB little-endian `f32` triples to `OUT`, row 0 at the
//! top, NaN where the pixel centre does not see a surface whose material
//! name is `gold` or `glossy-floor`.

use std::io::Write;

use glam::Vec2;
use lustre_geometry::{Bvh, Camera, builtin};
use lustre_photon::{
    BounceSelection, EmissionSampling, EstimatorOptions, Kernel, NoProgress, SplatEstimator,
    Support, TraceOptions, trace_photons,
};
use rayon::prelude::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, photons, rule, value, seed, size, out] = args.as_slice() else {
        return Err("usage: SCENE PHOTONS scaled|silverman VALUE SEED SIZE OUT".into());
    };
    let size: u32 = size.parse()?;
    let value: f32 = value.parse()?;
    let scene = builtin(scene)?;
    let bvh = Bvh::build(&scene);
    let options = TraceOptions {
        photons: photons.parse()?,
        seed: seed.parse()?,
        // As `lustre render`'s default.
        emission: EmissionSampling::Sobol,
        ..TraceOptions::default()
    };
    let map = trace_photons(&scene, &bvh, &options, &NoProgress)?;
    let support = match rule.as_str() {
        "scaled" => Support::Scaled(value),
        "silverman" => Support::Silverman(value),
        other => return Err(format!("unknown support rule {other}").into()),
    };
    let estimator = SplatEstimator::build(
        &scene,
        &map,
        EstimatorOptions {
            kernel: Kernel::Silverman,
            support,
            selection: BounceSelection::All,
            edges: lustre_photon::Edges::Truncated,
        },
    )?;
    let glossy: Vec<bool> = scene
        .materials()
        .iter()
        .map(|m| m.name == "gold" || m.name == "glossy-floor")
        .collect();
    let camera = scene.camera().with_aspect(1.0);
    let eye = camera.position;
    let pixels: Vec<[f32; 3]> = (0..size * size)
        .into_par_iter()
        .map(|i| {
            let ndc = Camera::pixel_ndc(i % size, i / size, size, size, Vec2::splat(0.5));
            let hit = bvh.closest_hit(&camera.primary_ray(ndc));
            match hit {
                Some(hit) if glossy[hit.material as usize] => {
                    let l = estimator.radiance_splatted(
                        hit.surface,
                        hit.position,
                        hit.shading_normal,
                        eye,
                    );
                    [l.x, l.y, l.z]
                }
                _ => [f32::NAN; 3],
            }
        })
        .collect();
    let mut file = std::io::BufWriter::new(std::fs::File::create(out)?);
    for p in pixels {
        for c in p {
            file.write_all(&c.to_le_bytes())?;
        }
    }
    Ok(())
}
