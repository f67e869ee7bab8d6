//! `shapeup._shapeup`: the Rust half of the `shapeup` Python package. The Python half
//! (`python/shapeup/`) checks shapes and dtypes, builds group entries and documents the API;
//! this module moves arrays in and out of `shapeup-core` and runs it without the GIL.
//!
//! Groups come in as JSON text in the scene contract's keys (`type`, `name`, `weight`, one
//! selection key, targets, options), so that the Python door and scene files share one parser
//! ([`GroupSpec::from_entry`]) and one builder ([`GroupSpec::build`]).

use glam::DVec3;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyOSError, PyValueError};
use pyo3::prelude::*;
use shapeup_core::constraints::held_vertices;
use shapeup_core::dynamics::{DynamicsParams, Simulation as CoreSimulation};
use shapeup_core::geometry::{RestGeometry, WorkingFrame};
use shapeup_core::io::{
    Attributes, IoError, MESH_OUTPUT_EXTENSIONS, OutputError, check_output_extension, check_output_folder,
};
use shapeup_core::mesh::{Mesh as CoreMesh, Polygons};
use shapeup_core::scene::frames::{FrameFormat, FrameWriter};
use shapeup_core::scene::{GroupSpec, Scene as CoreScene, SceneError, SceneFormat, StepTotals, lumped_masses};
use shapeup_core::solver::{Acceleration, GroupId, SolveError, SolveReport, SolverParams, System};
use shapeup_core::warnings::Warnings;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

create_exception!(
    _shapeup,
    SolveFailed,
    PyException,
    "The solver refused: an unsolvable system (nothing anchors it), non-finite positions or energy."
);

/// How often a long solve looks for Ctrl+C (it takes the GIL for a moment to ask).
const SIGNAL_CHECK: Duration = Duration::from_millis(50);

fn value_error(message: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(message.to_string().replace('\n', " "))
}

fn solve_error(e: SolveError) -> PyErr {
    SolveFailed::new_err(e.to_string())
}

/// A missing or unreadable file is an `OSError` (`FileNotFoundError` when it is not there);
/// a file that is there but wrong is a `ValueError`.
fn io_error(e: IoError) -> PyErr {
    let message = e.to_string();
    match &e {
        IoError::Open { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            pyo3::exceptions::PyFileNotFoundError::new_err(message)
        }
        IoError::Open { .. } | IoError::Read { .. } | IoError::Write { .. } => PyOSError::new_err(message),
        _ => value_error(message),
    }
}

fn scene_error(e: SceneError) -> PyErr {
    match e {
        SceneError::Read { ref source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            pyo3::exceptions::PyFileNotFoundError::new_err(e.to_string())
        }
        SceneError::Read { .. } => PyOSError::new_err(e.to_string()),
        SceneError::Mesh { source: IoError::Open { ref source, .. }, .. }
            if source.kind() == std::io::ErrorKind::NotFound =>
        {
            pyo3::exceptions::PyFileNotFoundError::new_err(e.to_string())
        }
        SceneError::Solve { .. } => SolveFailed::new_err(e.to_string()),
        _ => value_error(e),
    }
}

/// (n, 3) float64 rows as points, read in place from a C-contiguous array.
fn points(array: &PyReadonlyArray2<'_, f64>, what: &str) -> PyResult<Vec<DVec3>> {
    let shape = array.shape();
    if shape[1] != 3 {
        return Err(value_error(format!("{what} must have shape (n, 3), found {shape:?}")));
    }
    let flat = array.as_slice().map_err(|_| value_error(format!("{what} must be C-contiguous")))?;
    Ok(flat.chunks_exact(3).map(|p| DVec3::new(p[0], p[1], p[2])).collect())
}

/// Points as a new (n, 3) float64 array.
fn to_array<'py>(py: Python<'py>, points: &[DVec3]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = points.iter().flat_map(|p| p.to_array()).collect();
    // The shape matches the data by construction.
    Array2::from_shape_vec((points.len(), 3), flat).unwrap_or_else(|_| Array2::zeros((0, 3))).into_pyarray(py)
}

/// Index rows (triangles, tetrahedra) as a new (m, K) int64 array.
fn index_array<'py, const K: usize>(py: Python<'py>, rows: &[[u32; K]]) -> Bound<'py, PyArray2<i64>> {
    let flat: Vec<i64> = rows.iter().flatten().map(|&v| i64::from(v)).collect();
    // The shape matches the data by construction.
    Array2::from_shape_vec((rows.len(), K), flat).unwrap_or_else(|_| Array2::zeros((0, K))).into_pyarray(py)
}

/// Rows of an (m, k) int64 array as `[u32; K]` (the Python side checked range and sign).
fn rows<const K: usize>(array: &PyReadonlyArray2<'_, i64>, what: &str) -> PyResult<Vec<[u32; K]>> {
    let shape = array.shape();
    if shape[1] != K {
        return Err(value_error(format!("{what} must have shape (m, {K}), found {shape:?}")));
    }
    let flat = array.as_slice().map_err(|_| value_error(format!("{what} must be C-contiguous")))?;
    flat.chunks_exact(K)
        .map(|row| {
            let mut out = [0u32; K];
            for (o, &v) in out.iter_mut().zip(row) {
                *o = u32::try_from(v).map_err(|_| value_error(format!("{what}: index {v} is out of range")))?;
            }
            Ok(out)
        })
        .collect()
}

fn warnings_list(warnings: &Warnings) -> Vec<String> {
    warnings.iter().map(ToString::to_string).collect()
}

/// A mesh as the library holds it: positions, polygons (kept as they are), their
/// triangulation, tetrahedra and attributes (texture coordinates, normals, colours, scalars).
#[pyclass(name = "_Mesh", module = "shapeup._shapeup", frozen)]
struct PyMesh {
    mesh: CoreMesh,
    attributes: Attributes,
    warnings: Warnings,
}

#[pymethods]
impl PyMesh {
    /// Vertex positions, float64 (n, 3).
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        to_array(py, &self.mesh.positions)
    }

    /// The triangulation of the polygons, int64 (m, 3).
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        index_array(py, &self.mesh.triangles)
    }

    /// Tetrahedra, int64 (t, 4).
    #[getter]
    fn tetrahedra<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        index_array(py, &self.mesh.tetrahedra)
    }

    /// The polygons as (corner indices, offsets): polygon i is `indices[offsets[i]:offsets[i+1]]`.
    #[getter]
    fn polygon_arrays(&self) -> (Vec<i64>, Vec<i64>) {
        let indices = self.mesh.polygons.indices().iter().map(|&v| i64::from(v)).collect();
        let offsets = self.mesh.polygons.offsets().iter().map(|&o| o as i64).collect();
        (indices, offsets)
    }

    /// Texture coordinates as (values float64 (k, 2), corner → value index int64 per polygon
    /// corner, -1 where a corner has none), or None.
    #[getter]
    fn texcoords(&self) -> Option<(Vec<[f64; 2]>, Vec<i64>)> {
        let t = self.attributes.texcoords(&self.mesh.polygons)?;
        let corners =
            t.corners.iter().map(|&c| if c == shapeup_core::io::NO_INDEX { -1 } else { i64::from(c) }).collect();
        Some((t.values, corners))
    }

    /// Per-vertex colours (r, g, b in [0, 1]), or None.
    #[getter]
    fn vertex_colors(&self) -> Option<Vec<[f64; 3]>> {
        self.attributes.vertex_colors()
    }

    /// Per-vertex scalar properties as {name: values}.
    #[getter]
    fn vertex_scalars(&self) -> Vec<(String, Vec<f64>)> {
        self.attributes.vertex_scalars().into_iter().map(|s| (s.name, s.values)).collect()
    }

    /// What the file carries besides positions and faces, one description each.
    #[getter]
    fn attributes(&self) -> Vec<String> {
        self.attributes.kinds().iter().map(|k| k.describe()).collect()
    }

    /// What reading or building the mesh changed or left out, one line each.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        warnings_list(&self.warnings)
    }

    /// The same mesh (faces, attributes) with other positions, float64 (n, 3).
    fn with_vertices(&self, vertices: PyReadonlyArray2<'_, f64>) -> PyResult<PyMesh> {
        let positions = points(&vertices, "V")?;
        if positions.len() != self.mesh.num_vertices() {
            return Err(value_error(format!(
                "V has {} rows but the mesh has {} vertices",
                positions.len(),
                self.mesh.num_vertices()
            )));
        }
        Ok(PyMesh {
            mesh: self.mesh.with_positions(positions),
            attributes: self.attributes.clone(),
            warnings: Warnings::new(),
        })
    }

    fn __len__(&self) -> usize {
        self.mesh.num_vertices()
    }
}

/// Reads a mesh file (.obj .ply .off .stl .msh .vtu .node/.ele), as the command line does.
#[pyfunction]
fn read_mesh(py: Python<'_>, path: PathBuf) -> PyResult<PyMesh> {
    let loaded = py.detach(|| shapeup_core::io::read_mesh(&path)).map_err(io_error)?;
    Ok(PyMesh { mesh: loaded.mesh, attributes: loaded.attributes, warnings: loaded.warnings })
}

/// Writes a mesh (format from the extension), atomically; returns what writing it said.
#[pyfunction]
fn write_mesh(py: Python<'_>, path: PathBuf, mesh: &PyMesh) -> PyResult<Vec<String>> {
    let warnings = py.detach(|| shapeup_core::io::write_mesh(&path, &mesh.mesh, &mesh.attributes)).map_err(io_error)?;
    Ok(warnings_list(&warnings))
}

/// A mesh from arrays: V (n, 3); polygons as (indices, offsets) or None; T (t, 4) or None.
#[pyfunction]
#[pyo3(signature = (vertices, polygons=None, tetrahedra=None))]
fn mesh_from_arrays(
    vertices: PyReadonlyArray2<'_, f64>,
    polygons: Option<(PyReadonlyArray1<'_, i64>, PyReadonlyArray1<'_, i64>)>,
    tetrahedra: Option<PyReadonlyArray2<'_, i64>>,
) -> PyResult<PyMesh> {
    let positions = points(&vertices, "V")?;
    let mut faces = Polygons::new();
    if let Some((indices, offsets)) = &polygons {
        let indices = indices.as_slice().map_err(|_| value_error("polygon indices must be contiguous"))?;
        let offsets = offsets.as_slice().map_err(|_| value_error("polygon offsets must be contiguous"))?;
        let mut corners = Vec::new();
        for (i, w) in offsets.windows(2).enumerate() {
            let (a, b) = (usize::try_from(w[0]).unwrap_or(0), usize::try_from(w[1]).unwrap_or(0));
            let slice = indices.get(a..b).ok_or_else(|| value_error(format!("F: polygon {i} has bad offsets")))?;
            corners.clear();
            for &v in slice {
                corners.push(u32::try_from(v).map_err(|_| value_error(format!("F: face {i} has index {v}")))?);
            }
            faces.push(&corners);
        }
    }
    let (mut mesh, mut warnings) = CoreMesh::from_polygons(positions, faces).map_err(value_error)?;
    if let Some(t) = &tetrahedra {
        mesh.tetrahedra = rows::<4>(t, "T")?;
        mesh.validate().map_err(value_error)?;
    }
    if mesh.triangles.is_empty() && mesh.tetrahedra.is_empty() {
        let why = mesh.why_no_triangles();
        return Err(value_error(if why.is_empty() {
            "the mesh has no faces and no tetrahedra: give F or T".to_owned()
        } else {
            format!("F has no face that can be triangulated{why}")
        }));
    }
    warnings = warnings.for_file(Path::new("<arrays>"));
    Ok(PyMesh { mesh, attributes: Attributes::None, warnings })
}

/// The registry as (name, acts on, default weight, summary, has targets, options as
/// (key, "`key` = default and range", doc)) for the Python side's docstrings.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn constraint_types() -> Vec<(String, String, f64, String, bool, Vec<(String, String, String)>)> {
    shapeup_core::constraints::registry()
        .iter()
        .map(|t| {
            let options = t
                .options()
                .iter()
                .map(|o| (o.key.to_string(), shapeup_core::constraints::option_markdown(o), o.doc.to_string()))
                .collect();
            (
                t.name().into(),
                t.element().plural(),
                t.default_multiplier(),
                t.summary().into(),
                t.has_targets(),
                options,
            )
        })
        .collect()
}

/// The table `shapeup types` prints (Markdown).
#[pyfunction]
fn catalogue_markdown() -> String {
    shapeup_core::constraints::catalogue_markdown()
}

/// Adds a group from one entry (JSON text in scene keys: the scene parser and builder) on
/// `mesh` / `rest` (user coordinates) to `system`; returns (id, name, type, constraints). The
/// group calls below serve Solver and Simulation alike.
fn add_entry(
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

fn held(system: &System, id: u32) -> PyResult<Vec<u32>> {
    let group = system.group(GroupId(id)).ok_or_else(|| value_error(format!("no group {id}")))?;
    Ok(held_vertices(group))
}

fn set_targets(system: &mut System, id: u32, targets: &PyReadonlyArray2<'_, f64>) -> PyResult<()> {
    let targets = points(targets, "targets")?;
    system.set_targets(GroupId(id), &targets).map_err(value_error)
}

fn set_weight(system: &mut System, id: u32, weight: f64) -> PyResult<()> {
    system.set_multiplier(GroupId(id), weight).map_err(value_error)
}

fn remove(system: &mut System, id: u32) -> PyResult<()> {
    system.remove_group(GroupId(id)).map(|_| ()).ok_or_else(|| value_error(format!("no group {id}")))
}

/// The report of a solve as JSON text.
fn solve_report_json(report: &SolveReport, acceleration: Acceleration) -> String {
    serde_json::json!({
        "iterations": report.energies.len(),
        "initial_energy": report.initial_energy,
        "energy": report.energies,
        "relative_change": shapeup_core::scene::relative_changes(report.initial_energy, &report.energies),
        "acceleration": acceleration.name(),
        "rejected": report.rejected,
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
    let mut interrupt: Option<PyErr> = None;
    let result = py.detach(|| {
        let mut last_check = Instant::now();
        system.solve_with(q, iterations, tolerance, |_, _| {
            if last_check.elapsed() < SIGNAL_CHECK {
                return ControlFlow::Continue(());
            }
            last_check = Instant::now();
            match Python::attach(|py| py.check_signals()) {
                Ok(()) => ControlFlow::Continue(()),
                Err(e) => {
                    interrupt = Some(e);
                    ControlFlow::Break(())
                }
            }
        })
    });
    if let Some(e) = interrupt {
        return Err(e);
    }
    result.map_err(solve_error)
}

/// Constraint groups on one mesh and the ShapeUp solver (user coordinates, no normalization).
#[pyclass(name = "_Solver", module = "shapeup._shapeup")]
struct PySolver {
    mesh: CoreMesh,
    rest: RestGeometry,
    system: System,
}

#[pymethods]
impl PySolver {
    #[new]
    fn new(mesh: &PyMesh) -> Self {
        let rest = RestGeometry::of_mesh(mesh.mesh.positions.clone(), &mesh.mesh);
        let system = System::new(mesh.mesh.num_vertices(), SolverParams::default());
        PySolver { mesh: mesh.mesh.clone(), rest, system }
    }

    /// Adds a group from a scene entry (JSON text); returns (id, name, type, constraints).
    fn add(&mut self, entry: &str) -> PyResult<(u32, String, String, usize)> {
        add_entry(&mut self.system, &self.mesh, &self.rest, entry)
    }

    fn held(&self, id: u32) -> PyResult<Vec<u32>> {
        held(&self.system, id)
    }

    fn set_targets(&mut self, id: u32, targets: PyReadonlyArray2<'_, f64>) -> PyResult<()> {
        set_targets(&mut self.system, id, &targets)
    }

    fn set_weight(&mut self, id: u32, weight: f64) -> PyResult<()> {
        set_weight(&mut self.system, id, weight)
    }

    fn remove(&mut self, id: u32) -> PyResult<()> {
        remove(&mut self.system, id)
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
        let report = solve_interruptible(py, &mut self.system, &mut x, iterations, tolerance)?;
        Ok((to_array(py, &x), solve_report_json(&report, acceleration)))
    }

    /// (E, [(id, E_group)]) at q.
    fn energy(&mut self, q: PyReadonlyArray2<'_, f64>) -> PyResult<(f64, Vec<(u32, f64)>)> {
        let q = points(&q, "q")?;
        let e = self.system.energy(&q).map_err(solve_error)?;
        Ok((e.total, e.per_group.iter().map(|(id, v)| (id.0, *v)).collect()))
    }
}

/// A Projective Dynamics simulation on one mesh (user coordinates and units).
#[pyclass(name = "_Simulation", module = "shapeup._shapeup")]
struct PySimulation {
    mesh: CoreMesh,
    rest: RestGeometry,
    simulation: CoreSimulation,
}

#[pymethods]
impl PySimulation {
    /// `params`: JSON text with time_step, gravity, stiffness, damping, density, iterations,
    /// tolerance, acceleration (each optional; defaults as in scene files).
    #[new]
    fn new(mesh: &PyMesh, params: &str) -> PyResult<Self> {
        let settings: shapeup_core::scene::SolverSettings =
            serde_json::from_str(params).map_err(|e| value_error(format!("bad simulation settings: {e}")))?;
        let rest = RestGeometry::of_mesh(mesh.mesh.positions.clone(), &mesh.mesh);
        if !(settings.density.is_finite() && settings.density > 0.0) {
            return Err(value_error(format!("density must be a finite number > 0, found {}", settings.density)));
        }
        let masses = lumped_masses(&rest, settings.density);
        let solver = SolverParams {
            acceleration: settings.acceleration,
            anderson_window: settings.anderson_window,
            lbfgs_memory: settings.lbfgs_memory,
            ..SolverParams::default()
        };
        let dynamics = DynamicsParams {
            time_step: settings.time_step,
            stiffness: settings.stiffness,
            damping: settings.damping,
            gravity: DVec3::from_array(settings.gravity),
            iterations: settings.iterations,
            tolerance: settings.tolerance,
        };
        dynamics.validate().map_err(value_error)?;
        let system = System::new(mesh.mesh.num_vertices(), solver);
        let simulation = CoreSimulation::new(system, masses, rest.positions.clone(), dynamics).map_err(value_error)?;
        Ok(PySimulation { mesh: mesh.mesh.clone(), rest, simulation })
    }

    fn add(&mut self, entry: &str) -> PyResult<(u32, String, String, usize)> {
        add_entry(self.simulation.system_mut(), &self.mesh, &self.rest, entry)
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

    /// `n` time steps without the GIL (Ctrl+C stops between steps); returns the steps' reports
    /// as JSON text.
    fn step(&mut self, py: Python<'_>, n: usize) -> PyResult<String> {
        let mut interrupt = None;
        let simulation = &mut self.simulation;
        let reports = py.detach(|| {
            let mut reports = Vec::with_capacity(n.min(1 << 16));
            let mut last_check = Instant::now();
            for _ in 0..n {
                let r = simulation.step()?;
                reports.push(serde_json::json!({
                    "energy": r.energy, "iterations": r.iterations, "rejected": r.rejected,
                    "local_s": r.local_seconds, "global_s": r.global_seconds,
                    "setup_s": r.setup_seconds, "total_s": r.total_seconds,
                }));
                if !simulation.kinetic_energy().is_finite() {
                    return Err(SolveError::NonFiniteEnergy);
                }
                if last_check.elapsed() >= SIGNAL_CHECK {
                    last_check = Instant::now();
                    if let Err(e) = Python::attach(|py| py.check_signals()) {
                        interrupt = Some(e);
                        break;
                    }
                }
            }
            Ok(reports)
        });
        if let Some(e) = interrupt {
            return Err(e);
        }
        Ok(serde_json::Value::from(reports.map_err(solve_error)?).to_string())
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

/// What `Scene.simulate` returns: the kept frames' positions, their numbers, the report.
type Frames<'py> = (Vec<Bound<'py, PyArray2<f64>>>, Vec<usize>, String);

/// A scene file, loaded: what `shapeup deform` and `shapeup simulate` run.
#[pyclass(name = "_Scene", module = "shapeup._shapeup")]
struct PyScene {
    scene: CoreScene,
}

#[pymethods]
impl PyScene {
    /// Reads a scene file, or (with `text`) scene JSON text standing for that file (its
    /// paths relative to the file's folder): a sweep's scene with overrides applied.
    #[new]
    #[pyo3(signature = (path, text=None))]
    fn new(path: PathBuf, text: Option<&str>) -> PyResult<Self> {
        let scene = match text {
            None => CoreScene::from_file(&path).map_err(scene_error)?,
            Some(text) => {
                let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
                CoreScene::parse(text, SceneFormat::Json, &path, base).map_err(scene_error)?
            }
        };
        Ok(PyScene { scene })
    }

    #[getter]
    fn path(&self) -> PathBuf {
        self.scene.file.clone()
    }

    #[getter]
    fn mode(&self) -> &'static str {
        match self.scene.solver.mode {
            shapeup_core::scene::Mode::Static => "static",
            shapeup_core::scene::Mode::Dynamic => "dynamic",
        }
    }

    #[getter]
    fn steps(&self) -> usize {
        self.scene.solver.steps
    }

    #[getter]
    fn output_path(&self) -> Option<PathBuf> {
        self.scene.output_path()
    }

    #[getter]
    fn report_path(&self) -> Option<PathBuf> {
        self.scene.report_path()
    }

    /// The scene as TOML text.
    fn to_toml(&self) -> String {
        self.scene.to_toml_string()
    }

    /// `shapeup deform`: (output mesh, report JSON text); writes `output` / `report` when given.
    #[pyo3(signature = (iterations=None, output=None, report=None))]
    fn deform(
        &self,
        py: Python<'_>,
        iterations: Option<usize>,
        output: Option<PathBuf>,
        report: Option<PathBuf>,
    ) -> PyResult<(PyMesh, String)> {
        let start = Instant::now();
        if let Some(path) = &output {
            check_extension(path, MESH_OUTPUT_EXTENSIONS)?;
        }
        if let Some(path) = &report {
            check_extension(path, &["json"])?;
        }
        for path in output.iter().chain(&report) {
            check_folder(path)?;
        }
        let mut loaded = py.detach(|| self.scene.load()).map_err(scene_error)?;
        let iterations = loaded.static_iterations(iterations);
        let mut q = loaded.rest.positions.clone();
        let tolerance = self.scene.solver.tolerance;
        let solve = solve_interruptible(py, &mut loaded.system, &mut q, iterations, tolerance)
            .map_err(|e| annotate(py, e, &self.scene.file))?;
        let mut warnings = loaded.warnings.clone();
        let mesh = match &output {
            Some(path) => {
                let (mesh, written) = py.detach(|| loaded.write_result(path, &q, None)).map_err(io_error)?;
                warnings.extend(written);
                mesh
            }
            None => loaded.output_mesh(&q, false, |v| loaded.system.is_solved(v)),
        };
        let json = loaded.deform_report(&q, &solve, &mesh, &warnings, start.elapsed().as_secs_f64());
        let text = serde_json::to_string_pretty(&json).map_err(value_error)?;
        if let Some(path) = &report {
            shapeup_core::io::write_atomic(path, |w| w.write_all(text.as_bytes())).map_err(io_error)?;
        }
        Ok((PyMesh { mesh, attributes: loaded.attributes.clone(), warnings }, text))
    }

    /// `shapeup simulate`: `frames` time steps from rest. Returns (positions of every
    /// `every`-th frame and the last, frame numbers, report JSON text); writes the frames to
    /// `output` in `format` when given.
    #[pyo3(signature = (frames, every=1, output=None, format="obj", report=None))]
    fn simulate<'py>(
        &self,
        py: Python<'py>,
        frames: usize,
        every: usize,
        output: Option<PathBuf>,
        format: &str,
        report: Option<PathBuf>,
    ) -> PyResult<Frames<'py>> {
        let start = Instant::now();
        if every == 0 {
            return Err(value_error("every must be at least 1"));
        }
        let format = FrameFormat::parse(format).map_err(value_error)?;
        if let Some(r) = &report {
            check_extension(r, &["json"])?;
            check_folder(r)?;
        }
        let mut loaded = py.detach(|| self.scene.load()).map_err(scene_error)?;
        if let Some(dir) = &output {
            std::fs::create_dir_all(dir).map_err(|e| {
                PyOSError::new_err(format!("cannot create the output directory {}: {e}", dir.display()))
            })?;
            check_folder(&dir.join("frame"))?;
        }
        let mut run = loaded.start_scene_simulation().map_err(scene_error)?;
        let loaded = &loaded;
        let mut writer = output.as_deref().map(|dir| FrameWriter::new(loaded, dir, frames, format));
        let mut kept: Vec<(usize, Vec<DVec3>)> = Vec::new();
        let mut keep = |k: usize, sim: &CoreSimulation, writer: &mut Option<FrameWriter<'_>>| -> PyResult<()> {
            let system = sim.system();
            let mesh = loaded.output_mesh(sim.positions(), false, |v| system.is_solved(v));
            kept.push((k, mesh.positions));
            if let Some(w) = writer {
                w.write(k, sim).map_err(io_error)?;
            }
            Ok(())
        };
        keep(0, &run.simulation, &mut writer)?;
        let mut last_check = Instant::now();
        let mut totals = StepTotals::default();
        for k in 1..=frames {
            let step = py
                .detach(|| run.step())
                .map_err(|e| value_error(format!("{}: step {k} of {frames} failed: {e}", self.scene.file.display())))?;
            totals.add(&step);
            let energy = match step.energy {
                Some(e) => e,
                None => {
                    let t = Instant::now();
                    let e = py.detach(|| run.simulation.energy()).map_err(solve_error)?;
                    totals.energy_seconds += t.elapsed().as_secs_f64();
                    e
                }
            };
            totals.energies.push(energy);
            if k % every == 0 || k == frames {
                keep(k, &run.simulation, &mut writer)?;
            }
            if last_check.elapsed() >= SIGNAL_CHECK {
                last_check = Instant::now();
                py.check_signals()?;
            }
        }
        if let Some(w) = &writer
            && format == FrameFormat::Vtu
        {
            w.write_pvd().map_err(io_error)?;
        }
        let mut warnings = loaded.warnings.clone();
        if let Some(w) = &mut writer {
            warnings.extend(w.warnings.take().unwrap_or_default());
        }
        let written = writer.as_ref().map_or(0, |w| w.written.len());
        let json = loaded.simulate_report(
            &run.simulation,
            &totals,
            frames,
            format.extension(),
            written,
            &warnings,
            start.elapsed().as_secs_f64(),
        );
        let text = serde_json::to_string_pretty(&json).map_err(value_error)?;
        if let Some(path) = &report {
            shapeup_core::io::write_atomic(path, |w| w.write_all(text.as_bytes())).map_err(io_error)?;
        }
        let numbers = kept.iter().map(|(k, _)| *k).collect();
        let arrays = kept.iter().map(|(_, p)| to_array(py, p)).collect();
        Ok((arrays, numbers, text))
    }
}

/// A solve error of a scene names the scene file, as the command line's does.
fn annotate(py: Python<'_>, e: PyErr, file: &Path) -> PyErr {
    if e.is_instance_of::<SolveFailed>(py) {
        SolveFailed::new_err(format!("{}: {}", file.display(), e.value(py)))
    } else {
        e
    }
}

/// The library's before-any-work output checks as Python exceptions: a missing folder is a
/// `FileNotFoundError`, an unwritable one an `OSError`, an extension a `ValueError`.
fn output_error(e: OutputError) -> PyErr {
    match e {
        OutputError::MissingFolder { .. } => pyo3::exceptions::PyFileNotFoundError::new_err(e.to_string()),
        OutputError::Unwritable { .. } => PyOSError::new_err(e.to_string()),
        OutputError::Extension { .. } => value_error(e),
    }
}

fn check_folder(path: &Path) -> PyResult<()> {
    check_output_folder(path).map_err(output_error)
}

fn check_extension(path: &Path, allowed: &'static [&'static str]) -> PyResult<()> {
    check_output_extension(path, allowed).map_err(output_error)
}

/// Sets the worker threads of the parallel local step (once, before the first solve).
#[pyfunction]
fn set_threads(n: usize) -> PyResult<()> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build_global()
        .map_err(|e| value_error(format!("cannot set the threads: {e} (set them once, before the first solve)")))
}

#[pymodule]
fn _shapeup(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(write_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh_from_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(constraint_types, m)?)?;
    m.add_function(wrap_pyfunction!(catalogue_markdown, m)?)?;
    m.add_function(wrap_pyfunction!(set_threads, m)?)?;
    m.add_class::<PyMesh>()?;
    m.add_class::<PySolver>()?;
    m.add_class::<PySimulation>()?;
    m.add_class::<PyScene>()?;
    m.add("SolveFailed", m.py().get_type::<SolveFailed>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
