//! The path tracer's error against time, for `cargo xtask converge`'s
//! comparison at equal time (issue 15): each scene rendered with Mitsuba 3
//! as its reference was (variant, integrator, filter and light radius from
//! the reference's sidecar, [`crate::reference::export_like`]) at several
//! sample counts, with a seed no reference pass uses, on the same machine in
//! the same run as our renders.
//!
//! A render at N samples per pixel, independent of the reference's N_ref,
//! has the expected relMSE against the reference c (1/N + 1/N_ref): its own
//! variance and the reference's. [`Curve`] fits c to the measured points and
//! the time to a line a + b N, interpolates the points on log–log axes, and
//! uses the fitted model only outside them (marked as extrapolated).

use std::path::Path;

use anyhow::{Context, Result, bail, ensure};
use lustre_geometry::builtin::builtin;
use lustre_geometry::mitsuba;
use lustre_image::metrics::{self, RELATIVE_MSE_EPSILON};
use lustre_image::read_exr;

use crate::converge::Reference;
use crate::reference::{ensure_venv, export_like, path_str, run_helper};

/// The seed of the path tracer's renders: far above the seeds of a
/// reference's passes (0, 1, … one per pass), so no render shares samples with it.
pub const SEED: u32 = 1_000_000;

/// One path-traced render set beside the reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    /// Samples per pixel.
    pub spp: u32,
    /// Seconds to load the scene and render it (Mitsuba's own timings; the
    /// Python start and `import mitsuba` are not counted, as our renders'
    /// process start is not).
    pub seconds: f64,
    /// Relative MSE against the reference.
    pub rel_mse: f64,
}

/// A value read off the curve, and whether it lies outside the measured points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// The value.
    pub value: f64,
    /// Taken from the fitted model beyond the measured points.
    pub extrapolated: bool,
}

/// The path tracer's relMSE against time on one scene.
#[derive(Debug, Clone)]
pub struct Curve {
    /// The measured renders, by sample count.
    pub points: Vec<Point>,
    /// The reference's samples per pixel.
    pub reference_spp: f64,
    /// c of relMSE = c (1/N + 1/N_ref): the relMSE of one sample per pixel against the truth.
    pub variance: f64,
    /// a of seconds = a + b N.
    pub setup_seconds: f64,
    /// b of seconds = a + b N.
    pub seconds_per_spp: f64,
}

impl Curve {
    /// Fits the model to `points` (at least two sample counts, times growing with them).
    pub fn new(mut points: Vec<Point>, reference_spp: u64) -> Result<Self> {
        points.sort_by_key(|p| p.spp);
        points.dedup_by_key(|p| p.spp);
        ensure!(
            points.len() >= 2,
            "the path tracer's curve needs at least two sample counts"
        );
        ensure!(
            points
                .iter()
                .all(|p| p.spp > 0 && p.seconds > 0.0 && p.rel_mse > 0.0 && p.rel_mse.is_finite()),
            "the path tracer's renders need positive sample counts, times and errors: {points:?}"
        );
        let reference_spp = reference_spp as f64;
        ensure!(reference_spp > 0.0, "the reference has no samples");
        // c from each point; the median resists one noisy render.
        let mut cs: Vec<f64> = points
            .iter()
            .map(|p| p.rel_mse / (1.0 / f64::from(p.spp) + 1.0 / reference_spp))
            .collect();
        cs.sort_by(f64::total_cmp);
        let variance = if cs.len() % 2 == 1 {
            cs[cs.len() / 2]
        } else {
            0.5 * (cs[cs.len() / 2 - 1] + cs[cs.len() / 2])
        };
        // Least-squares line through (N, seconds).
        let n = points.len() as f64;
        let mean_n = points.iter().map(|p| f64::from(p.spp)).sum::<f64>() / n;
        let mean_t = points.iter().map(|p| p.seconds).sum::<f64>() / n;
        let sxy: f64 = points
            .iter()
            .map(|p| (f64::from(p.spp) - mean_n) * (p.seconds - mean_t))
            .sum();
        let sxx: f64 = points
            .iter()
            .map(|p| (f64::from(p.spp) - mean_n).powi(2))
            .sum();
        let seconds_per_spp = sxy / sxx;
        ensure!(
            seconds_per_spp > 0.0,
            "the path tracer's time does not grow with its samples: {points:?}"
        );
        Ok(Self {
            points,
            reference_spp,
            variance,
            setup_seconds: mean_t - seconds_per_spp * mean_n,
            seconds_per_spp,
        })
    }

    /// The reference's own noise, c / N_ref: the relMSE every render keeps
    /// against it however close to the truth it is.
    pub fn reference_noise(&self) -> f64 {
        self.variance / self.reference_spp
    }

    /// The model's relMSE at `spp` samples per pixel.
    fn model_rel_mse(&self, spp: f64) -> f64 {
        self.variance * (1.0 / spp + 1.0 / self.reference_spp)
    }

    /// The model's samples per pixel in `seconds`; `None` before one sample is done.
    fn model_spp(&self, seconds: f64) -> Option<f64> {
        let spp = (seconds - self.setup_seconds) / self.seconds_per_spp;
        (spp >= 1.0).then_some(spp)
    }

    /// The measured segment around `x` (by `key`), as (before, after).
    fn segment(&self, x: f64, key: impl Fn(&Point) -> f64) -> Option<(&Point, &Point)> {
        self.points
            .windows(2)
            .find(|w| {
                let (a, b) = (key(&w[0]), key(&w[1]));
                (a.min(b)..=a.max(b)).contains(&x)
            })
            .map(|w| (&w[0], &w[1]))
    }

    /// The path tracer's relMSE after `seconds`; `None` before its first sample per pixel.
    pub fn rel_mse_at(&self, seconds: f64) -> Option<Estimate> {
        if let Some((a, b)) = self.segment(seconds, |p| p.seconds) {
            return Some(Estimate {
                value: log_lerp(seconds, (a.seconds, a.rel_mse), (b.seconds, b.rel_mse)),
                extrapolated: false,
            });
        }
        let spp = self.model_spp(seconds)?;
        Some(Estimate {
            value: self.model_rel_mse(spp),
            extrapolated: true,
        })
    }

    /// Seconds the path tracer takes to reach `rel_mse`; `None` when that is
    /// at or below the reference's own noise, which no render gets under.
    pub fn seconds_for(&self, rel_mse: f64) -> Option<Estimate> {
        if let Some((a, b)) = self.segment(rel_mse, |p| p.rel_mse) {
            return Some(Estimate {
                value: log_lerp(rel_mse, (a.rel_mse, a.seconds), (b.rel_mse, b.seconds)),
                extrapolated: false,
            });
        }
        let excess = rel_mse - self.reference_noise();
        if excess <= 0.0 {
            return None;
        }
        let spp = (self.variance / excess).max(1.0);
        Some(Estimate {
            value: self.setup_seconds + self.seconds_per_spp * spp,
            extrapolated: true,
        })
    }
}

/// y at `x` on the straight line through `a` and `b` on log–log axes.
fn log_lerp(x: f64, a: (f64, f64), b: (f64, f64)) -> f64 {
    let (lx, la, lb) = (x.ln(), a.0.ln(), b.0.ln());
    if (lb - la).abs() < f64::EPSILON {
        return a.1;
    }
    let t = (lx - la) / (lb - la);
    (a.1.ln() + t * (b.1.ln() - a.1.ln())).exp()
}

/// Renders `reference`'s scene with Mitsuba at each of `spps`, as the
/// reference was rendered, and measures each render against it.
pub fn measure(reference: &Reference, spps: &[u32], work: &Path) -> Result<Curve> {
    let root = crate::workspace_root();
    let python = ensure_venv(&root)?;
    let scene = builtin(&reference.scene)?;
    let reference_spp = reference.spp.with_context(|| {
        format!(
            "the reference of `{}` names no spp in its sidecar",
            reference.scene
        )
    })?;
    let mut points = Vec::new();
    // One render first, not counted: Dr.Jit compiles its kernels on the first
    // render and caches them on disk, and a user rendering a scene again finds them there.
    let warm_up = spps.iter().copied().min().unwrap_or(1);
    for (spp, counted) in std::iter::once((warm_up, false)).chain(spps.iter().map(|&s| (s, true))) {
        let (options, variant) = export_like(&reference.sidecar, spp, SEED)?;
        if (options.width, options.height) != (reference.image.width(), reference.image.height()) {
            bail!(
                "the sidecar of `{}` says {}x{} but its image is {}x{}",
                reference.scene,
                options.width,
                options.height,
                reference.image.width(),
                reference.image.height()
            );
        }
        let dir = work.join(format!("{}-{spp}", reference.scene));
        let (image, times) = render(&python, &scene, &options, &variant, &dir)
            .with_context(|| format!("path tracing `{}` at {spp} spp", reference.scene))?;
        let seconds = times.load + times.render;
        if !counted {
            continue;
        }
        let rel_mse = metrics::relative_mse(&image, &reference.image, RELATIVE_MSE_EPSILON)?;
        println!(
            "converge {:<10} path tracer {spp} spp: {seconds:.2} s, relMSE {rel_mse:.5}",
            reference.scene
        );
        points.push(Point {
            spp,
            seconds,
            rel_mse,
        });
    }
    Curve::new(points, reference_spp)
}

/// Seconds a Mitsuba render took, by its own timings (the Python start and `import mitsuba` not counted).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Times {
    /// Loading the scene.
    pub load: f64,
    /// Rendering it.
    pub render: f64,
}

/// One Mitsuba render of `scene` as `options` say (size, spp, seed, integrator), in `dir` (removed after): the image and its times.
pub fn render(
    python: &Path,
    scene: &lustre_geometry::Scene,
    options: &mitsuba::ExportOptions,
    variant: &str,
    dir: &Path,
) -> Result<(lustre_image::Image, Times)> {
    let xml = export_into(scene, options, dir)?;
    let rendered = run_exported(python, &xml, options, variant);
    let _ = std::fs::remove_dir_all(dir);
    rendered
}

/// Like [`render`] for a reference, whose time nobody reads: taken from
/// `cache` when a render of the same exported files (XML, meshes, textures),
/// variant, samples, seed, Mitsuba release and helper script is there, else
/// rendered and kept there (written atomically, so an interrupted run keeps
/// only whole images). The walkthrough's references take hours on a small
/// machine, so they outlive a run; returns the image and whether it was rendered now.
pub fn render_cached(
    python: &Path,
    scene: &lustre_geometry::Scene,
    options: &mitsuba::ExportOptions,
    variant: &str,
    dir: &Path,
    cache: &Path,
) -> Result<(lustre_image::Image, bool)> {
    let result = (|| {
        let xml = export_into(scene, options, dir)?;
        let kept = cache.join(format!("{}.exr", render_key(dir, options, variant)?));
        if kept.is_file() {
            let image = read_exr(&kept)
                .with_context(|| format!("reading the kept reference {}", kept.display()))?;
            return Ok((image, false));
        }
        let (image, _) = run_exported(python, &xml, options, variant)?;
        std::fs::create_dir_all(cache).with_context(|| format!("creating {}", cache.display()))?;
        lustre_image::write_exr(&kept, &image, lustre_image::Precision::F32)
            .with_context(|| format!("keeping the reference as {}", kept.display()))?;
        Ok((image, true))
    })();
    let _ = std::fs::remove_dir_all(dir);
    result
}

/// Exports `scene` into `dir` as `scene.xml` with its meshes and textures.
fn export_into(
    scene: &lustre_geometry::Scene,
    options: &mitsuba::ExportOptions,
    dir: &Path,
) -> Result<std::path::PathBuf> {
    let xml = dir.join("scene.xml");
    mitsuba::export(scene, &xml, options)
        .with_context(|| format!("exporting `{}` to Mitsuba", scene.name))?;
    Ok(xml)
}

/// SHA-256, in hex, of everything a render of the export in `dir` depends
/// on: every file there (relative name and bytes, in name order), the
/// variant, samples, seed, Mitsuba release and the helper script.
fn render_key(dir: &Path, options: &mitsuba::ExportOptions, variant: &str) -> Result<String> {
    use sha2::{Digest, Sha256};
    let mut files = Vec::new();
    let mut pending = vec![dir.to_path_buf()];
    while let Some(d) = pending.pop() {
        for entry in std::fs::read_dir(&d).with_context(|| format!("listing {}", d.display()))? {
            let path = entry?.path();
            if path.is_dir() {
                pending.push(path);
            } else {
                files.push(path);
            }
        }
    }
    files.sort();
    let mut hash = Sha256::new();
    let mut field = |bytes: &[u8]| {
        hash.update((bytes.len() as u64).to_le_bytes());
        hash.update(bytes);
    };
    for file in &files {
        let name = file.strip_prefix(dir).unwrap_or(file);
        field(path_str(name)?.as_bytes());
        field(&std::fs::read(file).with_context(|| format!("reading {}", file.display()))?);
    }
    field(variant.as_bytes());
    field(&options.spp.to_le_bytes());
    field(&options.seed.to_le_bytes());
    field(crate::reference::MITSUBA_VERSION.as_bytes());
    let script = crate::reference::helper_script(&crate::workspace_root());
    field(&std::fs::read(&script).with_context(|| format!("reading {}", script.display()))?);
    Ok(hash.finalize().iter().map(|b| format!("{b:02x}")).collect())
}

/// Renders the exported `xml` with the helper: the image and its times.
fn run_exported(
    python: &Path,
    xml: &Path,
    options: &mitsuba::ExportOptions,
    variant: &str,
) -> Result<(lustre_image::Image, Times)> {
    let root = crate::workspace_root();
    let exr = xml.with_file_name("render.exr");
    let spp = options.spp.to_string();
    let seed = options.seed.to_string();
    let info = run_helper(
        python,
        &root,
        &[
            "--variant",
            variant,
            "--scene",
            path_str(xml)?,
            "--out",
            path_str(&exr)?,
            "--spp",
            &spp,
            "--spp-per-pass",
            &spp,
            "--seed",
            &seed,
        ],
    )?;
    let time = |k: &str| {
        info[k]
            .as_f64()
            .with_context(|| format!("the helper reported no {k}"))
    };
    let times = Times {
        load: time("load_seconds")?,
        render: time("render_seconds")?,
    };
    Ok((read_exr(&exr)?, times))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reference_is_kept_under_what_its_render_depends_on() {
        let scratch = crate::render::Scratch::new("render-key").unwrap();
        let key = |scene: &lustre_geometry::Scene, options: &mitsuba::ExportOptions, name: &str| {
            let dir = scratch.path().join(name);
            export_into(scene, options, &dir).unwrap();
            render_key(&dir, options, "scalar_rgb").unwrap()
        };
        let scene = builtin("cornell").unwrap();
        let options = mitsuba::ExportOptions {
            width: 8,
            height: 6,
            ..Default::default()
        };
        let first = key(&scene, &options, "a");
        // The same export in another directory: the same key.
        assert_eq!(key(&scene, &options, "b"), first);
        let dir = scratch.path().join("a");
        assert_ne!(render_key(&dir, &options, "llvm_ad_rgb").unwrap(), first);
        let seed = mitsuba::ExportOptions { seed: 1, ..options };
        assert_ne!(key(&scene, &seed, "seed"), first);
        let size = mitsuba::ExportOptions {
            width: 9,
            ..options
        };
        assert_ne!(key(&scene, &size, "size"), first);
        // Another camera changes only the XML; another scene the meshes too.
        let mut moved = scene.clone();
        let mut camera = *scene.camera();
        camera.position.x += 0.01;
        moved.set_camera(camera);
        assert_ne!(key(&moved, &options, "camera"), first);
        assert_ne!(
            key(&builtin("glosbox").unwrap(), &options, "glosbox"),
            first
        );
    }

    /// Points on the exact model c (1/N + 1/N_ref), seconds a + b N.
    fn exact(c: f64, n_ref: u64, a: f64, b: f64, spps: &[u32]) -> Vec<Point> {
        spps.iter()
            .map(|&spp| Point {
                spp,
                seconds: a + b * f64::from(spp),
                rel_mse: c * (1.0 / f64::from(spp) + 1.0 / n_ref as f64),
            })
            .collect()
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-9 * b.abs().max(1e-12)
    }

    #[test]
    fn the_model_is_recovered_from_its_own_points() {
        let curve = Curve::new(exact(2.2, 4096, 0.3, 0.02, &[64, 1, 4, 16, 256]), 4096).unwrap();
        assert!(close(curve.variance, 2.2) && close(curve.setup_seconds, 0.3));
        assert!(close(curve.seconds_per_spp, 0.02));
        assert!(close(curve.reference_noise(), 2.2 / 4096.0));
        assert_eq!(curve.points[0].spp, 1);
    }

    #[test]
    fn reading_the_curve_at_a_time_and_an_error() {
        let (c, a, b) = (2.0, 0.5, 0.01);
        let curve = Curve::new(exact(c, 4096, a, b, &[1, 4, 16, 64, 256]), 4096).unwrap();
        // At a measured point: exact, not extrapolated.
        let at = curve.rel_mse_at(a + b * 16.0).unwrap();
        assert!(close(at.value, c * (1.0 / 16.0 + 1.0 / 4096.0)) && !at.extrapolated);
        // Between points: between their errors.
        let between = curve.rel_mse_at(a + b * 8.0).unwrap();
        assert!(!between.extrapolated);
        assert!(between.value < c * (1.0 / 4.0 + 1.0 / 4096.0));
        assert!(between.value > c * (1.0 / 16.0 + 1.0 / 4096.0));
        // Beyond the points: the model, marked.
        let beyond = curve.rel_mse_at(a + b * 1024.0).unwrap();
        assert!(beyond.extrapolated && close(beyond.value, c * (1.0 / 1024.0 + 1.0 / 4096.0)));
        // Before the first sample: no image yet.
        assert_eq!(curve.rel_mse_at(a), None);

        // The inverse: the time of a measured error, of a model error, and none below the reference's noise.
        let t = curve.seconds_for(c * (1.0 / 64.0 + 1.0 / 4096.0)).unwrap();
        assert!(close(t.value, a + b * 64.0) && !t.extrapolated);
        let t = curve
            .seconds_for(c * (1.0 / 2048.0 + 1.0 / 4096.0))
            .unwrap();
        assert!(t.extrapolated && close(t.value, a + b * 2048.0), "{t:?}");
        assert_eq!(curve.seconds_for(c / 4096.0), None);
        assert_eq!(curve.seconds_for(0.5 * c / 4096.0), None);
        // Reading an error's time and that time's error goes round.
        for spp in [2.0, 10.0, 100.0, 3000.0] {
            let e = c * (1.0 / spp + 1.0 / 4096.0);
            let t = curve.seconds_for(e).unwrap().value;
            let back = curve.rel_mse_at(t).unwrap().value;
            assert!((back / e - 1.0).abs() < 0.05, "{spp}: {back} vs {e}");
        }
    }

    #[test]
    fn curves_that_cannot_be_fitted_are_refused() {
        assert!(Curve::new(exact(1.0, 64, 0.1, 0.1, &[4]), 64).is_err());
        assert!(Curve::new(exact(1.0, 64, 0.1, 0.1, &[4, 4]), 64).is_err());
        assert!(Curve::new(exact(1.0, 64, 1.0, -0.001, &[1, 16]), 64).is_err());
        let mut zero = exact(1.0, 64, 0.1, 0.1, &[1, 16]);
        zero[1].rel_mse = 0.0;
        assert!(Curve::new(zero, 64).is_err());
        assert!(Curve::new(exact(1.0, 64, 0.1, 0.1, &[1, 16]), 0).is_err());
    }
}
