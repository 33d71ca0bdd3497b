//! `cargo xtask reference-check`: every technique of `lustre render` on every
//! built-in scene with a path-traced reference (Mitsuba 3, 4096 spp, box
//! filter, `tests/references/<scene>.exr`), held to bounds in CI.
//!
//! Each [`Case`] renders at a small size with few photons (CI runs on two
//! cores with lavapipe), box-filters the 256 × 256 reference down to the
//! render's size, and measures the relative MSE (Rousselle et al. 2011),
//! FLIP's mean and 99th percentile, and the ratio of mean luminances. Each
//! case states its bounds with the value measured beside them; a technique
//! that gets worse fails. `--measure` renders every case and prints the
//! measured values with bounds from [`Bounds::from_measured`], ready to
//! paste into [`CASES`].

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use lustre_image::metrics::{self, RELATIVE_MSE_EPSILON, luminance};
use lustre_image::{Image, Precision, read_exr, write_exr, write_png};

use crate::golden::box_downsample_to;
use crate::render::{Lustre, NoAdapter, Scratch, gpu_required};

/// Pixels whose reference luminance exceeds this are emitters, left out of the mean luminance ratio.
const EMITTER_LUMINANCE: f64 = 1.0;

/// The exposure (stops) at which FLIP tone maps both images.
const EXPOSURE: f32 = 0.0;

/// Options of `cargo xtask reference-check`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Only the case with this name.
    #[arg(long)]
    case: Option<String>,
    /// Print the measured values and bounds derived from them as Rust, ready to paste into `CASES`, instead of checking.
    #[arg(long)]
    measure: bool,
}

impl Args {
    /// Every case, checked (what `cargo xtask ci` runs).
    pub fn all() -> Self {
        Self {
            case: None,
            measure: false,
        }
    }
}

/// The largest errors a case may have against the reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// Largest relative MSE (ε = 0.01).
    pub rel_mse: f64,
    /// Largest mean FLIP.
    pub flip_mean: f32,
    /// Largest 99th percentile of FLIP: an object rendered wrong shows here.
    pub flip_p99: f32,
    /// Smallest and largest ratio of the render's mean luminance to the reference's, emitters left out: more or less light shows here.
    pub mean_ratio: (f64, f64),
}

/// Margins of [`Bounds::from_measured`]: a re-render with the same seed on
/// lavapipe gives the same values to four digits; the margins leave room for
/// other adapters' arithmetic while 5 % more light (mean ratio +0.05) or a
/// black object covering 1 % of the image (FLIP p99 near 1, relMSE +0.01)
/// exceeds them (`bounds_catch_more_light_and_a_black_object`).
pub mod margin {
    /// relMSE may grow by this factor.
    pub const REL_MSE_FACTOR: f64 = 1.1;
    /// relMSE may also grow by this much (for cases with tiny relMSE).
    pub const REL_MSE_ABSOLUTE: f64 = 0.0005;
    /// Mean FLIP may grow by this much.
    pub const FLIP_MEAN: f32 = 0.01;
    /// FLIP p99 may grow by this much.
    pub const FLIP_P99: f32 = 0.05;
    /// The mean luminance ratio may move by this much either way.
    pub const MEAN_RATIO: f64 = 0.02;
}

impl Bounds {
    /// The bounds a case gets from its measured values and [`margin`].
    pub fn from_measured(m: &Measured) -> Self {
        Self {
            rel_mse: m.rel_mse * margin::REL_MSE_FACTOR + margin::REL_MSE_ABSOLUTE,
            flip_mean: m.flip_mean + margin::FLIP_MEAN,
            flip_p99: m.flip_p99 + margin::FLIP_P99,
            mean_ratio: (
                m.mean_ratio - margin::MEAN_RATIO,
                m.mean_ratio + margin::MEAN_RATIO,
            ),
        }
    }

    /// What exceeds the bounds, one phrase each; empty when nothing does.
    pub fn violations(&self, m: &Measured) -> Vec<String> {
        let mut out = Vec::new();
        if !(m.rel_mse <= self.rel_mse) {
            out.push(format!("relMSE {:.5} > {:.5}", m.rel_mse, self.rel_mse));
        }
        if !(m.flip_mean <= self.flip_mean) {
            out.push(format!(
                "FLIP mean {:.4} > {:.4}",
                m.flip_mean, self.flip_mean
            ));
        }
        if !(m.flip_p99 <= self.flip_p99) {
            out.push(format!("FLIP p99 {:.4} > {:.4}", m.flip_p99, self.flip_p99));
        }
        let (lo, hi) = self.mean_ratio;
        if !(m.mean_ratio >= lo && m.mean_ratio <= hi) {
            out.push(format!(
                "mean luminance ratio {:.4} outside [{lo:.4}, {hi:.4}]",
                m.mean_ratio
            ));
        }
        out
    }
}

/// One reference case: a technique on a scene, small and fast.
#[derive(Debug)]
pub struct Case {
    /// Name of the case.
    pub name: &'static str,
    /// The built-in scene, or a scene file relative to the workspace root (`tests/scenes/...`); its reference is `tests/references/<scene>.exr`, `<scene>` the file's stem for a file ([`reference_name`]).
    pub scene: &'static str,
    /// Options of `lustre render` after the scene (without `--out`).
    pub args: &'static [&'static str],
    /// Options of a `lustre trace` of the scene (without `--out`) whose file the render reads with `--photons-file`, if any.
    pub trace: Option<&'static [&'static str]>,
    /// The bounds (the measured values are in a comment beside them).
    pub bounds: Bounds,
}

/// What a render's comparison with the reference gives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measured {
    /// Relative MSE (ε = 0.01).
    pub rel_mse: f64,
    /// Mean FLIP.
    pub flip_mean: f32,
    /// 99th percentile of FLIP.
    pub flip_p99: f32,
    /// The render's mean luminance over the reference's, over the pixels that are not emitters in the reference.
    pub mean_ratio: f64,
}

/// Compares `render` with `reference`, box-filtering the reference down to the render's size when it is larger.
pub fn measure(render: &Image, reference: &Image) -> Result<Measured> {
    let reference = if render.width() == reference.width() && render.height() == reference.height()
    {
        reference.clone()
    } else {
        box_downsample_to(reference, render.width(), render.height()).with_context(|| {
            format!(
                "the render is {}x{}, which does not divide the {}x{} reference",
                render.width(),
                render.height(),
                reference.width(),
                reference.height()
            )
        })?
    };
    let flip = metrics::flip(render, &reference, EXPOSURE)?;
    // Emitters (reference luminance above 1, white at exposure 0) are left
    // out: the light's few pixels carry a large share of the mean, so a
    // change in the light reflected by the scene would hide behind them.
    let lit: Vec<usize> = (0..reference.pixels().len())
        .filter(|&i| luminance(reference.pixels()[i]) <= EMITTER_LUMINANCE)
        .collect();
    let mean_y = |image: &Image| {
        lit.iter()
            .map(|&i| luminance(image.pixels()[i]))
            .sum::<f64>()
    };
    Ok(Measured {
        rel_mse: metrics::relative_mse(render, &reference, RELATIVE_MSE_EPSILON)?,
        flip_mean: flip.mean,
        flip_p99: flip.p99,
        mean_ratio: mean_y(render) / mean_y(&reference),
    })
}

/// Shorthand for the cases' bounds.
const fn bounds(rel_mse: f64, flip_mean: f32, flip_p99: f32, ratio: (f64, f64)) -> Bounds {
    Bounds {
        rel_mse,
        flip_mean,
        flip_p99,
        mean_ratio: ratio,
    }
}

/// The options shared by every case: 128 × 128 (the reference box-filtered 2 × 2), seed 1.
macro_rules! small {
    ($($arg:literal),*) => {
        &["--size", "128x128", "--seed", "1", $($arg),*]
    };
}

/// The reference cases; the bounds come from `cargo xtask reference-check
/// --measure` (measured on lavapipe, llvmpipe Mesa 22.3.6, 2 cores, with
/// the default soft shadows, antialiasing and glossy-surface support; the
/// times are wall-clock on a shared machine). Leaving the emitters out, the
/// techniques reflect 0.95–1.04 of the reference's light at these small
/// sizes and photon counts. The `mpr` cases on `mirrors` and `bathroom`
/// carry errors the technique does not yet remove: mirrors beyond
/// `--spec-depth` show the limit radiance instead of further images, and
/// `bathroom` reflects 0.93 of the reference's light. Its glass door lets
/// the light through as a virtual light (section 4.2; before it, the door's
/// opaque shadow volume left the shower dark: relMSE 0.046). The
/// `photon-file` case reads `glosbox-splat-direct`'s photons from a file
/// traced by `lustre trace`, in batches: the 21-byte records' quantisation
/// moves relMSE from 0.00449 to 0.00448. `glosbox-composed` is the default
/// composition of every technique (`L = direct + k_d D + k_s (M * K) R +
/// caustics`): its frame is the one `--technique beams` draws (the same
/// image, so `beams` has no case of its own here), the glossy faces as
/// glossy images and the gold
/// box's reflections as glossy beams from the area light's centre (Duvenhage
/// et al. 2010, section 4.2) with the scatter Gaussian integrated over each
/// domain; `glosbox-beams-facets` draws them with the paper's planar facets clamped to
/// one, which put a bright glossy patch on the ceiling above the box that
/// the reference lacks (2.5 times the beams' light in the frame of
/// `crates/mpr/tests/beams.rs`). `cardioid-beams` holds the cardioid
/// caustic to a reference path-traced with the point light as a 2 cm sphere
/// of equal power (no path tracer finds a point light through a mirror):
/// FLIP is high from the reference's own noise (caustics by path tracing
/// converge slowly even at 163,840 samples per pixel), and the beams' light
/// that leaks through the ring (no second-order shadows, the paper's
/// section 3.2) makes the frame 1.03 of the reference's; over the caustic
/// and the ring's inner floor the 256² render is within 0.2 % and 1.3 % of
/// it (BENCHMARKS.md). `stained-glass-mpr` draws the light through the
/// window's 16 panes as one virtual light modulated by the window's
/// projective texture (Diefenbach & Badler 1997, section 4.5), against a
/// reference light-traced from the exact point light (Mitsuba's `ptracer`,
/// 262,144 spp, about 1.7 % noise per pixel on the floor); left to the
/// splats (`--pane-light off`) the same 256² render has 146 times its
/// relMSE (BENCHMARKS.md). `glosbox-ibr` draws the floor and the gold box's
/// faces from radiance maps (Bastos et al. 1999) captured at 45° and 48²
/// (the defaults, 30° and 96², take 48 s here); [`RANKINGS`] holds its
/// floor to less error than `glosbox-splat-direct`'s. `glosbox-ibr-geometry`
/// draws the same shading from geometry-based reflected images (the
/// paper's comparison), no maps captured. `cornell-splat-direct-point-light`
/// traces its photons from the cosine point light that replaces the area
/// light (section 3, `--light-samples 1`), which sits on the emitter: before
/// its photons left the emitter's plane they hit it at t = 0, and the frame
/// had relMSE 0.106 and a mean ratio of 0.794. The `textured-cornell` cases
/// render the scene file `tests/scenes/textured-cornell/` (checker `map_Kd`
/// maps); `textured-cornell-splat-only` splats every surface
/// (`--diffuse splat`), the splats reading the map where they land: read at
/// each photon instead, the checker blurred over the kernel support (256²
/// relMSE 0.0101 against 0.0040). `textured-cornell-detp` draws the maps in
/// the Gouraud pass per pixel; before it read none (relMSE 0.296, mean
/// ratio 2.39: every textured wall at its untextured `Kd`).
pub const CASES: &[Case] = &[
    // CASES-START (generated by `cargo xtask reference-check --measure`)
    // measured: relMSE 0.00146, FLIP mean 0.0515, p99 0.1679, mean ratio 0.9941 (0.6 s)
    Case {
        name: "cornell-splat",
        scene: "cornell",
        args: small!("--technique", "splat", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00210, 0.0615, 0.2179, (0.9741, 1.0141)),
    },
    // measured: relMSE 0.00108, FLIP mean 0.0457, p99 0.1528, mean ratio 0.9938 (1.0 s)
    Case {
        name: "cornell-splat-direct",
        scene: "cornell",
        args: small!("--technique", "splat-direct", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00169, 0.0557, 0.2028, (0.9738, 1.0138)),
    },
    // measured: relMSE 0.00119, FLIP mean 0.0174, p99 0.1067, mean ratio 0.9983 (0.7 s)
    Case {
        name: "textured-cornell-splat-direct",
        scene: "tests/scenes/textured-cornell/textured-cornell.obj",
        args: small!("--technique", "splat-direct", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00181, 0.0274, 0.1567, (0.9783, 1.0183)),
    },
    // measured: relMSE 0.00562, FLIP mean 0.0527, p99 0.2900, mean ratio 0.9952 (0.7 s)
    Case {
        name: "textured-cornell-splat-only",
        scene: "tests/scenes/textured-cornell/textured-cornell.obj",
        args: small!(
            "--technique",
            "splat",
            "--diffuse",
            "splat",
            "--photons",
            "200000"
        ),
        trace: None,
        bounds: bounds(0.00668, 0.0627, 0.3400, (0.9752, 1.0152)),
    },
    // measured: relMSE 0.00198, FLIP mean 0.0533, p99 0.2029, mean ratio 0.9939 (1.0 s)
    Case {
        name: "cornell-splat-direct-point-light",
        scene: "cornell",
        args: small!(
            "--technique",
            "splat-direct",
            "--photons",
            "200000",
            "--light-samples",
            "1"
        ),
        trace: None,
        bounds: bounds(0.00268, 0.0633, 0.2529, (0.9739, 1.0139)),
    },
    // measured: relMSE 0.00218, FLIP mean 0.0631, p99 0.1692, mean ratio 0.9988 (0.9 s)
    Case {
        name: "cornell-detp",
        scene: "cornell",
        args: small!("--technique", "detp", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00290, 0.0732, 0.2191, (0.9786, 1.0186)),
    },
    // measured: relMSE 0.00164, FLIP mean 0.0283, p99 0.1385, mean ratio 0.9888 (0.6 s)
    Case {
        name: "textured-cornell-detp",
        scene: "tests/scenes/textured-cornell/textured-cornell.obj",
        args: small!("--technique", "detp", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00231, 0.0383, 0.1885, (0.9688, 1.0088)),
    },
    // measured: relMSE 0.00187, FLIP mean 0.0597, p99 0.1610, mean ratio 0.9974 (0.5 s)
    Case {
        name: "cornell-impact",
        scene: "cornell",
        args: small!("--technique", "impact", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00255, 0.0697, 0.2110, (0.9774, 1.0174)),
    },
    // measured: relMSE 0.00226, FLIP mean 0.0617, p99 0.2016, mean ratio 1.0058 (0.9 s)
    Case {
        name: "cornell-photonmap",
        scene: "cornell",
        args: small!("--technique", "photonmap", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00298, 0.0717, 0.2516, (0.9858, 1.0258)),
    },
    // measured: relMSE 0.00481, FLIP mean 0.0689, p99 0.3105, mean ratio 0.9962 (5.5 s)
    Case {
        name: "glosbox-splat",
        scene: "glosbox",
        args: small!("--technique", "splat", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00580, 0.0789, 0.3605, (0.9762, 1.0162)),
    },
    // measured: relMSE 0.00449, FLIP mean 0.0652, p99 0.3127, mean ratio 0.9968 (4.5 s)
    Case {
        name: "glosbox-splat-direct",
        scene: "glosbox",
        args: small!("--technique", "splat-direct", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00544, 0.0752, 0.3627, (0.9768, 1.0168)),
    },
    // measured: relMSE 0.00531, FLIP mean 0.0793, p99 0.3184, mean ratio 1.0006 (3.3 s)
    Case {
        name: "glosbox-detp",
        scene: "glosbox",
        args: small!("--technique", "detp", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00640, 0.0894, 0.3692, (0.9803, 1.0203)),
    },
    // measured: relMSE 0.01336, FLIP mean 0.0843, p99 0.4129, mean ratio 0.9997 (0.5 s)
    Case {
        name: "glosbox-impact",
        scene: "glosbox",
        args: small!("--technique", "impact", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.01520, 0.0943, 0.4629, (0.9797, 1.0197)),
    },
    // measured: relMSE 0.00810, FLIP mean 0.0816, p99 0.3632, mean ratio 1.0068 (1.1 s)
    Case {
        name: "glosbox-photonmap",
        scene: "glosbox",
        args: small!("--technique", "photonmap", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00941, 0.0916, 0.4132, (0.9868, 1.0268)),
    },
    // measured: relMSE 0.00109, FLIP mean 0.0457, p99 0.1506, mean ratio 0.9946 (1.0 s)
    Case {
        name: "cornell-mpr",
        scene: "cornell",
        args: small!("--technique", "mpr", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00170, 0.0557, 0.2006, (0.9746, 1.0146)),
    },
    // measured: relMSE 0.00129, FLIP mean 0.0455, p99 0.1451, mean ratio 0.9972 (12.7 s)
    Case {
        name: "glosbox-mpr",
        scene: "glosbox",
        args: small!("--technique", "mpr", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00193, 0.0556, 0.1946, (0.9786, 1.0186)),
    },
    // measured: relMSE 0.00140, FLIP mean 0.0483, p99 0.1544, mean ratio 0.9950 (20.4 s)
    Case {
        name: "glosbox-composed",
        scene: "glosbox",
        args: small!("--technique", "composed", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00204, 0.0583, 0.2044, (0.9750, 1.0150)),
    },
    // The reference's own size: at 128² no pixel showed the beams' light
    // upstream of the gold box's faces, at 256² a line of isolated pixels on
    // the green wall's top did (relMSE 0.0232 before `Beam::flux_triangle`
    // refused flux planes behind every scatterer vertex).
    // measured: relMSE 0.00194, FLIP mean 0.0542, p99 0.1898, mean ratio 0.9914 (2.4 s)
    Case {
        name: "glosbox-composed-256",
        scene: "glosbox",
        args: &[
            "--size",
            "256x256",
            "--seed",
            "1",
            "--technique",
            "composed",
            "--photons",
            "200000",
        ],
        trace: None,
        bounds: bounds(0.00264, 0.0642, 0.2398, (0.9714, 1.0114)),
    },
    // measured: relMSE 0.01090, FLIP mean 0.0872, p99 0.4479, mean ratio 1.0820 (28.8 s)
    Case {
        name: "glosbox-beams-facets",
        scene: "glosbox",
        args: small!(
            "--technique",
            "beams",
            "--glossy-volume",
            "facets",
            "--photons",
            "200000"
        ),
        trace: None,
        bounds: bounds(0.01249, 0.0972, 0.4979, (1.0620, 1.1020)),
    },
    // measured: relMSE 0.01076, FLIP mean 0.1282, p99 0.4911, mean ratio 1.0302 (5.6 s)
    Case {
        name: "cardioid-beams",
        scene: "cardioid",
        args: small!(
            "--technique",
            "beams",
            "--spec-depth",
            "1",
            "--photons",
            "200000"
        ),
        trace: None,
        bounds: bounds(0.01259, 0.1390, 0.5439, (1.0101, 1.0501)),
    },
    // measured: relMSE 0.00447, FLIP mean 0.0651, p99 0.3128, mean ratio 0.9974 (4.7 s)
    Case {
        name: "glosbox-mpr-splatted-glossy",
        scene: "glosbox",
        args: small!(
            "--technique",
            "mpr",
            "--photons",
            "200000",
            "--glossy-images",
            "0"
        ),
        trace: None,
        bounds: bounds(0.00542, 0.0751, 0.3628, (0.9774, 1.0174)),
    },
    // measured: relMSE 0.00261, FLIP mean 0.0586, p99 0.2844, mean ratio 0.9997 (14.2 s)
    Case {
        name: "glosbox-ibr",
        scene: "glosbox",
        args: small!(
            "--technique",
            "ibr",
            "--photons",
            "200000",
            "--ibr-arc-step",
            "45",
            "--ibr-map-size",
            "48"
        ),
        trace: None,
        bounds: bounds(0.00338, 0.0686, 0.3344, (0.9797, 1.0197)),
    },
    // measured: relMSE 0.00234, FLIP mean 0.0565, p99 0.2636, mean ratio 0.9914 (3.3 s)
    Case {
        name: "glosbox-ibr-geometry",
        scene: "glosbox",
        args: small!(
            "--technique",
            "ibr",
            "--photons",
            "200000",
            "--ibr-reflected",
            "geometry"
        ),
        trace: None,
        bounds: bounds(0.00308, 0.0665, 0.3136, (0.9714, 1.0114)),
    },
    // measured: relMSE 0.01197, FLIP mean 0.0970, p99 0.4584, mean ratio 0.9505 (20.8 s)
    Case {
        name: "mirrors-mpr",
        scene: "mirrors",
        args: small!("--technique", "mpr", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.01366, 0.1070, 0.5084, (0.9305, 0.9705)),
    },
    // measured: relMSE 0.01771, FLIP mean 0.1032, p99 0.4174, mean ratio 0.9627 (12.9 s)
    // (0.02237 and 0.9340 before photons inside the glass met η's inverse)
    Case {
        name: "bathroom-mpr",
        scene: "bathroom",
        args: small!(
            "--technique",
            "mpr",
            "--photons",
            "200000",
            "--light-samples",
            "4",
            "--aa",
            "2",
            "--spec-depth",
            "1"
        ),
        trace: None,
        bounds: bounds(0.01998, 0.1132, 0.4674, (0.9427, 0.9827)),
    },
    // measured: relMSE 0.00011, FLIP mean 0.0243, p99 0.1075, mean ratio 1.0057 (0.6 s)
    Case {
        name: "stained-glass-mpr",
        scene: "stained-glass",
        args: small!("--technique", "mpr", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00062, 0.0343, 0.1575, (0.9857, 1.0257)),
    },
    // measured: relMSE 0.00448, FLIP mean 0.0652, p99 0.3130, mean ratio 0.9969 (6.6 s)
    Case {
        name: "glosbox-splat-direct-photon-file",
        scene: "glosbox",
        args: &[
            "--size",
            "128x128",
            "--technique",
            "splat-direct",
            "--batch-records",
            "100000",
        ],
        trace: Some(&["--photons", "200000", "--seed", "1"]),
        bounds: bounds(0.00542, 0.0752, 0.3630, (0.9769, 1.0169)),
    },
    // measured: relMSE 0.00520, FLIP mean 0.0313, p99 0.2637, mean ratio 1.0051 (30.6 s)
    // The wavy water as one interface at its mean level (before: no view
    // through it, relMSE 0.103 at 256²), photons inside it totally
    // reflected (before: relMSE 0.0106, mean ratio 0.817).
    Case {
        name: "pool-composed",
        scene: "pool",
        args: small!("--photons", "200000"),
        trace: None,
        bounds: bounds(0.00622, 0.0413, 0.3137, (0.9851, 1.0251)),
    },
    // measured: relMSE 0.00685, FLIP mean 0.0338, p99 0.3164, mean ratio 1.0188 (29.9 s)
    // No virtual light through the wavy water (its photons' splats keep the
    // caustic): with one through its mean plane, relMSE 0.062.
    Case {
        name: "pool-mpr",
        scene: "pool",
        args: small!("--technique", "mpr", "--photons", "200000"),
        trace: None,
        bounds: bounds(0.00804, 0.0438, 0.3664, (0.9988, 1.0388)),
    },
    // CASES-END
];

/// Pairs of cases whose first must have less relative MSE than the second
/// over the pixels that see only the named mesh (both rendered in the same
/// run): radiance maps (Bastos et al. 1999; issue 12) and the composed
/// frame's glossy images draw glosbox's glossy floor better than its splats.
pub const RANKINGS: &[(&str, &str, &str)] = &[
    ("glosbox-ibr", "glosbox-splat-direct", "floor"),
    ("glosbox-composed", "glosbox-splat-direct", "floor"),
];

/// The cases to run: all, or the one named.
fn select(name: Option<&str>) -> Result<Vec<&'static Case>> {
    crate::select_case(CASES, name, |c| c.name, "reference")
}

/// One case's outcome.
enum Outcome {
    /// Rendered (the image) and measured in `seconds`.
    Measured(Measured, f64, Image),
    /// No adapter, and none required.
    Skipped(String),
}

/// Whether a case's scene is a file (it has an extension or a folder) rather than a built-in's name.
fn is_scene_file(scene: &str) -> bool {
    scene.contains('/') || Path::new(scene).extension().is_some()
}

/// The name of a case's reference in `tests/references/`: the built-in scene's name, or the scene file's stem.
pub fn reference_name(scene: &str) -> &str {
    if is_scene_file(scene) {
        Path::new(scene)
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or(scene)
    } else {
        scene
    }
}

/// The scene argument of `lustre` for a case: a built-in's name, or the scene file under the workspace root.
fn scene_arg(scene: &str) -> String {
    if is_scene_file(scene) {
        crate::workspace_root().join(scene).display().to_string()
    } else {
        scene.to_owned()
    }
}

/// Renders `case` and measures it against its reference.
fn run_case(lustre: &Lustre, case: &Case, scratch: &Path, require_gpu: bool) -> Result<Outcome> {
    let reference = crate::converge::load_reference(
        &crate::converge::references_dir(),
        reference_name(case.scene),
    )?
    .image;
    let scene = scene_arg(case.scene);
    let out = scratch.join(format!("{}.exr", case.name));
    let start = Instant::now();
    let photons = scratch.join(format!("{}.lph", case.name));
    let mut args: Vec<&str> = case.args.to_vec();
    if let Some(trace) = case.trace {
        lustre.trace(&scene, trace, &photons)?;
        let path = photons.to_str().context("non-UTF-8 scratch path")?;
        args.extend(["--photons-file", path]);
    }
    let render = match lustre.render(&scene, &args, &out) {
        Ok(render) => render,
        Err(error) => match error.downcast_ref::<NoAdapter>() {
            Some(no_adapter) if !require_gpu => {
                return Ok(Outcome::Skipped(format!(
                    "{no_adapter} (set LUSTRE_REQUIRE_GPU to make this a failure)"
                )));
            }
            _ => return Err(error),
        },
    };
    let seconds = start.elapsed().as_secs_f64();
    Ok(Outcome::Measured(
        measure(&render.image, &reference)?,
        seconds,
        render.image,
    ))
}

/// The relative MSE of `a` and of `b` against `scene`'s reference over the pixels that see only `mesh`.
fn ranked_errors(scene: &str, mesh: &str, a: &Image, b: &Image) -> Result<(f64, f64)> {
    let reference =
        crate::converge::load_reference(&crate::converge::references_dir(), scene)?.image;
    let reference = box_downsample_to(&reference, a.width(), a.height())
        .context("the render's size does not divide the reference's")?;
    let map = crate::surfaces::SurfaceMap::of_builtin(scene, a.width(), a.height())?;
    let pixels = map.pixels_of(map.mesh(mesh)?);
    let error = |image: &Image| {
        crate::surfaces::relative_mse_over(image, &reference, &pixels)
            .with_context(|| format!("no pixel sees only `{mesh}`"))
    };
    Ok((error(a)?, error(b)?))
}

/// The measured values of a case as a line.
fn shown(m: &Measured) -> String {
    format!(
        "relMSE {:.5}, FLIP mean {:.4}, p99 {:.4}, mean ratio {:.4}",
        m.rel_mse, m.flip_mean, m.flip_p99, m.mean_ratio
    )
}

/// A case as Rust, with its measured values in the comment and bounds from them.
fn case_source(case: &Case, m: &Measured, seconds: f64) -> String {
    let b = Bounds::from_measured(m);
    let small = case.args.starts_with(&["--size", "128x128", "--seed", "1"]);
    let args = case
        .args
        .iter()
        .skip(if small { 4 } else { 0 })
        .map(|a| format!("{a:?}"))
        .collect::<Vec<_>>()
        .join(", ");
    let args = if small {
        format!("small!({args})")
    } else {
        format!("&[{args}]")
    };
    let trace = case.trace.map_or("None".to_owned(), |t| {
        let t: Vec<String> = t.iter().map(|a| format!("{a:?}")).collect();
        format!("Some(&[{}])", t.join(", "))
    });
    let mut s = String::new();
    let _ = writeln!(s, "    // measured: {} ({seconds:.1} s)", shown(m));
    let _ = writeln!(s, "    Case {{");
    let _ = writeln!(s, "        name: {:?},", case.name);
    let _ = writeln!(s, "        scene: {:?},", case.scene);
    let _ = writeln!(s, "        args: {args},");
    let _ = writeln!(s, "        trace: {trace},");
    let _ = writeln!(
        s,
        "        bounds: bounds({:.5}, {:.4}, {:.4}, ({:.4}, {:.4})),",
        b.rel_mse, b.flip_mean, b.flip_p99, b.mean_ratio.0, b.mean_ratio.1
    );
    let _ = writeln!(s, "    }},");
    s
}

/// Runs `cargo xtask reference-check`: every case (or the one named), one
/// line each, then `reference: N passed, N failed, N skipped`; with
/// `--measure`, the cases as Rust with bounds from the measured values.
pub fn run(args: Args) -> Result<()> {
    let cases = select(args.case.as_deref())?;
    let lustre = Lustre::build_for_checks()?;
    let scratch = Scratch::new("reference-check")?;
    let require_gpu = gpu_required();
    let (mut passed, mut failed, mut skipped) = (0, 0, 0);
    let mut source = String::new();
    let mut ranked = std::collections::HashMap::new();
    for case in cases {
        let outcome = run_case(&lustre, case, scratch.path(), require_gpu);
        if let Ok(Outcome::Measured(_, _, image)) = &outcome
            && RANKINGS
                .iter()
                .any(|&(a, b, _)| a == case.name || b == case.name)
        {
            ranked.insert(case.name, (case.scene, image.clone()));
        }
        match outcome {
            Ok(Outcome::Measured(m, seconds, _)) if args.measure => {
                println!("reference {:<28} {} ({seconds:.1} s)", case.name, shown(&m));
                source.push_str(&case_source(case, &m, seconds));
                passed += 1;
            }
            Ok(Outcome::Measured(m, seconds, _)) => {
                let violations = case.bounds.violations(&m);
                if violations.is_empty() {
                    println!(
                        "reference {:<28} pass  {} ({seconds:.1} s)",
                        case.name,
                        shown(&m)
                    );
                    passed += 1;
                } else {
                    let kept = keep_failure(scratch.path(), case)?;
                    println!(
                        "reference {:<28} FAIL  {} ({seconds:.1} s); wrote {kept}",
                        case.name,
                        violations.join(", ")
                    );
                    failed += 1;
                }
            }
            Ok(Outcome::Skipped(reason)) => {
                println!("reference {:<28} skip  {reason}", case.name);
                skipped += 1;
            }
            Err(error) => {
                println!("reference {:<28} FAIL  {error:#}", case.name);
                failed += 1;
            }
        }
    }
    for &(better, worse, mesh) in RANKINGS {
        let (Some((scene, a)), Some((_, b))) = (ranked.get(better), ranked.get(worse)) else {
            continue;
        };
        let (ea, eb) = ranked_errors(scene, mesh, a, b)?;
        let verdict = if ea < eb { "pass" } else { "FAIL" };
        println!(
            "reference {verdict} {better} {ea:.5} < {worse} {eb:.5}: relMSE over the pixels of `{mesh}`"
        );
        if ea < eb {
            passed += 1;
        } else {
            failed += 1;
        }
    }
    if args.measure {
        println!("\n// Paste between CASES-START and CASES-END in xtask/src/reference_check.rs:");
        print!("{source}");
    }
    println!("reference: {passed} passed, {failed} failed, {skipped} skipped");
    if failed > 0 {
        bail!("{failed} reference case(s) failed");
    }
    Ok(())
}

/// Copies a failing render out of the scratch directory to
/// `target/reference-check/<name>.exr` and `.png`, and says where.
fn keep_failure(scratch: &Path, case: &Case) -> Result<String> {
    let dir = crate::workspace_root()
        .join("target")
        .join("reference-check");
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let image = read_exr(scratch.join(format!("{}.exr", case.name)))?;
    let exr = dir.join(format!("{}.exr", case.name));
    write_exr(&exr, &image, Precision::F32)?;
    write_png(exr.with_extension("png"), &image, EXPOSURE)?;
    Ok(exr.with_extension("png").display().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surfaces::SurfaceMap;

    /// The glosbox reference at 128 × 128 with a deterministic ±20 %
    /// per-pixel noise: an image with a render's kind of error.
    fn noisy_render() -> (Image, Image) {
        let reference = read_exr(crate::converge::references_dir().join("glosbox.exr")).unwrap();
        let small = box_downsample_to(&reference, 128, 128).unwrap();
        let mut render = small.clone();
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for p in render.pixels_mut() {
            // xorshift64*: the same noise every run.
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            let u = (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32;
            *p = p.map(|c| c * (0.8 + 0.4 * u));
        }
        (render, reference)
    }

    #[test]
    fn bounds_catch_more_light_and_a_black_object() {
        let (render, reference) = noisy_render();
        let m = measure(&render, &reference).unwrap();
        assert!(m.rel_mse > 0.002 && m.flip_mean > 0.01, "{m:?}");
        let bounds = Bounds::from_measured(&m);
        assert!(bounds.violations(&m).is_empty());

        // 5 % more light everywhere.
        let mut brighter = render.clone();
        for p in brighter.pixels_mut() {
            *p = p.map(|c| c * 1.05);
        }
        let brighter_m = measure(&brighter, &reference).unwrap();
        eprintln!("noisy {m:?}\n5 % brighter {brighter_m:?}");
        let violations = bounds.violations(&brighter_m);
        assert!(
            violations.iter().any(|v| v.contains("mean luminance")),
            "{violations:?}"
        );

        // 5 % less light.
        let mut darker = render.clone();
        for p in darker.pixels_mut() {
            *p = p.map(|c| c * 0.95);
        }
        assert!(
            !bounds
                .violations(&measure(&darker, &reference).unwrap())
                .is_empty()
        );

        // The gold box black.
        let map = SurfaceMap::of_builtin("glosbox", 128, 128).unwrap();
        let gold = map.pixels_of(map.mesh("large-box").unwrap());
        let mut black_box = render.clone();
        for &i in &gold {
            black_box.pixels_mut()[i] = [0.0; 3];
        }
        let black_m = measure(&black_box, &reference).unwrap();
        eprintln!("gold box black {black_m:?}");
        let violations = bounds.violations(&black_m);
        assert!(
            violations.iter().any(|v| v.contains("p99"))
                && violations.iter().any(|v| v.contains("relMSE")),
            "{violations:?}"
        );

        // The small box black: 1.6 % of the pixels.
        let small_box = map.pixels_of(map.mesh("small-box").unwrap());
        assert!(small_box.len() > 128 * 128 / 100, "{}", small_box.len());
        let mut black_small = render.clone();
        for &i in &small_box {
            black_small.pixels_mut()[i] = [0.0; 3];
        }
        let small_m = measure(&black_small, &reference).unwrap();
        eprintln!("small box black ({} pixels) {small_m:?}", small_box.len());
        let violations = bounds.violations(&small_m);
        assert!(
            violations.iter().any(|v| v.contains("p99")),
            "{violations:?}"
        );
    }

    #[test]
    fn measure_downsamples_the_reference_and_refuses_other_sizes() {
        let reference = Image::filled(4, 4, [0.5; 3]).unwrap();
        let render = Image::filled(2, 2, [0.5; 3]).unwrap();
        let m = measure(&render, &reference).unwrap();
        assert_eq!(m.rel_mse, 0.0);
        assert!((m.mean_ratio - 1.0).abs() < 1e-12);
        assert!(measure(&Image::filled(3, 3, [0.5; 3]).unwrap(), &reference).is_err());
    }

    #[test]
    fn registry_covers_every_technique_on_every_referenced_scene() {
        let mut names: Vec<&str> = CASES.iter().map(|c| c.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), CASES.len(), "case names must be unique");
        for scene in ["cornell", "glosbox"] {
            for technique in ["splat", "splat-direct", "detp", "impact", "photonmap"] {
                assert!(
                    CASES.iter().any(|c| c.scene == scene
                        && c.args.windows(2).any(|w| w == ["--technique", technique])),
                    "no case renders {technique} on {scene}"
                );
            }
        }
        for case in CASES {
            let b = case.bounds;
            assert!(
                b.rel_mse > 0.0 && b.flip_mean > 0.0 && b.flip_p99 > 0.0,
                "{}",
                case.name
            );
            assert!(b.mean_ratio.0 < b.mean_ratio.1, "{}", case.name);
            assert!(!case.args.contains(&"--out"), "{}", case.name);
        }
        assert!(select(Some("nope")).is_err());
    }

    #[test]
    fn scene_files_name_their_reference_by_stem() {
        assert_eq!(reference_name("cornell"), "cornell");
        assert_eq!(
            reference_name("tests/scenes/textured-cornell/textured-cornell.obj"),
            "textured-cornell"
        );
        for case in CASES.iter().filter(|c| is_scene_file(c.scene)) {
            let path = crate::workspace_root().join(case.scene);
            assert!(
                path.is_file(),
                "{}: no scene file {}",
                case.name,
                path.display()
            );
            let reference = crate::converge::references_dir()
                .join(format!("{}.exr", reference_name(case.scene)));
            assert!(
                reference.is_file(),
                "{}: no reference {}",
                case.name,
                reference.display()
            );
        }
    }

    #[test]
    fn measured_cases_print_as_rust() {
        let m = Measured {
            rel_mse: 0.01,
            flip_mean: 0.1,
            flip_p99: 0.5,
            mean_ratio: 0.97,
        };
        let text = case_source(&CASES[0], &m, 3.25);
        assert!(
            text.contains(
                "measured: relMSE 0.01000, FLIP mean 0.1000, p99 0.5000, mean ratio 0.9700 (3.2 s)"
            ),
            "{text}"
        );
        assert!(
            text.contains("bounds(0.01150, 0.1100, 0.5500, (0.9500, 0.9900))"),
            "{text}"
        );
        assert!(!text.contains("128x128"), "{text}");
    }
}
