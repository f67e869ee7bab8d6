//! `shapeup simulate`: Projective Dynamics time steps of a scene, written as a sequence of mesh
//! files (OBJ by default; PLY, OFF, STL, or VTU and MSH with the tetrahedra).

use anyhow::{Context, Result, bail};
use glam::DVec3;
use indicatif::{ProgressBar, ProgressStyle};
use shapeup_core::Mesh;
use shapeup_core::dynamics::Simulation;
use shapeup_core::io::vtu::{PointVectors, write_pvd, write_vtu};
use shapeup_core::io::{IoError, write_atomic, write_mesh};
use shapeup_core::scene::{LoadedScene, Scene};
use shapeup_core::warnings::Warnings;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

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

impl FrameFormat {
    /// Every format with its `--format` name, which is also the files' extension.
    const ALL: [(&'static str, FrameFormat); 6] = [
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
    pub fn parse(name: &str) -> Result<Self> {
        match Self::ALL.iter().find(|(n, _)| n.eq_ignore_ascii_case(name)) {
            Some(&(_, format)) => Ok(format),
            None => {
                let known: Vec<&str> = Self::ALL.iter().map(|(n, _)| *n).collect();
                bail!("unsupported --format \"{name}\" (use one of: {})", known.join(", "))
            }
        }
    }

    /// The extension of its files.
    fn extension(self) -> &'static str {
        Self::ALL.iter().find(|(_, f)| *f == self).map_or("obj", |(n, _)| n)
    }

    /// Whether it stores the whole mesh with its tetrahedra (else the input's surface).
    fn is_volume(self) -> bool {
        matches!(self, FrameFormat::Vtu | FrameFormat::Msh)
    }
}

/// What to run and write.
pub struct SimulateArgs<'a> {
    /// The scene file.
    pub scene: &'a Path,
    /// Changes to the scene's solver settings from the command line.
    pub overrides: &'a dyn Fn(&mut shapeup_core::scene::SolverSettings),
    /// Time steps to run.
    pub frames: usize,
    /// Output directory (created if missing).
    pub output: &'a Path,
    /// Write frame k only when k is a multiple of this (and always the last).
    pub every: usize,
    /// The frames' format, as `--format` names it (`obj`, `ply`, `off`, `stl`, `vtu`, `msh`).
    pub format: &'a str,
    /// Optional JSON report.
    pub report: Option<&'a Path>,
}

/// `DIR/frame_0000.EXT`, with at least four digits and enough for the last frame.
fn frame_path(dir: &Path, k: usize, last: usize, format: FrameFormat) -> PathBuf {
    let width = last.to_string().len().max(4);
    dir.join(format!("frame_{k:0width$}.{}", format.extension()))
}

/// The ParaView time series of a VTU sequence, next to its frames.
const PVD_NAME: &str = "frames.pvd";

/// Writes the frames of a simulation, collecting what the first one reports.
struct FrameWriter<'a> {
    loaded: &'a LoadedScene,
    dir: &'a Path,
    last: usize,
    format: FrameFormat,
    /// What writing the first frame reported (the same holds for every frame).
    warnings: Option<Warnings>,
    /// (time in s, file name) of each frame written, for the `.pvd`.
    written: Vec<(f64, String)>,
}

impl FrameWriter<'_> {
    /// Writes frame `k` (the state of `simulation` after k steps), atomically.
    fn write(&mut self, k: usize, simulation: &Simulation) -> Result<()> {
        let path = frame_path(self.dir, k, self.last, self.format);
        let system = simulation.system();
        let mesh = self.loaded.output_mesh(simulation.positions(), self.format.is_volume(), |v| system.is_solved(v));
        let warnings = if self.format == FrameFormat::Vtu {
            self.write_vtu(&path, &mesh, simulation)?
        } else {
            write_mesh(&path, &mesh)?
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
        write_atomic(path, |w| write_vtu(w, mesh, &vectors, &mut warnings))?;
        Ok(warnings.for_file(path))
    }

    /// Writes `DIR/frames.pvd` listing every frame written so far with its time.
    fn write_pvd(&self) -> Result<()> {
        let entries: Vec<(f64, &str)> = self.written.iter().map(|(t, name)| (*t, name.as_str())).collect();
        write_atomic(&self.dir.join(PVD_NAME), |w| write_pvd(w, &entries))?;
        Ok(())
    }
}

/// Runs the simulation; frames are written one by one (each atomically), so an error part-way
/// leaves the complete frames before it and no partial file (and, for VTU, a `frames.pvd` that
/// lists them).
pub fn run(args: &SimulateArgs<'_>) -> Result<()> {
    let start = Instant::now();
    let format = FrameFormat::parse(args.format)?;
    if args.every == 0 {
        bail!("--every must be at least 1");
    }
    if let Some(r) = args.report
        && !r.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("json"))
    {
        bail!("{}: the report must be a .json file", r.display());
    }
    if let Some(r) = args.report {
        crate::check_parent_dir(r)?;
    }
    let mut scene = Scene::from_file(args.scene)?;
    (args.overrides)(&mut scene.solver);
    let mut loaded = scene.load()?;
    let mut simulation = loaded.start_simulation()?;
    std::fs::create_dir_all(args.output)
        .with_context(|| format!("cannot create the output directory {}", args.output.display()))?;

    let mut frames = FrameWriter {
        loaded: &loaded,
        dir: args.output,
        last: args.frames,
        format,
        warnings: None,
        written: Vec::new(),
    };
    let progress = if std::io::stderr().is_terminal() {
        let bar = ProgressBar::new(args.frames as u64);
        if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} frames  {per_sec}  ETA {eta}") {
            bar.set_style(style);
        }
        bar
    } else {
        ProgressBar::hidden()
    };
    let (mut energies, mut local, mut global, mut setup, mut energy_seconds, mut rejected) =
        (Vec::with_capacity(args.frames.min(1 << 20)), 0.0, 0.0, 0.0, 0.0, 0);
    let h = simulation.params().time_step;
    let spinning = loaded.spinning_handles(simulation.system())?;
    let mut steps = || -> Result<()> {
        frames.write(0, &simulation)?;
        for k in 1..=args.frames {
            // Spinning handles: their targets at the end of this step.
            for handle in &spinning {
                simulation.system_mut().set_targets(handle.id, &handle.targets_at(k as f64 * h))?;
            }
            // The cause in the same line: only the outermost message is printed.
            let step = simulation
                .step()
                .map_err(|e| anyhow::anyhow!("{}: step {k} of {} failed: {e}", args.scene.display(), args.frames))?;
            if args.report.is_some() {
                // Only a report needs E: plain iterations skip it (one more local step per step).
                let energy = match step.energy {
                    Some(e) => e,
                    None => {
                        let t = Instant::now();
                        let e = simulation
                            .energy()
                            .map_err(|e| anyhow::anyhow!("{}: energy after step {k}: {e}", args.scene.display()))?;
                        energy_seconds += t.elapsed().as_secs_f64();
                        e
                    }
                };
                energies.push(energy);
            }
            // Overflowing velocities fail the step whether or not a report is asked for: a rigid
            // fall keeps E finite (even 0) while ½ m v² overflows, which a report would write as
            // null and the next steps would turn into infinite positions.
            if !simulation.kinetic_energy().is_finite() {
                anyhow::bail!(
                    "{}: step {k} of {}: the kinetic energy is not a finite number (velocities too large); check the gravity, time step and targets",
                    args.scene.display(),
                    args.frames
                );
            }
            local += step.local_seconds;
            rejected += step.rejected;
            global += step.global_seconds;
            setup += step.setup_seconds;
            if k % args.every == 0 || k == args.frames {
                frames.write(k, &simulation)?;
            }
            progress.inc(1);
        }
        Ok(())
    };
    let result = steps();
    progress.finish_and_clear();
    if format == FrameFormat::Vtu && !frames.written.is_empty() {
        match &result {
            Ok(()) => frames.write_pvd()?,
            // The frames written before the error stay usable; the first error is the one to tell.
            Err(_) => {
                let _ = frames.write_pvd();
            }
        }
    }
    result?;
    let written = frames.written.len();
    let mut warnings = loaded.warnings.clone();
    warnings.extend(frames.warnings.take().unwrap_or_default());
    let total = start.elapsed().as_secs_f64();
    let system = simulation.system();
    if let Some(path) = args.report {
        let report = serde_json::json!({
            "vertices": loaded.mesh.num_vertices(),
            "triangles": loaded.mesh.num_triangles(),
            "tetrahedra": loaded.mesh.num_tetrahedra(),
            "constraints": system.num_constraints(),
            "steps": args.frames,
            "format": format.extension(),
            "frames_written": written,
            "time_step": simulation.params().time_step,
            "simulated_s": simulation.time(),
            "energy": energies,
            "kinetic_energy_end": simulation.kinetic_energy(),
            "acceleration": system.params().acceleration.name(),
            "rejected": rejected,
            "warnings": warnings.to_json(),
            "timings": {
                "load_s": loaded.load_seconds,
                "setup_s": loaded.build_seconds + setup,
                "local_s": local,
                "global_s": global,
                "energy_s": energy_seconds,
                "total_s": total,
            },
        });
        let text = serde_json::to_string_pretty(&report)?;
        write_atomic(path, |w| w.write_all(text.as_bytes()))?;
    }
    crate::print_warnings(&warnings);
    let steps_per_s = args.frames as f64 / (total - loaded.load_seconds).max(1e-9);
    writeln!(
        std::io::stdout().lock(),
        "simulated {} steps ({:.3} s) of {} vertices, {} constraints at {steps_per_s:.1} steps/s; wrote {written} frames to {} ({total:.2} s)",
        args.frames,
        simulation.time(),
        loaded.mesh.num_vertices(),
        system.num_constraints(),
        args.output.display()
    )?;
    Ok(())
}
