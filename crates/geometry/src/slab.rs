//! Closed glass slabs (Diefenbach & Badler 1997, section 2: in-out refraction, "an entry refraction and an exit refraction, producing a refracted ray parallel to the incident ray"): a planar dielectric face and the nearest parallel, opposite face of the same mesh and material behind it.

use crate::material::MaterialModel;
use crate::scene::{Scene, SurfaceId, SurfaceKind};

/// One face of a closed slab and the face light leaves it by.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlabFace {
    /// The parallel, opposite face behind it (normal within 0.0001 of the
    /// reverse; the nearest such face of the same mesh and material).
    pub partner: SurfaceId,
    /// Distance between the two faces' planes in m.
    pub thickness: f32,
}

/// Per surface of `scene`, its [`SlabFace`] when it is a planar face of a
/// [`MaterialModel::Dielectric`] with a parallel, opposite face of the same
/// mesh and material behind it; `None` for every other surface (a single
/// interface, a curved face, any other material).
pub fn slab_faces(scene: &Scene) -> Vec<Option<SlabFace>> {
    let surfaces = scene.surfaces();
    let plane_of = |id: usize| match surfaces[id].kind {
        SurfaceKind::Planar(plane) => Some(plane),
        SurfaceKind::Curved => None,
    };
    (0..surfaces.len())
        .map(|id| {
            let surface = &surfaces[id];
            let plane = plane_of(id)?;
            let model = &scene.materials()[surface.material as usize].model;
            if !matches!(model, MaterialModel::Dielectric { .. }) {
                return None;
            }
            (0..surfaces.len())
                .filter(|&o| {
                    surfaces[o].mesh == surface.mesh && surfaces[o].material == surface.material
                })
                .filter_map(|o| {
                    let other = plane_of(o)?;
                    // Behind this face: the other plane's offset along -normal.
                    let thickness = plane.offset + other.offset;
                    (other.normal.dot(plane.normal) < -0.9999 && thickness > 0.0).then_some(
                        SlabFace {
                            partner: o as SurfaceId,
                            thickness,
                        },
                    )
                })
                .min_by(|a, b| a.thickness.total_cmp(&b.thickness))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bathroom_door_is_a_slab_of_one_centimetre() {
        let scene = crate::builtin::bathroom();
        let faces = slab_faces(&scene);
        let glass = scene
            .materials()
            .iter()
            .position(|m| matches!(m.model, MaterialModel::Dielectric { .. }))
            .unwrap() as u32;
        let mut door = 0;
        for (id, (surface, face)) in scene.surfaces().iter().zip(&faces).enumerate() {
            if surface.material != glass {
                assert_eq!(*face, None);
                continue;
            }
            let face = face.expect("every planar face of the closed door has a partner");
            // Partners pair up.
            assert_eq!(faces[face.partner as usize].unwrap().partner, id as u32);
            let SurfaceKind::Planar(plane) = surface.kind else {
                panic!("the door is planar")
            };
            if plane.normal.x.abs() > 0.999 {
                // The two large faces, x = 0.83 and x = 0.84.
                assert!((face.thickness - 0.01).abs() < 1e-4, "{}", face.thickness);
                door += 1;
            }
        }
        assert_eq!(door, 2);
    }

    #[test]
    fn a_single_interface_is_no_slab() {
        // The pool's water surface is one dielectric quad.
        let scene = crate::builtin::pool();
        assert!(slab_faces(&scene).iter().all(Option::is_none));
    }
}
