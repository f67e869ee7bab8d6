//! Rigid motions that scenes describe, beneath both the scene's handles and the colliders:
//! a fixed rotation ([`Rotate`]) and a constant turning rate ([`Spin`]).

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// A rotation about an axis (of a handle's targets, applied before their translation; of a box
/// collider).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rotate {
    /// Rotation axis (normalized on use; must be non-zero).
    pub axis: [f64; 3],
    /// Angle in degrees, right-handed about the axis.
    pub angle_deg: f64,
    /// Centre; default the centroid of the selected vertices.
    #[serde(default)]
    pub center: Option<[f64; 3]>,
}

/// A constant turning rate in dynamic mode (an extension of the contract): at time t a handle's
/// targets are the static ones turned by `deg_per_s` · t about the axis through `center` (a
/// collider's shape too).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spin {
    /// Rotation axis (normalized on use; must be non-zero).
    pub axis: [f64; 3],
    /// Turning rate in degrees per second, right-handed about the axis.
    pub deg_per_s: f64,
    /// Centre; default the centroid of the static targets.
    #[serde(default)]
    pub center: Option<[f64; 3]>,
}

impl Spin {
    /// The unit axis and the centre it turns about (default: the centroid of `targets`).
    ///
    /// # Errors
    /// A zero axis.
    pub fn pivot(&self, targets: &[DVec3]) -> Result<(DVec3, DVec3), &'static str> {
        let axis = DVec3::from(self.axis).try_normalize().ok_or("spin axis must be non-zero")?;
        let center = self
            .center
            .map(DVec3::from)
            .unwrap_or_else(|| targets.iter().copied().sum::<DVec3>() / targets.len().max(1) as f64);
        Ok((axis, center))
    }
}
