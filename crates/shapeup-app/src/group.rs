//! The editor's group vocabulary: a constraint group in a document is the scene's description
//! of it ([`GroupSpec`]) plus the editor's key and role; and the shape models that make the
//! shape groups.

use glam::DVec3;
use serde_json::{Map, Value};
use shapeup_core::scene::{GroupSpec, SelectionSpec, Targets};
use std::fmt;

/// The range of group weights (the weight sliders are logarithmic over it).
pub const WEIGHT_RANGE: (f64, f64) = (1e-4, 1e4);

/// The multiplier of the soft handle [`Command::PinFreePieces`](crate::command::Command::PinFreePieces) makes: enough to make the
/// system non-singular, small enough not to fight the shape model.
pub const FREE_PIECE_WEIGHT: f64 = 1e-2;

/// The shape model of a mesh opened in the editor (the radio offers all three): isometric
/// one-rings hold a real mesh's shape on a modest drag and reach the handle, where edge springs
/// crease it. Measured (editor test, the cow: hooves held, head dragged by 0.11 of the
/// diagonal): one-rings change the dihedral angles by 9° at the 99th percentile, reach the
/// handle to 0.2 % of the drag and converge in 91 iterations (0.1 s); edge springs fold edges
/// by 90° at the 99th percentile (174° at most); strain + bending holds the shape as well (7°)
/// but lags the handle by 7 % and takes 721 iterations (26 s on the bunny, where one-rings
/// take 1.1 s).
pub const DEFAULT_SHAPE_MODEL: ShapeModel = ShapeModel::IsoOneRing;

/// How near a piece must lie to the largest one, as a fraction of the rest shape's
/// bounding-box diagonal, for opening a mesh to attach it (Attach free pieces, the user's
/// explicit choice, attaches every free piece): 1 %, the gap between a fingernail, an eye or a
/// belt and the body under it on a modelled character, below the distance between separate
/// parts of an assembly.
pub const ATTACH_GAP: f64 = 0.01;

/// The constraint type of the group Attach free pieces and opening a mesh make.
pub const ATTACHMENT_KIND: &str = "attachment";

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

/// A constraint group as the editor lists it: the scene's description of the group, with a
/// key and a role.
///
/// In a document the description is always resolved: its selection is
/// [`SelectionSpec::All`], an explicit vertex list (ascending for groups the editor makes and
/// for handles) or a face list (ascending), never a box or a sphere; a handle's targets are
/// explicit, one per listed vertex in its order (input frame). Saving a scene writes the
/// description as it is.
#[derive(Debug, Clone, PartialEq)]
pub struct Group {
    /// Stable identity.
    pub key: GroupKey,
    /// What it is for.
    pub role: GroupRole,
    /// What the group is: type, name, multiplier g, selection, targets and options, as a
    /// scene's `[[constraints]]` entry says them.
    pub spec: GroupSpec,
}

impl Group {
    /// Whether it applies to vertex `v` (for hover highlighting): listed, or a group over all
    /// vertices or faces.
    pub fn covers(&self, v: u32) -> bool {
        self.vertices().is_none_or(|list| list.contains(&(v as usize)))
    }

    /// Its vertex list; `None` for a group over all vertices or over faces.
    pub fn vertices(&self) -> Option<&[usize]> {
        match &self.spec.selection {
            SelectionSpec::Vertices(list) => Some(list),
            _ => None,
        }
    }

    /// Its face list (polygon faces of the rest mesh, ascending); `None` for a group over
    /// vertices.
    pub fn faces(&self) -> Option<&[usize]> {
        match &self.spec.selection {
            SelectionSpec::Faces(list) => Some(list),
            _ => None,
        }
    }

    /// A handle's targets (input frame), one per vertex of [`Group::vertices`] in its order;
    /// empty for other groups.
    pub fn targets(&self) -> Vec<DVec3> {
        self.spec.targets.explicit.iter().flatten().map(|&t| DVec3::from(t)).collect()
    }

    /// Moves every target of a handle to `f(target)` (input frame); nothing for other groups.
    pub(crate) fn map_targets(&mut self, f: impl Fn(DVec3) -> DVec3) {
        for t in self.spec.targets.explicit.iter_mut().flatten() {
            *t = f(DVec3::from(*t)).to_array();
        }
    }

    /// Centroid of a handle's targets (input frame); `None` for other groups.
    pub fn target_centroid(&self) -> Option<DVec3> {
        let targets = self.spec.targets.explicit.as_deref().filter(|t| !t.is_empty())?;
        Some(targets.iter().map(|&t| DVec3::from(t)).sum::<DVec3>() / targets.len() as f64)
    }
}

/// Explicit targets (input frame), one per vertex of a handle's selection in its order: how
/// the editor keeps a handle's targets.
pub fn explicit_targets(targets: impl IntoIterator<Item = DVec3>) -> Targets {
    Targets { explicit: Some(targets.into_iter().map(|t| t.to_array()).collect()), ..Targets::default() }
}

/// What a rebuild of a group's constraints depends on: everything but its name, multiplier and
/// targets.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Structure {
    key: GroupKey,
    kind: String,
    selection: SelectionSpec,
    options: Map<String, Value>,
}

impl Structure {
    /// What `group`'s constraints were built from.
    pub(crate) fn of(group: &Group) -> Structure {
        let spec = &group.spec;
        Structure {
            key: group.key,
            kind: spec.kind.clone(),
            selection: spec.selection.clone(),
            options: spec.options.clone(),
        }
    }

    /// Whether `group` still builds to the same constraints (compared in place, no copies).
    pub(crate) fn matches(&self, group: &Group) -> bool {
        let spec = &group.spec;
        self.key == group.key
            && self.kind == spec.kind
            && self.selection == spec.selection
            && self.options == spec.options
    }
}
