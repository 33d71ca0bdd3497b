//! O'Neill's PCG-XSH-RR 64/32 pseudo-random generator.
//!
//! M. E. O'Neill, "PCG: A Family of Simple Fast Space-Efficient Statistically
//! Good Algorithms for Random Number Generation", Harvey Mudd College
//! HMC-CS-2014-0905 (2014): a 64-bit linear congruential generator (section
//! 4.1) whose state is permuted into 32 output bits by a xorshift followed by
//! a random rotation (section 6.3.1, "XSH RR"). Every odd increment selects
//! one of 2^63 distinct streams of period 2^64; [`Pcg32::advance`] jumps
//! along a stream in O(log n) steps (Brown, "Random Number Generation with
//! Arbitrary Strides", Trans. Am. Nucl. Soc. 1994), which is how parallel
//! workers take disjoint, deterministic substreams.

use glam::Vec2;

/// The LCG multiplier of PCG's 64-bit generators (O'Neill 2014, section 4.2.1).
const MULTIPLIER: u64 = 6_364_136_223_846_793_005;

/// A PCG32 generator (O'Neill 2014, PCG-XSH-RR 64/32): 64-bit state, one stream per odd increment.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Pcg32 {
    /// The LCG state.
    state: u64,
    /// The LCG increment; always odd, it names the stream.
    increment: u64,
}

/// Largest `f32` below one, `1 - 2^-24` (pbrt-v4 `OneMinusEpsilon`, section B.2.2).
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// Maps 32 random bits to `[0, 1)`: the top 24 bits over 2^24, so every value is exact and below one (pbrt-v4 section B.2.2).
pub fn unit_f32_from_bits(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

impl Pcg32 {
    /// A generator at position `seed` of stream `stream`, seeded as the reference `pcg32_srandom_r` (O'Neill 2014, section 4.3.2).
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut rng = Self {
            state: 0,
            increment: (stream << 1) | 1,
        };
        rng.step();
        rng.state = rng.state.wrapping_add(seed);
        rng.step();
        rng
    }

    /// One LCG step, `state <- a * state + c` (O'Neill 2014, equation 4.1).
    fn step(&mut self) {
        self.state = self
            .state
            .wrapping_mul(MULTIPLIER)
            .wrapping_add(self.increment);
    }

    /// The next 32 random bits: XSH-RR output of the pre-step state (O'Neill 2014, section 6.3.1).
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.step();
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rotation = (old >> 59) as u32;
        xorshifted.rotate_right(rotation)
    }

    /// A uniform float in `[0, 1)`, never 1.0 (24 random bits, [`unit_f32_from_bits`]).
    pub fn next_f32(&mut self) -> f32 {
        unit_f32_from_bits(self.next_u32())
    }

    /// A uniform point in `[0, 1)^2`: two consecutive [`Pcg32::next_f32`] draws, x first.
    pub fn next_vec2(&mut self) -> Vec2 {
        let x = self.next_f32();
        let y = self.next_f32();
        Vec2::new(x, y)
    }

    /// Jumps `delta` draws ahead in O(log delta) (Brown 1994; O'Neill 2014, section 4.3.1); `delta.wrapping_neg()` goes back.
    ///
    /// Worker `k` of a parallel job that needs at most `n` draws can take
    /// `Pcg32::new(seed, stream)` advanced by `k * n`: the substreams are
    /// disjoint and do not depend on scheduling.
    pub fn advance(&mut self, delta: u64) {
        // Compose `delta` LCG steps into one affine map x -> mult * x + plus by
        // repeated squaring of the single-step map (a, c).
        let mut mult_acc: u64 = 1;
        let mut plus_acc: u64 = 0;
        let mut mult = MULTIPLIER;
        let mut plus = self.increment;
        let mut remaining = delta;
        while remaining > 0 {
            if remaining & 1 == 1 {
                mult_acc = mult_acc.wrapping_mul(mult);
                plus_acc = plus_acc.wrapping_mul(mult).wrapping_add(plus);
            }
            plus = mult.wrapping_add(1).wrapping_mul(plus);
            mult = mult.wrapping_mul(mult);
            remaining >>= 1;
        }
        self.state = mult_acc.wrapping_mul(self.state).wrapping_add(plus_acc);
    }

    /// A copy of this generator advanced by `delta` draws (see [`Pcg32::advance`]).
    pub fn advanced(&self, delta: u64) -> Self {
        let mut rng = self.clone();
        rng.advance(delta);
        rng
    }
}
