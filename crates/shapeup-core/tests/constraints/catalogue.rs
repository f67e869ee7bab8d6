//! The shared suite every registered constraint type gets by being registered: on small meshes
//! (a wavy quad grid, its triangles, a box of tetrahedra) each type's projection lies on its
//! set and no sampled point of the set is closer; the energy never increases over iterations;
//! moving the input and targets rigidly moves the result the same way; its scene keys parse
//! and bad options are refused by name.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::{Rng, dist2, quad_grid, rest_of, turned_options, wavy};
use glam::{DQuat, DVec3};
use shapeup_core::constraints::{
    ConstraintType, Element, GroupDescription, OptionKind, OptionSpec, Params, Selection, build_group, registry,
};
use shapeup_core::geometry::{RestGeometry, WorkingFrame};
use shapeup_core::mesh::Mesh;
use shapeup_core::scene::{Scene, SceneFormat};
use shapeup_core::solver::{Acceleration, ConstraintGroup, SolverParams, System};
use shapeup_core::warnings::Warnings;
use std::path::{Path, PathBuf};

/// The mesh a type is tested on: tetrahedra for tetrahedron types, the quad grid with a flake
/// (a triangle of its own, vertices 25..28) above it for types that attach a piece to another,
/// else the quad grid (its triangulation gives triangles, edges and vertices).
fn mesh_for(ty: &dyn ConstraintType) -> Mesh {
    match ty.element() {
        Element::Tetrahedron => shapeup_core::generate::tet_box([2, 2, 2], DVec3::new(1.0, 0.8, 0.6)),
        Element::PieceVertex => {
            let grid = quad_grid(4);
            let mut positions = grid.positions.clone();
            positions.extend([wavy(0.1, 0.0), wavy(0.3, 0.1), wavy(0.15, 0.25)].map(|p| p + 0.05 * DVec3::Z));
            let mut polygons = grid.polygons.clone();
            polygons.push(&[25, 26, 27]);
            Mesh::from_polygons(positions, polygons).unwrap().0
        }
        _ => quad_grid(4),
    }
}

/// The vertices a type's group takes: the flake for types that attach a piece, else all.
const FLAKE: [usize; 3] = [25, 26, 27];
fn selection_for(ty: &dyn ConstraintType, rest: &RestGeometry) -> Selection {
    match ty.element() {
        Element::PieceVertex => Selection::from_indices(rest.num_vertices(), &FLAKE),
        _ => Selection::All,
    }
}

fn group(ty: &dyn ConstraintType, rest: &RestGeometry, options: Params) -> ConstraintGroup {
    let description = GroupDescription { options, ..GroupDescription::new(ty.name(), selection_for(ty, rest)) };
    build_group(&description, rest, &WorkingFrame::IDENTITY)
        .unwrap_or_else(|e| panic!("{}: default group on the test mesh: {e}", ty.name()))
}

#[test]
fn every_projection_lies_on_its_set_and_no_sampled_point_of_the_set_is_closer() {
    for ty in registry() {
        let mesh = mesh_for(*ty);
        let rest = rest_of(&mesh);
        let built = group(*ty, &rest, Params::default());
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for trial in 0..6 {
            let amplitude = [0.02, 0.1, 0.4][trial % 3];
            let q: Vec<DVec3> = rest.positions.iter().map(|&x| x + amplitude * rng.vec3()).collect();
            for c in built.constraints.iter().filter(|c| c.num_rows() > 0) {
                let cq = c.apply(&q);
                let mut p = vec![DVec3::ZERO; c.num_rows()];
                c.project(&q, &mut p);
                let size = 1.0 + p.iter().chain(&cq).map(|x| x.length()).fold(0.0, f64::max);
                let residual = c.set_residual(&p);
                assert!(residual <= 1e-8 * size, "{}: projection off its set by {residual:e}", ty.name());
                let d = dist2(&cq, &p);
                // Points of the set: projections of nearby configurations (each checked on the set).
                for k in 0..60 {
                    let eps = [1e-3, 1e-2, 5e-2, 0.2][k % 4];
                    let other: Vec<DVec3> = q.iter().map(|&x| x + eps * rng.vec3()).collect();
                    let mut sample = vec![DVec3::ZERO; c.num_rows()];
                    c.project(&other, &mut sample);
                    let r = c.set_residual(&sample);
                    assert!(r <= 1e-8 * size, "{}: a projection off its set by {r:e}", ty.name());
                    let ds = dist2(&cq, &sample);
                    assert!(
                        d <= ds + 1e-10 * size * size,
                        "{}: a point of the set is closer than the projection ({ds:e} < {d:e})",
                        ty.name()
                    );
                }
            }
        }
    }
}

/// A system of the type's group over the whole mesh, a soft closeness to rest (so that every
/// type is solvable alone) and a handle pulling a few vertices.
fn system_for(
    ty: &dyn ConstraintType,
    rest: &RestGeometry,
    options: Params,
    handle: &[(u32, DVec3)],
    acceleration: Acceleration,
) -> System {
    let params = SolverParams { acceleration, ..SolverParams::default() };
    let mut system = System::new(rest.num_vertices(), params);
    let frame = WorkingFrame::IDENTITY;
    system.add_group(group(ty, rest, options)).unwrap();
    if ty.name() != "position" {
        let closeness = GroupDescription::new("position", Selection::All).weight(1e-3);
        system.add_group(build_group(&closeness, rest, &frame).unwrap()).unwrap();
    }
    let held: Vec<usize> = handle.iter().map(|&(v, _)| v as usize).collect();
    let pull = GroupDescription {
        targets: Some(handle.to_vec()),
        ..GroupDescription::new("position", Selection::from_indices(rest.num_vertices(), &held))
    };
    system.add_group(build_group(&pull, rest, &frame).unwrap()).unwrap();
    system
}

/// Two corner vertices pulled up and sideways.
fn handle_of(rest: &RestGeometry) -> Vec<(u32, DVec3)> {
    let n = rest.num_vertices() as u32;
    vec![(0, rest.positions[0] + DVec3::new(0.1, 0.0, 0.2)), (n - 1, rest.positions[n as usize - 1])]
}

#[test]
fn the_energy_never_increases_over_iterations() {
    for ty in registry() {
        let rest = rest_of(&mesh_for(*ty));
        for acceleration in Acceleration::ALL {
            let mut system = system_for(*ty, &rest, Params::default(), &handle_of(&rest), acceleration);
            let mut q = rest.positions.clone();
            let report = system.solve(&mut q, 40, 0.0).unwrap();
            let mut previous = report.initial_energy;
            for (k, &e) in report.energies.iter().enumerate() {
                let slack = 1e-9 * previous.abs().max(1e-12);
                assert!(
                    e <= previous + slack,
                    "{} with {}: E rose at iteration {k} from {previous:e} to {e:e}",
                    ty.name(),
                    acceleration.name()
                );
                previous = e;
            }
            assert!(q.iter().all(|p| p.is_finite()), "{}: non-finite result", ty.name());
        }
    }
}

#[test]
fn every_type_time_steps_in_dynamic_mode() {
    use shapeup_core::dynamics::{DynamicsParams, Simulation};
    use shapeup_core::geometry::{lumped_masses_surface, lumped_masses_volume};
    for ty in registry() {
        let mesh = mesh_for(*ty);
        let rest = rest_of(&mesh);
        let masses = if mesh.tetrahedra.is_empty() {
            lumped_masses_surface(mesh.num_vertices(), &mesh.triangles, &rest.triangle_areas, 1.0)
        } else {
            lumped_masses_volume(&mesh.positions, &mesh.tetrahedra, 1.0)
        };
        for acceleration in Acceleration::ALL {
            let system = system_for(*ty, &rest, Params::default(), &handle_of(&rest), acceleration);
            let mut sim = Simulation::new(system, masses.clone(), rest.positions.clone(), DynamicsParams::default())
                .unwrap_or_else(|e| panic!("{}: {e}", ty.name()));
            for _ in 0..5 {
                sim.step().unwrap_or_else(|e| panic!("{} with {}: {e}", ty.name(), acceleration.name()));
            }
            assert!(
                sim.positions().iter().all(|p| p.is_finite() && p.length() < 10.0),
                "{} with {}: the body left",
                ty.name(),
                acceleration.name()
            );
        }
    }
}

#[test]
fn moving_the_input_and_targets_rigidly_moves_the_result_the_same_way() {
    let turn = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.9);
    let shift = DVec3::new(0.3, -1.2, 2.0);
    let motion = |p: DVec3| turn * p + shift;
    for ty in registry().iter().filter(|t| t.is_rigidly_invariant()) {
        let mesh = mesh_for(*ty);
        let rest = rest_of(&mesh);
        let handle = handle_of(&rest);
        let mut system = system_for(*ty, &rest, turned_options(*ty, DQuat::IDENTITY), &handle, Acceleration::None);
        let mut q = rest.positions.clone();
        system.solve(&mut q, 30, 0.0).unwrap();

        let moved_mesh = mesh.with_positions(mesh.positions.iter().map(|&p| motion(p)).collect());
        let moved_rest = rest_of(&moved_mesh);
        let moved_handle: Vec<(u32, DVec3)> = handle.iter().map(|&(v, p)| (v, motion(p))).collect();
        let mut moved = system_for(*ty, &moved_rest, turned_options(*ty, turn), &moved_handle, Acceleration::None);
        let mut q_moved = moved_rest.positions.clone();
        moved.solve(&mut q_moved, 30, 0.0).unwrap();
        let worst = q.iter().zip(&q_moved).map(|(&a, &b)| (motion(a) - b).length()).fold(0.0, f64::max);
        assert!(worst < 1e-8, "{}: the moved solve is off the moved result by {worst:e}", ty.name());
    }
}

/// A scene on the quad grid with one group of `ty` and `options` (TOML lines).
fn scene_with(ty: &dyn ConstraintType, options: &str) -> Result<(), String> {
    let selection = match ty.element() {
        Element::PieceVertex => format!("vertices = {FLAKE:?}\n"),
        _ => String::new(),
    };
    let text = format!(
        "[mesh]\npath = \"grid.obj\"\nnormalize = false\n[[constraints]]\ntype = \"{}\"\n{selection}{options}\n\
         [[constraints]]\ntype = \"position\"\nvertices = [0, 24]\nweight = 1\n",
        ty.name()
    );
    let scene =
        Scene::parse(&text, SceneFormat::Toml, Path::new("s.toml"), PathBuf::new()).map_err(|e| e.to_string())?;
    scene.build(mesh_for(ty), Warnings::new(), 0.0).map(|_| ()).map_err(|e| e.to_string())
}

/// A TOML value inside an option's range.
fn valid_value(option: &OptionSpec) -> String {
    match option.kind {
        OptionKind::Number { default: Some(d), .. } => format!("{d:?}"),
        OptionKind::Number { min, max, .. } => {
            let x = if min > -1e300 && max < 1e300 { 0.5 * (min + max) } else { min.max(-0.0).min(max) };
            format!("{x:?}")
        }
        OptionKind::Bool { default } => format!("{}", !default),
        OptionKind::Vector { default } => format!("[{:?}, {:?}, {:?}]", default[0], default[1], default[2]),
    }
}

#[test]
fn every_scene_key_parses_and_bad_options_are_refused_by_name() {
    for ty in registry() {
        // Every option, at a valid value.
        let all: String = ty.options().iter().map(|o| format!("{} = {}\n", o.key, valid_value(o))).collect();
        scene_with(*ty, &all).unwrap_or_else(|e| panic!("{}: valid options refused: {e}", ty.name()));
        let e = scene_with(*ty, "no_such_option = 1").unwrap_err();
        assert!(e.contains("no_such_option") && e.contains(ty.name()), "{}: {e}", ty.name());
        for option in ty.options() {
            let e = scene_with(*ty, &format!("{} = \"text\"", option.key)).unwrap_err();
            assert!(e.contains(option.key), "{}: a string for {} gives: {e}", ty.name(), option.key);
            if let OptionKind::Number { min, max, .. } = option.kind {
                for outside in [min - 1.0 - min.abs(), max + 1.0 + max.abs()].into_iter().filter(|x| x.abs() < 1e300) {
                    let e = scene_with(*ty, &format!("{} = {outside:?}", option.key)).unwrap_err();
                    assert!(e.contains(option.key), "{}: {} = {outside} gives: {e}", ty.name(), option.key);
                }
            }
        }
    }
}

#[test]
fn every_type_documents_its_options_and_elements() {
    for ty in registry() {
        assert!(!ty.summary().is_empty(), "{}", ty.name());
        for option in ty.options() {
            assert!(!option.doc.is_empty(), "{}: option {} has no doc", ty.name(), option.key);
        }
        assert!(ty.default_multiplier().is_finite() && ty.default_multiplier() >= 0.0);
        let _ = ty.element().plural();
    }
}

#[test]
fn the_readme_and_the_scene_contract_list_every_registered_type() {
    let table = shapeup_core::constraints::catalogue_markdown();
    for doc in ["README.md", "docs/scenes-and-cli.md"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(doc);
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.contains(&table),
            "{doc} does not hold the registry's table: paste the output of `shapeup types` into it\n{table}"
        );
    }
}
