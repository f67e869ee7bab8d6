//! Small dense kernels for the local step (f64, on glam matrices; glam has no SVD).
//!
//! - 2×2, closed form ([`nearest_rotation2`], [`svd2`], [`clamp_singular_values2`]): triangle
//!   strain, in the plane of the current triangle.
//! - 3×3 SVD by one-sided Jacobi ([`svd3`], [`svd3_rotations`]): tet strain with strain freedom,
//!   and the fallback of the nearest rotation.
//! - The one-sided Jacobi rotation ([`jacobi_rotation`]) both SVDs apply.
//! - Forward-mode jets (`jet`) and small dense solves (`small`) for the sphere and circle fits.
//! - 3×3 nearest rotation ([`nearest_rotation3`]): scaled Newton polar iteration on a lifted
//!   matrix, falling back to the SVD ([`nearest_rotation3_svd`]); iso one-ring and tet strain.
//!
//! Each routine's doc states its formula; the tests compare them with nalgebra.

mod jacobi;
pub(crate) mod jet;
mod polar2;
pub(crate) mod small;
mod svd3;

pub use jacobi::jacobi_rotation;
pub use polar2::{Svd2, clamp_singular_values2, nearest_rotation2, svd2};
pub use svd3::{
    Svd3, cofactor, frobenius2, nearest_rotation3, nearest_rotation3_newton, nearest_rotation3_svd, svd3,
    svd3_rotations,
};

#[cfg(test)]
pub(crate) mod test_rng {
    //! The unit tests' random numbers: a small deterministic xorshift, so tests need no extra crate.
    use glam::{DVec2, DVec3};

    /// xorshift64 state.
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
        /// A 2-vector with entries uniform in [-1, 1).
        pub fn vec2(&mut self) -> DVec2 {
            DVec2::new(self.uniform(), self.uniform())
        }
    }
}
