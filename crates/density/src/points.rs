//! Vertex-based calculation (section 3.4.2): one estimation point per distinct vertex position and normal, shared by the triangles of every colour that meet there; each triangle multiplies the shared irradiance by its own reflectance.

use std::collections::HashMap;

use glam::Vec3;
use lustre_geometry::{MeshId, Scene};

use crate::VertexIrradiance;
use crate::world::World;

/// An estimation point: a vertex position with its unit normal (the disc's plane in DETP).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimationPoint {
    /// World position.
    pub position: Vec3,
    /// Unit shading normal (zero for a degenerate vertex, which gets no estimate).
    pub normal: Vec3,
    /// The first mesh whose vertex maps to this point.
    pub mesh: MeshId,
    /// Whether the point belongs to a mobile object (section 2.5: dynamic vertices).
    pub mobile: bool,
}

/// The distinct estimation points of a scene and the map from every mesh vertex to its point (section 3.4.2).
#[derive(Debug, Clone)]
pub struct EstimationPoints {
    /// The points: static ones first, then mobile ones.
    pub points: Vec<EstimationPoint>,
    /// Point of each vertex, `[mesh][vertex]`.
    pub vertex_point: Vec<Vec<u32>>,
    /// Index of the first mobile point in `points`.
    pub first_mobile: usize,
}

impl EstimationPoints {
    /// Builds the points of the scene's current pose; vertices of different meshes with bit-identical position and normal share a point, static and mobile vertices never do.
    pub fn new(scene: &Scene, world: &World) -> Self {
        let mut points = Vec::new();
        let mut vertex_point = vec![Vec::new(); scene.meshes().len()];
        let mut first_mobile = 0;
        for mobile in [false, true] {
            if mobile {
                first_mobile = points.len();
            }
            let mut seen: HashMap<([u32; 3], [u32; 3]), u32> = HashMap::new();
            for (m, slot) in vertex_point.iter_mut().enumerate() {
                let m = m as MeshId;
                if world.is_mobile_mesh(m) != mobile {
                    continue;
                }
                let positions = scene.world_positions(m);
                let normals = scene.world_normals(m);
                *slot = positions
                    .iter()
                    .zip(&normals)
                    .map(|(&position, &normal)| {
                        let normal = normal.normalize_or_zero();
                        let key = (
                            position.to_array().map(f32::to_bits),
                            normal.to_array().map(f32::to_bits),
                        );
                        *seen.entry(key).or_insert_with(|| {
                            points.push(EstimationPoint {
                                position,
                                normal,
                                mesh: m,
                                mobile,
                            });
                            (points.len() - 1) as u32
                        })
                    })
                    .collect();
            }
        }
        Self {
            points,
            vertex_point,
            first_mobile,
        }
    }

    /// Moves the mobile points to the scene's current pose (their sharing is rigid, so the map is kept).
    pub fn move_mobile(&mut self, scene: &Scene) {
        for (m, map) in self.vertex_point.iter().enumerate() {
            let Some(&first) = map.first() else { continue };
            if !self.points[first as usize].mobile {
                continue;
            }
            let positions = scene.world_positions(m as MeshId);
            let normals = scene.world_normals(m as MeshId);
            for ((&p, &x), &n) in map.iter().zip(&positions).zip(&normals) {
                let point = &mut self.points[p as usize];
                point.position = x;
                point.normal = n.normalize_or_zero();
            }
        }
    }

    /// Spreads per-point irradiance to every mesh vertex (`[mesh][vertex]`).
    pub fn to_vertices(&self, per_point: &[lustre_geometry::Rgb]) -> VertexIrradiance {
        self.vertex_point
            .iter()
            .map(|map| map.iter().map(|&p| per_point[p as usize]).collect())
            .collect()
    }
}
