//! Constraints: the `w‖C q − p(q)‖²` terms of the ShapeUp / Projective Dynamics energy.
//!
//! A constraint type is one file in `types/`: a struct implementing [`Constraint`] (its rows of
//! C, its projection p and its element weight ω) and a unit struct implementing
//! [`ConstraintType`] (how a scene or the editor builds it on a selection), listed once in the
//! [`registry`]. Assembly, factorization, the parallel local step, energies and the editor's
//! list are generic over them.
//!
//! Layers, from the ground up: `options`, `error`, `params`, `selection` (what a group takes),
//! `contract` (the two traits), `kit/` (what several types share), `types/`, then `registry`,
//! `shape_model`, `group` and `attachment` on top. This file only names them.

mod attachment;
mod contract;
mod error;
mod group;
pub(crate) mod kit;
mod options;
mod params;
mod registry;
mod selection;
mod shape_model;
mod types;

pub use attachment::{
    DEGENERATE_FACES_GROUP, DegenerateAttachments, EdgeAttachment, attach_degenerate_vertices, degenerate_attachments,
};
pub use contract::{BuildContext, Constraint, ConstraintType, Load, RowEntry, RowSink, TypeInfo};
pub use error::ConstraintError;
pub use group::{ConstraintGroup, GroupDescription, GroupId, WeightError, build_group, check_weight, held_vertices};
pub use kit::point_set::{PointSet, Primitive};
pub use options::{OptionKind, OptionSpec, option_markdown};
pub use params::Params;
pub use registry::{build_constraints, catalogue_markdown, constraint_type, registry, type_names};
pub use selection::{Element, Selection, selects_any};
pub use shape_model::ShapeModel;
// Every type's constraint and `ConstraintType`: the list is the `types!` line of each in types/mod.rs.
pub use types::*;
