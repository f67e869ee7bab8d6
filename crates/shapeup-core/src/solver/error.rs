//! [`SolveError`]: what can go wrong in a solve, each message one line saying what to do.

use super::FactorError;

/// How far, in sizes of the start shape, a static solve with terms that are not projective may
/// carry a vertex before it is [`SolveError::RanAway`]: a minimum a million sizes away is no
/// minimum (a balloon past its limit point reaches 1e80 in a few dozen iterations).
pub const RUNAWAY: f64 = 1e6;

/// An error from the solver. Messages are one line and say what to do.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// No constraint at all.
    #[error("there are no constraints to solve (add a shape constraint and a position handle)")]
    NoConstraints,
    /// A connected piece of constrained vertices has no position-like constraint (static mode).
    #[error(
        "singular system: a connected piece of {piece_size} vertices (e.g. vertex {vertex}) has no position \
         constraint{}, so it can move freely ({num_pieces} piece(s) in all); {}",
        if *only_zero_weight { " of weight > 0 (those it has weigh 0)" } else { "" },
        if *only_zero_weight { "give its position group a weight > 0" } else { "add a position group that touches it" }
    )]
    Unanchored {
        /// Number of vertices of the piece.
        piece_size: usize,
        /// One of its vertices (original index).
        vertex: usize,
        /// Number of connected pieces.
        num_pieces: usize,
        /// Whether the piece has position-like rows, all of weight 0 (a handle turned off).
        only_zero_weight: bool,
    },
    /// The factorization found the matrix singular or indefinite.
    #[error(
        "singular system: {0}; some vertices are not held in place by the constraints (add a position \
         group, or a shape constraint over all vertices)"
    )]
    Singular(FactorError),
    /// The factorization found the matrix singular with groups lost to round-off: their only
    /// anchor (a handle) is below the last digits of the other terms where it acts.
    #[error(
        "singular system: {count} group(s) lost to round-off, their terms below the last digits of the others where they act (first: {first}); bring the weights within 1e12 of each other"
    )]
    LostToRoundOff {
        /// The first lost group, named with its weight and the group that dwarfs it.
        first: String,
        /// How many groups are lost.
        count: usize,
    },
    /// The factorization could not be built: its factor overflows 32-bit indices or memory (a
    /// mesh of millions of vertices, or constraints that couple wide neighbourhoods).
    #[error(
        "the system is too large to factor ({0}): use fewer vertices, or constraints that couple fewer \
         of them (springs or strain instead of bending)"
    )]
    TooLarge(FactorError),
    /// A static solve with terms that are not projective (a material, a pressure) carried a
    /// vertex [`RUNAWAY`] times the size of the start shape or more: the energy has no minimum.
    #[error(
        "the solve ran away (a vertex moved {factor:.1e} times the shape's size): the energy has no minimum, as for a part that nothing anchors under a load (gravity, a force, a pressure) or a pressure past the most a membrane can hold (a rubber balloon's limit point); anchor the part with a position group, or lower the load"
    )]
    RanAway {
        /// The largest displacement over the start shape's bounding-box diagonal.
        factor: f64,
    },
    /// The solve produced NaN or infinity.
    #[error("the solve produced non-finite positions (the system is numerically singular); check the weights")]
    NonFinite,
    /// The energy overflowed (targets, forces or coordinates too large for f64).
    #[error(
        "the energy is not a finite number (targets, gravity or coordinates too large); check the translations, targets and gravity"
    )]
    NonFiniteEnergy,
    /// A negative or non-finite multiplier.
    #[error("group \"{name}\": weight must be a finite number ≥ 0, found {value}")]
    BadWeight {
        /// Group name.
        name: String,
        /// The value given.
        value: f64,
    },
    /// A group id that is not (or no longer) in the system.
    #[error("no constraint group with id {0}")]
    UnknownGroup(u32),
    /// Targets for a group that is not a position group, or of the wrong count.
    #[error("group \"{name}\" {problem}")]
    BadTargets {
        /// Group name.
        name: String,
        /// What is wrong.
        problem: String,
    },
    /// A hard group of a type that cannot hold its vertices exactly.
    #[error("group \"{name}\" cannot be hard: only position groups hold their vertices exactly, not {kind}")]
    NotHardable {
        /// Group name.
        name: String,
        /// Its constraint type.
        kind: String,
    },
    /// Positions of the wrong length.
    #[error("expected {expected} positions, got {found}")]
    WrongLength {
        /// Vertices of the system.
        expected: usize,
        /// Length given.
        found: usize,
    },
}

impl SolveError {
    /// A failed factorization: a non-positive pivot is a singular system; anything else (faer's
    /// index overflow, an allocation) is a system too large, not a missing handle.
    pub(super) fn from_factor(e: FactorError) -> Self {
        match e {
            FactorError::NotPositiveDefinite(_) => SolveError::Singular(e),
            FactorError::Other(_) => SolveError::TooLarge(e),
        }
    }
}

/// [`crate::constraints::check_weight`], naming the group (or `"inertia"`, `"load scale"`) in the error.
pub(super) fn check_weight(name: &str, value: f64) -> Result<(), SolveError> {
    crate::constraints::check_weight(value).map(|_| ()).map_err(|_| SolveError::BadWeight { name: name.into(), value })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_factorization_that_cannot_be_built_is_not_called_singular() {
        let too_large = SolveError::from_factor(FactorError::Other("IndexOverflow".into())).to_string();
        assert!(too_large.starts_with("the system is too large to factor") && too_large.contains("IndexOverflow"));
        let singular = SolveError::from_factor(FactorError::NotPositiveDefinite(3)).to_string();
        assert!(singular.starts_with("singular system"), "{singular}");
    }
}
