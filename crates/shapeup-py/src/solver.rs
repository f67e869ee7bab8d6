//! `_Solver`: constraint groups on one mesh and the ShapeUp solver.

use crate::contact::{ContactSetup, flags};
use crate::convert::{points, to_array};
use crate::errors::{solve_error, value_error};
use crate::groups::{add_entry, held, remove, set_targets, set_weight};
use crate::mesh::PyMesh;
use crate::signals::Interrupt;
use glam::DVec3;
use numpy::{PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use shapeup_core::contact::ContactModel;
use shapeup_core::geometry::RestGeometry;
use shapeup_core::mesh::Mesh as CoreMesh;
use shapeup_core::solver::{Acceleration, SolveError, SolveReport, SolverParams, System};

/// The report of a solve of `iterations` iterations as JSON text.
fn solve_report_json(report: &SolveReport, iterations: usize, acceleration: Acceleration) -> String {
    serde_json::json!({
        "iterations": iterations,
        "initial_energy": report.initial_energy,
        "energy": report.energies,
        "relative_change": shapeup_core::scene::relative_changes(report.initial_energy, &report.energies),
        "acceleration": acceleration.name(),
        "rejected": report.rejected,
        "residual": report.residual,
        "unconverged": report.residual.map(|_| report.unconverged),
        "warnings": report.warnings().to_json(),
        "timings": {
            "setup_s": report.setup_seconds,
            "local_s": report.local_seconds,
            "global_s": report.global_seconds,
        },
    })
    .to_string()
}

/// `system.solve_with` without the GIL, stopping for Ctrl+C (the `KeyboardInterrupt` is
/// returned after the solve stops, q left at the last iteration).
fn solve_interruptible(
    py: Python<'_>,
    system: &mut System,
    q: &mut [DVec3],
    iterations: usize,
    tolerance: f64,
) -> PyResult<SolveReport> {
    let mut interrupt = Interrupt::new();
    let result = py.detach(|| system.solve_with(q, iterations, tolerance, |_, _| interrupt.poll()));
    if let Some(e) = interrupt.error {
        return Err(e);
    }
    result.map_err(solve_error)
}

/// [`shapeup_core::scene::solve_static_with_contact`] without the GIL, stopping for Ctrl+C
/// between chunks; returns the report and the iterations run.
fn solve_with_contact_interruptible(
    py: Python<'_>,
    system: &mut System,
    model: &mut ContactModel,
    q: &mut [DVec3],
    iterations: usize,
) -> PyResult<(SolveReport, usize)> {
    let mut interrupt = Interrupt::new();
    let mut done = 0;
    let result = py.detach(|| {
        shapeup_core::scene::solve_static_with_contact(system, model, q, iterations, |k, _| {
            done = k;
            interrupt.poll()
        })
    });
    if let Some(e) = interrupt.error {
        return Err(e);
    }
    Ok((result.map_err(solve_error)?, done))
}

/// Constraint groups on one mesh and the ShapeUp solver (user coordinates, no normalization).
#[pyclass(name = "_Solver", module = "shapeup._shapeup")]
pub(crate) struct PySolver {
    mesh: CoreMesh,
    /// The physical groups of the `.msh` file the mesh was read from (`physical=` selections).
    physical_groups: Vec<shapeup_core::io::PhysicalGroup>,
    rest: RestGeometry,
    system: System,
    contact: ContactSetup,
    /// Built from `contact` (`None` with no collider and no self-collision).
    model: Option<ContactModel>,
}

#[pymethods]
impl PySolver {
    #[new]
    fn new(mesh: &PyMesh) -> Self {
        let rest = RestGeometry::of_mesh(mesh.mesh.positions.clone(), &mesh.mesh);
        let system = System::new(mesh.mesh.num_vertices(), SolverParams::default());
        let physical_groups = mesh.attributes.physical_groups().to_vec();
        PySolver {
            mesh: mesh.mesh.clone(),
            physical_groups,
            rest,
            system,
            contact: ContactSetup::default(),
            model: None,
        }
    }

    /// A new contact model (or the groups changed): the contact weights are set again,
    /// relative to the matrix, at the next solve.
    fn reset_contact_weights(&mut self) -> PyResult<()> {
        if self.system.contact_weights().is_some() {
            self.system.set_contact_weights(None).map_err(value_error)?;
        }
        Ok(())
    }

    /// Adds a group from a scene entry and its selection (JSON text each); returns (id, name,
    /// type, constraints).
    #[pyo3(signature = (entry, selection="{}"))]
    fn add(&mut self, entry: &str, selection: &str) -> PyResult<(u32, String, String, usize)> {
        let added = add_entry(&mut self.system, &self.mesh, &self.rest, &self.physical_groups, entry, selection)?;
        self.reset_contact_weights()?;
        Ok(added)
    }

    fn held(&self, id: u32) -> PyResult<Vec<u32>> {
        held(&self.system, id)
    }

    fn set_targets(&mut self, id: u32, targets: PyReadonlyArray2<'_, f64>) -> PyResult<()> {
        set_targets(&mut self.system, id, &targets)
    }

    fn set_weight(&mut self, id: u32, weight: f64) -> PyResult<()> {
        set_weight(&mut self.system, id, weight)?;
        self.reset_contact_weights()
    }

    fn remove(&mut self, id: u32) -> PyResult<()> {
        remove(&mut self.system, id)?;
        self.reset_contact_weights()
    }

    /// Adds a collider from a scene entry (JSON text); returns its index.
    fn add_collider(&mut self, entry: &str) -> PyResult<usize> {
        let (spec, model) = self.contact.with_collider(entry, &self.mesh, &self.rest)?;
        self.model = model;
        self.reset_contact_weights()?;
        Ok(self.contact.commit_collider(spec))
    }

    /// Replaces the `[contact]` settings (JSON text).
    fn set_contact(&mut self, settings: &str) -> PyResult<()> {
        let (settings, model) = self.contact.with_settings(settings, &self.mesh, &self.rest)?;
        self.model = model;
        self.reset_contact_weights()?;
        self.contact.commit_settings(settings);
        Ok(())
    }

    #[getter]
    fn colliders(&self) -> String {
        self.contact.colliders_json()
    }

    #[getter]
    fn contact_settings(&self) -> String {
        self.contact.settings_json()
    }

    #[getter]
    fn contact_thickness(&self) -> Option<f64> {
        self.model.as_ref().map(|c| c.params().thickness)
    }

    /// Per vertex: touching at the end of the last solve.
    #[getter]
    fn contact_flags<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        flags(py, self.model.as_ref(), self.mesh.num_vertices())
    }

    #[getter]
    fn factorizations(&self) -> u64 {
        self.system.factorizations()
    }

    /// Solves from `q` (default the rest shape); returns (q, report as JSON text).
    #[pyo3(signature = (q, iterations, tolerance, acceleration))]
    fn solve<'py>(
        &mut self,
        py: Python<'py>,
        q: Option<PyReadonlyArray2<'py, f64>>,
        iterations: usize,
        tolerance: f64,
        acceleration: &str,
    ) -> PyResult<(Bound<'py, PyArray2<f64>>, String)> {
        let mut x = match &q {
            Some(q) => points(q, "q")?,
            None => self.rest.positions.clone(),
        };
        let acceleration = Acceleration::from_name(acceleration).ok_or_else(|| {
            let names: Vec<&str> = Acceleration::ALL.iter().map(|a| a.name()).collect();
            value_error(format!("unknown acceleration \"{acceleration}\" ({})", names.join(", ")))
        })?;
        if self.system.params().acceleration != acceleration {
            self.system.set_params(SolverParams { acceleration, ..*self.system.params() });
        }
        if let Some(model) = self.model.as_mut().filter(|m| m.is_active()) {
            // With contact: plain iterations in chunks, each detecting again (as a scene's
            // static solve runs them); no tolerance, no acceleration.
            let (report, done) = solve_with_contact_interruptible(py, &mut self.system, model, &mut x, iterations)?;
            return Ok((to_array(py, &x), solve_report_json(&report, done, Acceleration::None)));
        }
        let report = solve_interruptible(py, &mut self.system, &mut x, iterations, tolerance)?;
        let done = report.energies.len();
        Ok((to_array(py, &x), solve_report_json(&report, done, acceleration)))
    }

    /// (E, [(id, E_group)]) at q.
    fn energy(&mut self, q: PyReadonlyArray2<'_, f64>) -> PyResult<(f64, Vec<(u32, f64)>)> {
        let q = points(&q, "q")?;
        let e = self.system.energy(&q).map_err(solve_error)?;
        // Coordinates or weights too large for f64: an error, as a solve's, not inf.
        if !e.total.is_finite() {
            return Err(solve_error(SolveError::NonFiniteEnergy));
        }
        Ok((e.total, e.per_group.iter().map(|(id, v)| (id.0, *v)).collect()))
    }
}
