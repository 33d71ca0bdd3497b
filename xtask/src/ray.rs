//! `cargo xtask ray`: the Ray driver (`tools/ray/lustre_ray.py`) checked on a local Ray instance.
//!
//! Creates `.ray-venv` at the workspace root with `python3 -m venv` and
//! `pip install ray==`[`RAY_VERSION`] when missing. The check traces a run of
//! `glosbox` photons in batches as Ray tasks on several worker processes,
//! merges them, and holds the merged file byte for byte to a single-process
//! `lustre trace` of the same run; then renders two frames from it as tasks
//! and holds them to the same renders run directly. `cargo xtask ci` runs it.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail, ensure};

/// The Ray release the driver is checked with.
pub const RAY_VERSION: &str = "2.60.0";

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
    let python = ensure_venv(&root)?;
    if args.install_only {
        println!("ray: {} has Ray {RAY_VERSION}", python.display());
        return Ok(());
    }
    check(&root, &python)
}

/// The Python of `.ray-venv`.
fn venv_python(root: &Path) -> PathBuf {
    root.join(".ray-venv").join("bin").join("python")
}

/// Ray's version in the venv, or why it cannot be imported.
fn venv_ray(python: &Path) -> std::result::Result<String, String> {
    let output = Command::new(python)
        .args(["-c", "import ray; print(ray.__version__)"])
        .output()
        .map_err(|e| format!("cannot run {}: {e}", python.display()))?;
    if !output.status.success() {
        return Err(format!("{} cannot import ray", python.display()));
    }
    Ok(String::from_utf8_lossy(&output.stdout).trim().to_owned())
}

/// Makes sure `.ray-venv` imports Ray [`RAY_VERSION`], installing it when missing.
fn ensure_venv(root: &Path) -> Result<PathBuf> {
    let venv = root.join(".ray-venv");
    let python = venv_python(root);
    if !python.exists() {
        eprintln!("ray: creating the Python environment {}", venv.display());
        checked(Command::new("python3").args(["-m", "venv"]).arg(&venv)).context(
            "creating the virtual environment (is python3 with the venv module installed? \
             `apt-get install python3-venv`)",
        )?;
    }
    match venv_ray(&python) {
        Ok(version) if version == RAY_VERSION => return Ok(python),
        Ok(version) => eprintln!(
            "ray: {} has Ray {version}; installing {RAY_VERSION}",
            venv.display()
        ),
        Err(why) => eprintln!("ray: {why}; installing ray=={RAY_VERSION}"),
    }
    checked(Command::new(&python).args([
        "-m",
        "pip",
        "install",
        "-q",
        &format!("ray=={RAY_VERSION}"),
    ]))
    .with_context(|| format!("installing ray=={RAY_VERSION} with pip"))?;
    match venv_ray(&python) {
        Ok(version) if version == RAY_VERSION => Ok(python),
        Ok(version) => bail!("{} has Ray {version} after pip install", python.display()),
        Err(why) => bail!("{why} after pip install"),
    }
}

/// Runs a command with inherited output and fails on a non-zero exit.
fn checked(command: &mut Command) -> Result<()> {
    let status = command
        .status()
        .with_context(|| format!("starting {command:?}"))?;
    ensure!(status.success(), "{command:?} failed ({status})");
    Ok(())
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
