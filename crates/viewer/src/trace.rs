//! `lustre trace` and `lustre merge`: photons traced to a file on disk in bounded memory, in batches that several machines can trace, and merged (Stürzlinger & Bastos 1997, section 2.1: hits stored on disk, incremental refinement).

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use indicatif::{ProgressBar, ProgressStyle};
use lustre_geometry::{Bvh, Scene};
use lustre_photon::trace::batch_range;
use lustre_photon::{
    EmissionSampling, FileHeader, PhotonFileReader, PhotonFileWriter, PhotonTracer, Progress,
    Provenance, TraceOptions, allocate_photons, merge_photon_files, scene_fingerprint,
};

use crate::render::EmissionArg;
use crate::scene_arg;

/// How the scene's area lights emit photons.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum AreaLightsArg {
    /// From the area lights themselves, as `lustre render` does by default (`--light-samples` above 1, or `--technique splat`).
    Area,
    /// Each area light replaced by a cosine point light of equal power (section 3), as `lustre render --light-samples 1` does for splat-direct and mpr.
    Points,
}

/// Options of `lustre trace`.
#[derive(Debug, clap::Args)]
pub struct TraceArgs {
    /// A built-in scene (cornell, glosbox, tree, mirrors, bathroom, cardioid, pool, stained-glass, pyramid, house), or an OBJ or glTF 2.0 file (`.gltf`, `.glb`).
    pub scene: String,
    /// The photon file to write (or, with --append, to extend).
    #[arg(long)]
    pub out: PathBuf,
    /// Photons to emit over all lights (of the whole run with --batch; added with --append).
    #[arg(long, default_value_t = 1_000_000)]
    pub photons: u64,
    /// Seed of the photon tracer (the default is `lustre render`'s).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Photon emission sampling (the default is `lustre render`'s).
    #[arg(long, value_enum, default_value_t = EmissionArg::Sobol)]
    pub emission: EmissionArg,
    /// Largest number of hits recorded per photon (1 to 255).
    #[arg(long, default_value_t = 64)]
    pub max_bounces: u8,
    /// How area lights emit: as equivalent point lights or from their area.
    #[arg(long, value_enum, default_value_t = AreaLightsArg::Area)]
    pub area_lights: AreaLightsArg,
    /// Trace only batch I of N of the run, `I/N` with 0 <= I < N: the batches of one run merge (`lustre merge`) into the file of the whole run.
    #[arg(long, value_parser = parse_batch, conflicts_with = "append")]
    pub batch: Option<(u64, u64)>,
    /// Add --photons photons to the existing file --out, continuing its run (its own seed, emission, bounce limit and lights; incremental refinement).
    #[arg(long, conflicts_with_all = ["seed", "emission", "max_bounces", "area_lights"])]
    pub append: bool,
}

/// Parses `I/N` with `0 <= I < N`.
fn parse_batch(s: &str) -> Result<(u64, u64), String> {
    let (i, n) = s
        .split_once('/')
        .ok_or_else(|| format!("`{s}` is not I/N, e.g. 0/4"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u64>()
            .map_err(|_| format!("`{v}` is not a whole number"))
    };
    let (i, n) = (parse(i)?, parse(n)?);
    if n == 0 || i >= n {
        return Err(format!("batch {i}/{n}: need 0 <= I < N"));
    }
    Ok((i, n))
}

/// The emission sampling of an argument.
pub fn emission_of(arg: EmissionArg) -> EmissionSampling {
    match arg {
        EmissionArg::Random => EmissionSampling::Random,
        EmissionArg::Halton => EmissionSampling::Halton,
        EmissionArg::Sobol => EmissionSampling::Sobol,
    }
}

/// A progress bar over photons, on stderr.
pub struct PhotonBar(pub ProgressBar);

impl PhotonBar {
    /// A bar of `total` photons headed `what`.
    pub fn new(what: &str, total: u64) -> anyhow::Result<Self> {
        Ok(Self(
            ProgressBar::new(total).with_style(
                ProgressStyle::with_template(&format!(
                    "{what} {{bar:40}} {{pos}}/{{len}} ({{eta}} left)"
                ))
                .context("progress bar template")?,
            ),
        ))
    }
}

impl Progress for PhotonBar {
    fn begin(&self, total: u64) {
        self.0.set_length(total);
    }
    fn advance(&self, photons: u64) {
        self.0.inc(photons);
    }
    fn finish(&self) {
        self.0.finish_and_clear();
    }
}

/// The scene whose lights emit as `point_lights` says.
pub fn emitting_scene(scene: &Scene, point_lights: bool) -> anyhow::Result<Scene> {
    if point_lights {
        scene
            .with_area_lights_as_points()
            .context("cannot replace the area lights by point lights")
    } else {
        Ok(scene.clone())
    }
}

/// Runs `lustre trace`.
pub fn run(args: &TraceArgs) -> anyhow::Result<()> {
    if args.photons == 0 {
        bail!("--photons 0: at least one photon is needed");
    }
    if args.max_bounces == 0 {
        bail!("--max-bounces 0: at least one hit per photon is recorded");
    }
    let loaded = scene_arg::load(&args.scene)?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    let out = &args.out;
    let existing = if args.append {
        let reader = PhotonFileReader::open(out)
            .with_context(|| format!("--append: cannot read {}", out.display()))?;
        let Some(provenance) = reader.header().provenance else {
            bail!(
                "--append: {} does not record its seed and photon ranges; trace a new file",
                out.display()
            );
        };
        Some((reader, provenance))
    } else {
        None
    };
    let provenance = match &existing {
        Some((_, p)) => *p,
        None => Provenance {
            seed: args.seed,
            emission: emission_of(args.emission),
            max_bounces: args.max_bounces,
            point_lights: args.area_lights == AreaLightsArg::Points,
            scene: 0,
        },
    };
    let scene = emitting_scene(&loaded.scene, provenance.point_lights)?;
    let fingerprint = scene_fingerprint(&scene);
    if existing.is_some() && provenance.scene != fingerprint {
        bail!(
            "--append: {} was traced in another scene than `{}` as loaded now (its materials \
             or lights differ)",
            out.display(),
            scene.name
        );
    }
    let provenance = Provenance {
        scene: fingerprint,
        ..provenance
    };
    if scene.lights().is_empty() {
        bail!("scene `{}` has no light", scene.name);
    }
    let bvh = Bvh::build(&scene);
    let tracer = PhotonTracer::new(&scene, &bvh)
        .with_context(|| format!("cannot trace photons in `{}`", scene.name))?;
    let powers: Vec<_> = scene.lights().iter().map(|l| l.power()).collect();
    let counts = allocate_photons(&powers, args.photons);
    let (first, counts, mut writer) = match existing {
        Some((reader, _)) => {
            let header = reader.header();
            let first: Vec<u64> = header
                .first
                .iter()
                .zip(&header.lights)
                .map(|(f, l)| f + l.emitted)
                .collect();
            // The file was verified when it was opened above: not read again.
            let writer =
                PhotonFileWriter::append_from(reader, tracer.params()).with_context(|| {
                    format!(
                        "--append: {} is not a photon file of `{}` as loaded now",
                        out.display(),
                        scene.name
                    )
                })?;
            (first, counts, writer)
        }
        None => {
            let (first, counts) = match args.batch {
                Some((i, n)) => batch_range(&counts, i, n)?,
                None => (vec![0; counts.len()], counts),
            };
            let writer = PhotonFileWriter::create(
                out,
                &powers,
                first.clone(),
                tracer.params(),
                Some(provenance),
            )
            .with_context(|| format!("cannot create {}", out.display()))?;
            (first, counts, writer)
        }
    };
    let options = TraceOptions {
        photons: counts.iter().sum(),
        seed: provenance.seed,
        max_bounces: provenance.max_bounces,
        emission: provenance.emission,
    };
    let bar = PhotonBar::new("tracing photons", options.photons)?;
    tracer
        .trace_streamed(&first, &counts, &options, &bar, &mut |emitted, records| {
            writer.push(emitted, &records)
        })
        .with_context(|| format!("cannot trace photons in `{}`", scene.name))?;
    let header = writer
        .finish()
        .with_context(|| format!("cannot write {}", out.display()))?;
    let what = match (args.append, args.batch) {
        (true, _) => format!("added {} photons", options.photons),
        (false, Some((i, n))) => format!("batch {i}/{n}: {} photons", options.photons),
        (false, None) => format!("{} photons", options.photons),
    };
    eprintln!("{what}; {}", summary(out, &header));
    Ok(())
}

/// One line about a photon file: its photons, records and size.
fn summary(path: &Path, header: &FileHeader) -> String {
    format!(
        "{}: {} photons, {} hit records, {:.1} MiB",
        path.display(),
        header.emitted(),
        header.records,
        header.file_length() as f64 / (1024.0 * 1024.0)
    )
}

/// Runs `lustre merge`.
pub fn merge(inputs: &[PathBuf], out: &Path) -> anyhow::Result<()> {
    if inputs.iter().any(|p| p == out) {
        bail!(
            "--out {} is one of the inputs; write the merge to a new file",
            out.display()
        );
    }
    let header = merge_photon_files(inputs, out)
        .with_context(|| format!("cannot merge into {}", out.display()))?;
    eprintln!("merged {} files; {}", inputs.len(), summary(out, &header));
    Ok(())
}

/// Prints a photon file's header (`lustre info photons.lph`).
pub fn info(path: &Path) -> anyhow::Result<()> {
    let reader = PhotonFileReader::open(path)?;
    let h = reader.header();
    println!(
        "photon file {} (format version {})",
        path.display(),
        h.version
    );
    println!("photons     {}", h.emitted());
    println!("records     {}", h.records);
    println!("size        {} bytes", h.file_length());
    match h.provenance {
        Some(p) => println!(
            "traced      seed {}, {:?} emission, at most {} hits, {}",
            p.seed,
            p.emission,
            p.max_bounces,
            if p.point_lights {
                "area lights as point lights"
            } else {
                "area lights as areas"
            }
        ),
        None => println!("traced      unknown seed and emission"),
    }
    println!("surfaces    {}", h.surfaces.len());
    println!("lights      {}", h.lights.len());
    for (l, first) in h.lights.iter().zip(&h.first) {
        println!(
            "  power {:.4?} W, photons {}..{}",
            l.power.to_array(),
            first,
            first + l.emitted
        );
    }
    Ok(())
}
