//! `cargo xtask reference`: exports built-in scenes to Mitsuba 3 and renders
//! path-traced references into `tests/references/` (DESIGN.md, "Testing").
//!
//! The Python side (`xtask/python/mitsuba_render.py`) runs in the virtual
//! environment `.mitsuba-venv` at the workspace root, created here with
//! `python3 -m venv` and `pip install mitsuba==3.9.1 numpy` when missing
//! (a venv with another Mitsuba is reinstalled to [`MITSUBA_VERSION`]). Each scene
//! gives `tests/references/<scene>.exr` (linear float32 RGB) and a sidecar
//! `tests/references/<scene>.json` with the settings and timing.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::{Context, Result, bail, ensure};
use clap::ValueEnum;
use lustre_geometry::builtin::{BUILTIN_SCENES, builtin};
use lustre_geometry::mitsuba::{self, ExportOptions, Integrator, ReconstructionFilter};
use lustre_geometry::{Scene, load_scene_arg};

/// The spp a committed reference aims for.
const TARGET_SPP: u32 = 4096;

/// Options of `cargo xtask reference`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Render only this scene: a built-in name, or an OBJ or glTF 2.0 file
    /// (written as `<file stem>.exr` and `.json`; default: every built-in scene).
    #[arg(long)]
    scene: Option<String>,
    /// Samples per pixel.
    #[arg(long, default_value_t = TARGET_SPP)]
    spp: u32,
    /// Samples per pixel of each pass (the image is the mean of the passes).
    #[arg(long, default_value_t = 64)]
    spp_per_pass: u32,
    /// Width and height of the square image in pixels.
    #[arg(long, default_value_t = 256)]
    size: u32,
    /// Mitsuba variant: `llvm_ad_rgb` is faster but needs libLLVM 17 or newer.
    #[arg(long, value_enum, default_value_t = Variant::LlvmAdRgb)]
    variant: Variant,
    /// Longest path (-1: unbounded; Mitsuba's Russian roulette ends paths from depth 5).
    #[arg(long, default_value_t = -1, allow_negative_numbers = true)]
    max_depth: i32,
    /// Reconstruction filter of the film.
    #[arg(long, value_enum, default_value_t = Filter::Box)]
    filter: Filter,
    /// Seed of the first pass (pass i uses seed + i).
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Where the EXR and JSON files go (default: `tests/references` in the workspace).
    #[arg(long)]
    out_dir: Option<PathBuf>,
    /// Export each isotropic point light as a sphere of this radius in metres
    /// emitting the same power (`ExportOptions::point_light_radius`), so the
    /// path tracer finds its caustics; default: [`default_point_light_radius`].
    #[arg(long, value_name = "R", allow_negative_numbers = true)]
    point_light_radius: Option<f64>,
    /// The integrator; default: [`default_integrator`].
    #[arg(long, value_enum)]
    integrator: Option<IntegratorArg>,
    /// A note for the sidecar (e.g. why the spp is below the target).
    #[arg(long)]
    note: Option<String>,
    /// Only create the Python environment with Mitsuba; render nothing.
    #[arg(long)]
    install_only: bool,
}

/// The Mitsuba variants the references may use (CPU only).
#[derive(Debug, Clone, Copy, ValueEnum)]
enum Variant {
    /// Scalar CPU variant: slow, no dependencies.
    #[value(name = "scalar_rgb")]
    ScalarRgb,
    /// Vectorised CPU variant through LLVM: faster, needs libLLVM.
    #[value(name = "llvm_ad_rgb")]
    LlvmAdRgb,
}

impl Variant {
    /// Mitsuba's name of the variant.
    fn name(self) -> &'static str {
        match self {
            Self::ScalarRgb => "scalar_rgb",
            Self::LlvmAdRgb => "llvm_ad_rgb",
        }
    }
}

/// Film reconstruction filters.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum Filter {
    /// One-pixel box.
    Box,
    /// Gaussian of standard deviation 0.5 pixels (Mitsuba's default).
    Gaussian,
}

/// The radius of the spherical area light that stands for the point light of
/// a scene whose light reaches diffuse surfaces through mirrors or water
/// (delta-delta paths that a path tracer never finds from a point light):
/// `cardioid` (light → ring mirror → floor) and `pool` (light → water →
/// floor, and the floor seen through the water); `None` for the other
/// scenes. A camera path finds the sphere by BSDF sampling with probability
/// about `E r² / I` at a floor point of caustic irradiance `E`, so the noise
/// falls as `1/r`, while a caustic edge cast from a scatterer at distance
/// `d_ls` from the light onto a floor at `d_sf` from it blurs over about `2r
/// d_sf / d_ls`. `cardioid`: 2 cm, a blur of 1–4 cm (1–4 pixels at 256 ×
/// 256) where the far side of the ring (1.5–2 m from the light) throws the
/// caustic 0.5–1.5 m onto the floor. `pool`: 10 cm: the light is 2 m above
/// the water and the floor 0.5 m below it, so the sphere's image blurs the
/// floor by a disc of radius about 0.1 / 2 · 0.5 / 1.33 ≈ 2 cm, while the
/// waves' caustic is bands 20–50 cm wide (its contrast drops by about 1 %).
/// `stained-glass` takes the particle tracer instead ([`default_integrator`]).
pub fn default_point_light_radius(scene: &str) -> Option<f64> {
    match scene {
        "cardioid" => Some(0.02),
        "pool" => Some(0.1),
        _ => None,
    }
}

/// The integrator of a scene's reference: Mitsuba's particle tracer for
/// `stained-glass`, whose room is lit only through thin-dielectric panes
/// (light → pane → floor). A path tracer finds that light only by hitting a
/// sphere standing for the point light through the panes: at r = 10 cm and
/// 262,144 spp (24 minutes on 2 cores) the floor was still 13.5 % noise per
/// pixel, and the sphere blurred the pane edges by 8–37 cm, a luminance
/// error of about 14 % over the coloured patch. Light tracing follows the
/// point light through the panes exactly and connects the floor to the
/// camera: 3.4 % noise at 65,536 spp in about a minute, sharp edges, and
/// over the patch 1.008 of the path-traced sphere's light (the whole frame
/// 0.9999). It misses only what the camera sees in or through a pane (the
/// room reflected in the window, about 8 % of a dim wall). `path` otherwise.
pub fn default_integrator(scene: &str) -> Integrator {
    match scene {
        "stained-glass" => Integrator::ParticleTracer,
        _ => Integrator::Path,
    }
}

/// The integrators `--integrator` names.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum IntegratorArg {
    /// Path tracing from the camera.
    Path,
    /// Particle (light) tracing.
    Ptracer,
}

/// The workspace root (the parent of `xtask/`).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in the workspace")
        .to_path_buf()
}

/// The Python interpreter of `.mitsuba-venv`.
pub fn venv_python(root: &Path) -> PathBuf {
    root.join(".mitsuba-venv").join("bin").join("python")
}

/// Runs `cargo xtask reference`.
pub fn run(args: Args) -> Result<()> {
    let root = workspace_root();
    let python = ensure_venv(&root)?;
    if args.install_only {
        eprintln!("reference: Mitsuba is ready in {}", python.display());
        return Ok(());
    }
    ensure!(
        args.spp > 0 && args.size > 0 && args.spp_per_pass > 0,
        "--spp, --size and --spp-per-pass must be positive"
    );
    if let Some(r) = args.point_light_radius {
        ensure!(
            r.is_finite() && r > 0.0,
            "--point-light-radius must be a positive, finite radius in metres, not {r}"
        );
    }
    let scenes: Vec<(String, Scene)> = match &args.scene {
        Some(arg) => vec![reference_scene(arg)?],
        None => BUILTIN_SCENES
            .iter()
            .map(|name| Ok(((*name).to_owned(), builtin(name)?)))
            .collect::<Result<_>>()?,
    };
    let out_dir = args
        .out_dir
        .clone()
        .unwrap_or_else(|| root.join("tests").join("references"));
    std::fs::create_dir_all(&out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let work = std::env::temp_dir().join(format!("lustre-reference-{}", std::process::id()));
    let result = scenes.iter().try_for_each(|(name, scene)| {
        render_scene(name, scene, &args, &python, &root, &out_dir, &work)
    });
    let _ = std::fs::remove_dir_all(&work);
    result
}

/// The scene `--scene` names and the name its files take (the scene's own:
/// a built-in scene's name, a scene file's stem; [`load_scene_arg`], the
/// loader's warnings on stderr). Fails on a name that is neither.
fn reference_scene(arg: &str) -> Result<(String, Scene)> {
    let loaded = load_scene_arg(arg).with_context(|| format!("--scene `{arg}`"))?;
    for warning in &loaded.warnings {
        eprintln!("reference: {arg}: warning: {warning}");
    }
    Ok((loaded.scene.name.clone(), loaded.scene))
}

/// Exports one scene, renders it and writes its EXR and sidecar.
fn render_scene(
    name: &str,
    scene: &Scene,
    args: &Args,
    python: &Path,
    root: &Path,
    out_dir: &Path,
    work: &Path,
) -> Result<()> {
    let xml = work.join(name).join("scene.xml");
    let filter = match args.filter {
        Filter::Box => ReconstructionFilter::Box,
        Filter::Gaussian => ReconstructionFilter::Gaussian { stddev: 0.5 },
    };
    let point_light_radius = args
        .point_light_radius
        .or_else(|| default_point_light_radius(name));
    let integrator = match args.integrator {
        Some(IntegratorArg::Path) => Integrator::Path,
        Some(IntegratorArg::Ptracer) => Integrator::ParticleTracer,
        None => default_integrator(name),
    };
    let options = ExportOptions {
        width: args.size,
        height: args.size,
        spp: args.spp,
        seed: args.seed,
        integrator,
        max_depth: args.max_depth,
        filter,
        point_light_radius: point_light_radius.map(|r| r as f32),
        ..ExportOptions::default()
    };
    let report = mitsuba::export(scene, &xml, &options)
        .with_context(|| format!("exporting `{name}` to Mitsuba"))?;
    for warning in &report.warnings {
        eprintln!("reference: {name}: warning: {warning}");
    }
    if let Some(r) = point_light_radius {
        eprintln!("reference: {name}: point lights exported as spheres of radius {r} m");
    }
    eprintln!(
        "reference: {name}: exported to {}; rendering {}x{} at {} spp with Mitsuba {} ({}, max_depth {})",
        xml.display(),
        args.size,
        args.size,
        args.spp,
        args.variant.name(),
        integrator.plugin(),
        args.max_depth
    );
    let exr = out_dir.join(format!("{name}.exr"));
    let info = run_helper(
        python,
        root,
        &[
            "--variant",
            args.variant.name(),
            "--scene",
            path_str(&xml)?,
            "--out",
            path_str(&exr)?,
            "--spp",
            &args.spp.to_string(),
            "--spp-per-pass",
            &args.spp_per_pass.to_string(),
            "--seed",
            &args.seed.to_string(),
        ],
    )
    .with_context(|| {
        let hint = match args.variant {
            Variant::LlvmAdRgb => {
                "; llvm_ad_rgb needs libLLVM 17 or newer (e.g. `apt-get install libllvm19`, or point \
                 DRJIT_LIBLLVM_PATH at it), or use --variant scalar_rgb"
            }
            Variant::ScalarRgb => "",
        };
        format!("rendering `{name}` with Mitsuba{hint}")
    })?;
    let seconds = info["render_seconds"].as_f64().unwrap_or(f64::NAN);
    let mut note = args.note.clone().unwrap_or_default();
    if args.spp < TARGET_SPP && note.is_empty() {
        note = format!("{} spp, below the {TARGET_SPP} spp target", args.spp);
    }
    let mut sidecar = serde_json::json!({
        "scene": name,
        "renderer": "Mitsuba 3",
        "mitsuba_version": info["mitsuba_version"],
        "variant": args.variant.name(),
        "integrator": integrator.plugin(),
        "max_depth": args.max_depth,
        "rr_depth": 5,
        "rfilter": match filter {
            ReconstructionFilter::Box => "box".to_owned(),
            ReconstructionFilter::Gaussian { stddev } => format!("gaussian (stddev {stddev})"),
        },
        "width": args.size,
        "height": args.size,
        "spp": info["spp"],
        "spp_per_pass": info["spp_per_pass"],
        "seed": args.seed,
        "render_seconds": info["render_seconds"],
        "date": info["date"],
        "mean_rgb": info["mean"],
        "export_warnings": report.warnings,
        "note": note,
        "command": format!(
            "cargo xtask reference --scene {} --spp {} --spp-per-pass {} --size {} --variant {} --integrator {} --max-depth {} --filter {} --seed {}{}",
            args.scene.as_deref().unwrap_or(name),
            args.spp,
            args.spp_per_pass,
            args.size,
            args.variant.name(),
            integrator.plugin(),
            args.max_depth,
            match args.filter { Filter::Box => "box", Filter::Gaussian => "gaussian" },
            args.seed,
            point_light_radius.map_or(String::new(), |r| format!(" --point-light-radius {r}"))
        ),
    });
    if let Some(r) = point_light_radius {
        // The point light's stand-in (ExportOptions::point_light_radius): a sphere of equal power.
        sidecar["point_light_radius"] = serde_json::json!(r);
    }
    let json_path = out_dir.join(format!("{name}.json"));
    write_atomically(
        &json_path,
        format!("{}\n", serde_json::to_string_pretty(&sidecar)?).as_bytes(),
    )?;
    eprintln!(
        "reference: {name}: wrote {} and {} ({seconds:.1} s)",
        exr.display(),
        json_path.display()
    );
    Ok(())
}

/// How a committed reference was rendered, read back from its sidecar
/// (`tests/references/<scene>.json`): the export options and Mitsuba
/// variant that render the scene as the reference did, at `spp` samples with
/// `seed` (for renders to set beside it: `cargo xtask converge`'s path-tracer
/// curve).
pub fn export_like(
    sidecar: &serde_json::Value,
    spp: u32,
    seed: u32,
) -> Result<(ExportOptions, String)> {
    let field = |name: &str| {
        sidecar
            .get(name)
            .with_context(|| format!("the reference's sidecar has no `{name}`"))
    };
    let size = |name: &str| -> Result<u32> {
        let value = field(name)?;
        value
            .as_u64()
            .and_then(|v| u32::try_from(v).ok())
            .filter(|&v| v > 0)
            .with_context(|| format!("the reference's `{name}` is {value}, not a positive size"))
    };
    let integrator = match field("integrator")?.as_str() {
        Some("path") => Integrator::Path,
        Some("ptracer") => Integrator::ParticleTracer,
        other => bail!("the reference's integrator {other:?} is neither `path` nor `ptracer`"),
    };
    let max_depth = field("max_depth")?
        .as_i64()
        .and_then(|d| i32::try_from(d).ok())
        .context("the reference's `max_depth` is not an integer")?;
    let filter = match field("rfilter")?.as_str() {
        Some("box") => ReconstructionFilter::Box,
        Some(text) if text.starts_with("gaussian") => ReconstructionFilter::Gaussian {
            stddev: text
                .trim_start_matches("gaussian (stddev ")
                .trim_end_matches(')')
                .parse()
                .with_context(|| {
                    format!("the reference's filter {text:?} names no standard deviation")
                })?,
        },
        other => bail!("the reference's filter {other:?} is neither box nor gaussian"),
    };
    let point_light_radius = match sidecar.get("point_light_radius") {
        None | Some(serde_json::Value::Null) => None,
        Some(r) => Some(
            r.as_f64()
                .filter(|r| r.is_finite() && *r > 0.0)
                .with_context(|| {
                    format!("the reference's point_light_radius {r} is not a positive radius")
                })? as f32,
        ),
    };
    let variant = field("variant")?
        .as_str()
        .context("the reference's `variant` is not a string")?
        .to_owned();
    let options = ExportOptions {
        width: size("width")?,
        height: size("height")?,
        spp,
        seed,
        integrator,
        max_depth,
        filter,
        point_light_radius,
        ..ExportOptions::default()
    };
    Ok((options, variant))
}

/// Runs the Python helper with `args`, passing its stderr (progress) through,
/// and returns the JSON object on the last line of its stdout.
pub fn run_helper(python: &Path, root: &Path, args: &[&str]) -> Result<serde_json::Value> {
    let script = helper_script(root);
    let output = Command::new(python)
        .arg(&script)
        .args(args)
        .stdin(Stdio::null())
        .stderr(Stdio::inherit())
        .output()
        .with_context(|| format!("running {} {}", python.display(), script.display()))?;
    let stdout = String::from_utf8_lossy(&output.stdout);
    if !output.status.success() {
        bail!(
            "{} failed ({}); its output:\n{stdout}",
            script.display(),
            output.status
        );
    }
    let last = stdout
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("");
    serde_json::from_str(last).with_context(|| format!("reading the helper's report {last:?}"))
}

/// The Python helper that renders with Mitsuba, under the workspace `root`.
pub fn helper_script(root: &Path) -> PathBuf {
    root.join("xtask").join("python").join("mitsuba_render.py")
}

/// The Mitsuba 3 release the references and the Mitsuba tests use (`tests/references/*.json` say 3.9.1).
pub const MITSUBA_VERSION: &str = "3.9.1";

/// The pip requirement of Mitsuba: exactly [`MITSUBA_VERSION`].
fn mitsuba_requirement() -> String {
    format!("mitsuba=={MITSUBA_VERSION}")
}

/// The pip requirement of numpy: the 2.x series the venv was built with (2.4.6), which Mitsuba 3.9 supports.
const NUMPY_REQUIREMENT: &str = "numpy>=2.0,<3";

/// What the venv's Python has: Mitsuba's version, or why it cannot import Mitsuba and numpy.
fn venv_mitsuba(python: &Path) -> std::result::Result<String, String> {
    let output = Command::new(python)
        .args(["-c", "import mitsuba, numpy; print(mitsuba.__version__)"])
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run {}: {e}", python.display()))?;
    if !output.status.success() {
        return Err(format!(
            "{} cannot import mitsuba and numpy",
            python.display()
        ));
    }
    Ok(String::from_utf8_lossy(&output.stdout).trim().to_owned())
}

/// Makes sure `.mitsuba-venv` exists and imports Mitsuba [`MITSUBA_VERSION`]
/// and numpy, installing them with pip when missing and reinstalling
/// Mitsuba when the venv has another version; returns its Python.
pub(crate) fn ensure_venv(root: &Path) -> Result<PathBuf> {
    let venv = root.join(".mitsuba-venv");
    let python = venv_python(root);
    if !python.exists() {
        eprintln!(
            "reference: creating the Python environment {}",
            venv.display()
        );
        run_checked(Command::new("python3").args(["-m", "venv"]).arg(&venv)).context(
            "creating the virtual environment (is python3 with the venv module installed? \
             `apt-get install python3-venv`)",
        )?;
    }
    match venv_mitsuba(&python) {
        Ok(version) if version == MITSUBA_VERSION => return Ok(python),
        Ok(version) => eprintln!(
            "reference: {} has Mitsuba {version}, but the references and tests use {MITSUBA_VERSION}; \
             reinstalling {}",
            venv.display(),
            mitsuba_requirement()
        ),
        Err(why) => eprintln!(
            "reference: {why}; installing {} and {NUMPY_REQUIREMENT} into {}",
            mitsuba_requirement(),
            venv.display()
        ),
    }
    run_checked(Command::new(&python).args(["-m", "pip", "install", "--upgrade", "pip"]))
        .context("upgrading pip")?;
    run_checked(Command::new(&python).args([
        "-m",
        "pip",
        "install",
        &mitsuba_requirement(),
        NUMPY_REQUIREMENT,
    ]))
    .with_context(|| {
        format!(
            "installing {} and {NUMPY_REQUIREMENT} with pip",
            mitsuba_requirement()
        )
    })?;
    check_version(&python, venv_mitsuba(&python))?;
    Ok(python)
}

/// Refuses a venv whose Mitsuba is not [`MITSUBA_VERSION`] after installing, saying what to do.
fn check_version(python: &Path, found: std::result::Result<String, String>) -> Result<()> {
    match found {
        Ok(version) if version == MITSUBA_VERSION => Ok(()),
        Ok(version) => bail!(
            "{} has Mitsuba {version} after `pip install {}`; the references need \
             {MITSUBA_VERSION}: remove .mitsuba-venv and run `cargo xtask reference --install-only`",
            python.display(),
            mitsuba_requirement()
        ),
        Err(why) => bail!("{why} after pip install"),
    }
}

/// Runs a command with inherited output and fails on a non-zero exit.
fn run_checked(command: &mut Command) -> Result<()> {
    let status = command
        .status()
        .with_context(|| format!("starting {command:?}"))?;
    ensure!(status.success(), "{command:?} failed ({status})");
    Ok(())
}

/// The path as UTF-8, for the helper's command line.
pub(crate) fn path_str(path: &Path) -> Result<&str> {
    path.to_str()
        .with_context(|| format!("{} is not valid UTF-8", path.display()))
}

/// Writes `bytes` to a temporary name beside `path` and renames it.
fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension(format!("json.tmp-{}", std::process::id()));
    std::fs::write(&tmp, bytes)
        .and_then(|()| std::fs::rename(&tmp, path))
        .with_context(|| format!("writing {}", path.display()))
        .inspect_err(|_| {
            let _ = std::fs::remove_file(&tmp);
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_is_a_builtin_name_or_a_scene_file_named_by_its_stem() {
        let (name, scene) = reference_scene("cornell").unwrap();
        assert_eq!(name, "cornell");
        assert_eq!(scene.name, builtin("cornell").unwrap().name);
        let file = workspace_root().join("tests/scenes/textured-cornell/textured-cornell.obj");
        let (name, scene) = reference_scene(file.to_str().unwrap()).unwrap();
        assert_eq!(name, "textured-cornell");
        // The file's checker map is loaded, as the export bakes it into the reference.
        assert!(scene.materials().iter().any(|m| m.diffuse_map.is_some()));
        let error = format!("{:#}", reference_scene("no-such-scene.obj").unwrap_err());
        assert!(
            error.contains("neither a built-in scene (cornell, ")
                && error.contains("nor an existing file"),
            "{error}"
        );
    }

    #[test]
    fn references_are_rendered_again_as_their_sidecars_say() {
        let dir = workspace_root().join("tests").join("references");
        let read = |scene: &str| -> serde_json::Value {
            serde_json::from_str(
                &std::fs::read_to_string(dir.join(format!("{scene}.json"))).unwrap(),
            )
            .unwrap()
        };
        let (options, variant) = export_like(&read("glosbox"), 16, 1000).unwrap();
        assert_eq!(
            (options.width, options.height, options.spp, options.seed),
            (256, 256, 16, 1000)
        );
        assert_eq!(
            (options.integrator, options.max_depth),
            (Integrator::Path, -1)
        );
        assert_eq!(options.filter, ReconstructionFilter::Box);
        assert_eq!(
            (options.point_light_radius, variant.as_str()),
            (None, "llvm_ad_rgb")
        );
        let (options, _) = export_like(&read("cardioid"), 1, 0).unwrap();
        assert_eq!(options.point_light_radius, Some(0.02));
        let (options, _) = export_like(&read("stained-glass"), 1, 0).unwrap();
        assert_eq!(options.integrator, Integrator::ParticleTracer);

        let mut gaussian = read("glosbox");
        gaussian["rfilter"] = "gaussian (stddev 0.5)".into();
        let (options, _) = export_like(&gaussian, 1, 0).unwrap();
        assert_eq!(
            options.filter,
            ReconstructionFilter::Gaussian { stddev: 0.5 }
        );
        for (key, bad) in [
            ("integrator", serde_json::json!("bdpt")),
            ("width", serde_json::json!(0)),
            ("rfilter", serde_json::json!("tent")),
            ("point_light_radius", serde_json::json!(-1.0)),
        ] {
            let mut sidecar = read("glosbox");
            sidecar[key] = bad;
            let error = export_like(&sidecar, 1, 0).unwrap_err().to_string();
            assert!(
                error.contains(key) || error.contains("filter"),
                "{key}: {error}"
            );
        }
        let mut missing = read("glosbox");
        missing.as_object_mut().unwrap().remove("max_depth");
        assert!(
            export_like(&missing, 1, 0)
                .unwrap_err()
                .to_string()
                .contains("max_depth")
        );
    }

    #[test]
    fn the_pinned_mitsuba_is_the_one_the_references_name() {
        let dir = workspace_root().join("tests").join("references");
        for scene in ["cornell", "glosbox"] {
            let text = std::fs::read_to_string(dir.join(format!("{scene}.json"))).unwrap();
            let sidecar: serde_json::Value = serde_json::from_str(&text).unwrap();
            assert_eq!(sidecar["mitsuba_version"], MITSUBA_VERSION, "{scene}");
        }
        assert_eq!(mitsuba_requirement(), "mitsuba==3.9.1");
    }

    #[test]
    fn another_mitsuba_is_refused_with_what_to_do() {
        let python = Path::new("/venv/bin/python");
        assert!(check_version(python, Ok(MITSUBA_VERSION.to_owned())).is_ok());
        let error = check_version(python, Ok("3.5.0".to_owned()))
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("Mitsuba 3.5.0") && error.contains("--install-only"),
            "{error}"
        );
        assert!(check_version(python, Err("cannot import".to_owned())).is_err());
    }
}
