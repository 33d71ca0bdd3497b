//! Frame times of photon splatting on `glosbox` at 640×480 (Stürzlinger &
//! Bastos 1997, section 4, tables 1 and 2), on the adapter
//! `GpuContext::new(AdapterPreference::Hardware)` gives (printed):
//!
//! - `full-*`: the method of section 2.2, depth pre-pass plus the splats of
//!   every hit record, at 250k and 1M emitted photons;
//! - `optimised-*`: the method of section 2.2.1 on the scene with its area
//!   light as a cosine point light, depth pre-pass plus direct light with
//!   shadow maps plus the splats of hits with `bounce > 1`, with enough photons
//!   traced for about 250k and 1M such hits (a pilot trace measures the ratio);
//!
//! Per configuration: `<config>/<restriction>/frame` for both [`Restriction`]s
//! (clear, depth pre-pass, [direct light,] splats) and `<config>/splats`, the
//! splat pass alone with the surface-id restriction on the depth and ids of a
//! previous frame, whose median gives splats per second. A frame is encode +
//! submit + `device.poll(wait)`; pipelines, buffers, photon maps and shadow
//! maps (one per light pose, not per frame) are made before timing.
//! Throughput is the splat count.
//!
//! Beside criterion's results the bench writes `splat_glosbox/<config>.json`
//! for each configuration criterion's filter lets run, in criterion's output
//! directory (`$CRITERION_HOME`, else `$CARGO_TARGET_DIR/criterion`, else the
//! workspace's `target/criterion`, as criterion itself chooses): the adapter,
//! resolution, C, the photons emitted, hit records and splats, and how busy
//! the cores were (all work, and this bench's) while the configuration was
//! measured, since other work on a shared machine lengthens frames.
//! `cargo xtask bench` reads them for BENCHMARKS.md. Without an adapter the
//! bench prints why and measures nothing.
//!
//! Criterion times at least 11 frames per benchmark, and a software adapter
//! takes seconds per frame, so on a CPU adapter only the 250k configurations
//! run by default (about 20 minutes on 2 cores with llvmpipe, most of it the
//! `-c16` frames, of which only the surface-id frame is measured);
//! `LUSTRE_BENCH_SPLAT_MAX=<n>` measures the configurations of nominal size
//! up to `n` (1000000 for all) on any adapter.

// criterion's macros generate undocumented public items.
#![allow(missing_docs)]

use std::cell::Cell;
use std::path::PathBuf;
use std::time::Duration;

use criterion::{Criterion, SamplingMode, Throughput, criterion_group, criterion_main};
use lustre_geometry::{Bvh, Scene, builtin};
use lustre_mpr::frame::clear_hdr;
use lustre_mpr::material::GlossyModel;
use lustre_mpr::passes::depth::DepthPass;
use lustre_mpr::passes::direct::{DirectLights, DirectPass};
use lustre_mpr::passes::splat::{KernelFiltering, Restriction, SplatBuffers, SplatPass};
use lustre_mpr::{AdapterPreference, GpuContext, MprError, RenderTargets, SceneBuffers};
use lustre_photon::{
    BounceSelection, EmissionSampling, EstimatorOptions, Kernel, NoProgress, PhotonMap,
    SplatEstimator, Support, TraceOptions, trace_photons,
};
use serde_json::json;

/// Image size (the paper does not state its resolution; 640×480 is `lustre render`'s default).
const WIDTH: u32 = 640;
/// Image height.
const HEIGHT: u32 = 480;
/// The C of equation 3 in most configurations (`lustre render` defaults to 16, measured in the `-c16` ones; 4 keeps the software-driver frames within the bench's time).
const KERNEL_C: f32 = 4.0;
/// `lustre render`'s default C of equation 3.
const DEFAULT_KERNEL_C: f32 = 16.0;
/// Photons of the pilot trace that measures indirect hits per emitted photon.
const PILOT_PHOTONS: u64 = 50_000;
/// Criterion group name, also the folder of the configurations' JSON files.
const GROUP: &str = "splat_glosbox";

/// Which method a configuration renders.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Method {
    /// Section 2.2: every hit splatted.
    Full,
    /// Section 2.2.1: direct light by shadow maps, indirect hits splatted.
    Optimised,
}

/// One photon map to render: its name, method and nominal size.
struct Config {
    name: &'static str,
    method: Method,
    /// Emitted photons (`Full`) or the indirect hits aimed at (`Optimised`).
    nominal: u64,
    /// C of equation 3.
    kernel_c: f32,
}

impl Config {
    /// Whether only the surface-id frame is measured: the `-c16` configurations, whose frames take tens of seconds on a software adapter, skip the stencil frame and the splat pass alone.
    fn frame_only(&self) -> bool {
        self.kernel_c != KERNEL_C
    }
}

const CONFIGS: &[Config] = &[
    Config {
        name: "full-250k",
        method: Method::Full,
        nominal: 250_000,
        kernel_c: KERNEL_C,
    },
    Config {
        name: "full-1M",
        method: Method::Full,
        nominal: 1_000_000,
        kernel_c: KERNEL_C,
    },
    Config {
        name: "optimised-250k",
        method: Method::Optimised,
        nominal: 250_000,
        kernel_c: KERNEL_C,
    },
    Config {
        name: "optimised-1M",
        method: Method::Optimised,
        nominal: 1_000_000,
        kernel_c: KERNEL_C,
    },
    Config {
        name: "full-250k-c16",
        method: Method::Full,
        nominal: 250_000,
        kernel_c: DEFAULT_KERNEL_C,
    },
    Config {
        name: "optimised-250k-c16",
        method: Method::Optimised,
        nominal: 250_000,
        kernel_c: DEFAULT_KERNEL_C,
    },
];

/// Criterion's output directory, as criterion chooses it when run by cargo or `cargo xtask bench`.
fn criterion_dir() -> PathBuf {
    if let Some(home) = std::env::var_os("CRITERION_HOME") {
        return home.into();
    }
    if let Some(target) = std::env::var_os("CARGO_TARGET_DIR") {
        return PathBuf::from(target).join("criterion");
    }
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/criterion")
}

/// Traces `photons` photons as `lustre render` does (Sobol' emission, seed 1).
fn trace(scene: &Scene, bvh: &Bvh, photons: u64) -> PhotonMap {
    let options = TraceOptions {
        photons,
        seed: 1,
        emission: EmissionSampling::Sobol,
        ..TraceOptions::default()
    };
    trace_photons(scene, bvh, &options, &NoProgress).expect("glosbox traces")
}

/// The GPU state shared by every configuration of one scene variant.
struct Renderer {
    scene: Scene,
    buffers: SceneBuffers,
    depth: DepthPass,
    splat: SplatPass,
    /// Direct pass and its lights, with shadow cubes already drawn (optimised method only).
    direct: Option<(DirectPass, DirectLights)>,
    views: lustre_mpr::ViewBuffer,
    slot: lustre_mpr::ViewSlot,
}

impl Renderer {
    fn new(ctx: &GpuContext, targets: &RenderTargets, scene: Scene, method: Method) -> Self {
        let camera = *scene.camera();
        let buffers = SceneBuffers::upload(ctx, &scene).unwrap();
        let depth = DepthPass::new(ctx).unwrap();
        let splat = SplatPass::new(ctx, targets.hdr_format(), Kernel::Silverman).unwrap();
        let (views, slot) = lustre_mpr::ViewBuffer::for_camera(ctx, &camera).unwrap();
        splat.prepare(
            &ctx.queue,
            &lustre_mpr::View::from_camera(&camera),
            KernelFiltering::PixelCentre,
        );
        let direct = (method == Method::Optimised).then(|| {
            let pass = DirectPass::new(ctx, targets.hdr_format()).unwrap();
            let lights = DirectLights::new(ctx, &pass, &scene, GlossyModel::Exact).unwrap();
            // Shadow maps are per light pose: drawn once, outside the timed frames.
            let mut encoder = ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
            pass.encode_shadows(&mut encoder, &buffers, &lights);
            ctx.queue.submit([encoder.finish()]);
            (pass, lights)
        });
        Self {
            scene,
            buffers,
            depth,
            splat,
            direct,
            views,
            slot,
        }
    }

    /// One frame: clear, depth pre-pass, direct light (optimised method), splats; submitted and waited for.
    fn frame(
        &self,
        ctx: &GpuContext,
        targets: &RenderTargets,
        splats: &SplatBuffers,
        restriction: Restriction,
    ) {
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
        clear_hdr(&mut encoder, targets);
        self.depth.encode(
            &mut encoder,
            &self.buffers,
            targets,
            &self.views,
            self.slot,
            true,
        );
        if let Some((pass, lights)) = &self.direct {
            pass.encode(
                &mut encoder,
                &self.buffers,
                targets,
                lights,
                &self.views,
                self.slot,
            );
        }
        self.splat
            .encode(
                &ctx.device,
                &mut encoder,
                &self.buffers,
                splats,
                targets,
                restriction,
            )
            .unwrap();
        ctx.queue.submit([encoder.finish()]);
        ctx.device
            .poll(wgpu::PollType::wait_indefinitely())
            .unwrap();
    }

    /// The splat pass alone (stencil masks included), on the depth and surface ids already in `targets`.
    fn splats_only(
        &self,
        ctx: &GpuContext,
        targets: &RenderTargets,
        splats: &SplatBuffers,
        restriction: Restriction,
    ) {
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("splats"),
            });
        self.splat
            .encode(
                &ctx.device,
                &mut encoder,
                &self.buffers,
                splats,
                targets,
                restriction,
            )
            .unwrap();
        ctx.queue.submit([encoder.finish()]);
        ctx.device
            .poll(wgpu::PollType::wait_indefinitely())
            .unwrap();
    }
}

/// The photon map of `config` and the splats it selects: (emitted photons, hit records, splats on the GPU).
fn photon_splats(
    ctx: &GpuContext,
    renderer: &Renderer,
    config: &Config,
) -> (u64, usize, SplatBuffers) {
    let scene = &renderer.scene;
    let bvh = Bvh::build(scene);
    let (photons, selection) = match config.method {
        Method::Full => (config.nominal, BounceSelection::All),
        Method::Optimised => {
            let pilot = trace(scene, &bvh, PILOT_PHOTONS);
            let per_photon = pilot.indirect().count() as f64 / pilot.emitted() as f64;
            let photons = (config.nominal as f64 / per_photon).ceil() as u64;
            (photons, BounceSelection::Indirect)
        }
    };
    let map = trace(scene, &bvh, photons);
    let estimator = SplatEstimator::build(
        scene,
        &map,
        EstimatorOptions {
            kernel: Kernel::Silverman,
            support: Support::Scaled(config.kernel_c),
            selection,
            edges: lustre_photon::Edges::Truncated,
        },
    )
    .expect("glosbox splats build");
    let buffers = SplatBuffers::new(ctx, scene, &estimator, GlossyModel::Exact).unwrap();
    (map.emitted(), map.len(), buffers)
}

/// CPU time counters from `/proc` (Linux), in clock ticks: to tell how busy
/// the machine was with other work while a configuration was measured.
struct CpuTicks {
    /// Busy ticks of all CPUs (everything but idle and iowait).
    busy: u64,
    /// All ticks of all CPUs.
    total: u64,
    /// User and system ticks of this process (all its threads, llvmpipe's included).
    own: u64,
}

impl CpuTicks {
    /// The counters now; `None` where `/proc` cannot be read.
    fn now() -> Option<Self> {
        let stat = std::fs::read_to_string("/proc/stat").ok()?;
        let cpu: Vec<u64> = stat
            .lines()
            .next()?
            .strip_prefix("cpu ")?
            .split_whitespace()
            .filter_map(|v| v.parse().ok())
            .collect();
        let total: u64 = cpu.iter().take(8).sum();
        let idle = cpu.get(3)? + cpu.get(4)?;
        let own_stat = std::fs::read_to_string("/proc/self/stat").ok()?;
        // Fields after the command name: state is 0, utime 11, stime 12.
        let fields: Vec<&str> = own_stat
            .get(own_stat.rfind(')')? + 1..)?
            .split_whitespace()
            .collect();
        let own = fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?;
        Some(Self {
            busy: total - idle,
            total,
            own,
        })
    }

    /// (fraction of all cores busy, fraction used by this process) from `earlier` to `self`.
    fn since(&self, earlier: &Self) -> (f64, f64) {
        let total = self.total.saturating_sub(earlier.total).max(1) as f64;
        (
            self.busy.saturating_sub(earlier.busy) as f64 / total,
            self.own.saturating_sub(earlier.own) as f64 / total,
        )
    }
}

/// The largest nominal size to measure: `LUSTRE_BENCH_SPLAT_MAX`, else 250k on a software adapter and all on hardware.
fn max_nominal(ctx: &GpuContext) -> u64 {
    let default = if ctx.adapter().is_software() {
        250_000
    } else {
        u64::MAX
    };
    std::env::var("LUSTRE_BENCH_SPLAT_MAX")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(default)
}

fn splat(c: &mut Criterion) {
    let ctx = match GpuContext::new(AdapterPreference::Hardware) {
        Ok(ctx) => ctx,
        Err(e @ MprError::NoAdapter { .. }) => {
            eprintln!("SKIPPED {GROUP}: {e}");
            return;
        }
        Err(e) => panic!("{GROUP}: {e}"),
    };
    let adapter = ctx.adapter().to_string();
    println!("{GROUP}: adapter {adapter}, HDR {:?}", ctx.hdr_format());
    let targets = RenderTargets::new(&ctx, WIDTH, HEIGHT).unwrap();
    let mut glosbox = builtin("glosbox").expect("glosbox is built in");
    glosbox.set_camera(glosbox.camera().with_aspect(WIDTH as f32 / HEIGHT as f32));
    let point_lit = glosbox
        .with_area_lights_as_points()
        .expect("glosbox's light becomes a point light");
    let full = Renderer::new(&ctx, &targets, glosbox, Method::Full);
    let optimised = Renderer::new(&ctx, &targets, point_lit, Method::Optimised);
    let mut restrictions = vec![(Restriction::SurfaceId, "surface-id")];
    if full.splat.supports_stencil() {
        restrictions.push((Restriction::Stencil, "stencil"));
    } else {
        println!("{GROUP}: no stencil format on this adapter, surface-id restriction only");
    }
    let max = max_nominal(&ctx);
    if CONFIGS.iter().any(|c| c.nominal > max) {
        println!(
            "{GROUP}: configurations above {max} nominal splats left out \
             (LUSTRE_BENCH_SPLAT_MAX=1000000 measures them all)"
        );
    }
    let dir = criterion_dir().join(GROUP);

    let mut group = c.benchmark_group(GROUP);
    group
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(1))
        .measurement_time(Duration::from_secs(2));
    for config in CONFIGS.iter().filter(|c| c.nominal <= max) {
        let renderer = match config.method {
            Method::Full => &full,
            Method::Optimised => &optimised,
        };
        let (emitted, hits, splats) = photon_splats(&ctx, renderer, config);
        println!(
            "{GROUP}/{}: {emitted} photons emitted, {hits} hit records, {} splats",
            config.name, splats.count
        );
        let load_before = CpuTicks::now();
        group.throughput(Throughput::Elements(u64::from(splats.count)));
        // Whether criterion's filter let any benchmark of this configuration run.
        let ran = Cell::new(false);
        let measured: &[(Restriction, &str)] = if config.frame_only() {
            &restrictions[..1]
        } else {
            &restrictions
        };
        for &(restriction, label) in measured {
            group.bench_function(format!("{}/{label}/frame", config.name), |b| {
                ran.set(true);
                b.iter(|| renderer.frame(&ctx, &targets, &splats, restriction))
            });
        }
        if !config.frame_only() {
            let primed = Cell::new(false);
            group.bench_function(format!("{}/splats", config.name), |b| {
                ran.set(true);
                if !primed.replace(true) {
                    // The depth and ids the splat-only draw reads.
                    renderer.frame(&ctx, &targets, &splats, Restriction::SurfaceId);
                }
                b.iter(|| renderer.splats_only(&ctx, &targets, &splats, Restriction::SurfaceId))
            });
        }
        if !ran.get() {
            continue;
        }
        let load = load_before.zip(CpuTicks::now()).map(|(a, b)| b.since(&a));
        if let Some((busy, own)) = load {
            println!(
                "{GROUP}/{}: cores {:.0}% busy while measuring, {:.0}% by this bench",
                config.name,
                busy * 100.0,
                own * 100.0
            );
        }
        let setup = json!({
            "adapter": adapter,
            "software": ctx.adapter().is_software(),
            "hdr_format": format!("{:?}", ctx.hdr_format()),
            "width": WIDTH,
            "height": HEIGHT,
            "kernel_c": config.kernel_c,
            "kernel": "Silverman",
            "filtering": "PixelCentre",
            "glossy": "Exact",
            "name": config.name,
            "method": match config.method {
                Method::Full => "full",
                Method::Optimised => "optimised",
            },
            "emitted": emitted,
            "hit_records": hits,
            "splats": splats.count,
            "restrictions": measured.iter().map(|(_, label)| *label).collect::<Vec<_>>(),
            "cpu_busy": load.map(|(busy, _)| busy),
            "cpu_bench": load.map(|(_, own)| own),
        });
        let path = dir.join(format!("{}.json", config.name));
        let written = std::fs::create_dir_all(&dir)
            .and_then(|()| std::fs::write(&path, format!("{setup:#}\n")));
        if let Err(e) = written {
            eprintln!("{GROUP}: cannot write {}: {e}", path.display());
        }
    }
    group.finish();
}

criterion_group!(benches, splat);
criterion_main!(benches);
