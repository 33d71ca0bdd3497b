//! Which photon hits the beams stand for (Duvenhage et al. 2010, section 3.1: beams model the light-to-specular-to-diffuse paths, L(S|G)DE): a photon's second hit when its first was on a scatterer (a mirror, a rough conductor, a dielectric interface or a thin slab), and its first hit past a closed glass slab when every hit before was on that slab's faces (the beams' thin slab, [`lustre_beams::Scatterer::slab_face`], sums the refractions and internal reflections). A frame that draws the beam pass leaves those hits out of its splats and diffuse textures so that the light is added once; later hits of the same photon (the caustic's own diffuse inter-reflection) stay.

use lustre_beams::ScatterMaterial;
use lustre_geometry::Scene;
use lustre_photon::HitRecord;

use crate::{MprError, Result};

/// What a surface is to the beams.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BeamSurface {
    /// Its material scatters no beam: light arriving there is received.
    Receiver,
    /// It scatters one beam per light ([`ScatterMaterial::from_model`]).
    Scatterer,
    /// A face of a closed glass slab ([`lustre_geometry::slab::slab_faces`]):
    /// the beams treat the faces of one mesh as one scatter.
    SlabFace {
        /// The slab's mesh.
        mesh: u32,
    },
}

/// Per surface of `scene`, what it is to the beams.
pub fn scatterer_surfaces(scene: &Scene) -> Result<Vec<BeamSurface>> {
    let materials = scene
        .materials()
        .iter()
        .map(|m| {
            ScatterMaterial::from_model(&m.model)
                .map(|s| s.is_some())
                .map_err(|e| MprError::UnsupportedMaterial {
                    material: m.name.clone(),
                    message: e.to_string(),
                })
        })
        .collect::<Result<Vec<_>>>()?;
    let slabs = lustre_geometry::slab::slab_faces(scene);
    Ok(scene
        .surfaces()
        .iter()
        .zip(slabs)
        .map(|(s, slab)| match (slab, materials[s.material as usize]) {
            (Some(_), _) => BeamSurface::SlabFace { mesh: s.mesh },
            (None, true) => BeamSurface::Scatterer,
            (None, false) => BeamSurface::Receiver,
        })
        .collect())
}

/// The hits of one photon so far, as the beams see them.
#[derive(Clone, Copy)]
enum Before {
    /// None: the next record is the photon's first hit.
    Nothing,
    /// One hit, on a scatterer.
    Scattered,
    /// Hits on the faces of one closed slab only.
    Slab(u32),
    /// Anything else: no beam draws what follows.
    Other,
}

/// Per record, whether the beams draw its light: the hit right after a photon's first hit on a scatterer, or after hits on one closed slab's faces only (`surfaces` per surface, [`scatterer_surfaces`]). Records must hold whole photon paths in order, as the tracer writes them.
pub fn drawn_by_beams(records: &[HitRecord], surfaces: &[BeamSurface]) -> Vec<bool> {
    let mut before = Before::Nothing;
    records
        .iter()
        .map(|r| {
            if r.bounce == 1 {
                before = Before::Nothing;
            }
            let drawn = matches!(before, Before::Scattered | Before::Slab(_));
            let here = surfaces
                .get(r.surface as usize)
                .copied()
                .unwrap_or(BeamSurface::Receiver);
            before = match (before, here) {
                (Before::Nothing, BeamSurface::Scatterer) => Before::Scattered,
                (Before::Nothing, BeamSurface::SlabFace { mesh }) => Before::Slab(mesh),
                (Before::Slab(a), BeamSurface::SlabFace { mesh }) if a == mesh => Before::Slab(a),
                _ => Before::Other,
            };
            drawn
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec2, Vec3};
    use lustre_geometry::Rgb;

    fn hit(surface: u32, bounce: u8) -> HitRecord {
        HitRecord {
            surface,
            triangle: 0,
            position: Vec2::ZERO,
            direction: Vec3::Y,
            light: 0,
            bounce,
            rho: Rgb::ONE,
        }
    }

    #[test]
    fn only_the_hit_after_a_first_scatter_is_drawn() {
        // Surface 1 scatters; 0 and 2 receive.
        let scatterer = [
            BeamSurface::Receiver,
            BeamSurface::Scatterer,
            BeamSurface::Receiver,
        ];
        let records = [
            hit(1, 1), // light -> mirror
            hit(0, 2), // -> floor: the beam's
            hit(2, 3), // -> wall: stays
            hit(0, 1), // direct on the floor
            hit(1, 2), // -> mirror second: not a first scatter
            hit(2, 3), // stays
            hit(1, 1), // a new photon on the mirror
            hit(1, 2), // -> mirror again (L S S): the beam lights nothing there
        ];
        assert_eq!(
            drawn_by_beams(&records, &scatterer),
            [false, true, false, false, false, false, false, true]
        );
    }

    #[test]
    fn scatterers_of_the_caustic_scenes_are_their_specular_surfaces() {
        let scene = lustre_geometry::builtin::cardioid();
        let s = scatterer_surfaces(&scene).unwrap();
        assert_eq!(s.len(), scene.surfaces().len());
        for (surface, &is) in scene.surfaces().iter().zip(&s) {
            let mirror = matches!(
                scene.materials()[surface.material as usize].model,
                lustre_geometry::MaterialModel::Mirror { .. }
            );
            assert_eq!(is == BeamSurface::Scatterer, mirror);
            assert_ne!(is == BeamSurface::Receiver, mirror);
        }
        assert!(s.contains(&BeamSurface::Scatterer) && s.contains(&BeamSurface::Receiver));
    }

    #[test]
    fn a_chain_through_one_closed_slab_is_one_scatter() {
        // Surfaces 1 and 2 are the faces of slab mesh 7, 3 of slab mesh 8;
        // 4 a mirror; 0 receives.
        let surfaces = [
            BeamSurface::Receiver,
            BeamSurface::SlabFace { mesh: 7 },
            BeamSurface::SlabFace { mesh: 7 },
            BeamSurface::SlabFace { mesh: 8 },
            BeamSurface::Scatterer,
        ];
        let records = [
            hit(1, 1), // light -> near face
            hit(2, 2), // -> far face (inside the glass)
            hit(0, 3), // -> floor: the thin slab's transmitted beam
            hit(0, 4), // -> floor again: stays
            hit(1, 1), // near face
            hit(2, 2), // far face, reflected inside
            hit(1, 3), // near face again, out
            hit(0, 4), // -> floor: the thin slab's reflected beam
            hit(1, 1), // near face
            hit(3, 2), // -> another slab: no beam draws two slabs
            hit(0, 3), // stays
            hit(4, 1), // mirror
            hit(1, 2), // -> slab: the mirror's beam lights nothing there
            hit(2, 3), // past a mirror and a slab: stays
            hit(0, 4), // stays
        ];
        assert_eq!(
            drawn_by_beams(&records, &surfaces),
            [
                false, true, true, false, false, true, true, true, false, true, false, false, true,
                false, false
            ]
        );
    }

    #[test]
    fn the_bathroom_door_is_one_slab_and_the_mirror_a_scatterer() {
        let scene = lustre_geometry::builtin::bathroom();
        let s = scatterer_surfaces(&scene).unwrap();
        let slab_meshes: std::collections::BTreeSet<u32> = s
            .iter()
            .filter_map(|x| match x {
                BeamSurface::SlabFace { mesh } => Some(*mesh),
                _ => None,
            })
            .collect();
        assert_eq!(slab_meshes.len(), 1, "{slab_meshes:?}");
        let door = *slab_meshes.first().unwrap();
        assert_eq!(scene.meshes()[door as usize].name, "shower-door");
        assert_eq!(
            s.iter().filter(|&&x| x == BeamSurface::Scatterer).count(),
            1
        );
    }
}
