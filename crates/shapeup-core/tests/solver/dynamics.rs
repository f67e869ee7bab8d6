//! Projective Dynamics: the discrete free fall, conserved momentum, damping to rest, the floor,
//! inverted tetrahedra, rigid-motion equivariance and convergence in the time step.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use glam::{DQuat, DVec3};
use shapeup_core::constraints::{BuildContext, Params, Position, Selection, build_constraints};
use shapeup_core::dynamics::{DynamicsParams, Simulation};
use shapeup_core::generate;
use shapeup_core::geometry::tet_volume;
use shapeup_core::geometry::{RestGeometry, WorkingFrame, lumped_masses_surface, lumped_masses_volume};
use shapeup_core::mesh::Mesh;
use shapeup_core::solver::{Acceleration, ConstraintGroup, SolverParams, System};

fn group(kind: &str, weight: f64, rest: &RestGeometry, params: Params) -> ConstraintGroup {
    let ctx = BuildContext { rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
    ConstraintGroup::new(kind, weight, build_constraints(kind, &ctx, params).unwrap())
}

fn masses(mesh: &Mesh, rest: &RestGeometry) -> Vec<f64> {
    if mesh.tetrahedra.is_empty() {
        lumped_masses_surface(mesh.num_vertices(), &mesh.triangles, &rest.triangle_areas, 1.0)
    } else {
        lumped_masses_volume(&mesh.positions, &mesh.tetrahedra, 1.0)
    }
}

/// A simulation of `mesh` with the given shape groups (kind, weight) and settings.
fn simulation(mesh: &Mesh, kinds: &[(&str, f64)], params: DynamicsParams) -> (Simulation, RestGeometry) {
    simulation_with(mesh, kinds, params, SolverParams::default().acceleration)
}

/// [`simulation`] with a chosen acceleration.
fn simulation_with(
    mesh: &Mesh,
    kinds: &[(&str, f64)],
    params: DynamicsParams,
    acceleration: Acceleration,
) -> (Simulation, RestGeometry) {
    simulation_solved(mesh, kinds, params, SolverParams { acceleration, ..SolverParams::default() })
}

/// [`simulation`] with chosen solver settings (iterations per step, tolerance, acceleration).
fn simulation_solved(
    mesh: &Mesh,
    kinds: &[(&str, f64)],
    params: DynamicsParams,
    solver: SolverParams,
) -> (Simulation, RestGeometry) {
    let rest = RestGeometry::new(mesh.positions.clone(), mesh.triangles.clone(), mesh.tetrahedra.clone());
    let mut system = System::new(mesh.num_vertices(), solver);
    for &(kind, w) in kinds {
        system.add_group(group(kind, w, &rest, Params::default())).unwrap();
    }
    let m = masses(mesh, &rest);
    (Simulation::new(system, m, mesh.positions.clone(), params).unwrap(), rest)
}

/// A non-uniform initial velocity field (a swirl plus a drift), so constraints are exercised.
fn swirl(positions: &[DVec3]) -> Vec<DVec3> {
    positions.iter().map(|p| DVec3::new(-p.z, 0.3 * p.x * p.x, p.x) * 2.0 + DVec3::new(0.1, 0.2, -0.05)).collect()
}

#[test]
fn free_fall_without_constraints_follows_the_discrete_formula() {
    let mesh = generate::cloth_grid(5, 4, 1.0, 0.8);
    let params = DynamicsParams { gravity: DVec3::new(0.5, -9.81, 0.2), ..DynamicsParams::default() };
    for acceleration in [Acceleration::None, Acceleration::Anderson, Acceleration::Lbfgs] {
        let (mut sim, _) = simulation_with(&mesh, &[], params, acceleration);
        let v0 = swirl(&mesh.positions);
        sim.set_state(&mesh.positions, &v0).unwrap();
        let h = params.time_step;
        let (mut x, mut v) = (mesh.positions.clone(), v0);
        for _ in 0..30 {
            sim.step().unwrap();
            for i in 0..x.len() {
                // x_{n+1} = x_n + h v_n + h² g, v_{n+1} = (x_{n+1} − x_n)/h
                let next = x[i] + h * v[i] + h * h * params.gravity;
                v[i] = (next - x[i]) / h;
                x[i] = next;
            }
        }
        for (a, b) in sim.positions().iter().zip(&x) {
            assert!((*a - *b).length() < 1e-12, "{a} vs {b}");
        }
        for (a, b) in sim.velocities().iter().zip(&v) {
            assert!((*a - *b).length() < 1e-9, "{a} vs {b}");
        }
    }
}

#[test]
fn momentum_is_conserved_without_gravity_or_damping() {
    let mesh = generate::cloth_grid(12, 12, 1.0, 1.0);
    let params = DynamicsParams { gravity: DVec3::ZERO, ..DynamicsParams::default() };
    let kinds = [&[("edge_spring", 10.0)][..], &[("triangle_strain", 10.0), ("bending", 10.0)][..]];
    for (kinds, acceleration) in
        kinds.iter().flat_map(|k| [Acceleration::None, Acceleration::Anderson, Acceleration::Lbfgs].map(|a| (*k, a)))
    {
        let (mut sim, _) = simulation_with(&mesh, kinds, params, acceleration);
        sim.set_state(&mesh.positions, &swirl(&mesh.positions)).unwrap();
        let p0 = sim.momentum();
        let mut moved = 0.0_f64;
        for _ in 0..40 {
            sim.step().unwrap();
            moved = moved.max((sim.positions()[0] - mesh.positions[0]).length());
        }
        assert!(moved > 0.1, "the body moved ({moved})");
        let p = sim.momentum();
        assert!((p - p0).length() < 1e-10 * (1.0 + p0.length()), "{kinds:?} {acceleration:?}: momentum {p0} -> {p}");
    }
}

#[test]
fn a_pinned_cloth_with_damping_comes_to_rest() {
    let mesh = generate::cloth_grid(15, 15, 1.0, 1.0);
    let params = DynamicsParams { damping: 0.05, ..DynamicsParams::default() };
    let (mut sim, _) = simulation(&mesh, &[("triangle_strain", 10.0), ("bending", 10.0)], params);
    // Pin two corners where they are.
    let corners = [0u32, 14];
    let pins = Position::new(corners.to_vec(), corners.iter().map(|&v| mesh.positions[v as usize]).collect()).unwrap();
    sim.system_mut().add_group(ConstraintGroup::new("pins", 100.0, vec![Box::new(pins)])).unwrap();
    let mut peak = 0.0_f64;
    for _ in 0..600 {
        sim.step().unwrap();
        peak = peak.max(sim.kinetic_energy());
    }
    assert!(peak > 1e-2, "the cloth swung (peak kinetic energy {peak})");
    let ke = sim.kinetic_energy();
    assert!(ke < 1e-6 * peak, "kinetic energy {ke} after 10 s (peak {peak})");
    // It hangs below the pins and the pins held.
    let lowest = sim.positions().iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    assert!(lowest < -0.5, "the cloth drapes down ({lowest})");
    for &c in &corners {
        assert!((sim.positions()[c as usize] - mesh.positions[c as usize]).length() < 0.02);
    }
}

#[test]
fn nothing_falls_through_the_floor() {
    // A tetrahedral box dropped from above a floor at y = 0.
    let mut mesh = generate::tet_box([4, 3, 3], DVec3::new(0.4, 0.3, 0.3));
    mesh.positions.iter_mut().for_each(|p| *p += DVec3::new(0.0, 0.5, 0.0));
    let params = DynamicsParams { damping: 0.02, ..DynamicsParams::default() };
    let (mut sim, rest) = simulation(&mesh, &[("tet_strain", 10.0)], params);
    // A floor of multiplier 1000.
    let floor = group("floor", 1000.0, &rest, Params::default().with("height", 0.0));
    sim.system_mut().add_group(floor).unwrap();
    let mut lowest_ever = f64::INFINITY;
    for _ in 0..240 {
        sim.step().unwrap();
        lowest_ever = lowest_ever.min(sim.positions().iter().map(|p| p.y).fold(f64::INFINITY, f64::min));
    }
    // At impact (2.6 units/s) a soft floor gives a little; at rest it holds to a small tolerance.
    assert!(lowest_ever > -0.03, "a vertex went {lowest_ever} below the floor on impact");
    let lowest = sim.positions().iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    // The floor is a soft term (PD): at rest the load of the box above sinks the bottom by
    // < 1 % of the box height.
    assert!(lowest > -3e-3 && lowest < 0.01, "it landed and rests on the floor (lowest {lowest})");
    assert!(sim.kinetic_energy() < 1e-8, "and came to rest ({})", sim.kinetic_energy());
}

#[test]
fn an_inverted_tetrahedron_recovers_positive_volume() {
    let rest = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
    let mesh =
        Mesh::with_tetrahedra(rest.clone(), vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], vec![[0, 1, 2, 3]])
            .unwrap();
    let volume = |p: &[DVec3]| tet_volume(p[0], p[1], p[2], p[3]);
    assert!(volume(&rest) > 0.0);
    let params = DynamicsParams { gravity: DVec3::ZERO, damping: 0.1, ..DynamicsParams::default() };
    let (mut sim, _) = simulation(&mesh, &[("tet_strain", 10.0)], params);
    // Push vertex 3 through the opposite face: the tet is inverted.
    let mut inverted = rest.clone();
    inverted[3] = DVec3::new(0.2, 0.2, -0.5);
    assert!(volume(&inverted) < 0.0);
    sim.set_state(&inverted, &[DVec3::ZERO; 4]).unwrap();
    for _ in 0..200 {
        sim.step().unwrap();
    }
    let v = volume(sim.positions());
    assert!(v > 0.9 * volume(&rest), "volume {v} (rest {})", volume(&rest));
}

#[test]
fn a_rigid_motion_of_the_input_moves_the_result_rigidly() {
    let mesh = generate::cloth_grid(8, 8, 1.0, 1.0);
    let params = DynamicsParams { damping: 0.01, ..DynamicsParams::default() };
    let rotation = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.9);
    let shift = DVec3::new(0.3, -1.0, 2.0);
    let moved =
        Mesh::new(mesh.positions.iter().map(|&p| rotation * p + shift).collect(), mesh.triangles.clone()).unwrap();
    let kinds = [("triangle_strain", 10.0), ("bending", 10.0)];
    let (mut a, _) = simulation(&mesh, &kinds, params);
    let (mut b, _) = simulation(&moved, &kinds, DynamicsParams { gravity: rotation * params.gravity, ..params });
    let v0 = swirl(&mesh.positions);
    a.set_state(&mesh.positions, &v0).unwrap();
    b.set_state(&moved.positions, &v0.iter().map(|&v| rotation * v).collect::<Vec<_>>()).unwrap();
    for _ in 0..60 {
        a.step().unwrap();
        b.step().unwrap();
    }
    for (p, q) in a.positions().iter().zip(b.positions()) {
        assert!((rotation * *p + shift - *q).length() < 1e-8, "{p} -> {q}");
    }
}

#[test]
fn smaller_time_steps_converge_to_one_trajectory() {
    // A cloth pinned at two corners swinging for 0.5 s; each halving of h must shrink the gap
    // to the next finer trajectory.
    let mesh = generate::cloth_grid(7, 7, 1.0, 1.0);
    let run = |h: f64| {
        let params = DynamicsParams { time_step: h, ..DynamicsParams::default() };
        let solver = SolverParams { iterations: 200, tolerance: 1e-13, ..SolverParams::default() };
        let (mut sim, _) = simulation_solved(&mesh, &[("edge_spring", 10.0)], params, solver);
        let pins = Position::new(vec![0, 6], vec![mesh.positions[0], mesh.positions[6]]).unwrap();
        sim.system_mut().add_group(ConstraintGroup::new("pins", 100.0, vec![Box::new(pins)])).unwrap();
        let steps = (0.5 / h).round() as usize;
        for _ in 0..steps {
            sim.step().unwrap();
        }
        sim.positions().to_vec()
    };
    let trajectories: Vec<Vec<DVec3>> = [1.0 / 60.0, 1.0 / 120.0, 1.0 / 240.0, 1.0 / 480.0].map(run).to_vec();
    let gap = |a: &[DVec3], b: &[DVec3]| a.iter().zip(b).map(|(p, q)| (*p - *q).length()).fold(0.0, f64::max);
    let gaps: Vec<f64> = trajectories.windows(2).map(|w| gap(&w[0], &w[1])).collect();
    assert!(gaps[0] > 1e-4, "the time step matters ({gaps:?})");
    assert!(gaps.windows(2).all(|g| g[1] < 0.75 * g[0]), "gaps shrink with h: {gaps:?}");
}

#[test]
fn a_grab_pulls_vertices_without_refactoring_and_release_lets_go() {
    let mesh = generate::cloth_grid(6, 6, 1.0, 1.0);
    let params = DynamicsParams { gravity: DVec3::ZERO, damping: 0.1, ..DynamicsParams::default() };
    let (mut sim, _) = simulation(&mesh, &[("edge_spring", 10.0)], params);
    sim.step().unwrap();
    let target = mesh.positions[35] + DVec3::new(0.0, 0.5, 0.0);
    sim.grab(vec![35], vec![target], 0.5).unwrap();
    let mut setup = 0.0;
    for _ in 0..200 {
        setup += sim.step().unwrap().setup_seconds;
    }
    assert!(setup < 1e-3, "grabbing does not refactor ({setup} s of setup)");
    assert!((sim.positions()[35] - target).length() < 0.05, "the grabbed vertex reached its target");
    assert!(sim.grab(vec![99], vec![target], 0.5).is_err(), "out of range");
    assert!(sim.grab(vec![35], vec![target], 1.5).is_err(), "strength above 1");
    sim.release();
    assert!(sim.grabbed().is_none());
}

#[test]
fn bad_settings_are_refused() {
    let mesh = generate::cloth_grid(3, 3, 1.0, 1.0);
    let rest = RestGeometry::new(mesh.positions.clone(), mesh.triangles.clone(), vec![]);
    let m = masses(&mesh, &rest);
    for bad in [
        DynamicsParams { time_step: 0.0, ..DynamicsParams::default() },
        DynamicsParams { stiffness: -1.0, ..DynamicsParams::default() },
        DynamicsParams { damping: 1.0, ..DynamicsParams::default() },
        DynamicsParams { gravity: DVec3::new(f64::NAN, 0.0, 0.0), ..DynamicsParams::default() },
    ] {
        let system = System::new(mesh.num_vertices(), SolverParams::default());
        assert!(Simulation::new(system, m.clone(), mesh.positions.clone(), bad).is_err(), "{bad:?}");
    }
    // Iterations per step are the system's: none is as bad as a bad time step.
    for bad in [
        SolverParams { iterations: 0, ..SolverParams::default() },
        SolverParams { tolerance: f64::NAN, ..SolverParams::default() },
    ] {
        let system = System::new(mesh.num_vertices(), bad);
        assert!(
            Simulation::new(system, m.clone(), mesh.positions.clone(), DynamicsParams::default()).is_err(),
            "{bad:?}"
        );
    }
    let system = System::new(mesh.num_vertices(), SolverParams::default());
    let mut negative = m.clone();
    negative[4] = -1.0;
    let err = Simulation::new(system, negative, mesh.positions.clone(), DynamicsParams::default()).unwrap_err();
    assert!(err.to_string().contains("vertex 4"), "{err}");
}

/// A plain step without a tolerance skips E (the peers' work, no more) and lands on the same
/// positions, bit for bit, as the iterations that evaluate it; `Simulation::energy` then gives
/// the E those would have reported.
#[test]
fn a_plain_step_skips_the_energy_and_moves_the_same() {
    let mesh = generate::cloth_grid(12, 10, 1.0, 0.8);
    let kinds = [("triangle_strain", 10.0), ("bending", 10.0)];
    let plain = SolverParams { acceleration: Acceleration::None, ..SolverParams::default() };
    // A tolerance no iteration meets: the same iterations, with E after each.
    let measured = SolverParams { tolerance: 1e-300, ..plain };
    let (mut fast, _) = simulation_solved(&mesh, &kinds, DynamicsParams::default(), plain);
    let (mut full, _) = simulation_solved(&mesh, &kinds, DynamicsParams::default(), measured);
    for sim in [&mut fast, &mut full] {
        sim.set_state(&mesh.positions, &swirl(&mesh.positions)).unwrap();
    }
    for _ in 0..15 {
        let a = fast.step().unwrap();
        let b = full.step().unwrap();
        assert_eq!(a.energy, None, "plain iterations do not evaluate E");
        assert_eq!(a.iterations, 10);
        assert_eq!(b.iterations, 10);
        assert_eq!(fast.positions(), full.positions(), "the same iterations");
        let e = fast.energy().unwrap();
        let reported = b.energy.unwrap();
        assert!((e - reported).abs() <= 1e-12 * reported, "E {e} vs {reported}");
    }
    // Anderson acceleration needs E for its safeguard: reported.
    let (mut accelerated, _) = simulation_with(&mesh, &kinds, DynamicsParams::default(), Acceleration::Anderson);
    assert!(accelerated.step().unwrap().energy.is_some());
}

/// Hard pins in dynamic mode: the pinned corners stay exactly where they are while the cloth
/// falls around them (they leave the system; the rest keeps its inertia).
#[test]
fn hard_pins_hold_a_falling_cloth_exactly() {
    let mesh = generate::cloth_grid(10, 10, 1.0, 1.0);
    for acceleration in [Acceleration::None, Acceleration::Anderson, Acceleration::Lbfgs] {
        let (mut sim, _) =
            simulation_with(&mesh, &[("triangle_strain", 10.0)], DynamicsParams::default(), acceleration);
        let corners = [0u32, 9];
        let pins =
            Position::new(corners.to_vec(), corners.iter().map(|&v| mesh.positions[v as usize]).collect()).unwrap();
        sim.system_mut().add_group(ConstraintGroup::new("pins", 1.0, vec![Box::new(pins)]).with_hard(true)).unwrap();
        let mut lowest = f64::INFINITY;
        for _ in 0..60 {
            sim.step().unwrap();
            lowest = lowest.min(sim.positions()[95].y);
        }
        for &c in &corners {
            assert_eq!(sim.positions()[c as usize], mesh.positions[c as usize], "{acceleration:?}");
            assert_eq!(sim.velocities()[c as usize], DVec3::ZERO);
        }
        assert!(lowest < mesh.positions[95].y - 0.5, "the free edge swung down (lowest y {lowest})");
    }
}

/// Every registered constraint type, with its default options, under every acceleration: in
/// static mode (with the box's ends held and one end moved) the energy never increases, and in
/// dynamic mode a few time steps stay finite with momentum-free motion bounded.
#[test]
fn every_constraint_type_solves_under_every_acceleration() {
    let mesh = generate::tet_box([4, 2, 2], DVec3::new(2.0, 1.0, 1.0));
    let rest = RestGeometry::new(mesh.positions.clone(), mesh.triangles.clone(), mesh.tetrahedra.clone());
    let (low, high): (Vec<u32>, Vec<u32>) = {
        let x = |v: &u32| mesh.positions[*v as usize].x;
        let all: Vec<u32> = (0..mesh.num_vertices() as u32).collect();
        (all.iter().copied().filter(|v| x(v) < -0.99).collect(), all.iter().copied().filter(|v| x(v) > 0.99).collect())
    };
    let handles = |offset: DVec3| {
        let held = |vs: &[u32], d: DVec3| {
            Position::new(vs.to_vec(), vs.iter().map(|&v| mesh.positions[v as usize] + d).collect()).unwrap()
        };
        [
            ConstraintGroup::new("low", 100.0, vec![Box::new(held(&low, DVec3::ZERO))]),
            ConstraintGroup::new("high", 100.0, vec![Box::new(held(&high, offset))]),
        ]
    };
    for ty in shapeup_core::constraints::registry() {
        let kind = ty.name();
        // The box has no polygon faces: a face type runs over all its vertices at once where it
        // can (whole_selection), else it has nothing to act on here.
        // An attachment needs a second piece to follow; the box is one.
        if ty.element() == shapeup_core::constraints::Element::PieceVertex {
            continue;
        }
        let options = if !ty.element().is_face() {
            Params::default()
        } else if ty.options().iter().any(|o| o.key == "whole_selection") {
            Params::default().with("whole_selection", true)
        } else {
            continue;
        };
        for acceleration in [Acceleration::None, Acceleration::Anderson, Acceleration::Lbfgs] {
            let params = SolverParams { acceleration, ..SolverParams::default() };
            let mut system = System::new(mesh.num_vertices(), params);
            system.add_group(group(kind, 10.0, &rest, options.clone())).unwrap();
            for h in handles(DVec3::new(0.4, 0.3, -0.2)) {
                system.add_group(h).unwrap();
            }
            let mut q = mesh.positions.clone();
            let loads_only = group(kind, 10.0, &rest, options.clone()).constraints.iter().all(|c| c.num_rows() == 0);
            if loads_only {
                // A load that nothing but the two end handles holds: its vertices are an
                // unanchored piece in static mode, refused rather than left in place.
                let e = system.solve(&mut q, 30, 0.0).unwrap_err();
                assert!(matches!(e, shapeup_core::solver::SolveError::Unanchored { .. }), "{kind}: {e}");
            } else {
                let report = system.solve(&mut q, 30, 0.0).unwrap();
                check_energies(kind, acceleration, &report);
            }

            let mut system = System::new(mesh.num_vertices(), params);
            system.add_group(group(kind, 10.0, &rest, options.clone())).unwrap();
            let m = masses(&mesh, &rest);
            let mut sim = Simulation::new(system, m, mesh.positions.clone(), DynamicsParams::default()).unwrap();
            for _ in 0..5 {
                sim.step().unwrap();
            }
            assert!(sim.positions().iter().all(|p| p.is_finite() && p.length() < 10.0), "{kind} {acceleration:?}");
        }
    }
}

/// E never rose over a solve's iterations and fell overall.
fn check_energies(kind: &str, acceleration: Acceleration, report: &shapeup_core::solver::SolveReport) {
    for w in report.energies.windows(2) {
        assert!(w[1] <= w[0] + 1e-12 * w[0].abs() + 1e-15, "{kind} {acceleration:?}: E rose from {} to {}", w[0], w[1]);
    }
    let last = report.energies.last().copied().unwrap_or(report.initial_energy);
    assert!(last < report.initial_energy, "{kind} {acceleration:?}: E decreased");
}

/// A time step's tolerance is on the objective it minimizes (E plus the inertial term), not on
/// E alone: a pinned cloth draping under gravity stops each accelerated step well before the
/// cap, at the positions much longer steps reach. (On E alone, whose relative change hovers at
/// the objective's round-off, these steps ran 150–400 of their 500 iterations; the plain
/// iteration needs the whole cap at this tolerance either way.)
#[test]
fn a_step_tolerance_is_on_the_objective() {
    let mesh = generate::cloth_grid(21, 21, 1.0, 1.0);
    let kinds = [("triangle_strain", 10.0), ("bending", 10.0)];
    let corners = [0u32, 20];
    let pins = || {
        let p = Position::new(corners.to_vec(), corners.iter().map(|&v| mesh.positions[v as usize]).collect()).unwrap();
        ConstraintGroup::new("pins", 100.0, vec![Box::new(p)])
    };
    for acceleration in [Acceleration::Anderson, Acceleration::Lbfgs] {
        let run = |iterations: usize, tolerance: f64| {
            let solver = SolverParams { iterations, tolerance, acceleration, ..SolverParams::default() };
            let (mut sim, _) = simulation_solved(&mesh, &kinds, DynamicsParams::default(), solver);
            sim.system_mut().add_group(pins()).unwrap();
            let mut counts = Vec::new();
            for _ in 0..8 {
                counts.push(sim.step().unwrap().iterations);
            }
            (sim.positions().to_vec(), counts)
        };
        let (converged, counts) = run(500, 1e-8);
        let (reference, _) = run(3000, 1e-15);
        assert!(counts.iter().all(|&n| n < 250), "{acceleration:?}: iterations per step {counts:?}");
        let off = converged.iter().zip(&reference).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
        assert!(off < 1e-4, "{acceleration:?}: {off} from the long steps");
    }
}
