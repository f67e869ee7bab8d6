//! `shapeup`: the command-line tool.
//!
//! - `shapeup deform SCENE -o OUT` — static ShapeUp solve from the rest shape.
//! - `shapeup simulate SCENE --frames N -o DIR` — Projective Dynamics, a mesh file per frame
//!   (OBJ by default; `--format` ply, off, stl, vtu with a ParaView `.pvd`, msh).
//! - `shapeup energy SCENE POSITIONS` — E of given positions under a scene's constraints.
//! - `shapeup bench` — the standard benchmark scenarios, as a table.
//!
//! Every error is one line on stderr and a non-zero exit; nothing is written on failure.

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use shapeup_core::bench::{Scenario, load_scenario};
use shapeup_core::io::{
    MESH_OUTPUT_EXTENSIONS, PlyEncoding, check_output_extension, check_output_folder, read_mesh, write_atomic,
};
use shapeup_core::scene::Scene;
use shapeup_core::scene::SolverSettings;
use shapeup_core::solver::{Acceleration, Factorization, MAX_ANDERSON_WINDOW, MAX_LBFGS_MEMORY, SolverParams};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

mod simulate;
#[cfg(feature = "gui")]
mod view;

#[derive(Parser)]
#[command(
    name = "shapeup",
    version,
    about = "Constraint-based shape deformation (ShapeUp) and simulation (Projective Dynamics) of polygon, triangle and tetrahedral meshes"
)]
struct Cli {
    /// Worker threads for the parallel local step (default: all cores).
    #[arg(long, global = true, value_name = "N")]
    threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Lists every constraint type a scene can use: what it acts on, its default weight and its options.
    Types,
    /// Static solve of a scene from its rest shape; writes the deformed mesh.
    Deform {
        /// Scene file (.toml or .json).
        scene: PathBuf,
        /// Output mesh (.obj, .ply, .off, .stl, .vtu or .msh); keeps the input's vertex count and order, faces and attributes (STL cannot). Default: the scene's `[output] path`.
        #[arg(short, long, value_name = "OUT")]
        output: Option<PathBuf>,
        /// Total local-global iterations (default: the scene's steps × iterations).
        #[arg(long, value_name = "N")]
        iterations: Option<usize>,
        /// Write a JSON report (energies per iteration, timings, warnings). Default: the scene's
        /// `[output] report`, if any.
        #[arg(long, value_name = "REPORT.json")]
        report: Option<PathBuf>,
        /// PLY output encoding: ascii, binary_little_endian or binary_big_endian (default: the
        /// input's when it is a PLY file, else binary_little_endian).
        #[arg(long, value_name = "ENCODING", value_parser = parse_ply_encoding)]
        ply_encoding: Option<PlyEncoding>,
        #[command(flatten)]
        acceleration: AccelerationArgs,
    },
    /// Projective Dynamics time steps of a scene (whatever its mode) from rest; writes frame k
    /// (the state after k steps) to DIR/frame_000k.EXT: the input's surface (obj, ply, off,
    /// stl) or the whole mesh with its tetrahedra (vtu, with velocities and DIR/frames.pvd for
    /// ParaView; msh).
    Simulate {
        /// Scene file (.toml or .json).
        scene: PathBuf,
        /// Time steps to run (overrides the scene's steps).
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
        frames: u64,
        /// Output directory for the frames (created if missing). Default: the scene's
        /// `[output] path`.
        #[arg(short, long, value_name = "DIR")]
        output: Option<PathBuf>,
        /// Write only frames that are multiples of K (and always the last).
        #[arg(long, default_value_t = 1, value_name = "K")]
        every: usize,
        /// Frame format: obj, ply, off, stl, vtu or msh.
        // A string checked by `simulate::run`, so that a bad name is one line of error.
        #[arg(long, default_value = "obj", value_name = "FORMAT")]
        format: String,
        /// Write a JSON report (energy after each step, warnings, timings).
        #[arg(long, value_name = "REPORT.json")]
        report: Option<PathBuf>,
        #[command(flatten)]
        acceleration: AccelerationArgs,
    },
    /// Prints the energy of given positions under a scene's constraints (working frame), in all
    /// and per group.
    Energy {
        /// Scene file (.toml or .json).
        scene: PathBuf,
        /// Mesh with the positions to evaluate (.obj, .ply, …), same vertex count as the scene's.
        positions: PathBuf,
    },
    /// Opens the interactive editor on a mesh or a scene (default: the bundled bunny).
    #[cfg(feature = "gui")]
    View {
        /// Mesh (.obj .ply .stl .off) or scene (.toml .json).
        input: Option<PathBuf>,
        /// Render one frame to this PNG and exit (no window; a scene is solved first).
        #[arg(long, value_name = "OUT.png")]
        screenshot: Option<PathBuf>,
        /// Screenshot size in pixels, WIDTHxHEIGHT.
        #[arg(long, default_value = "1200x800", value_parser = parse_size)]
        size: (u32, u32),
        /// Print frames/s, solves/s and solve times to stderr once per second.
        #[arg(long)]
        stats: bool,
    },
    /// Runs the standard benchmark scenarios (springs, strain+bending, iso) and prints a table.
    Bench {
        /// Mesh to benchmark on (default: the bundled Stanford bunny).
        #[arg(long, value_name = "MESH")]
        mesh: Option<PathBuf>,
        /// Timed iterations per scenario.
        #[arg(long, default_value_t = 20, value_name = "N")]
        iterations: usize,
        /// Only these scenarios (springs, strain+bending, iso).
        #[arg(long = "scenario", value_name = "NAME")]
        scenarios: Vec<String>,
        /// Sparse Cholesky layout: auto, simplicial or supernodal.
        #[arg(long, default_value = "auto", value_parser = parse_factorization)]
        factorization: Factorization,
        /// Run the dynamic scenarios instead (cloth-10k, cloth-40k, tet-box-20k: generated
        /// meshes, 10 iterations per time step); `--iterations` counts time steps.
        #[arg(long)]
        dynamic: bool,
        /// Time to a converged shape instead: for each scenario, iterations and seconds until
        /// (E_k − E*)/E* ≤ 1 %, 0.1 % and 0.01 %, plain, with Anderson acceleration and with
        /// L-BFGS, E* the lowest energy of a long run with the default acceleration and of the
        /// timed runs (`--reference-iterations`); `--iterations` caps each timed run.
        #[arg(long, conflicts_with = "dynamic")]
        converge: bool,
        /// Iterations of the reference run that gives E* (with --converge).
        #[arg(long, default_value_t = 3000, value_name = "N", requires = "converge")]
        reference_iterations: usize,
    },
}

/// Overrides of the scene's acceleration settings.
#[derive(Args, Clone, Copy)]
struct AccelerationArgs {
    /// How iterates are combined: lbfgs (the default), anderson or none (overrides the scene's
    /// `acceleration`).
    #[arg(long, value_name = "KIND", value_parser = parse_acceleration)]
    acceleration: Option<Acceleration>,
    /// Iterations Anderson acceleration mixes, 1 to 50 (overrides `anderson_window`).
    #[arg(long, value_name = "M", value_parser = clap::value_parser!(u64).range(1..=MAX_ANDERSON_WINDOW as u64))]
    anderson_window: Option<u64>,
    /// Pairs L-BFGS keeps, 1 to 50 (overrides `lbfgs_memory`).
    #[arg(long, value_name = "M", value_parser = clap::value_parser!(u64).range(1..=MAX_LBFGS_MEMORY as u64))]
    lbfgs_memory: Option<u64>,
}

impl AccelerationArgs {
    fn apply(self, solver: &mut SolverSettings) {
        if let Some(a) = self.acceleration {
            solver.acceleration = a;
        }
        if let Some(m) = self.anderson_window {
            solver.anderson_window = usize::try_from(m).unwrap_or(MAX_ANDERSON_WINDOW);
        }
        if let Some(m) = self.lbfgs_memory {
            solver.lbfgs_memory = usize::try_from(m).unwrap_or(MAX_LBFGS_MEMORY);
        }
    }
}

fn parse_acceleration(s: &str) -> Result<Acceleration, String> {
    Acceleration::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = Acceleration::ALL.iter().map(|a| a.name()).collect();
        format!("unknown acceleration \"{s}\" ({})", names.join(", "))
    })
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // One line. shapeup-core's errors already quote their cause in their own message,
            // so only the outermost message is printed (the `{:#}` chain would repeat it).
            let message = e.to_string().replace('\n', " ");
            let _ = writeln!(std::io::stderr(), "shapeup: error: {message}");
            ExitCode::FAILURE
        }
    }
}

/// The most worker threads `--threads` accepts: far beyond any core count a solve can use (each
/// thread costs a stack; tens of thousands exhaust the machine before the first iteration).
const MAX_THREADS: usize = 1024;

fn run(cli: Cli) -> Result<()> {
    if let Some(n) = cli.threads {
        if !(1..=MAX_THREADS).contains(&n) {
            bail!("--threads must be between 1 and {MAX_THREADS}, found {n}");
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| anyhow::anyhow!("cannot start the thread pool: {e}"))?;
    }
    match cli.command {
        Command::Deform { scene, output, iterations, report, ply_encoding, acceleration } => {
            deform(&scene, output.as_deref(), iterations, report.as_deref(), ply_encoding, acceleration)
        }
        Command::Energy { scene, positions } => energy(&scene, &positions),
        Command::Types => {
            std::io::stdout().lock().write_all(shapeup_core::constraints::catalogue_markdown().as_bytes())?;
            Ok(())
        }
        Command::Simulate { scene, frames, output, every, format, report, acceleration } => {
            simulate::run(&simulate::SimulateArgs {
                scene: &scene,
                overrides: &|solver| acceleration.apply(solver),
                frames: usize::try_from(frames).unwrap_or(usize::MAX),
                output: output.as_deref(),
                every,
                format: &format,
                report: report.as_deref(),
            })
        }
        #[cfg(feature = "gui")]
        Command::View { input, screenshot, size, stats } => view::run(input, screenshot, size, stats),
        Command::Bench { iterations: 0, .. } => {
            bail!("--iterations must be at least 1 (a benchmark of no iterations measures nothing)")
        }
        Command::Bench { dynamic: true, iterations, scenarios, .. } => bench_dynamic(iterations, &scenarios),
        Command::Bench { mesh, iterations, scenarios, converge: true, reference_iterations, .. } => {
            bench_converge(mesh, iterations, reference_iterations, &scenarios)
        }
        Command::Bench { mesh, iterations, scenarios, factorization, dynamic: false, .. } => {
            bench(mesh, iterations, &scenarios, factorization)
        }
    }
}

/// Fails early (before any work, so that nothing is written) when the folder `path` goes in
/// does not exist or cannot take a new file ([`shapeup_core::io::check_output_folder`]).
pub(crate) fn check_parent_dir(path: &Path) -> Result<()> {
    Ok(check_output_folder(path)?)
}

fn deform(
    scene_path: &Path,
    output: Option<&Path>,
    iterations: Option<usize>,
    report_path: Option<&Path>,
    ply_encoding: Option<PlyEncoding>,
    acceleration: AccelerationArgs,
) -> Result<()> {
    let start = Instant::now();
    let mut scene = Scene::from_file(scene_path)?;
    let output = match output {
        Some(o) => o.to_path_buf(),
        None => scene.output_path().with_context(|| {
            format!("{}: no output mesh: give -o OUT, or `path` in the scene's [output] table", scene_path.display())
        })?,
    };
    let output = output.as_path();
    let report_path = report_path.map(Path::to_path_buf).or_else(|| scene.report_path());
    let report_path = report_path.as_deref();
    check_output_extension(output, MESH_OUTPUT_EXTENSIONS)?;
    check_parent_dir(output)?;
    if let Some(r) = report_path {
        check_output_extension(r, &["json"])?;
        check_parent_dir(r)?;
    }
    acceleration.apply(&mut scene.solver);
    let mut loaded = scene.load()?;
    let (q, solve) = loaded.solve_static(iterations)?;
    let mut warnings = loaded.warnings.clone();
    let (mesh, written) = loaded.write_result(output, &q, ply_encoding)?;
    warnings.extend(written);
    let total = start.elapsed().as_secs_f64();
    if let Some(path) = report_path {
        let report = loaded.deform_report(&q, &solve, &mesh, &warnings, total);
        let text = serde_json::to_string_pretty(&report)?;
        write_atomic(path, |w| w.write_all(text.as_bytes()))?;
    }
    print_warnings(&warnings);
    // From the energy at the start: with 0 iterations that is also the energy at the end.
    let first = solve.initial_energy;
    let last = solve.energies.last().copied().unwrap_or(first);
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "deformed {} vertices, {} constraints, {}: E {first:.6e} -> {last:.6e}; wrote {} ({total:.2} s)",
        loaded.mesh.num_vertices(),
        loaded.system.num_constraints(),
        count(solve.energies.len(), "iteration"),
        output.display()
    )?;
    Ok(())
}

/// Each warning once, as one line on stderr.
pub(crate) fn print_warnings(warnings: &shapeup_core::warnings::Warnings) {
    let mut err = std::io::stderr().lock();
    for w in warnings.iter() {
        let _ = writeln!(err, "shapeup: warning: {w}");
    }
}

fn energy(scene_path: &Path, positions_path: &Path) -> Result<()> {
    let scene = Scene::from_file(scene_path)?;
    let mut loaded = scene.load()?;
    let positions = read_mesh(positions_path)?.mesh.positions;
    if positions.len() != loaded.mesh.num_vertices() {
        bail!(
            "{}: has {} vertices but the scene's mesh has {} (positions must match the mesh vertex by vertex)",
            positions_path.display(),
            positions.len(),
            loaded.mesh.num_vertices()
        );
    }
    let e = loaded.energy_of(&positions)?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "E = {:.12e}", e.total)?;
    for (id, value) in &e.per_group {
        if let Some(g) = loaded.system.group(*id) {
            writeln!(out, "  {:<20} {:<16} {value:.12e}", g.name, g.kind)?;
        }
    }
    Ok(())
}

/// The scenarios named by `--scenario` (all of them when none is), or an error listing the
/// known names.
fn pick_scenarios<T: Copy>(names: &[String], all: &[T], name: fn(T) -> &'static str) -> Result<Vec<T>> {
    if names.is_empty() {
        return Ok(all.to_vec());
    }
    names
        .iter()
        .map(|n| {
            all.iter().copied().find(|&s| name(s) == n).with_context(|| {
                let known: Vec<&str> = all.iter().map(|&s| name(s)).collect();
                format!("unknown scenario \"{n}\" (known: {})", known.join(", "))
            })
        })
        .collect()
}

/// `shapeup bench --dynamic`: time steps per second of the dynamic scenarios.
fn bench_dynamic(steps: usize, names: &[String]) -> Result<()> {
    use shapeup_core::bench::DynamicScenario;
    let scenarios = pick_scenarios(names, &DynamicScenario::ALL, DynamicScenario::name)?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}; {steps} time steps per scenario after 3 warm-up steps", threads_label())?;
    writeln!(
        out,
        "{:<14} {:>9} {:>7} {:>11} {:>9} {:>10} {:>11} {:>9} {:>9}",
        "scenario", "vertices", "tets", "constraints", "setup s", "local ms", "global ms", "ms/step", "steps/s"
    )?;
    for s in scenarios {
        let t = Instant::now();
        let (loaded, mut simulation) = s.load()?;
        for _ in 0..3 {
            simulation.step().with_context(|| format!("{}: step failed", s.name()))?;
        }
        let setup_s = t.elapsed().as_secs_f64();
        let (mut local, mut global) = (0.0, 0.0);
        let t = Instant::now();
        for _ in 0..steps.max(1) {
            let r = simulation.step().with_context(|| format!("{}: step failed", s.name()))?;
            local += r.local_seconds;
            global += r.global_seconds;
        }
        let per_step = t.elapsed().as_secs_f64() / steps.max(1) as f64;
        let n = steps.max(1) as f64;
        writeln!(
            out,
            "{:<14} {:>9} {:>7} {:>11} {:>9.3} {:>10.2} {:>11.2} {:>9.2} {:>9.1}",
            s.name(),
            loaded.mesh.num_vertices(),
            loaded.mesh.num_tetrahedra(),
            simulation.system().num_constraints(),
            setup_s,
            1e3 * local / n,
            1e3 * global / n,
            1e3 * per_step,
            1.0 / per_step
        )?;
    }
    Ok(())
}

/// The bundled bunny, found from the working directory or from the source tree.
fn default_bench_mesh() -> PathBuf {
    let local = PathBuf::from("data/stanford-bunny.obj");
    if local.exists() {
        local
    } else {
        PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/stanford-bunny.obj"))
    }
}

#[cfg(feature = "gui")]
fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("expected WIDTHxHEIGHT (e.g. 1200x800), found \"{s}\"");
    let (w, h) = s.split_once('x').ok_or_else(bad)?;
    let (w, h) = (w.parse::<u32>().map_err(|_| bad())?, h.parse::<u32>().map_err(|_| bad())?);
    if (1..=8192).contains(&w) && (1..=8192).contains(&h) { Ok((w, h)) } else { Err(bad()) }
}

fn parse_ply_encoding(s: &str) -> Result<PlyEncoding, String> {
    match s {
        "ascii" => Ok(PlyEncoding::Ascii),
        "binary_little_endian" => Ok(PlyEncoding::BinaryLittleEndian),
        "binary_big_endian" => Ok(PlyEncoding::BinaryBigEndian),
        _ => Err(format!("unknown PLY encoding \"{s}\" (ascii, binary_little_endian, binary_big_endian)")),
    }
}

fn parse_factorization(s: &str) -> Result<Factorization, String> {
    match s {
        "auto" => Ok(Factorization::Auto),
        "simplicial" => Ok(Factorization::Simplicial),
        "supernodal" => Ok(Factorization::Supernodal),
        _ => Err(format!("unknown factorization \"{s}\" (auto, simplicial, supernodal)")),
    }
}

fn bench(mesh: Option<PathBuf>, iterations: usize, names: &[String], factorization: Factorization) -> Result<()> {
    let scenarios = pick_scenarios(names, &Scenario::ALL, Scenario::name)?;
    let path = mesh.unwrap_or_else(default_bench_mesh);
    let t = Instant::now();
    let loaded = read_mesh(&path)?;
    let load_s = t.elapsed().as_secs_f64();
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "{}: {} vertices, {} triangles; load {:.3} s; {}; {}",
        path.display(),
        loaded.mesh.num_vertices(),
        loaded.mesh.num_triangles(),
        load_s,
        threads_label(),
        count(iterations, "plain iteration")
    )?;
    writeln!(
        out,
        "{:<16} {:>11} {:>9} {:>10} {:>11} {:>11} {:>9}",
        "scenario", "constraints", "setup s", "local ms", "global ms", "ms/iter", "E end"
    )?;
    for s in scenarios {
        let t = Instant::now();
        let mut scene = load_scenario(s, &loaded.mesh, path.clone())?;
        // Plain iterations, energies left out: the per-iteration work the peers do.
        let params = SolverParams { factorization, acceleration: Acceleration::None, ..*scene.system.params() };
        scene.system.set_params(params);
        scene.system.prepare().map_err(|e| anyhow::anyhow!("{}: {e}", s.name()))?;
        let setup_s = t.elapsed().as_secs_f64() + load_s;
        let mut q = scene.rest.positions.clone();
        let report = scene.system.iterate(&mut q, iterations).map_err(|e| anyhow::anyhow!("{}: {e}", s.name()))?;
        let energy = scene.system.energy(&q).map_err(|e| anyhow::anyhow!("{}: {e}", s.name()))?.total;
        let n = iterations.max(1) as f64;
        let local_ms = 1e3 * report.local_seconds / n;
        let global_ms = 1e3 * report.global_seconds / n;
        writeln!(
            out,
            "{:<16} {:>11} {:>9.3} {:>10.2} {:>11.2} {:>11.2} {:>9.3e}",
            s.name(),
            scene.system.num_constraints(),
            setup_s,
            local_ms,
            global_ms,
            local_ms + global_ms,
            energy
        )?;
    }
    Ok(())
}

/// |E_k − E_{k−1}| / E_{k−1} after each iteration; `None` for the first.
/// "1 thread", "2 threads": the worker threads this run uses.
fn threads_label() -> String {
    count(rayon::current_num_threads(), "thread")
}

/// "1 iteration", "0 iterations", "2 iterations".
fn count(n: usize, what: &str) -> String {
    if n == 1 { format!("1 {what}") } else { format!("{n} {what}s") }
}

/// The relative energy gaps `shapeup bench --converge` reports.
const CONVERGE_GAPS: [f64; 3] = [1e-2, 1e-3, 1e-4];

/// Energy after each iteration and the seconds since the solve began (setup included), for up
/// to `iterations` iterations from the rest shape.
fn convergence_run(
    scene: &mut shapeup_core::scene::LoadedScene,
    acceleration: Acceleration,
    iterations: usize,
) -> Result<Vec<(f64, f64)>> {
    let params = SolverParams { acceleration, ..*scene.system.params() };
    scene.system.set_params(params);
    let mut q = scene.rest.positions.clone();
    let start = Instant::now();
    let mut trace = Vec::with_capacity(iterations);
    scene
        .system
        .solve_with(&mut q, iterations, 0.0, |_, e| {
            trace.push((e, start.elapsed().as_secs_f64()));
            std::ops::ControlFlow::Continue(())
        })
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(trace)
}

fn bench_converge(mesh: Option<PathBuf>, iterations: usize, reference: usize, names: &[String]) -> Result<()> {
    let scenarios = pick_scenarios(names, &Scenario::ALL, Scenario::name)?;
    let path = mesh.unwrap_or_else(default_bench_mesh);
    let loaded = read_mesh(&path)?;
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "{}: {} vertices; {}; E* = lowest energy of {reference} iterations with the default acceleration ({}) and of the timed runs; runs capped at {iterations} iterations",
        path.display(),
        loaded.mesh.num_vertices(),
        threads_label(),
        Acceleration::default().name()
    )?;
    writeln!(
        out,
        "time to (E_k - E*)/E* <= gap: iterations / seconds from the start of the solve (factorization included); - = not within the cap"
    )?;
    writeln!(
        out,
        "{:<16} {:<10} {:>18} {:>18} {:>18} {:>12}",
        "scenario", "iteration", "1 %", "0.1 %", "0.01 %", "E end"
    )?;
    for s in scenarios {
        let mut scene = load_scenario(s, &loaded.mesh, path.clone())?;
        let star = convergence_run(&mut scene, Acceleration::default(), reference)?;
        let mut runs = Vec::new();
        for acceleration in [Acceleration::None, Acceleration::Anderson, Acceleration::Lbfgs] {
            let mut scene = load_scenario(s, &loaded.mesh, path.clone())?;
            runs.push((acceleration, convergence_run(&mut scene, acceleration, iterations)?));
        }
        let e_star = star.iter().chain(runs.iter().flat_map(|(_, r)| r)).map(|(e, _)| *e).fold(f64::INFINITY, f64::min);
        for (acceleration, trace) in &runs {
            let cell = |gap: f64| {
                trace
                    .iter()
                    .position(|(e, _)| (e - e_star) / e_star <= gap)
                    .map_or("-".to_string(), |k| format!("{} / {:.2} s", k + 1, trace[k].1))
            };
            let name = match acceleration {
                Acceleration::None => "plain",
                a => a.name(),
            };
            writeln!(
                out,
                "{:<16} {:<10} {:>18} {:>18} {:>18} {:>12.6e}",
                s.name(),
                name,
                cell(CONVERGE_GAPS[0]),
                cell(CONVERGE_GAPS[1]),
                cell(CONVERGE_GAPS[2]),
                trace.last().map_or(f64::NAN, |(e, _)| *e)
            )?;
        }
    }
    Ok(())
}
