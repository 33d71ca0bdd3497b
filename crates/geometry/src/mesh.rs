//! Triangle meshes with per-vertex normals and UVs.

use glam::{Vec2, Vec3};

use crate::material::MaterialId;
use crate::{Aabb, GeometryError, Result};

/// Index of a mesh in [`crate::Scene::meshes`].
pub type MeshId = u32;

/// A triangle mesh with one material.
///
/// Positions and normals are in the scene's world frame at the object's rest
/// pose; the owning object's transform is applied on top (see [`crate::Object`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    /// The mesh's name (OBJ object/group name or the built-in part's name).
    pub name: String,
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (unit length), as many as positions.
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates, as many as positions (zero when the source has none).
    pub uvs: Vec<Vec2>,
    /// Counter-clockwise triangles (seen from the side the geometric normal points to).
    pub indices: Vec<[u32; 3]>,
    /// The material of every triangle.
    pub material: MaterialId,
}

impl Mesh {
    /// A mesh with flat normals (one normal per triangle, vertices duplicated) and per-triangle UVs `(0, 0)`, `(1, 0)`, `(0, 1)`.
    pub fn flat(
        name: impl Into<String>,
        positions: &[Vec3],
        indices: &[[u32; 3]],
        material: MaterialId,
    ) -> Self {
        Self::flat_with_uvs(name, positions, &[], indices, material)
    }

    /// A mesh with flat normals (one normal per triangle, vertices duplicated) and the UVs of `uvs` (one per position); with fewer UVs than positions, [`Mesh::flat`]'s.
    pub fn flat_with_uvs(
        name: impl Into<String>,
        positions: &[Vec3],
        uvs: &[Vec2],
        indices: &[[u32; 3]],
        material: MaterialId,
    ) -> Self {
        let keep_uvs = uvs.len() >= positions.len();
        let mut mesh = Self {
            name: name.into(),
            positions: Vec::with_capacity(indices.len() * 3),
            normals: Vec::with_capacity(indices.len() * 3),
            uvs: Vec::with_capacity(indices.len() * 3),
            indices: Vec::with_capacity(indices.len()),
            material,
        };
        for tri in indices {
            let p = tri.map(|i| positions[i as usize]);
            let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            let base = mesh.positions.len() as u32;
            mesh.positions.extend(p);
            mesh.normals.extend([n; 3]);
            if keep_uvs {
                mesh.uvs.extend(tri.map(|i| uvs[i as usize]));
            } else {
                mesh.uvs.extend([Vec2::ZERO, Vec2::X, Vec2::Y]);
            }
            mesh.indices.push([base, base + 1, base + 2]);
        }
        mesh
    }

    /// The three corner positions of triangle `t`.
    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        self.indices[t].map(|i| self.positions[i as usize])
    }

    /// Area of triangle `t`.
    pub fn triangle_area(&self, t: usize) -> f32 {
        triangle_area(self.triangle(t))
    }

    /// Unit geometric normal of triangle `t` (zero for a degenerate triangle).
    pub fn geometric_normal(&self, t: usize) -> Vec3 {
        let [a, b, c] = self.triangle(t);
        (b - a).cross(c - a).normalize_or_zero()
    }

    /// Total area of the mesh.
    pub fn area(&self) -> f32 {
        (0..self.indices.len()).map(|t| self.triangle_area(t)).sum()
    }

    /// Bounding box of the mesh's vertices.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.positions.iter().copied())
    }

    /// Checks that the attribute arrays have one entry per position, that the
    /// positions are finite and that every index is in range; an empty mesh passes.
    pub fn validate_arrays(&self) -> Result<()> {
        let n = self.positions.len();
        if self.normals.len() != n || self.uvs.len() != n {
            return Err(self.invalid(format!(
                "{n} positions but {} normals and {} uvs",
                self.normals.len(),
                self.uvs.len()
            )));
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(self.invalid(format!("position {i} is not finite")));
        }
        if let Some(t) = self
            .indices
            .iter()
            .position(|tri| tri.iter().any(|&i| i as usize >= n))
        {
            return Err(self.invalid(format!(
                "triangle {t} indexes a vertex beyond the {n} vertices"
            )));
        }
        Ok(())
    }

    /// Checks everything [`Mesh::validate_arrays`] does, plus that the mesh has
    /// triangles, unit normals and finite UVs.
    pub fn validate(&self) -> Result<()> {
        if self.indices.is_empty() {
            return Err(GeometryError::EmptyMesh {
                mesh: self.name.clone(),
                file: None,
            });
        }
        self.validate_arrays()?;
        if let Some(i) = self
            .normals
            .iter()
            .position(|v| !v.is_finite() || (v.length() - 1.0).abs() > 1e-3)
        {
            return Err(self.invalid(format!("normal {i} is not a unit vector")));
        }
        if let Some(i) = self.uvs.iter().position(|uv| !uv.is_finite()) {
            return Err(self.invalid(format!("uv {i} is not finite")));
        }
        Ok(())
    }

    /// An [`GeometryError::InvalidMesh`] naming this mesh.
    fn invalid(&self, message: String) -> GeometryError {
        GeometryError::InvalidMesh {
            mesh: self.name.clone(),
            message,
        }
    }

    /// Removes triangles whose area is below `min_area` (or not finite); returns how many went.
    pub fn remove_degenerate(&mut self, min_area: f32) -> usize {
        let before = self.indices.len();
        let positions = &self.positions;
        self.indices.retain(|tri| {
            let area = triangle_area(tri.map(|i| positions[i as usize]));
            area.is_finite() && area > min_area
        });
        before - self.indices.len()
    }
}

/// Area of a triangle: half the length of the cross product of two edges.
pub fn triangle_area([a, b, c]: [Vec3; 3]) -> f32 {
    0.5 * (b - a).cross(c - a).length()
}
