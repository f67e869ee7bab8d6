//! Frames of a scene's simulation as mesh files (`shapeup simulate`, the Python package's
//! `Scene.simulate`): `DIR/frame_000k.EXT` in one of the mesh formats, and for VTU a ParaView
//! `frames.pvd` time series.

use super::LoadedScene;
use crate::dynamics::Simulation;
use crate::io::vtu::{PointScalars, PointVectors, write_pvd, write_vtu_with_scalars};
use crate::io::{IoError, write_atomic, write_mesh};
use crate::mesh::Mesh;
use crate::warnings::Warnings;
use glam::DVec3;
use std::path::{Path, PathBuf};

/// The file format of the frames, named by `--format`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameFormat {
    /// Wavefront OBJ (the surface).
    Obj,
    /// PLY (the surface).
    Ply,
    /// OFF (the surface).
    Off,
    /// Binary STL (the surface; STL keeps no shared or unreferenced vertices).
    Stl,
    /// VTK XML unstructured grid: the whole mesh with its tetrahedra and a `velocity` array,
    /// plus a `frames.pvd` time series.
    Vtu,
    /// Gmsh MSH 4.1: the whole mesh with its tetrahedra.
    Msh,
}

/// A `--format` name that no [`FrameFormat`] has.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unsupported --format \"{name}\" (use one of: {})", FrameFormat::ALL.map(|(n, _)| n).join(", "))]
pub struct UnknownFormat {
    /// The name as given.
    pub name: String,
}

impl FrameFormat {
    /// Every format with its `--format` name, which is also the files' extension.
    pub const ALL: [(&'static str, FrameFormat); 6] = [
        ("obj", FrameFormat::Obj),
        ("ply", FrameFormat::Ply),
        ("off", FrameFormat::Off),
        ("stl", FrameFormat::Stl),
        ("vtu", FrameFormat::Vtu),
        ("msh", FrameFormat::Msh),
    ];

    /// The format named `name` (as `--format` takes it, case-insensitive).
    ///
    /// # Errors
    /// An unknown name, with the list of known ones.
    pub fn parse(name: &str) -> Result<Self, UnknownFormat> {
        match Self::ALL.iter().find(|(n, _)| n.eq_ignore_ascii_case(name)) {
            Some(&(_, format)) => Ok(format),
            None => Err(UnknownFormat { name: name.into() }),
        }
    }

    /// The extension of its files.
    pub fn extension(self) -> &'static str {
        Self::ALL.iter().find(|(_, f)| *f == self).map_or("obj", |(n, _)| n)
    }

    /// Whether it stores the whole mesh with its tetrahedra (else the input's surface).
    pub fn is_volume(self) -> bool {
        matches!(self, FrameFormat::Vtu | FrameFormat::Msh)
    }
}

/// `DIR/frame_0000.EXT`, with at least four digits and enough for the last frame.
pub fn frame_path(dir: &Path, k: usize, last: usize, format: FrameFormat) -> PathBuf {
    let width = last.to_string().len().max(4);
    dir.join(format!("frame_{k:0width$}.{}", format.extension()))
}

/// The ParaView time series of a VTU sequence, next to its frames.
pub const PVD_NAME: &str = "frames.pvd";

/// Whether a run of `frames` steps keeps frame k (0 ≤ k ≤ `frames`): every `every`-th, and
/// always the last.
pub fn is_kept(k: usize, frames: usize, every: usize) -> bool {
    k <= frames && (k.is_multiple_of(every.max(1)) || k == frames)
}

/// The file a run into `dir` would write over one of `inputs` (as [`crate::scene::Scene::input_files`]
/// lists them): `frames` steps, frame k kept when k is a multiple of `every` or the last, in
/// `format`. Returns that frame and the input; `None` when the run replaces none (a scene
/// whose mesh is `DIR/frame_0000.obj` of an earlier run, simulated into `DIR` again, would have
/// its mesh overwritten by the first frame).
pub fn frame_replacing_input(
    inputs: &[(PathBuf, String)],
    dir: &Path,
    frames: usize,
    every: usize,
    format: FrameFormat,
) -> Option<super::ReplacedInput> {
    inputs.iter().find_map(|input| {
        // The file itself, whatever link or relative path names it.
        let real = std::fs::canonicalize(&input.0).ok()?;
        let name = real.file_name()?.to_str()?;
        let output = if format == FrameFormat::Vtu && name == PVD_NAME {
            dir.join(PVD_NAME)
        } else {
            let (digits, _) = name.strip_prefix("frame_")?.split_once('.')?;
            let k = digits.parse::<usize>().ok().filter(|&k| is_kept(k, frames, every))?;
            frame_path(dir, k, frames, format)
        };
        let (input, what) = input;
        same_file::is_same_file(&output, &real).unwrap_or(false).then(|| super::ReplacedInput {
            output,
            input: input.clone(),
            what: what.clone(),
            frame: true,
        })
    })
}

/// The frame files (`frame_…` in any frame format) in `dir` whose names are not in `written`,
/// sorted: an earlier, longer run's, which a run never deletes.
pub fn frames_not_written(dir: &Path, written: &[(f64, String)]) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Vec::new() };
    let ours: std::collections::HashSet<&str> = written.iter().map(|(_, name)| name.as_str()).collect();
    let mut stale: Vec<String> = entries
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|name| {
            name.starts_with("frame_")
                && !ours.contains(name.as_str())
                && Path::new(name)
                    .extension()
                    .and_then(|e| e.to_str())
                    .is_some_and(|e| FrameFormat::ALL.iter().any(|(n, _)| n.eq_ignore_ascii_case(e)))
        })
        .collect();
    stale.sort();
    stale
}

/// [`frames_not_written`] as the one warning a run gives (`frames_of_another_run`), for `dir`.
pub fn warn_of_frames_not_written(dir: &Path, written: &[(f64, String)]) -> Warnings {
    let stale = frames_not_written(dir, written);
    let mut found = Warnings::new();
    found.add_many(
        "frames_of_another_run",
        "frame files this run did not write are in the output folder (an earlier, longer run's, or another format's): a series read from it mixes runs; simulate into an empty folder",
        stale.len(),
        || stale.first().cloned().unwrap_or_default(),
    );
    found.for_file(dir)
}

/// Writes the frames of a simulation, collecting what the first one reports.
pub struct FrameWriter<'a> {
    loaded: &'a LoadedScene,
    dir: &'a Path,
    last: usize,
    format: FrameFormat,
    /// What writing the first frame reported (the same holds for every frame).
    pub warnings: Option<Warnings>,
    /// (time in s, file name) of each frame written, for the `.pvd`.
    pub written: Vec<(f64, String)>,
}

impl<'a> FrameWriter<'a> {
    /// Frames of `loaded`'s simulation into `dir` (which must exist), `last` the number of the
    /// last frame (it sets the digits of the names).
    pub fn new(loaded: &'a LoadedScene, dir: &'a Path, last: usize, format: FrameFormat) -> Self {
        FrameWriter { loaded, dir, last, format, warnings: None, written: Vec::new() }
    }
}

impl FrameWriter<'_> {
    /// Writes frame `k` (the state of `simulation` after k steps), atomically.
    ///
    /// # Errors
    /// [`IoError`] naming the frame's file.
    pub fn write(&mut self, k: usize, simulation: &Simulation) -> Result<(), IoError> {
        let path = frame_path(self.dir, k, self.last, self.format);
        let system = simulation.system();
        let mesh = self.loaded.output_mesh(simulation.positions(), self.format.is_volume(), |v| system.is_solved(v));
        let warnings = if self.format == FrameFormat::Vtu {
            self.write_vtu(&path, &mesh, simulation)?
        } else {
            write_mesh(&path, &mesh, &self.loaded.attributes)?
        };
        if self.warnings.is_none() {
            self.warnings = Some(warnings);
        }
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        self.written.push((simulation.time(), name));
        Ok(())
    }

    /// A VTU frame with the velocities, in input units per second.
    fn write_vtu(&self, path: &Path, mesh: &Mesh, simulation: &Simulation) -> Result<Warnings, IoError> {
        mesh.validate().map_err(|source| IoError::Mesh { path: path.to_path_buf(), source })?;
        let scale = self.loaded.frame.scale;
        let system = simulation.system();
        // Working-frame lengths are input lengths times the scale; time is not scaled.
        let velocity: Vec<DVec3> = simulation
            .velocities()
            .iter()
            .enumerate()
            .map(|(v, &velocity)| if system.is_solved(v) { velocity / scale } else { DVec3::ZERO })
            .collect();
        let mut warnings = Warnings::new();
        let vectors = [PointVectors { name: "velocity", values: &velocity }];
        // With contact: 1 for a vertex touching a collider or the surface at the end of the
        // step, else 0.
        let flags: Option<Vec<f64>> = simulation.contact().map(|c| {
            let touching = c.touching();
            (0..mesh.positions.len()).map(|v| if touching.get(v) == Some(&true) { 1.0 } else { 0.0 }).collect()
        });
        let scalars: Vec<PointScalars> =
            flags.as_deref().map(|values| PointScalars { name: "contact", values }).into_iter().collect();
        write_atomic(path, |w| {
            write_vtu_with_scalars(w, mesh, &self.loaded.attributes, &vectors, &scalars, &mut warnings)
        })?;
        Ok(warnings.for_file(path))
    }

    /// Ends a run whose frames this writer wrote, `result` what the run returned: for VTU,
    /// writes `DIR/frames.pvd` listing the frames written, also after a run that stopped early,
    /// so that the frames before the error stay usable. Returns `result`; after a run that
    /// succeeded, an error writing the `.pvd` (through `io`) instead; after one that failed,
    /// the run's error (the first one is the one to tell).
    ///
    /// # Errors
    /// The run's error, or the `.pvd`'s [`IoError`] mapped by `io`.
    pub fn finish<T, E>(&self, result: Result<T, E>, io: impl FnOnce(IoError) -> E) -> Result<T, E> {
        if self.format != FrameFormat::Vtu || self.written.is_empty() {
            return result;
        }
        let pvd = self.write_pvd();
        match (result, pvd) {
            (Ok(value), Ok(())) => Ok(value),
            (Ok(_), Err(e)) => Err(io(e)),
            (Err(e), _) => Err(e),
        }
    }

    /// Writes `DIR/frames.pvd` listing every frame written so far with its time.
    ///
    /// # Errors
    /// [`IoError`] naming the file.
    pub fn write_pvd(&self) -> Result<(), IoError> {
        let entries: Vec<(f64, &str)> = self.written.iter().map(|(t, name)| (*t, name.as_str())).collect();
        write_atomic(&self.dir.join(PVD_NAME), |w| write_pvd(w, &entries))?;
        Ok(())
    }
}
