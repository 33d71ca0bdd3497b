//! The on-disk hit-record file (section 2.1, "Photon hits are stored on disk"; section 3.1, 21 bytes per record).
//!
//! Layout, little-endian (version 2):
//!
//! | bytes | content |
//! |---|---|
//! | 0..8 | magic `LUSTPHOT` |
//! | 8..12 | format version (`u32`, [`FORMAT_VERSION`]) |
//! | 12..16 | number of lights `L` (`u32`) |
//! | 16..20 | number of surfaces `S` (`u32`) |
//! | 20..28 | number of records `N` (`u64`) |
//! | 28..36 | seed of the photons' random streams (`u64`) |
//! | 36 | flags: bit 0 set when the seed, emission and bounce limit are known ([`Provenance`]) |
//! | 37 | emission sampling (0 random, 1 Halton, 2 Sobol') |
//! | 38 | largest number of hits per photon (`u8`) |
//! | 39 | 1 when the scene's area lights were replaced by cosine point lights of equal power (Stürzlinger & Bastos section 3), else 0 |
//! | 40..44 | fingerprint of the scene's materials and lights ([`scene_fingerprint`], `u32`) |
//! | 44.. | light table, `L` × 28 bytes: power `Φ_i` (3 × `f32`), emitted photons `m_i` (`u64`), index of the light's first photon (`u64`) |
//! | .. | surface table, `S` × 17 bytes: kind (`u8`, 0 planar, 1 curved), `u`/`v` minimum and extent (4 × `f32`) |
//! | .. | CRC-32 of all header bytes above (`u32`) |
//! | .. | `N` records of 21 bytes ([`crate::quantise`]) |
//! | last 4 | CRC-32 of the record bytes (`u32`) |
//!
//! Version 1 files (no bytes 28..40, light entries without the first index)
//! are still read, with unknown provenance and first indices 0.
//!
//! The photon power is not stored: it follows from the light table by
//! equation 1, so adding photons (incremental refinement) rewrites only the
//! header (new `m_i`, new `N`) and extends the records without touching
//! earlier ones. A light's photons in a file are those with indices
//! `first_i .. first_i + m_i` of its random streams ([`crate::emission`]), so
//! files traced in batches ([`crate::trace::batch_range`]) merge into the file
//! of one run, and a merge refuses overlapping or non-adjacent ranges.
//! Readers check the magic, the version, both checksums and the exact length
//! before decoding anything, then every record's fields, so a corrupt or
//! truncated file is an error, never half-read. Files are written and read
//! as streams ([`crate::stream`]): memory is bounded by one batch of records,
//! whatever the file's size. Every write goes to a temporary file in the
//! same directory which is synced and renamed over the target.

use std::io::Read;
use std::path::Path;

use glam::{Vec2, Vec3};

use crate::crc32::crc32;
use crate::emission::EmissionSampling;
use crate::error::{PhotonError, Result};
use crate::hit_record::{HitRecord, LightEmission, PhotonMap};
use crate::parameterisation::{SurfaceParam, SurfaceParams};
use crate::quantise::{PositionRange, RECORD_BYTES, packed_surface, unpack_record};
use crate::stream::{PhotonFileReader, PhotonFileWriter};

/// The file's first eight bytes.
pub const MAGIC: [u8; 8] = *b"LUSTPHOT";

/// The format version this build writes (it reads versions 1 and 2).
pub const FORMAT_VERSION: u32 = 2;

/// Bytes before the light table in version 1.
const FIXED_HEADER_V1: usize = 28;
/// Bytes before the light table.
const FIXED_HEADER: usize = 44;
/// Bytes per light table entry in version 1.
const LIGHT_ENTRY_V1: usize = 20;
/// Bytes per light table entry.
const LIGHT_ENTRY: usize = 28;
/// Bytes per surface table entry.
const SURFACE_ENTRY: usize = 17;

/// One entry of the file's surface table: how positions on the surface are quantised.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceEntry {
    /// Whether the surface is planar (`(u, v)` in metres) or curved (barycentrics).
    pub planar: bool,
    /// The quantisation range of its positions.
    pub range: PositionRange,
}

impl SurfaceEntry {
    /// The entry of a surface's parameterisation: a planar surface's bounds (a tiny extent where degenerate), `[0, 1]²` for curved ones.
    pub fn of(param: &SurfaceParam) -> Self {
        match param {
            SurfaceParam::Planar(frame) => {
                let extent = (frame.max - frame.min).max(Vec2::splat(1e-6));
                Self {
                    planar: true,
                    range: PositionRange {
                        min: frame.min,
                        extent,
                    },
                }
            }
            SurfaceParam::Curved => Self {
                planar: false,
                range: PositionRange::BARYCENTRIC,
            },
        }
    }

    /// Whether two entries are equal bit for bit.
    pub(crate) fn same(&self, other: &Self) -> bool {
        let bits = |e: &Self| {
            (
                e.planar,
                e.range.min.to_array().map(f32::to_bits),
                e.range.extent.to_array().map(f32::to_bits),
            )
        };
        bits(self) == bits(other)
    }
}

/// How a file's photons were traced: what must agree for two files to hold different photons of one run (section 2.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Provenance {
    /// Seed of the photons' random streams.
    pub seed: u64,
    /// Emission sampling.
    pub emission: EmissionSampling,
    /// Largest number of hits recorded per photon.
    pub max_bounces: u8,
    /// Whether the photons left cosine point lights that replaced the scene's area lights with their power (section 3: "replaced by point light sources with equivalent power for both phases"), rather than the area lights themselves.
    pub point_lights: bool,
    /// [`scene_fingerprint`] of the scene as traced: its materials and lights (the surface table covers its geometry).
    pub scene: u32,
}

/// A CRC-32 of a scene's materials (names, models, emission) and lights, as `Debug` writes them: photons traced in one scene must not be used with another of the same geometry (`cornell` and `glosbox`).
pub fn scene_fingerprint(scene: &lustre_geometry::Scene) -> u32 {
    let mut crc = crate::crc32::Crc32::new();
    for m in scene.materials() {
        crc.update(format!("{}|{:?}|{:?};", m.name, m.model, m.emission).as_bytes());
    }
    for l in scene.lights() {
        crc.update(format!("{l:?};").as_bytes());
    }
    crc.value()
}

/// The byte of an emission sampling.
fn emission_code(e: EmissionSampling) -> u8 {
    match e {
        EmissionSampling::Random => 0,
        EmissionSampling::Halton => 1,
        EmissionSampling::Sobol => 2,
    }
}

/// A photon file's header (module table).
#[derive(Debug, Clone, PartialEq)]
pub struct FileHeader {
    /// Format version of the file (1 or 2).
    pub version: u32,
    /// The light table: powers `Φ_i` and emitted counts `m_i`.
    pub lights: Vec<LightEmission>,
    /// Index of each light's first photon: the file holds photons `first_i .. first_i + m_i`.
    pub first: Vec<u64>,
    /// The surface table.
    pub surfaces: Vec<SurfaceEntry>,
    /// Number of records.
    pub records: u64,
    /// Seed, emission and bounce limit, when known.
    pub provenance: Option<Provenance>,
}

impl FileHeader {
    /// Length of the encoded header including its CRC.
    pub fn length(&self) -> usize {
        let (fixed, light) = if self.version == 1 {
            (FIXED_HEADER_V1, LIGHT_ENTRY_V1)
        } else {
            (FIXED_HEADER, LIGHT_ENTRY)
        };
        fixed + self.lights.len() * light + self.surfaces.len() * SURFACE_ENTRY + 4
    }

    /// Length of the whole file this header describes.
    pub fn file_length(&self) -> u128 {
        self.length() as u128 + self.records as u128 * RECORD_BYTES as u128 + 4
    }

    /// Total photons emitted over all lights.
    pub fn emitted(&self) -> u64 {
        self.lights.iter().map(|l| l.emitted).sum()
    }

    /// The bytes of this header in the current version (a version 1 header is written as version 2).
    pub(crate) fn encode(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(
            FIXED_HEADER
                + self.lights.len() * LIGHT_ENTRY
                + self.surfaces.len() * SURFACE_ENTRY
                + 4,
        );
        b.extend_from_slice(&MAGIC);
        b.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        b.extend_from_slice(&(self.lights.len() as u32).to_le_bytes());
        b.extend_from_slice(&(self.surfaces.len() as u32).to_le_bytes());
        b.extend_from_slice(&self.records.to_le_bytes());
        let p = self.provenance;
        b.extend_from_slice(&p.map_or(0, |p| p.seed).to_le_bytes());
        b.push(u8::from(p.is_some()));
        b.push(p.map_or(0, |p| emission_code(p.emission)));
        b.push(p.map_or(0, |p| p.max_bounces));
        b.push(p.map_or(0, |p| u8::from(p.point_lights)));
        b.extend_from_slice(&p.map_or(0, |p| p.scene).to_le_bytes());
        for (i, l) in self.lights.iter().enumerate() {
            for c in l.power.to_array() {
                b.extend_from_slice(&c.to_le_bytes());
            }
            b.extend_from_slice(&l.emitted.to_le_bytes());
            b.extend_from_slice(&self.first.get(i).copied().unwrap_or(0).to_le_bytes());
        }
        for s in &self.surfaces {
            b.push(if s.planar { 0 } else { 1 });
            for c in [
                s.range.min.x,
                s.range.min.y,
                s.range.extent.x,
                s.range.extent.y,
            ] {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        let crc = crc32(&b);
        b.extend_from_slice(&crc.to_le_bytes());
        b
    }

    /// Fails unless the file's surface table equals `scene`'s (the file was traced in this scene's pose).
    pub fn check_surfaces(&self, path: &Path, scene: &[SurfaceEntry]) -> Result<()> {
        check_surfaces(path, &self.surfaces, scene)
    }

    /// Decodes and checks one packed record (surface, light, bounce, attenuation byte); `index` names it in errors.
    pub(crate) fn decode_record(
        &self,
        path: &Path,
        index: u64,
        b: &[u8; RECORD_BYTES],
    ) -> Result<HitRecord> {
        let corrupt = |message: String| PhotonError::CorruptRecord {
            path: path.to_owned(),
            index,
            message,
        };
        let surface = packed_surface(b);
        let entry = self
            .surfaces
            .get(surface as usize)
            .ok_or_else(|| corrupt(format!("surface {surface} does not exist")))?;
        let r = unpack_record(b, entry.range);
        if r.light as usize >= self.lights.len() {
            return Err(corrupt(format!("light {} does not exist", r.light)));
        }
        if r.bounce == 0 {
            return Err(corrupt("bounce 0".into()));
        }
        let exponent = b[20];
        if b[17..20] != [0, 0, 0] && !(8..=248).contains(&exponent) {
            return Err(corrupt(format!("attenuation exponent byte {exponent}")));
        }
        Ok(r)
    }
}

/// Little-endian readers over a byte slice known to be long enough.
fn le_u32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}
fn le_u64(b: &[u8], at: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(a)
}
fn le_f32(b: &[u8], at: usize) -> f32 {
    f32::from_bits(le_u32(b, at))
}

/// Reads and checks the header at the start of `file`, whose whole length is `found` bytes (magic, version, lengths, CRC, values).
pub(crate) fn read_header(path: &Path, file: &mut impl Read, found: u64) -> Result<FileHeader> {
    let truncated = |expected: u64| PhotonError::Truncated {
        path: path.to_owned(),
        expected,
        found,
    };
    let io = |source| PhotonError::Io {
        path: path.to_owned(),
        source,
    };
    let mut bytes = vec![0u8; found.min(FIXED_HEADER as u64) as usize];
    file.read_exact(&mut bytes).map_err(io)?;
    if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != MAGIC {
        if bytes.len() < MAGIC.len() && MAGIC.starts_with(&bytes) {
            return Err(truncated(FIXED_HEADER_V1 as u64 + 8));
        }
        return Err(PhotonError::BadMagic {
            path: path.to_owned(),
        });
    }
    if bytes.len() < 12 {
        return Err(truncated(FIXED_HEADER_V1 as u64 + 8));
    }
    let version = le_u32(&bytes, 8);
    let (fixed, light_entry) = match version {
        1 => (FIXED_HEADER_V1, LIGHT_ENTRY_V1),
        2 => (FIXED_HEADER, LIGHT_ENTRY),
        _ => {
            return Err(PhotonError::UnsupportedVersion {
                path: path.to_owned(),
                found: version,
                supported: FORMAT_VERSION,
            });
        }
    };
    if bytes.len() < fixed {
        return Err(truncated(fixed as u64 + 8));
    }
    let light_count = le_u32(&bytes, 12) as u64;
    let surface_count = le_u32(&bytes, 16) as u64;
    let records = le_u64(&bytes, 20);
    let header_len =
        fixed as u64 + light_count * light_entry as u64 + surface_count * SURFACE_ENTRY as u64 + 4;
    if found < header_len {
        return Err(truncated(header_len + 4));
    }
    let header_len = header_len as usize;
    let read = bytes.len();
    bytes.resize(header_len, 0);
    file.read_exact(&mut bytes[read..]).map_err(io)?;
    let stored = le_u32(&bytes, header_len - 4);
    let computed = crc32(&bytes[..header_len - 4]);
    if stored != computed {
        return Err(PhotonError::Checksum {
            path: path.to_owned(),
            part: "header",
            stored,
            computed,
        });
    }
    let corrupt = |message: String| PhotonError::CorruptHeader {
        path: path.to_owned(),
        message,
    };
    let provenance = if version == 1 {
        None
    } else {
        let emission = match bytes[37] {
            0 => EmissionSampling::Random,
            1 => EmissionSampling::Halton,
            2 => EmissionSampling::Sobol,
            k => return Err(corrupt(format!("emission sampling {k}"))),
        };
        match (bytes[36], bytes[39]) {
            (0, _) => None,
            (1, lights @ (0 | 1)) if bytes[38] > 0 => Some(Provenance {
                seed: le_u64(&bytes, 28),
                emission,
                max_bounces: bytes[38],
                point_lights: lights == 1,
                scene: le_u32(&bytes, 40),
            }),
            (f, lights) => {
                return Err(corrupt(format!(
                    "flags {f}, bounce limit {}, light kind {lights}",
                    bytes[38]
                )));
            }
        }
    };
    let mut at = fixed;
    let mut lights = Vec::with_capacity(light_count as usize);
    let mut first = Vec::with_capacity(light_count as usize);
    for i in 0..light_count {
        let power = Vec3::new(
            le_f32(&bytes, at),
            le_f32(&bytes, at + 4),
            le_f32(&bytes, at + 8),
        );
        let emitted = le_u64(&bytes, at + 12);
        if !power.is_finite() || power.min_element() < 0.0 {
            return Err(corrupt(format!("light #{i} has power {power}")));
        }
        let start = if version == 1 {
            0
        } else {
            le_u64(&bytes, at + 20)
        };
        if start.checked_add(emitted).is_none() {
            return Err(corrupt(format!(
                "light #{i}: photons {start} + {emitted} overflow"
            )));
        }
        lights.push(LightEmission { power, emitted });
        first.push(start);
        at += light_entry;
    }
    let mut surfaces = Vec::with_capacity(surface_count as usize);
    for i in 0..surface_count {
        let planar = match bytes[at] {
            0 => true,
            1 => false,
            k => return Err(corrupt(format!("surface #{i} has kind {k}"))),
        };
        let range = PositionRange {
            min: Vec2::new(le_f32(&bytes, at + 1), le_f32(&bytes, at + 5)),
            extent: Vec2::new(le_f32(&bytes, at + 9), le_f32(&bytes, at + 13)),
        };
        if !range.is_valid() {
            return Err(corrupt(format!(
                "surface #{i} has an invalid range {range:?}"
            )));
        }
        surfaces.push(SurfaceEntry { planar, range });
        at += SURFACE_ENTRY;
    }
    Ok(FileHeader {
        version,
        lights,
        first,
        surfaces,
        records,
        provenance,
    })
}

/// The surface table of a scene's parameterisation.
pub fn surface_table(params: &SurfaceParams) -> Vec<SurfaceEntry> {
    params.all().iter().map(SurfaceEntry::of).collect()
}

/// Fails unless two surface tables are equal.
fn check_surfaces(path: &Path, file: &[SurfaceEntry], scene: &[SurfaceEntry]) -> Result<()> {
    if file.len() != scene.len() {
        return Err(PhotonError::SceneMismatch {
            path: path.to_owned(),
            message: format!(
                "{} surfaces in the file, {} in the scene",
                file.len(),
                scene.len()
            ),
        });
    }
    if let Some(i) = file.iter().zip(scene).position(|(a, b)| !a.same(b)) {
        return Err(PhotonError::SceneMismatch {
            path: path.to_owned(),
            message: format!(
                "surface #{i}: {:?} in the file, {:?} in the scene",
                file[i], scene[i]
            ),
        });
    }
    Ok(())
}

/// Writes a photon map as a new file (section 2.1), atomically; `params` are the parameterisations of the scene it was traced in. Its first photon indices are 0 and its provenance unknown (use [`PhotonFileWriter`] to record them).
pub fn write_photon_file(path: &Path, map: &PhotonMap, params: &SurfaceParams) -> Result<()> {
    let powers: Vec<_> = map.lights().iter().map(|l| l.power).collect();
    let first = vec![0; powers.len()];
    let mut writer = PhotonFileWriter::create(path, &powers, first, params, None)?;
    let emitted: Vec<u64> = map.lights().iter().map(|l| l.emitted).collect();
    writer.push(&emitted, map.records())?;
    writer.finish().map(|_| ())
}

/// Reads a whole photon file into memory (section 2.1): everything is verified before any record is returned. [`PhotonFileReader::batches`] reads it in bounded memory.
pub fn read_photon_file(path: &Path) -> Result<PhotonMap> {
    collect(PhotonFileReader::open(path)?)
}

/// Reads a whole photon file and checks that its surface table matches the scene's parameterisation.
pub fn read_photon_file_for(path: &Path, params: &SurfaceParams) -> Result<PhotonMap> {
    collect(PhotonFileReader::open_for(path, params)?)
}

/// Every record of a verified file in one map.
fn collect(reader: PhotonFileReader) -> Result<PhotonMap> {
    let mut map = PhotonMap::from_parts(reader.header().lights.clone(), Vec::new())?;
    for batch in reader.batches(1 << 20)? {
        let batch = batch?;
        map.extend_records(batch.records());
    }
    Ok(map)
}

/// Appends the photons of `more` to an existing file (incremental refinement, section 2.1): the file is verified, its emitted counts `m_i` grow by `more`'s, its records are kept byte for byte and `more`'s are added; the result replaces the file atomically. Streams the file: memory is bounded by `more`.
pub fn append_photon_file(path: &Path, more: &PhotonMap, params: &SurfaceParams) -> Result<()> {
    let mut writer = PhotonFileWriter::append(path, params)?;
    let existing = PhotonMap::from_parts(writer.header().lights.clone(), Vec::new())?;
    existing.check_same_lights(more.lights())?;
    let emitted: Vec<u64> = more.lights().iter().map(|l| l.emitted).collect();
    writer.push(&emitted, more.records())?;
    writer.finish().map(|_| ())
}
