//! The Halton sequence: radical inverses in the first prime bases.
//!
//! J. H. Halton, "On the efficiency of certain quasi-random sequences of
//! points in evaluating multi-dimensional integrals", Numer. Math. 2 (1960):
//! dimension `d` of point `i` is the radical inverse of `i` in the `d`-th
//! prime (pbrt-v4, Pharr, Jakob & Humphreys, section 8.6.1). Optional
//! scrambling follows Owen's nested uniform scrambling (A. B. Owen,
//! "Randomly permuted (t,m,s)-nets and (t,s)-sequences", 1995): the
//! permutation applied to a digit depends on the seed, the dimension and all
//! more significant digits; permutations are hashed, not stored (pbrt-v4
//! section 8.6.2, `OwenScrambledRadicalInverse`), and are drawn from the
//! affine maps `x -> m x + c (mod b)` of the prime field (J. Matoušek, "On the
//! L2-discrepancy for anchored boxes", J. Complexity 14, 1998).

use super::mix_bits;
use super::pcg::ONE_MINUS_EPSILON;

/// The first 64 primes, the bases of the Halton dimensions (Halton 1960).
const PRIMES: [u32; 64] = [
    2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73, 79, 83, 89, 97,
    101, 103, 107, 109, 113, 127, 131, 137, 139, 149, 151, 157, 163, 167, 173, 179, 181, 191, 193,
    197, 199, 211, 223, 227, 229, 233, 239, 241, 251, 257, 263, 269, 271, 277, 281, 283, 293, 307,
    311,
];

/// Number of Halton dimensions available (one per tabulated prime, Halton 1960).
pub const HALTON_DIMENSIONS: usize = PRIMES.len();

/// The largest `f32` not above `v` (for `v` in `[0, 1]`), kept below one: rounding down keeps a point in its stratum.
fn f32_at_or_below(v: f64) -> f32 {
    let f = v as f32;
    let f = if f64::from(f) > v {
        f32::from_bits(f.to_bits() - 1)
    } else {
        f
    };
    f.min(ONE_MINUS_EPSILON)
}

/// The radical inverse `Φ_b(i)`: the base-`b` digits of `i` mirrored about the radix point (pbrt-v4 equation 8.19).
///
/// The result is the largest `f32` not above the exact value, so it is in
/// `[0, 1)`. Bases below 2 are treated as 2.
pub fn radical_inverse(base: u32, index: u64) -> f32 {
    let b = u64::from(base.max(2));
    let inv_base = 1.0 / b as f64;
    let mut reversed: u128 = 0;
    let mut inv_base_n = 1.0_f64;
    let mut a = index;
    while a > 0 {
        let next = a / b;
        let digit = a - next * b;
        reversed = reversed * u128::from(b) + u128::from(digit);
        inv_base_n *= inv_base;
        a = next;
    }
    f32_at_or_below(reversed as f64 * inv_base_n)
}

/// Owen-scrambled radical inverse: digit `k` goes through a permutation hashed from `seed` and the `k` digits above it (Owen 1995; pbrt-v4 section 8.6.2).
///
/// Each per-node permutation is the affine map `x -> m x + c (mod b)` with
/// `m` in `1..b` and `c` in `0..b`, a bijection because `b` must be prime
/// (Matoušek 1998). At least enough digits for 2^-32 resolution are
/// scrambled, so trailing zero digits become random too and every point lies
/// strictly inside its elementary interval.
pub fn owen_scrambled_radical_inverse(base: u32, index: u64, seed: u64) -> f32 {
    let b = u64::from(base.max(2));
    let b_wide = u128::from(b);
    let inv_base = 1.0 / b as f64;
    // Digits for a resolution of 2^-32: the smallest k with b^k >= 2^32.
    let mut min_digits = 0;
    let mut power: u128 = 1;
    while power < 1 << 32 {
        power *= b_wide;
        min_digits += 1;
    }
    let mut value = 0.0_f64;
    let mut inv_base_n = 1.0_f64;
    // The node of the scrambling tree: a leading 1 followed by the unscrambled
    // digits so far, so nodes at different depths never share a key.
    let mut node: u128 = 1;
    let mut a = index;
    let mut k = 0;
    while k < min_digits || a > 0 {
        let next = a / b;
        let digit = a - next * b;
        a = next;
        let hash = mix_bits(seed ^ mix_bits((node as u64) ^ mix_bits((node >> 64) as u64)));
        let m = 1 + (hash >> 32) % (b - 1);
        let c = (hash & 0xffff_ffff) % b;
        let scrambled = (m * digit + c) % b;
        inv_base_n *= inv_base;
        value += scrambled as f64 * inv_base_n;
        node = node * b_wide + u128::from(digit);
        k += 1;
    }
    f32_at_or_below(value)
}

/// Dimension `dim` of Halton point `index`, unscrambled: `Φ_{p_dim}(index)` (Halton 1960; pbrt-v4 section 8.6.1).
///
/// # Panics
///
/// If `dim >= HALTON_DIMENSIONS`.
pub fn halton(index: u64, dim: usize) -> f32 {
    radical_inverse(Halton::base(dim), index)
}

/// The Halton sequence, plain or Owen-scrambled with an explicit seed (Halton 1960; Owen 1995; pbrt-v4 section 8.6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Halton {
    /// The scrambling seed; `None` gives the plain sequence.
    scramble_seed: Option<u64>,
}

impl Halton {
    /// Number of dimensions (the first 64 primes, Halton 1960).
    pub const DIMENSIONS: usize = HALTON_DIMENSIONS;

    /// The plain (unscrambled) Halton sequence (Halton 1960).
    pub fn new() -> Self {
        Self {
            scramble_seed: None,
        }
    }

    /// The Owen-scrambled Halton sequence; each seed gives an independent randomisation (Owen 1995).
    pub fn scrambled(seed: u64) -> Self {
        Self {
            scramble_seed: Some(seed),
        }
    }

    /// The scrambling seed, `None` when plain.
    pub fn scramble_seed(&self) -> Option<u64> {
        self.scramble_seed
    }

    /// The prime base of dimension `dim` (Halton 1960).
    ///
    /// # Panics
    ///
    /// If `dim >= HALTON_DIMENSIONS`.
    pub fn base(dim: usize) -> u32 {
        assert!(
            dim < HALTON_DIMENSIONS,
            "Halton dimension {dim} is beyond the {HALTON_DIMENSIONS} tabulated primes"
        );
        PRIMES[dim]
    }

    /// Dimension `dim` of point `index`, in `[0, 1)` (pbrt-v4 sections 8.6.1-8.6.2).
    ///
    /// # Panics
    ///
    /// If `dim >= HALTON_DIMENSIONS`.
    pub fn sample(&self, index: u64, dim: usize) -> f32 {
        let base = Self::base(dim);
        match self.scramble_seed {
            None => radical_inverse(base, index),
            Some(seed) => {
                let dim_seed = mix_bits(seed ^ mix_bits(dim as u64 ^ 0x4a41_4c54_4f4e));
                owen_scrambled_radical_inverse(base, index, dim_seed)
            }
        }
    }
}
