//! The tests' and benches' random numbers: a small deterministic xorshift, so they need no
//! extra crate (benches include this file by `#[path]`).

use glam::DVec3;

/// xorshift64 state: uniform numbers in [-1, 1).
pub struct Rng(pub u64);

impl Rng {
    /// Uniform in [-1, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
    /// A vector with entries uniform in [-1, 1).
    pub fn vec3(&mut self) -> DVec3 {
        DVec3::new(self.uniform(), self.uniform(), self.uniform())
    }
}
