//! Scene round trips: a document from a scene (its groups become editor groups) and back.

use super::Document;
use crate::edit_state::Rest;
use crate::error::{Cause, EditorError, LoadError};
use crate::group::{Group, GroupRole, ShapeModel, explicit_targets};
use glam::DVec3;
use shapeup_core::mesh::Mesh;
use shapeup_core::scene::{GroupSpec, MeshSettings, Scene, SelectionSpec, SolverSettings, Targets};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What [`Document::save_scene_with_mesh`] wrote besides the scene.
#[derive(Debug, Clone, PartialEq)]
pub struct SavedScene {
    /// The rest mesh written beside the scene, if the rest shape had to be saved.
    pub rest_mesh: Option<PathBuf>,
    /// The shape on screen written beside the scene as its `[mesh] start`, unless it was the
    /// rest shape.
    pub start_mesh: Option<PathBuf>,
    /// What the rest mesh's format could not keep, said once each.
    pub warnings: Vec<String>,
}

impl Document {
    /// The `[solver]` table the document saves: the one it was opened with, with the editor's
    /// iterations, tolerance and acceleration; one run of up to `iterations` to the tolerance,
    /// which is how the editor converges.
    pub fn solver_settings(&self) -> SolverSettings {
        SolverSettings {
            iterations: self.state.iterations,
            steps: 1,
            tolerance: self.state.tolerance,
            acceleration: self.state.acceleration,
            anderson_window: self.state.anderson_window,
            lbfgs_memory: self.state.lbfgs_memory,
            ..self.solver_settings
        }
    }

    /// A document from a scene: reads its mesh and takes its groups. Shape types over all
    /// vertices without options become the shape model (when they match one), position groups
    /// become handles (box and sphere selections resolved to vertices, targets made explicit),
    /// smoothing groups stay smoothing, anything else is kept as an "other" group.
    ///
    /// # Errors
    /// [`EditorError::Load`] for an unreadable mesh, a bad selection or target, or a
    /// tetrahedralized scene; [`EditorError::Constraint`] for a group that cannot be built.
    pub fn from_scene(scene: &Scene) -> Result<Document, EditorError> {
        let loaded = scene.read_mesh().map_err(|e| EditorError::Load(LoadError::Scene(Cause::new(e))))?;
        let start = scene.read_start(&loaded.mesh).map_err(|e| EditorError::Load(LoadError::Scene(Cause::new(e))))?;
        let mut document = Document::from_scene_with_mesh(scene, loaded.mesh)?;
        document.source = scene.mesh.generate.is_none().then(|| scene.mesh_path());
        document.attributes = loaded.attributes;
        // The shape the scene was saved with is where the editor converges from, as
        // `shapeup deform` does.
        if let Some(start) = start {
            document.set_shape(start);
        }
        Ok(document)
    }

    /// [`Document::from_scene`] on an already loaded mesh.
    ///
    /// # Errors
    /// As [`Document::from_scene`].
    pub fn from_scene_with_mesh(scene: &Scene, mesh: Mesh) -> Result<Document, EditorError> {
        if scene.mesh.tetrahedralize {
            return Err(EditorError::Load(LoadError::Tetrahedralize));
        }
        if scene.material.as_ref().is_some_and(|m| m.model != "projective") {
            return Err(EditorError::Load(LoadError::Material));
        }
        if scene.loads != Default::default() {
            return Err(EditorError::Load(LoadError::Loads));
        }
        if mesh.triangles.is_empty() {
            return Err(EditorError::Load(LoadError::NoTriangles));
        }
        let rest = Arc::new(Rest::new(mesh, scene.mesh.normalize));
        let mut document = Document::empty(Arc::clone(&rest), scene.solver);
        let mut groups = Vec::with_capacity(scene.groups.len());
        for (i, spec) in scene.groups.iter().enumerate() {
            let (role, spec) = editor_group(spec, &rest)
                .map_err(|cause| EditorError::Load(LoadError::Entry { index: i, name: spec.name.clone(), cause }))?;
            groups.push(Group { key: document.new_key(), role, spec });
        }
        let kinds: Vec<&str> =
            groups.iter().filter(|g| g.role == GroupRole::Shape).map(|g| g.spec.kind.as_str()).collect();
        document.state.shape_model = ShapeModel::from_kinds(&kinds);
        document.state.groups = groups;
        document.state.colliders = scene
            .colliders
            .iter()
            .cloned()
            .map(|mut c| {
                if let shapeup_core::contact::ShapeSpec::Mesh { path, .. } = &mut c.shape {
                    *path = scene.base_dir.join(&*path);
                }
                c
            })
            .collect();
        document.state.contact = scene.contact;
        document.solver.sync(&document.state)?;
        Ok(document)
    }

    /// The document as a scene whose `[mesh] path` is `mesh_path` (as it should appear in the
    /// file: relative to the scene's directory, or absolute). Its groups are the document's
    /// descriptions as they are: handles with explicit targets, editor groups with explicit
    /// vertex lists. After [`Command::MakeRest`](crate::command::Command::MakeRest), save
    /// [`Document::rest_mesh`] to that path too.
    pub fn to_scene(&self, mesh_path: impl Into<PathBuf>) -> Scene {
        let groups = self.state.groups.iter().map(|g| g.spec.clone()).collect();
        Scene {
            mesh: MeshSettings {
                path: mesh_path.into(),
                generate: None,
                normalize: self.state.rest.normalize,
                tetrahedralize: false,
                start: None,
                units: None,
            },
            solver: self.solver_settings(),
            groups,
            colliders: self.state.colliders.clone(),
            contact: self.state.contact,
            output: Default::default(),
            material: None,
            loads: Default::default(),
            base_dir: PathBuf::new(),
            file: PathBuf::new(),
        }
    }

    /// Writes [`Document::to_scene`] as TOML to `scene_path` (atomically).
    ///
    /// # Errors
    /// [`EditorError::Save`] naming the file.
    pub fn save_scene(&self, scene_path: &Path, mesh_path: impl Into<PathBuf>) -> Result<(), EditorError> {
        write_scene(scene_path, &self.to_scene(mesh_path))
    }

    /// Saves what replays the shape on screen: a scene at `scene_path` whose mesh is the file
    /// the document was opened from (absolute path) or, when the rest shape changed (Make rest
    /// shape) or the mesh has no file, the rest mesh written beside the scene as
    /// `STEM.rest.EXT` (the opened format when it is OBJ, PLY or OFF, else OBJ); and whose
    /// `[mesh] start` is the shape on screen, `STEM.start.obj`, so that the replay converges
    /// from it into the same minimum. Clears [`Document::is_modified`].
    ///
    /// # Errors
    /// [`EditorError::Save`] naming the file that cannot be written.
    pub fn save_scene_with_mesh(&mut self, scene_path: &Path) -> Result<SavedScene, EditorError> {
        let source = self.source.as_ref().filter(|_| Arc::ptr_eq(&self.state.rest, &self.opened_rest));
        let (mesh_path, rest_mesh, warnings) = match source {
            Some(source) => (std::fs::canonicalize(source).unwrap_or_else(|_| source.clone()), None, Vec::new()),
            None => {
                let ext = self
                    .source
                    .as_ref()
                    .and_then(|p| p.extension())
                    .and_then(|e| e.to_str())
                    .map(str::to_ascii_lowercase)
                    .filter(|e| matches!(e.as_str(), "obj" | "ply" | "off"))
                    .unwrap_or_else(|| "obj".into());
                let stem = scene_path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
                let name = format!("{stem}.rest.{ext}");
                let rest_path = scene_path.with_file_name(&name);
                let warnings = shapeup_core::io::write_mesh(&rest_path, &self.state.rest.mesh, &self.attributes)
                    .map_err(|e| EditorError::Save(Cause::new(e)))?;
                (PathBuf::from(name), Some(rest_path), warnings.iter().map(ToString::to_string).collect())
            }
        };
        let mut scene = self.to_scene(mesh_path);
        let start_mesh = self.save_start_shape(scene_path, &mut scene)?;
        write_scene(scene_path, &scene)?;
        self.modified = false;
        Ok(SavedScene { rest_mesh, start_mesh, warnings })
    }

    /// The shape on screen as `[mesh] start` of `scene`: `STEM.start.obj` beside the scene
    /// (positions only matter; OBJ keeps every vertex in order), unless it is the rest shape.
    /// These energies have several minima: a replay from rest may settle in another one.
    ///
    /// # Errors
    /// [`EditorError::Save`] naming the file that cannot be written.
    fn save_start_shape(&self, scene_path: &Path, scene: &mut Scene) -> Result<Option<PathBuf>, EditorError> {
        if self.positions == self.state.rest.mesh.positions {
            return Ok(None);
        }
        let stem = scene_path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let name = format!("{stem}.start.obj");
        let path = scene_path.with_file_name(&name);
        shapeup_core::io::write_mesh(&path, &self.current_mesh(), &shapeup_core::io::Attributes::None)
            .map_err(|e| EditorError::Save(Cause::new(e)))?;
        scene.mesh.start = Some(PathBuf::from(name));
        Ok(Some(path))
    }
}

/// `scene` as TOML at `path` (atomically).
///
/// # Errors
/// [`EditorError::Save`] naming the file.
fn write_scene(path: &Path, scene: &Scene) -> Result<(), EditorError> {
    let text = scene.to_toml_string();
    shapeup_core::io::write_atomic(path, |w| w.write_all(text.as_bytes())).map_err(|e| EditorError::Save(Cause::new(e)))
}

/// Whether `value` of option `key` is that option's default among `options` (a number option
/// whose default comes from the rest shape has none).
fn at_default(options: &[shapeup_core::constraints::OptionSpec], key: &str, value: &serde_json::Value) -> bool {
    use shapeup_core::constraints::OptionKind;
    let Some(option) = options.iter().find(|o| o.key == key) else { return false };
    match option.kind {
        OptionKind::Number { default, .. } => default.is_some() && value.as_f64() == default,
        OptionKind::Bool { default } => value.as_bool() == Some(default),
        OptionKind::Vector { default } => {
            value.as_array().is_some_and(|a| a.len() == 3 && a.iter().zip(default).all(|(v, d)| v.as_f64() == Some(d)))
        }
    }
}

/// A scene's group as the editor keeps it (see [`Group`]) and its role: a type with targets
/// is a handle on an ascending vertex list with explicit targets (box and sphere selections
/// resolved, translate and rotate applied, spin dropped); a shape-model type over all vertices
/// with no options is part of the shape model; smoothing with no options is smoothing; anything
/// else is kept as an "other" group, its box or sphere resolved to a vertex list and its faces
/// sorted.
///
/// # Errors
/// An unknown type, a vertex or face out of range, a vertex listed twice in a handle, bad
/// targets.
fn editor_group(spec: &GroupSpec, rest: &Rest) -> Result<(GroupRole, GroupSpec), Cause> {
    let ty = shapeup_core::constraints::constraint_type(&spec.kind).map_err(Cause::new)?;
    if ty.has_targets() {
        let (picked, targets) = spec.input_targets(&rest.mesh).map_err(Cause::new)?;
        // Ascending, as the editor keeps every selection (targets follow their vertex).
        let mut pairs: Vec<(usize, DVec3)> = picked.into_iter().zip(targets).collect();
        pairs.sort_unstable_by_key(|&(v, _)| v);
        let (vertices, targets): (Vec<usize>, Vec<DVec3>) = pairs.into_iter().unzip();
        let spec = GroupSpec {
            selection: SelectionSpec::Vertices(vertices),
            targets: explicit_targets(targets),
            ..spec.clone()
        };
        return Ok((GroupRole::Handle, spec));
    }
    let selection = match &spec.selection {
        SelectionSpec::All => SelectionSpec::All,
        SelectionSpec::Faces(list) => {
            let m = rest.geometry.faces.len();
            if let Some(&f) = list.iter().find(|&&f| f >= m) {
                return Err(Cause::text(format!("face {f} is out of range (the mesh has {m} faces)")));
            }
            let mut list = list.clone();
            list.sort_unstable();
            list.dedup();
            SelectionSpec::Faces(list)
        }
        other => SelectionSpec::Vertices(other.resolve(&rest.mesh.positions).map_err(Cause::new)?),
    };
    let shape_kind = ShapeModel::ALL.iter().any(|m| m.groups().iter().any(|(k, _)| *k == spec.kind));
    // Options spelled out at their defaults are the preset's too.
    let plain = spec.options.iter().all(|(key, value)| at_default(ty.options(), key, value));
    let role = if shape_kind && plain && selection == SelectionSpec::All {
        GroupRole::Shape
    } else if spec.kind == "smoothing" && plain {
        GroupRole::Smoothing
    } else {
        GroupRole::Other
    };
    Ok((role, GroupSpec { selection, targets: Targets::default(), ..spec.clone() }))
}
