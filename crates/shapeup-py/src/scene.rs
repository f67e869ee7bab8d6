//! `_Scene`: a scene file, run as `shapeup deform` and `shapeup simulate` run it.

use crate::convert::to_array;
use crate::errors::{check_extension, check_folder, io_error, scene_error, solve_error, value_error};
use crate::mesh::PyMesh;
use crate::signals::{Interrupt, SIGNAL_CHECK};
use glam::DVec3;
use numpy::PyArray2;
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use shapeup_core::dynamics::Simulation as CoreSimulation;
use shapeup_core::io::MESH_OUTPUT_EXTENSIONS;
use shapeup_core::scene::frames::{FrameFormat, FrameWriter};
use shapeup_core::scene::{Scene as CoreScene, SceneFormat, StepTotals};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What `Scene.simulate` returns: the kept frames' positions, their numbers, the report.
pub(crate) type Frames<'py> = (Vec<Bound<'py, PyArray2<f64>>>, Vec<usize>, String);

/// A scene file, loaded: what `shapeup deform` and `shapeup simulate` run.
#[pyclass(name = "_Scene", module = "shapeup._shapeup")]
pub(crate) struct PyScene {
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
        // The command line's static solve, stopping for Ctrl+C (the `KeyboardInterrupt` is
        // returned after the solve stops).
        let mut interrupt = Interrupt::new();
        let result = py.detach(|| loaded.solve_static_with(iterations, |_, _| interrupt.poll()));
        if let Some(e) = interrupt.error {
            return Err(e);
        }
        let (q, solve) = result.map_err(scene_error)?;
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
