//! The radiance-map cache file: every reflector's maps, versioned and checksummed, so the capture (the preprocessing phase, section 6) runs once per scene and lighting (Bastos et al. 1999, sections 6 and 9).
//!
//! Layout, little-endian throughout:
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `LUSTRIBR` |
//! | 4 | format version ([`CACHE_VERSION`]) |
//! | 8 | key: the caller's hash of the scene, the lighting and the settings |
//! | 4 | reflector count |
//! | per reflector | surface `u32`; plane normal and offset, centre, `u`, `v` (`f32`s); half-extents; planar resolution (2 `u32`); arc step, maximum polar angle (`f32`); map resolution (2 `u32`); map count `u32`; per map: hemisphere `u32`, polar and azimuth `f32`, then its texels, radiance as 3 half floats and depth as `f32` |
//! | 4 | CRC-32 (IEEE) of everything before it |
//!
//! Cameras are rebuilt from their reflector, planar resolution, hemisphere,
//! polar angle and azimuth, as sampling made them; quadtrees are rebuilt on
//! loading under the caller's settings. A file is written to a temporary
//! name beside the target and renamed into place, so a crash leaves no
//! half-written cache. [`read`] refuses a wrong magic, version, key,
//! length or checksum with [`IbrError::BadCache`]; a caller treats that as
//! a cache miss.

use std::io::Write;
use std::path::Path;

use glam::Vec3;
use half::f16;
use lustre_geometry::Plane;

use crate::error::{IbrError, Result};
use crate::quadtree::QuadtreeSettings;
use crate::radiance_map::RadianceMap;
use crate::reflector::Reflector;
use crate::reflector_maps::ReflectorMaps;
use crate::sampling::{SampleCamera, SamplingSettings};

/// The file's magic bytes.
pub const CACHE_MAGIC: &[u8; 8] = b"LUSTRIBR";
/// The format version this crate writes and reads.
pub const CACHE_VERSION: u32 = 1;

/// Writes `reflectors` under `key` to `path`, atomically (module documentation).
pub fn write<'a>(
    path: &Path,
    key: u64,
    reflectors: impl ExactSizeIterator<Item = &'a ReflectorMaps>,
) -> Result<()> {
    let mut b = Vec::new();
    b.extend_from_slice(CACHE_MAGIC);
    put_u32(&mut b, CACHE_VERSION);
    b.extend_from_slice(&key.to_le_bytes());
    put_u32(&mut b, reflectors.len() as u32);
    for r in reflectors {
        let f = &r.reflector;
        put_u32(&mut b, f.surface);
        put_vec3(&mut b, f.plane.normal);
        put_f32(&mut b, f.plane.offset);
        for v in [f.centre, f.u, f.v] {
            put_vec3(&mut b, v);
        }
        put_f32(&mut b, f.half_u);
        put_f32(&mut b, f.half_v);
        let s = &r.sampling;
        put_u32(&mut b, s.planar_resolution.0);
        put_u32(&mut b, s.planar_resolution.1);
        put_f32(&mut b, s.arc_step_degrees);
        put_f32(&mut b, s.max_polar_degrees);
        put_u32(&mut b, s.map_resolution.0);
        put_u32(&mut b, s.map_resolution.1);
        put_u32(&mut b, r.maps.len() as u32);
        for m in &r.maps {
            put_u32(&mut b, m.camera.hemisphere);
            put_f32(&mut b, m.camera.polar);
            put_f32(&mut b, m.camera.azimuth);
            for (rgb, z) in m.radiance.iter().zip(&m.depth) {
                for c in rgb {
                    b.extend_from_slice(&c.to_bits().to_le_bytes());
                }
                put_f32(&mut b, *z);
            }
        }
    }
    let crc = crc32fast::hash(&b);
    put_u32(&mut b, crc);
    let io = |source| IbrError::Io {
        path: path.to_owned(),
        source,
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "cache".into());
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(&b)?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io)
}

/// Reads the cache at `path` if it holds `key`, rebuilding quadtrees under `quadtree` (module documentation).
pub fn read(path: &Path, key: u64, quadtree: &QuadtreeSettings) -> Result<Vec<ReflectorMaps>> {
    let bytes = std::fs::read(path).map_err(|source| IbrError::Io {
        path: path.to_owned(),
        source,
    })?;
    let bad = |reason: String| IbrError::BadCache {
        path: path.to_owned(),
        reason,
    };
    if bytes.len() < 28 || &bytes[..8] != CACHE_MAGIC {
        return Err(bad("not a Lustre radiance-map cache".into()));
    }
    let (body, tail) = bytes.split_at(bytes.len() - 4);
    let stored = u32::from_le_bytes(tail.try_into().unwrap_or_default());
    let mut r = Reader { b: body, at: 8 };
    let version = r.u32().ok_or_else(|| bad("truncated".into()))?;
    if version != CACHE_VERSION {
        return Err(bad(format!(
            "format version {version}, this build reads {CACHE_VERSION}"
        )));
    }
    if crc32fast::hash(body) != stored {
        return Err(bad("checksum mismatch: the file is damaged".into()));
    }
    let found = r.u64().ok_or_else(|| bad("truncated".into()))?;
    if found != key {
        return Err(bad(format!(
            "made for other settings or lighting (key {found:016x}, wanted {key:016x})"
        )));
    }
    let truncated = || bad("truncated".into());
    let count = r.u32().ok_or_else(truncated)?;
    let mut out = Vec::new();
    for _ in 0..count {
        let surface = r.u32().ok_or_else(truncated)?;
        let normal = r.vec3().ok_or_else(truncated)?;
        let offset = r.f32().ok_or_else(truncated)?;
        let centre = r.vec3().ok_or_else(truncated)?;
        let u = r.vec3().ok_or_else(truncated)?;
        let v = r.vec3().ok_or_else(truncated)?;
        let half_u = r.f32().ok_or_else(truncated)?;
        let half_v = r.f32().ok_or_else(truncated)?;
        let reflector = Reflector {
            surface,
            plane: Plane { normal, offset },
            centre,
            u,
            v,
            half_u,
            half_v,
        };
        let sampling = SamplingSettings {
            planar_resolution: (
                r.u32().ok_or_else(truncated)?,
                r.u32().ok_or_else(truncated)?,
            ),
            arc_step_degrees: r.f32().ok_or_else(truncated)?,
            max_polar_degrees: r.f32().ok_or_else(truncated)?,
            map_resolution: (
                r.u32().ok_or_else(truncated)?,
                r.u32().ok_or_else(truncated)?,
            ),
        };
        sampling.validate()?;
        let elements =
            reflector.elements(sampling.planar_resolution.0, sampling.planar_resolution.1)?;
        let (w, h) = sampling.map_resolution;
        let texels = (w * h) as usize;
        let maps_len = r.u32().ok_or_else(truncated)?;
        let mut maps = Vec::new();
        for _ in 0..maps_len {
            let hemisphere = r.u32().ok_or_else(truncated)?;
            let polar = r.f32().ok_or_else(truncated)?;
            let azimuth = r.f32().ok_or_else(truncated)?;
            let element = *elements
                .get(hemisphere as usize)
                .ok_or_else(|| bad(format!("hemisphere {hemisphere} out of range")))?;
            let camera = SampleCamera::new(hemisphere, element, polar, azimuth);
            if r.b.len() - r.at < texels * 10 {
                return Err(truncated());
            }
            let mut radiance = Vec::with_capacity(texels);
            let mut depth = Vec::with_capacity(texels);
            for _ in 0..texels {
                let mut rgb = [f16::ZERO; 3];
                for c in &mut rgb {
                    *c = f16::from_bits(r.u16().ok_or_else(truncated)?);
                }
                radiance.push(rgb);
                depth.push(r.f32().ok_or_else(truncated)?);
            }
            maps.push(RadianceMap {
                camera,
                width: w,
                height: h,
                radiance,
                depth,
            });
        }
        out.push(ReflectorMaps::from_maps(
            reflector, sampling, maps, quadtree,
        )?);
    }
    if r.at != r.b.len() {
        return Err(bad(format!(
            "{} bytes after the last map",
            r.b.len() - r.at
        )));
    }
    Ok(out)
}

fn put_u32(b: &mut Vec<u8>, x: u32) {
    b.extend_from_slice(&x.to_le_bytes());
}

fn put_f32(b: &mut Vec<u8>, x: f32) {
    b.extend_from_slice(&x.to_le_bytes());
}

fn put_vec3(b: &mut Vec<u8>, v: Vec3) {
    for x in v.to_array() {
        put_f32(b, x);
    }
}

/// A cursor over the file's bytes.
struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let s = self.b.get(self.at..self.at + N)?;
        self.at += N;
        s.try_into().ok()
    }
    fn u16(&mut self) -> Option<u16> {
        self.take().map(u16::from_le_bytes)
    }
    fn u32(&mut self) -> Option<u32> {
        self.take().map(u32::from_le_bytes)
    }
    fn u64(&mut self) -> Option<u64> {
        self.take().map(u64::from_le_bytes)
    }
    fn f32(&mut self) -> Option<f32> {
        self.take().map(f32::from_le_bytes)
    }
    fn vec3(&mut self) -> Option<Vec3> {
        Some(Vec3::new(self.f32()?, self.f32()?, self.f32()?))
    }
}
