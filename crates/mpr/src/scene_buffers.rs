//! The scene's world-space triangles on the GPU: three [`GpuVertex`] per
//! triangle (unshared, so per-triangle attributes stay flat), in scene-wide
//! triangle-id order (`Scene::world_triangles`).

use bytemuck::{Pod, Zeroable};
use lustre_geometry::{Scene, WorldTriangle};
use wgpu::util::DeviceExt;

use crate::{GpuContext, Result};

/// One vertex as the passes read it: world position and the triangle's `SurfaceId`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GpuVertex {
    /// World position in m.
    pub position: [f32; 3],
    /// Scene `SurfaceId` of the triangle.
    pub surface: u32,
}

impl GpuVertex {
    /// The vertex buffer layout: `@location(0) vec3f` position, `@location(1) u32` surface.
    pub const LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
        array_stride: size_of::<GpuVertex>() as wgpu::BufferAddress,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Uint32],
    };
}

/// The vertices of world triangles, three per triangle.
pub fn gpu_vertices(triangles: &[WorldTriangle]) -> Vec<GpuVertex> {
    triangles
        .iter()
        .flat_map(|t| {
            t.positions.map(|p| GpuVertex {
                position: p.to_array(),
                surface: t.surface,
            })
        })
        .collect()
}

/// A scene's triangles uploaded once per pose.
#[derive(Debug)]
pub struct SceneBuffers {
    /// The vertex buffer ([`GpuVertex`], three per triangle).
    pub vertices: wgpu::Buffer,
    /// Number of vertices to draw (0 for an empty scene).
    pub vertex_count: u32,
}

impl SceneBuffers {
    /// Uploads the scene's current pose.
    pub fn upload(ctx: &GpuContext, scene: &Scene) -> Result<Self> {
        Self::from_triangles(ctx, &scene.world_triangles())
    }

    /// Uploads world triangles.
    pub fn from_triangles(ctx: &GpuContext, triangles: &[WorldTriangle]) -> Result<Self> {
        let mut vertices = gpu_vertices(triangles);
        let vertex_count = vertices.len() as u32;
        if vertices.is_empty() {
            // A zero-sized vertex buffer cannot be bound; keep one unused vertex.
            vertices.push(GpuVertex::zeroed());
        }
        let buffer = ctx.checked("scene vertex upload", || {
            ctx.device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("scene-vertices"),
                    contents: bytemuck::cast_slice(&vertices),
                    usage: wgpu::BufferUsages::VERTEX,
                })
        })?;
        Ok(Self {
            vertices: buffer,
            vertex_count,
        })
    }
}
