//! GPU time of each pass of a frame from timestamp queries written between the passes (where the adapter has `TIMESTAMP_QUERY_INSIDE_ENCODERS`), summed per pass name over every view and accumulation sample: the window's per-pass graph and the sidecar's `gpu_pass_ms`.

use std::sync::Mutex;

use crate::{GpuContext, MprError, Result};

/// Timestamps one frame may hold (wgpu's largest query set); spans beyond it go untimed.
pub const MAX_QUERIES: u32 = 4096;

/// The timestamp queries of a frame and the names of the spans they bound.
#[derive(Debug)]
pub struct PassTimer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    period_ns: f32,
    spans: Mutex<Vec<&'static str>>,
}

/// GPU milliseconds per pass name, in the order the passes first ran.
pub type PassTimes = Vec<(&'static str, f64)>;

impl PassTimer {
    /// A timer on `ctx`, or `None` when the device cannot write timestamps inside encoders.
    pub fn new(ctx: &GpuContext) -> Option<Self> {
        if !ctx.has_timestamps() {
            return None;
        }
        let queries = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass-timing"),
            ty: wgpu::QueryType::Timestamp,
            count: MAX_QUERIES,
        });
        let size = u64::from(MAX_QUERIES) * wgpu::QUERY_SIZE as u64;
        let resolve = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pass-timing-resolve"),
            size,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pass-timing-readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Some(Self {
            queries,
            resolve,
            readback,
            period_ns: ctx.queue.get_timestamp_period(),
            spans: Mutex::new(Vec::new()),
        })
    }

    /// Forgets the last frame's spans (called when a frame starts).
    pub fn reset(&self) {
        self.spans.lock().unwrap_or_else(|e| e.into_inner()).clear();
    }

    /// Records `f` between two timestamps named `name` (untimed once the frame's queries run out).
    pub fn span<R>(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        name: &'static str,
        f: impl FnOnce(&mut wgpu::CommandEncoder) -> R,
    ) -> R {
        let index = {
            let mut spans = self.spans.lock().unwrap_or_else(|e| e.into_inner());
            let index = 2 * spans.len() as u32;
            if index + 2 > MAX_QUERIES {
                None
            } else {
                spans.push(name);
                Some(index)
            }
        };
        let Some(index) = index else {
            return f(encoder);
        };
        encoder.write_timestamp(&self.queries, index);
        let value = f(encoder);
        encoder.write_timestamp(&self.queries, index + 1);
        value
    }

    /// Reads the last frame's spans back (waiting for the GPU) and sums them per name.
    pub fn read(&self, ctx: &GpuContext) -> Result<PassTimes> {
        let names = self.spans.lock().unwrap_or_else(|e| e.into_inner()).clone();
        if names.is_empty() {
            return Ok(Vec::new());
        }
        let count = 2 * names.len() as u32;
        let bytes = u64::from(count) * wgpu::QUERY_SIZE as u64;
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("pass-timing-resolve"),
            });
        encoder.resolve_query_set(&self.queries, 0..count, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.readback, 0, bytes);
        ctx.queue.submit([encoder.finish()]);
        let slice = self.readback.slice(..bytes);
        let (sender, receiver) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |result| {
            // The receiver outlives the wait below.
            let _ = sender.send(result);
        });
        ctx.wait()?;
        let failed = |message: String| MprError::Readback {
            what: "pass timestamps".into(),
            message,
        };
        receiver
            .recv()
            .map_err(|e| failed(e.to_string()))?
            .map_err(|e| failed(e.to_string()))?;
        let ticks: Vec<u64> = {
            let data = slice
                .get_mapped_range()
                .map_err(|e| failed(e.to_string()))?;
            data.chunks_exact(8)
                .map(|c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
                .collect()
        };
        self.readback.unmap();
        Ok(sum_spans(&names, &ticks, self.period_ns))
    }
}

/// Milliseconds per name of spans `i` bounded by `ticks[2i]` and `ticks[2i + 1]` at `period_ns` a tick, summed per name in first-seen order (a span whose end precedes its start counts zero).
pub fn sum_spans(names: &[&'static str], ticks: &[u64], period_ns: f32) -> PassTimes {
    let mut times: PassTimes = Vec::new();
    for (i, &name) in names.iter().enumerate() {
        let (Some(&start), Some(&end)) = (ticks.get(2 * i), ticks.get(2 * i + 1)) else {
            break;
        };
        let ms = end.saturating_sub(start) as f64 * f64::from(period_ns) * 1e-6;
        match times.iter_mut().find(|(n, _)| *n == name) {
            Some((_, total)) => *total += ms,
            None => times.push((name, ms)),
        }
    }
    times
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_sum_per_name_in_first_seen_order() {
        let names = ["depth", "splats", "depth", "tone map"];
        let ticks = [0, 1_000, 1_000, 5_000, 5_000, 5_500, 6_000, 6_250];
        let times = sum_spans(&names, &ticks, 2.0);
        let expected = [("depth", 0.003), ("splats", 0.008), ("tone map", 0.0005)];
        assert_eq!(times.len(), expected.len());
        for ((name, ms), (want_name, want)) in times.iter().zip(expected) {
            assert_eq!(*name, want_name);
            assert!((ms - want).abs() < 1e-12, "{name}: {ms} against {want}");
        }
        // A reversed span counts zero; missing ticks end the list.
        assert_eq!(sum_spans(&["a"], &[10, 5], 1.0), vec![("a", 0.0)]);
        let one = sum_spans(&["a", "b"], &[0, 1_000_000], 1.0);
        assert_eq!(one.len(), 1);
        assert!((one[0].1 - 1.0).abs() < 1e-12);
    }
}
