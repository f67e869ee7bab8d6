//! Small dense kernels for the local step (f64, on glam matrices; glam has no SVD).
//!
//! - 2×2, closed form ([`nearest_rotation2`], [`svd2`], [`clamp_singular_values2`]): triangle
//!   strain, in the plane of the current triangle.
//! - 3×3 SVD by one-sided Jacobi ([`svd3`], [`svd3_rotations`]): tet strain with strain freedom,
//!   and the fallback of the nearest rotation.
//! - 3×3 nearest rotation ([`nearest_rotation3`]): scaled Newton polar iteration on a lifted
//!   matrix, falling back to the SVD ([`nearest_rotation3_svd`]); iso one-ring and tet strain.
//!
//! Each routine's doc states its formula; the tests compare them with nalgebra.

mod polar2;
mod svd3;

pub use polar2::{Svd2, clamp_singular_values2, nearest_rotation2, svd2};
pub use svd3::{
    Svd3, cofactor, frobenius2, nearest_rotation3, nearest_rotation3_newton, nearest_rotation3_svd, svd3,
    svd3_rotations,
};

#[cfg(test)]
pub(crate) mod test_rng {
    //! The tests' random numbers (the constraints' xorshift, plus 2-vectors).
    pub use crate::constraints::test_util::Rng;
    use glam::DVec2;

    impl Rng {
        /// A 2-vector with entries uniform in [-1, 1).
        pub fn vec2(&mut self) -> DVec2 {
            DVec2::new(self.uniform(), self.uniform())
        }
    }
}
