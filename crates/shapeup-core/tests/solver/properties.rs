//! Property tests (proptest) of the solver on random small meshes (`tests/common/random.rs`,
//! degenerate and inverted elements, coordinates from 1e-12 to 1e12) with random constraint
//! groups, weights from 1e-12 to 1e12, soft or hard handles, and every acceleration:
//! - static mode: every iterate is finite (or the solve refuses with one clear line: a singular
//!   system), E never increases (up to round-off of the terms' size), hard handles sit exactly
//!   on their targets, a run in chunks is the same run, scaling every weight by a power of two
//!   changes nothing but E's unit (bit for bit), and a rigid motion of the whole input (rest
//!   shape, targets, vector options) moves each plain iterate rigidly for rigidly invariant
//!   types (up to the round-off that the system's and the iterates' conditioning amplify);
//! - dynamic mode (Projective Dynamics): time steps on the same inputs stay finite, or fail with
//!   one clear line and leave the state as it was.
//!
//! Runs are reproducible: a fixed seed and case count (`common::random::config`;
//! PROPTEST_RNG_SEED and PROPTEST_CASES override them), nothing persisted
//! (`failure_persistence: None`): each failure found was fixed and kept below as a plain
//! `#[test]` with its literal input.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common;

use common::random::{Base, MeshCase, magnitude, mesh_case, motion, vertex};
use common::turned_options;
use glam::{DQuat, DVec3};
use proptest::prelude::*;
use shapeup_core::constraints::{
    ConstraintType, DEGENERATE_FACES_GROUP, GroupDescription, RowSink, Selection, attach_degenerate_vertices,
    build_group, registry,
};
use shapeup_core::dynamics::{DynamicsParams, Simulation};
use shapeup_core::geometry::{RestGeometry, WorkingFrame, lumped_masses_surface, lumped_masses_volume};
use shapeup_core::solver::{Acceleration, GroupId, SolveError, SolverParams, System};

/// One shape group: which type (its name), its multiplier relative to the case's weight scale.
#[derive(Debug, Clone)]
struct GroupCase {
    ty: &'static str,
    relative_weight: f64,
}

/// A solver case: a mesh, groups, a handle, settings and a rigid motion.
#[derive(Debug, Clone)]
struct SolverCase {
    mesh: MeshCase,
    groups: Vec<GroupCase>,
    /// Every multiplier is multiplied by this (1e-12 … 1e12).
    weight_scale: f64,
    /// The handle's vertices (at least one; modulo the vertex count) and their targets'
    /// displacement (unit coordinates).
    handle: Vec<usize>,
    pull: [f64; 3],
    hard: bool,
    /// A weak closeness to rest over every vertex (multiplier relative to the weight scale), so
    /// that most cases are anchored.
    closeness: Option<f64>,
    acceleration: Acceleration,
    iterations: usize,
    motion: (DQuat, DVec3),
}

fn acceleration() -> impl Strategy<Value = Acceleration> {
    prop::sample::select(Acceleration::ALL.to_vec())
}

fn solver_case() -> impl Strategy<Value = SolverCase> {
    let names: Vec<&'static str> = types().iter().map(|t| t.name()).collect();
    let group = (prop::sample::select(names), prop_oneof![3 => 0.1..10.0f64, 1 => magnitude()])
        .prop_map(|(ty, relative_weight)| GroupCase { ty, relative_weight });
    let closeness = prop_oneof![3 => (1e-4..1e-1f64).prop_map(Some), 1 => Just(None), 1 => magnitude().prop_map(Some)];
    (
        mesh_case(),
        prop::collection::vec(group, 1..4),
        magnitude(),
        prop::collection::vec(vertex(), 1..4),
        prop::array::uniform3(-0.5..0.5f64),
        any::<bool>(),
        closeness,
        acceleration(),
        1usize..25,
        motion(),
    )
        .prop_map(
            |(mesh, groups, weight_scale, handle, pull, hard, closeness, acceleration, iterations, motion)| {
                SolverCase {
                    mesh,
                    groups,
                    weight_scale,
                    handle,
                    pull,
                    hard,
                    closeness,
                    acceleration,
                    iterations,
                    motion,
                }
            },
        )
}

/// The types a case draws its groups from: every registered one (face types over the whole
/// selection on a tetrahedral box, which has no polygon faces).
fn types() -> &'static [&'static dyn ConstraintType] {
    registry()
}

/// The registered type of this name.
fn type_named(name: &str) -> &'static dyn ConstraintType {
    *types().iter().find(|t| t.name() == name).expect("a registered type")
}

/// A case's system and its hard handle's (vertex, target) pairs (none for a soft handle).
type Built = (System, Vec<(u32, DVec3)>);

/// The system of a case on `rest` (moved by `turn` for the handle's pull and the vector
/// options) with every multiplier times `weight_scale`, and its hard handle (vertices,
/// targets) if any. `None` when a group cannot be built on this mesh (checked to be one clear
/// line).
fn system_of(
    case: &SolverCase,
    rest: &RestGeometry,
    turn: DQuat,
    weight_scale: f64,
) -> Result<Option<Built>, TestCaseError> {
    system_with(case, rest, turn, weight_scale, 1.0)
}

/// [`system_of`] with the degenerate faces' attachments (which scenes add with multiplier 1,
/// whatever the other weights) at multiplier `attachments`.
fn system_with(
    case: &SolverCase,
    rest: &RestGeometry,
    turn: DQuat,
    weight_scale: f64,
    attachments: f64,
) -> Result<Option<Built>, TestCaseError> {
    let n = rest.num_vertices();
    let params = SolverParams { acceleration: case.acceleration, ..SolverParams::default() };
    let mut system = System::new(n, params);
    let frame = WorkingFrame::IDENTITY;
    for g in &case.groups {
        let ty = type_named(g.ty);
        let mut description =
            GroupDescription { options: turned_options(ty, turn), ..GroupDescription::new(ty.name(), Selection::All) }
                .weight(g.relative_weight * weight_scale);
        if ty.options().iter().any(|o| o.key == "whole_selection") && !rest.tetrahedra.is_empty() {
            description = description.with("whole_selection", true);
        }
        match build_group(&description, rest, &frame) {
            Ok(group) => {
                system.add_group(group).unwrap();
            }
            Err(e) => {
                let e = e.to_string();
                prop_assert!(!e.is_empty() && !e.contains('\n'), "{}: {e}", ty.name());
                return Ok(None);
            }
        }
    }
    if let Some(w) = case.closeness {
        let closeness = GroupDescription::new("position", Selection::All).weight(w * weight_scale);
        system.add_group(build_group(&closeness, rest, &frame).unwrap()).unwrap();
    }
    let mut held: Vec<usize> = case.handle.iter().map(|i| i % n).collect();
    held.sort_unstable();
    held.dedup();
    let pull = turn * DVec3::from(case.pull) * case.mesh.scale;
    let targets: Vec<(u32, DVec3)> = held.iter().map(|&v| (v as u32, rest.positions[v] + pull)).collect();
    let handle = GroupDescription {
        targets: Some(targets.clone()),
        ..GroupDescription::new("position", Selection::from_indices(n, &held))
    }
    .weight(weight_scale)
    .with("hard", case.hard);
    system.add_group(build_group(&handle, rest, &frame).unwrap()).unwrap();
    if let (Some(group), _, _) = attach_degenerate_vertices(rest, system.groups().map(|(_, g)| g)) {
        system.add_group(group).unwrap();
    }
    let attached: Vec<GroupId> =
        system.groups().filter(|(_, g)| g.name == DEGENERATE_FACES_GROUP).map(|(id, _)| id).collect();
    for id in attached {
        system.set_multiplier(id, attachments).unwrap();
    }
    Ok(Some((system, if case.hard { targets } else { Vec::new() })))
}

/// The round-off scale of E's terms at q: Σ_groups g Σ_c ω_c Σ_r (m_r + ‖p_r‖)², with
/// m_r = Σ_v |c_rv| ‖q_v‖ the size of what cancels in (C q)_r (computing (C q)_r − p_r rounds
/// by ε (m_r + ‖p_r‖)), plus the loads' |energy|. Round-off in E is relative to this, not to E
/// (which may be ~0 at a minimum).
fn term_size(system: &System, q: &[DVec3]) -> f64 {
    let mut size = 0.0;
    for (_, group) in system.groups() {
        if group.hard {
            continue;
        }
        for c in &group.constraints {
            if let Some(load) = c.load() {
                size += group.multiplier * load.energy(q).abs();
            }
            if c.num_rows() == 0 {
                continue;
            }
            let mut sink = RowSink::default();
            c.rows(&mut sink);
            let mut m = vec![0.0; c.num_rows()];
            for e in &sink.entries {
                m[e.row as usize] += e.coeff.abs() * q[e.vertex as usize].length();
            }
            let mut p = vec![DVec3::ZERO; c.num_rows()];
            c.project(q, &mut p);
            let s: f64 = m.iter().zip(&p).map(|(m, p)| (m + p.length()).powi(2)).sum();
            size += group.multiplier * c.element_weight() * s;
        }
    }
    size
}

/// What the global step's round-off can add to E: a Cholesky solve is backward stable, so its
/// residual is about ε ‖A‖ ‖q‖ (and the right-hand side's rounding as much), and the error it
/// leaves in q costs rᵀA⁻¹r ≤ ‖r‖²/λ_min in E. With A = Σ w CᵀC over the solved vertices
/// (assembled densely here, per coordinate), that is 400 ε² λ_max² ‖q‖² / λ_min: negligible for a
/// well-conditioned system, and as large as f64 makes it for weights 1e24 apart or a mesh 1e8
/// of its sizes from the origin. `None` for a numerically singular A.
fn solve_round_off(system: &System, q: &[DVec3]) -> Option<f64> {
    let (lo, hi, solved) = spectrum(system)?;
    let q2: f64 = solved.iter().map(|&v| q[v].length_squared()).sum();
    Some(400.0 * f64::EPSILON * f64::EPSILON * hi * hi * q2 / lo)
}

/// The smallest and largest eigenvalues of the global matrix A = Σ w CᵀC over the solved
/// vertices (assembled densely, per coordinate), and those vertices; `None` for a numerically
/// singular A.
fn spectrum(system: &System) -> Option<(f64, f64, Vec<usize>)> {
    let n = system.num_vertices();
    let mut held = vec![false; n];
    let mut a = nalgebra::DMatrix::<f64>::zeros(n, n);
    for (_, group) in system.groups() {
        if group.hard {
            for c in &group.constraints {
                if let Some((vertices, _)) = c.held_points() {
                    vertices.iter().for_each(|&v| held[v as usize] = true);
                }
            }
        }
    }
    let mut touched = vec![false; n];
    for (_, group) in system.groups().filter(|(_, g)| !g.hard) {
        for c in &group.constraints {
            let mut sink = RowSink::default();
            c.rows(&mut sink);
            let w = group.multiplier * c.element_weight();
            let mut rows = vec![Vec::new(); c.num_rows()];
            for e in &sink.entries {
                rows[e.row as usize].push((e.vertex as usize, e.coeff));
                touched[e.vertex as usize] |= e.coeff != 0.0;
            }
            for row in &rows {
                for &(i, ci) in row {
                    for &(j, cj) in row {
                        a[(i, j)] += w * ci * cj;
                    }
                }
            }
        }
    }
    let solved: Vec<usize> = (0..n).filter(|&v| touched[v] && !held[v]).collect();
    if solved.is_empty() {
        return Some((1.0, 1.0, solved));
    }
    let a = a.select_rows(&solved).select_columns(&solved);
    let eigenvalues = a.symmetric_eigenvalues();
    let (lo, hi) = eigenvalues.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &x| (lo.min(x), hi.max(x.abs())));
    (lo > 1e-15 * hi).then_some((lo, hi, solved))
}

/// A refused solve: one line, and a singular or numerically singular system (never NaN).
fn check_refusal(e: &SolveError) -> Result<(), TestCaseError> {
    let message = e.to_string();
    prop_assert!(!message.is_empty() && !message.contains('\n'), "{message}");
    prop_assert!(
        matches!(e, SolveError::Unanchored { .. } | SolveError::Singular(_)),
        "a solve failed with: {message}"
    );
    Ok(())
}

/// Static mode: the run one iteration at a time (every iterate checked), then the same run at
/// once, then with every weight scaled, then moved rigidly.
fn check_static(case: &SolverCase) -> Result<(), TestCaseError> {
    let realized = case.mesh.realize();
    let Some((mut system, held)) = system_of(case, &realized.rest, DQuat::IDENTITY, case.weight_scale)? else {
        return Ok(());
    };
    // Start from the rest shape (q of the case as a start is a dynamic-mode matter).
    let mut q = realized.rest.positions.clone();
    let mut energies = Vec::new();
    for k in 0..case.iterations {
        let before = q.clone();
        let report = match system.solve(&mut q, 1, 0.0) {
            Ok(r) => r,
            Err(e) => {
                prop_assert_eq!(k, 0, "refused after {} iterations: {}", k, e);
                return check_refusal(&e);
            }
        };
        prop_assert!(q.iter().all(|x| x.is_finite()), "iteration {k}: non-finite positions");
        for &(v, target) in &held {
            prop_assert_eq!(q[v as usize], target, "iteration {}: hard handle {} off its target", k, v);
        }
        prop_assert_eq!(report.energies.len(), 1);
        let e = report.energies[0];
        let start = report.initial_energy;
        // E may rise by round-off only: of its evaluation (ε of its terms' size, around E),
        // and of the global solve (see `solve_round_off`). Not checked for a numerically
        // singular system (the solve is then only required to stay finite).
        let size = term_size(&system, &before).max(term_size(&system, &q));
        if let Some(solve) = solve_round_off(&system, &before) {
            let eps = f64::EPSILON;
            let slack = 8.0 * eps * (start.abs().max(e.abs()) * size).sqrt() + 8.0 * eps * eps * size + solve;
            prop_assert!(
                e <= start + slack,
                "iteration {k} ({:?}): E rose from {start:e} to {e:e} (terms' size {size:e}, solve round-off {solve:e})",
                case.acceleration
            );
        }
        energies.push(e);
    }
    // The same run in one solve.
    let Some((mut once, _)) = system_of(case, &realized.rest, DQuat::IDENTITY, case.weight_scale)? else {
        return Ok(());
    };
    let mut q_once = realized.rest.positions.clone();
    let report = once.solve(&mut q_once, case.iterations, 0.0).unwrap();
    let coordinates = q.iter().map(|x| x.length()).fold(0.0, f64::max);
    let off = q.iter().zip(&q_once).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
    prop_assert!(off <= 1e-9 * coordinates, "chunks of one iteration differ from one run by {off:e}");
    prop_assert_eq!(report.energies.len(), energies.len());
    Ok(())
}

/// The distance between two configurations over the size of their coordinates.
fn relative_gap(a: &[DVec3], b: &[DVec3]) -> f64 {
    let size = a.iter().chain(b).map(|x| x.length()).fold(0.0, f64::max);
    let off = a.iter().zip(b).map(|(x, y)| (*x - *y).length()).fold(0.0, f64::max);
    if off == 0.0 { 0.0 } else { off / size }
}

/// Scaling every multiplier by a power of two (2^±40 ≈ 1e±12) scales E and nothing else: the
/// same iterates bit for bit, with and without a tolerance (whose round-off floor must scale
/// with the weights too). Every multiplier includes the degenerate faces' attachments, which a
/// scene adds at 1 whatever its own weights (on a mesh 1e-12 across, outside the working frame,
/// every triangle is degenerate: an area ≤ 1e-12).
fn check_weight_scaling(case: &SolverCase, factor: f64, tolerance: f64) -> Result<(), TestCaseError> {
    let realized = case.mesh.realize();
    type Run = (Vec<DVec3>, Vec<f64>);
    let run = |weight_scale: f64, attachments: f64| -> Result<Option<Run>, TestCaseError> {
        let Some((mut system, _)) = system_with(case, &realized.rest, DQuat::IDENTITY, weight_scale, attachments)?
        else {
            return Ok(None);
        };
        let mut q = realized.rest.positions.clone();
        match system.solve(&mut q, case.iterations, tolerance) {
            Ok(report) => Ok(Some((q, report.energies))),
            Err(e) => check_refusal(&e).map(|()| None),
        }
    };
    let (Some((q, e)), Some((q_scaled, e_scaled))) =
        (run(case.weight_scale, 1.0)?, run(case.weight_scale * factor, factor)?)
    else {
        return Ok(());
    };
    // A power of two scales every product and sum of weights exactly (and square roots of them
    // by its square root): the whole run is the same up to that factor, bit for bit, unless some
    // test compares a weighted quantity with an absolute number.
    prop_assert_eq!(e.len(), e_scaled.len(), "iterations with weights × {:e}", factor);
    prop_assert!(
        q == q_scaled,
        "weights × {factor:e} move the result by {:e} of its size",
        relative_gap(&q, &q_scaled)
    );
    for (a, b) in e.iter().zip(&e_scaled) {
        prop_assert!(a * factor == *b, "E {a:e} × {factor:e} ≠ {b:e}");
    }
    Ok(())
}

/// A rigid motion of the rest shape, the handle's pull and vector options moves each iterate
/// the same way, for rigidly invariant types on well-conditioned input, up to the round-off
/// that the iterations amplify:
/// - each global step leaves a relative error of about κ ε in q (κ = λ_max/λ_min of A);
/// - each projection reads its vertices' positions, which keep log₁₀(1/ε) − log₁₀(c) digits of
///   the element's shape, c = (largest ‖q_v‖) / (the vertices' extent, see
///   [`shape_conditioning`]): a rigid fit of an element pulled 1e12 of its sizes away (a load
///   on a mesh 1e-12 across), or squashed onto a line, is round-off. The comparison stops at an
///   iterate where some c exceeds 1e6.
///
/// The plain iteration only (the case's acceleration is set aside): an accelerated one builds its
/// step from differences of earlier iterates (L-BFGS's secant pairs, Anderson's residual
/// differences, known only to ε ‖q‖ / ‖s‖ for a step s, which near convergence is all
/// round-off) and accepts it on an energy comparison that round-off decides at a tie. The two
/// runs then part by far more than ε and no bound is useful; found on 4-point spheres and stiff
/// planes, L-BFGS runs 1e-4 apart after one quasi-Newton step.
///
/// A refusal must be the same for both, unless A is numerically singular (a pivot then comes
/// out ≤ 0 or not, depending on the rounding).
fn check_rigid_solve(case: &SolverCase) -> Result<(), TestCaseError> {
    let case = &SolverCase { acceleration: Acceleration::None, ..case.clone() };
    if !case.mesh.is_generic() || case.groups.iter().any(|g| !type_named(g.ty).is_rigidly_invariant()) {
        return Ok(());
    }
    let (turn, shift) = case.motion;
    let shift = shift * case.mesh.scale;
    let realized = case.mesh.realize();
    let moved = case.mesh.realize_moved(turn, case.motion.1);
    let Some((mut system, _)) = system_of(case, &realized.rest, DQuat::IDENTITY, case.weight_scale)? else {
        return Ok(());
    };
    let (mut moved_system, _) = system_of(case, &moved.rest, turn, case.weight_scale)?
        .ok_or_else(|| TestCaseError::fail("builds on the input but not on the moved input"))?;
    let mut q = realized.rest.positions.clone();
    let mut q_moved = moved.rest.positions.clone();
    let mut bound = 1e-9;
    for k in 0..case.iterations {
        let digits_lost = shape_conditioning(&system, &q);
        if digits_lost > 1e6 {
            return Ok(());
        }
        let (a, b) = (system.solve(&mut q, 1, 0.0), moved_system.solve(&mut q_moved, 1, 0.0));
        match (a, b) {
            (Ok(_), Ok(_)) => {}
            (Err(e), Err(f)) => {
                prop_assert_eq!(std::mem::discriminant(&e), std::mem::discriminant(&f));
                return check_refusal(&e);
            }
            (a, b) => {
                let singular = spectrum(&system).is_none() || spectrum(&moved_system).is_none();
                prop_assert!(singular, "only one solve failed: {:?} vs {:?}", a.err(), b.err());
                return Ok(());
            }
        }
        let Some((lo, hi, _)) = spectrum(&system) else { return Ok(()) };
        bound += 100.0 * (hi / lo) * f64::EPSILON * digits_lost.max(1.0);
        let expected: Vec<DVec3> = q.iter().map(|&x| turn * x + shift).collect();
        let gap = relative_gap(&expected, &q_moved);
        prop_assert!(
            gap <= bound,
            "iteration {k}: the moved iterate is off the moved one by {gap:e} of its size (κ = {:e}, c = {:e})",
            hi / lo,
            digits_lost
        );
    }
    Ok(())
}

/// The largest c = (largest ‖q_v‖) / (the vertices' extent about their centroid) over the
/// system's constraints of two or more vertices (see [`check_rigid_solve`]); ∞ where some
/// constraint's vertices coincide. The extent is the second singular value of the centred
/// positions (the first for two vertices): a fit (a rotation, a plane, a circle) of points
/// nearly on a line is as ill-conditioned as that of points nearly on one point.
fn shape_conditioning(system: &System, q: &[DVec3]) -> f64 {
    let mut worst: f64 = 1.0;
    for (_, group) in system.groups() {
        for c in group.constraints.iter().filter(|c| c.num_rows() > 0 && c.vertices().len() > 1) {
            let points: Vec<DVec3> = c.vertices().iter().map(|&v| q[v as usize]).collect();
            let centroid = points.iter().copied().sum::<DVec3>() / points.len() as f64;
            let centred = nalgebra::DMatrix::from_fn(points.len(), 3, |i, j| (points[i] - centroid)[j]);
            let mut sigma: Vec<f64> = centred.singular_values().iter().copied().collect();
            sigma.sort_by(|a, b| b.total_cmp(a));
            let extent = sigma[if points.len() == 2 { 0 } else { 1 }];
            let far = points.iter().map(|p| p.length()).fold(0.0, f64::max);
            worst = worst.max(if extent > 0.0 { far / extent } else { f64::INFINITY });
        }
    }
    worst
}

proptest! {
    #![proptest_config(common::random::config(128))]

    #[test]
    fn static_solves_are_finite_monotone_and_hold_hard_handles(case in solver_case()) {
        check_static(&case)?;
    }

    #[test]
    fn scaling_every_weight_scales_only_the_energy(
        case in solver_case(),
        factor in prop::sample::select(vec![2f64.powi(40), 2f64.powi(-40), 2f64.powi(20), 2f64.powi(-20)]),
        tolerance in prop::sample::select(vec![0.0, 1e-6]),
    ) {
        check_weight_scaling(&case, factor, tolerance)?;
    }

    #[test]
    fn rigid_motions_of_the_input_move_the_result(case in solver_case()) {
        check_rigid_solve(&case)?;
    }
}

/// Dynamic mode: a few time steps stay finite, or fail with one clear line and leave the state.
fn check_dynamic(case: &SolverCase, time_step: f64, stiffness: f64, gravity_scale: f64) -> Result<(), TestCaseError> {
    let realized = case.mesh.realize();
    let Some((mut system, _)) = system_of(case, &realized.rest, DQuat::IDENTITY, case.weight_scale)? else {
        return Ok(());
    };
    system.set_params(SolverParams { iterations: case.iterations.min(10), ..*system.params() });
    let rest = &realized.rest;
    let masses = if rest.tetrahedra.is_empty() {
        lumped_masses_surface(rest.num_vertices(), &rest.triangles, &rest.triangle_areas, 1.0)
    } else {
        lumped_masses_volume(&rest.positions, &rest.tetrahedra, 1.0)
    };
    let params = DynamicsParams {
        time_step,
        stiffness,
        gravity: DVec3::new(0.0, -9.81, 0.0) * gravity_scale,
        ..DynamicsParams::default()
    };
    let mut sim = match Simulation::new(system, masses, realized.q.clone(), params) {
        Ok(s) => s,
        Err(e) => {
            let e = e.to_string();
            prop_assert!(!e.is_empty() && !e.contains('\n'), "{e}");
            return Ok(());
        }
    };
    for k in 0..4 {
        let (x, v) = (sim.positions().to_vec(), sim.velocities().to_vec());
        match sim.step() {
            Ok(_) => {
                prop_assert!(
                    sim.positions().iter().chain(sim.velocities()).all(|p| p.is_finite()),
                    "step {k}: non-finite state"
                );
            }
            Err(e) => {
                let message = e.to_string();
                prop_assert!(!message.is_empty() && !message.contains('\n'), "{message}");
                prop_assert!(
                    sim.positions() == &x[..] && sim.velocities() == &v[..],
                    "a failed step changed the state"
                );
                return Ok(());
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(common::random::config(96))]

    #[test]
    fn time_steps_stay_finite_or_fail_clearly(
        case in solver_case(),
        time_step in prop::sample::select(vec![1.0 / 60.0, 1e-6, 1.0]),
        stiffness in prop::sample::select(vec![100.0, 1e-6, 1e6]),
        gravity_scale in magnitude(),
    ) {
        check_dynamic(&case, time_step, stiffness, gravity_scale)?;
    }
}

// Cases the properties found, as proptest shrank them, each failing before the fix it names.

/// A case on `mesh` with these (type, relative weight) groups, a soft handle on vertex 0 that
/// stays put, no closeness, L-BFGS, one iteration.
fn literal(mesh: MeshCase, groups: &[(&'static str, f64)]) -> SolverCase {
    SolverCase {
        mesh,
        groups: groups.iter().map(|&(ty, relative_weight)| GroupCase { ty, relative_weight }).collect(),
        weight_scale: 1.0,
        handle: vec![0],
        pull: [0.0; 3],
        hard: false,
        closeness: None,
        acceleration: Acceleration::Lbfgs,
        iterations: 1,
        motion: (DQuat::IDENTITY, DVec3::ZERO),
    }
}

/// A tolerance run with weights 1e-12 ran 3 iterations, and 1 with the weights 2^-40 times
/// that: the absolute energy floor 1e-20 stopped it. The floor is now relative to the terms.
#[test]
fn regression_energy_floor_scales_with_the_weights() {
    let mesh = MeshCase { scale: 1e-6, ..MeshCase::still(Base::Quads { nx: 1, ny: 1 }) };
    let case = SolverCase { weight_scale: 1e-12, iterations: 3, ..literal(mesh, &[("plane", 1e12)]) };
    check_weight_scaling(&case, 2f64.powi(-40), 1e-6).unwrap_or_else(|e| panic!("{e}"));
}

/// Bending 1e12 across with a hard handle: E rose (the absolute thresholds on H took the
/// vertices for flat at rest, and p = 0 is no nearest point of the set).
#[test]
fn regression_bending_1e12_across_never_raises_the_energy() {
    let mesh = MeshCase { scale: 1e12, ..MeshCase::still(Base::Tets { cells: [1, 1, 2] }) };
    let case = SolverCase { hard: true, iterations: 4, ..literal(mesh, &[("bending", 0.1)]) };
    check_static(&case).unwrap_or_else(|e| panic!("{e}"));
}

/// On a mesh 1e-12 across every triangle is degenerate and gets an attachment, which scenes
/// add at multiplier 1: scaling the other weights alone moved the result (the test's fix: the
/// attachments scale too).
#[test]
fn regression_attachments_scale_with_the_weights() {
    let mesh = MeshCase { scale: 1e-12, ..MeshCase::still(Base::Quads { nx: 1, ny: 1 }) };
    let case = SolverCase { weight_scale: 1e6, pull: [0.0, 0.0, 0.3], ..literal(mesh, &[("iso_one_ring", 0.1)]) };
    check_weight_scaling(&case, 2f64.powi(40), 0.0).unwrap_or_else(|e| panic!("{e}"));
}
