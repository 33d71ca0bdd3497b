//! `lustre render --frames K` (García Hernández, Ureña & Lastra 2003, section 2): the mobile objects move along their paths over `K` frames; each frame recalculates the ray set (figure 2.2) and updates the per-vertex irradiance (equation 2.4 on static vertices, the full estimate on the mobile ones), then renders it with the Gouraud pass, writing `NAME-0000.png`, `NAME-0001.png`, ... and one JSON sidecar with every frame's times and their medians. `--timing-only` skips the GPU and the images.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use lustre_density::{Estimator, FrameStats, QuasiStatic};
use lustre_geometry::{ObjectId, Scene};
use lustre_image::Image;
use lustre_mpr::diffuse_map::DiffuseMaps;
use lustre_mpr::frame::AccumulatedSplats;
use lustre_mpr::passes::gouraud::corner_layers;
use lustre_mpr::passes::tonemap::Tonemap;
use lustre_mpr::{
    AdapterPreference, FrameGraph, FrameInputs, GpuContext, RenderTargets, SceneBuffers,
};
use serde_json::json;

use crate::gpu_frame::{OUTPUT_FORMAT, output_texture};
use crate::render::{RenderArgs, sidecar_path, write_image};
use crate::render_density::{DensityLengths, corners, tinted_at_vertices};

/// The path of frame `index` of `out`: `render.png` becomes `render-0003.png`.
pub fn frame_path(out: &Path, index: usize) -> PathBuf {
    let stem = out.file_stem().and_then(|s| s.to_str()).unwrap_or("frame");
    let ext = out.extension().and_then(|s| s.to_str()).unwrap_or("png");
    out.with_file_name(format!("{stem}-{index:04}.{ext}"))
}

/// Milliseconds of a duration.
fn ms(d: std::time::Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// The median of some values (the mean of the two middle ones for an even count).
pub fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// The GPU state reused by every frame: targets, the frame graph with the emission and Gouraud passes, the output texture.
struct Gpu {
    ctx: GpuContext,
    targets: RenderTargets,
    graph: FrameGraph,
    /// A view of the tone-mapped output (the frame's images are read from the HDR target).
    output: wgpu::TextureView,
    /// Jittered accumulation samples per frame (`--aa`, Diefenbach & Badler section 7).
    aa: u32,
}

impl Gpu {
    fn new(args: &RenderArgs, scene: &Scene) -> anyhow::Result<Self> {
        let preference = if args.software {
            AdapterPreference::Software
        } else {
            AdapterPreference::Hardware
        };
        let ctx = GpuContext::new(preference)?;
        let (width, height) = args.size;
        eprintln!("rendering {width}x{height} on {}", ctx.adapter());
        let targets = RenderTargets::new(&ctx, width, height)?;
        let buffers = SceneBuffers::upload(&ctx, scene)?;
        let mut graph = FrameGraph::new(&ctx, OUTPUT_FORMAT)?
            .with_emission(&ctx, targets.hdr_format(), scene)?
            .with_gouraud(&ctx, targets.hdr_format(), &buffers)?;
        let maps = DiffuseMaps::upload(&ctx, scene)?;
        if maps.is_textured() {
            let tinted = tinted_at_vertices(scene, args.glossy_estimate);
            graph.set_gouraud_diffuse_maps(&ctx, &maps, &corner_layers(scene, &maps, &tinted))?;
        }
        if args.aa > 1 {
            graph = graph.with_accumulation(&ctx, targets.hdr_format())?;
        }
        let (_, output) = output_texture(&ctx, width, height);
        Ok(Self {
            ctx,
            targets,
            graph,
            output,
            aa: args.aa,
        })
    }

    /// Draws the scene's current pose with the given per-corner radiance and reads the HDR image back.
    fn frame(&self, scene: &Scene, corners: &[[f32; 3]]) -> anyhow::Result<Image> {
        // The mobile objects moved: upload the pose (the corner count is unchanged, so the Gouraud pass is kept).
        let buffers = SceneBuffers::upload(&self.ctx, scene)?;
        self.graph.set_gouraud_radiance(&self.ctx, corners)?;
        self.graph.render_accumulated(
            &self.ctx,
            &FrameInputs {
                graph_terms: lustre_mpr::GraphTerms::ALL,
                scene: &buffers,
                camera: scene.camera(),
                tonemap: &Tonemap::default(),
                targets: &self.targets,
                output: &self.output,
                splats: None,
                direct: None,
                diffuse: None,
            },
            self.aa,
            AccumulatedSplats::Once,
            &mut |_| Ok(()),
        )?;
        self.ctx
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .context("waiting for the frame")?;
        let hdr = lustre_mpr::readback::read_rgba_f32(&self.ctx, &self.targets.hdr.texture)?;
        let (width, height) = (self.targets.width, self.targets.height);
        Ok(Image::from_rgba(width, height, &hdr)?)
    }
}

/// Runs `frames` frames of the quasi-static simulation on `scene` (already meshed for per-vertex lighting) and writes the images and the sidecar.
pub fn run(
    args: &RenderArgs,
    lengths: &DensityLengths,
    scene: Scene,
    estimator: Estimator,
    frames: usize,
) -> anyhow::Result<()> {
    if frames == 0 {
        bail!("--frames 0: at least one frame is needed");
    }
    let paths = scene.mobile_objects().to_vec();
    if paths.is_empty() {
        bail!(
            "--frames: scene `{}` has no mobile object (the built-in `tree` and `cornell` have one)",
            scene.name
        );
    }
    let ids: Vec<ObjectId> = paths.iter().map(|m| m.object).collect();
    let times: Vec<Vec<f32>> = paths.iter().map(|m| m.path.frame_times(frames)).collect();
    let start = Instant::now();
    let mut sim = QuasiStatic::new(
        scene,
        &ids,
        args.density_settings(lengths).options(estimator),
    )
    .map_err(crate::render_density::explain_too_many_rays)
    .with_context(|| format!("{} first frame", estimator.name()))?;
    let setup_ms = ms(start.elapsed());
    let first = sim.first_frame();
    eprintln!(
        "{}: first frame: ray set of {} segments in {:.0} ms, estimate at {} points in {:.0} ms",
        estimator.name(),
        sim.rays().segments().count(),
        ms(first.photosimulation),
        sim.points().points.len(),
        ms(first.radiosity),
    );
    let gpu = if args.timing_only {
        None
    } else {
        Some(Gpu::new(args, sim.scene())?)
    };
    let mut stats: Vec<FrameStats> = Vec::with_capacity(frames);
    let mut written = Vec::new();
    for frame in 0..frames {
        let pose: Vec<(ObjectId, glam::Affine3A)> = paths
            .iter()
            .zip(&times)
            .map(|(m, t)| (m.object, m.path.at(t[frame])))
            .collect();
        let s = sim
            .set_pose(&pose)
            .with_context(|| format!("frame {frame}"))?;
        stats.push(s);
        if let Some(gpu) = &gpu {
            let corners = corners(&sim).with_context(|| format!("frame {frame}"))?;
            let image = gpu.frame(sim.scene(), &corners)?;
            let path = frame_path(&args.out, frame);
            write_image(&path, args.exposure, &image)?;
            written.push(path.display().to_string());
        }
        eprintln!(
            "frame {frame}: photosimulation update {:.1} ms ({} paths, {} old and {} new segments), radiosity {:.1} ms",
            ms(s.photosimulation),
            s.recalculated,
            s.old_rays,
            s.new_rays,
            ms(s.radiosity)
        );
    }
    let photosimulation = median(stats.iter().map(|s| ms(s.photosimulation)).collect());
    let radiosity = median(stats.iter().map(|s| ms(s.radiosity)).collect());
    let total = median(
        stats
            .iter()
            .map(|s| ms(s.photosimulation) + ms(s.radiosity))
            .collect(),
    );
    eprintln!(
        "{frames} frames: median photosimulation update {photosimulation:.1} ms, radiosity {radiosity:.1} ms, frame {total:.1} ms ({:.1} fps without drawing)",
        1e3 / total.max(1e-9)
    );
    let info = json!({
        "scene": sim.scene().name,
        "technique": estimator.name(),
        "estimator": format!("{estimator:?}"),
        "photons": args.photons,
        "seed": args.seed,
        "frames": frames,
        "scene_size": lengths.scene_size,
        "mesh_edge": lengths.mesh_edge,
        "artifact_control": args.artifact_control,
        "glossy_radius": matches!(estimator, Estimator::Detp { .. }).then_some(lengths.glossy_radius),
        "glossy_estimate": format!("{:?}", args.glossy_estimate),
        "detp_acceleration": format!("{:?}", args.detp_acceleration),
        "pretest": format!("{:?}", args.pretest),
        "triangles": sim.scene().triangle_count(),
        "estimation_points": sim.points().points.len(),
        "ray_segments": sim.rays().segments().count(),
        "first_frame_ms": {
            "setup": setup_ms,
            "photosimulation": ms(first.photosimulation),
            "radiosity": ms(first.radiosity),
        },
        "median_ms": {
            "photosimulation_update": photosimulation,
            "radiosity": radiosity,
            "frame": total,
        },
        "per_frame": stats.iter().map(|s| json!({
            "photosimulation_update_ms": ms(s.photosimulation),
            "radiosity_ms": ms(s.radiosity),
            "recalculated_paths": s.recalculated,
            "old_segments": s.old_rays,
            "new_segments": s.new_rays,
        })).collect::<Vec<_>>(),
        "images": written,
        "adapter": gpu.as_ref().map(|g| g.ctx.adapter().to_string()),
        "size": [args.size.0, args.size.1],
        "version": env!("CARGO_PKG_VERSION"),
    });
    let sidecar = sidecar_path(&args.out);
    lustre_image::write_json_atomic(&sidecar, &info)
        .with_context(|| format!("cannot write {}", sidecar.display()))?;
    eprintln!("wrote {} images and {}", written.len(), sidecar.display());
    crate::render_density::drop_in_background(sim);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_paths_number_the_frames_beside_the_output() {
        assert_eq!(
            frame_path(Path::new("out/render.png"), 3),
            PathBuf::from("out/render-0003.png")
        );
        assert_eq!(
            frame_path(Path::new("a.exr"), 12),
            PathBuf::from("a-0012.exr")
        );
    }

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(median(vec![]), 0.0);
    }
}
