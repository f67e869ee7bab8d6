//! `_Simulation`: Projective Dynamics on one mesh.

use crate::contact::{ContactSetup, flags};
use crate::convert::{points, to_array};
use crate::errors::{solve_error, value_error};
use crate::groups::{add_entry, held, remove, set_targets, set_weight};
use crate::mesh::PyMesh;
use crate::signals::Interrupt;
use numpy::{PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use shapeup_core::dynamics::Simulation as CoreSimulation;
use shapeup_core::geometry::RestGeometry;
use shapeup_core::mesh::Mesh as CoreMesh;
use shapeup_core::scene::{StepTotals, lumped_masses};
use shapeup_core::solver::{SolveError, System};
use shapeup_core::warnings::Warnings;

/// A Projective Dynamics simulation on one mesh (user coordinates and units).
#[pyclass(name = "_Simulation", module = "shapeup._shapeup")]
pub(crate) struct PySimulation {
    mesh: CoreMesh,
    /// The physical groups of the `.msh` file the mesh was read from (`physical=` selections).
    physical_groups: Vec<shapeup_core::io::PhysicalGroup>,
    rest: RestGeometry,
    simulation: CoreSimulation,
    contact: ContactSetup,
}

#[pymethods]
impl PySimulation {
    /// `params`: JSON text with time_step, gravity, stiffness, damping, density, iterations,
    /// tolerance, acceleration (each optional; defaults as in scene files).
    #[new]
    fn new(mesh: &PyMesh, params: &str) -> PyResult<Self> {
        let settings: shapeup_core::scene::SolverSettings = shapeup_core::scene::from_json_entry(params)
            .map_err(|e| value_error(format!("bad simulation settings: {e}")))?;
        let rest = RestGeometry::of_mesh(mesh.mesh.positions.clone(), &mesh.mesh);
        // As a scene's `[solver]` table starts a simulation, in the mesh's own units (scale 1).
        let dynamics = settings.checked_dynamics_params(1.0).map_err(value_error)?;
        let masses = lumped_masses(&rest, settings.density);
        let system = System::new(mesh.mesh.num_vertices(), settings.solver_params());
        let simulation = CoreSimulation::new(system, masses, rest.positions.clone(), dynamics).map_err(value_error)?;
        let physical_groups = mesh.attributes.physical_groups().to_vec();
        Ok(PySimulation {
            mesh: mesh.mesh.clone(),
            physical_groups,
            rest,
            simulation,
            contact: ContactSetup::default(),
        })
    }

    /// Adds a group from a scene entry and its selection (JSON text each); returns (id, name,
    /// type, constraints).
    #[pyo3(signature = (entry, selection="{}"))]
    fn add(&mut self, entry: &str, selection: &str) -> PyResult<(u32, String, String, usize)> {
        add_entry(self.simulation.system_mut(), &self.mesh, &self.rest, &self.physical_groups, entry, selection)
    }

    fn held(&self, id: u32) -> PyResult<Vec<u32>> {
        held(self.simulation.system(), id)
    }

    fn set_targets(&mut self, id: u32, targets: PyReadonlyArray2<'_, f64>) -> PyResult<()> {
        set_targets(self.simulation.system_mut(), id, &targets)
    }

    fn set_weight(&mut self, id: u32, weight: f64) -> PyResult<()> {
        set_weight(self.simulation.system_mut(), id, weight)
    }

    fn remove(&mut self, id: u32) -> PyResult<()> {
        remove(self.simulation.system_mut(), id)
    }

    /// Adds a collider from a scene entry (JSON text); returns its index. The contact model is
    /// built again (its state starts afresh; the matrix is refactored at the next step).
    fn add_collider(&mut self, entry: &str) -> PyResult<usize> {
        let (spec, model) = self.contact.with_collider(entry, &self.mesh, &self.rest)?;
        self.simulation.set_contact(model).map_err(value_error)?;
        Ok(self.contact.commit_collider(spec))
    }

    /// Replaces the `[contact]` settings (JSON text) and builds the contact model again.
    fn set_contact(&mut self, settings: &str) -> PyResult<()> {
        let (settings, model) = self.contact.with_settings(settings, &self.mesh, &self.rest)?;
        self.simulation.set_contact(model).map_err(value_error)?;
        self.contact.commit_settings(settings);
        Ok(())
    }

    /// The colliders as JSON text (a list of scene entries).
    #[getter]
    fn colliders(&self) -> String {
        self.contact.colliders_json()
    }

    /// The `[contact]` settings as JSON text.
    #[getter]
    fn contact_settings(&self) -> String {
        self.contact.settings_json()
    }

    /// The contact thickness in use (None without contact).
    #[getter]
    fn contact_thickness(&self) -> Option<f64> {
        self.simulation.contact().map(|c| c.params().thickness)
    }

    /// Per vertex: touching at the end of the last step.
    #[getter]
    fn contact_flags<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        flags(py, self.simulation.contact(), self.mesh.num_vertices())
    }

    #[getter]
    fn factorizations(&self) -> u64 {
        self.simulation.system().factorizations()
    }

    /// `n` time steps without the GIL (Ctrl+C stops between steps); returns JSON text
    /// `{"reports": [each step's report], "warnings": [...]}`, the warnings those steps should
    /// say once (time steps that stopped short, groups lost to round-off), in the command
    /// line's words ([`StepTotals::add_warnings`]).
    fn step(&mut self, py: Python<'_>, n: usize) -> PyResult<String> {
        let mut interrupt = Interrupt::new();
        let simulation = &mut self.simulation;
        let params = simulation.system().params();
        let mut totals =
            StepTotals { iteration_cap: params.iterations, tolerance: params.tolerance, ..StepTotals::default() };
        let reports = py.detach(|| {
            let mut reports = Vec::with_capacity(n.min(1 << 16));
            for _ in 0..n {
                let r = simulation.step()?;
                totals.add(&r);
                totals.add_residual(usize::try_from(simulation.steps()).unwrap_or(usize::MAX), &r);
                reports.push(serde_json::json!({
                    "energy": r.energy, "iterations": r.iterations, "rejected": r.rejected,
                    "local_s": r.local_seconds, "global_s": r.global_seconds,
                    "setup_s": r.setup_seconds, "total_s": r.total_seconds,
                    "contacts": r.contact.touching, "self_contacts": r.contact.self_touching,
                    "contact_candidates": r.contact.candidates, "contact_vertices": r.contact.vertices,
                    "crossings_stopped": r.contact.stopped, "ended_inside": r.contact.inside,
                    "contact_s": r.contact_seconds,
                    "residual": r.residual, "unconverged": r.unconverged, "check_s": r.check_seconds,
                    "lost_groups": r.lost_groups.iter().map(|g| g.describe()).collect::<Vec<_>>(),
                }));
                if !simulation.kinetic_energy().is_finite() {
                    return Err(SolveError::NonFiniteEnergy);
                }
                if interrupt.poll().is_break() {
                    break;
                }
            }
            Ok(reports)
        });
        if let Some(e) = interrupt.error {
            return Err(e);
        }
        let reports = reports.map_err(solve_error)?;
        let mut warnings = Warnings::new();
        totals.add_warnings(&mut warnings);
        Ok(serde_json::json!({ "reports": reports, "warnings": warnings.to_json() }).to_string())
    }

    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        to_array(py, self.simulation.positions())
    }

    #[getter]
    fn velocities<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        to_array(py, self.simulation.velocities())
    }

    #[getter]
    fn masses(&self) -> Vec<f64> {
        self.simulation.masses().to_vec()
    }

    #[getter]
    fn time(&self) -> f64 {
        self.simulation.time()
    }

    #[getter]
    fn steps(&self) -> u64 {
        self.simulation.steps()
    }

    #[getter]
    fn kinetic_energy(&self) -> f64 {
        self.simulation.kinetic_energy()
    }

    fn energy(&mut self) -> PyResult<f64> {
        self.simulation.energy().map_err(solve_error)
    }

    fn set_state(
        &mut self,
        positions: PyReadonlyArray2<'_, f64>,
        velocities: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<()> {
        let (x, v) = (points(&positions, "positions")?, points(&velocities, "velocities")?);
        self.simulation.set_state(&x, &v).map_err(value_error)
    }

    #[pyo3(signature = (forces))]
    fn set_external_forces(&mut self, forces: Option<PyReadonlyArray2<'_, f64>>) -> PyResult<()> {
        let forces = forces.map(|f| points(&f, "forces")).transpose()?;
        self.simulation.set_external_forces(forces).map_err(value_error)
    }

    fn grab(&mut self, vertices: Vec<u32>, targets: PyReadonlyArray2<'_, f64>, strength: f64) -> PyResult<()> {
        let targets = points(&targets, "targets")?;
        self.simulation.grab(vertices, targets, strength).map_err(value_error)
    }

    fn release(&mut self) {
        self.simulation.release();
    }
}
