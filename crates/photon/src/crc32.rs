//! CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320) for the photon file's checksums.
//!
//! The table-driven byte-at-a-time algorithm (Sarwate, "Computation of
//! cyclic redundancy checks via table look-up", CACM 31(8), 1988), with
//! the usual initial value and final xor of `0xFFFFFFFF`, so `crc32(b"123456789")`
//! is the standard check value `0xCBF43926`.

/// The reflected IEEE polynomial.
const POLYNOMIAL: u32 = 0xEDB8_8320;

/// The 256-entry table, built at compile time.
const TABLE: [u32; 256] = {
    let mut table = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                POLYNOMIAL ^ (c >> 1)
            } else {
                c >> 1
            };
            k += 1;
        }
        table[i] = c;
        i += 1;
    }
    table
};

/// An incremental CRC-32 (Sarwate 1988): feed bytes with [`Crc32::update`], read [`Crc32::value`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Crc32 {
    /// The running register (complemented CRC).
    state: u32,
}

impl Default for Crc32 {
    fn default() -> Self {
        Self::new()
    }
}

impl Crc32 {
    /// A CRC of no bytes.
    pub fn new() -> Self {
        Self { state: !0 }
    }

    /// Continues a CRC whose value over earlier bytes was `crc`, so appended data need not be re-read.
    pub fn resume(crc: u32) -> Self {
        Self { state: !crc }
    }

    /// Adds bytes.
    pub fn update(&mut self, bytes: &[u8]) {
        let mut c = self.state;
        for &b in bytes {
            c = TABLE[((c ^ u32::from(b)) & 0xff) as usize] ^ (c >> 8);
        }
        self.state = c;
    }

    /// The CRC of the bytes so far.
    pub fn value(&self) -> u32 {
        !self.state
    }
}

/// The CRC-32 of `bytes` (Sarwate 1988).
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut c = Crc32::new();
    c.update(bytes);
    c.value()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_value_and_resume() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
        let mut c = Crc32::resume(crc32(b"12345"));
        c.update(b"6789");
        assert_eq!(c.value(), 0xCBF4_3926);
    }
}
