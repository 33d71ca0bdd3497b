//! Random and low-discrepancy sampling, warps to directions and areas, frames.
//!
//! Every random choice in Lustre comes from a generator seeded explicitly
//! (DESIGN.md, "Conventions"): [`Pcg32`] for independent random numbers,
//! [`Halton`] and [`Sobol`] for low-discrepancy points, each optionally
//! Owen-scrambled with an explicit seed. The [`Sampler`] trait lets a caller
//! draw 1D and 2D samples from any of them; a [`SequenceSampler`] walks a
//! low-discrepancy sequence point by point and dimension by dimension.
//!
//! ```
//! use lustre_geometry::sampling::{
//!     Pcg32, Sampler, SequenceSampler, Sobol, sample_cosine_hemisphere,
//! };
//!
//! fn direction(sampler: &mut impl Sampler) -> glam::Vec3 {
//!     sample_cosine_hemisphere(sampler.next_2d())
//! }
//!
//! let mut rng = Pcg32::new(7, 0);
//! let mut sobol = SequenceSampler::new(Sobol::scrambled(7), 7);
//! sobol.start_point(3);
//! assert!(direction(&mut rng).z >= 0.0);
//! assert!(direction(&mut sobol).z >= 0.0);
//! ```

mod frame;
mod halton;
mod pcg;
mod sobol;
mod warp;

use glam::Vec2;

pub use frame::Frame;
pub use halton::{
    HALTON_DIMENSIONS, Halton, halton, owen_scrambled_radical_inverse, radical_inverse,
};
pub use pcg::{ONE_MINUS_EPSILON, Pcg32, unit_f32_from_bits};
pub use sobol::{SOBOL_DIMENSIONS, Sobol, nested_uniform_scramble, sobol, sobol_u32};
pub use warp::*;

/// A 64-bit finaliser that spreads every input bit over the output (Steele, Lea & Flood, "Fast Splittable Pseudorandom Number Generators", OOPSLA 2014, SplitMix64 `mix64`).
pub(crate) fn mix_bits(mut v: u64) -> u64 {
    v = (v ^ (v >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    v = (v ^ (v >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    v ^ (v >> 31)
}

/// A source of uniform samples in `[0, 1)`, drawn one or two dimensions at a time (pbrt-v4 section 8.3, `Sampler::Get1D`/`Get2D`).
///
/// Implemented by [`Pcg32`] (independent samples) and by
/// [`SequenceSampler`] over [`Halton`] or [`Sobol`] (low-discrepancy
/// samples). Warps such as [`sample_cosine_hemisphere`] take the `Vec2` that
/// [`Sampler::next_2d`] returns.
pub trait Sampler {
    /// The next sample dimension, in `[0, 1)`.
    fn next_1d(&mut self) -> f32;

    /// The next two sample dimensions as a point of `[0, 1)^2`, x first.
    fn next_2d(&mut self) -> Vec2 {
        let x = self.next_1d();
        let y = self.next_1d();
        Vec2::new(x, y)
    }
}

impl Sampler for Pcg32 {
    fn next_1d(&mut self) -> f32 {
        self.next_f32()
    }

    fn next_2d(&mut self) -> Vec2 {
        self.next_vec2()
    }
}

/// A low-discrepancy sequence addressed by point index and dimension (pbrt-v4 sections 8.6-8.7).
pub trait LowDiscrepancySequence {
    /// How many dimensions the sequence defines.
    fn dimensions(&self) -> usize;

    /// Dimension `dim < self.dimensions()` of point `index`, in `[0, 1)`.
    fn sample(&self, index: u64, dim: usize) -> f32;
}

impl LowDiscrepancySequence for Halton {
    fn dimensions(&self) -> usize {
        Halton::DIMENSIONS
    }

    fn sample(&self, index: u64, dim: usize) -> f32 {
        Halton::sample(self, index, dim)
    }
}

impl LowDiscrepancySequence for Sobol {
    fn dimensions(&self) -> usize {
        Sobol::DIMENSIONS
    }

    /// The sequence is 32-bit: `index` is taken modulo 2^32.
    fn sample(&self, index: u64, dim: usize) -> f32 {
        Sobol::sample(self, index as u32, dim)
    }
}

/// Walks a low-discrepancy sequence one point at a time, handing out its dimensions in order and padding with seeded [`Pcg32`] numbers past the last one (pbrt-v4 section 8.3, the `StartPixelSample`/`Get1D` protocol).
#[derive(Debug, Clone)]
pub struct SequenceSampler<S> {
    /// The sequence.
    sequence: S,
    /// The seed of the padding generator.
    seed: u64,
    /// The current point.
    index: u64,
    /// The next dimension to hand out.
    dimension: usize,
    /// Independent numbers for dimensions beyond the sequence's.
    padding: Pcg32,
}

impl<S: LowDiscrepancySequence> SequenceSampler<S> {
    /// A sampler at point 0 of `sequence`; `seed` seeds the padding dimensions (pbrt-v4 section 8.3).
    pub fn new(sequence: S, seed: u64) -> Self {
        Self {
            padding: Self::padding_for(seed, 0),
            sequence,
            seed,
            index: 0,
            dimension: 0,
        }
    }

    /// The padding generator of point `index`: stream `seed`, position hashed from `index`.
    fn padding_for(seed: u64, index: u64) -> Pcg32 {
        Pcg32::new(mix_bits(index), seed)
    }

    /// Moves to point `index` and back to its dimension 0 (pbrt-v4 section 8.3, `StartPixelSample`).
    pub fn start_point(&mut self, index: u64) {
        self.index = index;
        self.dimension = 0;
        self.padding = Self::padding_for(self.seed, index);
    }

    /// The current point's index.
    pub fn index(&self) -> u64 {
        self.index
    }

    /// The next dimension [`Sampler::next_1d`] will hand out.
    pub fn dimension(&self) -> usize {
        self.dimension
    }

    /// The sequence being walked.
    pub fn sequence(&self) -> &S {
        &self.sequence
    }
}

impl<S: LowDiscrepancySequence> Sampler for SequenceSampler<S> {
    fn next_1d(&mut self) -> f32 {
        let dim = self.dimension;
        self.dimension += 1;
        if dim < self.sequence.dimensions() {
            self.sequence.sample(self.index, dim)
        } else {
            self.padding.next_f32()
        }
    }
}
