//! A solve that stops short says so: a static solve that ends at its iteration cap far from its
//! minimum is warned of once, with its residual; solves that converge, or stop at their
//! tolerance, are not.

use shapeup_core::scene::{LoadedScene, Scene, SceneFormat};
use shapeup_core::solver::STATIC_RESIDUAL_LIMIT;
use std::path::PathBuf;

fn load(text: &str) -> LoadedScene {
    Scene::parse(text, SceneFormat::Toml, &PathBuf::from("convergence.toml"), PathBuf::new()).unwrap().load().unwrap()
}

/// An 11 × 11 sheet of edge springs of weight `springs`, one corner held and the opposite one
/// pulled by handles of weight 1, `solver` the [solver] table's lines.
fn springs_against_handles(springs: f64, solver: &str) -> String {
    format!(
        "[mesh]\ngenerate = {{ kind = \"cloth\", vertices = [11, 11], size = [1.0, 1.0] }}\nnormalize = false\n\
         [solver]\n{solver}\n\
         [[constraints]]\ntype = \"edge_spring\"\nweight = {springs:e}\n\
         [[constraints]]\ntype = \"position\"\nvertices = [0]\n\
         [[constraints]]\ntype = \"position\"\nvertices = [120]\ntranslate = [0.5, 0.3, 0.0]\n"
    )
}

#[test]
fn a_static_solve_stopped_short_of_its_minimum_says_so_once() {
    // Springs 1e8 times stiffer than the handles: the local-global iteration turns the sheet
    // towards the handles very slowly.
    let mut stiff = load(&springs_against_handles(1e8, "iterations = 200"));
    let (q, report) = stiff.solve_static(None).unwrap();
    let residual = report.residual.unwrap();
    let stiff_residual = residual;
    assert!(report.unconverged && residual > STATIC_RESIDUAL_LIMIT, "{residual}");
    assert_eq!(stiff.warnings.count("unconverged"), 1, "{:?}", stiff.warnings.to_json());
    let line = stiff.warnings.iter().find(|w| w.kind == "unconverged").unwrap().to_string();
    assert!(
        line.contains("convergence.toml: 1 static solve stopped at its 200-iteration cap")
            && line.contains("raise `iterations`"),
        "{line}"
    );
    // It is short indeed: far more iterations take it well away from there.
    let mut long = load(&springs_against_handles(1e8, "iterations = 20000\ntolerance = 1e-14"));
    let (converged, _) = long.solve_static(None).unwrap();
    let apart = q.iter().zip(&converged).map(|(a, b)| a.distance(*b)).fold(0.0, f64::max);
    assert!(apart > 0.05, "the capped solve is {apart} from the long one");

    // Springs as soft as the handles converge within the same cap: nothing said.
    let mut soft = load(&springs_against_handles(1.0, "iterations = 200"));
    let (_, report) = soft.solve_static(None).unwrap();
    let residual = report.residual.unwrap();
    assert!(!report.unconverged && residual < STATIC_RESIDUAL_LIMIT, "{residual}");
    assert_eq!(soft.warnings.count("unconverged"), 0);

    // Springs 1e12 times stiffer than handles that shift the sheet by 1e-3: the solve ends at
    // the exact answer (the sheet shifted by half that), where the gradient left is the
    // springs' round-off, which more iterations would not lower: nothing said.
    let shifted = springs_against_handles(1e12, "iterations = 50").replace("[0.5, 0.3, 0.0]", "[1e-3, 0.0, 1e-3]");
    let mut exact = load(&shifted);
    let (q, report) = exact.solve_static(None).unwrap();
    let rest = exact.rest_positions().to_vec();
    let off =
        q.iter().zip(&rest).map(|(p, r)| (*p - *r - glam::DVec3::new(5e-4, 0.0, 5e-4)).length()).fold(0.0, f64::max);
    assert!(off < 1e-12, "the sheet shifts rigidly by half the handle's move ({off})");
    assert!(!report.unconverged && exact.warnings.count("unconverged") == 0, "{:?}", report.residual);

    // The stiff sheet 1e5 from the origin (not normalized): its coordinates keep eleven digits,
    // its gradient is still real, and it is as short as at the origin.
    let dir = tempfile::tempdir().unwrap();
    let mut far = shapeup_core::generate::cloth_grid(11, 11, 1.0, 1.0);
    let offset = glam::DVec3::new(1e5, -1e5, 1e5);
    for p in &mut far.positions {
        *p += offset;
    }
    let path = dir.path().join("far.obj");
    shapeup_core::io::write_mesh(&path, &far, &shapeup_core::io::Attributes::None).unwrap();
    let text = springs_against_handles(1e8, "iterations = 200").replace(
        "generate = { kind = \"cloth\", vertices = [11, 11], size = [1.0, 1.0] }",
        &format!("path = {:?}", path.display().to_string()),
    );
    let mut far = load(&text);
    let (_, report) = far.solve_static(None).unwrap();
    assert!(report.unconverged, "{:?} at 1e5 from the origin, {stiff_residual} at it", report.residual);

    // A solve that meets its tolerance before the cap has no residual to report.
    let mut early = load(&springs_against_handles(1.0, "iterations = 5000\ntolerance = 1e-6"));
    let (_, report) = early.solve_static(None).unwrap();
    assert!(report.energies.len() < 5000 && report.residual.is_none() && !report.unconverged);
}

/// A 6 × 6 cloth of springs at `springs`, its corners 0 and 5 pinned and corner 35 pulled by
/// handles at `handles`, and (`anchor`) vertex 0 also held by a handle of weight 1.
fn lopsided(springs: f64, handles: f64, anchor: bool) -> String {
    let anchor = if anchor { "[[constraints]]\ntype = \"position\"\nname = \"anchor\"\nvertices = [0]\n" } else { "" };
    format!(
        "[mesh]\ngenerate = {{ kind = \"cloth\", vertices = [6, 6], size = [1.0, 1.0] }}\n\
         [[constraints]]\ntype = \"edge_spring\"\nweight = {springs:e}\n\
         [[constraints]]\ntype = \"position\"\nname = \"pin\"\nvertices = [0, 5]\nweight = {handles:e}\n\
         [[constraints]]\ntype = \"position\"\nname = \"pull\"\nvertices = [35]\ntranslate = [0.0, 0.0, 0.5]\nweight = {handles:e}\n{anchor}"
    )
}

/// Weights so far apart that the factorization cannot see the small ones are said, naming the
/// groups: as the error when they were the only anchor (not "add a position group", which the
/// scene has), as a warning with a count when the solve runs without them; weights 10⁸ apart
/// are no such case.
#[test]
fn groups_lost_to_round_off_are_named() {
    let scene =
        Scene::parse(&lopsided(1e8, 1e-8, false), SceneFormat::Toml, &PathBuf::from("l.toml"), PathBuf::new()).unwrap();
    let error = scene.load().and_then(|mut l| l.solve_static(Some(5)).map(|_| ())).unwrap_err().to_string();
    assert!(error.contains("2 group(s) lost to round-off"), "{error}");
    assert!(error.contains("\"pin\" (weight 1e-8) against \"edge_spring\" (weight 1e8)"), "{error}");
    assert!(!error.contains("add a position group"), "{error}");

    let mut loaded = load(&lopsided(1e8, 1e-8, true));
    let (_, report) = loaded.solve_static(Some(5)).unwrap();
    let names: Vec<&str> = report.lost_groups.iter().map(|g| g.name.as_str()).collect();
    assert_eq!(names, ["pin", "pull"]);
    assert!(report.lost_groups.iter().all(|g| g.share <= shapeup_core::solver::ROUND_OFF_SHARE));
    let warning = loaded.warnings.iter().find(|w| w.kind == "groups_lost_to_round_off").unwrap();
    assert_eq!(
        (warning.count, warning.first.as_str()),
        (2, "\"pin\" (weight 1e-8) against \"edge_spring\" (weight 1e8)")
    );

    // Time steps: the same groups, said once for the run.
    let dynamic = lopsided(1e8, 1e-8, true) + "[solver]\nmode = \"dynamic\"\n";
    let (_, warnings, _) = simulate(&dynamic, 3);
    let warning = warnings.iter().find(|w| w.kind == "groups_lost_to_round_off").unwrap();
    assert_eq!(
        (warning.count, warning.first.as_str()),
        (2, "\"pin\" (weight 1e-8) against \"edge_spring\" (weight 1e8)")
    );
    let (_, warnings, _) = simulate(&(lopsided(10.0, 1.0, true) + "[solver]\nmode = \"dynamic\"\n"), 3);
    assert_eq!(warnings.count("groups_lost_to_round_off"), 0);
    // The inertia m / (k h²) lost below the constraints (nothing would fall), and groups lost
    // below the inertia (a tiny time step): named as such, not as a group against itself.
    let (_, warnings, frozen) = simulate(&pinned_cloth(1e17, "iterations = 10"), 3);
    let warning = warnings.iter().find(|w| w.kind == "groups_lost_to_round_off").unwrap();
    assert!(
        warning.first.starts_with("the inertia m / (stiffness · time_step²) (of every vertex, the largest "),
        "{}",
        warning.first
    );
    assert!(warning.message.contains("change `stiffness` or `time_step`"), "{}", warning.message);
    assert!(frozen.iter().all(|p| p.y.abs() < 1e-9), "nothing falls");
    let (_, warnings, _) = simulate(&pinned_cloth(100.0, "iterations = 10\ntime_step = 1e-40"), 2);
    let warning = warnings.iter().find(|w| w.kind == "groups_lost_to_round_off").unwrap();
    assert!(warning.first.contains("against the inertia m / (stiffness · time_step²)"), "{}", warning.first);

    for (springs, handles) in [(1e4, 1e-4), (10.0, 1.0), (1.0, 1e3)] {
        let mut loaded = load(&lopsided(springs, handles, false));
        let (_, report) = loaded.solve_static(Some(5)).unwrap();
        assert!(report.lost_groups.is_empty(), "{springs} vs {handles}: {:?}", report.lost_groups);
        assert!(loaded.warnings.iter().all(|w| w.kind != "groups_lost_to_round_off"));
    }
}

/// A 9 × 9 cloth 1 m across (triangle strain and bending of weight 10) pinned at two corners
/// of one edge, under gravity, of stiffness `stiffness`; `solver` adds lines to [solver].
fn pinned_cloth(stiffness: f64, solver: &str) -> String {
    format!(
        "[mesh]\ngenerate = {{ kind = \"cloth\", vertices = [9, 9], size = [1.0, 1.0] }}\n\
         [solver]\nmode = \"dynamic\"\nstiffness = {stiffness:e}\ndamping = 0.02\n{solver}\n\
         [[constraints]]\ntype = \"triangle_strain\"\nweight = 10.0\n\
         [[constraints]]\ntype = \"bending\"\nweight = 10.0\n\
         [[constraints]]\ntype = \"position\"\nvertices = [0, 8]\nweight = 100.0\n"
    )
}

/// Runs `steps` time steps of `text`; the totals and the warnings the run says.
fn simulate(
    text: &str,
    steps: usize,
) -> (shapeup_core::scene::StepTotals, shapeup_core::warnings::Warnings, Vec<glam::DVec3>) {
    let mut loaded = load(text);
    let mut sim = loaded.start_scene_simulation().unwrap();
    let totals = sim.run(steps, 1, false, |_, _, _| Ok::<(), ()>(())).unwrap();
    let mut warnings = shapeup_core::warnings::Warnings::new();
    totals.add_warnings(&mut warnings);
    (totals, warnings, sim.simulation.positions().to_vec())
}

#[test]
fn a_time_step_stopped_short_of_its_converged_motion_says_so_once() {
    use shapeup_core::dynamics::{DYNAMIC_RESIDUAL_LIMIT, is_checked_step};
    // Stiffness 1e8: the global matrix models the cloth's swing 10⁶ times too stiff, so 10
    // iterations a step barely move it (the case: lowest point −0.015 after 30 steps
    // where a converged run swings to −0.98).
    let (totals, warnings, stuck) = simulate(&pinned_cloth(1e8, "iterations = 10"), 64);
    let checked: Vec<usize> = totals.residuals.iter().map(|r| r.0).collect();
    assert_eq!(checked, [1, 2, 4, 8, 16, 32, 64]);
    assert!(checked.iter().all(|&k| is_checked_step(k as u64)));
    assert!(totals.unconverged >= 5, "{:?}", totals.residuals);
    assert_eq!(warnings.count("unconverged"), totals.unconverged, "{:?}", warnings.to_json());
    let line = warnings.iter().find(|w| w.kind == "unconverged").unwrap().to_string();
    assert!(
        line.contains("of the 7 time steps checked")
            && line.contains("(10 iterations a step)")
            && line.contains("% of its motion (the limit is 50 %)")
            && line.contains("raise `iterations`"),
        "{line}"
    );
    // It is short indeed: the same steps converged swing the cloth down.
    let (converged_totals, converged_warnings, swung) =
        simulate(&pinned_cloth(1e8, "iterations = 3000\ntolerance = 1e-12"), 64);
    let lowest = |q: &[glam::DVec3]| q.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    assert!(lowest(&stuck) > -0.1 && lowest(&swung) < -0.5, "{} {}", lowest(&stuck), lowest(&swung));
    // Those long steps, checked, are within a tenth of their motion: nothing said.
    assert_eq!(converged_totals.residuals.len(), 7);
    assert!(converged_totals.residuals.iter().all(|r| r.1 < 0.1), "{:?}", converged_totals.residuals);
    assert_eq!(converged_warnings.count("unconverged"), 0);
    const { assert!(DYNAMIC_RESIDUAL_LIMIT > 0.1) };

    // Steps that met their tolerance are measured too: a soft cloth's are near their answer,
    // a stiff one's stall far from it (the energy barely changes per iteration), and say so.
    let (met, _, _) = simulate(&pinned_cloth(100.0, "iterations = 1000\ntolerance = 1e-6"), 8);
    assert_eq!(met.residuals.len(), 4);
    assert!(met.residuals.iter().all(|r| r.1 < 0.1), "{:?}", met.residuals);
    let (stalled, warnings, _) = simulate(&pinned_cloth(1e8, "iterations = 10\ntolerance = 1e-5"), 8);
    assert!(stalled.unconverged >= 2, "{:?}", stalled.residuals);
    let line = warnings.iter().find(|w| w.kind == "unconverged").unwrap().to_string();
    assert!(line.contains("tolerance 1e-5") && line.contains("lower `tolerance`"), "{line}");

    // A short time step: each step moves less than 1e-6 of the size, yet the cloth is frozen
    // (stiffness 7e11 at h = 2e-4 s): still said.
    let (short_steps, _, _) = simulate(&pinned_cloth(7e11, "iterations = 10\ntime_step = 2e-4"), 16);
    assert_eq!(short_steps.unconverged, 5, "{:?}", short_steps.residuals);

    // The default stiffness: each step within a few % of its motion, nothing said.
    let (soft, soft_warnings, _) = simulate(&pinned_cloth(100.0, "iterations = 10"), 64);
    assert_eq!(soft.residuals.len(), 7);
    assert!(soft.residuals.iter().all(|r| r.1 < 0.2), "{:?}", soft.residuals);
    assert_eq!(soft_warnings.count("unconverged"), 0);
}

/// The Newton–CG estimate of the step left (`System::remaining_step`) is what a long solve
/// from the same point still moves: after 3 iterations of a soft cloth's step, within 10 %.
#[test]
fn the_remaining_step_estimates_what_a_long_solve_still_moves() {
    let mut loaded = load(&pinned_cloth(100.0, "iterations = 3"));
    let mut sim = loaded.start_scene_simulation().unwrap();
    for _ in 0..5 {
        sim.step().unwrap();
    }
    // The state after step 5 and the step-6 system: take step 6 with 3 iterations by hand.
    let simulation = &mut sim.simulation;
    let before = simulation.positions().to_vec();
    simulation.step().unwrap();
    let short = simulation.positions().to_vec();
    let system = simulation.system_mut();
    let delta = system.remaining_step(&short, 16).unwrap();
    let mut long = short.clone();
    system.solve(&mut long, 5000, 1e-15).unwrap();
    let (mut err, mut off, mut moved) = (0.0, 0.0, 0.0);
    for ((d, l), (s, b)) in delta.iter().zip(&long).zip(short.iter().zip(&before)) {
        err += (*l - *s).length_squared();
        off += (*s + *d - *l).length_squared();
        moved += (*s - *b).length_squared();
    }
    assert!(err.sqrt() > 1e-3 * moved.sqrt(), "the 3-iteration step should still be short: {err:e} of {moved:e}");
    assert!(off.sqrt() < 0.1 * err.sqrt(), "estimate off by {:e} of {:e}", off.sqrt(), err.sqrt());
}
