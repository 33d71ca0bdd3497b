//! Drives the `lustre` binary's headless renderer, the only way xtask
//! renders (golden, bless, converge).
//!
//! The contract: `lustre render <scene> [options] --out FILE.exr` writes a
//! linear float EXR and a JSON sidecar `FILE.json` (at least `adapter`,
//! `photons`, `technique`, `timings_ms`), and exits non-zero with a message
//! on error; exit status [`EXIT_NO_ADAPTER`] means no GPU adapter exists.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};
use lustre_image::{Image, read_exr};
use serde_json::Value;

/// Names a prebuilt `lustre` binary to use instead of building one.
pub const LUSTRE_BIN_ENV: &str = "LUSTRE_BIN";

/// The exit status with which `lustre render` says that no GPU adapter
/// exists (77, the automake convention for a skipped test): a case then
/// skips unless `LUSTRE_REQUIRE_GPU` is set.
pub const EXIT_NO_ADAPTER: i32 = 77;

/// `lustre render` found no GPU adapter; carries its message.
#[derive(Debug)]
pub struct NoAdapter(pub String);

impl std::fmt::Display for NoAdapter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "no GPU adapter: {}", self.0)
    }
}

impl std::error::Error for NoAdapter {}

/// Whether a missing GPU adapter is a failure (CI sets `LUSTRE_REQUIRE_GPU`) rather than a skip.
pub fn gpu_required() -> bool {
    std::env::var_os("LUSTRE_REQUIRE_GPU").is_some()
}

/// The `lustre` binary.
#[derive(Debug, Clone)]
pub struct Lustre {
    /// Path of the executable.
    path: PathBuf,
    /// Arguments before `render` (the script, when `path` is an interpreter).
    leading: Vec<PathBuf>,
}

/// One finished render: the image and its sidecar.
#[derive(Debug)]
pub struct Render {
    /// The linear image read back from the EXR.
    pub image: Image,
    /// The JSON sidecar.
    pub sidecar: Value,
}

impl Render {
    /// The adapter named by the sidecar.
    pub fn adapter(&self) -> &str {
        self.sidecar["adapter"]
            .as_str()
            .unwrap_or("unknown adapter")
    }
}

/// The cargo profile `lustre` is built with.
enum Profile {
    Release,
    Dev,
}

impl Lustre {
    /// The binary at `path`, used as is.
    pub fn at(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            leading: Vec::new(),
        }
    }

    /// The binary named by `LUSTRE_BIN`, or else a fresh
    /// `cargo build --release -p lustre-viewer --bin lustre` in the target
    /// directory cargo reports (which honours `CARGO_TARGET_DIR`): for
    /// benchmarks, whose times must come from the release profile.
    pub fn build() -> Result<Self> {
        Self::build_profile(Profile::Release)
    }

    /// The binary named by `LUSTRE_BIN`, or else the dev profile's
    /// `lustre`: for the golden and reference checks, which judge images,
    /// not times. `cargo test --workspace` has already built it (the viewer's
    /// tests run it), so CI compiles the dependencies once, not twice; the
    /// dev profile builds them at opt-level 3, and its renders take about
    /// 1.1 times the release binary's (the goldens: 57 s against 52 s).
    pub fn build_for_checks() -> Result<Self> {
        Self::build_profile(Profile::Dev)
    }

    fn build_profile(profile: Profile) -> Result<Self> {
        if let Some(path) = std::env::var_os(LUSTRE_BIN_ENV) {
            let path = PathBuf::from(path);
            if !path.is_file() {
                bail!("{LUSTRE_BIN_ENV}={} is not a file", path.display());
            }
            return Ok(Self::at(path));
        }
        let (flag, dir) = match profile {
            Profile::Release => (Some("--release"), "release"),
            Profile::Dev => (None, "debug"),
        };
        let mut args = vec!["build"];
        args.extend(flag);
        args.extend(["-p", "lustre-viewer", "--bin", "lustre"]);
        crate::ci::cargo(&args)?;
        let path = target_directory()?
            .join(dir)
            .join(format!("lustre{}", std::env::consts::EXE_SUFFIX));
        if !path.is_file() {
            bail!("cargo built lustre but {} does not exist", path.display());
        }
        Ok(Self::at(path))
    }

    /// Runs `lustre render <scene> <args> --out <out>` (an `.exr` path) and
    /// reads back the image and its sidecar `<out>.json`.
    pub fn render(&self, scene: &str, args: &[&str], out: &Path) -> Result<Render> {
        let sidecar = self.run(scene, args, out)?;
        let image = read_exr(out).with_context(|| {
            format!(
                "reading the render of {scene} {} into {}",
                args.join(" "),
                out.display()
            )
        })?;
        Ok(Render { image, sidecar })
    }

    /// Runs `lustre trace <scene> <args> --out <out>`: a photon file for `--photons-file`.
    pub fn trace(&self, scene: &str, args: &[&str], out: &Path) -> Result<()> {
        let output = Command::new(&self.path)
            .args(&self.leading)
            .arg("trace")
            .arg(scene)
            .args(args)
            .arg("--out")
            .arg(out)
            .output()
            .with_context(|| format!("cannot run {} trace", self.path.display()))?;
        if !output.status.success() {
            bail!(
                "lustre trace {scene} {} failed ({}): {}",
                args.join(" "),
                output.status,
                String::from_utf8_lossy(&output.stderr).trim()
            );
        }
        Ok(())
    }

    /// Runs `lustre render <scene> <args> --out <out>` and reads back only its sidecar `<out>.json` (for `--frames --timing-only`, which writes no image).
    pub fn run(&self, scene: &str, args: &[&str], out: &Path) -> Result<Value> {
        let mut command = Command::new(&self.path);
        command
            .args(&self.leading)
            .arg("render")
            .arg(scene)
            .args(args)
            .arg("--out")
            .arg(out);
        let shown = format!(
            "{} render {scene} {} --out {}",
            self.path.display(),
            args.join(" "),
            out.display()
        );
        let output = command
            .output()
            .with_context(|| format!("cannot run {shown}"))?;
        if !output.status.success() {
            let stderr = String::from_utf8_lossy(&output.stderr);
            let tail: Vec<&str> = stderr.lines().rev().take(20).collect();
            let message = tail.into_iter().rev().collect::<Vec<_>>().join("\n");
            if output.status.code() == Some(EXIT_NO_ADAPTER) {
                return Err(NoAdapter(message).into());
            }
            bail!("{shown} failed ({}):\n{message}", output.status);
        }
        let sidecar_path = out.with_extension("json");
        let text = std::fs::read_to_string(&sidecar_path)
            .with_context(|| format!("reading the sidecar {}", sidecar_path.display()))?;
        serde_json::from_str(&text)
            .with_context(|| format!("{} is not JSON", sidecar_path.display()))
    }
}

/// Frame `index` of a `lustre render --camera-path` run written to `out`: `walk.exr` gives `walk-0003.exr` (the binary's `render_frames::frame_path`).
pub fn frame_path(out: &Path, index: usize) -> PathBuf {
    let stem = out.file_stem().and_then(|s| s.to_str()).unwrap_or("frame");
    let ext = out.extension().and_then(|s| s.to_str()).unwrap_or("png");
    out.with_file_name(format!("{stem}-{index:04}.{ext}"))
}

/// Cargo's target directory for this workspace, from `cargo metadata`.
fn target_directory() -> Result<PathBuf> {
    let output = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .args(["metadata", "--format-version", "1", "--no-deps"])
        .current_dir(crate::workspace_root())
        .output()
        .context("cannot run cargo metadata")?;
    if !output.status.success() {
        bail!(
            "cargo metadata failed ({}): {}",
            output.status,
            String::from_utf8_lossy(&output.stderr)
        );
    }
    let metadata: Value =
        serde_json::from_slice(&output.stdout).context("cargo metadata printed no JSON")?;
    metadata["target_directory"]
        .as_str()
        .map(PathBuf::from)
        .context("cargo metadata names no target_directory")
}

/// A fresh scratch directory `<tmp>/lustre-<what>-<pid>`, removed on drop.
pub struct Scratch(PathBuf);

impl Scratch {
    /// Creates the directory, emptied first.
    pub fn new(what: &str) -> Result<Self> {
        let dir = std::env::temp_dir().join(format!("lustre-{what}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        Ok(Self(dir))
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[cfg(test)]
pub mod tests {
    //! A fake `lustre` (a shell script) to test the harness without a GPU.

    use super::*;
    use lustre_image::{Precision, write_exr};

    /// Writes a shell script `lustre-<status>` into `dir` that, like the
    /// real binary, copies `source` to its `--out` path and writes a
    /// sidecar; it exits with `status` instead when that is non-zero. It runs
    /// through `sh` so that no test ever executes a file another thread may
    /// still hold open for writing (ETXTBSY).
    pub fn fake_lustre(dir: &Path, source: &Path, status: i32) -> Lustre {
        let script = dir.join(format!("lustre-{status}"));
        let text = format!(
            r#"#!/bin/sh
if [ {status} -ne 0 ]; then echo "fake lustre: failing with {status}" >&2; exit {status}; fi
[ "$1" = render ] || exit 2
out=""; photons=0; technique=splat; prev=""
for arg in "$@"; do
  case "$prev" in
    --out) out="$arg" ;;
    --photons) photons="$arg" ;;
    --technique) technique="$arg" ;;
  esac
  prev="$arg"
done
cp '{}' "$out" || exit 1
printf '{{"adapter": "fake adapter", "photons": %s, "technique": "%s", "timings_ms": {{"total": 12.5}}}}\n' "$photons" "$technique" > "${{out%.exr}}.json"
"#,
            source.display()
        );
        std::fs::write(&script, text).unwrap();
        Lustre {
            path: "sh".into(),
            leading: vec![script],
        }
    }

    #[test]
    fn render_reads_image_and_sidecar() {
        let dir = Scratch::new("xtask-render-test").unwrap();
        let source = dir.path().join("source.exr");
        let image = Image::filled(4, 3, [0.5, 0.25, 1.0]).unwrap();
        write_exr(&source, &image, Precision::F32).unwrap();
        let lustre = fake_lustre(dir.path(), &source, 0);
        let out = dir.path().join("out.exr");
        let render = lustre
            .render(
                "glosbox",
                &["--technique", "splat-direct", "--photons", "7"],
                &out,
            )
            .unwrap();
        assert_eq!(render.image, image);
        assert_eq!(render.adapter(), "fake adapter");
        assert_eq!(render.sidecar["photons"], 7);
        assert_eq!(render.sidecar["technique"], "splat-direct");
    }

    #[test]
    fn failures_and_missing_adapters_are_told_apart() {
        let dir = Scratch::new("xtask-render-fail-test").unwrap();
        let out = dir.path().join("out.exr");
        let source = dir.path().join("none.exr");
        let error = fake_lustre(dir.path(), &source, 3)
            .render("cornell", &[], &out)
            .unwrap_err();
        assert!(error.downcast_ref::<NoAdapter>().is_none());
        assert!(format!("{error:#}").contains("failing with 3"), "{error:#}");
        let error = fake_lustre(dir.path(), &source, EXIT_NO_ADAPTER)
            .render("cornell", &[], &out)
            .unwrap_err();
        assert!(error.downcast_ref::<NoAdapter>().is_some(), "{error:#}");
    }
}
