//! Shared by the GPU tests: open a device or skip, loudly, unless `LUSTRE_REQUIRE_GPU` is set.

use lustre_mpr::{AdapterPreference, GpuContext, MprError};

/// A device for `test`, or `None` (with a printed message) when no adapter
/// exists; panics instead when `LUSTRE_REQUIRE_GPU` is set, and on any other error.
pub fn gpu_or_skip(test: &str) -> Option<GpuContext> {
    match GpuContext::new(AdapterPreference::Hardware) {
        Ok(ctx) => {
            eprintln!(
                "{test}: adapter {} (HDR {:?}, float32 blendable: {})",
                ctx.adapter(),
                ctx.hdr_format(),
                ctx.float32_blendable()
            );
            Some(ctx)
        }
        Err(e @ MprError::NoAdapter { .. }) => {
            if std::env::var_os("LUSTRE_REQUIRE_GPU").is_some() {
                panic!("{test}: LUSTRE_REQUIRE_GPU is set but {e}");
            }
            eprintln!("SKIPPED {test}: {e} (set LUSTRE_REQUIRE_GPU to make this a failure)");
            None
        }
        Err(e) => panic!("{test}: {e}"),
    }
}

/// One `size`² frame of `graph` lit by `lights` (point lights, exact
/// materials, default shadow settings; the shadow maps drawn first where the
/// graph has no shadow volumes): the HDR radiance and the surface ids. The
/// frame of the direct-light tests (shadow volumes, virtual lights).
#[allow(dead_code)]
pub fn direct_frame(
    ctx: &GpuContext,
    graph: &lustre_mpr::FrameGraph,
    scene: &lustre_geometry::Scene,
    camera: &lustre_geometry::Camera,
    lights: &[lustre_geometry::Light],
    size: u32,
) -> (Vec<[f32; 4]>, Vec<u32>) {
    use lustre_mpr::material::{GlossyModel, scene_materials};
    use lustre_mpr::passes::direct::DirectLights;
    use lustre_mpr::passes::shadow::ShadowSettings;
    let targets = lustre_mpr::RenderTargets::new(ctx, size, size).unwrap();
    let buffers = lustre_mpr::SceneBuffers::upload(ctx, scene).unwrap();
    let direct = DirectLights::with_settings(
        ctx,
        graph.direct.as_ref().unwrap(),
        lights,
        &scene_materials(scene, GlossyModel::Exact).unwrap(),
        ShadowSettings::default(),
    )
    .unwrap();
    if graph.shadow_volumes.is_none() {
        graph.update_shadows(ctx, &buffers, &direct).unwrap();
    }
    render_frame(ctx, graph, &buffers, camera, &targets, Some(&direct))
}

/// One frame of `graph` over `targets` (the tone map into a throwaway
/// texture), with `direct`'s point lights if any and nothing else: the HDR
/// radiance and the surface ids.
#[allow(dead_code)]
pub fn render_frame(
    ctx: &GpuContext,
    graph: &lustre_mpr::FrameGraph,
    buffers: &lustre_mpr::SceneBuffers,
    camera: &lustre_geometry::Camera,
    targets: &lustre_mpr::RenderTargets,
    direct: Option<&lustre_mpr::passes::direct::DirectLights>,
) -> (Vec<[f32; 4]>, Vec<u32>) {
    let output = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("test-frame-output"),
        size: wgpu::Extent3d {
            width: targets.width,
            height: targets.height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let view = output.create_view(&wgpu::TextureViewDescriptor::default());
    graph
        .render(
            ctx,
            &lustre_mpr::FrameInputs {
                graph_terms: lustre_mpr::GraphTerms::ALL,
                scene: buffers,
                camera,
                tonemap: &lustre_mpr::passes::tonemap::Tonemap::default(),
                targets,
                output: &view,
                splats: None,
                direct,
                diffuse: None,
            },
        )
        .unwrap();
    (
        lustre_mpr::readback::read_rgba_f32(ctx, &targets.hdr.texture).unwrap(),
        lustre_mpr::readback::read_u32(ctx, &targets.surface_id.texture).unwrap(),
    )
}

/// `scene` renamed `name` with a 4 × 4 diffuse map on every material, its texels all different (red grows to the right, green downwards, blue a checker), so that a flipped or transposed lookup shows.
#[allow(dead_code)]
pub fn with_asymmetric_maps(scene: lustre_geometry::Scene, name: &str) -> lustre_geometry::Scene {
    use lustre_geometry::{Rgb, Texture};
    let texels = (0..16)
        .map(|i| {
            let (x, y) = ((i % 4) as f32, (i / 4) as f32);
            Rgb::new(
                0.2 + 0.8 * x / 3.0,
                0.2 + 0.8 * y / 3.0,
                if (i % 4 + i / 4) % 2 == 0 { 1.0 } else { 0.3 },
            )
        })
        .collect();
    let map = std::sync::Arc::new(Texture::new("asymmetric", 4, 4, texels).unwrap());
    let materials = scene
        .materials()
        .iter()
        .map(|m| m.clone().with_diffuse_map(map.clone()))
        .collect();
    let mut scene = scene.with_materials(materials).unwrap();
    scene.name = name.into();
    scene
}
