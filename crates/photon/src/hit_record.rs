//! Hit records and the photon map that holds them (sections 2.1 and 3.1, equation 1).

use glam::{Vec2, Vec3};
use lustre_geometry::{Rgb, Scene, SurfaceId};

use crate::error::{PhotonError, Result};

/// One photon hit (section 3.1): where on which surface, from where, from which light, after how many bounces, with what attenuation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HitRecord {
    /// The surface hit.
    pub surface: SurfaceId,
    /// The triangle hit, as an index into the surface's `triangles`.
    pub triangle: u32,
    /// Position on the surface: `(u, v)` in metres in the surface's [`crate::PlanarFrame`] for planar surfaces, barycentrics `(b1, b2)` of `triangle` for curved ones (see [`crate::parameterisation`]).
    pub position: Vec2,
    /// Unit incoming direction in world space, pointing away from the surface towards where the photon came from (the BRDF's `wi`).
    pub direction: Vec3,
    /// Index of the light that emitted the photon, into [`PhotonMap::lights`].
    pub light: u32,
    /// Number of the hit along the photon's path: 1 for the first surface hit (direct illumination), 2 and more for indirect (section 2.2.1).
    pub bounce: u8,
    /// Accumulated attenuation `ρ_φ` (RGB) of the photon until it hit this surface (section 2.1).
    pub rho: Rgb,
}

impl HitRecord {
    /// Whether the photon was reflected at least once before this hit: the indirect photons splatted by the optimised method (section 2.2.1).
    pub fn is_indirect(&self) -> bool {
        self.bounce > 1
    }
}

/// What a photon map knows of one light (section 2.1): its power `Φ_i` and the number of photons `m_i` it has emitted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightEmission {
    /// Power `Φ_i` of the light in W.
    pub power: Rgb,
    /// Number of photons `m_i` emitted so far.
    pub emitted: u64,
}

/// Hit records of every light with their emitted counts, so photon powers follow from equation 1 and more photons can be added later (incremental refinement, section 2.1).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PhotonMap {
    /// One entry per light of the scene.
    lights: Vec<LightEmission>,
    /// The hit records, in emission order.
    records: Vec<HitRecord>,
}

impl PhotonMap {
    /// An empty map for lights of the given powers (nothing emitted yet).
    pub fn new(powers: impl IntoIterator<Item = Rgb>) -> Self {
        Self {
            lights: powers
                .into_iter()
                .map(|power| LightEmission { power, emitted: 0 })
                .collect(),
            records: Vec::new(),
        }
    }

    /// An empty map for a scene's lights.
    pub fn for_scene(scene: &Scene) -> Self {
        Self::new(scene.lights().iter().map(|l| l.power()))
    }

    /// A map from its parts; fails when a record names a light that does not exist or a power is negative or not finite.
    pub fn from_parts(lights: Vec<LightEmission>, records: Vec<HitRecord>) -> Result<Self> {
        for (i, l) in lights.iter().enumerate() {
            if !l.power.is_finite() || l.power.min_element() < 0.0 {
                return Err(PhotonError::LightMismatch(format!(
                    "light #{i} has power {} (must be finite and non-negative)",
                    l.power
                )));
            }
        }
        if let Some(index) = records
            .iter()
            .position(|r| r.light as usize >= lights.len())
        {
            return Err(PhotonError::InvalidRecord {
                index,
                message: format!(
                    "light #{} does not exist ({} lights)",
                    records[index].light,
                    lights.len()
                ),
            });
        }
        Ok(Self { lights, records })
    }

    /// The lights' powers and emitted counts.
    pub fn lights(&self) -> &[LightEmission] {
        &self.lights
    }

    /// The hit records.
    pub fn records(&self) -> &[HitRecord] {
        &self.records
    }

    /// Number of hit records.
    pub fn len(&self) -> usize {
        self.records.len()
    }

    /// Whether the map holds no record.
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// Total number of photons emitted by all lights.
    pub fn emitted(&self) -> u64 {
        self.lights.iter().map(|l| l.emitted).sum()
    }

    /// Power of one photon of light `light` before any attenuation, `Φ_i / m_i` (zero before any photon was emitted).
    pub fn photon_scale(&self, light: u32) -> Rgb {
        match self.lights.get(light as usize) {
            Some(l) if l.emitted > 0 => l.power / l.emitted as f32,
            _ => Rgb::ZERO,
        }
    }

    /// The photon's power `φ = Φ_i / m_i ρ_φ` (equation 1).
    pub fn photon_power(&self, record: &HitRecord) -> Rgb {
        self.photon_scale(record.light) * record.rho
    }

    /// The records with more than one bounce, splatted by the optimised method (section 2.2.1).
    pub fn indirect(&self) -> impl Iterator<Item = &HitRecord> {
        self.records.iter().filter(|r| r.is_indirect())
    }

    /// Total power of the records at each bounce number: entry `k - 1` sums `φ` over the records with `bounce == k` (equation 1).
    pub fn power_by_bounce(&self) -> Vec<Rgb> {
        // Summed in f64 so a million photons add up to the light's power to f32 precision.
        let mut out: Vec<glam::DVec3> = Vec::new();
        for r in &self.records {
            let k = r.bounce as usize;
            if k == 0 {
                continue;
            }
            if out.len() < k {
                out.resize(k, glam::DVec3::ZERO);
            }
            out[k - 1] += self.photon_power(r).as_dvec3();
        }
        out.into_iter().map(|p| p.as_vec3()).collect()
    }

    /// Adds records of `more` photons (incremental refinement, section 2.1): the light tables must have the same powers; emitted counts add up, records are appended, earlier records are untouched.
    pub fn append(&mut self, more: PhotonMap) -> Result<()> {
        self.check_same_lights(&more.lights)?;
        for (l, m) in self.lights.iter_mut().zip(&more.lights) {
            l.emitted += m.emitted;
        }
        self.records.extend(more.records);
        Ok(())
    }

    /// Fails unless `other` has as many lights with the same powers (bit for bit).
    pub(crate) fn check_same_lights(&self, other: &[LightEmission]) -> Result<()> {
        if self.lights.len() != other.len() {
            return Err(PhotonError::LightMismatch(format!(
                "{} lights against {}",
                self.lights.len(),
                other.len()
            )));
        }
        for (i, (a, b)) in self.lights.iter().zip(other).enumerate() {
            if a.power.to_array().map(f32::to_bits) != b.power.to_array().map(f32::to_bits) {
                return Err(PhotonError::LightMismatch(format!(
                    "light #{i} has power {} against {}",
                    a.power, b.power
                )));
            }
        }
        Ok(())
    }

    /// Appends records without changing the emitted counts (a file read batch by batch).
    pub(crate) fn extend_records(&mut self, records: &[HitRecord]) {
        self.records.extend_from_slice(records);
    }

    /// Records emitted photons and appends hit records (used by the tracer).
    pub(crate) fn extend_traced(&mut self, emitted: &[u64], records: Vec<HitRecord>) {
        for (l, &m) in self.lights.iter_mut().zip(emitted) {
            l.emitted += m;
        }
        self.records.extend(records);
    }
}
