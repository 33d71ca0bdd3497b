//! The Sobol' sequence in base 2 with Joe & Kuo's direction numbers.
//!
//! I. M. Sobol', "On the distribution of points in a cube and the approximate
//! evaluation of integrals", USSR Comput. Math. Math. Phys. 7 (1967); the
//! direction numbers are S. Joe and F. Y. Kuo's `new-joe-kuo-6.21201` table
//! ("Constructing Sobol sequences with better two-dimensional projections",
//! SIAM J. Sci. Comput. 30, 2008), dimension 0 being the van der Corput
//! sequence. Points are 32-bit: bit `k` of the index selects column `k` of a
//! per-dimension generator matrix (pbrt-v4 section 8.7.1). Optional
//! scrambling is Owen's nested uniform scramble computed by hashing (S.
//! Laine and T. Karras, "Stratified sampling for stochastic transparency",
//! 2011; B. Burley, "Practical Hash-based Owen Scrambling", JCGT 9(4), 2020).

use super::mix_bits;
use super::pcg::unit_f32_from_bits;

/// Joe & Kuo's primitive-polynomial degree `s`, coefficients `a` and initial `m_1..m_s`, for their dimensions 2 to 32 (new-joe-kuo-6.21201, lines d = 2..32).
const JOE_KUO: [(u32, u32, [u32; 7]); 31] = [
    (1, 0, [1, 0, 0, 0, 0, 0, 0]),
    (2, 1, [1, 3, 0, 0, 0, 0, 0]),
    (3, 1, [1, 3, 1, 0, 0, 0, 0]),
    (3, 2, [1, 1, 1, 0, 0, 0, 0]),
    (4, 1, [1, 1, 3, 3, 0, 0, 0]),
    (4, 4, [1, 3, 5, 13, 0, 0, 0]),
    (5, 2, [1, 1, 5, 5, 17, 0, 0]),
    (5, 4, [1, 1, 5, 5, 5, 0, 0]),
    (5, 7, [1, 1, 7, 11, 19, 0, 0]),
    (5, 11, [1, 1, 5, 1, 1, 0, 0]),
    (5, 13, [1, 1, 1, 3, 11, 0, 0]),
    (5, 14, [1, 3, 5, 5, 31, 0, 0]),
    (6, 1, [1, 3, 3, 9, 7, 49, 0]),
    (6, 13, [1, 1, 1, 15, 21, 21, 0]),
    (6, 16, [1, 3, 1, 13, 27, 49, 0]),
    (6, 19, [1, 1, 1, 15, 7, 5, 0]),
    (6, 22, [1, 3, 1, 15, 13, 25, 0]),
    (6, 25, [1, 1, 5, 5, 19, 61, 0]),
    (7, 1, [1, 3, 7, 11, 23, 15, 103]),
    (7, 4, [1, 3, 7, 13, 13, 15, 69]),
    (7, 7, [1, 1, 3, 13, 7, 35, 63]),
    (7, 8, [1, 3, 5, 9, 1, 25, 53]),
    (7, 14, [1, 3, 1, 13, 9, 35, 107]),
    (7, 19, [1, 3, 1, 5, 27, 61, 31]),
    (7, 21, [1, 1, 5, 11, 19, 41, 61]),
    (7, 28, [1, 3, 5, 3, 3, 13, 69]),
    (7, 31, [1, 1, 7, 13, 1, 19, 1]),
    (7, 32, [1, 3, 7, 5, 13, 19, 59]),
    (7, 37, [1, 1, 3, 9, 25, 29, 41]),
    (7, 41, [1, 3, 5, 13, 23, 1, 55]),
    (7, 42, [1, 3, 7, 3, 13, 59, 17]),
];

/// Number of Sobol' dimensions available: van der Corput plus Joe & Kuo's dimensions 2 to 32.
pub const SOBOL_DIMENSIONS: usize = JOE_KUO.len() + 1;

/// The 32 direction numbers `v_k = m_k / 2^k` (as 0.32 fixed point) of every dimension, from Bratley & Fox's recurrence (ACM TOMS Algorithm 659, 1988, equation for `m_k`; Joe & Kuo 2008, section 2).
const SOBOL_MATRICES: [[u32; 32]; SOBOL_DIMENSIONS] = sobol_matrices();

/// Builds [`SOBOL_MATRICES`]; `v_k = a_1 v_{k-1} ^ ... ^ a_{s-1} v_{k-s+1} ^ v_{k-s} ^ (v_{k-s} >> s)` (Joe & Kuo 2008, equation 2.3).
const fn sobol_matrices() -> [[u32; 32]; SOBOL_DIMENSIONS] {
    let mut matrices = [[0_u32; 32]; SOBOL_DIMENSIONS];
    // Dimension 0: the van der Corput sequence, v_k = 2^-k.
    let mut k = 0;
    while k < 32 {
        matrices[0][k] = 1 << (31 - k);
        k += 1;
    }
    let mut d = 1;
    while d < SOBOL_DIMENSIONS {
        let (s, a, m) = JOE_KUO[d - 1];
        let s = s as usize;
        let mut k = 0;
        while k < 32 {
            matrices[d][k] = if k < s {
                // v_{k+1} = m_{k+1} / 2^{k+1}.
                m[k] << (31 - k)
            } else {
                let older = matrices[d][k - s];
                let mut v = older ^ (older >> s);
                let mut i = 1;
                while i < s {
                    // a_i is bit (s - 1 - i) of `a`, a_1 the most significant.
                    if (a >> (s - 1 - i)) & 1 == 1 {
                        v ^= matrices[d][k - i];
                    }
                    i += 1;
                }
                v
            };
            k += 1;
        }
        d += 1;
    }
    matrices
}

/// Dimension `dim` of Sobol' point `index` as 0.32 fixed point: the XOR of the direction numbers selected by the bits of `index` (Sobol' 1967; pbrt-v4 section 8.7.1).
///
/// # Panics
///
/// If `dim >= SOBOL_DIMENSIONS`.
pub fn sobol_u32(index: u32, dim: usize) -> u32 {
    assert!(
        dim < SOBOL_DIMENSIONS,
        "Sobol' dimension {dim} is beyond the {SOBOL_DIMENSIONS} tabulated dimensions"
    );
    let matrix = &SOBOL_MATRICES[dim];
    let mut x = 0;
    let mut bits = index;
    while bits != 0 {
        x ^= matrix[bits.trailing_zeros() as usize];
        bits &= bits - 1;
    }
    x
}

/// Dimension `dim` of Sobol' point `index` in `[0, 1)`, unscrambled (Sobol' 1967; Joe & Kuo 2008).
///
/// # Panics
///
/// If `dim >= SOBOL_DIMENSIONS`.
pub fn sobol(index: u32, dim: usize) -> f32 {
    unit_f32_from_bits(sobol_u32(index, dim))
}

/// Laine & Karras's hash permutation of 32 bits, with Burley's constants: bit `k` of the result flips by a hash of bits below `k` (Burley 2020, listing 2).
fn laine_karras_permutation(x: u32, seed: u32) -> u32 {
    let mut x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Owen's nested uniform scramble of a 0.32 fixed-point value, hashed: the Laine-Karras permutation of the bit-reversed value (Burley 2020, listing 3).
///
/// Each bit is flipped by a function of `seed` and the more significant bits
/// only, so the first `2^m` points of a (t, s)-sequence in base 2 keep their
/// stratification (Owen 1995).
pub fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    laine_karras_permutation(x.reverse_bits(), seed).reverse_bits()
}

/// The Sobol' sequence, plain or Owen-scrambled with an explicit seed (Joe & Kuo 2008; Burley 2020).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Sobol {
    /// The scrambling seed; `None` gives the plain sequence.
    scramble_seed: Option<u64>,
}

impl Sobol {
    /// Number of dimensions (van der Corput plus Joe & Kuo's dimensions 2 to 32).
    pub const DIMENSIONS: usize = SOBOL_DIMENSIONS;

    /// The plain (unscrambled) Sobol' sequence (Sobol' 1967; Joe & Kuo 2008).
    pub fn new() -> Self {
        Self {
            scramble_seed: None,
        }
    }

    /// The Owen-scrambled Sobol' sequence; each seed and dimension gets its own scramble (Burley 2020, section 4).
    pub fn scrambled(seed: u64) -> Self {
        Self {
            scramble_seed: Some(seed),
        }
    }

    /// The scrambling seed, `None` when plain.
    pub fn scramble_seed(&self) -> Option<u64> {
        self.scramble_seed
    }

    /// Dimension `dim` of point `index` as 0.32 fixed point (Sobol' 1967; Burley 2020).
    ///
    /// # Panics
    ///
    /// If `dim >= SOBOL_DIMENSIONS`.
    pub fn sample_u32(&self, index: u32, dim: usize) -> u32 {
        let x = sobol_u32(index, dim);
        match self.scramble_seed {
            None => x,
            Some(seed) => {
                let dim_seed = mix_bits(seed ^ mix_bits(dim as u64 ^ 0x0053_4f42_4f4c));
                nested_uniform_scramble(x, (dim_seed >> 32) as u32)
            }
        }
    }

    /// Dimension `dim` of point `index` in `[0, 1)` (Sobol' 1967; Burley 2020).
    ///
    /// # Panics
    ///
    /// If `dim >= SOBOL_DIMENSIONS`.
    pub fn sample(&self, index: u32, dim: usize) -> f32 {
        unit_f32_from_bits(self.sample_u32(index, dim))
    }
}
