//! `lustre render --photons-file`: a photon file read in batches, so memory is bounded by one batch whatever the file's size (Stürzlinger & Bastos 1997, section 2.1: hits stored on disk; section 2.2 splats; section 2.2.1 diffuse textures).
//!
//! Three passes over the file: a tally (equation 3's photon count per
//! surface and the lit sides of planar surfaces), the diffuse textures
//! (each batch's flux added to the atlas), and, after the frame without
//! splats is drawn, each batch's splats uploaded, added to the frame on the
//! GPU and dropped ([`lustre_mpr::FrameGraph::add_splats`]).

use std::path::Path;

use anyhow::{Context, bail};
use lustre_geometry::Scene;
use lustre_mpr::beam_paths::{BeamSurface, drawn_by_beams, scatterer_surfaces};
use lustre_mpr::passes::diffuse_texture::{DiffuseAtlas, DiffuseTextureOptions};
use lustre_mpr::projective_texture::PaneLight;
use lustre_mpr::virtual_light::{PassedFaces, drawn_by_virtual_lights};
use lustre_photon::{
    EmissionSampling, EstimatorOptions, PhotonFileReader, PhotonMap, SplatEstimator, SplatTally,
    SurfaceParams, scene_fingerprint,
};

use crate::trace::PhotonBar;

/// `map` without the records of light that reached them through mirrors, slabs and stained-glass windows only, which the virtual lights draw (Diefenbach & Badler 1997, sections 4.2, 4.5, 6; [`drawn_by_virtual_lights`]); `map` must hold whole photon paths.
fn without_virtual_light_photons(
    map: PhotonMap,
    passed: &PassedFaces,
    depth: u32,
) -> anyhow::Result<PhotonMap> {
    let drawn = drawn_by_virtual_lights(map.records(), &passed.faces, &passed.windows, depth);
    without(map, &drawn).context("cannot leave the virtual lights' photons out")
}

/// `map` without the records `drawn` marks.
fn without(map: PhotonMap, drawn: &[bool]) -> lustre_photon::Result<PhotonMap> {
    let kept = map
        .records()
        .iter()
        .zip(drawn)
        .filter(|&(_, &d)| !d)
        .map(|(r, _)| *r)
        .collect();
    PhotonMap::from_parts(map.lights().to_vec(), kept)
}

/// `map` without the records of light that a scatterer (or a closed glass slab) sent onto the next surface, which the beams draw (Duvenhage et al. 2010, section 3.1; [`drawn_by_beams`]); `surfaces` per surface, `map` whole photon paths.
fn without_beam_photons(map: PhotonMap, surfaces: &[BeamSurface]) -> anyhow::Result<PhotonMap> {
    let drawn = drawn_by_beams(map.records(), surfaces);
    without(map, &drawn).context("cannot leave the beams' photons out")
}

/// A verified photon file and the tally of its selected photons.
pub struct StreamedPhotons {
    /// The file.
    reader: PhotonFileReader,
    /// Records per batch.
    batch_records: usize,
    /// The scene's parameterisations.
    params: SurfaceParams,
    /// Equation 3's counts and the lit sides over the whole file.
    tally: SplatTally,
    /// What the splats leave out of every batch.
    left_out: LeftOut,
    /// Hit records kept after the beams' and the virtual lights' filters.
    pub kept_records: u64,
    /// Hit records left out because the beams draw their light.
    pub beam_records: u64,
    /// Indirect records kept.
    pub indirect_records: u64,
}

impl StreamedPhotons {
    /// Opens `path` for `scene` (whose lights emit as the file says: `point_lights`), checks it, and tallies it batch by batch.
    pub fn open(
        path: &Path,
        scene: &Scene,
        point_lights: bool,
        batch_records: usize,
        options: &EstimatorOptions,
        left_out: LeftOut,
    ) -> anyhow::Result<Self> {
        let params = SurfaceParams::new(scene);
        let reader = PhotonFileReader::open_for(path, &params).with_context(|| {
            format!(
                "--photons-file {}: not a photon file of `{}` as this render loads it",
                path.display(),
                scene.name
            )
        })?;
        let Some(provenance) = reader.header().provenance else {
            bail!(
                "--photons-file {}: the file does not record how its lights emitted; \
                 trace it with `lustre trace`",
                path.display()
            );
        };
        // The fingerprint covers the lights as they emitted; where it differs,
        // the light model is the likelier cause to name.
        if provenance.scene != scene_fingerprint(scene) {
            if provenance.point_lights != point_lights {
                let (file, render) = if provenance.point_lights {
                    ("area lights replaced by point lights", "the area lights")
                } else {
                    ("the area lights", "point lights of equal power")
                };
                bail!(
                    "--photons-file {}: its photons left {file}, this render's photons leave \
                     {render}; trace with `lustre trace --area-lights {}`",
                    path.display(),
                    if point_lights { "points" } else { "area" }
                );
            }
            bail!(
                "--photons-file {}: traced in another scene than `{}` (its materials or lights \
                 differ); trace it with `lustre trace {}`",
                path.display(),
                scene.name,
                scene.name
            );
        }
        let bar = PhotonBar::new("reading photons", reader.header().records)?;
        let mut tally = SplatTally::new(&params, options.selection);
        let (mut kept, mut indirect) = (0u64, 0u64);
        let beam_records = read_batches(
            &reader,
            batch_records,
            &left_out,
            &mut |batch| {
                tally.add(&params, batch.records())?;
                kept += batch.len() as u64;
                indirect += batch.indirect().count() as u64;
                Ok(())
            },
            &bar,
        )?;
        Ok(Self {
            reader,
            batch_records,
            params,
            tally,
            left_out,
            kept_records: kept,
            beam_records,
            indirect_records: indirect,
        })
    }

    /// The emission sampling the file was traced with.
    pub fn emission(&self) -> EmissionSampling {
        self.reader
            .header()
            .provenance
            .map_or(EmissionSampling::Random, |p| p.emission)
    }

    /// Photons emitted by the file's lights.
    pub fn emitted(&self) -> u64 {
        self.reader.header().emitted()
    }

    /// Calls `f` with each batch of the file, the beams' and the virtual lights' photons left out; `bar` counts records.
    pub fn for_each_batch(
        &self,
        f: &mut dyn FnMut(&PhotonMap) -> anyhow::Result<()>,
        bar: &PhotonBar,
    ) -> anyhow::Result<()> {
        read_batches(&self.reader, self.batch_records, &self.left_out, f, bar).map(|_| ())
    }

    /// The estimator without photons whose supports (equation 3, from the whole file's counts), kernel mass and BRDFs every batch's estimator shares ([`SplatEstimator::with_photons`]).
    pub fn template(
        &self,
        scene: &Scene,
        options: EstimatorOptions,
    ) -> anyhow::Result<SplatEstimator> {
        let empty = PhotonMap::from_parts(self.reader.header().lights.clone(), Vec::new())?;
        SplatEstimator::build_tallied(scene, &empty, options, &self.tally)
            .context("cannot size the splats from the photon file's counts")
    }

    /// The diffuse textures of the whole file (section 2.2.1), accumulated batch by batch with the estimator `options`.
    pub fn atlas(
        &self,
        scene: &Scene,
        options: EstimatorOptions,
        texture_options: DiffuseTextureOptions,
    ) -> anyhow::Result<DiffuseAtlas> {
        let template = self.template(scene, options)?;
        let mut atlas = DiffuseAtlas::layout(
            scene,
            &self.params,
            &|id| template.support(id),
            &self.tally.lit,
            texture_options,
        )?;
        let bar = PhotonBar::new("diffuse textures", self.reader.header().records)?;
        self.for_each_batch(
            &mut |batch| {
                atlas.accumulate(&template.with_photons(batch)?)?;
                Ok(())
            },
            &bar,
        )?;
        Ok(atlas)
    }
}

/// The photons the splats leave out, from the photons in memory or from each batch of a file alike: light the beams draw (Duvenhage et al. 2010, section 3.1; per surface, [`BeamSurface`]), then light the virtual lights draw (Diefenbach & Badler 1997, sections 4.2, 6; their faces and depth). Both filters need whole photon paths, which every batch holds.
pub struct LeftOut {
    beams: Option<Vec<BeamSurface>>,
    virtual_lights: Option<(PassedFaces, u32)>,
}

impl LeftOut {
    /// The filters of a render of `scene`: the beams' where it draws `beams`, the virtual lights' to `virtual_depth` (none for `None` or 0), their windows as `panes` says.
    pub fn new(
        scene: &Scene,
        beams: bool,
        virtual_depth: Option<u32>,
        panes: PaneLight,
    ) -> anyhow::Result<Self> {
        Ok(Self {
            beams: beams.then(|| scatterer_surfaces(scene)).transpose()?,
            virtual_lights: match virtual_depth.filter(|&d| d > 0) {
                Some(d) => Some((PassedFaces::new(scene, panes)?, d)),
                None => None,
            },
        })
    }

    /// `map` without what the filters leave out, and the number of records the beams' filter left out.
    pub fn apply(&self, mut map: PhotonMap) -> anyhow::Result<(PhotonMap, u64)> {
        let mut beam_records = 0u64;
        if let Some(surfaces) = &self.beams {
            let before = map.len();
            map = without_beam_photons(map, surfaces)?;
            beam_records = (before - map.len()) as u64;
        }
        if let Some((faces, depth)) = &self.virtual_lights {
            map = without_virtual_light_photons(map, faces, *depth)?;
        }
        Ok((map, beam_records))
    }
}

/// Calls `f` with each batch of `reader`, what `left_out` names left out; `bar` counts records. Returns the number of records the beams' filter left out.
fn read_batches(
    reader: &PhotonFileReader,
    batch_records: usize,
    left_out: &LeftOut,
    f: &mut dyn FnMut(&PhotonMap) -> anyhow::Result<()>,
    bar: &PhotonBar,
) -> anyhow::Result<u64> {
    bar.0.set_position(0);
    let mut beam_records = 0u64;
    for batch in reader.batches(batch_records)? {
        let batch = batch?;
        bar.0.inc(batch.len() as u64);
        let (batch, beams) = left_out.apply(batch)?;
        beam_records += beams;
        f(&batch)?;
    }
    bar.0.finish_and_clear();
    Ok(beam_records)
}
