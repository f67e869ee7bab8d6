//! `_Scene`: a scene file, run as `shapeup deform` and `shapeup simulate` run it.

use crate::convert::to_array;
use crate::errors::{SolveFailed, check_extension, check_folder, io_error, output_error, scene_error, value_error};
use crate::mesh::PyMesh;
use crate::signals::Interrupt;
use glam::DVec3;
use numpy::PyArray2;
use pyo3::prelude::*;
use shapeup_core::io::MESH_OUTPUT_EXTENSIONS;
use shapeup_core::scene::frames::{FrameFolder, FrameFormat, FrameWriter, frame_replacing_input};
use shapeup_core::scene::{RunError, Scene as CoreScene};
use std::ops::ControlFlow;
use std::path::PathBuf;
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
    /// Reads a scene file; with `overrides` (JSON text: a list of `[dotted key, value]`
    /// pairs), the core applies them to the file's entries before checking it
    /// ([`CoreScene::from_file_with_overrides`]).
    #[new]
    #[pyo3(signature = (path, overrides=None))]
    fn new(path: PathBuf, overrides: Option<&str>) -> PyResult<Self> {
        let scene = match overrides {
            None => CoreScene::from_file(&path),
            Some(text) => {
                let overrides: Vec<(String, serde_json::Value)> =
                    serde_json::from_str(text).map_err(|e| value_error(format!("bad scene overrides: {e}")))?;
                CoreScene::from_file_with_overrides(&path, &overrides)
            }
        };
        Ok(PyScene { scene: scene.map_err(scene_error)? })
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
        let outputs: Vec<&std::path::Path> = output.iter().chain(&report).map(PathBuf::as_path).collect();
        if let Some(replaced) = self.scene.input_replaced_by(&outputs) {
            // As `shapeup deform`: a run never replaces its inputs.
            return Err(value_error(replaced));
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
        if let Some(dir) = &output
            && let Some(replaced) = frame_replacing_input(&self.scene.input_files(), dir)
        {
            // As `shapeup simulate`: a run never replaces its inputs.
            return Err(value_error(replaced));
        }
        // As `shapeup simulate`: frames reach `output` only when the run succeeds.
        let folder = output.as_deref().map(FrameFolder::create).transpose().map_err(output_error)?;
        let mut loaded = py.detach(|| self.scene.load()).map_err(scene_error)?;
        let mut run = loaded.start_scene_simulation().map_err(scene_error)?;
        let loaded = &loaded;
        let mut writer = folder.as_ref().map(|f| FrameWriter::new(loaded, f, frames, format));
        let mut kept: Vec<(usize, Vec<DVec3>)> = Vec::new();
        // The core's run of `shapeup simulate` without the GIL (Ctrl+C stops it between steps;
        // the `KeyboardInterrupt` is returned after it stops). E after every step is recorded:
        // the report is always returned.
        let mut interrupt = Interrupt::new();
        let result = py.detach(|| {
            run.run(frames, every, true, |k, simulation, keep| -> PyResult<()> {
                if keep {
                    let system = simulation.system();
                    let mesh = loaded.output_mesh(simulation.positions(), false, |v| system.is_solved(v));
                    kept.push((k, mesh.positions));
                    if let Some(w) = &mut writer {
                        w.write(k, simulation).map_err(io_error)?;
                    }
                }
                match (interrupt.poll(), interrupt.error.take()) {
                    (ControlFlow::Break(()), Some(e)) => Err(e),
                    _ => Ok(()),
                }
            })
        });
        let file = self.scene.file.display();
        let result = result.map_err(|e| match e {
            RunError::Stopped(e) => e,
            e @ RunError::Step { .. } => value_error(format!("{file}: {e}")),
            e @ RunError::Energy { .. } => SolveFailed::new_err(format!("{file}: {e}")),
        });
        // Nothing reaches the output folder unless the run succeeded.
        let totals = result?;
        let mut warnings = loaded.warnings.clone();
        let written = writer.as_ref().map_or(0, |w| w.written.len());
        if let Some(mut w) = writer {
            w.finish().map_err(io_error)?;
            warnings.extend(w.warnings.take().unwrap_or_default());
        }
        if let Some(f) = folder {
            warnings.extend(py.detach(|| f.commit()).map_err(io_error)?);
        }
        // What the run says once, as the command line's report has it.
        let mut found = shapeup_core::warnings::Warnings::new();
        totals.add_warnings(&mut found);
        warnings.extend(found.for_file(&self.scene.file));
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
