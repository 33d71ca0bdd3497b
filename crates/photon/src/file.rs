//! The on-disk hit-record file (section 2.1, "Photon hits are stored on disk"; section 3.1, 21 bytes per record).
//!
//! Layout, little-endian (version 1):
//!
//! | bytes | content |
//! |---|---|
//! | 0..8 | magic `LUSTPHOT` |
//! | 8..12 | format version (`u32`, [`FORMAT_VERSION`]) |
//! | 12..16 | number of lights `L` (`u32`) |
//! | 16..20 | number of surfaces `S` (`u32`) |
//! | 20..28 | number of records `N` (`u64`) |
//! | 28.. | light table, `L` × 20 bytes: power `Φ_i` (3 × `f32`), emitted photons `m_i` (`u64`) |
//! | .. | surface table, `S` × 17 bytes: kind (`u8`, 0 planar, 1 curved), `u`/`v` minimum and extent (4 × `f32`) |
//! | .. | CRC-32 of all header bytes above (`u32`) |
//! | .. | `N` records of 21 bytes ([`crate::quantise`]) |
//! | last 4 | CRC-32 of the record bytes (`u32`) |
//!
//! The photon power is not stored: it follows from the light table by
//! equation 1, so [`append_photon_file`] adds photons by rewriting the
//! header (new `m_i`, new `N`) and extending the records without touching
//! earlier ones. Readers check the magic, the version, both checksums and
//! the exact length before decoding anything, then every record's fields,
//! so a corrupt or truncated file is an error, never half-read. Every write
//! goes to a temporary file in the same directory which is synced and
//! renamed over the target.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use crate::crc32::{Crc32, crc32};
use crate::error::{PhotonError, Result};
use crate::hit_record::{LightEmission, PhotonMap};
use crate::parameterisation::{SurfaceParam, SurfaceParams};
use crate::quantise::{PositionRange, RECORD_BYTES, pack_record, packed_surface, unpack_record};

/// The file's first eight bytes.
pub const MAGIC: [u8; 8] = *b"LUSTPHOT";

/// The format version this build reads and writes.
pub const FORMAT_VERSION: u32 = 1;

/// Bytes before the light table.
const FIXED_HEADER: usize = 28;
/// Bytes per light table entry.
const LIGHT_ENTRY: usize = 20;
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
    fn same(&self, other: &Self) -> bool {
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

/// A decoded file header.
#[derive(Debug, Clone)]
struct Header {
    /// The light table.
    lights: Vec<LightEmission>,
    /// The surface table.
    surfaces: Vec<SurfaceEntry>,
    /// Number of records.
    records: u64,
    /// Length of the header including its CRC.
    length: usize,
}

/// The bytes of a header.
fn encode_header(lights: &[LightEmission], surfaces: &[SurfaceEntry], records: u64) -> Vec<u8> {
    let mut b = Vec::with_capacity(
        FIXED_HEADER + lights.len() * LIGHT_ENTRY + surfaces.len() * SURFACE_ENTRY + 4,
    );
    b.extend_from_slice(&MAGIC);
    b.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    b.extend_from_slice(&(lights.len() as u32).to_le_bytes());
    b.extend_from_slice(&(surfaces.len() as u32).to_le_bytes());
    b.extend_from_slice(&records.to_le_bytes());
    for l in lights {
        for c in l.power.to_array() {
            b.extend_from_slice(&c.to_le_bytes());
        }
        b.extend_from_slice(&l.emitted.to_le_bytes());
    }
    for s in surfaces {
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

/// Decodes and checks the header at the start of `bytes` (magic, version, lengths, CRC, values).
fn decode_header(path: &Path, bytes: &[u8]) -> Result<Header> {
    let found = bytes.len() as u64;
    let truncated = |expected: u64| PhotonError::Truncated {
        path: path.to_owned(),
        expected,
        found,
    };
    if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != MAGIC {
        if bytes.len() < MAGIC.len() && MAGIC.starts_with(bytes) {
            return Err(truncated(FIXED_HEADER as u64 + 8));
        }
        return Err(PhotonError::BadMagic {
            path: path.to_owned(),
        });
    }
    if bytes.len() < FIXED_HEADER {
        return Err(truncated(FIXED_HEADER as u64 + 8));
    }
    let version = le_u32(bytes, 8);
    if version != FORMAT_VERSION {
        return Err(PhotonError::UnsupportedVersion {
            path: path.to_owned(),
            found: version,
            supported: FORMAT_VERSION,
        });
    }
    let light_count = le_u32(bytes, 12) as u64;
    let surface_count = le_u32(bytes, 16) as u64;
    let records = le_u64(bytes, 20);
    let header_len = FIXED_HEADER as u64
        + light_count * LIGHT_ENTRY as u64
        + surface_count * SURFACE_ENTRY as u64
        + 4;
    if found < header_len {
        return Err(truncated(header_len + 4));
    }
    let header_len = header_len as usize;
    let stored = le_u32(bytes, header_len - 4);
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
    let mut at = FIXED_HEADER;
    let mut lights = Vec::with_capacity(light_count as usize);
    for i in 0..light_count {
        let power = Vec3::new(
            le_f32(bytes, at),
            le_f32(bytes, at + 4),
            le_f32(bytes, at + 8),
        );
        let emitted = le_u64(bytes, at + 12);
        if !power.is_finite() || power.min_element() < 0.0 {
            return Err(corrupt(format!("light #{i} has power {power}")));
        }
        lights.push(LightEmission { power, emitted });
        at += LIGHT_ENTRY;
    }
    let mut surfaces = Vec::with_capacity(surface_count as usize);
    for i in 0..surface_count {
        let planar = match bytes[at] {
            0 => true,
            1 => false,
            k => return Err(corrupt(format!("surface #{i} has kind {k}"))),
        };
        let range = PositionRange {
            min: Vec2::new(le_f32(bytes, at + 1), le_f32(bytes, at + 5)),
            extent: Vec2::new(le_f32(bytes, at + 9), le_f32(bytes, at + 13)),
        };
        if !range.is_valid() {
            return Err(corrupt(format!(
                "surface #{i} has an invalid range {range:?}"
            )));
        }
        surfaces.push(SurfaceEntry { planar, range });
        at += SURFACE_ENTRY;
    }
    Ok(Header {
        lights,
        surfaces,
        records,
        length: header_len,
    })
}

/// The header of a file whose whole length and both checksums have been verified, with the records' CRC.
fn verify(path: &Path, bytes: &[u8]) -> Result<(Header, u32)> {
    let header = decode_header(path, bytes)?;
    let expected = (header.records as u128) * RECORD_BYTES as u128 + header.length as u128 + 4;
    let found = bytes.len() as u64;
    if (found as u128) < expected {
        return Err(PhotonError::Truncated {
            path: path.to_owned(),
            expected: expected.min(u64::MAX as u128) as u64,
            found,
        });
    }
    if found as u128 > expected {
        return Err(PhotonError::TrailingBytes {
            path: path.to_owned(),
            expected: expected as u64,
            found,
        });
    }
    let end = bytes.len() - 4;
    let stored = le_u32(bytes, end);
    let computed = crc32(&bytes[header.length..end]);
    if stored != computed {
        return Err(PhotonError::Checksum {
            path: path.to_owned(),
            part: "records",
            stored,
            computed,
        });
    }
    Ok((header, computed))
}

/// The surface table of a scene's parameterisation.
pub fn surface_table(params: &SurfaceParams) -> Vec<SurfaceEntry> {
    params.all().iter().map(SurfaceEntry::of).collect()
}

/// Packs every record of `map`; errors name the record that does not fit.
fn pack_all(map: &PhotonMap, params: &SurfaceParams, surfaces: &[SurfaceEntry]) -> Result<Vec<u8>> {
    let mut out = Vec::with_capacity(map.len() * RECORD_BYTES);
    for (index, r) in map.records().iter().enumerate() {
        let entry = surfaces
            .get(r.surface as usize)
            .ok_or_else(|| PhotonError::InvalidRecord {
                index,
                message: format!("surface {} does not exist", r.surface),
            })?;
        if r.triangle as usize >= params.triangle_count(r.surface) {
            return Err(PhotonError::InvalidRecord {
                index,
                message: format!("surface {} has no triangle {}", r.surface, r.triangle),
            });
        }
        if r.light as usize >= map.lights().len() {
            return Err(PhotonError::InvalidRecord {
                index,
                message: format!("light {} does not exist", r.light),
            });
        }
        let packed = pack_record(r, entry.range).map_err(|e| PhotonError::Unrepresentable {
            index,
            message: e.0,
        })?;
        out.extend_from_slice(&packed);
    }
    Ok(out)
}

/// A temporary path beside `path`, unique to this process and call.
fn temporary_path(path: &Path) -> PathBuf {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "photons".into());
    path.with_file_name(format!(".{name}.{}.{n}.tmp", std::process::id()))
}

/// Writes `parts` to a temporary file beside `path`, syncs it and renames it over `path` (DESIGN.md: no half-written file).
fn write_atomically(path: &Path, parts: &[&[u8]]) -> Result<()> {
    let tmp = temporary_path(path);
    let io = |source| PhotonError::Io {
        path: path.to_owned(),
        source,
    };
    let result = (|| -> std::io::Result<()> {
        let mut f = fs::File::create(&tmp)?;
        for p in parts {
            f.write_all(p)?;
        }
        f.sync_all()?;
        drop(f);
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result.map_err(io)
}

/// Reads a whole file, naming it on failure.
fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    fs::read(path).map_err(|source| PhotonError::Io {
        path: path.to_owned(),
        source,
    })
}

/// Writes a photon map as a new file (section 2.1), atomically; `params` are the parameterisations of the scene it was traced in.
pub fn write_photon_file(path: &Path, map: &PhotonMap, params: &SurfaceParams) -> Result<()> {
    check_table_sizes(map, params)?;
    let surfaces = surface_table(params);
    let records = pack_all(map, params, &surfaces)?;
    let header = encode_header(map.lights(), &surfaces, map.len() as u64);
    let crc = crc32(&records).to_le_bytes();
    write_atomically(path, &[&header, &records, &crc])
}

/// Fails when the light or surface table cannot be counted in 32 bits.
fn check_table_sizes(map: &PhotonMap, params: &SurfaceParams) -> Result<()> {
    if map.lights().len() > 256 {
        return Err(PhotonError::InvalidOption {
            option: "lights",
            message: format!(
                "{} lights; the record's light field holds 256",
                map.lights().len()
            ),
        });
    }
    if params.len() > crate::quantise::U24_MAX as usize + 1 {
        return Err(PhotonError::InvalidOption {
            option: "surfaces",
            message: format!(
                "{} surfaces; the record's surface field holds 2^24",
                params.len()
            ),
        });
    }
    Ok(())
}

/// Reads a photon file (section 2.1): everything is verified before any record is returned.
pub fn read_photon_file(path: &Path) -> Result<PhotonMap> {
    decode_file(path, &read_bytes(path)?, None)
}

/// Reads a photon file and checks that its surface table matches the scene's parameterisation.
pub fn read_photon_file_for(path: &Path, params: &SurfaceParams) -> Result<PhotonMap> {
    decode_file(path, &read_bytes(path)?, Some(&surface_table(params)))
}

/// Verifies a whole file, checks its surface table against `scene` when given, then decodes and checks every record.
fn decode_file(path: &Path, bytes: &[u8], scene: Option<&[SurfaceEntry]>) -> Result<PhotonMap> {
    let (header, _) = verify(path, bytes)?;
    if let Some(scene) = scene {
        check_surfaces(path, &header.surfaces, scene)?;
    }
    let mut records = Vec::with_capacity(header.records as usize);
    let body = &bytes[header.length..bytes.len() - 4];
    for (index, chunk) in body.chunks_exact(RECORD_BYTES).enumerate() {
        let mut b = [0u8; RECORD_BYTES];
        b.copy_from_slice(chunk);
        let corrupt = |message: String| PhotonError::CorruptRecord {
            path: path.to_owned(),
            index: index as u64,
            message,
        };
        let surface = packed_surface(&b);
        let entry = header
            .surfaces
            .get(surface as usize)
            .ok_or_else(|| corrupt(format!("surface {surface} does not exist")))?;
        let r = unpack_record(&b, entry.range);
        if r.light as usize >= header.lights.len() {
            return Err(corrupt(format!("light {} does not exist", r.light)));
        }
        if r.bounce == 0 {
            return Err(corrupt("bounce 0".into()));
        }
        let exponent = b[20];
        if b[17..20] != [0, 0, 0] && !(8..=248).contains(&exponent) {
            return Err(corrupt(format!("attenuation exponent byte {exponent}")));
        }
        records.push(r);
    }
    PhotonMap::from_parts(header.lights, records)
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

/// Appends the photons of `more` to an existing file (incremental refinement, section 2.1): the file is verified, its emitted counts `m_i` grow by `more`'s, its records are kept byte for byte and `more`'s are added; the result replaces the file atomically.
pub fn append_photon_file(path: &Path, more: &PhotonMap, params: &SurfaceParams) -> Result<()> {
    check_table_sizes(more, params)?;
    let bytes = read_bytes(path)?;
    let (header, records_crc) = verify(path, &bytes)?;
    let surfaces = surface_table(params);
    check_surfaces(path, &header.surfaces, &surfaces)?;
    let existing = PhotonMap::from_parts(header.lights.clone(), Vec::new())?;
    existing.check_same_lights(more.lights())?;
    let new_records = pack_all(more, params, &surfaces)?;
    let lights: Vec<LightEmission> = header
        .lights
        .iter()
        .zip(more.lights())
        .map(|(a, b)| LightEmission {
            power: a.power,
            emitted: a.emitted + b.emitted,
        })
        .collect();
    let count = header.records + more.len() as u64;
    let new_header = encode_header(&lights, &header.surfaces, count);
    let mut crc = Crc32::resume(records_crc);
    crc.update(&new_records);
    let old_records = &bytes[header.length..bytes.len() - 4];
    write_atomically(
        path,
        &[
            &new_header,
            old_records,
            &new_records,
            &crc.value().to_le_bytes(),
        ],
    )
}
