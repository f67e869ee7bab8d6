//! The group calls `_Solver` and `_Simulation` share. Groups come in as JSON text in the scene
//! contract's keys (`type`, `name`, `weight`, one selection key, targets, options), so that the
//! Python door and scene files share one parser ([`GroupSpec::from_entry`]) and one builder
//! ([`GroupSpec::build`]).

use crate::convert::points;
use crate::errors::value_error;
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;
use shapeup_core::constraints::held_vertices;
use shapeup_core::geometry::{RestGeometry, WorkingFrame};
use shapeup_core::mesh::Mesh as CoreMesh;
use shapeup_core::scene::GroupSpec;
use shapeup_core::solver::{GroupId, System};

/// Adds a group from one entry (JSON text in scene keys: the scene parser and builder) on
/// `mesh` / `rest` (user coordinates) to `system`; returns (id, name, type, constraints).
pub(crate) fn add_entry(
    system: &mut System,
    mesh: &CoreMesh,
    rest: &RestGeometry,
    entry: &str,
) -> PyResult<(u32, String, String, usize)> {
    let map: serde_json::Map<String, serde_json::Value> =
        serde_json::from_str(entry).map_err(|e| value_error(format!("bad group entry: {e}")))?;
    let spec = GroupSpec::from_entry(map).map_err(value_error)?;
    let group = spec.build(mesh, rest, &WorkingFrame::IDENTITY).map_err(value_error)?;
    let (name, kind, count) = (group.name.clone(), group.kind.to_string(), group.constraints.len());
    let id = system.add_group(group).map_err(value_error)?;
    Ok((id.0, name, kind, count))
}

pub(crate) fn held(system: &System, id: u32) -> PyResult<Vec<u32>> {
    let group = system.group(GroupId(id)).ok_or_else(|| value_error(format!("no group {id}")))?;
    Ok(held_vertices(group))
}

pub(crate) fn set_targets(system: &mut System, id: u32, targets: &PyReadonlyArray2<'_, f64>) -> PyResult<()> {
    let targets = points(targets, "targets")?;
    system.set_targets(GroupId(id), &targets).map_err(value_error)
}

pub(crate) fn set_weight(system: &mut System, id: u32, weight: f64) -> PyResult<()> {
    system.set_multiplier(GroupId(id), weight).map_err(value_error)
}

pub(crate) fn remove(system: &mut System, id: u32) -> PyResult<()> {
    system.remove_group(GroupId(id)).map(|_| ()).ok_or_else(|| value_error(format!("no group {id}")))
}
