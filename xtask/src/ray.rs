//! `cargo xtask ray`: the Ray driver (`tools/ray/lustre_ray.py`) checked on a local Ray instance.
//!
//! Creates `.ray-venv` at the workspace root with `python3 -m venv` and
//! `pip install ray==`[`RAY_VERSION`] when missing. The check traces a run of
//! `glosbox` photons in batches as Ray tasks on several worker processes,
//! merges them, and holds the merged file byte for byte to a single-process
//! `lustre trace` of the same run; then renders two frames from it as tasks
//! and holds them to the same renders run directly. `cargo xtask ci` runs it.

use std::path::Path;
use std::process::Command;

use anyhow::{Context, Result, ensure};

use crate::venv::{Venv, checked};

/// The Ray release the driver is checked with.
pub const RAY_VERSION: &str = "2.60.0";

/// `.ray-venv` with Ray [`RAY_VERSION`].
const RAY_VENV: Venv = Venv {
    dir: ".ray-venv",
    package: "ray",
    version: RAY_VERSION,
    probe: "import ray; print(ray.__version__)",
    user: "ray",
};

/// Options of `cargo xtask ray`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Only create `.ray-venv` with Ray, without running the check.
    #[arg(long)]
    pub install_only: bool,
}

/// Runs `cargo xtask ray`.
pub fn run(args: Args) -> Result<()> {
    let root = crate::workspace_root();
    let python = RAY_VENV.ensure(&root)?;
    if args.install_only {
        println!("ray: {} has Ray {RAY_VERSION}", python.display());
        return Ok(());
    }
    check(&root, &python)
}

/// The check of the module documentation.
fn check(root: &Path, python: &Path) -> Result<()> {
    crate::ci::cargo(&["build", "-p", "lustre-viewer", "--bin", "lustre"])?;
    let lustre = root.join("target").join("debug").join("lustre");
    let dir = root.join("target").join("tmp").join("ray-check");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let driver = root.join("tools").join("ray").join("lustre_ray.py");
    let path = |p: &Path| p.to_str().map(str::to_owned).context("non-UTF-8 path");
    let (merged, single) = (dir.join("merged.lph"), dir.join("single.lph"));
    let photons = "100000";
    // Four batches on three worker processes, one tracing thread each.
    checked(
        Command::new(python)
            .arg(&driver)
            .args([
                "--lustre",
                &path(&lustre)?,
                "--workers",
                "3",
                "--threads-per-task",
                "1",
            ])
            .args(["trace", "glosbox", "--photons", photons, "--batches", "4"])
            .args(["--out", &path(&merged)?]),
    )
    .context("the Ray driver's trace")?;
    checked(
        Command::new(&lustre)
            .args(["trace", "glosbox", "--photons", photons])
            .args(["--out", &path(&single)?]),
    )
    .context("the single-process trace")?;
    let (a, b) = (
        std::fs::read(&merged).context("reading the merged file")?,
        std::fs::read(&single).context("reading the single-process file")?,
    );
    ensure!(
        a == b,
        "the merged file ({} bytes) differs from the single-process trace ({} bytes)",
        a.len(),
        b.len()
    );
    println!(
        "ray: 4 batches traced as Ray tasks and merged equal the single-process trace ({} bytes)",
        a.len()
    );
    // Two frames from the merged file as tasks, against the same renders run directly.
    let frame = |name: &str, size: &str| -> Result<Vec<String>> {
        Ok(vec![
            "glosbox".into(),
            "--photons-file".into(),
            path(&merged)?,
            "--batch-records".into(),
            "50000".into(),
            "--size".into(),
            size.into(),
            "--out".into(),
            path(&dir.join(name))?,
        ])
    };
    let frames = vec![frame("ray-0.exr", "48x48")?, frame("ray-1.exr", "64x32")?];
    let list = dir.join("frames.json");
    std::fs::write(&list, serde_json::to_vec(&frames)?).context("writing frames.json")?;
    checked(
        Command::new(python)
            .arg(&driver)
            .args(["--lustre", &path(&lustre)?, "--workers", "2"])
            .args(["frames", &path(&list)?]),
    )
    .context("the Ray driver's frames")?;
    for (i, (name, size)) in [("0", "48x48"), ("1", "64x32")].into_iter().enumerate() {
        let direct = dir.join(format!("direct-{name}.exr"));
        let mut args = frame(&format!("direct-{name}.exr"), size)?;
        args.insert(0, "render".into());
        checked(Command::new(&lustre).args(&args)).context("a direct render")?;
        let ray = lustre_image::read_exr(dir.join(format!("ray-{name}.exr")))?;
        let direct = lustre_image::read_exr(&direct)?;
        let largest = ray
            .pixels()
            .iter()
            .flatten()
            .fold(0.0f32, |m, v| m.max(v.abs()));
        let worst = ray
            .pixels()
            .iter()
            .flatten()
            .zip(direct.pixels().iter().flatten())
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f32, f32::max);
        ensure!(
            largest > 0.0 && worst <= 1e-6 * largest,
            "frame {i} rendered as a Ray task differs from the direct render by {worst} (largest value {largest})"
        );
    }
    println!("ray: 2 frames rendered as Ray tasks equal the direct renders");
    std::fs::remove_dir_all(&dir).ok();
    Ok(())
}
