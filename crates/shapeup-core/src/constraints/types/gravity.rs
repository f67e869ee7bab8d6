//! Gravity: the self-weight of the mesh as a constant load, in static mode (form finding: a
//! hanging net, a self-supporting shell found upside down).
//!
//! Term: a [`Force`] on each selected vertex v with a lumped measure m̃_v > 0:
//!
//!   f_v = ρ m̃_v a,   m̃_v = Σ_{t ∋ v} A_t / 3 (surface)  or  Σ_{T ∋ v} |V_T| / 4 (tetrahedra),
//!
//! with rest areas A_t and volumes V_T in the working frame, density ρ (option `density`,
//! ≥ 0, default 1) and acceleration a (option `acceleration`, input units per s², default
//! [0, −9.81, 0], converted with `frame.vector_to_working`). E gains −2 g f_v · (q_v − x⁰_v) and
//! the global step's right-hand side g f_v (math reference, "Forces"); no rows, ω = 1.
//!
//! Sources: ShapeOp's gravity force (Deuss et al. 2015, `GravityForce`: one constant vector for
//! every vertex); the lumped masses of Projective Dynamics (Bouaziz et al. 2014) as this framework's
//! dynamic mode computes them (`geometry::lumped_masses_surface` / `_volume`), in the ShapeUp
//! solver (Bouaziz et al. 2012).
//!
//! Choices, and why:
//! - The masses are the dynamic mode's lumped masses (without their 1e-9 floor, so that ρ = 0
//!   means no load and a vertex in no element gets none), so that a static form-finding scene
//!   and its simulated counterpart carry the same weights; a tetrahedral mesh is weighed by
//!   volume, a surface by area.
//! - The acceleration converts as a vector of input lengths per s² (× the working scale; time is
//!   not scaled), like the dynamic mode's gravity, so a scene means the same in millimetres or
//!   metres: 9.81 in a metre scene is 9810 in a millimetre one. The default assumes metres.
//! - m̃ is measured in the working frame (the mesh normalized to radius 0.5 unless the scene
//!   turns that off), so the total load ρ |a| Σ m̃ does not change with the input's units
//!   either; ρ is relative to the multipliers of the shape terms it balances.
//! - A vector option, so that rotating a scene turns gravity with it (the shared rigid-motion
//!   test); a world-fixed "down" would not be rigidly invariant.
//! - ShapeOp's gravity is one vector for every vertex (times one scalar mass for all of them),
//!   whatever its share of the surface; that is the `force` type here.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType};
use crate::constraints::error::ConstraintError;
use crate::constraints::options::{OptionKind, OptionSpec};
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::constraints::kit::load::Force;
use crate::geometry::{RestGeometry, tet_volume};
use crate::constraints::kit::build::non_empty;

/// Name in scene files.
const KIND: &str = "gravity";

/// `acceleration`: gravity, input units per s².
const ACCELERATION: OptionSpec = OptionSpec {
    key: "acceleration",
    doc: "gravitational acceleration [x, y, z], input units per s²; default [0, -9.81, 0] (metres)",
    kind: OptionKind::Vector { default: [0.0, -9.81, 0.0] },
};

/// `density`: mass per working-frame area (surface) or volume (tetrahedra).
const DENSITY: OptionSpec = OptionSpec {
    key: "density",
    doc: "density ρ: mass per unit of rest area (surface) or volume (tetrahedra), working frame; ≥ 0, default 1",
    kind: OptionKind::Number { default: Some(1.0), min: 0.0, max: f64::MAX },
};

/// The lumped measure m̃_v of every vertex: Σ |V_T|/4 over its tetrahedra if `rest` has any,
/// else Σ A_t/3 over its triangles (0 for a vertex in no element; no floor).
pub(crate) fn lumped_measures(rest: &RestGeometry) -> Vec<f64> {
    let mut m = vec![0.0; rest.num_vertices()];
    if rest.tetrahedra.is_empty() {
        for (t, &a) in rest.triangles.iter().zip(&rest.triangle_areas) {
            for &v in t {
                m[v as usize] += a / 3.0;
            }
        }
    } else {
        let x = &rest.positions;
        for t in &rest.tetrahedra {
            let volume = tet_volume(x[t[0] as usize], x[t[1] as usize], x[t[2] as usize], x[t[3] as usize]).abs();
            for &v in t {
                m[v as usize] += volume / 4.0;
            }
        }
    }
    m
}

/// Builds a [`Force`] f_v = ρ m̃_v a on every selected vertex with m̃_v > 0 (reported as kind
/// `gravity`). Options `acceleration`, `density`. Default multiplier 1.
#[derive(Debug, Clone, Copy)]
pub struct GravityType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "gravity: the self-weight of the selected vertices (lumped area or volume), static form finding",
    options: &[ACCELERATION, DENSITY],
    element: Element::Vertex,
    default_multiplier: 1.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for GravityType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let a = ctx.frame.vector_to_working(params.vector(KIND, &ACCELERATION)?);
        let density = params.number(KIND, &DENSITY)?.unwrap_or(1.0);
        let rest = ctx.rest;
        let built: Vec<Box<dyn Constraint>> = lumped_measures(rest)
            .into_iter()
            .enumerate()
            .filter(|&(v, m)| m > 0.0 && ctx.selection.contains(v as u32))
            .map(|(v, m)| {
                Box::new(Force::of_kind(KIND, v as u32, density * m * a, rest.positions[v])) as Box<dyn Constraint>
            })
            .collect();
        non_empty(built, KIND, "vertices of a triangle or tetrahedron")
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::{GroupDescription, Selection, build_constraints, build_group};
    use crate::geometry::{WorkingFrame, lumped_masses_surface, lumped_masses_volume};
    use crate::solver::{Acceleration, SolveError, SolverParams, System};
    use glam::DVec3;

    fn total_force(built: &[Box<dyn Constraint>]) -> DVec3 {
        built.iter().filter_map(|c| c.load()).flat_map(|l| l.forces.iter().copied()).sum()
    }

    #[test]
    fn the_weights_are_the_lumped_masses_times_the_acceleration() {
        let mesh = crate::generate::cloth_grid(5, 4, 1.0, 0.6);
        let rest = RestGeometry::new(mesh.positions.clone(), mesh.triangles.clone(), vec![]);
        let frame = WorkingFrame { center: DVec3::ZERO, scale: 0.5, physical: false };
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &frame };
        let params = Params::default().with("density", 2.0).with("acceleration", vec![0.0, -10.0, 4.0]);
        let built = build_constraints(KIND, &ctx, params).unwrap();
        assert_eq!(built.len(), rest.num_vertices());
        let masses = lumped_masses_surface(rest.num_vertices(), &rest.triangles, &rest.triangle_areas, 2.0);
        let a = DVec3::new(0.0, -5.0, 2.0); // × the working scale
        for c in &built {
            assert_eq!(c.kind(), KIND);
            let load = c.load().unwrap();
            let v = load.vertices[0] as usize;
            assert!((load.forces[0] - masses[v] * a).length() < 1e-14);
        }
        // The whole weight: ρ × area × a.
        assert!((total_force(&built) - 2.0 * 0.6 * a).length() < 1e-12);
        // ρ = 0: no load at all (the forces vanish, no floor).
        let none = build_constraints(KIND, &ctx, Params::default().with("density", 0.0)).unwrap();
        assert_eq!(total_force(&none), DVec3::ZERO);
    }

    #[test]
    fn a_tetrahedral_mesh_is_weighed_by_volume() {
        let mesh = crate::generate::tet_box([2, 1, 1], DVec3::new(1.0, 0.5, 0.4));
        let rest = RestGeometry::of_mesh(mesh.positions.clone(), &mesh);
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        let built = build_constraints(KIND, &ctx, Params::default()).unwrap();
        let masses = lumped_masses_volume(&rest.positions, &rest.tetrahedra, 1.0);
        for c in &built {
            let load = c.load().unwrap();
            let want = masses[load.vertices[0] as usize] * DVec3::new(0.0, -9.81, 0.0);
            assert!((load.forces[0] - want).length() < 1e-13);
        }
        assert!((total_force(&built).y + 9.81 * 0.2).abs() < 1e-12, "ρ × volume × g");
    }

    #[test]
    fn bad_options_are_refused_by_key_and_isolated_vertices_carry_nothing() {
        let mut positions = crate::generate::cloth_grid(3, 3, 1.0, 1.0).positions;
        let triangles = crate::generate::cloth_grid(3, 3, 1.0, 1.0).triangles;
        positions.push(DVec3::splat(2.0)); // vertex 9: in no triangle
        let rest = RestGeometry::new(positions, triangles, vec![]);
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        assert_eq!(build_constraints(KIND, &ctx, Params::default()).unwrap().len(), 9);
        let err = build_constraints(KIND, &ctx, Params::default().with("density", -1.0)).unwrap_err();
        assert!(err.to_string().contains("density"), "{err}");
        let err = build_constraints(KIND, &ctx, Params::default().with("acceleration", 9.81)).unwrap_err();
        assert!(err.to_string().contains("acceleration"), "{err}");
        let isolated = Selection::from_indices(10, &[9]);
        let ctx = BuildContext { rest: &rest, selection: &isolated, frame: &WorkingFrame::IDENTITY };
        let err = build_constraints(KIND, &ctx, Params::default()).unwrap_err();
        assert!(matches!(err, ConstraintError::NothingSelected { .. }), "{err}");
    }

    /// A 7×7 net of edge springs in the plane y = 0, held at its four corners (hard), under
    /// `load` (a gravity or force group): solved to convergence with `acceleration`.
    fn hanging_net(
        load: GroupDescription,
        acceleration: Acceleration,
        iterations: usize,
    ) -> (Vec<DVec3>, System, Vec<f64>) {
        let mesh = crate::generate::cloth_grid(7, 7, 1.0, 1.0);
        let rest = RestGeometry::new(mesh.positions.clone(), mesh.triangles.clone(), vec![]);
        let frame = WorkingFrame::IDENTITY;
        let n = rest.num_vertices();
        let params = SolverParams { acceleration, ..SolverParams::default() };
        let mut system = System::new(n, params);
        let springs = GroupDescription::new("edge_spring", Selection::All).weight(10.0);
        system.add_group(build_group(&springs, &rest, &frame).unwrap()).unwrap();
        system.add_group(build_group(&load, &rest, &frame).unwrap()).unwrap();
        let corners = [0, 6, 42, 48];
        let pins = GroupDescription::new("position", Selection::from_indices(n, &corners)).with("hard", true);
        system.add_group(build_group(&pins, &rest, &frame).unwrap()).unwrap();
        let mut q = rest.positions.clone();
        let report = system.solve(&mut q, iterations, 0.0).unwrap();
        let mut energies = vec![report.initial_energy];
        energies.extend(report.energies);
        (q, system, energies)
    }

    /// max_v ‖∇_v E‖ over the free vertices, by central differences of E (the loads' potential
    /// included): twice the solver's half-gradient, 0 at an equilibrium.
    fn gradient_at(system: &mut System, q: &[DVec3], pinned: &[usize]) -> f64 {
        let h = 1e-6;
        let mut worst: f64 = 0.0;
        for v in (0..q.len()).filter(|v| !pinned.contains(v)) {
            let mut g = DVec3::ZERO;
            for k in 0..3 {
                let (mut plus, mut minus) = (q.to_vec(), q.to_vec());
                plus[v][k] += h;
                minus[v][k] -= h;
                g[k] = (system.energy(&plus).unwrap().total - system.energy(&minus).unwrap().total) / (2.0 * h);
            }
            worst = worst.max(g.length());
        }
        worst
    }

    #[test]
    fn a_pinned_net_under_its_weight_sags_to_an_equilibrium_with_e_decreasing() {
        let gravity = GroupDescription::new(KIND, Selection::All);
        // Plain iterations: E never rises.
        let (_, _, energies) = hanging_net(gravity.clone(), Acceleration::None, 200);
        for pair in energies.windows(2) {
            assert!(pair[1] <= pair[0] + 1e-12 * pair[0].abs(), "E rose from {} to {}", pair[0], pair[1]);
        }
        assert!(energies[energies.len() - 1] < 0.0, "the load's potential makes E negative");
        // Converged (L-BFGS): the gradient of E vanishes; the net hangs below its corners, the
        // middle lowest, and symmetric about the centre.
        let (q, mut system, energies) = hanging_net(gravity, Acceleration::Lbfgs, 2000);
        for pair in energies.windows(2) {
            assert!(pair[1] <= pair[0] + 1e-12 * pair[0].abs(), "E rose from {} to {}", pair[0], pair[1]);
        }
        let pinned = [0, 6, 42, 48];
        let weight = 2.0 * 9.81 / 36.0; // 2 g ‖f‖ of an interior vertex (area 1/36)
        let gradient = gradient_at(&mut system, &q, &pinned);
        assert!(gradient < 1e-5 * weight, "not at equilibrium: ‖∇E‖ = {gradient:e}");
        for (v, p) in q.iter().enumerate() {
            if pinned.contains(&v) {
                assert!(p.y.abs() < 1e-12);
            } else {
                assert!(p.y < -1e-3, "vertex {v} does not sag: {p}");
            }
        }
        let centre = q[24].y;
        assert!(q.iter().all(|p| p.y >= centre - 1e-9), "the centre is the lowest point");
        assert!((q[3].y - q[27].y).abs() < 1e-6 && (q[21].y - q[45].y).abs() < 1e-6, "symmetric sag");
    }

    #[test]
    fn a_force_group_sags_the_net_the_way_it_points_and_doubling_it_sags_it_more() {
        let sideways = GroupDescription::new("force", Selection::All).with("force", vec![0.0, 0.0, 0.05]);
        let (q, mut system, _) = hanging_net(sideways, Acceleration::Lbfgs, 2000);
        assert!(gradient_at(&mut system, &q, &[0, 6, 42, 48]) < 1e-5 * 0.1);
        assert!(q[24].z > 1e-3 && q[24].y.abs() < 1e-9, "pushed along +z only: {}", q[24]);
        let harder = GroupDescription::new("force", Selection::All).with("force", vec![0.0, 0.0, 0.05]).weight(2.0);
        let (q2, _, _) = hanging_net(harder, Acceleration::Lbfgs, 2000);
        assert!(q2[24].z > q[24].z + 1e-4, "the multiplier scales the load");
    }

    /// Needs the solver to count loaded vertices as unknowns (`solver/assemble.rs`,
    /// `Assembly::new` / `number_solved_vertices`: chain every `Constraint::load` vertex of a
    /// non-hard group into the touched set); without that, a vertex that only a load touches is
    /// not solved, so a load alone moves nothing and the solve returns E = 0 without an error.
    /// With it, such a vertex is a piece without an anchor: `SolveError::Unanchored`.
    #[test]
    fn a_load_alone_on_an_unpinned_mesh_is_refused_not_nan() {
        let mesh = crate::generate::cloth_grid(4, 4, 1.0, 1.0);
        let rest = RestGeometry::new(mesh.positions.clone(), mesh.triangles.clone(), vec![]);
        let frame = WorkingFrame::IDENTITY;
        for kind in ["force", KIND] {
            let mut system = System::new(rest.num_vertices(), SolverParams::default());
            system
                .add_group(build_group(&GroupDescription::new(kind, Selection::All), &rest, &frame).unwrap())
                .unwrap();
            let mut q = rest.positions.clone();
            let result = system.solve(&mut q, 10, 0.0);
            assert!(q.iter().all(|p| p.is_finite()), "{kind}: non-finite positions");
            let err = result.expect_err("a load alone has nothing to balance it");
            assert!(matches!(err, SolveError::Unanchored { .. }), "{kind}: {err}");
            assert!(err.to_string().starts_with("singular system"), "{kind}: {err}");
        }
    }
}
