//! Frames of a scene's simulation as mesh files (`shapeup simulate`, the Python package's
//! `Scene.simulate`): `DIR/frame_000k.EXT` in one of the mesh formats, and for VTU a ParaView
//! `frames.pvd` time series.

use super::LoadedScene;
use crate::dynamics::Simulation;
use crate::io::vtu::{PointScalars, PointVectors, write_pvd, write_vtu_with_scalars};
use crate::io::{IoError, OutputError, check_output_folder, write_atomic, write_mesh};
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

/// Whether `name` is a frame file's (`frame_` and digits, with a frame format's extension) or a
/// VTU series' `frames.pvd`: what a run into a folder replaces there.
pub fn is_frame_file_name(name: &str) -> bool {
    let frame = name.strip_prefix("frame_").and_then(|rest| rest.split_once('.')).is_some_and(|(digits, ext)| {
        !digits.is_empty()
            && digits.bytes().all(|b| b.is_ascii_digit())
            && FrameFormat::ALL.iter().any(|(n, _)| n.eq_ignore_ascii_case(ext))
    });
    name == PVD_NAME || frame
}

/// The input (of `inputs`, as [`crate::scene::Scene::input_files`] lists them) that a run into
/// `dir` would replace: a frame file or `frames.pvd` in `dir`, which the run writes over or
/// removes ([`FrameFolder::commit`]; a scene whose mesh is `DIR/frame_0000.obj` of an earlier
/// run, simulated into `DIR` again). `None` when it replaces none.
pub fn frame_replacing_input(inputs: &[(PathBuf, String)], dir: &Path) -> Option<super::ReplacedInput> {
    // The folder itself, whatever link or relative path names it; a new folder holds no input.
    let dir_real = std::fs::canonicalize(dir).ok()?;
    inputs.iter().find_map(|(input, what)| {
        let real = std::fs::canonicalize(input).ok()?;
        let name = real.file_name()?.to_str()?;
        (real.parent() == Some(dir_real.as_path()) && is_frame_file_name(name)).then(|| super::ReplacedInput {
            output: dir.join(name),
            input: input.clone(),
            what: what.clone(),
            frame: true,
        })
    })
}

/// The frame files in `dir` (files, or links, named as [`is_frame_file_name`] says; never a
/// folder) whose names are not in `written`, sorted: an earlier run's (a longer one's, another
/// format's), which a run replaces.
pub fn frames_not_written(dir: &Path, written: &[String]) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Vec::new() };
    let ours: std::collections::HashSet<&str> = written.iter().map(String::as_str).collect();
    let mut stale: Vec<String> = entries
        .filter_map(Result::ok)
        .filter(|e| e.file_type().is_ok_and(|t| !t.is_dir()))
        .filter_map(|e| e.file_name().into_string().ok())
        .filter(|name| is_frame_file_name(name) && !ours.contains(name.as_str()))
        .collect();
    stale.sort();
    stale
}

/// The folder a run's frames end in (`shapeup simulate -o DIR`, Python's
/// `Scene.simulate(output=DIR)`), filled through a staging folder beside it so that a run
/// that fails writes nothing.
///
/// Frames go into a hidden staging folder, `.DIR.partial-XXXXXXXX` beside `DIR`, and reach
/// `DIR` only when the run succeeds ([`FrameFolder::commit`]); dropped without a commit (an
/// error, Ctrl+C), the staging folder is removed with what it holds. A new `DIR` is the
/// staging folder renamed in one step. Into an existing `DIR` each frame is renamed in
/// (replacing a file of the same name) and then the frame files of an earlier run that this
/// one did not write (a longer run's, another format's, a `frames.pvd` not this run's) are
/// removed, with one warning that counts them: the folder holds one run's series. Other files
/// in `DIR` stay. As for every output, the folder `DIR` goes in must exist: shapeup creates
/// the folder named, never the folders above it.
pub struct FrameFolder {
    target: PathBuf,
    staging: tempfile::TempDir,
}

impl FrameFolder {
    /// Checks that `target` can be a folder of frames (its parent exists and takes files; it
    /// is not a file; if it exists, it takes files) and creates the staging folder beside it.
    ///
    /// # Errors
    /// [`OutputError`] naming `target`.
    pub fn create(target: &Path) -> Result<Self, OutputError> {
        // `.`, `..`, `sub/..`: the folder itself, by a name that has a folder above it.
        let named;
        let target = match std::fs::canonicalize(target) {
            Ok(real) if target.is_dir() && target.file_name().is_none() => {
                named = real;
                named.as_path()
            }
            _ => target,
        };
        check_output_folder(target)?;
        // A link to nothing: neither a folder to fill nor a name to rename the frames to.
        if !target.exists()
            && let Ok(pointed) = std::fs::read_link(target)
        {
            return Err(OutputError::MissingFolder { path: target.to_path_buf(), dir: pointed });
        }
        if target.exists() {
            if !target.is_dir() {
                return Err(OutputError::NotAFolder { path: target.to_path_buf(), file: target.to_path_buf() });
            }
            // Frames are renamed into it at the end: it must take files.
            check_output_folder(&target.join("frame"))?;
        }
        let parent = target.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        let mut prefix = std::ffi::OsString::from(".");
        prefix.push(target.file_name().unwrap_or(target.as_os_str()));
        prefix.push(".partial-");
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).rand_bytes(8);
        #[cfg(unix)]
        {
            // As a folder made by mkdir: the umask decides (a staging folder is 0700).
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o777));
        }
        let staging = builder.tempdir_in(parent).map_err(|source| OutputError::Unwritable {
            path: target.to_path_buf(),
            dir: parent.to_path_buf(),
            source,
        })?;
        Ok(FrameFolder { target: target.to_path_buf(), staging })
    }

    /// Where the frames are written until [`FrameFolder::commit`].
    pub fn staging(&self) -> &Path {
        self.staging.path()
    }

    /// The folder the frames end in.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Moves the staged frames into the target folder (see [`FrameFolder`]). Returns the
    /// warning (`earlier_frames_removed`, naming the folder) when an earlier run's frames were
    /// removed.
    ///
    /// # Errors
    /// [`IoError::Write`] naming the folder or the file that could not be moved or removed.
    pub fn commit(self) -> Result<Warnings, IoError> {
        let write_error = |path: &Path, source| IoError::Write { path: path.to_path_buf(), source };
        let target = self.target.clone();
        if !target.exists() {
            let staging = self.staging.keep();
            return match std::fs::rename(&staging, &target) {
                Ok(()) => Ok(Warnings::new()),
                Err(e) => {
                    let _ = std::fs::remove_dir_all(&staging);
                    Err(write_error(&target, e))
                }
            };
        }
        let entries = std::fs::read_dir(self.staging.path()).map_err(|e| write_error(self.staging.path(), e))?;
        let mut staged = Vec::new();
        for entry in entries {
            let entry = entry.map_err(|e| write_error(self.staging.path(), e))?;
            staged.push(entry.file_name());
        }
        // Before anything moves: a folder in the way of a frame fails the run with the target
        // as it was.
        if let Some(name) = staged.iter().find(|name| target.join(name).is_dir()) {
            let source = std::io::Error::new(std::io::ErrorKind::IsADirectory, "a folder of that name is in the way");
            return Err(write_error(&target.join(name), source));
        }
        for name in &staged {
            let to = target.join(name);
            std::fs::rename(self.staging.path().join(name), &to).map_err(|e| write_error(&to, e))?;
        }
        let written: Vec<String> = staged.iter().map(|n| n.to_string_lossy().into_owned()).collect();
        let earlier = frames_not_written(&target, &written);
        for name in &earlier {
            std::fs::remove_file(target.join(name)).map_err(|e| write_error(&target.join(name), e))?;
        }
        let mut found = Warnings::new();
        found.add_many(
            "earlier_frames_removed",
            "frame files of an earlier run that this one did not write (a longer run's, another format's) were removed from the output folder, so that it holds this run's series",
            earlier.len(),
            || earlier.first().cloned().unwrap_or_default(),
        );
        Ok(found.for_file(&target))
    }
}

/// Writes the frames of a simulation, collecting what the first one reports.
pub struct FrameWriter<'a> {
    loaded: &'a LoadedScene,
    dir: &'a Path,
    /// The folder the frames reach: what messages name.
    shown: &'a Path,
    last: usize,
    format: FrameFormat,
    /// What writing the first frame reported (the same holds for every frame).
    pub warnings: Option<Warnings>,
    /// (time in s, file name) of each frame written, for the `.pvd`.
    pub written: Vec<(f64, String)>,
}

impl<'a> FrameWriter<'a> {
    /// Frames of `loaded`'s simulation into `folder`'s staging folder (warnings name the
    /// files as they will be in its target), `last` the number of the last frame (it sets the
    /// digits of the names).
    pub fn new(loaded: &'a LoadedScene, folder: &'a FrameFolder, last: usize, format: FrameFormat) -> Self {
        let (dir, shown) = (folder.staging(), folder.target());
        FrameWriter { loaded, dir, shown, last, format, warnings: None, written: Vec::new() }
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
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if self.warnings.is_none() {
            self.warnings = Some(warnings.renamed(&path, &self.shown.join(&name)));
        }
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

    /// Ends a run that succeeded: for VTU, writes `DIR/frames.pvd` listing the frames written.
    ///
    /// # Errors
    /// The `.pvd`'s [`IoError`].
    pub fn finish(&self) -> Result<(), IoError> {
        if self.format != FrameFormat::Vtu || self.written.is_empty() {
            return Ok(());
        }
        self.write_pvd()
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
