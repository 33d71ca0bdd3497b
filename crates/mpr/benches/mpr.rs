//! Frame times of multi-pass pipeline rendering on `bathroom` at 640×480
//! (Diefenbach & Badler 1997, section 8, table 2), on the adapter
//! `GpuContext::new(AdapterPreference::Hardware)` gives (printed).
//!
//! Configurations, each a frame of the frame graph (clear, `draw_window` of
//! every view: depth pass, specular masks and restores, emitters, direct
//! light), encode + submit + `device.poll(wait)`, with everything built
//! before timing; the indirect term (splats, diffuse textures) is left out,
//! as the paper's table 2 frames used a constant ambient term:
//!
//! - `d1-maps`: specular depth 1, the area lights as one cosine point light
//!   each with cube shadow maps;
//! - `d1-volumes`, `d2-volumes`: depth 1 or 2, shadow volumes;
//! - `d2-volumes-k4`: depth 2, shadow volumes, 4 jittered point lights per
//!   area light (soft shadows, section 4.4);
//! - table 2's configurations, specular depth 2 with virtual lights through
//!   the mirror and the door (sections 4.2, 4.3): `t2a-shadow-d2` (shadow
//!   depth 2, every specular shadow), `t2b-shadow-d2-one-bounce` (no
//!   shadows through two or more faces), `t2c-shadow-d2-no-spec-shadows`
//!   (light volumes only), `t2e-shadow-d1` (shadow depth 1). Table 2's (d),
//!   the door made a non-refracting surface, has no counterpart.
//!
//! `mpr_stained_glass`: `stained-glass` at 640×480 from its camera, direct
//! light under shadow volumes with virtual lights of depth 1, its window of
//! 16 panes drawn as one light volume with a projective texture
//! (`projective`, section 4.5), as one light volume per pane (`per-pane`,
//! section 4.2's uniform faces), or not at all (`off`).
//!
//! Criterion times at least 10 frames per configuration. Without an adapter
//! the bench prints why and measures nothing.

// criterion's macros generate undocumented public items.
#![allow(missing_docs)]

use std::time::Duration;

use criterion::{Criterion, SamplingMode, criterion_group, criterion_main};
use lustre_geometry::builtin;
use lustre_geometry::light::pivot_point_lights;
use lustre_mpr::frame::FrameInputs;
use lustre_mpr::material::GlossyModel;
use lustre_mpr::passes::direct::DirectLights;
use lustre_mpr::passes::specular::{SpecularSettings, mean_radiance};
use lustre_mpr::passes::tonemap::Tonemap;
use lustre_mpr::projective_texture::PaneLight;
use lustre_mpr::virtual_light::{SpecularShadows, VirtualLightSettings};
use lustre_mpr::{
    AdapterPreference, FrameGraph, GpuContext, MprError, RenderTargets, SceneBuffers,
};

/// Image width (the paper's bathroom was 623×942; 640×480 is `lustre render`'s default).
const WIDTH: u32 = 640;
/// Image height.
const HEIGHT: u32 = 480;

/// One configuration: specular depth, shadow volumes or maps, point lights
/// per area light, shadow recursion depth and specular shadows of the
/// virtual lights (0: none).
struct Config {
    name: &'static str,
    depth: u32,
    volumes: bool,
    light_samples: u32,
    shadow_depth: u32,
    spec_shadows: SpecularShadows,
}

const NO_VIRTUAL: (u32, SpecularShadows) = (0, SpecularShadows::All);

const CONFIGS: &[Config] = &[
    Config {
        name: "d1-maps",
        depth: 1,
        volumes: false,
        light_samples: 1,
        shadow_depth: NO_VIRTUAL.0,
        spec_shadows: NO_VIRTUAL.1,
    },
    Config {
        name: "d1-volumes",
        depth: 1,
        volumes: true,
        light_samples: 1,
        shadow_depth: NO_VIRTUAL.0,
        spec_shadows: NO_VIRTUAL.1,
    },
    Config {
        name: "d2-volumes",
        depth: 2,
        volumes: true,
        light_samples: 1,
        shadow_depth: NO_VIRTUAL.0,
        spec_shadows: NO_VIRTUAL.1,
    },
    Config {
        name: "d2-volumes-k4",
        depth: 2,
        volumes: true,
        light_samples: 4,
        shadow_depth: NO_VIRTUAL.0,
        spec_shadows: NO_VIRTUAL.1,
    },
    // Table 2: virtual lights through the mirror and the door, specular depth 2.
    Config {
        name: "t2a-shadow-d2",
        depth: 2,
        volumes: true,
        light_samples: 1,
        shadow_depth: 2,
        spec_shadows: SpecularShadows::All,
    },
    Config {
        name: "t2b-shadow-d2-one-bounce",
        depth: 2,
        volumes: true,
        light_samples: 1,
        shadow_depth: 2,
        spec_shadows: SpecularShadows::OneBounce,
    },
    Config {
        name: "t2c-shadow-d2-no-spec-shadows",
        depth: 2,
        volumes: true,
        light_samples: 1,
        shadow_depth: 2,
        spec_shadows: SpecularShadows::Off,
    },
    Config {
        name: "t2e-shadow-d1",
        depth: 2,
        volumes: true,
        light_samples: 1,
        shadow_depth: 1,
        spec_shadows: SpecularShadows::All,
    },
];

fn mpr(c: &mut Criterion) {
    let ctx = match GpuContext::new(AdapterPreference::Hardware) {
        Ok(ctx) => ctx,
        Err(e @ MprError::NoAdapter { .. }) => {
            eprintln!("mpr bench: {e}; nothing measured");
            return;
        }
        Err(e) => panic!("mpr bench: {e}"),
    };
    eprintln!("mpr bench on {}", ctx.adapter());
    let mut scene = builtin::bathroom();
    scene.set_camera(scene.camera().with_aspect(WIDTH as f32 / HEIGHT as f32));
    let targets = RenderTargets::new(&ctx, WIDTH, HEIGHT).unwrap();
    let buffers = SceneBuffers::upload(&ctx, &scene).unwrap();
    let output_view = output(&ctx);
    let camera = *scene.camera();
    let mut group = c.benchmark_group("mpr_bathroom");
    configure(&mut group);
    for config in CONFIGS {
        let hdr = targets.hdr_format();
        let mut graph = FrameGraph::new(&ctx, FORMAT)
            .unwrap()
            .with_emission(&ctx, hdr, &scene)
            .unwrap()
            .with_direct(&ctx, hdr)
            .unwrap()
            .with_specular(
                &ctx,
                hdr,
                &scene,
                SpecularSettings {
                    max_depth: config.depth,
                    limit_radiance: mean_radiance(&scene),
                    clip: None,
                },
            )
            .unwrap();
        let pass = graph.direct.as_ref().unwrap();
        let lights =
            DirectLights::jittered(&ctx, pass, &scene, GlossyModel::Exact, config.light_samples)
                .unwrap();
        if config.volumes {
            // Every jittered light pivots the volume of its area light's centre.
            let centres = pivot_point_lights(scene.lights(), config.light_samples);
            graph = graph
                .with_shadow_volumes(&ctx, hdr, &scene, &centres)
                .unwrap();
            if config.shadow_depth > 0 {
                graph = graph
                    .with_virtual_lights(
                        &ctx,
                        &scene,
                        VirtualLightSettings {
                            depth: config.shadow_depth,
                            shadows: config.spec_shadows,
                            panes: PaneLight::default(),
                        },
                    )
                    .unwrap();
            }
        } else {
            graph.update_shadows(&ctx, &buffers, &lights).unwrap();
        }
        let frame = FrameInputs {
            graph_terms: lustre_mpr::GraphTerms::ALL,
            scene: &buffers,
            camera: &camera,
            tonemap: &Tonemap::default(),
            targets: &targets,
            output: &output_view,
            splats: None,
            direct: Some(&lights),
            diffuse: None,
        };
        let views = graph.render(&ctx, &frame).unwrap();
        let volumes = graph.shadow_volumes.as_ref();
        eprintln!(
            "{}: {views} scene passes, {} direct lights, {} shadow generations per image \
             ({} shadow passes), volumes {} + {} bytes",
            config.name,
            lights.len(),
            volumes.map_or(0, |v| v.shadow_generations()),
            volumes.map_or(0, |v| v.shadow_generations() * views),
            volumes.map_or(0, |v| v.set().byte_size()),
            volumes
                .and_then(|v| v.virtual_lights())
                .map_or(0, |v| v.byte_size())
        );
        group.bench_function(config.name, |b| {
            b.iter(|| {
                graph.render(&ctx, &frame).unwrap();
                ctx.wait().unwrap();
            })
        });
    }
    group.finish();
    stained_glass(c, &ctx);
}

/// The output format of the frames.
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// A `WIDTH × HEIGHT` output view.
fn output(ctx: &GpuContext) -> wgpu::TextureView {
    let output = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("mpr-bench-output"),
        size: wgpu::Extent3d {
            width: WIDTH,
            height: HEIGHT,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    output.create_view(&Default::default())
}

/// At least 10 frames, 5 s, flat sampling.
fn configure(group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>) {
    group
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(5));
}

/// `mpr_stained_glass`: the window's light as a projective texture, per pane, or not drawn.
fn stained_glass(c: &mut Criterion, ctx: &GpuContext) {
    let mut scene = builtin::stained_glass::stained_glass();
    scene.set_camera(scene.camera().with_aspect(WIDTH as f32 / HEIGHT as f32));
    let targets = RenderTargets::new(ctx, WIDTH, HEIGHT).unwrap();
    let buffers = SceneBuffers::upload(ctx, &scene).unwrap();
    let output_view = output(ctx);
    let camera = *scene.camera();
    let mut group = c.benchmark_group("mpr_stained_glass");
    configure(&mut group);
    for (name, panes) in [
        ("projective", PaneLight::default()),
        ("per-pane", PaneLight::PerPane),
        ("off", PaneLight::Off),
    ] {
        let hdr = targets.hdr_format();
        let graph = FrameGraph::new(ctx, FORMAT)
            .unwrap()
            .with_direct(ctx, hdr)
            .unwrap();
        let lights = DirectLights::jittered(
            ctx,
            graph.direct.as_ref().unwrap(),
            &scene,
            GlossyModel::Exact,
            1,
        )
        .unwrap();
        let graph = graph
            .with_shadow_volumes(ctx, hdr, &scene, &pivot_point_lights(scene.lights(), 1))
            .unwrap()
            .with_virtual_lights(
                ctx,
                &scene,
                VirtualLightSettings {
                    panes,
                    ..VirtualLightSettings::default()
                },
            )
            .unwrap();
        let frame = FrameInputs {
            graph_terms: lustre_mpr::GraphTerms::ALL,
            scene: &buffers,
            camera: &camera,
            tonemap: &Tonemap::default(),
            targets: &targets,
            output: &output_view,
            splats: None,
            direct: Some(&lights),
            diffuse: None,
        };
        graph.render(ctx, &frame).unwrap();
        let volumes = graph.shadow_volumes.as_ref().unwrap();
        eprintln!(
            "stained-glass {name}: {} shadow generations, virtual volumes {} bytes",
            volumes.shadow_generations(),
            volumes.virtual_lights().map_or(0, |v| v.byte_size())
        );
        group.bench_function(name, |b| {
            b.iter(|| {
                graph.render(ctx, &frame).unwrap();
                ctx.wait().unwrap();
            })
        });
    }
    group.finish();
}

criterion_group!(benches, mpr);
criterion_main!(benches);
