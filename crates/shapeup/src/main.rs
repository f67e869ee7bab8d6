//! `shapeup`: the command-line tool.
//!
//! - `shapeup deform SCENE -o OUT` — static ShapeUp solve from the rest shape (or `[mesh] start`).
//! - `shapeup simulate SCENE --frames N -o DIR` — Projective Dynamics, a mesh file per frame
//!   (OBJ by default; `--format` ply, off, stl, vtu with a ParaView `.pvd`, msh).
//! - `shapeup energy SCENE POSITIONS` — E of given positions under a scene's constraints.
//! - `shapeup bench` — the standard benchmark scenarios, as a table.
//! - `shapeup info MESH` — counts, pieces, boundary loops, defects, bounding box of a mesh.
//! - `shapeup samples` — the sample meshes built into the binary (`--write DIR` writes them).
//! - `shapeup completions SHELL`, `shapeup man` — shell completions and manual pages.
//!
//! Every error is one line on stderr and a non-zero exit; bad input writes nothing (a simulation
//! failing part-way keeps its finished frames, see `simulate`). Log records and progress bars:
//! [`logging`].

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use glam::DVec3;
use shapeup_core::bench::{Scenario, load_scenario};
use shapeup_core::io::{
    LoadedMesh, MESH_OUTPUT_EXTENSIONS, PlyEncoding, check_output_extension, check_output_folder, read_mesh,
    write_atomic,
};
use shapeup_core::scene::{LoadedScene, Scene, SolverSettings};
use shapeup_core::solver::{
    Acceleration, Factorization, MAX_ANDERSON_WINDOW, MAX_LBFGS_MEMORY, SolveReport, SolverParams,
};
use std::io::Write;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

mod logging;
mod manual;
mod samples;
mod simulate;
#[cfg(feature = "gui")]
mod view;

#[derive(Parser)]
#[command(
    name = "shapeup",
    version,
    about = "Constraint-based shape deformation (ShapeUp) and simulation (Projective Dynamics) of polygon, triangle and tetrahedral meshes",
    after_long_help = "Environment: RUST_LOG sets the log filter (env_logger's syntax, e.g. RUST_LOG=info or \
                       RUST_LOG=wgpu_core=debug); -q and -v set the default level over it.\n\
                       Samples: wherever a MESH is taken, the name of a mesh built into shapeup \
                       (`shapeup samples`) stands for it when no file of that name exists."
)]
struct Cli {
    /// Worker threads the command runs on (default: RAYON_NUM_THREADS when set, else all cores).
    #[arg(long, global = true, value_name = "N", allow_negative_numbers = true, value_parser = parse_threads)]
    threads: Option<usize>,
    /// Errors only on stderr: no warnings, no progress bars (RUST_LOG's default level becomes
    /// error). The one-line summary of what was written stays on stdout.
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    quiet: bool,
    /// More log output on stderr: -v info, -vv debug, -vvv trace (over RUST_LOG's default
    /// level; its per-module directives stay). Default: warnings.
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    verbose: u8,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Lists every constraint type a scene can use: what it acts on, its default weight and its options.
    Types,
    /// Static solve of a scene from its rest shape (or its `[mesh] start`); writes the deformed mesh.
    Deform {
        /// Scene file (.toml or .json).
        scene: PathBuf,
        /// Output mesh (.obj, .ply, .off, .stl, .vtu or .msh); keeps the input's vertex count and order, faces and attributes (STL cannot). Default: the scene's `[output] path`.
        #[arg(short, long, value_name = "OUT")]
        output: Option<PathBuf>,
        /// Total local-global iterations (default: the scene's steps × iterations).
        #[arg(long, allow_negative_numbers = true, value_name = "N", value_parser = parse_count)]
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
    /// Projective Dynamics time steps of a scene (whatever its mode) from rest (at its `[mesh] start` shape when it has one); writes frame k
    /// (the state after k steps) to DIR/frame_000k.EXT: the input's surface (obj, ply, off,
    /// stl) or the whole mesh with its tetrahedra (vtu, with velocities and DIR/frames.pvd for
    /// ParaView; msh).
    Simulate {
        /// Scene file (.toml or .json).
        scene: PathBuf,
        /// Time steps to run (overrides the scene's steps).
        #[arg(long, allow_negative_numbers = true, value_name = "N", value_parser = parse_positive)]
        frames: usize,
        /// Output directory for the frames (created if missing). Default: the scene's
        /// `[output] path`.
        #[arg(short, long, value_name = "DIR")]
        output: Option<PathBuf>,
        /// Write only frames that are multiples of K (and always the last).
        #[arg(long, allow_negative_numbers = true, default_value_t = 1, value_name = "K", value_parser = parse_positive)]
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
        /// Mesh with the positions to evaluate (.obj, .ply, …, or a bundled sample's name), same
        /// vertex count as the scene's.
        positions: PathBuf,
    },
    /// Describes a mesh: counts (vertices, faces by corner count, triangles, tetrahedra, edges),
    /// pieces, boundary loops, degenerate and non-manifold elements, bounding box and a guess
    /// of its units.
    Info {
        /// Mesh file (.obj .ply .stl .off .msh .node/.ele .vtu) or a bundled sample's name.
        mesh: PathBuf,
        /// Print the description as JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Lists the sample meshes built into this binary (name, vertices, faces, source); any
    /// MESH argument takes a sample's name when no file of that name exists.
    Samples {
        /// Write them into this folder (created if missing) as NAME.obj instead.
        #[arg(long, value_name = "DIR")]
        write: Option<PathBuf>,
    },
    /// Prints a shell completion script for shapeup on stdout (e.g. `shapeup completions bash >
    /// ~/.local/share/bash-completion/completions/shapeup`).
    Completions {
        /// bash, zsh, fish, elvish or powershell.
        shell: clap_complete::Shell,
    },
    /// Prints the manual page shapeup.1 (roff) on stdout, or writes it and one page per
    /// subcommand (shapeup-deform.1, …) into a folder.
    Man {
        /// Write shapeup.1 and the subcommands' pages into this folder (created if missing).
        #[arg(short, long, value_name = "DIR")]
        output: Option<PathBuf>,
    },
    /// Opens the interactive editor on a mesh or a scene (default: the bundled bunny).
    #[cfg(feature = "gui")]
    View {
        /// Mesh (.obj .ply .stl .off …), scene (.toml .json) or the name of a bundled sample
        /// (`shapeup samples`).
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
        /// Mesh to benchmark on, a file or a bundled sample's name (default: the Stanford
        /// bunny, data/stanford-bunny.obj when there, else the bundled copy).
        #[arg(long, value_name = "MESH")]
        mesh: Option<PathBuf>,
        /// Timed iterations per scenario.
        #[arg(long, allow_negative_numbers = true, default_value_t = 20, value_name = "N", value_parser = parse_positive)]
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
        /// Run the contact scenarios instead (cloth-on-sphere, cloth-folding, body-on-terrain,
        /// stacked-cloths), each with and without its contact; `--iterations` counts time steps
        /// after 60 untimed ones (the bodies have landed by then).
        #[arg(long, conflicts_with_all = ["dynamic", "converge"])]
        contact: bool,
        /// Time to a converged shape instead: for each scenario, iterations and seconds until
        /// (E_k − E*)/E* ≤ 1 %, 0.1 % and 0.01 %, plain, with Anderson acceleration and with
        /// L-BFGS, E* the lowest energy of a long run with the default acceleration and of the
        /// timed runs (`--reference-iterations`); `--iterations` caps each timed run.
        #[arg(long, conflicts_with = "dynamic")]
        converge: bool,
        /// Iterations of the reference run that gives E* (with --converge).
        #[arg(long, allow_negative_numbers = true, default_value_t = 3000, value_name = "N", requires = "converge", value_parser = parse_positive)]
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
    #[arg(long, allow_negative_numbers = true, value_name = "M", value_parser = parse_anderson_window)]
    anderson_window: Option<usize>,
    /// Pairs L-BFGS keeps, 1 to 50 (overrides `lbfgs_memory`).
    #[arg(long, allow_negative_numbers = true, value_name = "M", value_parser = parse_lbfgs_memory)]
    lbfgs_memory: Option<usize>,
}

impl AccelerationArgs {
    fn apply(self, solver: &mut SolverSettings) {
        if let Some(a) = self.acceleration {
            solver.acceleration = a;
        }
        if let Some(m) = self.anderson_window {
            solver.anderson_window = m;
        }
        if let Some(m) = self.lbfgs_memory {
            solver.lbfgs_memory = m;
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
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage_error(&e),
    };
    logging::init(cli.quiet, cli.verbose);
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        // `shapeup man | head`: the reader left, nothing is wrong.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            logging::print_held();
            // One line. shapeup-core's errors already quote their cause in their own message,
            // so only the outermost message is printed (the `{:#}` chain would repeat it).
            let message = e.to_string().replace('\n', " ");
            let _ = writeln!(std::io::stderr(), "shapeup: error: {message}");
            ExitCode::FAILURE
        }
    }
}

/// A command-line usage error as one line (`shapeup: error: invalid value '0' for '--frames <N>':
/// … (shapeup deform --help)`), exit status 2. Help and version requests, and a bare `shapeup`
/// (which shows the help), print as clap has them.
fn usage_error(e: &clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(
        e.kind(),
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        e.exit();
    }
    // clap's first paragraph (the error, and what it lists: missing arguments, possible
    // values, a tip), joined; the usage block after it is what --help shows.
    let rendered = e.render().to_string();
    let paragraph: Vec<&str> = rendered
        .lines()
        .map(str::trim)
        .skip_while(|l| l.is_empty())
        .take_while(|l| !l.is_empty() && !l.starts_with("Usage:"))
        .collect();
    let joined = paragraph.join(" ");
    let message = joined.strip_prefix("error: ").unwrap_or(&joined);
    let _ = writeln!(std::io::stderr(), "shapeup: error: {} (see shapeup --help)", shapeup_core::io::one_line(message));
    ExitCode::from(2)
}

/// Whether `e` is a write to a closed pipe (stdout read by a program that stopped reading).
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| c.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe))
}

/// The most worker threads `--threads` accepts: far beyond any core count a solve can use (each
/// thread costs a stack; tens of thousands exhaust the machine before the first iteration).
const MAX_THREADS: usize = 1024;

/// A whole number in `min..=max` given on the command line, or one line saying what was found
/// (clap's own parsers said "invalid digit found in string" of a negative count, and printed
/// an unbounded range's end as 18446744073709551615).
fn whole_number(s: &str, min: usize, max: usize) -> Result<usize, String> {
    let digits = s.trim().trim_start_matches(['+', '-']);
    match s.trim().parse::<i128>() {
        Ok(n) if (min as i128..=max as i128).contains(&n) => Ok(n as usize),
        Ok(n) if n > max as i128 && max == usize::MAX => {
            Err(format!("must be a whole number at most {max}, found {n}"))
        }
        Ok(n) if max == usize::MAX => Err(format!("must be a whole number ≥ {min}, found {n}")),
        Ok(n) => Err(format!("must be a whole number from {min} to {max}, found {n}")),
        Err(_) if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) => Err(if max == usize::MAX {
            format!("must be a whole number at most {max}, found {}", s.trim())
        } else {
            format!("must be a whole number from {min} to {max}, found {}", s.trim())
        }),
        Err(_) if max == usize::MAX => Err(format!("must be a whole number, found \"{s}\"")),
        Err(_) => Err(format!("must be a whole number from {min} to {max}, found \"{s}\"")),
    }
}

/// A count that may be 0 (iterations).
fn parse_count(s: &str) -> Result<usize, String> {
    whole_number(s, 0, usize::MAX)
}

/// A count of at least 1 (frames, every K-th frame).
fn parse_positive(s: &str) -> Result<usize, String> {
    whole_number(s, 1, usize::MAX)
}

fn parse_anderson_window(s: &str) -> Result<usize, String> {
    whole_number(s, 1, MAX_ANDERSON_WINDOW)
}

fn parse_lbfgs_memory(s: &str) -> Result<usize, String> {
    whole_number(s, 1, MAX_LBFGS_MEMORY)
}

/// `--threads`: a whole number from 1 to [`MAX_THREADS`] (a negative one is named as such, not
/// taken for an unknown flag).
fn parse_threads(s: &str) -> Result<usize, String> {
    whole_number(s, 1, MAX_THREADS)
}

fn run(cli: Cli) -> Result<()> {
    // Listing types or samples and printing a manual compute nothing: a thread setting, good
    // or bad, does not concern them.
    if matches!(
        cli.command,
        Command::Types | Command::Samples { .. } | Command::Completions { .. } | Command::Man { .. }
    ) {
        return run_command(cli);
    }
    // rayon reads RAYON_NUM_THREADS when --threads is not given: the same bounds (0 is rayon's
    // "all cores"), said rather than ignored.
    let from_env = match (cli.threads, std::env::var_os("RAYON_NUM_THREADS").filter(|v| !v.is_empty())) {
        (None, Some(value)) => match value.to_str().and_then(|v| v.trim().parse::<usize>().ok()) {
            Some(n) if n <= MAX_THREADS => Some(n),
            _ => bail!(
                "RAYON_NUM_THREADS must be a whole number between 0 (all cores) and {MAX_THREADS}, found {:?}",
                value.to_string_lossy()
            ),
        },
        _ => None,
    };
    let threads = cli.threads.or(from_env).unwrap_or(0);
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    if threads > cores {
        log::warn!(
            target: logging::TARGET,
            "{threads} threads on {cores} cores: they take turns on the cores, which slows every parallel loop ({} {cores} or fewer)",
            if cli.threads.is_some() { "give --threads" } else { "set RAYON_NUM_THREADS to" }
        );
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .stack_size(WORKER_STACK)
        .build_global()
        .map_err(|e| anyhow::anyhow!("cannot start the thread pool: {e}"))?;
    // The command runs on one of the pool's threads, so that each parallel loop starts on the
    // thread that reaches it (and at 1 thread runs there) instead of being handed to the pool
    // while the main thread sleeps: a contact step runs some hundred such loops, each two
    // context switches.
    // The editor's window stays on the main thread: winit opens its event loop nowhere else.
    if on_main_thread(&cli.command) {
        return run_command(cli);
    }
    rayon::scope(move |_| run_command(cli))
}

/// Whether `command` must run on the main thread (the editor's window).
fn on_main_thread(command: &Command) -> bool {
    #[cfg(feature = "gui")]
    if matches!(command, Command::View { .. }) {
        return true;
    }
    let _ = command;
    false
}

/// The pool's threads' stacks: the main thread's 8 MiB, as the command runs on one of them.
const WORKER_STACK: usize = 8 << 20;

fn run_command(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Deform { scene, output, iterations, report, ply_encoding, acceleration } => {
            deform(&scene, output.as_deref(), iterations, report.as_deref(), ply_encoding, acceleration)
        }
        Command::Energy { scene, positions } => energy(&scene, &positions),
        Command::Info { mesh, json } => info(&mesh, json),
        Command::Samples { write } => samples::run(write.as_deref()),
        Command::Completions { shell } => manual::completions(shell),
        Command::Man { output } => manual::man(output.as_deref()),
        Command::Types => {
            std::io::stdout().lock().write_all(shapeup_core::constraints::catalogue_markdown().as_bytes())?;
            Ok(())
        }
        Command::Simulate { scene, frames, output, every, format, report, acceleration } => {
            simulate::run(&simulate::SimulateArgs {
                scene: &scene,
                overrides: &|solver| acceleration.apply(solver),
                frames,
                output: output.as_deref(),
                every,
                format: &format,
                report: report.as_deref(),
            })
        }
        #[cfg(feature = "gui")]
        Command::View { input, screenshot, size, stats } => view::run(input, screenshot, size, stats),
        Command::Bench { dynamic: true, iterations, scenarios, .. } => bench_dynamic(iterations, &scenarios),
        Command::Bench { contact: true, iterations, scenarios, .. } => bench_contact(iterations, &scenarios),
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

/// Refuses, before any work, an output that is one of the run's inputs
/// ([`Scene::input_replaced_by`]): a result or a report written there would replace what the
/// run was read from.
pub(crate) fn refuse_inputs_as_outputs(scene: &Scene, outputs: &[&Path]) -> Result<()> {
    match scene.input_replaced_by(outputs) {
        Some(replaced) => Err(replaced.into()),
        None => Ok(()),
    }
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
    refuse_inputs_as_outputs(&scene, &[Some(output), report_path].into_iter().flatten().collect::<Vec<_>>())?;
    if let Some(r) = report_path {
        check_output_extension(r, &["json"])?;
        check_parent_dir(r)?;
    }
    acceleration.apply(&mut scene.solver);
    let spinner = logging::spinner(format!("loading {}", scene_path.display()));
    let mut loaded = scene.load()?;
    drop(spinner);
    log::info!(
        "{}: {} vertices, {} constraints (mesh read in {:.2} s, constraints built in {:.2} s)",
        scene_path.display(),
        loaded.mesh.num_vertices(),
        loaded.system.num_constraints(),
        loaded.load_seconds,
        loaded.build_seconds
    );
    let (q, solve) = solve_static(&mut loaded, iterations)?;
    log::info!(
        "solve: setup {:.3} s, local steps {:.3} s, global steps {:.3} s",
        solve.setup_seconds,
        solve.local_seconds,
        solve.global_seconds
    );
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
    // A start shape kept as it is (it met the tolerance at once) ran no counted iteration.
    let kept = if solve.energies.is_empty() && loaded.start.is_some() && loaded.static_iterations(iterations) > 0 {
        " (the start shape already meets the tolerance: kept as it is)"
    } else {
        ""
    };
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "deformed {} vertices, {} constraints, {}{kept}: E {first:.6e} -> {last:.6e}; wrote {} ({total:.2} s)",
        loaded.mesh.num_vertices(),
        loaded.system.num_constraints(),
        count(solve.energies.len(), "iteration"),
        shapeup_core::io::one_line(output.display())
    )?;
    Ok(())
}

/// [`LoadedScene::solve_static`] with a progress bar of the iterations and the current energy
/// on a terminal.
fn solve_static(loaded: &mut LoadedScene, iterations: Option<usize>) -> Result<(Vec<DVec3>, SolveReport)> {
    let total = loaded.static_iterations(iterations);
    let progress = logging::bar(total as u64, "{bar:40} {pos}/{len} iterations  E {msg}  {per_sec}  ETA {eta}");
    progress.bar.set_message("…");
    Ok(loaded.solve_static_with(iterations, |k, energy| {
        progress.bar.set_position(k as u64);
        progress.bar.set_message(format!("{energy:.6e}"));
        ControlFlow::Continue(())
    })?)
}

/// Each warning once, as one line on stderr (`shapeup: warning: FILE: COUNT MESSAGE (first:
/// …)`): a warn record of shapeup's own target, so `-q` silences it.
pub(crate) fn print_warnings(warnings: &shapeup_core::warnings::Warnings) {
    for w in warnings.iter() {
        log::warn!(target: logging::TARGET, "{}", shapeup_core::io::one_line(w));
    }
}

fn energy(scene_path: &Path, positions_path: &Path) -> Result<()> {
    let scene = Scene::from_file(scene_path)?;
    let mut loaded = scene.load()?;
    let shape = samples::read_mesh_arg(positions_path)?.0.mesh;
    if shape.num_vertices() != loaded.mesh.num_vertices() {
        bail!(
            "{}: has {} vertices but the scene's mesh has {} (positions must match the mesh vertex by vertex)",
            positions_path.display(),
            shape.num_vertices(),
            loaded.mesh.num_vertices()
        );
    }
    // Same count, other order (an STL file merges vertices in the order its triangles use
    // them): refused, as a `[mesh] start` is. A file of points alone is taken as it is.
    let has_elements = !shape.polygons.is_empty() || !shape.tetrahedra.is_empty();
    if let Some(why) = has_elements.then(|| shapeup_core::scene::other_elements(&loaded.mesh, &shape)).flatten() {
        let stl = positions_path.extension().is_some_and(|e| e.eq_ignore_ascii_case("stl"));
        bail!(
            "{}: is not a shape of the scene's mesh vertex by vertex: {why}{}",
            positions_path.display(),
            if stl { " (STL merges vertices and reorders them)" } else { "" }
        );
    }
    let positions = shape.positions;
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

/// `shapeup info MESH`: [`shapeup_core::inspect::MeshInfo`] of the mesh, as text or JSON (with
/// the file's name under `"path"`); the reader's warnings go to stderr as usual.
fn info(mesh: &Path, json: bool) -> Result<()> {
    let (loaded, path) = samples::read_mesh_arg(mesh)?;
    let info = shapeup_core::inspect::MeshInfo::of_loaded(&loaded);
    let mut out = std::io::stdout().lock();
    if json {
        let mut value = serde_json::to_value(&info)?;
        if let Some(object) = value.as_object_mut() {
            object.insert("path".into(), path.display().to_string().into());
        }
        writeln!(out, "{}", serde_json::to_string_pretty(&value)?)?;
    } else {
        writeln!(out, "{}", path.display())?;
        writeln!(out, "{}", info.to_string().trim_end())?;
    }
    print_warnings(&loaded.warnings);
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
    writeln!(
        out,
        "{}; {steps} time steps per scenario after 3 warm-up steps (the check of steps 4, 8, …, 64 and every 64th for stopping short not counted)",
        threads_label()
    )?;
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
        let (mut local, mut global, mut check) = (0.0, 0.0, 0.0);
        let progress = logging::bar(steps.max(1) as u64, &bar_template(s.name(), "steps"));
        let t = Instant::now();
        for _ in 0..steps.max(1) {
            let r = simulation.step().with_context(|| format!("{}: step failed", s.name()))?;
            local += r.local_seconds;
            global += r.global_seconds;
            check += r.check_seconds;
            progress.bar.inc(1);
        }
        let per_step = (t.elapsed().as_secs_f64() - check) / steps.max(1) as f64;
        // The row goes to stdout, the bar to stderr: clear it first (same screen on a terminal).
        drop(progress);
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

/// `shapeup bench --contact`: ms per time step of the contact scenarios with and without their
/// contact (same meshes, constraints and settings), measured after 60 untimed steps.
fn bench_contact(steps: usize, names: &[String]) -> Result<()> {
    use shapeup_core::bench::ContactScenario;
    let scenarios = pick_scenarios(names, &ContactScenario::ALL, ContactScenario::name)?;
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "{}; {steps} time steps after 60 untimed ones, 10 iterations each (the check of every 64th step for stopping short not counted)",
        threads_label()
    )?;
    writeln!(
        out,
        "{:<16} {:>9} {:>13} {:>12} {:>7} {:>15} {:>10} {:>9} {:>15}",
        "scenario",
        "vertices",
        "free ms/step",
        "contact ms",
        "ratio",
        "detect+project",
        "contacts",
        "steps/s",
        "factorizations"
    )?;
    for s in scenarios {
        let mut time = [0.0; 2];
        let mut contacts = 0usize;
        // Of the contact run's time: detection at each step's start and projection at its end.
        let mut detect_project = 0.0;
        let mut factorizations = 0;
        let mut vertices = 0;
        for (k, contact) in [false, true].into_iter().enumerate() {
            let (loaded, mut simulation, _dir) = s.load(contact)?;
            vertices = loaded.mesh.num_vertices();
            for _ in 0..60 {
                simulation.step().with_context(|| format!("{}: step failed", s.name()))?;
            }
            let progress = logging::bar(steps.max(1) as u64, &bar_template(s.name(), "steps"));
            let t = Instant::now();
            let mut check = 0.0;
            for _ in 0..steps.max(1) {
                let r = simulation.step().with_context(|| format!("{}: step failed", s.name()))?;
                if contact {
                    contacts += r.contact.touching;
                    detect_project += r.contact_seconds;
                }
                check += r.check_seconds;
                progress.bar.inc(1);
            }
            time[k] = (t.elapsed().as_secs_f64() - check) / steps.max(1) as f64;
            drop(progress);
            factorizations = simulation.system().factorizations();
        }
        writeln!(
            out,
            "{:<16} {:>9} {:>13.2} {:>12.2} {:>7.2} {:>12.2} ms {:>10} {:>9.1} {:>15}",
            s.name(),
            vertices,
            1e3 * time[0],
            1e3 * time[1],
            time[1] / time[0],
            1e3 * detect_project / steps.max(1) as f64,
            contacts / steps.max(1),
            1.0 / time[1],
            factorizations
        )?;
    }
    Ok(())
}

/// The benchmark's mesh: `--mesh` (a file or a sample's name), else data/stanford-bunny.obj
/// from the working directory, else the bundled bunny; and the name to show.
fn bench_mesh(mesh: Option<&Path>) -> Result<(LoadedMesh, PathBuf)> {
    let local = Path::new("data/stanford-bunny.obj");
    match mesh {
        Some(mesh) => samples::read_mesh_arg(mesh),
        None if local.exists() => Ok((read_mesh(local)?, local.to_path_buf())),
        None => samples::read_mesh_arg(Path::new(samples::DEFAULT)),
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
    let t = Instant::now();
    let (loaded, path) = bench_mesh(mesh.as_deref())?;
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
        let progress = logging::bar(iterations as u64, &bar_template(s.name(), "iterations"));
        // In one run unless a bar is drawn; then in about 50 runs of plain iterations (the same
        // iterates: a run starts with the local step at the last one's result).
        let chunk = if progress.is_drawn() { iterations.div_ceil(50) } else { iterations };
        let (mut local_s, mut global_s, mut done) = (0.0, 0.0, 0);
        while done < iterations {
            let k = chunk.min(iterations - done);
            let report = scene.system.iterate(&mut q, k).map_err(|e| anyhow::anyhow!("{}: {e}", s.name()))?;
            local_s += report.local_seconds;
            global_s += report.global_seconds;
            done += k;
            progress.bar.set_position(done as u64);
        }
        drop(progress);
        let energy = scene.system.energy(&q).map_err(|e| anyhow::anyhow!("{}: {e}", s.name()))?.total;
        let n = iterations.max(1) as f64;
        let local_ms = 1e3 * local_s / n;
        let global_ms = 1e3 * global_s / n;
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

/// The progress bar of one benchmark scenario.
fn bar_template(scenario: &str, unit: &str) -> String {
    format!("{scenario:<16} {{bar:40}} {{pos}}/{{len}} {unit}  ETA {{eta}}")
}

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
    progress: &logging::Progress,
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
            progress.bar.inc(1);
            ControlFlow::Continue(())
        })
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(trace)
}

fn bench_converge(mesh: Option<PathBuf>, iterations: usize, reference: usize, names: &[String]) -> Result<()> {
    let scenarios = pick_scenarios(names, &Scenario::ALL, Scenario::name)?;
    let (loaded, path) = bench_mesh(mesh.as_deref())?;
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
        let total = reference.saturating_add(iterations.saturating_mul(3));
        let progress = logging::bar(total as u64, &bar_template(s.name(), "iterations"));
        let mut scene = load_scenario(s, &loaded.mesh, path.clone())?;
        let star = convergence_run(&mut scene, Acceleration::default(), reference, &progress)?;
        let mut runs = Vec::new();
        for acceleration in [Acceleration::None, Acceleration::Anderson, Acceleration::Lbfgs] {
            let mut scene = load_scenario(s, &loaded.mesh, path.clone())?;
            runs.push((acceleration, convergence_run(&mut scene, acceleration, iterations, &progress)?));
        }
        drop(progress);
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
