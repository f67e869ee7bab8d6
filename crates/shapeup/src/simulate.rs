//! `shapeup simulate`: Projective Dynamics time steps of a scene, written as an OBJ sequence.

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use shapeup_core::io::{write_atomic, write_mesh};
use shapeup_core::scene::Scene;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What to run and write.
pub struct SimulateArgs<'a> {
    /// The scene file.
    pub scene: &'a Path,
    /// Time steps to run.
    pub frames: usize,
    /// Output directory (created if missing).
    pub output: &'a Path,
    /// Write frame k only when k is a multiple of this (and always the last).
    pub every: usize,
    /// Optional JSON report.
    pub report: Option<&'a Path>,
}

/// `DIR/frame_0000.obj`, with at least four digits and enough for the last frame.
fn frame_path(dir: &Path, k: usize, last: usize) -> PathBuf {
    let width = last.to_string().len().max(4);
    dir.join(format!("frame_{k:0width$}.obj"))
}

/// Runs the simulation; frames are written one by one (each atomically), so an error part-way
/// leaves the complete frames before it and no partial file.
pub fn run(args: &SimulateArgs<'_>) -> Result<()> {
    let start = Instant::now();
    if args.every == 0 {
        bail!("--every must be at least 1");
    }
    if let Some(r) = args.report
        && !r.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("json"))
    {
        bail!("{}: the report must be a .json file", r.display());
    }
    let scene = Scene::from_file(args.scene)?;
    let mut loaded = scene.load()?;
    let mut simulation = loaded.start_simulation()?;
    std::fs::create_dir_all(args.output)
        .with_context(|| format!("cannot create the output directory {}", args.output.display()))?;

    let write_frame = |k: usize, q: &[glam::DVec3]| -> Result<()> {
        write_mesh(&frame_path(args.output, k, args.frames), &loaded.surface_at(q))?;
        Ok(())
    };
    write_frame(0, simulation.positions())?;
    let mut written = 1;

    let progress = if std::io::stderr().is_terminal() {
        let bar = ProgressBar::new(args.frames as u64);
        if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} frames  {per_sec}  ETA {eta}") {
            bar.set_style(style);
        }
        bar
    } else {
        ProgressBar::hidden()
    };
    let (mut energies, mut local, mut global, mut setup) = (Vec::with_capacity(args.frames), 0.0, 0.0, 0.0);
    let h = simulation.params().time_step;
    let spinning = loaded.spinning_handles()?;
    for k in 1..=args.frames {
        // Spinning handles: their targets at the end of this step.
        for handle in &spinning {
            simulation.system_mut().set_position_targets(handle.id, &handle.targets_at(k as f64 * h))?;
        }
        let step = simulation
            .step()
            .with_context(|| format!("{}: step {k} of {} failed", args.scene.display(), args.frames))?;
        energies.push(step.energy);
        local += step.local_seconds;
        global += step.global_seconds;
        setup += step.setup_seconds;
        if k % args.every == 0 || k == args.frames {
            write_frame(k, simulation.positions())?;
            written += 1;
        }
        progress.inc(1);
    }
    progress.finish_and_clear();
    let total = start.elapsed().as_secs_f64();
    let system = simulation.system();
    if let Some(path) = args.report {
        let report = serde_json::json!({
            "vertices": loaded.mesh.num_vertices(),
            "triangles": loaded.mesh.num_triangles(),
            "tetrahedra": loaded.mesh.num_tetrahedra(),
            "constraints": system.num_constraints(),
            "steps": args.frames,
            "frames_written": written,
            "time_step": simulation.params().time_step,
            "simulated_s": simulation.time(),
            "energy": energies,
            "kinetic_energy_end": simulation.kinetic_energy(),
            "timings": {
                "load_s": loaded.load_seconds,
                "setup_s": loaded.build_seconds + setup,
                "local_s": local,
                "global_s": global,
                "total_s": total,
            },
        });
        let text = serde_json::to_string_pretty(&report)?;
        write_atomic(path, |w| w.write_all(text.as_bytes()))?;
    }
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
