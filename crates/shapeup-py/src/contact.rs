//! Colliders and contact settings, shared by `_Solver` and `_Simulation`. A collider comes in
//! as JSON text in the scene contract's keys (one `[[colliders]]` entry) and the settings as
//! the `[contact]` table, so that the Python door and scene files share one parser and one set
//! of messages ([`ColliderSpec::from_entry`], [`ContactSettings::validate`]) and one builder
//! ([`ColliderSpec::build`]). The model is built as [`shapeup_core::scene::Scene::build_contact`]
//! builds a scene's, in the mesh's own units (no normalization).

use crate::errors::value_error;
use numpy::PyArray1;
use pyo3::prelude::*;
use serde_json::{Map, Value};
use shapeup_core::contact::{ColliderSpec, ContactModel, ContactParams, ContactSettings, ShapeSpec};
use shapeup_core::geometry::{RestGeometry, WorkingFrame, bounding_box_diagonal, mean_edge_length};
use shapeup_core::mesh::Mesh as CoreMesh;
use std::path::Path;

/// The colliders and `[contact]` settings given so far.
#[derive(Debug, Default)]
pub(crate) struct ContactSetup {
    colliders: Vec<ColliderSpec>,
    settings: ContactSettings,
}

/// The contact thickness: the settings' or the default fraction of the rest shape's mean edge
/// length (as a scene with `normalize = false`).
///
/// # Errors
/// `ValueError` "[contact]: …": a thickness over a quarter of the rest shape's size, or a
/// self-collision thickness over the mean edge length.
fn thickness(settings: &ContactSettings, rest: &RestGeometry) -> PyResult<f64> {
    settings
        .resolve_thickness(1.0, mean_edge_length(rest), bounding_box_diagonal(rest))
        .map_err(|e| value_error(format!("[contact]: {e}")))
}

impl ContactSetup {
    /// The model of `colliders` and `settings` on `mesh` (`None` with no collider and no
    /// self-collision): every vertex in a triangle or tetrahedron takes part, the surface
    /// (a tetrahedral mesh's boundary) collides with itself when asked.
    fn model(
        colliders: &[ColliderSpec],
        settings: &ContactSettings,
        mesh: &CoreMesh,
        rest: &RestGeometry,
    ) -> PyResult<Option<ContactModel>> {
        if colliders.is_empty() && !settings.self_collision {
            return Ok(None);
        }
        let thickness = thickness(settings, rest)?;
        let built = colliders
            .iter()
            .enumerate()
            .map(|(i, c)| {
                // Mesh paths were made absolute when the collider was added.
                c.build(&WorkingFrame::IDENTITY, Path::new(""), thickness)
                    .map_err(|e| value_error(format!("colliders[{i}]: {e}")))
            })
            .collect::<PyResult<Vec<_>>>()?;
        let mut active = vec![false; mesh.num_vertices()];
        for v in mesh.triangles.iter().flatten().chain(mesh.tetrahedra.iter().flatten()) {
            active[*v as usize] = true;
        }
        let surface = if mesh.tetrahedra.is_empty() {
            mesh.triangles.clone()
        } else {
            shapeup_core::topology::tetrahedron_boundary(&mesh.tetrahedra)
        };
        let params = ContactParams { thickness, friction: settings.friction, self_collision: settings.self_collision };
        Ok(Some(ContactModel::new(built, params, &surface, active)))
    }

    /// Reads one collider entry (JSON text in scene keys) and returns the model with it added
    /// after the others, and its index; nothing changes until [`ContactSetup::commit_collider`].
    /// A mesh's relative `path` is taken from the current directory.
    ///
    /// # Errors
    /// `ValueError` "colliders[i]: …" with the core's message naming the key, or the mesh
    /// file's problem.
    pub(crate) fn with_collider(
        &self,
        entry: &str,
        mesh: &CoreMesh,
        rest: &RestGeometry,
    ) -> PyResult<(ColliderSpec, Option<ContactModel>)> {
        let i = self.colliders.len();
        let map: Map<String, Value> = shapeup_core::scene::from_json_entry(entry)
            .map_err(|e| value_error(format!("colliders[{i}]: bad entry: {e}")))?;
        let mut spec = ColliderSpec::from_entry(map).map_err(|e| value_error(format!("colliders[{i}]: {e}")))?;
        if let ShapeSpec::Mesh { path, .. } = &mut spec.shape
            && path.is_relative()
        {
            let here = std::env::current_dir()
                .map_err(|e| value_error(format!("colliders[{i}]: no current directory for `path`: {e}")))?;
            *path = here.join(&*path);
        }
        let mut colliders = self.colliders.clone();
        colliders.push(spec.clone());
        let model = Self::model(&colliders, &self.settings, mesh, rest)?;
        Ok((spec, model))
    }

    pub(crate) fn commit_collider(&mut self, spec: ColliderSpec) -> usize {
        self.colliders.push(spec);
        self.colliders.len() - 1
    }

    /// Reads the `[contact]` settings (JSON text: self_collision, thickness, friction; a key
    /// left out takes its default) and returns them with the model they give.
    ///
    /// # Errors
    /// `ValueError` "contact: …" naming the bad key.
    pub(crate) fn with_settings(
        &self,
        text: &str,
        mesh: &CoreMesh,
        rest: &RestGeometry,
    ) -> PyResult<(ContactSettings, Option<ContactModel>)> {
        let settings: ContactSettings = shapeup_core::scene::from_json_entry(text)
            .map_err(|e| value_error(format!("contact: bad settings: {e}")))?;
        settings.validate().map_err(|e| value_error(format!("contact: {e}")))?;
        let model = Self::model(&self.colliders, &settings, mesh, rest)?;
        Ok((settings, model))
    }

    pub(crate) fn commit_settings(&mut self, settings: ContactSettings) {
        self.settings = settings;
    }

    /// The colliders as JSON text: a list of entries in scene keys.
    pub(crate) fn colliders_json(&self) -> String {
        Value::from(self.colliders.iter().map(|c| Value::Object(c.to_entry())).collect::<Vec<_>>()).to_string()
    }

    /// The settings as JSON text (thickness null when it is the default).
    pub(crate) fn settings_json(&self) -> String {
        serde_json::to_string(&self.settings).unwrap_or_else(|_| "{}".into())
    }
}

/// Per vertex, whether it touched a collider or the surface at the end of the last step or
/// solve, as a bool array of length `n` (all false without contact).
pub(crate) fn flags<'py>(py: Python<'py>, model: Option<&ContactModel>, n: usize) -> Bound<'py, PyArray1<bool>> {
    match model {
        Some(m) => PyArray1::from_slice(py, m.touching()),
        None => PyArray1::from_vec(py, vec![false; n]),
    }
}
