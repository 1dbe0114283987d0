//! A stable 64-bit hash (FNV-1a) for fingerprints and checksums that must
//! read the same across Rust versions, platforms and processes (campaign
//! journals, FMU state bytes, instance tags), unlike `DefaultHasher`. It is
//! not collision resistant against an adversary; it catches accidents (a
//! changed input, a corrupted byte).

use std::fmt;

/// 64-bit FNV-1a, a hash fixed by its specification (stable across Rust
/// versions, platforms and processes, unlike `DefaultHasher`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fnv1a(u64);

impl Default for Fnv1a {
    fn default() -> Self {
        Self::new()
    }
}

impl Fnv1a {
    const OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0000_0100_0000_01b3;

    pub fn new() -> Self {
        Fnv1a(Self::OFFSET)
    }
    /// Raw bytes.
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(Self::PRIME);
        }
    }
    /// Length-prefixed text, so that `("ab","c")` and `("a","bc")` differ.
    pub fn write_str(&mut self, s: &str) {
        self.write(&(s.len() as u64).to_le_bytes());
        self.write(s.as_bytes());
    }
    /// A float by its exact bit pattern.
    pub fn write_f64(&mut self, x: f64) {
        self.write(&x.to_bits().to_le_bytes());
    }
    pub fn write_u64(&mut self, x: u64) {
        self.write(&x.to_le_bytes());
    }
    pub fn finish(&self) -> Fingerprint {
        Fingerprint(self.0)
    }
}

/// A stable 64-bit fingerprint, shown as 16 hex digits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Fingerprint(pub u64);

impl fmt::Display for Fingerprint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:016x}", self.0)
    }
}
