//! `cargo xtask converge`: how each technique converges to the path-traced
//! reference with the photon count (DESIGN.md, "Testing", reference
//! comparison). Renders every scene, technique and photon count at the
//! reference's size with `--seed 1`, measures the relative MSE and the
//! mean FLIP against `tests/references/<scene>.exr`, prints the table and
//! writes it into BENCHMARKS.md between `<!-- converge:start -->` and
//! `<!-- converge:end -->`.
//!
//! Beside them, in the same run on the same machine, Mitsuba's path tracer
//! renders each scene at several sample counts (`--path-tracer-spp`,
//! [`crate::path_tracer`]), and each of our renders is set beside the path
//! tracer's relMSE at the same time and the time it takes to reach the same
//! relMSE (issue 15, "Error at equal time").

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result, bail};
use lustre_image::metrics::{self, PIXELS_PER_DEGREE, RELATIVE_MSE_EPSILON};
use lustre_image::{Image, read_exr};
use serde_json::Value;

use crate::path_tracer::{self, Curve, Estimate};
use crate::render::{Lustre, Render, Scratch};
use crate::surfaces::{SurfaceMap, relative_mse_over};

/// The meshes whose pixels get their own relMSE column: the floor (glossy
/// in glosbox) and the large box (gold in glosbox), where speckled glossy
/// reflections hide in the whole-image number.
const PER_SURFACE: &[(&str, &str)] = &[("floor", "floor"), ("large-box", "large box")];

/// The seed of every convergence render.
const SEED: &str = "1";

/// The exposure (stops) at which FLIP tone maps both images.
const EXPOSURE: f32 = 0.0;

/// Options of `cargo xtask converge`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Built-in scenes, each with a reference `tests/references/<scene>.exr` (comma-separated).
    #[arg(long = "scene", value_delimiter = ',', default_value = "glosbox")]
    scenes: Vec<String>,
    /// Photon counts (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "100000,1000000,4000000")]
    photons: Vec<u64>,
    /// Techniques of `lustre render --technique` (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "splat,splat-direct")]
    techniques: Vec<String>,
    /// Kernel constants C of equation 3 (`lustre render --kernel-c`, comma-separated).
    #[arg(long = "kernel-c", value_delimiter = ',', default_value = "16")]
    kernel_c: Vec<String>,
    /// Support rules of `lustre render --support` (comma-separated): equation3, silverman, glossy-silverman.
    #[arg(long, value_delimiter = ',', default_value = "glossy-silverman")]
    support: Vec<String>,
    /// Name of the BENCHMARKS.md section to (re)write, between `<!-- NAME:start -->` and `<!-- NAME:end -->`.
    #[arg(long, default_value = "converge")]
    section: String,
    /// Heading of that section.
    #[arg(long, default_value = "Convergence to the path-traced references")]
    title: String,
    /// Samples per pixel of the path tracer's renders beside ours (comma-separated; each
    /// scene rendered as its reference was, with another seed).
    #[arg(
        long = "path-tracer-spp",
        value_delimiter = ',',
        default_value = "1,4,16,64,256,1024,4096"
    )]
    path_tracer_spp: Vec<u32>,
    /// Render no path-traced curve: no comparison at equal time.
    #[arg(long)]
    no_path_tracer: bool,
}

/// A path-traced reference and what its sidecar says about it.
pub(crate) struct Reference {
    /// The scene.
    pub scene: String,
    /// The image.
    pub image: Image,
    /// Samples per pixel, from `tests/references/<scene>.json`.
    pub spp: Option<u64>,
    /// The renderer, from the sidecar (e.g. "Mitsuba 3").
    pub renderer: String,
    /// The whole sidecar (how the reference was rendered).
    pub sidecar: Value,
}

/// One measured render.
#[derive(Debug)]
struct Row {
    /// The scene.
    scene: String,
    /// The technique.
    technique: String,
    /// Photons emitted.
    photons: u64,
    /// Kernel constant C (equation 3).
    kernel_c: String,
    /// The support rule (`--support`).
    support: String,
    /// GPU frame time from the sidecar's `timings_ms.frame`.
    frame_ms: Option<f64>,
    /// Relative MSE against the reference (ε = 0.01).
    rel_mse: f64,
    /// Relative MSE over the pixels that see only each of [`PER_SURFACE`]'s meshes.
    surface_rel_mse: Vec<Option<f64>>,
    /// Mean FLIP against the reference.
    flip_mean: f32,
    /// Render time from the sidecar's `timings_ms`.
    time_ms: Option<f64>,
    /// The adapter from the sidecar.
    adapter: String,
}

/// `tests/references` in the workspace: the path-traced references and their sidecars.
pub(crate) fn references_dir() -> std::path::PathBuf {
    crate::workspace_root().join("tests").join("references")
}

/// Reads `<dir>/<scene>.exr` and its sidecar `<dir>/<scene>.json`.
pub(crate) fn load_reference(dir: &Path, scene: &str) -> Result<Reference> {
    let exr = dir.join(format!("{scene}.exr"));
    let image = read_exr(&exr).with_context(|| {
        format!(
            "no reference for `{scene}` (render one with `cargo xtask reference --scene {scene}`)"
        )
    })?;
    let json = dir.join(format!("{scene}.json"));
    let sidecar: Value = std::fs::read_to_string(&json)
        .ok()
        .and_then(|text| serde_json::from_str(&text).ok())
        .unwrap_or(Value::Null);
    Ok(Reference {
        scene: scene.to_owned(),
        image,
        spp: sidecar["spp"].as_u64(),
        renderer: sidecar["renderer"]
            .as_str()
            .unwrap_or("unknown renderer")
            .to_owned(),
        sidecar,
    })
}

/// The render time of a sidecar: `timings_ms.total`, else the sum of its numbers.
fn render_time_ms(sidecar: &Value) -> Option<f64> {
    let timings = sidecar["timings_ms"].as_object()?;
    if let Some(total) = timings.get("total").and_then(Value::as_f64) {
        return Some(total);
    }
    let values: Vec<f64> = timings.values().filter_map(Value::as_f64).collect();
    (!values.is_empty()).then(|| values.iter().sum())
}

/// Compares one render with its reference.
fn measure(
    reference: &Reference,
    technique: &str,
    photons: u64,
    kernel_c: &str,
    support: &str,
    render: &Render,
    surfaces: &[Vec<usize>],
) -> Result<Row> {
    let rel_mse = metrics::relative_mse(&render.image, &reference.image, RELATIVE_MSE_EPSILON)?;
    let surface_rel_mse = surfaces
        .iter()
        .map(|pixels| relative_mse_over(&render.image, &reference.image, pixels))
        .collect();
    let flip = metrics::flip(&render.image, &reference.image, EXPOSURE)?;
    Ok(Row {
        scene: reference.scene.clone(),
        technique: technique.to_owned(),
        photons,
        kernel_c: kernel_c.to_owned(),
        support: support.to_owned(),
        frame_ms: render
            .sidecar
            .get("timings_ms")
            .and_then(|t| t.get("frame"))
            .and_then(Value::as_f64),
        rel_mse,
        surface_rel_mse,
        flip_mean: flip.mean,
        time_ms: render_time_ms(&render.sidecar),
        adapter: render.adapter().to_owned(),
    })
}

/// `12345678` as `12,345,678`.
pub(crate) fn thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// One table row, in Markdown.
fn table_row(row: &Row) -> String {
    let surfaces: String = row
        .surface_rel_mse
        .iter()
        .map(|r| r.map_or(" - |".to_owned(), |r| format!(" {r:.5} |")))
        .collect();
    format!(
        "| {} | {} | {} | {} | {:.5} |{surfaces} {:.4} | {} | {} |",
        row.technique,
        thousands(row.photons),
        row.kernel_c,
        row.support,
        row.rel_mse,
        row.flip_mean,
        row.frame_ms.map_or("-".to_owned(), |t| format!("{t:.0}")),
        row.time_ms.map_or("-".to_owned(), |t| format!("{t:.0}"))
    )
}

/// An estimate read off the path tracer's curve, `*` when extrapolated.
fn estimate(e: Option<Estimate>, digits: usize) -> String {
    e.map_or("–".to_owned(), |e| {
        format!(
            "{:.digits$}{}",
            e.value,
            if e.extrapolated { "*" } else { "" }
        )
    })
}

/// The path tracer's curve on one scene and each of our renders beside it, in Markdown.
fn equal_time(curve: &Curve, rows: &[&Row]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Mitsuba's path tracer on the same machine in this run ({} spp, seed {}; its relMSE \
         fits c (1/N + 1/N_ref) with c = {:.3}, so the reference's own noise is c / N_ref = {:.5}; \
         time {:.2} s + {:.4} s per spp):\n",
        curve
            .points
            .iter()
            .map(|p| thousands(u64::from(p.spp)))
            .collect::<Vec<_>>()
            .join(", "),
        path_tracer::SEED,
        curve.variance,
        curve.reference_noise(),
        curve.setup_seconds,
        curve.seconds_per_spp,
    );
    let _ = writeln!(s, "| spp | time (s) | relMSE |\n|---:|---:|---:|");
    for p in &curve.points {
        let _ = writeln!(
            s,
            "| {} | {:.2} | {:.5} |",
            thousands(u64::from(p.spp)),
            p.seconds,
            p.rel_mse
        );
    }
    let _ = writeln!(
        s,
        "\nAt equal time: the path tracer's relMSE after our render's time, our relMSE over it \
         (below 1: ours is better), the same without the reference's noise (c / N_ref taken \
         from both), and the path tracer's time to our relMSE over our time (above 1: ours is \
         faster). `*`: beyond the measured spp, from the fit; –: below the reference's noise.\n"
    );
    let _ = writeln!(
        s,
        "| technique | photons | C | support | time (s) | relMSE | path tracer's relMSE | ratio | ratio without reference noise | path tracer's time (s) | its time / ours |"
    );
    let _ = writeln!(s, "|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|");
    for row in rows {
        let Some(ms) = row.time_ms else { continue };
        let seconds = ms / 1000.0;
        let at = curve.rel_mse_at(seconds);
        let noise = curve.reference_noise();
        let ratio = at.map(|a| Estimate {
            value: row.rel_mse / a.value,
            ..a
        });
        let clean = at.and_then(|a| {
            (a.value > noise).then(|| Estimate {
                value: (row.rel_mse - noise).max(0.0) / (a.value - noise),
                ..a
            })
        });
        let time = curve.seconds_for(row.rel_mse);
        let speed = time.map(|t| Estimate {
            value: t.value / seconds,
            ..t
        });
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {seconds:.1} | {:.5} | {} | {} | {} | {} | {} |",
            row.technique,
            thousands(row.photons),
            row.kernel_c,
            row.support,
            row.rel_mse,
            estimate(at, 5),
            estimate(ratio, 2),
            estimate(clean, 2),
            estimate(time, 1),
            estimate(speed, 2),
        );
    }
    s
}

/// The BENCHMARKS.md section (between its markers) for `rows`, with the
/// path tracer's curve of each reference where one was measured.
fn section(
    references: &[Reference],
    rows: &[Row],
    curves: &[Option<Curve>],
    machine: &str,
    title: &str,
) -> String {
    let mut adapters: Vec<&str> = rows.iter().map(|r| r.adapter.as_str()).collect();
    adapters.sort_unstable();
    adapters.dedup();
    let mut s = String::new();
    let _ = writeln!(s, "## {title}\n");
    let _ = writeln!(
        s,
        "Written by `cargo xtask converge`; do not edit by hand. Each technique renders the scene \
         with `lustre render` at the reference's size with `--seed {SEED}` and the kernel constant C of equation 3 and support rule (`--support`) shown. relMSE = 1/(3N) Σ (t − r)² \
         / (r² + {RELATIVE_MSE_EPSILON}) over pixels and channels (Rousselle, Knaus & Zwicker 2011); \
         FLIP is the mean LDR-FLIP of both images tone mapped at exposure {EXPOSURE} \
         ({PIXELS_PER_DEGREE} pixels per degree). relMSE per surface counts only the pixels whose \
         {rays} stratified camera rays all hit that mesh first (lustre-geometry's camera and BVH; the \
         references are box-filtered, so edge pixels belong to no surface): the floor (glossy in \
         glosbox) and the large box (gold in glosbox). Time is the sidecar's `timings_ms.total` (or the sum of its entries).\n",
        rays = {
            let n = crate::surfaces::RAYS_PER_AXIS;
            format!("{n} × {n}")
        }
    );
    let _ = writeln!(
        s,
        "Machine: {machine}. GPU adapter: {}.\n",
        if adapters.is_empty() {
            "none".to_owned()
        } else {
            adapters.join("; ")
        }
    );
    for (i, reference) in references.iter().enumerate() {
        let _ = writeln!(
            s,
            "### {} (reference: {}, {} spp, {}x{}, `tests/references/{}.exr`)\n",
            reference.scene,
            reference.renderer,
            reference.spp.map_or("unknown".to_owned(), thousands),
            reference.image.width(),
            reference.image.height(),
            reference.scene
        );
        let surfaces: String = PER_SURFACE
            .iter()
            .map(|(_, shown)| format!(" relMSE {shown} |"))
            .collect();
        let _ = writeln!(
            s,
            "| technique | photons | C | support | relMSE |{surfaces} mean FLIP | GPU frame (ms) | total (ms) |"
        );
        let _ = writeln!(
            s,
            "|---|---:|---:|---|---:|{}---:|---:|---:|",
            "---:|".repeat(PER_SURFACE.len())
        );
        let scene_rows: Vec<&Row> = rows.iter().filter(|r| r.scene == reference.scene).collect();
        for row in &scene_rows {
            let _ = writeln!(s, "{}", table_row(row));
        }
        s.push('\n');
        if let Some(Some(curve)) = curves.get(i) {
            s.push_str(&equal_time(curve, &scene_rows));
            s.push('\n');
        }
    }
    s
}

/// Renders and measures every scene × technique × photon count; a failed
/// render is reported and counted, the others still run.
fn converge(
    lustre: &Lustre,
    references_dir: &Path,
    args: &Args,
    scratch: &Path,
) -> Result<(Vec<Reference>, Vec<Row>, usize)> {
    let mut references = Vec::new();
    let mut rows = Vec::new();
    let mut failures = 0;
    for scene in &args.scenes {
        let reference = load_reference(references_dir, scene)?;
        let size = format!("{}x{}", reference.image.width(), reference.image.height());
        let map = SurfaceMap::of_builtin(scene, reference.image.width(), reference.image.height())?;
        let surfaces = PER_SURFACE
            .iter()
            .map(|(mesh, _)| Ok(map.pixels_of(map.mesh(mesh)?)))
            .collect::<Result<Vec<_>>>()?;
        for technique in &args.techniques {
            for (kernel_c, support) in args
                .kernel_c
                .iter()
                .flat_map(|c| args.support.iter().map(move |s| (c, s)))
            {
                for &photons in &args.photons {
                    let out = scratch.join(format!(
                        "{scene}-{technique}-{photons}-{kernel_c}-{support}.exr"
                    ));
                    let photons_arg = photons.to_string();
                    let render_args = [
                        "--technique",
                        technique.as_str(),
                        "--photons",
                        &photons_arg,
                        "--kernel-c",
                        kernel_c.as_str(),
                        "--support",
                        support.as_str(),
                        "--size",
                        &size,
                        "--seed",
                        SEED,
                    ];
                    let result = lustre.render(scene, &render_args, &out).and_then(|render| {
                        measure(
                            &reference, technique, photons, kernel_c, support, &render, &surfaces,
                        )
                    });
                    match result {
                        Ok(row) => {
                            println!("converge {scene:<10} {}", table_row(&row));
                            rows.push(row);
                        }
                        Err(error) => {
                            println!(
                                "converge {scene:<10} {technique} {photons} C={kernel_c} {support}: FAILED: {error:#}"
                            );
                            failures += 1;
                        }
                    }
                }
            }
        }
        references.push(reference);
    }
    Ok((references, rows, failures))
}

/// Runs `cargo xtask converge`.
pub fn run(args: Args) -> Result<()> {
    if args.scenes.is_empty() || args.photons.is_empty() || args.techniques.is_empty() {
        bail!("--scene, --photons and --techniques need at least one value each");
    }
    if args.photons.contains(&0) {
        bail!("--photons must be positive");
    }
    if !args.no_path_tracer && (args.path_tracer_spp.len() < 2 || args.path_tracer_spp.contains(&0))
    {
        bail!("--path-tracer-spp needs at least two positive sample counts (or --no-path-tracer)");
    }
    let lustre = Lustre::build()?;
    let scratch = Scratch::new("converge")?;
    let references_dir = references_dir();
    let (references, rows, failures) = converge(&lustre, &references_dir, &args, scratch.path())?;
    if failures > 0 {
        bail!("{failures} render(s) failed; BENCHMARKS.md left as it was");
    }
    let curves = if args.no_path_tracer {
        vec![None; references.len()]
    } else {
        references
            .iter()
            .map(|r| path_tracer::measure(r, &args.path_tracer_spp, scratch.path()).map(Some))
            .collect::<Result<Vec<_>>>()?
    };
    let text = section(
        &references,
        &rows,
        &curves,
        &crate::bench::machine(),
        &args.title,
    );
    println!("\n{text}");
    crate::bench::write_section(&args.section, &text)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::tests::fake_lustre;
    use lustre_image::{Precision, write_exr};

    #[test]
    fn committed_references_have_size_and_spp() {
        let dir = references_dir();
        for scene in ["glosbox", "cornell"] {
            let reference = load_reference(&dir, scene).unwrap();
            assert_eq!(
                (reference.image.width(), reference.image.height()),
                (256, 256)
            );
            assert!(reference.spp.is_some_and(|spp| spp > 0));
            assert_eq!(reference.renderer, "Mitsuba 3");
        }
        let error = load_reference(&dir, "no-such-scene").err().unwrap();
        assert!(
            format!("{error:#}").contains("cargo xtask reference"),
            "{error:#}"
        );
    }

    #[test]
    fn times_and_numbers() {
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(999), "999");
        assert_eq!(thousands(4_000_000), "4,000,000");
        assert_eq!(thousands(100_000), "100,000");
        let with_total = serde_json::json!({"timings_ms": {"trace": 2.0, "total": 5.0}});
        assert_eq!(render_time_ms(&with_total), Some(5.0));
        let without = serde_json::json!({"timings_ms": {"trace": 2.0, "splat": 1.5}});
        assert_eq!(render_time_ms(&without), Some(3.5));
        assert_eq!(render_time_ms(&serde_json::json!({})), None);
    }

    #[test]
    fn converges_through_a_fake_renderer() {
        let scratch = Scratch::new("xtask-converge-fake").unwrap();
        let dir = scratch.path();
        // 32 × 24: big enough that some pixels see only the floor or the large box.
        let reference = Image::filled(32, 24, [0.5, 0.25, 0.125]).unwrap();
        write_exr(dir.join("glosbox.exr"), &reference, Precision::F32).unwrap();
        std::fs::write(
            dir.join("glosbox.json"),
            r#"{"spp": 4096, "renderer": "Mitsuba 3"}"#,
        )
        .unwrap();
        // The fake renders the reference itself, so every error is zero.
        let lustre = fake_lustre(dir, &dir.join("glosbox.exr"), 0);
        let args = Args {
            scenes: vec!["glosbox".into()],
            photons: vec![1000, 2_000_000],
            techniques: vec!["splat".into(), "splat-direct".into()],
            kernel_c: vec!["16".into()],
            support: vec!["glossy-silverman".into()],
            section: "converge".into(),
            title: "Convergence".into(),
            path_tracer_spp: vec![1, 4],
            no_path_tracer: true,
        };
        let (references, rows, failures) = converge(&lustre, dir, &args, dir).unwrap();
        assert_eq!(failures, 0);
        assert_eq!(rows.len(), 4);
        assert!(rows.iter().all(|r| r.rel_mse == 0.0
            && r.flip_mean.abs() < 1e-6
            && r.surface_rel_mse.iter().all(|s| *s == Some(0.0))));
        // A path tracer whose relMSE is 2 (1/N + 1/4096) after 0.001 N s: at our
        // 12.5 ms it has 12.5 spp, relMSE 0.16049.
        let points = [1u32, 4, 16, 64]
            .iter()
            .map(|&spp| path_tracer::Point {
                spp,
                seconds: 0.001 * f64::from(spp),
                rel_mse: 2.0 * (1.0 / f64::from(spp) + 1.0 / 4096.0),
            })
            .collect();
        let curve = Curve::new(points, 4096).unwrap();
        let text = section(
            &references,
            &rows,
            &[Some(curve)],
            "Test CPU, 2 cores available",
            "Convergence",
        );
        assert!(
            text.contains("Machine: Test CPU, 2 cores available. GPU adapter: fake adapter."),
            "{text}"
        );
        assert!(
            text.contains("### glosbox (reference: Mitsuba 3, 4,096 spp, 32x24"),
            "{text}"
        );
        assert!(
            text.contains(
                "| splat-direct | 2,000,000 | 16 | glossy-silverman | 0.00000 | 0.00000 | 0.00000 | 0.0000 | - | 12 |"
            ),
            "{text}"
        );
        assert!(!text.contains("converge:start"));
        assert!(text.contains("| 64 | 0.06 | 0.03174 |"), "{text}");
        // Our error is zero: ratio 0, and the path tracer never gets there.
        assert!(
            text.contains("| splat | 1,000 | 16 | glossy-silverman | 0.0 | 0.00000 | 0.16"),
            "{text}"
        );
        assert!(text.contains("| 0.00 | 0.00 | – | – |"), "{text}");

        // A failing renderer is counted, not fatal to the other rows.
        let broken = fake_lustre(dir, &dir.join("glosbox.exr"), 1);
        let (_, rows, failures) = converge(&broken, dir, &args, dir).unwrap();
        assert_eq!((rows.len(), failures), (0, 4));
    }
}
