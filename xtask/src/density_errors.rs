//! `cargo xtask density-errors`: the error and timing tables of García Hernández, Ureña & Lastra (2003), tables 2.1 and 2.6–2.8, for each per-vertex estimator and photon count: the noise error against the same estimator with many photons, its bias against the path-traced reference, the total error against the reference and against DETP with many photons (the paper's own reference), all as the mean luminance difference of section 2.5.3; with the photosimulation update and radiosity recalculation times per frame of `lustre render --frames --timing-only`. Written into BENCHMARKS.md between `<!-- density-errors:start -->` and `<!-- density-errors:end -->`.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use anyhow::{Result, bail};
use lustre_image::Image;
use lustre_image::metrics::{RELATIVE_MSE_EPSILON, mean_luminance_difference, relative_mse};
use serde_json::Value;

use crate::converge::{Reference, load_reference, thousands};
use crate::render::{Lustre, Scratch};

/// Options of `cargo xtask density-errors`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Built-in scene with a reference `tests/references/<scene>.exr`.
    #[arg(long, default_value = "cornell")]
    scene: String,
    /// Photon counts of the measured renders (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "10000,100000,1000000")]
    photons: Vec<u64>,
    /// Estimators, as `lustre render --technique` (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "detp,impact,photonmap")]
    estimators: Vec<String>,
    /// Photons of each estimator's own high-photon render (the noise reference).
    #[arg(long, default_value_t = 4_000_000)]
    reference_photons: u64,
    /// Frames of the timing run (`lustre render --frames`).
    #[arg(long, default_value_t = 8)]
    frames: usize,
    /// Extra arguments for every `lustre render` (e.g. `--radius=0.05`), space-separated.
    #[arg(long, default_value = "", allow_hyphen_values = true)]
    extra: String,
}

/// One estimator at one photon count.
#[derive(Debug, Clone, PartialEq)]
struct Row {
    estimator: String,
    photons: u64,
    /// Median photosimulation update per frame, ms.
    update_ms: Option<f64>,
    /// Median radiosity recalculation per frame, ms.
    radiosity_ms: Option<f64>,
    /// Against the same estimator with `reference_photons`.
    noise: f64,
    /// The same estimator with `reference_photons` against the path-traced reference.
    bias: f64,
    /// Against the path-traced reference.
    total: f64,
    /// Against DETP with `reference_photons`, the paper's reference.
    total_detp: Option<f64>,
    /// Relative MSE against the path-traced reference.
    rel_mse: f64,
}

/// The errors of one render (table 2.6's columns).
fn errors(
    image: &Image,
    own_reference: &Image,
    detp_reference: Option<&Image>,
    reference: &Image,
) -> Result<(f64, f64, f64, Option<f64>, f64)> {
    Ok((
        mean_luminance_difference(image, own_reference)?,
        mean_luminance_difference(own_reference, reference)?,
        mean_luminance_difference(image, reference)?,
        detp_reference
            .map(|d| mean_luminance_difference(image, d))
            .transpose()?,
        relative_mse(image, reference, RELATIVE_MSE_EPSILON)?,
    ))
}

/// The median of the sidecar's `median_ms.<key>`.
fn median_ms(sidecar: &Value, key: &str) -> Option<f64> {
    sidecar["median_ms"][key].as_f64()
}

fn percent(x: f64) -> String {
    format!("{:.2} %", 100.0 * x)
}

fn section(reference: &Reference, rows: &[Row], args: &Args, machine: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "## Quasi-static estimators: error and time per frame ({})\n",
        reference.scene
    );
    let _ = writeln!(
        s,
        "Written by `cargo xtask density-errors`; do not edit by hand. The form of García et al.'s tables 2.1 and 2.6–2.8. \
         Errors are the mean luminance difference Σ|Y − Y_ref| / ΣY_ref (section 2.5.3) at {}x{}: *noise* against the same estimator \
         with {} photons, *bias* of that render against the path-traced reference ({}, {} spp), *total* against the reference, and \
         *vs DETP* against DETP with {} photons (the paper's reference). Times are medians over {} frames of `lustre render --frames {} --timing-only` \
         with the scene's mobile object moving along its path: the photosimulation update (figure 2.2) and the radiosity recalculation \
         (equation 2.4 and the mobile vertices). Extra render arguments: `{}`. Machine: {machine}.\n",
        reference.image.width(),
        reference.image.height(),
        thousands(args.reference_photons),
        reference.renderer,
        reference.spp.map_or("unknown".to_owned(), thousands),
        thousands(args.reference_photons),
        args.frames,
        args.frames,
        if args.extra.is_empty() {
            "none"
        } else {
            &args.extra
        },
    );
    let _ = writeln!(
        s,
        "| estimator | photons | photosim. update (ms) | radiosity (ms) | noise | bias | total | vs DETP | relMSE |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {:.4} |",
            r.estimator,
            thousands(r.photons),
            r.update_ms.map_or("-".into(), |t| format!("{t:.1}")),
            r.radiosity_ms.map_or("-".into(), |t| format!("{t:.1}")),
            percent(r.noise),
            percent(r.bias),
            percent(r.total),
            r.total_detp.map_or("-".into(), percent),
            r.rel_mse
        );
    }
    s
}

/// Runs `cargo xtask density-errors`.
pub fn run(args: Args) -> Result<()> {
    if args.photons.is_empty() || args.estimators.is_empty() || args.photons.contains(&0) {
        bail!("--photons and --estimators need at least one value each, photons positive");
    }
    let lustre = Lustre::build()?;
    let scratch = Scratch::new("density-errors")?;
    let dir = scratch.path();
    let references_dir = crate::converge::references_dir();
    let reference = load_reference(&references_dir, &args.scene)?;
    let size = format!("{}x{}", reference.image.width(), reference.image.height());
    let extra: Vec<&str> = args.extra.split_whitespace().collect();
    let render = |technique: &str, photons: u64| -> Result<Image> {
        let out = dir.join(format!("{technique}-{photons}.exr"));
        let photons = photons.to_string();
        let mut a = vec![
            "--technique",
            technique,
            "--photons",
            &photons,
            "--size",
            &size,
            "--seed",
            "1",
        ];
        a.extend(&extra);
        println!("density-errors: {} {}", args.scene, a.join(" "));
        Ok(lustre.render(&args.scene, &a, &out)?.image)
    };
    let mut own = BTreeMap::new();
    for e in &args.estimators {
        own.insert(e.clone(), render(e, args.reference_photons)?);
    }
    let detp_reference = own.get("detp");
    let mut rows = Vec::new();
    for e in &args.estimators {
        for &photons in &args.photons {
            let image = render(e, photons)?;
            let (noise, bias, total, total_detp, rel_mse) =
                errors(&image, &own[e], detp_reference, &reference.image)?;
            let out = dir.join(format!("{e}-{photons}-frames.exr"));
            let (p, f) = (photons.to_string(), args.frames.to_string());
            let mut a = vec![
                "--technique",
                e,
                "--photons",
                &p,
                "--seed",
                "1",
                "--frames",
                &f,
                "--timing-only",
            ];
            a.extend(&extra);
            let timing = lustre.run(&args.scene, &a, &out)?;
            let row = Row {
                estimator: e.clone(),
                photons,
                update_ms: median_ms(&timing, "photosimulation_update"),
                radiosity_ms: median_ms(&timing, "radiosity"),
                noise,
                bias,
                total,
                total_detp,
                rel_mse,
            };
            println!("density-errors: {row:?}");
            rows.push(row);
        }
    }
    let text = section(&reference, &rows, &args, &crate::bench::machine());
    println!("\n{text}");
    crate::bench::write_section("density-errors", &text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_of_known_images() {
        let reference = Image::filled(4, 2, [1.0, 1.0, 1.0]).unwrap();
        let own = Image::filled(4, 2, [0.9, 0.9, 0.9]).unwrap();
        let image = Image::filled(4, 2, [0.8, 0.8, 0.8]).unwrap();
        let (noise, bias, total, vs_detp, _) =
            errors(&image, &own, Some(&reference), &reference).unwrap();
        assert!((noise - 0.1 / 0.9).abs() < 1e-6, "{noise}");
        assert!((bias - 0.1).abs() < 1e-6, "{bias}");
        assert!((total - 0.2).abs() < 1e-6, "{total}");
        assert!((vs_detp.unwrap() - 0.2).abs() < 1e-6);
        let sidecar = serde_json::json!({"median_ms": {"radiosity": 12.5}});
        assert_eq!(median_ms(&sidecar, "radiosity"), Some(12.5));
        assert_eq!(median_ms(&sidecar, "photosimulation_update"), None);
        assert_eq!(percent(0.1234), "12.34 %");
    }
}
