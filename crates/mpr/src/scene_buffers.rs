//! The scene's world-space triangles on the GPU: three [`GpuVertex`] per
//! triangle (unshared, so per-triangle attributes stay flat), in scene-wide
//! triangle-id order (`Scene::world_triangles`), plus an index buffer that
//! lists them surface by surface, for passes that draw one surface at a time
//! (the per-surface stencil masks of Stürzlinger & Bastos 1997, section 2.2).

use bytemuck::{Pod, Zeroable};
use lustre_geometry::{Scene, WorldTriangle};
use wgpu::util::DeviceExt;

use crate::{GpuContext, Result};

/// One vertex as the passes read it: world position, the triangle's `SurfaceId`, shading normal, `MaterialId` and texture coordinates.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GpuVertex {
    /// World position in m.
    pub position: [f32; 3],
    /// Scene `SurfaceId` of the triangle.
    pub surface: u32,
    /// Unit world shading normal.
    pub normal: [f32; 3],
    /// Scene `MaterialId` of the triangle.
    pub material: u32,
    /// Texture coordinates (OBJ's convention, `v` up; [`lustre_geometry::WorldTriangle::uvs`]).
    pub uv: [f32; 2],
}

impl GpuVertex {
    /// The vertex buffer layout: `@location(0) vec3f` position, `@location(1) u32` surface,
    /// `@location(2) vec3f` normal, `@location(3) u32` material, `@location(6) vec2f` uv
    /// (locations 4 and 5 are left to the passes' own vertex buffers, e.g. the Gouraud pass's radiance).
    pub const LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
        array_stride: size_of::<GpuVertex>() as wgpu::BufferAddress,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Uint32, 2 => Float32x3, 3 => Uint32, 6 => Float32x2],
    };
}

/// The vertices of world triangles, three per triangle.
pub fn gpu_vertices(triangles: &[WorldTriangle]) -> Vec<GpuVertex> {
    triangles
        .iter()
        .flat_map(|t| {
            [0, 1, 2].map(|i| GpuVertex {
                position: t.positions[i].to_array(),
                surface: t.surface,
                normal: t.normals[i].to_array(),
                material: t.material,
                uv: t.uvs[i].to_array(),
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
    /// Vertex indices (`u32`), the triangles of surface 0 first, then surface 1, ...
    pub surface_indices: wgpu::Buffer,
    /// The range of [`SceneBuffers::surface_indices`] of each surface, by `SurfaceId`.
    pub surface_ranges: Vec<std::ops::Range<u32>>,
    /// The world box of each surface in this pose, by `SurfaceId` ([`crate::view::surface_boxes`]).
    pub surface_boxes: Vec<[glam::Vec3; 2]>,
}

/// Vertex indices grouped by surface and the range of each surface, for `surfaces` surfaces.
pub fn surface_index_ranges(
    triangles: &[WorldTriangle],
    surfaces: usize,
) -> (Vec<u32>, Vec<std::ops::Range<u32>>) {
    let mut by_surface: Vec<Vec<u32>> = vec![Vec::new(); surfaces];
    for (t, tri) in triangles.iter().enumerate() {
        if let Some(list) = by_surface.get_mut(tri.surface as usize) {
            let base = 3 * t as u32;
            list.extend([base, base + 1, base + 2]);
        }
    }
    let mut indices = Vec::with_capacity(3 * triangles.len());
    let mut ranges = Vec::with_capacity(surfaces);
    for list in by_surface {
        let start = indices.len() as u32;
        indices.extend(list);
        ranges.push(start..indices.len() as u32);
    }
    (indices, ranges)
}

impl SceneBuffers {
    /// Uploads the scene's current pose.
    pub fn upload(ctx: &GpuContext, scene: &Scene) -> Result<Self> {
        Self::from_triangles(ctx, &scene.world_triangles(), scene.surfaces().len())
    }

    /// Uploads world triangles of a scene with `surfaces` surfaces.
    pub fn from_triangles(
        ctx: &GpuContext,
        triangles: &[WorldTriangle],
        surfaces: usize,
    ) -> Result<Self> {
        let (mut indices, surface_ranges) = surface_index_ranges(triangles, surfaces);
        if indices.is_empty() {
            indices.push(0);
        }
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
        let surface_indices = ctx.checked("scene index upload", || {
            ctx.device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("scene-surface-indices"),
                    contents: bytemuck::cast_slice(&indices),
                    usage: wgpu::BufferUsages::INDEX,
                })
        })?;
        Ok(Self {
            vertices: buffer,
            vertex_count,
            surface_indices,
            surface_ranges,
            surface_boxes: crate::view::surface_boxes_of(triangles, surfaces),
        })
    }
}
