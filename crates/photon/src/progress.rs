//! Progress reporting for long particle-tracing runs (section 2.1).

/// Receives progress of [`crate::trace_photons`]; called from worker threads, so it must be `Sync`.
///
/// A closure `Fn(u64) + Sync` is a `Progress` that receives the number of
/// photons finished since its previous call. The viewer binary shows a bar
/// (indicatif) through this trait; the library does not depend on one.
pub trait Progress: Sync {
    /// Called once before tracing with the number of photons to trace.
    fn begin(&self, _total: u64) {}
    /// Called after each chunk of photons with the number just finished.
    fn advance(&self, photons: u64);
    /// Called once when tracing is done.
    fn finish(&self) {}
}

impl<F: Fn(u64) + Sync> Progress for F {
    fn advance(&self, photons: u64) {
        self(photons)
    }
}

/// A [`Progress`] that ignores every report.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn advance(&self, _photons: u64) {}
}
