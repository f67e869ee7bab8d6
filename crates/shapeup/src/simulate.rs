//! `shapeup simulate`: Projective Dynamics time steps of a scene, written as a sequence of mesh
//! files (OBJ by default; PLY, OFF, STL, or VTU and MSH with the tetrahedra).

use anyhow::{Context, Result, bail};
use shapeup_core::io::write_atomic;
use shapeup_core::scene::frames::{FrameFolder, FrameFormat, FrameWriter, frame_replacing_input};
use shapeup_core::scene::{RunError, Scene};
use std::io::Write;
use std::path::Path;
use std::time::Instant;

/// What to run and write.
pub struct SimulateArgs<'a> {
    /// The scene file.
    pub scene: &'a Path,
    /// Changes to the scene's solver settings from the command line.
    pub overrides: &'a dyn Fn(&mut shapeup_core::scene::SolverSettings),
    /// Time steps to run.
    pub frames: usize,
    /// Output folder (created if missing; the folder it goes in must exist); `None`: the
    /// scene's `[output] path`.
    pub output: Option<&'a Path>,
    /// Write frame k only when k is a multiple of this (and always the last).
    pub every: usize,
    /// The frames' format, as `--format` names it (`obj`, `ply`, `off`, `stl`, `vtu`, `msh`).
    pub format: &'a str,
    /// Optional JSON report.
    pub report: Option<&'a Path>,
}

/// Runs the simulation; frames are written into a staging folder beside the output folder and
/// moved in when the run succeeds ([`FrameFolder`]), so an error part-way writes nothing.
pub fn run(args: &SimulateArgs<'_>) -> Result<()> {
    let start = Instant::now();
    let format = FrameFormat::parse(args.format).map_err(anyhow::Error::msg)?;
    if args.every == 0 {
        bail!("--every must be at least 1");
    }
    let mut scene = Scene::from_file(args.scene)?;
    (args.overrides)(&mut scene.solver);
    let output = match args.output {
        Some(o) => o.to_path_buf(),
        None => scene.output_path().with_context(|| {
            format!("{}: no output folder: give -o DIR, or `path` in the scene's [output] table", args.scene.display())
        })?,
    };
    let report = args.report.map(Path::to_path_buf).or_else(|| scene.report_path());
    if let Some(r) = report.as_deref() {
        // As `deform` checks its report: a folder or another extension is refused before any
        // step (a folder named r.json used to fail after the last frame).
        shapeup_core::io::check_output_extension(r, &["json"])?;
        // A report in the frames' folder, which the run creates, needs no folder yet.
        let in_new_output = r.parent().is_some_and(|p| p.components().eq(output.components())) && !output.exists();
        if !in_new_output {
            crate::check_parent_dir(r)?;
        }
        crate::refuse_inputs_as_outputs(&scene, &[r])?;
    }
    // A run never replaces its inputs: not with a frame either.
    if let Some(replaced) = frame_replacing_input(&scene.input_files(), &output) {
        return Err(replaced.into());
    }
    // Ctrl+C (also while loading) stops the run between steps, so that the staging folder is removed (a process
    // killed by the signal would leave it behind).
    let interrupted = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flag = interrupted.clone();
    // Fails only when a handler is already set (a second run in one process): it then stays.
    let _ = ctrlc::set_handler(move || flag.store(true, std::sync::atomic::Ordering::Relaxed));
    // Before any work: the folder it goes in exists and takes files, and it is not a file.
    let folder = FrameFolder::create(&output)?;
    let spinner = crate::logging::spinner(format!("loading {}", args.scene.display()));
    let mut loaded = scene.load()?;
    let mut run = loaded.start_scene_simulation()?;
    drop(spinner);

    let mut frames = FrameWriter::new(&loaded, &folder, args.frames, format);
    let progress = crate::logging::bar(args.frames as u64, "{bar:40} {pos}/{len} frames  {per_sec}  ETA {eta}");
    // Only a report needs E: plain iterations skip it (one more local step per step).
    let result = run.run(args.frames, args.every, report.is_some(), |k, simulation, keep| -> Result<()> {
        if interrupted.load(std::sync::atomic::Ordering::Relaxed) {
            bail!(
                "interrupted (Ctrl+C) after step {k} of {}; nothing written to {}: frames reach it only when a run completes",
                args.frames,
                shapeup_core::io::one_line(output.display())
            );
        }
        if keep {
            frames.write(k, simulation)?;
        }
        if k > 0 {
            progress.bar.inc(1);
        }
        Ok(())
    });
    // The cause in the same line: only the outermost message is printed.
    let result = result.map_err(|e| match e {
        RunError::Stopped(e) => e,
        e => anyhow::anyhow!("{}: {e}", args.scene.display()),
    });
    drop(progress);
    // Nothing reaches the output folder unless the run succeeded (the staging folder goes
    // when `folder` is dropped).
    let totals = result?;
    frames.finish()?;
    let written = frames.written.len();
    let mut warnings = loaded.warnings.clone();
    warnings.extend(frames.warnings.take().unwrap_or_default());
    drop(frames);
    warnings.extend(folder.commit()?);
    // What the run found names the scene.
    let mut found = shapeup_core::warnings::Warnings::new();
    totals.add_warnings(&mut found);
    warnings.extend(found.for_file(args.scene));
    let total = start.elapsed().as_secs_f64();
    let simulation = &run.simulation;
    let system = simulation.system();
    if let Some(path) = report.as_deref() {
        let report =
            loaded.simulate_report(simulation, &totals, args.frames, format.extension(), written, &warnings, total);
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
        shapeup_core::io::one_line(output.as_path().display())
    )?;
    Ok(())
}
