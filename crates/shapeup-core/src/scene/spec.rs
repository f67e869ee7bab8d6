//! What one `[[constraints]]` entry says: its selection, targets and options ([`GroupSpec`]),
//! and how it resolves against a mesh.

use crate::constraints::{ConstraintError, GroupDescription, Params, Selection, build_group, constraint_type};
use crate::geometry::{RestGeometry, WorkingFrame};
use crate::mesh::Mesh;
use crate::solver::ConstraintGroup;
use glam::DVec3;
use serde::Deserialize;
use serde_json::{Map, Value};

pub use crate::motion::{Rotate, Spin};

/// Why a group entry cannot be read, or resolved against a mesh. Each message is one line
/// naming the key or the index.
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    /// A bad key, value, selection or targets list, described.
    #[error("{0}")]
    Invalid(String),
    /// The constraint type or its builder refused (unknown type, bad option, nothing selected…).
    #[error(transparent)]
    Constraint(#[from] ConstraintError),
}

impl From<String> for SpecError {
    fn from(message: String) -> Self {
        SpecError::Invalid(message)
    }
}

impl From<&str> for SpecError {
    fn from(message: &str) -> Self {
        SpecError::Invalid(message.into())
    }
}

/// Which vertices a group applies to (coordinates in the input frame).
#[derive(Debug, Clone, PartialEq)]
pub enum SelectionSpec {
    /// Every vertex.
    All,
    /// Listed vertex indices (0-based, file order).
    Vertices(Vec<usize>),
    /// Listed polygon faces (0-based, file order): face constraints act on them, vertex
    /// constraints on their corners.
    Faces(Vec<usize>),
    /// Vertices inside an axis-aligned box (bounds included).
    Box {
        /// Lower corner.
        min: [f64; 3],
        /// Upper corner.
        max: [f64; 3],
    },
    /// The vertices of a `.msh` mesh's physical group, by its name (or, for an unnamed group,
    /// its tag as text): resolved when the scene loads its mesh ([`crate::scene::Scene::load`]).
    Physical(String),
    /// Vertices inside a ball (boundary included).
    Sphere {
        /// Centre.
        center: [f64; 3],
        /// Radius.
        radius: f64,
    },
}

impl SelectionSpec {
    /// This selection with `physical = "NAME"` replaced by the vertices (ascending) of the
    /// physical groups of `groups` named NAME, or unnamed with tag NAME (groups of one name in
    /// several dimensions are joined); any other selection as it is. `mesh` names the file in
    /// errors.
    ///
    /// # Errors
    /// No such group (the message lists the mesh's), or one without vertices.
    pub fn with_physical_groups(
        &self,
        groups: &[crate::io::PhysicalGroup],
        mesh: &std::path::Path,
    ) -> Result<SelectionSpec, SpecError> {
        let SelectionSpec::Physical(name) = self else { return Ok(self.clone()) };
        let matching: Vec<&crate::io::PhysicalGroup> =
            groups.iter().filter(|g| g.label() == *name || g.tag.to_string() == *name).collect();
        if matching.is_empty() {
            let known: Vec<String> = groups.iter().map(|g| format!("\"{}\"", g.label())).collect();
            let has = if known.is_empty() {
                format!(
                    "{} has none (physical groups come from a .msh file's $PhysicalNames and element tags)",
                    mesh.display()
                )
            } else {
                format!("{} has {}", mesh.display(), known.join(", "))
            };
            return Err(SpecError::Invalid(format!("no physical group \"{name}\": {has}")));
        }
        let mut vertices: Vec<usize> = matching.iter().flat_map(|g| g.vertices.iter().map(|&v| v as usize)).collect();
        vertices.sort_unstable();
        vertices.dedup();
        if vertices.is_empty() {
            return Err(SpecError::Invalid(format!(
                "physical group \"{name}\" has no elements, so no vertices to select"
            )));
        }
        Ok(SelectionSpec::Vertices(vertices))
    }

    /// The keys of a scene entry that give its selection (an entry has at most one).
    pub const KEYS: [&'static str; 5] = SELECTION_KEYS;

    /// The vertex indices it picks among `positions` (input frame): every vertex for
    /// [`SelectionSpec::All`], the listed order for a list, ascending for a box or sphere.
    ///
    /// # Errors
    /// A listed index out of range, as a one-line message naming it.
    pub fn resolve(&self, positions: &[glam::DVec3]) -> Result<Vec<usize>, SpecError> {
        let n = positions.len();
        let inside = |f: &dyn Fn(glam::DVec3) -> bool| (0..n).filter(|&i| f(positions[i])).collect();
        Ok(match self {
            SelectionSpec::All => (0..n).collect(),
            SelectionSpec::Vertices(list) => {
                if let Some(&v) = list.iter().find(|&&v| v >= n) {
                    return Err(SpecError::Invalid(format!(
                        "vertex {v} is out of range (the mesh has {n} vertices: 0..{})",
                        n.saturating_sub(1)
                    )));
                }
                list.clone()
            }
            SelectionSpec::Faces(_) => {
                return Err("a face selection needs the mesh's faces: use scene::resolve_selection".into());
            }
            SelectionSpec::Physical(name) => {
                return Err(SpecError::Invalid(format!(
                    "\"physical\" = \"{name}\" needs the physical groups of a .msh mesh (it selects a group's vertices when a scene loads its mesh)"
                )));
            }
            SelectionSpec::Box { min, max } => {
                let (lo, hi) = (glam::DVec3::from(*min), glam::DVec3::from(*max));
                inside(&|p| p.cmpge(lo).all() && p.cmple(hi).all())
            }
            SelectionSpec::Sphere { center, radius } => {
                let c = glam::DVec3::from(*center);
                inside(&|p| (p - c).length() <= *radius)
            }
        })
    }
}

/// Where a position group's vertices should go (input frame).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Targets {
    /// Targets = rest (rotated) + translate.
    pub translate: [f64; 3],
    /// Optional rotation of the rest positions, applied first.
    pub rotate: Option<Rotate>,
    /// Explicit targets, one per selected vertex (overrides translate and rotate).
    pub explicit: Option<Vec<[f64; 3]>>,
    /// Dynamic mode: the targets turn at a constant rate (see [`Spin`]); static mode ignores it.
    pub spin: Option<Spin>,
}

impl Targets {
    /// The targets (input frame) of vertices at `rest` (input frame): the explicit ones, or
    /// `rest` rotated about the centre (default: their centroid) and then translated.
    ///
    /// # Errors
    /// An explicit list of the wrong length, or a zero rotation axis.
    pub fn resolve(&self, rest: &[glam::DVec3]) -> Result<Vec<glam::DVec3>, SpecError> {
        use glam::DQuat;
        if let Some(explicit) = &self.explicit {
            if explicit.len() != rest.len() {
                return Err(SpecError::Invalid(format!(
                    "{} targets given for {} selected vertices (one per vertex)",
                    explicit.len(),
                    rest.len()
                )));
            }
            return Ok(explicit.iter().map(|&t| DVec3::from(t)).collect());
        }
        let translate = DVec3::from(self.translate);
        let rotation = match &self.rotate {
            None => None,
            Some(r) => {
                let center = r
                    .center
                    .map(DVec3::from)
                    .unwrap_or_else(|| rest.iter().copied().sum::<DVec3>() / rest.len().max(1) as f64);
                let axis = DVec3::from(r.axis).try_normalize().ok_or("rotation axis must be non-zero")?;
                Some((center, DQuat::from_axis_angle(axis, r.angle_deg.to_radians())))
            }
        };
        Ok(rest
            .iter()
            .map(|&p| match rotation {
                Some((center, q)) => center + q * (p - center) + translate,
                None => p + translate,
            })
            .collect())
    }
}

/// One `[[constraints]]` entry: a group.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupSpec {
    /// Constraint type name.
    pub kind: String,
    /// Group name (default: the type; `type_2`, `type_3`… when taken, see [`unique_group_name`]).
    pub name: String,
    /// Group multiplier g (default: the type's default).
    pub weight: f64,
    /// The vertices it applies to.
    pub selection: SelectionSpec,
    /// Position groups: their targets.
    pub targets: Targets,
    /// Type-specific options (`strain_freedom`, `prevent_flips`, `height`, `push`).
    pub options: Map<String, Value>,
}

impl GroupSpec {
    /// A group from one `[[constraints]]` entry as JSON values (the keys of the scene
    /// contract: `type`, `name`, `weight`, one selection key, targets for types with targets,
    /// and the type's options, which [`GroupSpec::build`] checks). The scene parser and the
    /// Python package both come through here.
    ///
    /// # Errors
    /// A one-line message naming the bad key.
    pub fn from_entry(entry: Map<String, Value>) -> Result<GroupSpec, SpecError> {
        parse_group(entry)
    }

    /// [`GroupSpec::from_entry`] for a group joining groups named `existing`: a given name must
    /// be new, and an unnamed group is named by [`unique_group_name`] after its type. Scene
    /// files (each entry among the ones before it), the editor and the Python package all name
    /// groups through here.
    ///
    /// # Errors
    /// As [`GroupSpec::from_entry`], and a given name that a group in `existing` has.
    pub fn from_entry_among(mut entry: Map<String, Value>, existing: &[&str]) -> Result<GroupSpec, SpecError> {
        match entry.get("name") {
            Some(Value::String(name)) if existing.contains(&name.as_str()) => {
                return Err(SpecError::Invalid(format!("a group named \"{name}\" exists already")));
            }
            None => {
                if let Some(Value::String(kind)) = entry.get("type") {
                    let name = unique_group_name(kind, existing);
                    entry.insert("name".into(), Value::String(name));
                }
            }
            Some(_) => {}
        }
        parse_group(entry)
    }

    /// The group on `mesh` (input frame; `rest` its rest geometry in the working frame), as the
    /// library's one group route takes it ([`build_group`]): its selection resolved, its
    /// targets (for types with targets) mapped to the working frame. The only code that turns
    /// a selection and targets into what the builders take: scenes, the editor and the Python
    /// package all come through here.
    ///
    /// # Errors
    /// [`SpecError`]: an unknown type, a selection out of range, bad targets.
    pub fn resolve(
        &self,
        mesh: &Mesh,
        rest: &RestGeometry,
        frame: &WorkingFrame,
    ) -> Result<GroupDescription, SpecError> {
        let ty = constraint_type(&self.kind)?;
        let selection = resolve_selection(&self.selection, mesh, rest)?;
        let targets = if ty.has_targets() {
            let (picked, targets) = self.input_targets(mesh)?;
            Some(picked.iter().zip(targets).map(|(&v, t)| (v as u32, frame.to_working(t))).collect())
        } else {
            None
        };
        Ok(GroupDescription {
            kind: self.kind.clone(),
            name: self.name.clone(),
            weight: Some(self.weight),
            selection,
            options: Params::new(self.options.clone()),
            targets,
        })
    }

    /// [`GroupSpec::resolve`], then built ([`build_group`]).
    ///
    /// # Errors
    /// As [`GroupSpec::resolve`], and a bad option (named) or nothing to constrain.
    pub fn build(&self, mesh: &Mesh, rest: &RestGeometry, frame: &WorkingFrame) -> Result<ConstraintGroup, SpecError> {
        Ok(build_group(&self.resolve(mesh, rest, frame)?, rest, frame)?)
    }

    /// The vertices its selection picks (see [`SelectionSpec::resolve`]) and their targets
    /// (input frame, see [`Targets::resolve`]), in the same order.
    ///
    /// # Errors
    /// A selection out of range or of faces, a vertex listed twice, bad targets.
    pub fn input_targets(&self, mesh: &Mesh) -> Result<(Vec<usize>, Vec<DVec3>), SpecError> {
        let picked = self.selection.resolve(&mesh.positions)?;
        let mut seen = vec![false; mesh.num_vertices()];
        for &v in &picked {
            if std::mem::replace(&mut seen[v], true) {
                return Err(SpecError::Invalid(format!("vertex {v} is listed twice")));
            }
        }
        let rest: Vec<DVec3> = picked.iter().map(|&v| mesh.positions[v]).collect();
        let targets = self.targets.resolve(&rest)?;
        Ok((picked, targets))
    }
}

/// The one rule for naming an unnamed group: `base` (its type's name, or the editor's word for
/// what it made: "handle", "smoothing") when no name in `existing` is `base`, else `base_2`,
/// `base_3`, … the first that is free.
pub fn unique_group_name(base: &str, existing: &[&str]) -> String {
    if !existing.contains(&base) {
        return base.to_string();
    }
    (2..)
        .map(|k| format!("{base}_{k}"))
        .find(|name| !existing.contains(&name.as_str()))
        .unwrap_or_else(|| base.to_string())
}

/// A scene selection as the constraint builders take it.
///
/// # Errors
/// A vertex or face index out of range.
pub fn resolve_selection(spec: &SelectionSpec, mesh: &Mesh, rest: &RestGeometry) -> Result<Selection, SpecError> {
    let n = mesh.num_vertices();
    Ok(match spec {
        SelectionSpec::All => Selection::All,
        SelectionSpec::Faces(list) => {
            let m = rest.faces.len();
            if let Some(&f) = list.iter().find(|&&f| f >= m) {
                return Err(
                    format!("face {f} is out of range (the mesh has {m} faces: 0..{})", m.saturating_sub(1)).into()
                );
            }
            // As a vertex listed twice: a slip in the list, said rather than merged.
            let mut seen = vec![false; m];
            if let Some(&f) = list.iter().find(|&&f| std::mem::replace(&mut seen[f], true)) {
                return Err(format!("face {f} is listed twice").into());
            }
            Selection::from_faces(n, &rest.faces, list)
        }
        _ => Selection::from_indices(n, &spec.resolve(&mesh.positions)?),
    })
}

/// Keys every group takes; the rest go to the type's builder (which rejects unknown ones).
const SELECTION_KEYS: [&str; 5] = ["vertices", "faces", "box", "sphere", "physical"];

/// An empty selection list `key = []` (every type refuses a group with nothing selected): said
/// as what the file has, not as a group of no elements.
fn empty_list(key: &str) -> SpecError {
    SpecError::Invalid(format!(
        "\"{key}\" = [] selects nothing: list some indices, or leave {key} out to select the whole mesh"
    ))
}

fn parse_group(mut entry: Map<String, Value>) -> Result<GroupSpec, SpecError> {
    let kind = match entry.remove("type") {
        Some(Value::String(s)) => s,
        Some(other) => return Err(format!("\"type\" must be a string, found {other}").into()),
        None => {
            return Err(format!("missing \"type\" (one of: {})", crate::constraints::type_names().join(", ")).into());
        }
    };
    let ty = constraint_type(&kind)?;
    let name = match entry.remove("name") {
        Some(Value::String(s)) => s,
        Some(other) => return Err(format!("\"name\" must be a string, found {other}").into()),
        None => kind.clone(),
    };
    let weight = match entry.remove("weight") {
        None => ty.default_multiplier(),
        Some(v) => match v.as_f64() {
            Some(w) if w.is_finite() && w >= 0.0 => w,
            // TOML's inf and nan arrive as null (the entry went through JSON values).
            _ if v.is_null() => return Err("\"weight\" must be a finite number ≥ 0, found inf, nan or null".into()),
            _ => return Err(format!("\"weight\" must be a finite number ≥ 0, found {v}").into()),
        },
    };
    let given: Vec<&str> = SELECTION_KEYS.iter().copied().filter(|k| entry.contains_key(*k)).collect();
    if given.len() > 1 {
        return Err(SpecError::Invalid(format!(
            "give at most one of vertices, faces, box, sphere, physical (found {})",
            given.join(" and ")
        )));
    }
    let selection = if let Some(v) = entry.remove("vertices") {
        let list: Vec<usize> =
            serde_json::from_value(v).map_err(|_| "\"vertices\" must be a list of vertex indices ≥ 0")?;
        if list.is_empty() {
            return Err(empty_list("vertices"));
        }
        SelectionSpec::Vertices(list)
    } else if let Some(v) = entry.remove("faces") {
        let list: Vec<usize> = serde_json::from_value(v).map_err(|_| "\"faces\" must be a list of face indices ≥ 0")?;
        if list.is_empty() {
            return Err(empty_list("faces"));
        }
        SelectionSpec::Faces(list)
    } else if let Some(v) = entry.remove("box") {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct B {
            min: [f64; 3],
            max: [f64; 3],
        }
        let b: B = crate::text::value_as(v)
            .map_err(|e| format!("\"box\": {e} (expected {{ min = [x,y,z], max = [x,y,z] }})"))?;
        // A box with min > max selects nothing: said as what it is, not as an empty group.
        if let Some(axis) = (0..3).find(|&k| b.min[k] > b.max[k]) {
            let name = ["x", "y", "z"][axis];
            return Err(SpecError::Invalid(format!(
                "\"box\": min {name} ({}) is greater than max {name} ({}): min must be ≤ max on every axis",
                b.min[axis], b.max[axis]
            )));
        }
        SelectionSpec::Box { min: b.min, max: b.max }
    } else if let Some(v) = entry.remove("physical") {
        match v {
            Value::String(name) if !name.is_empty() => SelectionSpec::Physical(name),
            Value::Number(tag) => SelectionSpec::Physical(tag.to_string()),
            other => {
                return Err(format!(
                    "\"physical\" must name a physical group of the .msh mesh (\"fixed\", or an unnamed group's tag), found {other}"
                )
                .into());
            }
        }
    } else if let Some(v) = entry.remove("sphere") {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct S {
            center: [f64; 3],
            radius: f64,
        }
        let s: S = crate::text::value_as(v)
            .map_err(|e| format!("\"sphere\": {e} (expected {{ center = [x,y,z], radius = r }})"))?;
        if !(s.radius.is_finite() && s.radius >= 0.0) {
            return Err(SpecError::Invalid(format!("sphere radius must be ≥ 0, found {}", s.radius)));
        }
        SelectionSpec::Sphere { center: s.center, radius: s.radius }
    } else {
        SelectionSpec::All
    };
    let targets = if ty.has_targets() { parse_targets(&mut entry)? } else { Targets::default() };
    Ok(GroupSpec { kind, name, weight, selection, targets, options: entry })
}

fn parse_targets(entry: &mut Map<String, Value>) -> Result<Targets, SpecError> {
    let mut t = Targets::default();
    if let Some(v) = entry.remove("translate") {
        t.translate = serde_json::from_value(v).map_err(|_| "\"translate\" must be [x, y, z]")?;
    }
    if let Some(v) = entry.remove("rotate") {
        let r: Rotate = crate::text::value_as(v)
            .map_err(|e| format!("\"rotate\": {e} (expected {{ axis = [x,y,z], angle_deg = a, center = [x,y,z] }})"))?;
        if r.axis.iter().map(|a| a * a).sum::<f64>() <= 0.0 || !r.angle_deg.is_finite() {
            return Err("\"rotate\" needs a non-zero axis and a finite angle_deg".into());
        }
        t.rotate = Some(r);
    }
    if let Some(v) = entry.remove("spin") {
        let spin: Spin = crate::text::value_as(v)
            .map_err(|e| format!("\"spin\": {e} (expected {{ axis = [x,y,z], deg_per_s = w, center = [x,y,z] }})"))?;
        if spin.axis.iter().map(|a| a * a).sum::<f64>() <= 0.0 || !spin.deg_per_s.is_finite() {
            return Err("\"spin\" needs a non-zero axis and a finite deg_per_s".into());
        }
        t.spin = Some(spin);
    }
    if let Some(v) = entry.remove("targets") {
        if t.rotate.is_some() || t.translate != [0.0; 3] {
            return Err("give either \"targets\" or translate/rotate, not both".into());
        }
        t.explicit = Some(serde_json::from_value(v).map_err(|_| "\"targets\" must be a list of [x, y, z]")?);
    }
    if [t.translate.iter().all(|x| x.is_finite())].contains(&false)
        || t.explicit.as_ref().is_some_and(|e| e.iter().flatten().any(|x| !x.is_finite()))
    {
        return Err("targets must be finite numbers".into());
    }
    Ok(t)
}
