//! The emission pass: light-source surfaces seen directly show their emitted
//! radiance `Le` (one-sided, as Mitsuba's area emitter), added into the HDR
//! target after an equal-depth redraw of the scene. CPU twin:
//! [`emission_pass_cpu`].

use glam::{DVec2, Mat4, Vec2, Vec3};
use lustre_geometry::{Bvh, Camera, Scene};
use wgpu::util::DeviceExt;

use crate::passes::redraw::{
    ScenePipeline, scene_module, scene_pipeline, weighted_additive_target,
};
use crate::scene_buffers::SceneBuffers;
use crate::shaders::with_view;
use crate::target::RenderTargets;
use crate::view::{ViewBuffer, ViewSlot};
use crate::{GpuContext, Result};

/// The emission pass's own WGSL (`src/passes/emission.wgsl`); compiled after the view block.
pub const EMISSION_WGSL: &str = include_str!("emission.wgsl");

/// The GPU emission pass for one scene's materials.
#[derive(Debug)]
pub struct EmissionPass {
    pipeline: wgpu::RenderPipeline,
    bind_group: wgpu::BindGroup,
    /// Whether any material emits (otherwise [`EmissionPass::encode`] records nothing).
    emissive: bool,
    /// The world corners of every emissive triangle ([`EmissionPass::set_emitters`]), for [`EmissionPass::screen_rect`].
    emitters: Vec<Vec3>,
}

/// The world corners of `scene`'s triangles whose material emits.
fn emitter_corners(scene: &Scene) -> Vec<Vec3> {
    let mut corners = Vec::new();
    for surface in scene.surfaces() {
        let emits = scene
            .materials()
            .get(surface.material as usize)
            .is_some_and(|m| m.is_emissive());
        if !emits {
            continue;
        }
        let positions = scene.world_positions(surface.mesh);
        let mesh = &scene.meshes()[surface.mesh as usize];
        for &t in &surface.triangles {
            corners.extend(mesh.indices[t as usize].map(|i| positions[i as usize]));
        }
    }
    corners
}

impl EmissionPass {
    /// Builds the pipeline for HDR targets of `hdr_format` with the emission of `scene`'s materials.
    pub fn new(ctx: &GpuContext, hdr_format: wgpu::TextureFormat, scene: &Scene) -> Result<Self> {
        let mut emission: Vec<[f32; 4]> = scene
            .materials()
            .iter()
            .map(|m| m.emission.extend(0.0).to_array())
            .collect();
        let emissive = scene.materials().iter().any(|m| m.is_emissive());
        if emission.is_empty() {
            emission.push([0.0; 4]);
        }
        ctx.checked("emission pass creation", || {
            let device = &ctx.device;
            let module = scene_module(ctx, "emission", &with_view(EMISSION_WGSL));
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("emission"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: true },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                }],
            });
            let pipeline = scene_pipeline(
                ctx,
                &ScenePipeline {
                    label: "emission",
                    module: &module,
                    layouts: &[&layout],
                    extra_vertex_buffers: &[],
                    target: weighted_additive_target(hdr_format),
                    depth_compare: wgpu::CompareFunction::Equal,
                    depth_write: false,
                },
            );
            let emission = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("emission-materials"),
                contents: bytemuck::cast_slice(&emission),
                usage: wgpu::BufferUsages::STORAGE,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("emission"),
                layout: &layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: emission.as_entire_binding(),
                }],
            });
            Self {
                pipeline,
                bind_group,
                emissive,
                emitters: emitter_corners(scene),
            }
        })
    }

    /// Takes the emitters' corners from `scene` again (its objects moved; the materials must be those the pass was built with).
    pub fn set_emitters(&mut self, scene: &Scene) {
        self.emitters = emitter_corners(scene);
    }

    /// The pixels `[x, y, w, h]` of a `width × height` target that the
    /// emitters can cover under `view_projection`: the bounding rectangle of
    /// their projected corners and a pixel all round, the whole target when
    /// a corner lies behind the eye, `None` when nothing emits or the
    /// rectangle is empty.
    pub fn screen_rect(&self, view_projection: Mat4, width: u32, height: u32) -> Option<[u32; 4]> {
        if !self.emissive || self.emitters.is_empty() {
            return None;
        }
        let full = [0, 0, width, height];
        let m = view_projection.as_dmat4();
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for c in &self.emitters {
            let p = m * c.as_dvec3().extend(1.0);
            if p.w <= 1e-9 {
                return Some(full);
            }
            let ndc = DVec2::new(p.x / p.w, p.y / p.w);
            lo = lo.min(ndc);
            hi = hi.max(ndc);
        }
        let rect =
            crate::view::intersect_rects(crate::view::ndc_to_pixels(lo, hi, width, height), full);
        (rect[2] > 0 && rect[3] > 0).then_some(rect)
    }

    /// Records the pass after the depth pre-pass: adds `Le` where an emitter is visible from its emitting side.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        views: &ViewBuffer,
        slot: ViewSlot,
    ) {
        self.encode_weighted(encoder, scene, targets, views, slot, 1.0);
    }

    /// [`EmissionPass::encode`] with `Le` weighted by `weight` (the blend
    /// constant): one of several jittered samples summed in the HDR target.
    pub fn encode_weighted(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        targets: &RenderTargets,
        views: &ViewBuffer,
        slot: ViewSlot,
        weight: f32,
    ) {
        if !self.emissive || scene.vertex_count == 0 {
            return;
        }
        let mut pass = crate::passes::redraw::begin_over_depth(encoder, targets, "emission");
        pass.set_pipeline(&self.pipeline);
        if !views.bind_in(&mut pass, 0, slot, targets) {
            return;
        }
        pass.set_blend_constant(crate::passes::redraw::uniform_constant(f64::from(weight)));
        pass.set_bind_group(1, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.draw(0..scene.vertex_count, 0..1);
    }
}

/// CPU counterpart of [`EmissionPass`]: per pixel centre, the emission of the
/// hit triangle's material when the camera is on the side its shading normal
/// points to; zero elsewhere. Row 0 is the top.
pub fn emission_pass_cpu(
    scene: &Scene,
    bvh: &Bvh,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Vec<[f32; 3]> {
    let rays: Vec<_> = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| camera.primary_ray(Camera::pixel_ndc(x, y, width, height, Vec2::splat(0.5))))
        .collect();
    bvh.closest_hits(&rays)
        .iter()
        .map(|hit| {
            hit.map_or([0.0; 3], |h| {
                let material = &scene.materials()[h.material as usize];
                if (camera.position - h.position).dot(h.shading_normal) > 0.0 {
                    material.emission.to_array()
                } else {
                    [0.0; 3]
                }
            })
        })
        .collect()
}
