//! The editor's group vocabulary: what a constraint group is in a document (key, role, kind,
//! weight, vertices or faces, targets, options) and the shape models that make the shape groups.

use glam::DVec3;
use std::fmt;
use std::sync::Arc;

/// The range of group weights (the weight sliders are logarithmic over it).
pub const WEIGHT_RANGE: (f64, f64) = (1e-4, 1e4);

/// The multiplier of the soft handle [`Command::PinFreePieces`](crate::command::Command::PinFreePieces) makes: enough to make the
/// system non-singular, small enough not to fight the shape model.
pub const FREE_PIECE_WEIGHT: f64 = 1e-2;

/// A group's identity in a [`Document`](crate::document::Document): stable while the group exists, never reused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GroupKey(pub u32);

impl fmt::Display for GroupKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "#{}", self.0)
    }
}

/// The shape-model presets live in the core (one place for the editor, the benchmarks and the
/// tests).
pub use shapeup_core::constraints::ShapeModel;

/// What a group is for in the editor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum GroupRole {
    /// Part of the shape model (over all vertices).
    Shape,
    /// A handle: a position group with targets the user drags.
    Handle,
    /// Smoothing on a selection.
    Smoothing,
    /// Any other group read from a scene (floor, strain on a part, options…), kept as is.
    Other,
}

/// A constraint group as the editor lists it.
#[derive(Debug, Clone, PartialEq)]
pub struct Group {
    /// Stable identity.
    pub key: GroupKey,
    /// Display name.
    pub name: String,
    /// What it is for.
    pub role: GroupRole,
    /// Constraint type name (`"position"`, `"bending"`, …).
    pub kind: String,
    /// Multiplier g.
    pub weight: f64,
    /// The vertices it applies to (ascending); `None` = all (or the faces', when `faces` is
    /// set).
    pub vertices: Option<Vec<u32>>,
    /// The polygon faces it applies to (ascending), for a group made on a face selection.
    pub faces: Option<Vec<u32>>,
    /// Handles: one target per vertex of `vertices`, in its order (input frame); empty
    /// otherwise.
    pub targets: Vec<DVec3>,
    /// Type options (as a scene writes them, `hard` included), shared between undo steps.
    pub options: Arc<serde_json::Map<String, serde_json::Value>>,
}

impl Group {
    /// Whether it applies to vertex `v` (for hover highlighting).
    pub fn covers(&self, v: u32) -> bool {
        self.vertices.as_ref().is_none_or(|list| list.contains(&v))
    }

    /// Its vertices, `None` meaning every vertex.
    pub fn vertices(&self) -> Option<&[u32]> {
        self.vertices.as_deref()
    }

    /// Centroid of a handle's targets (input frame); `None` for other groups.
    pub fn target_centroid(&self) -> Option<DVec3> {
        (!self.targets.is_empty()).then(|| self.targets.iter().copied().sum::<DVec3>() / self.targets.len() as f64)
    }

    /// What the system needs to rebuild when this changes (everything but name, weight and
    /// targets).
    pub(crate) fn structure(&self) -> Structure {
        (self.key, self.kind.clone(), self.vertices.clone(), self.faces.clone(), Arc::clone(&self.options))
    }
}

/// What a rebuild of a group depends on: (key, kind, vertices, faces, options).
pub(crate) type Structure =
    (GroupKey, String, Option<Vec<u32>>, Option<Vec<u32>>, Arc<serde_json::Map<String, serde_json::Value>>);
