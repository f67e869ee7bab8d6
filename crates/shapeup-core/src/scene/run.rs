//! Running a loaded scene the way the command line does: the static solve's report, and time
//! steps with spinning handles. The CLI, the Python package and library users share these, so
//! that a scene gives the same result (and the same report) whichever door it comes through.

use super::{LoadedScene, SceneError, SpinningHandle};
use crate::dynamics::{Simulation, StepReport};
use crate::io::{IoError, PlyEncoding, WriteFormat, write_mesh_with};
use crate::mesh::Mesh;
use crate::solver::{SolveError, SolveReport};
use crate::warnings::Warnings;
use glam::DVec3;
use serde_json::{Value, json};
use std::path::Path;

/// |E_k − E_{k−1}| / |E_{k−1}| for each iteration k, from E_0 = `initial` (0 where the
/// energy did not change, so that 0 → 0 is no change rather than NaN).
pub fn relative_changes(initial: f64, energies: &[f64]) -> Vec<f64> {
    std::iter::once(initial)
        .chain(energies.iter().copied())
        .zip(energies)
        .map(|(before, &after)| if before == after { 0.0 } else { (before - after).abs() / before.abs() })
        .collect()
}

impl LoadedScene {
    /// The JSON report of a static solve (`shapeup deform --report`): sizes, each group's
    /// largest violation at rest and in the result (over the rest mesh's mean edge length, so
    /// that a plane group's is the planarity error), the largest vertex displacement over the
    /// bounding-box diagonal, the energy after each iteration, the factorizations, what touches
    /// the result (with contact) and the timings. `q` is the
    /// result (working frame), `output` the mesh written from it, `warnings` what loading and
    /// writing said, `total_seconds` the wall-clock time of the whole run.
    pub fn deform_report(
        &self,
        q: &[DVec3],
        solve: &SolveReport,
        output: &Mesh,
        warnings: &Warnings,
        total_seconds: f64,
    ) -> Value {
        let mean_edge = crate::geometry::mean_edge_length(&self.rest).max(f64::MIN_POSITIVE);
        let rest = self.rest_positions();
        let groups: Vec<Value> = self
            .group_ids
            .iter()
            .filter_map(|&id| self.system.group(id))
            .map(|g| {
                json!({
                    "name": g.name, "type": g.kind, "weight": g.multiplier, "constraints": g.constraints.len(),
                    "hard": g.hard,
                    "max_violation": {"rest": g.relative_violation(rest, mean_edge), "result": g.relative_violation(q, mean_edge)},
                })
            })
            .collect();
        let (lo, hi) = self.mesh.bounding_box();
        let diagonal = (hi - lo).length().max(f64::MIN_POSITIVE);
        let moved =
            output.positions.iter().zip(&self.mesh.positions).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
        let (nnz_a, nnz_l) = self.system.factor_sizes();
        // What touches the result (the contact's last projection), as `simulate` counts a step's.
        let touch = self.contact.as_ref().map(crate::contact::ContactModel::stats).unwrap_or_default();
        json!({
            "vertices": self.mesh.num_vertices(),
            "triangles": self.mesh.num_triangles(),
            "solved_vertices": self.system.num_solved_vertices(),
            "constraints": self.system.num_constraints(),
            "groups": groups,
            // The largest vertex displacement from the input, over its bounding-box diagonal.
            "max_displacement": moved / diagonal,
            // Where the solve started: `[mesh] start`'s file, or null for the rest shape. A
            // start that already met the tolerance is the result, with 0 iterations.
            "start": self.scene.start_path().map(|p| p.display().to_string()),
            "iterations": solve.energies.len(),
            "initial_energy": solve.initial_energy,
            "energy": solve.energies,
            // |E_k − E_{k−1}| / E_{k−1}, from E_0 = initial_energy.
            "relative_change": relative_changes(solve.initial_energy, &solve.energies),
            // Contact iterates plainly (crate::contact::solve_with_contact).
            "acceleration": if self.contact.as_ref().is_some_and(|c| c.is_active()) {
                crate::solver::Acceleration::None
            } else {
                self.system.params().acceleration
            },
            "rejected": solve.rejected,
            // The relative residual at the end when the solve ran all its iterations
            // (crate::solver::SolveReport::residual), and whether it is above the limit (null
            // when not measured).
            "residual": solve.residual,
            "unconverged": solve.residual.map(|_| solve.unconverged),
            "factor": {"nnz_lower": nnz_a, "nnz_l": nnz_l},
            "factorizations": self.system.factorizations(),
            "contacts": touch.touching,
            "self_contacts": touch.self_touching,
            "contact_vertices": touch.vertices,
            "ended_inside": touch.inside,
            "warnings": warnings.to_json(),
            "timings": {
                "load_s": self.load_seconds,
                "setup_s": self.build_seconds + solve.setup_seconds,
                "local_s": solve.local_seconds,
                "global_s": solve.global_seconds,
                "total_s": total_seconds,
            },
        })
    }

    /// Writes the result `q` (working frame) to `path` as `shapeup deform` does (the format
    /// from the extension; a volume format writes the tetrahedra too; `ply_encoding` for a
    /// PLY file, default the input's or binary little-endian), atomically. Returns the mesh
    /// written and what writing it said.
    ///
    /// # Errors
    /// [`IoError`] naming the file (an unknown extension, a folder that does not exist…).
    pub fn write_result(
        &self,
        path: &Path,
        q: &[DVec3],
        ply_encoding: Option<PlyEncoding>,
    ) -> Result<(Mesh, Warnings), IoError> {
        let format = match WriteFormat::from_path(path)? {
            WriteFormat::Ply(_) => WriteFormat::Ply(ply_encoding),
            other => other,
        };
        let volume = matches!(format, WriteFormat::Msh | WriteFormat::Vtu | WriteFormat::TetGen);
        let mesh = self.output_mesh(q, volume, |v| self.system.is_solved(v));
        let warnings = write_mesh_with(path, &mesh, &self.attributes, format)?;
        Ok((mesh, warnings))
    }

    /// Starts the scene's Projective Dynamics run (`shapeup simulate`): the simulation at rest
    /// and its spinning handles. The constraint system moves into it.
    ///
    /// # Errors
    /// As [`LoadedScene::start_simulation`] and [`LoadedScene::spinning_handles`].
    pub fn start_scene_simulation(&mut self) -> Result<SceneSimulation, SceneError> {
        let simulation = self.start_simulation()?;
        let spinning = self.spinning_handles(simulation.system())?;
        Ok(SceneSimulation { simulation, spinning })
    }
}

/// What a run of time steps adds up for its report.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepTotals {
    /// E after each step (when the run records it).
    pub energies: Vec<f64>,
    /// Seconds in local steps.
    pub local_seconds: f64,
    /// Seconds in global steps.
    pub global_seconds: f64,
    /// Seconds (re)assembling and factoring.
    pub setup_seconds: f64,
    /// Seconds spent computing E after plain steps (which skip it).
    pub energy_seconds: f64,
    /// Accelerated iterations replaced by plain ones.
    pub rejected: usize,
    /// Contacts touching at the end of each step (empty without contact).
    pub contacts: Vec<usize>,
    /// Of those, self contacts, per step.
    pub self_contacts: Vec<usize>,
    /// Vertices in a touching contact at the end of each step (the frames' `contact` flag).
    pub contact_vertices: Vec<usize>,
    /// Vertices whose motion the self-collision crossing check changed, summed over the
    /// run ([`crate::contact::ContactStats::stopped`]).
    pub crossings_stopped: usize,
    /// Vertices that ended a step inside a collider, summed over the run
    /// ([`crate::contact::ContactStats::inside`]).
    pub ended_inside: usize,
    /// The first step at whose end a vertex was inside a collider, and how many were.
    pub first_inside: Option<(usize, usize)>,
    /// Seconds in contact detection and end-of-step projection.
    pub contact_seconds: f64,
    /// Seconds checking steps for stopping short ([`StepReport::check_seconds`]).
    pub check_seconds: f64,
    /// Each checked step's residual, with its number ([`StepReport::residual`]).
    pub residuals: Vec<(usize, f64)>,
    /// Checked steps above [`crate::dynamics::DYNAMIC_RESIDUAL_LIMIT`]: stopped short.
    pub unconverged: usize,
    /// The iterations a step may run and the tolerance that ends it sooner
    /// ([`crate::solver::SolverParams`]), for the warning.
    pub iteration_cap: usize,
    /// See `iteration_cap`.
    pub tolerance: f64,
    /// Groups the factorization could not resolve, as the first step that had any found them.
    pub lost_groups: Vec<crate::solver::LostGroup>,
}

impl StepTotals {
    /// Adds one step's timings and rejections.
    pub fn add(&mut self, step: &StepReport) {
        self.local_seconds += step.local_seconds;
        self.global_seconds += step.global_seconds;
        self.setup_seconds += step.setup_seconds;
        self.rejected += step.rejected;
        self.contact_seconds += step.contact_seconds;
        self.check_seconds += step.check_seconds;
        if self.lost_groups.is_empty() {
            self.lost_groups.clone_from(&step.lost_groups);
        }
    }
}

impl StepTotals {
    /// Records step `k`'s residual, when it was checked.
    pub fn add_residual(&mut self, k: usize, step: &StepReport) {
        if let Some(r) = step.residual {
            self.residuals.push((k, r));
            self.unconverged += usize::from(step.unconverged);
        }
    }

    /// What the run should say once: groups the factorization cannot resolve, time steps that
    /// stopped short of their converged motion, vertices that ended steps inside a collider.
    pub fn add_warnings(&self, warnings: &mut Warnings) {
        crate::solver::add_lost_groups_warning(warnings, &self.lost_groups);
        let limit = crate::dynamics::DYNAMIC_RESIDUAL_LIMIT;
        let worst = self.residuals.iter().filter(|r| r.1 > limit).max_by(|a, b| a.1.total_cmp(&b.1));
        let first = self.residuals.iter().find(|r| r.1 > limit).map(|r| r.0);
        if let (Some(&(step, residual)), Some(first)) = (worst, first) {
            let (cap, tolerance) = (self.iteration_cap, self.tolerance);
            let (settings, advice) = if tolerance > 0.0 {
                (
                    format!("{cap} iterations a step at most, tolerance {tolerance:e}"),
                    "raise `iterations` and lower `tolerance`",
                )
            } else {
                (format!("{cap} iterations a step"), "raise `iterations`")
            };
            let message = format!(
                "of the {} time steps checked (steps 1, 2, 4, …, 64, then every 64th) stopped short of the converged step ({settings}): the worst, step {step}, misses {} % of its motion (the limit is {} %); {advice}, or lower `stiffness` or `time_step`",
                self.residuals.len(),
                crate::text::three_digits(100.0 * residual),
                100.0 * limit,
            );
            warnings.add_many("unconverged", &message, self.unconverged, || format!("step {first}"));
        }
        if let Some((step, count)) = self.first_inside {
            warnings.add_many(
                "inside_collider",
                "vertex-steps ended inside a collider (squeezed between two colliders, held back by the self-collision check where a moving collider came over them, or held there by a hard pin)",
                self.ended_inside,
                || format!("{count} vertices at the end of step {step}"),
            );
        }
    }
}

impl LoadedScene {
    /// The JSON report of a simulation (`shapeup simulate --report`): sizes, `steps` asked
    /// for, the frames' `format` and how many were written, E after each step, the kinetic
    /// energy at the end, the acceleration, the warnings and the timings.
    #[allow(clippy::too_many_arguments)]
    pub fn simulate_report(
        &self,
        simulation: &Simulation,
        totals: &StepTotals,
        steps: usize,
        format: &str,
        frames_written: usize,
        warnings: &Warnings,
        total_seconds: f64,
    ) -> Value {
        let system = simulation.system();
        json!({
            "vertices": self.mesh.num_vertices(),
            "triangles": self.mesh.num_triangles(),
            "tetrahedra": self.mesh.num_tetrahedra(),
            "constraints": system.num_constraints(),
            "steps": steps,
            "format": format,
            "frames_written": frames_written,
            "time_step": simulation.params().time_step,
            "simulated_s": simulation.time(),
            "energy": totals.energies,
            "kinetic_energy_end": simulation.kinetic_energy(),
            // Contact iterates plainly (crate::contact::solve_with_contact).
            "acceleration": if simulation.contact().is_some_and(|c| c.is_active()) {
                crate::solver::Acceleration::None.name()
            } else {
                system.params().acceleration.name()
            },
            "factorizations": system.factorizations(),
            "contacts": totals.contacts,
            "self_contacts": totals.self_contacts,
            "contact_vertices": totals.contact_vertices,
            "crossings_stopped": totals.crossings_stopped,
            "ended_inside": totals.ended_inside,
            "rejected": totals.rejected,
            // Checked steps: [step, share of the converged step's motion missed].
            "residuals": totals.residuals,
            "unconverged_steps": totals.unconverged,
            "warnings": warnings.to_json(),
            "timings": {
                "load_s": self.load_seconds,
                "setup_s": self.build_seconds + totals.setup_seconds,
                "local_s": totals.local_seconds,
                "global_s": totals.global_seconds,
                "energy_s": totals.energy_seconds,
                "contact_s": totals.contact_seconds,
                "check_s": totals.check_seconds,
                "total_s": total_seconds,
            },
        })
    }
}

/// Why a scene's time step failed.
#[derive(Debug, thiserror::Error)]
pub enum StepError {
    /// The solver refused (non-finite positions, a singular system…).
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// ½ Σ m v² overflowed: a rigid fall keeps E finite (even 0) while the velocities blow up.
    #[error(
        "the kinetic energy is not a finite number (velocities too large); check the gravity, time step and targets"
    )]
    Diverged,
}

/// A scene's simulation: [`Simulation`] plus the handles that turn with time.
#[derive(Debug)]
pub struct SceneSimulation {
    /// The state and the system in dynamic mode.
    pub simulation: Simulation,
    spinning: Vec<SpinningHandle>,
}

impl SceneSimulation {
    /// One time step: spinning handles take their targets at the end of the step, then
    /// [`Simulation::step`].
    ///
    /// # Errors
    /// [`StepError`]; on [`StepError::Diverged`] the step has been taken.
    pub fn step(&mut self) -> Result<StepReport, StepError> {
        let t = (self.simulation.steps() + 1) as f64 * self.simulation.params().time_step;
        for handle in &self.spinning {
            self.simulation.system_mut().set_targets(handle.id, &handle.targets_at(t))?;
        }
        let report = self.simulation.step()?;
        if !self.simulation.kinetic_energy().is_finite() {
            return Err(StepError::Diverged);
        }
        Ok(report)
    }
}

/// Why [`SceneSimulation::run`] stopped before its last step.
#[derive(Debug, thiserror::Error)]
pub enum RunError<E> {
    /// Time step `step` (from 1) of `frames` failed.
    #[error("step {step} of {frames} failed: {source}")]
    Step {
        /// The step.
        step: usize,
        /// The steps the run was asked for.
        frames: usize,
        /// Why.
        source: StepError,
    },
    /// E after step `step` could not be computed.
    #[error("energy after step {step}: {source}")]
    Energy {
        /// The step.
        step: usize,
        /// Why.
        source: SolveError,
    },
    /// The caller's `on_step` refused (a frame that cannot be written, an interrupt…).
    #[error(transparent)]
    Stopped(E),
}

impl SceneSimulation {
    /// The run of `shapeup simulate` and `Scene.simulate`: `frames` time steps from the
    /// current state. `on_step(k, simulation, keep)` is called for the state at rest (k = 0)
    /// and after each step k, with `keep` true for frame 0, every `every`-th frame and the
    /// last (the frames a run writes); an `Err` from it stops the run. With `energies`, E
    /// after each step is recorded in [`StepTotals::energies`] (computed when the step did
    /// not: plain iterations skip it; the seconds go to [`StepTotals::energy_seconds`]).
    ///
    /// # Errors
    /// [`RunError`]: the step that failed, or what `on_step` returned.
    pub fn run<E>(
        &mut self,
        frames: usize,
        every: usize,
        energies: bool,
        mut on_step: impl FnMut(usize, &Simulation, bool) -> Result<(), E>,
    ) -> Result<StepTotals, RunError<E>> {
        let capacity = if energies { frames.min(1 << 20) } else { 0 };
        let solver = *self.simulation.system().params();
        let mut totals = StepTotals {
            energies: Vec::with_capacity(capacity),
            iteration_cap: solver.iterations,
            tolerance: solver.tolerance,
            ..StepTotals::default()
        };
        on_step(0, &self.simulation, true).map_err(RunError::Stopped)?;
        for k in 1..=frames {
            // Overflowing velocities fail the step whether or not E is recorded (StepError::Diverged).
            let step = self.step().map_err(|source| RunError::Step { step: k, frames, source })?;
            if energies {
                let energy = match step.energy {
                    Some(e) => e,
                    None => {
                        let t = std::time::Instant::now();
                        let e = self.simulation.energy().map_err(|source| RunError::Energy { step: k, source })?;
                        totals.energy_seconds += t.elapsed().as_secs_f64();
                        e
                    }
                };
                totals.energies.push(energy);
            }
            totals.add(&step);
            totals.add_residual(k, &step);
            if self.simulation.contact().is_some() {
                totals.contacts.push(step.contact.touching);
                totals.self_contacts.push(step.contact.self_touching);
                totals.contact_vertices.push(step.contact.vertices);
                totals.crossings_stopped += step.contact.stopped;
                totals.ended_inside += step.contact.inside;
                if step.contact.inside > 0 && totals.first_inside.is_none() {
                    totals.first_inside = Some((k, step.contact.inside));
                }
            }
            on_step(k, &self.simulation, super::frames::is_kept(k, frames, every)).map_err(RunError::Stopped)?;
        }
        Ok(totals)
    }
}
