//! `cargo xtask walkthrough`: the walkthrough benchmark (issues 14 and 15;
//! Bastos et al. played 944 frames through their house). One `lustre render
//! --camera-path` renders every frame of a camera path from lighting
//! computed once; each frame is measured against a path-traced reference of
//! that frame, and set beside the time Mitsuba's path tracer needs for the
//! same error on the same machine in the same run.
//!
//! The path tracer's time at equal error comes from a probe render per frame
//! (`--probe-spp`, another seed than the reference): an independent render
//! at N samples has the expected relMSE c (1/N + 1/N_ref) against a
//! reference of N_ref samples, so the probe gives the frame's c, the
//! reference's own noise is c / N_ref, and our frame's error e is reached at
//! N = c / (e − c / N_ref) samples, in the probe's load time plus its render
//! time scaled by N / N_probe. Where e is within the reference's noise, the
//! path tracer's time is taken at N_ref samples, a lower bound (counted in
//! the report). Writes the result into BENCHMARKS.md between `<!--
//! walkthrough:start -->` and `<!-- walkthrough:end -->`.
//!
//! The references (1,024 spp at 640 × 480: about two hours for 100 frames
//! on 2 cores) are kept in `--reference-cache`, keyed by the exported scene
//! and the render's settings ([`path_tracer::render_cached`]); their time is
//! never read, so `--references-only` can fill the cache beforehand, for
//! example under `nice`, and the timed run renders only ours and the probes.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result, bail, ensure};
use lustre_geometry::builtin::builtin;
use lustre_geometry::camera_path::CameraPath;
use lustre_image::metrics::{self, RELATIVE_MSE_EPSILON};
use lustre_image::read_exr;

use crate::converge::{load_reference, references_dir};
use crate::path_tracer;
use crate::reference::{ensure_venv, export_like};
use crate::render::{Lustre, Scratch};

/// Seed of the first frame's reference (frame i: this + i).
const REFERENCE_SEED: u32 = 2_000_000;
/// Seed of the first frame's probe (frame i: this + i).
const PROBE_SEED: u32 = 3_000_000;

/// Options of `cargo xtask walkthrough`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The built-in scene (its reference sidecar says how to path-trace it).
    #[arg(long, default_value = "glosbox")]
    scene: String,
    /// The camera path (relative to the workspace).
    #[arg(long, default_value = "tests/paths/glosbox-walk.json")]
    path: PathBuf,
    /// Frames of the walkthrough.
    #[arg(long, default_value_t = 100)]
    frames: usize,
    /// Image size, `WxH`.
    #[arg(long, default_value = "640x480")]
    size: String,
    /// Samples per pixel of each frame's reference.
    #[arg(long, default_value_t = 1024)]
    reference_spp: u32,
    /// Samples per pixel of each frame's probe render.
    #[arg(long, default_value_t = 64)]
    probe_spp: u32,
    /// The relMSE every frame must stay within.
    #[arg(long, default_value_t = 0.02)]
    bound: f64,
    /// Further `lustre render` options, one string split at spaces (default: `lustre render`'s defaults).
    #[arg(long, default_value = "", allow_hyphen_values = true)]
    render_args: String,
    /// Name of the BENCHMARKS.md section to (re)write.
    #[arg(long, default_value = "walkthrough")]
    section: String,
    /// Where the frames' references are kept between runs (relative to the
    /// workspace), keyed by everything their render depends on.
    #[arg(long, default_value = "target/path-traced")]
    reference_cache: PathBuf,
    /// Only path-trace the references missing from the cache, without our
    /// render, the probes or BENCHMARKS.md: hours of work that can run
    /// ahead, at low priority, of the timed run on a quiet machine.
    #[arg(long)]
    references_only: bool,
}

/// One frame's measurements.
#[derive(Debug, Clone, Copy)]
struct Frame {
    /// Our render's relMSE against the frame's reference.
    rel_mse: f64,
    /// Our frame time (ms), from the sidecar.
    ms: f64,
    /// The path tracer's seconds to reach `rel_mse`.
    path_tracer_seconds: f64,
    /// Its samples per pixel for that.
    path_tracer_spp: f64,
    /// Whether `rel_mse` was within the reference's noise (the time is then a lower bound).
    at_noise: bool,
}

/// The path tracer's samples and seconds for relMSE `e`, from a probe of `probe_spp` samples with relMSE `probe` against a reference of `reference_spp` (module docs); `true` when `e` is within the reference's noise and the answer is the lower bound at `reference_spp`.
fn equal_error(
    e: f64,
    probe: f64,
    probe_spp: f64,
    reference_spp: f64,
    load_seconds: f64,
    render_seconds: f64,
) -> (f64, f64, bool) {
    let c = probe / (1.0 / probe_spp + 1.0 / reference_spp);
    let noise = c / reference_spp;
    let (spp, at_noise) = if e > noise {
        ((c / (e - noise)).max(1.0), false)
    } else {
        (reference_spp, true)
    };
    (
        spp,
        load_seconds + render_seconds * spp / probe_spp,
        at_noise,
    )
}

/// Runs `cargo xtask walkthrough`.
pub fn run(args: Args) -> Result<()> {
    ensure!(
        args.frames >= 2 && args.reference_spp > 0 && args.probe_spp > 0,
        "--frames must be at least 2 and the sample counts positive"
    );
    let (width, height) = args
        .size
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)))
        .filter(|&(w, h)| w > 0 && h > 0)
        .with_context(|| format!("--size {}: not WxH", args.size))?;
    let root = crate::workspace_root();
    let path_file = root.join(&args.path);
    let path = CameraPath::load(&path_file)?;
    let reference = load_reference(&references_dir(), &args.scene)?;
    let python = ensure_venv(&root)?;
    let cache = root.join(&args.reference_cache);
    let scratch = Scratch::new("walkthrough")?;
    let cameras = path.frames(args.frames);
    let frame_scene = |camera: &lustre_geometry::Camera| -> Result<lustre_geometry::Scene> {
        let mut scene = builtin(&args.scene)?;
        scene.set_camera(camera.with_aspect(width as f32 / height as f32));
        Ok(scene)
    };
    let options =
        |spp: u32, seed: u32| -> Result<(lustre_geometry::mitsuba::ExportOptions, String)> {
            let (mut options, variant) = export_like(&reference.sidecar, spp, seed)?;
            (options.width, options.height) = (width, height);
            Ok((options, variant))
        };
    let truth = |i: usize, scene: &lustre_geometry::Scene| {
        let (options, variant) = options(args.reference_spp, REFERENCE_SEED + i as u32)?;
        let dir = scratch.path().join(format!("reference-{i}"));
        let start = std::time::Instant::now();
        let (image, rendered) =
            path_tracer::render_cached(&python, scene, &options, &variant, &dir, &cache)
                .with_context(|| format!("path tracing frame {i}'s reference"))?;
        if rendered {
            println!(
                "walkthrough: frame {i}'s reference rendered in {:.0} s, kept in {}",
                start.elapsed().as_secs_f64(),
                cache.display()
            );
        }
        anyhow::Ok(image)
    };
    if args.references_only {
        for (i, camera) in cameras.iter().enumerate() {
            truth(i, &frame_scene(camera)?)?;
            println!(
                "walkthrough: {} of {} references ready",
                i + 1,
                cameras.len()
            );
        }
        return Ok(());
    }
    let lustre = Lustre::build()?;

    // Ours: one run, every frame.
    let out = scratch.path().join("walk.exr");
    let size = format!("{width}x{height}");
    let frames_arg = args.frames.to_string();
    let path_arg = path_file.to_str().context("the path's name is not UTF-8")?;
    let mut render_args = vec![
        "--camera-path",
        path_arg,
        "--path-frames",
        &frames_arg,
        "--size",
        &size,
        "--seed",
        "1",
    ];
    render_args.extend(args.render_args.split_whitespace());
    println!(
        "walkthrough: lustre render {} {}",
        args.scene,
        render_args.join(" ")
    );
    let sidecar = lustre.run(&args.scene, &render_args, &out)?;
    let total_ms = sidecar["timings_ms"]["total"]
        .as_f64()
        .context("the sidecar has no total time")?;
    let frame_ms: Vec<f64> = sidecar["camera_path"]["frame_ms"]
        .as_array()
        .context("the sidecar has no frame times")?
        .iter()
        .filter_map(serde_json::Value::as_f64)
        .collect();
    ensure!(
        frame_ms.len() == args.frames,
        "the sidecar has {} frame times",
        frame_ms.len()
    );
    let adapter = sidecar["adapter"]
        .as_str()
        .unwrap_or("unknown adapter")
        .to_owned();

    // The path tracer: a reference and a probe per frame.
    let mut frames = Vec::with_capacity(args.frames);
    for (i, camera) in cameras.iter().enumerate() {
        let scene = frame_scene(camera)?;
        let truth = truth(i, &scene)?;
        let (options, variant) = options(args.probe_spp, PROBE_SEED + i as u32)?;
        let dir = scratch.path().join(format!("probe-{i}"));
        let (probe, probe_times) = path_tracer::render(&python, &scene, &options, &variant, &dir)
            .with_context(|| format!("path tracing frame {i}'s probe"))?;
        let ours = read_exr(crate::render::frame_path(&out, i))
            .with_context(|| format!("reading our frame {i}"))?;
        let rel_mse = metrics::relative_mse(&ours, &truth, RELATIVE_MSE_EPSILON)?;
        let probe_rel = metrics::relative_mse(&probe, &truth, RELATIVE_MSE_EPSILON)?;
        let (spp, seconds, at_noise) = equal_error(
            rel_mse,
            probe_rel,
            f64::from(args.probe_spp),
            f64::from(args.reference_spp),
            probe_times.load,
            probe_times.render,
        );
        println!(
            "walkthrough frame {i}: relMSE {rel_mse:.5} in {:.0} ms; path tracer {spp:.0} spp, {seconds:.2} s{}",
            frame_ms[i],
            if at_noise {
                " (at the reference's noise)"
            } else {
                ""
            }
        );
        frames.push(Frame {
            rel_mse,
            ms: frame_ms[i],
            path_tracer_seconds: seconds,
            path_tracer_spp: spp,
            at_noise,
        });
    }
    let text = section(&args, &frames, total_ms, &adapter, width, height);
    println!("\n{text}");
    let over = frames.iter().filter(|f| f.rel_mse > args.bound).count();
    crate::bench::write_section(&args.section, &text)?;
    if over > 0 {
        bail!(
            "{over} of {} frames are above relMSE {}",
            frames.len(),
            args.bound
        );
    }
    Ok(())
}

/// The BENCHMARKS.md section.
fn section(
    args: &Args,
    frames: &[Frame],
    total_ms: f64,
    adapter: &str,
    width: u32,
    height: u32,
) -> String {
    let mut errors: Vec<f64> = frames.iter().map(|f| f.rel_mse).collect();
    errors.sort_by(f64::total_cmp);
    let ours = total_ms / 1000.0;
    let path_tracer: f64 = frames.iter().map(|f| f.path_tracer_seconds).sum();
    let median_ms = crate::bench::median(frames.iter().map(|f| f.ms).collect());
    let median_spp = crate::bench::median(frames.iter().map(|f| f.path_tracer_spp).collect());
    let over = frames.iter().filter(|f| f.rel_mse > args.bound).count();
    let at_noise = frames.iter().filter(|f| f.at_noise).count();
    let mut s = String::new();
    let _ = writeln!(s, "## Walkthrough against the path tracer at equal error\n");
    let _ = writeln!(
        s,
        "Written by `cargo xtask walkthrough`; do not edit by hand. `lustre render {} --camera-path {} --path-frames {} --size {width}x{height} --seed 1 {}` (lighting once, then every frame), each frame against a Mitsuba 3 reference of that frame at {} spp rendered as `tests/references/{}.exr` was; the path tracer's time for each frame's relMSE from a {}-spp probe of that frame (`xtask/src/walkthrough.rs` says how). Machine: {}. Adapter: {adapter}.\n",
        args.scene,
        args.path.display(),
        args.frames,
        args.render_args,
        args.reference_spp,
        args.scene,
        args.probe_spp,
        crate::bench::machine(),
    );
    let _ = writeln!(
        s,
        "| | ours | path tracer at equal error |\n|---|---:|---:|"
    );
    let _ = writeln!(s, "| total time | {ours:.1} s | {path_tracer:.1} s |");
    let _ = writeln!(
        s,
        "| median frame | {median_ms:.0} ms | {median_spp:.0} spp |"
    );
    let _ = writeln!(
        s,
        "| relMSE per frame (min / median / max) | {:.5} / {:.5} / {:.5} | the same |",
        errors[0],
        errors[errors.len() / 2],
        errors[errors.len() - 1]
    );
    let _ = writeln!(
        s,
        "\nOur time over the path tracer's: {:.3} (the goal: 0.01). Frames above relMSE {}: {over} of {}. Frames whose error is within the reference's own noise (the path tracer's time there a lower bound at {} spp): {at_noise}.",
        ours / path_tracer,
        args.bound,
        frames.len(),
        args.reference_spp
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_error_inverts_the_path_tracers_error_model() {
        // c = 2, N_ref = 1024: a 64-spp probe has 2 (1/64 + 1/1024).
        let probe = 2.0 * (1.0 / 64.0 + 1.0 / 1024.0);
        // Our error equals a 256-spp render's: 256 spp, four times the probe's render time.
        let e = 2.0 * (1.0 / 256.0 + 1.0 / 1024.0);
        let (spp, seconds, at_noise) = equal_error(e, probe, 64.0, 1024.0, 0.5, 3.0);
        assert!((spp - 256.0).abs() < 1e-9 && (seconds - 12.5).abs() < 1e-9 && !at_noise);
        // Within the reference's noise: the lower bound at the reference's spp.
        let (spp, seconds, at_noise) = equal_error(2.0 / 1024.0, probe, 64.0, 1024.0, 0.5, 3.0);
        assert!(at_noise && spp == 1024.0 && (seconds - 48.5).abs() < 1e-9);
        // Worse than one sample: one sample.
        let (spp, _, _) = equal_error(100.0, probe, 64.0, 1024.0, 0.5, 3.0);
        assert_eq!(spp, 1.0);
    }
}
