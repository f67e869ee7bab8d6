//! The group calls `_Solver` and `_Simulation` share. Groups come in as JSON text in the scene
//! contract's keys (`type`, `name`, `weight`, targets, options; the selection as its own object
//! of selection keys), so that the Python door and scene files share one parser, one naming
//! rule and one weight check ([`GroupSpec::from_entry_among`]) and one builder
//! ([`GroupSpec::build`]).

use crate::convert::points;
use crate::errors::value_error;
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;
use serde_json::{Map, Value};
use shapeup_core::constraints::held_vertices;
use shapeup_core::geometry::{RestGeometry, WorkingFrame};
use shapeup_core::mesh::Mesh as CoreMesh;
use shapeup_core::scene::{GroupSpec, SelectionSpec};
use shapeup_core::solver::{GroupId, System};

/// Adds a group to `system` on `mesh` / `rest` (user coordinates) from `entry` (JSON text in
/// scene keys) and `selection` (JSON text: an object holding at most the selection keys,
/// vertices, faces, box, sphere or physical; `{}` for every vertex). The group is named among the groups
/// already in `system`: `type`, else `type_2`, `type_3`…; a given name must be new. Returns
/// (id, name, type, constraints).
///
/// # Errors
/// `ValueError` for bad JSON, a key of `selection` that selects nothing or that `entry` gives
/// too, and whatever the scene parser and builder refuse (naming the key).
pub(crate) fn add_entry(
    system: &mut System,
    mesh: &CoreMesh,
    rest: &RestGeometry,
    physical_groups: &[shapeup_core::io::PhysicalGroup],
    entry: &str,
    selection: &str,
) -> PyResult<(u32, String, String, usize)> {
    let mut map: Map<String, Value> =
        shapeup_core::scene::from_json_entry(entry).map_err(|e| value_error(format!("bad group entry: {e}")))?;
    let selection: Map<String, Value> = shapeup_core::scene::from_json_entry(selection)
        .map_err(|e| value_error(format!("bad group selection: {e}")))?;
    for (key, value) in selection {
        if !SelectionSpec::KEYS.contains(&key.as_str()) {
            let keys = SelectionSpec::KEYS.join(", ");
            return Err(value_error(format!("unknown selection key '{key}' (one of: {keys})")));
        }
        if map.contains_key(&key) {
            return Err(value_error(format!("{key} given twice")));
        }
        map.insert(key, value);
    }
    let existing: Vec<&str> = system.groups().map(|(_, g)| g.name.as_str()).collect();
    let mut spec = GroupSpec::from_entry_among(map, &existing).map_err(value_error)?;
    // `physical="NAME"`: a group of the .msh file the mesh was read from.
    spec.selection =
        spec.selection.with_physical_groups(physical_groups, std::path::Path::new("the mesh")).map_err(value_error)?;
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
