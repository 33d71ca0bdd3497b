//! Photon files written and read as streams, in bounded memory (section 2.1: "Photon hits are stored on disk"; incremental refinement).
//!
//! [`PhotonFileWriter`] writes records batch by batch into a temporary file
//! and renames it over the target only when [`PhotonFileWriter::finish`]
//! has written the final header and checksum; [`PhotonFileReader`] verifies
//! a file's length and both checksums in one streaming pass, then hands out
//! its records in batches that end on photon boundaries (a record of
//! bounce 1 starts a photon), so a consumer that looks at a photon's whole
//! path (the virtual lights' filter of `lustre-mpr`) never sees one split.
//! [`merge_photon_files`] joins the files of one run's batches
//! ([`crate::trace::batch_range`]) into the file of the whole run.

use std::fs::{self, File};
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use lustre_geometry::Rgb;

use crate::crc32::Crc32;
use crate::error::{PhotonError, Result};
use crate::file::{FileHeader, Provenance, read_header, surface_table};
use crate::hit_record::{HitRecord, LightEmission, PhotonMap};
use crate::parameterisation::SurfaceParams;
use crate::quantise::{RECORD_BYTES, pack_record};

/// Bytes copied or checksummed per read.
const IO_CHUNK: usize = 1 << 20;

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

/// An I/O error naming `path`.
fn io_error(path: &Path) -> impl Fn(std::io::Error) -> PhotonError + '_ {
    move |source| PhotonError::Io {
        path: path.to_owned(),
        source,
    }
}

/// A photon file being written: records go to a temporary file as they come; [`PhotonFileWriter::finish`] writes the header and renames it over the target (section 2.1). Dropped unfinished, it removes its temporary file and leaves the target alone.
#[derive(Debug)]
pub struct PhotonFileWriter {
    /// The file to create or replace.
    path: PathBuf,
    /// The temporary file beside it.
    tmp: PathBuf,
    /// The temporary file, positioned after the last record.
    out: Option<BufWriter<File>>,
    /// The header so far (emitted counts and record count grow).
    header: FileHeader,
    /// Triangles per surface, to check records before packing them.
    triangles: Vec<usize>,
    /// CRC-32 of the record bytes so far.
    crc: Crc32,
}

impl PhotonFileWriter {
    /// Starts a new file for a scene's lights of `powers`, whose photons start at `first` (one per light) and were traced as `provenance` says.
    pub fn create(
        path: &Path,
        powers: &[Rgb],
        first: Vec<u64>,
        params: &SurfaceParams,
        provenance: Option<Provenance>,
    ) -> Result<Self> {
        if first.len() != powers.len() {
            return Err(PhotonError::InvalidOption {
                option: "first",
                message: format!("{} first indices for {} lights", first.len(), powers.len()),
            });
        }
        let header = FileHeader {
            version: crate::file::FORMAT_VERSION,
            lights: powers
                .iter()
                .map(|&power| LightEmission { power, emitted: 0 })
                .collect(),
            first,
            surfaces: surface_table(params),
            records: 0,
            provenance,
        };
        Self::start(path, header, params)
    }

    /// Starts a file with `header`'s tables (its record count must be 0) for records of the scene of `params`.
    fn start(path: &Path, header: FileHeader, params: &SurfaceParams) -> Result<Self> {
        let mut writer = Self::start_raw(path, header)?;
        writer.triangles = (0..params.len() as u32)
            .map(|s| params.triangle_count(s))
            .collect();
        Ok(writer)
    }

    /// Starts rewriting an existing file to add photons (incremental refinement, section 2.1): the file is verified against `params`, its records are copied byte for byte, and what [`PhotonFileWriter::push`] adds follows them; [`PhotonFileWriter::finish`] replaces the file.
    pub fn append(path: &Path, params: &SurfaceParams) -> Result<Self> {
        Self::append_from(PhotonFileReader::open_for(path, params)?, params)
    }

    /// [`PhotonFileWriter::append`] to a file already opened (and so verified) by `reader`, without reading it again; its surface table must be `params`'.
    pub fn append_from(reader: PhotonFileReader, params: &SurfaceParams) -> Result<Self> {
        reader
            .header()
            .check_surfaces(reader.path(), &surface_table(params))?;
        let mut header = reader.header().clone();
        header.version = crate::file::FORMAT_VERSION;
        header.records = 0;
        for l in &mut header.lights {
            l.emitted = 0;
        }
        let mut writer = Self::start(reader.path(), header, params)?;
        reader.copy_records(&mut writer)?;
        Ok(writer)
    }

    /// The header as it stands (light table, first indices, records written).
    pub fn header(&self) -> &FileHeader {
        &self.header
    }

    /// Adds `emitted` photons per light and their `records` (in emission order); a record that does not fit the scene or the 21-byte format is an error naming it.
    pub fn push(&mut self, emitted: &[u64], records: &[HitRecord]) -> Result<()> {
        if emitted.len() != self.header.lights.len() {
            return Err(PhotonError::LightMismatch(format!(
                "{} emitted counts for {} lights",
                emitted.len(),
                self.header.lights.len()
            )));
        }
        let mut bytes = Vec::with_capacity(records.len() * RECORD_BYTES);
        for (i, r) in records.iter().enumerate() {
            let index = (self.header.records as usize).saturating_add(i);
            let invalid = |message: String| PhotonError::InvalidRecord { index, message };
            let entry = self
                .header
                .surfaces
                .get(r.surface as usize)
                .ok_or_else(|| invalid(format!("surface {} does not exist", r.surface)))?;
            if r.triangle as usize >= self.triangles[r.surface as usize] {
                return Err(invalid(format!(
                    "surface {} has no triangle {}",
                    r.surface, r.triangle
                )));
            }
            if r.light as usize >= self.header.lights.len() {
                return Err(invalid(format!("light {} does not exist", r.light)));
            }
            let packed = pack_record(r, entry.range).map_err(|e| PhotonError::Unrepresentable {
                index,
                message: e.0,
            })?;
            bytes.extend_from_slice(&packed);
        }
        self.write_records(&bytes)?;
        for (l, &m) in self.header.lights.iter_mut().zip(emitted) {
            l.emitted = l.emitted.checked_add(m).ok_or_else(|| {
                PhotonError::LightMismatch("emitted photon count overflows".into())
            })?;
        }
        self.header.records += records.len() as u64;
        Ok(())
    }

    /// Appends packed record bytes (already checked) to the file and its checksum.
    fn write_records(&mut self, bytes: &[u8]) -> Result<()> {
        self.crc.update(bytes);
        let out = self.out.as_mut().ok_or_else(|| finished(&self.path))?;
        out.write_all(bytes).map_err(io_error(&self.path))
    }

    /// Writes the final header and the records' checksum, syncs and renames the file over its target; returns the header written.
    pub fn finish(mut self) -> Result<FileHeader> {
        let out = self.out.take().ok_or_else(|| finished(&self.path))?;
        let result = (|| -> std::io::Result<()> {
            let mut file = out.into_inner().map_err(|e| e.into_error())?;
            file.write_all(&self.crc.value().to_le_bytes())?;
            file.seek(SeekFrom::Start(0))?;
            file.write_all(&self.header.encode())?;
            file.sync_all()?;
            drop(file);
            fs::rename(&self.tmp, &self.path)
        })();
        match result {
            Ok(()) => {
                self.tmp = PathBuf::new();
                Ok(self.header.clone())
            }
            Err(e) => Err(io_error(&self.path)(e)),
        }
    }
}

/// The error of a writer used after it finished (cannot happen through the public API).
fn finished(path: &Path) -> PhotonError {
    PhotonError::Io {
        path: path.to_owned(),
        source: std::io::Error::other("the photon file writer has finished"),
    }
}

impl Drop for PhotonFileWriter {
    fn drop(&mut self) {
        if !self.tmp.as_os_str().is_empty() {
            self.out = None;
            let _ = fs::remove_file(&self.tmp);
        }
    }
}

/// A verified photon file, read as a stream (section 2.1): [`PhotonFileReader::open`] checks its length and both checksums without holding its records; [`PhotonFileReader::batches`] decodes them a batch at a time.
#[derive(Debug)]
pub struct PhotonFileReader {
    /// The file.
    path: PathBuf,
    /// Its header.
    header: FileHeader,
    /// The stored CRC-32 of its records.
    records_crc: u32,
}

impl PhotonFileReader {
    /// Opens and verifies a photon file: magic, version, header checksum, exact length, records' checksum (one streaming pass).
    pub fn open(path: &Path) -> Result<Self> {
        let io = io_error(path);
        let mut file = File::open(path).map_err(&io)?;
        let found = file.metadata().map_err(&io)?.len();
        let header = read_header(path, &mut file, found)?;
        let expected = header.file_length();
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
        let mut reader = BufReader::with_capacity(IO_CHUNK, file);
        let mut left = header.records * RECORD_BYTES as u64;
        let mut crc = Crc32::new();
        let mut buffer = vec![0u8; IO_CHUNK];
        while left > 0 {
            let n = left.min(IO_CHUNK as u64) as usize;
            reader.read_exact(&mut buffer[..n]).map_err(&io)?;
            crc.update(&buffer[..n]);
            left -= n as u64;
        }
        let mut stored = [0u8; 4];
        reader.read_exact(&mut stored).map_err(&io)?;
        let stored = u32::from_le_bytes(stored);
        if stored != crc.value() {
            return Err(PhotonError::Checksum {
                path: path.to_owned(),
                part: "records",
                stored,
                computed: crc.value(),
            });
        }
        Ok(Self {
            path: path.to_owned(),
            header,
            records_crc: stored,
        })
    }

    /// [`PhotonFileReader::open`], then checks that the file's surface table matches the scene's parameterisation.
    pub fn open_for(path: &Path, params: &SurfaceParams) -> Result<Self> {
        let reader = Self::open(path)?;
        reader.header.check_surfaces(path, &surface_table(params))?;
        Ok(reader)
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The file's header.
    pub fn header(&self) -> &FileHeader {
        &self.header
    }

    /// The file positioned at its first record.
    fn records_start(&self) -> Result<BufReader<File>> {
        let io = io_error(&self.path);
        let mut file = File::open(&self.path).map_err(&io)?;
        file.seek(SeekFrom::Start(self.header.length() as u64))
            .map_err(&io)?;
        Ok(BufReader::with_capacity(IO_CHUNK, file))
    }

    /// The records in maps of about `max_records` records each (a batch ends before the first record of a photon once it holds `max_records`), each with the file's whole light table so photon powers follow equation 1 over every photon of the file. Every record is checked; a file changed since it was verified ends the iteration with a checksum error.
    pub fn batches(&self, max_records: usize) -> Result<PhotonBatches> {
        if max_records == 0 {
            return Err(PhotonError::InvalidOption {
                option: "batch records",
                message: "0 must be at least 1".into(),
            });
        }
        Ok(PhotonBatches {
            path: self.path.clone(),
            header: self.header.clone(),
            reader: self.records_start()?,
            next: 0,
            max_records,
            pending: None,
            crc: Crc32::new(),
            stored_crc: self.records_crc,
            done: false,
        })
    }

    /// Copies the record bytes verbatim into `writer` (merging and appending), checking their checksum again on the way.
    pub(crate) fn copy_records(&self, writer: &mut PhotonFileWriter) -> Result<()> {
        let io = io_error(&self.path);
        let mut reader = self.records_start()?;
        let mut left = self.header.records * RECORD_BYTES as u64;
        let mut crc = Crc32::new();
        let mut buffer = vec![0u8; IO_CHUNK - IO_CHUNK % RECORD_BYTES];
        while left > 0 {
            let n = left.min(buffer.len() as u64) as usize;
            reader.read_exact(&mut buffer[..n]).map_err(&io)?;
            crc.update(&buffer[..n]);
            writer.write_records(&buffer[..n])?;
            left -= n as u64;
        }
        if crc.value() != self.records_crc {
            return Err(changed(&self.path, self.records_crc, crc.value()));
        }
        for (l, m) in writer.header.lights.iter_mut().zip(&self.header.lights) {
            l.emitted += m.emitted;
        }
        writer.header.records += self.header.records;
        Ok(())
    }
}

/// The error of a file whose records changed after they were verified.
fn changed(path: &Path, stored: u32, computed: u32) -> PhotonError {
    PhotonError::Checksum {
        path: path.to_owned(),
        part: "records (the file changed while it was read)",
        stored,
        computed,
    }
}

/// The records of a [`PhotonFileReader`] in batches ([`PhotonFileReader::batches`]).
#[derive(Debug)]
pub struct PhotonBatches {
    /// The file.
    path: PathBuf,
    /// Its header.
    header: FileHeader,
    /// The file after the records handed out.
    reader: BufReader<File>,
    /// Index of the next record to read.
    next: u64,
    /// Records per batch before a photon boundary ends it.
    max_records: usize,
    /// A record read past the end of the previous batch (the first of a photon).
    pending: Option<HitRecord>,
    /// CRC-32 of the record bytes read.
    crc: Crc32,
    /// The CRC-32 the file was verified with.
    stored_crc: u32,
    /// Whether the iteration has ended.
    done: bool,
}

impl PhotonBatches {
    /// The next batch: records until `max_records` and a photon boundary, or the end.
    fn read_batch(&mut self) -> Result<Vec<HitRecord>> {
        let mut records: Vec<HitRecord> = self.pending.take().into_iter().collect();
        let mut b = [0u8; RECORD_BYTES];
        while self.next < self.header.records {
            self.reader
                .read_exact(&mut b)
                .map_err(io_error(&self.path))?;
            self.crc.update(&b);
            let r = self.header.decode_record(&self.path, self.next, &b)?;
            self.next += 1;
            if records.len() >= self.max_records && r.bounce == 1 {
                self.pending = Some(r);
                return Ok(records);
            }
            records.push(r);
        }
        if self.crc.value() != self.stored_crc {
            return Err(changed(&self.path, self.stored_crc, self.crc.value()));
        }
        Ok(records)
    }
}

impl Iterator for PhotonBatches {
    type Item = Result<PhotonMap>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        match self.read_batch() {
            Ok(records) if records.is_empty() => {
                self.done = true;
                None
            }
            Ok(records) => {
                if self.pending.is_none() {
                    self.done = true;
                }
                Some(PhotonMap::from_parts(self.header.lights.clone(), records))
            }
            Err(e) => {
                self.done = true;
                Some(Err(e))
            }
        }
    }
}

/// Merges the files of one run's batches (the same scene, lights, seed, emission and bounce limit; adjacent photon ranges per light, in any order) into one file at `out` equal to the file of the whole run: light tables summed, records of the files in the order of their photon ranges. Streams every file; atomically written.
pub fn merge_photon_files(inputs: &[PathBuf], out: &Path) -> Result<FileHeader> {
    let Some(first_path) = inputs.first() else {
        return Err(PhotonError::InvalidOption {
            option: "inputs",
            message: "no photon file to merge".into(),
        });
    };
    let mut readers = inputs
        .iter()
        .map(|p| PhotonFileReader::open(p))
        .collect::<Result<Vec<_>>>()?;
    let base = readers[0].header.clone();
    let incompatible = |path: &Path, message: String| PhotonError::Incompatible {
        path: path.to_owned(),
        message,
    };
    if base.provenance.is_none() {
        return Err(incompatible(
            first_path,
            "the file does not record its seed and photon range (written by `write_photon_file` \
             or format version 1), so a merge cannot check that the files hold different photons"
                .into(),
        ));
    }
    for r in &readers[1..] {
        let h = &r.header;
        if h.surfaces.len() != base.surfaces.len()
            || h.surfaces
                .iter()
                .zip(&base.surfaces)
                .any(|(a, b)| !a.same(b))
        {
            return Err(incompatible(
                &r.path,
                format!(
                    "another scene's surface table than {}",
                    first_path.display()
                ),
            ));
        }
        let powers = |h: &FileHeader| -> Vec<[u32; 3]> {
            h.lights
                .iter()
                .map(|l| l.power.to_array().map(f32::to_bits))
                .collect()
        };
        if powers(h) != powers(&base) {
            return Err(incompatible(
                &r.path,
                format!("other lights than {}", first_path.display()),
            ));
        }
        if h.provenance != base.provenance {
            return Err(incompatible(
                &r.path,
                format!(
                    "traced as {:?}, {} as {:?}",
                    h.provenance,
                    first_path.display(),
                    base.provenance
                ),
            ));
        }
    }
    // Order by photon ranges; per light they must tile one range.
    readers.sort_by_key(|r| r.header.first.clone());
    let lights = base.lights.len();
    let mut first = vec![0u64; lights];
    for (light, start) in first.iter_mut().enumerate() {
        let mut ranges: Vec<(u64, u64, &Path)> = readers
            .iter()
            .map(|r| {
                let s = r.header.first[light];
                (s, s + r.header.lights[light].emitted, r.path.as_path())
            })
            .filter(|&(s, e, _)| e > s)
            .collect();
        ranges.sort_unstable();
        *start = ranges.first().map_or(0, |r| r.0);
        for pair in ranges.windows(2) {
            let ((_, end, a), (s, _, b)) = (pair[0], pair[1]);
            if s != end {
                let what = if s < end { "overlap" } else { "leave a gap" };
                return Err(incompatible(
                    b,
                    format!(
                        "light #{light}: its photons from {s} and those of {} ending at {end} \
                         {what}; merge the batches of one run (`--batch I/N` with the same N)",
                        a.display()
                    ),
                ));
            }
        }
    }
    let header = FileHeader {
        version: crate::file::FORMAT_VERSION,
        lights: base
            .lights
            .iter()
            .map(|l| LightEmission {
                power: l.power,
                emitted: 0,
            })
            .collect(),
        first,
        surfaces: base.surfaces.clone(),
        records: 0,
        provenance: base.provenance,
    };
    let mut writer = PhotonFileWriter::start_raw(out, header)?;
    for r in &readers {
        r.copy_records(&mut writer)?;
    }
    writer.finish()
}

impl PhotonFileWriter {
    /// A writer for raw record copies only (merging), without a scene: [`PhotonFileWriter::push`] refuses every record (no surface has a triangle).
    fn start_raw(path: &Path, header: FileHeader) -> Result<Self> {
        if header.lights.len() > 256 {
            return Err(PhotonError::InvalidOption {
                option: "lights",
                message: format!(
                    "{} lights; the record's light field holds 256",
                    header.lights.len()
                ),
            });
        }
        if header.surfaces.len() > crate::quantise::U24_MAX as usize + 1 {
            return Err(PhotonError::InvalidOption {
                option: "surfaces",
                message: format!(
                    "{} surfaces; the record's surface field holds 2^24",
                    header.surfaces.len()
                ),
            });
        }
        let tmp = temporary_path(path);
        let file = File::create(&tmp).map_err(io_error(path))?;
        let mut out = BufWriter::with_capacity(IO_CHUNK, file);
        let placeholder = vec![0u8; header.length()];
        let mut writer = Self {
            path: path.to_owned(),
            tmp,
            out: None,
            triangles: vec![0; header.surfaces.len()],
            header,
            crc: Crc32::new(),
        };
        out.write_all(&placeholder).map_err(io_error(path))?;
        writer.out = Some(out);
        Ok(writer)
    }
}
