//! `cargo xtask golden` and `cargo xtask bless`: golden-image tests of the
//! `lustre render` command (DESIGN.md, "Testing").
//!
//! Every [`Case`] renders a built-in scene through the `lustre` binary and
//! compares the render with its committed golden `tests/goldens/<name>.exr`
//! (f16) by mean LDR-FLIP at exposure 0. A failed or missing comparison
//! writes `<name>-actual.exr`, `<name>-actual.png` and
//! `<name>-difference.png` (FLIP's magma error map) beside the goldens,
//! git-ignored. A missing golden fails: only `cargo xtask bless` writes one.
//! The splatting cases pin `--splat-resolution full`, the splat pass as the
//! goldens were blessed with (the lower resolutions are tested against it
//! in `crates/mpr/tests/splat_lowres.rs`).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use lustre_image::metrics::{self, RELATIVE_MSE_EPSILON};
use lustre_image::{Image, Precision, read_exr, write_exr, write_png, write_png_srgb8};

use crate::render::{Lustre, NoAdapter, Scratch, gpu_required};

/// One golden-image test.
#[derive(Debug)]
pub struct Case {
    /// Name of the case and of its golden `tests/goldens/<name>.exr`.
    pub name: &'static str,
    /// The built-in scene rendered.
    pub scene: &'static str,
    /// Options of `lustre render` after the scene (without `--out`).
    pub args: &'static [&'static str],
    /// The case fails when the mean FLIP against the golden exceeds this.
    pub flip_mean_threshold: f32,
    /// Or when FLIP's 99th percentile exceeds this: a local error on a small object (the gold box is 9.5 % of glosbox's pixels) that the mean hides.
    pub flip_p99_threshold: f32,
    /// What set the threshold.
    pub comment: &'static str,
}

/// Why the thresholds are what they are.
const MEASURED: &str = "a re-render on lavapipe differs from its golden by mean FLIP 0.0010-0.0011 \
    (the golden's f16 rounding; the seed fixes the photon paths); 0.01 leaves room for other \
    adapters' summation order and arithmetic, while a changed estimator is far above it (5 % more \
    light on a smooth image gives 0.12)";

/// The FLIP p99 threshold of every case: a re-render on lavapipe differs
/// from its golden by p99 0.0072–0.0079 (f16 rounding), while 5 % more light on
/// the gold box alone (1,560 of 16,384 pixels) gives p99 0.067 with mean 0.0049,
/// under the mean threshold (`a_five_percent_error_on_the_gold_box_alone_fails`).
const P99: f32 = 0.03;

/// The golden-image tests.
pub const CASES: &[Case] = &[
    Case {
        name: "glosbox-splat",
        scene: "glosbox",
        args: &[
            "--splat-resolution",
            "full",
            "--technique",
            "splat",
            "--photons",
            "20000",
            "--size",
            "128x128",
            "--kernel-c",
            "16",
            "--seed",
            "1",
        ],
        flip_mean_threshold: 0.01,
        flip_p99_threshold: P99,
        comment: MEASURED,
    },
    Case {
        name: "glosbox-splat-stencil",
        scene: "glosbox",
        args: &[
            "--technique",
            "splat",
            "--photons",
            "20000",
            "--size",
            "128x128",
            "--kernel-c",
            "16",
            "--seed",
            "1",
            "--restriction",
            "stencil",
            "--diffuse",
            "splat",
        ],
        flip_mean_threshold: 0.01,
        flip_p99_threshold: P99,
        comment: MEASURED,
    },
    Case {
        name: "glosbox-splat-direct",
        scene: "glosbox",
        args: &[
            "--splat-resolution",
            "full",
            "--technique",
            "splat-direct",
            "--photons",
            "20000",
            "--size",
            "128x128",
            "--kernel-c",
            "16",
            "--seed",
            "1",
        ],
        flip_mean_threshold: 0.01,
        flip_p99_threshold: P99,
        comment: MEASURED,
    },
    Case {
        name: "cornell-splat",
        scene: "cornell",
        args: &[
            "--splat-resolution",
            "full",
            "--technique",
            "splat",
            "--photons",
            "20000",
            "--size",
            "128x128",
            "--kernel-c",
            "16",
            "--seed",
            "1",
        ],
        flip_mean_threshold: 0.01,
        flip_p99_threshold: P99,
        comment: MEASURED,
    },
    Case {
        name: "cornell-splat-paper",
        scene: "cornell",
        args: &[
            "--splat-resolution",
            "full",
            "--technique",
            "splat",
            "--photons",
            "20000",
            "--size",
            "128x128",
            "--kernel-c",
            "16",
            "--seed",
            "1",
            "--diffuse",
            "splat",
            "--edges",
            "truncated",
        ],
        flip_mean_threshold: 0.01,
        flip_p99_threshold: P99,
        comment: MEASURED,
    },
    Case {
        name: "cornell-impact",
        scene: "cornell",
        args: &[
            "--technique",
            "impact",
            "--photons",
            "20000",
            "--size",
            "128x128",
            "--seed",
            "1",
        ],
        flip_mean_threshold: 0.01,
        flip_p99_threshold: P99,
        comment: MEASURED,
    },
    Case {
        name: "cornell-detp",
        scene: "cornell",
        args: &[
            "--technique",
            "detp",
            "--artifact-control",
            "false",
            "--photons",
            "5000",
            "--radius",
            "0.1",
            "--mesh-edge",
            "0.2",
            "--size",
            "128x128",
            "--seed",
            "1",
        ],
        flip_mean_threshold: 0.01,
        flip_p99_threshold: P99,
        comment: MEASURED,
    },
    Case {
        name: "cornell-photonmap",
        scene: "cornell",
        args: &[
            "--technique",
            "photonmap",
            "--photons",
            "20000",
            "--k",
            "50",
            "--mesh-edge",
            "0.2",
            "--size",
            "128x128",
            "--seed",
            "1",
        ],
        flip_mean_threshold: 0.01,
        flip_p99_threshold: P99,
        comment: MEASURED,
    },
    Case {
        name: "glosbox-detp-quadtree",
        scene: "glosbox",
        args: &[
            "--technique",
            "detp",
            "--glossy-estimate",
            "quadtree",
            "--photons",
            "5000",
            "--radius",
            "0.1",
            "--mesh-edge",
            "0.2",
            "--size",
            "128x128",
            "--seed",
            "1",
        ],
        flip_mean_threshold: 0.01,
        flip_p99_threshold: P99,
        comment: MEASURED,
    },
    Case {
        name: "cornell-detp-artifact-control",
        scene: "cornell",
        args: &[
            "--technique",
            "detp",
            "--artifact-control",
            "--photons",
            "5000",
            "--radius",
            "0.1",
            "--mesh-edge",
            "0.2",
            "--size",
            "128x128",
            "--seed",
            "1",
        ],
        flip_mean_threshold: 0.01,
        flip_p99_threshold: P99,
        comment: MEASURED,
    },
    Case {
        name: "glosbox-splat-direct-mip",
        scene: "glosbox",
        args: &[
            "--splat-resolution",
            "full",
            "--technique",
            "splat-direct",
            "--filter",
            "mip",
            "--photons",
            "20000",
            "--size",
            "128x128",
            "--kernel-c",
            "16",
            "--seed",
            "1",
        ],
        flip_mean_threshold: 0.01,
        flip_p99_threshold: P99,
        comment: MEASURED,
    },
    // Checked against the path-traced reference before blessing: at 128²
    // and 200,000 photons relMSE 0.0014 (the reference case glosbox-composed,
    // whose default frame is this technique's). Blessed again on 2026-12-06
    // for the stored jittered shadow volumes and the beams refused upstream
    // of their scatterers: its own relMSE 0.00213 -> 0.00208 (a green-wall
    // firefly and the band along the large box's base gone, by eye).
    Case {
        name: "glosbox-beams",
        scene: "glosbox",
        args: &[
            "--technique",
            "beams",
            "--photons",
            "20000",
            "--size",
            "128x128",
            "--seed",
            "1",
        ],
        flip_mean_threshold: 0.01,
        flip_p99_threshold: P99,
        comment: MEASURED,
    },
    Case {
        name: "glosbox-splat-direct-fitted-phong",
        scene: "glosbox",
        args: &[
            "--splat-resolution",
            "full",
            "--technique",
            "splat-direct",
            "--glossy",
            "fitted-phong",
            "--photons",
            "20000",
            "--size",
            "128x128",
            "--kernel-c",
            "16",
            "--seed",
            "1",
        ],
        flip_mean_threshold: 0.01,
        flip_p99_threshold: P99,
        comment: MEASURED,
    },
];

/// The exposure (stops) at which renders are tone mapped for FLIP and PNGs.
const EXPOSURE: f32 = 0.0;

/// `tests/goldens` in the workspace.
fn goldens_dir() -> PathBuf {
    crate::workspace_root().join("tests").join("goldens")
}

/// The files of one case inside the goldens directory.
struct Files {
    /// `<name>.exr`: the golden.
    golden: PathBuf,
    /// `<name>-actual.exr`: the failing render, linear.
    actual_exr: PathBuf,
    /// `<name>-actual.png`: the failing render, tone mapped.
    actual_png: PathBuf,
    /// `<name>-difference.png`: FLIP's error map in magma.
    difference_png: PathBuf,
}

impl Files {
    fn new(dir: &Path, name: &str) -> Self {
        Self {
            golden: dir.join(format!("{name}.exr")),
            actual_exr: dir.join(format!("{name}-actual.exr")),
            actual_png: dir.join(format!("{name}-actual.png")),
            difference_png: dir.join(format!("{name}-difference.png")),
        }
    }

    /// Removes the `-actual` and `-difference` files of an earlier failure.
    fn remove_stale(&self) {
        for path in [&self.actual_exr, &self.actual_png, &self.difference_png] {
            let _ = std::fs::remove_file(path);
        }
    }

    /// Writes the render as `-actual.exr` (f32) and `-actual.png`.
    fn write_actual(&self, actual: &Image) -> Result<()> {
        write_exr(&self.actual_exr, actual, Precision::F32)?;
        write_png(&self.actual_png, actual, EXPOSURE)?;
        Ok(())
    }
}

/// The outcome of one case.
#[derive(Debug, PartialEq)]
enum Verdict {
    /// Mean FLIP and its 99th percentile at or below their thresholds.
    Pass {
        /// Mean FLIP against the golden.
        mean: f32,
        /// 99th percentile of FLIP against the golden.
        p99: f32,
    },
    /// Above the threshold, no golden, a size mismatch, or a failed render.
    Fail {
        /// Mean FLIP against the golden, when there was one to compare with.
        mean: Option<f32>,
        /// What went wrong and what was written.
        reason: String,
    },
    /// No GPU adapter and `LUSTRE_REQUIRE_GPU` unset.
    Skip {
        /// The renderer's message.
        reason: String,
    },
}

/// Compares `actual` with the golden of `case` in `dir`, writing the
/// `-actual` and `-difference` files on failure and removing stale ones on success.
fn check(case: &Case, actual: &Image, dir: &Path) -> Result<Verdict> {
    let files = Files::new(dir, case.name);
    if !files.golden.exists() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        files.remove_stale();
        files.write_actual(actual)?;
        return Ok(Verdict::Fail {
            mean: None,
            reason: format!(
                "no golden {}: check the render {} against the reference tests/references/{}.exr, \
                 then run `cargo xtask bless --case {}`",
                shown(&files.golden),
                shown(&files.actual_png),
                case.scene,
                case.name
            ),
        });
    }
    let golden = read_exr(&files.golden)?;
    if actual.check_same_size(&golden).is_err() {
        files.remove_stale();
        files.write_actual(actual)?;
        return Ok(Verdict::Fail {
            mean: None,
            reason: format!(
                "the render is {}x{} but the golden is {}x{}; wrote {}",
                actual.width(),
                actual.height(),
                golden.width(),
                golden.height(),
                shown(&files.actual_png)
            ),
        });
    }
    let flip = metrics::flip(actual, &golden, EXPOSURE)?;
    if flip.mean <= case.flip_mean_threshold && flip.p99 <= case.flip_p99_threshold {
        files.remove_stale();
        return Ok(Verdict::Pass {
            mean: flip.mean,
            p99: flip.p99,
        });
    }
    files.write_actual(actual)?;
    let difference = metrics::difference_image(&flip.error_map, flip.width, flip.height)?;
    write_png_srgb8(&files.difference_png, flip.width, flip.height, &difference)?;
    Ok(Verdict::Fail {
        mean: Some(flip.mean),
        reason: format!(
            "above a threshold (FLIP p99 {:.4} against {:.4}, p95 {:.4}, max {:.4}); wrote {}, {} and {}",
            flip.p99,
            case.flip_p99_threshold,
            flip.p95,
            flip.max,
            shown(&files.actual_exr),
            shown(&files.actual_png),
            shown(&files.difference_png)
        ),
    })
}

/// `path` relative to the workspace root when it is inside it.
fn shown(path: &Path) -> String {
    let root = crate::workspace_root();
    path.strip_prefix(&root)
        .unwrap_or(path)
        .display()
        .to_string()
}

/// Renders `case` into `scratch` and checks it against its golden in `dir`;
/// a missing adapter skips unless `require_gpu`.
fn render_and_check(
    lustre: &Lustre,
    case: &Case,
    dir: &Path,
    scratch: &Path,
    require_gpu: bool,
) -> Verdict {
    let out = scratch.join(format!("{}.exr", case.name));
    let result = lustre
        .render(case.scene, case.args, &out)
        .and_then(|render| check(case, &render.image, dir));
    match result {
        Ok(verdict) => verdict,
        Err(error) => match error.downcast_ref::<NoAdapter>() {
            Some(no_adapter) if !require_gpu => Verdict::Skip {
                reason: format!("{no_adapter} (set LUSTRE_REQUIRE_GPU to make this a failure)"),
            },
            _ => Verdict::Fail {
                mean: None,
                reason: format!("{error:#}"),
            },
        },
    }
}

/// The report of a case: one line, and the threshold's reason under a FLIP failure.
fn report_line(case: &Case, verdict: &Verdict) -> String {
    let (status, detail) = match verdict {
        Verdict::Pass { mean, p99 } => (
            "pass",
            format!(
                "mean FLIP {mean:.4} <= {:.4}, p99 {p99:.4} <= {:.4}",
                case.flip_mean_threshold, case.flip_p99_threshold
            ),
        ),
        Verdict::Fail {
            mean: Some(mean),
            reason,
        } => (
            "FAIL",
            format!(
                "mean FLIP {mean:.4} (threshold {:.4}): {reason}\n    the thresholds: {}",
                case.flip_mean_threshold, case.comment
            ),
        ),
        Verdict::Fail { mean: None, reason } => ("FAIL", reason.clone()),
        Verdict::Skip { reason } => ("skip", reason.clone()),
    };
    format!("golden {:<24} {status}  {detail}", case.name)
}

/// The cases to run: all, or the one named.
fn select(name: Option<&str>) -> Result<Vec<&'static Case>> {
    crate::select_case(CASES, name, |c| c.name, "golden")
}

/// Runs `cargo xtask golden`: every case (or the one named), one line each,
/// then a summary line `golden: N passed, N failed, N skipped`; fails if any case failed.
pub fn run(case: Option<&str>) -> Result<()> {
    let cases = select(case)?;
    let lustre = Lustre::build_for_checks()?;
    let scratch = Scratch::new("golden")?;
    let dir = goldens_dir();
    let require_gpu = gpu_required();
    let (mut passed, mut failed, mut skipped) = (0, 0, 0);
    for case in cases {
        let verdict = render_and_check(&lustre, case, &dir, scratch.path(), require_gpu);
        println!("{}", report_line(case, &verdict));
        match verdict {
            Verdict::Pass { .. } => passed += 1,
            Verdict::Fail { .. } => failed += 1,
            Verdict::Skip { .. } => skipped += 1,
        }
    }
    println!("golden: {passed} passed, {failed} failed, {skipped} skipped");
    if failed > 0 {
        bail!("{failed} golden case(s) failed");
    }
    Ok(())
}

/// Runs `cargo xtask bless`: renders every case (or the one named) and
/// writes its golden, saying what changed.
pub fn bless(case: Option<&str>) -> Result<()> {
    let cases = select(case)?;
    let lustre = Lustre::build_for_checks()?;
    let scratch = Scratch::new("bless")?;
    let dir = goldens_dir();
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    for case in cases {
        let out = scratch.path().join(format!("{}.exr", case.name));
        let render = lustre
            .render(case.scene, case.args, &out)
            .with_context(|| format!("rendering golden case `{}`", case.name))?;
        let reference = crate::converge::references_dir().join(format!("{}.exr", case.scene));
        println!(
            "{}",
            bless_case(case, &render.image, render.adapter(), &dir, &reference)?
        );
    }
    Ok(())
}

/// Writes the golden of `case` from `image` into `dir` and returns the
/// report line: size, adapter, the change against the previous golden and,
/// when `reference` has the same size, the relative MSE against it.
fn bless_case(
    case: &Case,
    image: &Image,
    adapter: &str,
    dir: &Path,
    reference: &Path,
) -> Result<String> {
    let files = Files::new(dir, case.name);
    let previous = match read_exr(&files.golden) {
        Ok(old) if old.check_same_size(image).is_ok() => format!(
            "mean FLIP {:.4} against the previous golden",
            metrics::flip(image, &old, EXPOSURE)?.mean
        ),
        Ok(old) => format!("previous golden was {}x{}", old.width(), old.height()),
        Err(_) if !files.golden.exists() => "no previous golden".to_owned(),
        Err(error) => format!("previous golden unreadable: {error}"),
    };
    write_exr(&files.golden, image, Precision::F16)?;
    files.remove_stale();
    let mut line = format!(
        "bless: wrote {} ({}x{} f16, {adapter}; {previous}",
        shown(&files.golden),
        image.width(),
        image.height()
    );
    // References are 256x256; a golden whose size divides it is compared
    // with the reference box-filtered down to its size.
    if let Some(reference) = read_exr(reference)
        .ok()
        .and_then(|r| box_downsample_to(&r, image.width(), image.height()))
    {
        let rel = metrics::relative_mse(image, &reference, RELATIVE_MSE_EPSILON)?;
        line.push_str(&format!(
            "; relMSE {rel:.5} against {} box-filtered to its size",
            shown_reference(case)
        ));
    }
    line.push(')');
    Ok(line)
}

/// `image` averaged over `k × k` blocks to `width × height`, when its sides are the same integer multiple `k` of those.
pub(crate) fn box_downsample_to(image: &Image, width: u32, height: u32) -> Option<Image> {
    let k = image.width() / width;
    if k == 0 || image.width() != k * width || image.height() != k * height {
        return None;
    }
    let mut pixels = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let mut sum = [0.0f64; 3];
            for dy in 0..k {
                for dx in 0..k {
                    let p = image.pixel(k * x + dx, k * y + dy);
                    for c in 0..3 {
                        sum[c] += f64::from(p[c]);
                    }
                }
            }
            let n = f64::from(k * k);
            pixels.push(sum.map(|v| (v / n) as f32));
        }
    }
    Image::new(width, height, pixels).ok()
}

/// `tests/references/<scene>.exr`, as shown.
fn shown_reference(case: &Case) -> String {
    format!("tests/references/{}.exr", case.scene)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::EXIT_NO_ADAPTER;
    use crate::render::tests::fake_lustre;

    /// A smooth test image.
    fn ramp(width: u32, height: u32, gain: f32) -> Image {
        let pixels = (0..height)
            .flat_map(|y| {
                (0..width).map(move |x| {
                    let (u, v) = (x as f32 / width as f32, y as f32 / height as f32);
                    [gain * u, gain * v, gain * 0.3]
                })
            })
            .collect();
        Image::new(width, height, pixels).unwrap()
    }

    fn case() -> Case {
        Case {
            name: "test-case",
            scene: "glosbox",
            args: &[],
            flip_mean_threshold: 0.05,
            flip_p99_threshold: 0.2,
            comment: "test",
        }
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn box_downsampling_averages_blocks_and_refuses_other_sizes() {
        let image = Image::new(
            4,
            2,
            vec![
                [1.0, 0.0, 0.0],
                [3.0, 0.0, 0.0],
                [5.0, 0.0, 0.0],
                [7.0, 0.0, 0.0],
                [1.0, 2.0, 0.0],
                [3.0, 2.0, 0.0],
                [5.0, 2.0, 0.0],
                [7.0, 2.0, 4.0],
            ],
        )
        .unwrap();
        let half = box_downsample_to(&image, 2, 1).unwrap();
        assert_eq!(half.pixels(), &[[2.0, 1.0, 0.0], [6.0, 1.0, 1.0]]);
        assert!(box_downsample_to(&image, 3, 1).is_none());
        assert!(box_downsample_to(&image, 2, 2).is_none());
    }

    #[test]
    fn registry_is_well_formed() {
        let mut names: Vec<&str> = CASES.iter().map(|c| c.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), CASES.len(), "case names must be unique");
        for case in CASES {
            assert!(
                lustre_geometry::builtin::BUILTIN_SCENES.contains(&case.scene),
                "{}",
                case.name
            );
            assert!(case.flip_mean_threshold > 0.0 && case.flip_mean_threshold < 1.0);
            assert!(case.flip_p99_threshold >= case.flip_mean_threshold);
            assert!(case.flip_p99_threshold < 1.0);
            assert!(!case.comment.is_empty());
            for option in ["--technique", "--photons", "--size", "--seed"] {
                assert!(case.args.contains(&option), "{} lacks {option}", case.name);
            }
            assert!(!case.args.contains(&"--out"), "{}", case.name);
        }
        assert!(select(Some("glosbox-splat")).is_ok());
        let error = select(Some("nope")).unwrap_err().to_string();
        assert!(error.contains("cornell-splat"), "{error}");
    }

    #[test]
    fn missing_golden_fails_and_writes_the_actual_render() {
        let scratch = Scratch::new("xtask-golden-missing").unwrap();
        let verdict = check(&case(), &ramp(8, 8, 1.0), scratch.path()).unwrap();
        let Verdict::Fail { mean: None, reason } = verdict else {
            panic!("{verdict:?}");
        };
        assert!(
            reason.contains("cargo xtask bless --case test-case"),
            "{reason}"
        );
        assert_eq!(
            entries(scratch.path()),
            vec!["test-case-actual.exr", "test-case-actual.png"]
        );
    }

    #[test]
    fn identical_passes_different_fails_then_passes_again() {
        let scratch = Scratch::new("xtask-golden-compare").unwrap();
        let dir = scratch.path();
        let golden = ramp(16, 16, 1.0);
        write_exr(dir.join("test-case.exr"), &golden, Precision::F16).unwrap();
        // The f16 golden against the f32 render: FLIP well under the threshold.
        let verdict = check(&case(), &golden, dir).unwrap();
        assert!(
            matches!(verdict, Verdict::Pass { mean, p99 } if mean < 0.01 && p99 < 0.03),
            "{verdict:?}"
        );
        assert_eq!(entries(dir), vec!["test-case.exr"]);

        let verdict = check(&case(), &ramp(16, 16, 3.0), dir).unwrap();
        let Verdict::Fail {
            mean: Some(mean),
            reason,
        } = &verdict
        else {
            panic!("{verdict:?}");
        };
        assert!(*mean > 0.05, "{mean}");
        assert!(reason.contains("test-case-difference.png"), "{reason}");
        assert_eq!(
            entries(dir),
            vec![
                "test-case-actual.exr",
                "test-case-actual.png",
                "test-case-difference.png",
                "test-case.exr"
            ]
        );
        assert!(report_line(&case(), &verdict).contains("FAIL"));

        // Passing again removes the stale files.
        assert!(matches!(
            check(&case(), &golden, dir).unwrap(),
            Verdict::Pass { .. }
        ));
        assert_eq!(entries(dir), vec!["test-case.exr"]);
    }

    #[test]
    fn a_five_percent_error_on_the_gold_box_alone_fails() {
        // A committed render, its golden beside it; then the same render with
        // only the gold box's pixels 5 % brighter.
        let golden_path = goldens_dir().join("glosbox-splat-direct.exr");
        let render = read_exr(&golden_path).unwrap();
        let case = CASES
            .iter()
            .find(|c| c.name == "glosbox-splat-direct")
            .unwrap();
        let scratch = Scratch::new("xtask-golden-gold-box").unwrap();
        let dir = scratch.path();
        std::fs::copy(&golden_path, dir.join(format!("{}.exr", case.name))).unwrap();
        assert!(matches!(
            check(case, &render, dir).unwrap(),
            Verdict::Pass { .. }
        ));

        let map =
            crate::surfaces::SurfaceMap::of_builtin("glosbox", render.width(), render.height())
                .unwrap();
        let gold = map.pixels_of(map.mesh("large-box").unwrap());
        let mut perturbed = render.clone();
        for &i in &gold {
            perturbed.pixels_mut()[i] = perturbed.pixels()[i].map(|c| c * 1.05);
        }
        let golden = read_exr(dir.join(format!("{}.exr", case.name))).unwrap();
        let flip = metrics::flip(&perturbed, &golden, EXPOSURE).unwrap();
        eprintln!(
            "gold box {} of {} pixels, 5 % brighter: FLIP mean {:.4}, p99 {:.4}",
            gold.len(),
            perturbed.pixels().len(),
            flip.mean,
            flip.p99
        );
        // The mean alone would let it pass; the 99th percentile does not.
        assert!(flip.mean <= case.flip_mean_threshold, "{}", flip.mean);
        assert!(flip.p99 > case.flip_p99_threshold, "{}", flip.p99);
        let verdict = check(case, &perturbed, dir).unwrap();
        assert!(matches!(verdict, Verdict::Fail { .. }), "{verdict:?}");
    }

    #[test]
    fn size_mismatch_fails() {
        let scratch = Scratch::new("xtask-golden-size").unwrap();
        let dir = scratch.path();
        write_exr(dir.join("test-case.exr"), &ramp(8, 8, 1.0), Precision::F16).unwrap();
        let verdict = check(&case(), &ramp(8, 6, 1.0), dir).unwrap();
        let Verdict::Fail { mean: None, reason } = verdict else {
            panic!("{verdict:?}");
        };
        assert!(reason.contains("8x6") && reason.contains("8x8"), "{reason}");
    }

    #[test]
    fn through_a_fake_renderer() {
        let scratch = Scratch::new("xtask-golden-fake").unwrap();
        let dir = scratch.path();
        let source = dir.join("source.exr");
        let image = ramp(12, 10, 1.0);
        write_exr(&source, &image, Precision::F32).unwrap();
        let goldens = dir.join("goldens");
        std::fs::create_dir(&goldens).unwrap();
        let lustre = fake_lustre(dir, &source, 0);

        // Bless, then check: pass.
        let reference = dir.join("reference.exr");
        write_exr(&reference, &ramp(12, 10, 1.1), Precision::F32).unwrap();
        let line = bless_case(&case(), &image, "fake adapter", &goldens, &reference).unwrap();
        assert!(
            line.contains("no previous golden") && line.contains("relMSE"),
            "{line}"
        );
        let verdict = render_and_check(&lustre, &case(), &goldens, dir, true);
        assert!(matches!(verdict, Verdict::Pass { .. }), "{verdict:?}");
        let line = bless_case(
            &case(),
            &image,
            "fake adapter",
            &goldens,
            &source.with_extension("none"),
        )
        .unwrap();
        assert!(
            line.contains("against the previous golden") && !line.contains("relMSE"),
            "{line}"
        );

        // A renderer without an adapter skips, unless a GPU is required.
        let no_gpu = fake_lustre(dir, &source, EXIT_NO_ADAPTER);
        let verdict = render_and_check(&no_gpu, &case(), &goldens, dir, false);
        assert!(matches!(verdict, Verdict::Skip { .. }), "{verdict:?}");
        let verdict = render_and_check(&no_gpu, &case(), &goldens, dir, true);
        assert!(matches!(verdict, Verdict::Fail { .. }), "{verdict:?}");

        // A crashing renderer fails with its message.
        let broken = fake_lustre(dir, &source, 1);
        let verdict = render_and_check(&broken, &case(), &goldens, dir, false);
        let Verdict::Fail { reason, .. } = verdict else {
            panic!("{verdict:?}");
        };
        assert!(reason.contains("failing with 1"), "{reason}");
    }
}
