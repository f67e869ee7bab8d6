//! Each model against its definition (stress = energy gradient, stress-free rest, rotation
//! invariance, linear elasticity at small strain), and the solver with a material against
//! theory (uniaxial stretch of a block) and against an independent Newton solver.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use super::*;
use crate::constraints::kit::load::Force;
use crate::constraints::{ConstraintGroup, Position};
use crate::generate::tet_box;
use crate::linalg::test_rng::Rng;
use crate::solver::{SolverParams, System};
use glam::DQuat;

const RUBBER: (f64, f64) = (1.0e6, 0.3);

fn lame() -> Lame {
    Lame::from_youngs(RUBBER.0, RUBBER.1).unwrap()
}

fn random_f(rng: &mut Rng, spread: f64) -> DMat3 {
    DMat3::IDENTITY + DMat3::from_cols(rng.vec3(), rng.vec3(), rng.vec3()) * spread
}

fn rotation(rng: &mut Rng) -> DMat3 {
    DMat3::from_quat(DQuat::from_xyzw(rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()).normalize())
}

fn entry(m: DMat3, i: usize, j: usize) -> f64 {
    m.col(j)[i]
}

fn with_entry(m: DMat3, i: usize, j: usize, delta: f64) -> DMat3 {
    let mut cols = [m.x_axis, m.y_axis, m.z_axis];
    cols[j][i] += delta;
    DMat3::from_cols(cols[0], cols[1], cols[2])
}

#[test]
fn lame_parameters_follow_youngs_modulus_and_poisson_ratio() {
    let l = lame();
    assert!((l.mu - 1.0e6 / 2.6).abs() < 1e-6);
    assert!((l.lambda - 1.0e6 * 0.3 / (1.3 * 0.4)).abs() < 1e-6);
    assert!((l.p_wave_modulus() - (l.lambda + 2.0 * l.mu)).abs() < 1e-9);
    for (e, nu) in [(0.0, 0.3), (-1.0, 0.3), (f64::NAN, 0.3), (1.0, 0.5), (1.0, -1.0), (1.0, f64::NAN)] {
        assert!(Lame::from_youngs(e, nu).is_err(), "E = {e}, ν = {nu} accepted");
    }
    assert!(Material::new("rubber", 1.0, 0.3, 1.0).unwrap_err().to_string().contains("neo_hookean"));
    assert!(matches!(Material::new("stvk", 1.0, 0.3, 0.0), Err(MaterialError::Density(_))));
}

/// P = ∂Ψ/∂F by central differences, at random F near and far from rest, inverted ones too.
#[test]
fn each_models_stress_is_its_energys_gradient() {
    let mut rng = Rng(0x5eed_1234);
    for model in MODELS {
        for spread in [0.05, 0.4, 1.2] {
            for _ in 0..20 {
                let f = random_f(&mut rng, spread);
                let p = model.first_piola(f, lame());
                let h = 1e-6;
                let scale = crate::linalg::frobenius2(&p).sqrt().max(lame().mu * 1e-3);
                for i in 0..3 {
                    for j in 0..3 {
                        let numeric = (model.energy_density(with_entry(f, i, j, h), lame())
                            - model.energy_density(with_entry(f, i, j, -h), lame()))
                            / (2.0 * h);
                        let err = (numeric - entry(p, i, j)).abs();
                        assert!(
                            err <= 1e-6 * scale,
                            "{}: P[{i}{j}] = {} but dΨ/dF = {numeric} at det F = {}",
                            model.info().name,
                            entry(p, i, j),
                            f.determinant()
                        );
                    }
                }
            }
        }
    }
}

/// Ψ(I) = 0, P(I) = 0, and Ψ(R F) = Ψ(F), P(R F) = R P(F) for rotations R (frame indifference).
#[test]
fn rest_is_stress_free_and_rotations_change_nothing() {
    let mut rng = Rng(77);
    for model in MODELS {
        let name = model.info().name;
        assert!(model.energy_density(DMat3::IDENTITY, lame()).abs() < 1e-9, "{name}: Ψ(I)");
        assert!(crate::linalg::frobenius2(&model.first_piola(DMat3::IDENTITY, lame())) < 1e-18, "{name}: P(I)");
        for _ in 0..20 {
            let (f, r) = (random_f(&mut rng, 0.3), rotation(&mut rng));
            let (psi, psi_r) = (model.energy_density(f, lame()), model.energy_density(r * f, lame()));
            assert!((psi - psi_r).abs() <= 1e-9 * psi.abs().max(1.0), "{name}: Ψ(RF) = {psi_r} ≠ Ψ(F) = {psi}");
            let rotated = r * model.first_piola(f, lame());
            let diff = crate::linalg::frobenius2(&(model.first_piola(r * f, lame()) - rotated)).sqrt();
            assert!(diff <= 1e-9 * lame().mu, "{name}: P(RF) ≠ R P(F) by {diff}");
            assert!(model.energy_density(r, lame()).abs() < 1e-6, "{name}: a rotation costs energy");
        }
    }
}

/// At small strain every model is linear elasticity: ∂P/∂F at I is
/// C_ijkl = μ (δ_ik δ_jl + δ_il δ_jk) + λ δ_ij δ_kl.
#[test]
fn small_strains_are_linear_elasticity() {
    let l = lame();
    let delta = |a: usize, b: usize| if a == b { 1.0 } else { 0.0 };
    for model in MODELS {
        let h = 1e-6;
        for k in 0..3 {
            for m in 0..3 {
                let dp = (model.first_piola(with_entry(DMat3::IDENTITY, k, m, h), l)
                    - model.first_piola(with_entry(DMat3::IDENTITY, k, m, -h), l))
                    * (0.5 / h);
                for i in 0..3 {
                    for j in 0..3 {
                        let c = l.mu * (delta(i, k) * delta(j, m) + delta(i, m) * delta(j, k))
                            + l.lambda * delta(i, j) * delta(k, m);
                        let err = (entry(dp, i, j) - c).abs();
                        assert!(
                            err <= 1e-5 * l.mu,
                            "{}: C[{i}{j}{k}{m}] = {} ≠ {c}",
                            model.info().name,
                            entry(dp, i, j)
                        );
                    }
                }
            }
        }
    }
}

/// Each model's uniaxial law, from its principal-stretch form written here (not the model
/// code): with F = diag(a, s, s), the stresses P₁₁(a, s) and P₂₂(a, s) (P₂₂ = P₃₃).
fn uniaxial_stresses(model: &str, l: Lame, a: f64, s: f64) -> (f64, f64) {
    let j = a * s * s;
    match model {
        "stvk" => {
            let (e1, e2) = (0.5 * (a * a - 1.0), 0.5 * (s * s - 1.0));
            let trace = e1 + 2.0 * e2;
            (a * (2.0 * l.mu * e1 + l.lambda * trace), s * (2.0 * l.mu * e2 + l.lambda * trace))
        }
        "corotated" => (
            2.0 * l.mu * (a - 1.0) + l.lambda * (j - 1.0) * s * s,
            2.0 * l.mu * (s - 1.0) + l.lambda * (j - 1.0) * a * s,
        ),
        "neo_hookean" => {
            let lambda = l.lambda + l.mu;
            let c = lambda * (j - 1.0) - l.mu;
            (l.mu * a + c * s * s, l.mu * s + c * a * s)
        }
        other => panic!("no uniaxial law for {other}"),
    }
}

/// The lateral stretch s with P₂₂(a, s) = 0 (bisection on (0.2, 1.5)), then P₁₁: the
/// first Piola stress a uniaxial stretch a needs.
fn uniaxial_law(model: &str, l: Lame, a: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (0.2, 1.5);
    let sign_lo = uniaxial_stresses(model, l, a, lo).1.signum();
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if uniaxial_stresses(model, l, a, mid).1.signum() == sign_lo {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let s = 0.5 * (lo + hi);
    (uniaxial_stresses(model, l, a, s).0, s)
}

/// Outward boundary triangles of a tet box whose corners all have coordinate `axis` = `at`.
fn face_triangles(mesh: &crate::mesh::Mesh, axis: usize, at: f64) -> Vec<[u32; 3]> {
    mesh.triangles
        .iter()
        .copied()
        .filter(|t| t.iter().all(|&v| (mesh.positions[v as usize][axis] - at).abs() < 1e-12))
        .collect()
}

/// Consistent nodal loads of a uniform traction t (force per rest area) on triangles: each
/// corner gets t A/3.
fn traction_loads(mesh: &crate::mesh::Mesh, triangles: &[[u32; 3]], t: DVec3, loads: &mut [DVec3]) {
    for tri in triangles {
        let [a, b, c] = tri.map(|v| mesh.positions[v as usize]);
        let area = 0.5 * (b - a).cross(c - a).length();
        for &v in tri {
            loads[v as usize] += t * (area / 3.0);
        }
    }
}

/// A block pulled by a uniform traction on its end faces (one corner held, nothing else):
/// the stress is uniaxial, so the stretch a and the lateral stretch s must follow each model's
/// uniaxial law, and at small strain −(s − 1)/(a − 1) is Poisson's ratio.
#[test]
fn a_block_in_uniaxial_tension_follows_each_models_law() {
    let size = DVec3::new(0.2, 0.1, 0.1);
    let mesh = tet_box([4, 2, 2], size);
    let rest = RestGeometry::new(mesh.positions.clone(), mesh.triangles.clone(), mesh.tetrahedra.clone());
    let (lo, hi) = (face_triangles(&mesh, 0, -0.1), face_triangles(&mesh, 0, 0.1));
    assert!(!lo.is_empty() && !hi.is_empty());
    for model in MODELS {
        let name = model.info().name;
        let material = Material::new(name, RUBBER.0, RUBBER.1, 1000.0).unwrap();
        for traction in [2.0e3, 1.0e5, 3.0e5] {
            let mut loads = vec![DVec3::ZERO; mesh.positions.len()];
            traction_loads(&mesh, &hi, DVec3::X * traction, &mut loads);
            traction_loads(&mesh, &lo, -DVec3::X * traction, &mut loads);
            let forces: Vec<Box<dyn Constraint>> = loads
                .iter()
                .enumerate()
                .filter(|(_, f)| **f != DVec3::ZERO)
                .map(|(v, f)| Box::new(Force::new(v as u32, *f, mesh.positions[v])) as Box<dyn Constraint>)
                .collect();
            let mut system = System::new(mesh.positions.len(), SolverParams::default());
            system.add_group(material_group(&rest, &material, 1.0).unwrap().0).unwrap();
            system.add_group(ConstraintGroup::new("traction", 1.0, forces)).unwrap();
            // One corner held: translations are fixed, the balanced loads fix the rotation.
            let corner = Position::new(vec![0], vec![mesh.positions[0]]).unwrap();
            system.add_group(ConstraintGroup::new("corner", 1.0, vec![Box::new(corner)]).with_hard(true)).unwrap();
            let mut q = mesh.positions.clone();
            let report = system.solve(&mut q, 2000, 1e-15).unwrap();
            assert!(report.energies.len() < 2000, "{name}: not converged in 2000 iterations");
            // Stretches from the end faces' and the sides' mean positions.
            let mean = |pick: &dyn Fn(DVec3) -> bool, axis: usize| {
                let picked: Vec<f64> = (0..q.len()).filter(|&v| pick(mesh.positions[v])).map(|v| q[v][axis]).collect();
                picked.iter().sum::<f64>() / picked.len() as f64
            };
            let a = (mean(&|p| p.x > 0.09, 0) - mean(&|p| p.x < -0.09, 0)) / size.x;
            let s = (mean(&|p| p.y > 0.049, 1) - mean(&|p| p.y < -0.049, 1)) / size.y;
            let (law, s_law) = uniaxial_law(name, material.lame, a);
            assert!(
                (law - traction).abs() <= 0.01 * traction,
                "{name}: stretch {a} takes {law} Pa by its law, the block carries {traction} Pa"
            );
            assert!((s - s_law).abs() <= 1e-3 * (a - 1.0).abs() + 1e-9, "{name}: lateral stretch {s} ≠ law's {s_law}");
            if traction < 1e4 {
                let nu = -(s - 1.0) / (a - 1.0);
                assert!((nu - RUBBER.1).abs() < 0.01 * RUBBER.1, "{name}: measured ν = {nu}");
            }
        }
    }
}

/// The total energy Σ |V_T| Ψ(F_T) − Σ f·u of a clamped mesh and its gradient, written for the
/// Newton check from the tetrahedra (not the solver's rows): ∂/∂x of |V_T| Ψ is
/// |V_T| P D⁻ᵀ for the columns b, c, d and minus their sum for a.
struct Problem<'a> {
    mesh: &'a crate::mesh::Mesh,
    model: &'static dyn Hyperelastic,
    lame: Lame,
    load: DVec3,
    free: Vec<usize>,
}

impl Problem<'_> {
    fn gradient(&self, q: &[DVec3]) -> Vec<DVec3> {
        let mut g = vec![DVec3::ZERO; q.len()];
        for t in &self.mesh.tetrahedra {
            let x = t.map(|v| self.mesh.positions[v as usize]);
            let y = t.map(|v| q[v as usize]);
            let dm = DMat3::from_cols(x[1] - x[0], x[2] - x[0], x[3] - x[0]);
            let volume = dm.determinant().abs() / 6.0;
            let f = DMat3::from_cols(y[1] - y[0], y[2] - y[0], y[3] - y[0]) * dm.inverse();
            let h = self.model.first_piola(f, self.lame) * dm.inverse().transpose() * volume;
            for k in 0..3 {
                g[t[k + 1] as usize] += h.col(k);
                g[t[0] as usize] -= h.col(k);
            }
        }
        for v in &self.free {
            g[*v] -= self.load;
        }
        g
    }

    /// Newton's method with a finite-difference Hessian of the gradient and a dense solve.
    fn newton(&self, mut q: Vec<DVec3>) -> Vec<DVec3> {
        let n = self.free.len() * 3;
        for _ in 0..50 {
            let g = self.gradient(&q);
            let rhs: Vec<f64> = self.free.iter().flat_map(|&v| g[v].to_array()).collect();
            if rhs.iter().map(|x| x * x).sum::<f64>().sqrt() < 1e-13 * self.lame.mu * 1e-3 {
                break;
            }
            let mut h = vec![vec![0.0; n]; n];
            let eps = 1e-7;
            for (col, (&v, k)) in self.free.iter().flat_map(|v| (0..3).map(move |k| (v, k))).enumerate() {
                let (mut plus, mut minus) = (q.clone(), q.clone());
                plus[v][k] += eps;
                minus[v][k] -= eps;
                let (gp, gm) = (self.gradient(&plus), self.gradient(&minus));
                for (row, (&w, m)) in self.free.iter().flat_map(|w| (0..3).map(move |m| (w, m))).enumerate() {
                    h[row][col] = (gp[w][m] - gm[w][m]) / (2.0 * eps);
                }
            }
            let step = solve_dense(h, rhs);
            for (i, &v) in self.free.iter().enumerate() {
                q[v] -= DVec3::new(step[3 * i], step[3 * i + 1], step[3 * i + 2]);
            }
        }
        q
    }
}

/// Gaussian elimination with partial pivoting.
fn solve_dense(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs())).unwrap();
        a.swap(c, p);
        b.swap(c, p);
        let pivot = a[c].clone();
        for r in c + 1..n {
            let factor = a[r][c] / pivot[c];
            for (x, p) in a[r][c..].iter_mut().zip(&pivot[c..]) {
                *x -= factor * p;
            }
            b[r] -= factor * b[c];
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x
}

/// A bar clamped at one end and loaded at every free vertex sags to the equilibrium an
/// independent Newton solver finds, to 1e-6 of the sag, for every model.
#[test]
fn the_static_equilibrium_is_newtons() {
    let mesh = tet_box([3, 1, 1], DVec3::new(0.3, 0.1, 0.1));
    let rest = RestGeometry::new(mesh.positions.clone(), mesh.triangles.clone(), mesh.tetrahedra.clone());
    let clamped: Vec<usize> = (0..mesh.positions.len()).filter(|&v| mesh.positions[v].x < -0.149).collect();
    let free: Vec<usize> = (0..mesh.positions.len()).filter(|v| !clamped.contains(v)).collect();
    let load = DVec3::new(0.0, -40.0, 10.0);
    for model in MODELS {
        let name = model.info().name;
        let material = Material::new(name, RUBBER.0, 0.4, 1000.0).unwrap();
        let mut system = System::new(mesh.positions.len(), SolverParams::default());
        system.add_group(material_group(&rest, &material, 1.0).unwrap().0).unwrap();
        let forces: Vec<Box<dyn Constraint>> = free
            .iter()
            .map(|&v| Box::new(Force::new(v as u32, load, mesh.positions[v])) as Box<dyn Constraint>)
            .collect();
        system.add_group(ConstraintGroup::new("load", 1.0, forces)).unwrap();
        let targets: Vec<DVec3> = clamped.iter().map(|&v| mesh.positions[v]).collect();
        let clamp = Position::new(clamped.iter().map(|&v| v as u32).collect(), targets).unwrap();
        system.add_group(ConstraintGroup::new("clamp", 1.0, vec![Box::new(clamp)]).with_hard(true)).unwrap();
        let mut q = mesh.positions.clone();
        let report = system.solve(&mut q, 5000, 1e-16).unwrap();
        // Energy never rises.
        assert!(report.energies.windows(2).all(|e| e[1] <= e[0] + 1e-12 * e[0].abs()), "{name}: E rose");
        let problem = Problem { mesh: &mesh, model: material.model, lame: material.lame, load, free: free.clone() };
        let newton = problem.newton(mesh.positions.clone());
        let sag = free.iter().map(|&v| (newton[v] - mesh.positions[v]).length()).fold(0.0, f64::max);
        let off = free.iter().map(|&v| (newton[v] - q[v]).length()).fold(0.0, f64::max);
        assert!(sag > 1e-3, "{name}: the bar barely sags ({sag} m)");
        assert!(off <= 1e-6 * sag, "{name}: L-BFGS is {off} m from Newton's equilibrium (sag {sag} m)");
    }
}

/// A block squashed through itself (every tetrahedron inverted) comes back to its rest shape
/// with the stable models, with no NaN on the way.
#[test]
fn an_inverted_block_recovers() {
    let mesh = tet_box([2, 2, 2], DVec3::splat(0.1));
    let rest = RestGeometry::new(mesh.positions.clone(), mesh.triangles.clone(), mesh.tetrahedra.clone());
    for name in ["neo_hookean", "corotated"] {
        let material = Material::new(name, RUBBER.0, 0.45, 1000.0).unwrap();
        let mut system = System::new(mesh.positions.len(), SolverParams::default());
        system.add_group(material_group(&rest, &material, 1.0).unwrap().0).unwrap();
        // The centre vertex held where it is: the rest shape is the minimum, up to rotations
        // about it, which the reflected start does not favour.
        let centre = (0..mesh.positions.len())
            .min_by(|&a, &b| mesh.positions[a].length().total_cmp(&mesh.positions[b].length()))
            .unwrap();
        let hold = Position::new(vec![centre as u32], vec![mesh.positions[centre]]).unwrap();
        system.add_group(ConstraintGroup::new("hold", 1.0, vec![Box::new(hold)]).with_hard(true)).unwrap();
        let mut q: Vec<DVec3> = mesh.positions.iter().map(|p| DVec3::new(p.x, -0.3 * p.y, p.z)).collect();
        system.solve(&mut q, 3000, 1e-14).unwrap();
        assert!(q.iter().all(|p| p.is_finite()), "{name}: NaN");
        // Back to a rigid copy of the rest shape: every edge its rest length.
        let worst = mesh
            .tetrahedra
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[0], t[2]), (t[0], t[3]), (t[1], t[2]), (t[1], t[3]), (t[2], t[3])])
            .map(|(a, b)| {
                let (a, b) = (a as usize, b as usize);
                ((q[a] - q[b]).length() / (mesh.positions[a] - mesh.positions[b]).length() - 1.0).abs()
            })
            .fold(0.0, f64::max);
        assert!(worst < 1e-4, "{name}: an edge is {worst} off its rest length");
        let inverted = mesh
            .tetrahedra
            .iter()
            .filter(|t| {
                let p = t.map(|v| q[v as usize]);
                (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]) <= 0.0
            })
            .count();
        assert_eq!(inverted, 0, "{name}: {inverted} tetrahedra still inverted");
    }
}

fn enclosed_volume(q: &[DVec3], triangles: &[[u32; 3]]) -> f64 {
    triangles.iter().map(|t| t.map(|v| q[v as usize])).map(|[a, b, c]| a.dot(b.cross(c)) / 6.0).sum()
}

/// A spherical membrane (rubber, 1 mm thick, radius 0.1 m) inflated by a pressure p: its
/// radius follows the model's pressure–stretch law within 1 %. Under a uniform stretch s the
/// membrane stores A₀ h Ψ_m(s) and encloses s³ V₀, so equilibrium (dE = p dV) is
/// p = A₀ h Ψ_m'(s) / (3 V₀ s²), with Ψ_m'(s) = 2 P₁₁(diag(s, s, λ₃(s))) by the envelope
/// theorem; for a true sphere A₀/(3V₀) = 1/R₀ (the thin-walled balloon's p = 2 h σ_θ/(s² R₀)
/// in nominal stress). Neo-Hookean's law is written out here from its formula: P₁₁ = μs +
/// (λ'(J − 1) − μ) s λ₃ with J = s²λ₃.
#[test]
fn an_inflated_spherical_membrane_follows_each_models_pressure_stretch_law() {
    let sphere = crate::generate::icosphere(3, 0.1);
    let (positions, triangles) = (sphere.positions.clone(), sphere.triangles.clone());
    let rest = RestGeometry::new(positions.clone(), triangles.clone(), vec![]);
    let v0 = enclosed_volume(&positions, &triangles);
    let a0: f64 = rest.triangle_areas.iter().sum();
    let h = 0.001;
    for model in MODELS {
        let name = model.info().name;
        let material = Material::new(name, RUBBER.0, 0.45, 1100.0).unwrap().with_thickness(h).unwrap();
        let l = material.lame;
        let slope = |s: f64| {
            let l3 = model.plane_stress_stretch([s, s], l);
            let p11 = if name == "neo_hookean" {
                let lambda = l.lambda + l.mu;
                l.mu * s + (lambda * (s * s * l3 - 1.0) - l.mu) * s * l3
            } else {
                model.first_piola(DMat3::from_diagonal(DVec3::new(s, s, l3)), l).x_axis.x
            };
            2.0 * p11
        };
        let law = |s: f64| a0 * h * slope(s) / (3.0 * v0 * s * s);
        for stretch in [1.05, 1.15, 1.25] {
            let pressure = law(stretch);
            let mut system = System::new(positions.len(), SolverParams::default());
            system.add_group(material_group(&rest, &material, 1.0).unwrap().0).unwrap();
            system.add_group(pressure_group(&rest, pressure, 1.0).unwrap()).unwrap();
            let mut q = positions.clone();
            let report = system.solve(&mut q, 3000, 1e-14).unwrap();
            assert!(report.energies.windows(2).all(|e| e[1] <= e[0] + 1e-12 * e[0].abs()), "{name}: E rose");
            assert!(q.iter().all(|p| p.is_finite()), "{name}: NaN");
            let s = (enclosed_volume(&q, &triangles) / v0).cbrt();
            let error = (law(s) / pressure - 1.0).abs();
            assert!(
                error < 0.01,
                "{name}: p = {pressure:.1} Pa inflates to s = {s:.5} (aimed at {stretch}), where the law gives {:.1} Pa ({:.2} % off)",
                law(s),
                100.0 * error
            );
            assert!((s - 1.0).abs() > 0.5 * (stretch - 1.0), "{name}: barely inflated ({s})");
        }
    }
}

/// A horizontal sheet (a membrane, 0.5 mm thick, ρ = 1500 kg/m³) falling in still air reaches
/// the terminal velocity where drag balances its weight, v = √(2 m g / (ρ_air C_D A)), and
/// stays flat; in a wind along x it also drifts with it. Through the scene, as `simulate` runs.
#[test]
fn a_falling_sheet_reaches_its_terminal_velocity_in_still_air() {
    use crate::scene::{Scene, SceneFormat};
    let text = "[mesh]\ngenerate = { kind = \"cloth\", vertices = [6, 6], size = [0.5, 0.5] }\n\
                [solver]\nmode = \"dynamic\"\ntime_step = 0.01\n\
                [material]\nmodel = \"stvk\"\nyoungs_modulus = 1e6\npoisson_ratio = 0.3\ndensity = 1500.0\nthickness = 0.0005\n\
                [loads]\nwind = { velocity = [0.0, 0.0, 0.0], drag = 1.2, air_density = 1.225 }\n";
    let scene = Scene::parse(text, SceneFormat::Toml, std::path::Path::new("sheet.toml"), Default::default()).unwrap();
    let mut loaded = scene.load().unwrap();
    let mut simulation = loaded.start_simulation().unwrap();
    for _ in 0..300 {
        simulation.step().unwrap();
    }
    let (mass_per_area, g): (f64, f64) = (1500.0 * 0.0005, 9.81);
    let terminal = (2.0 * mass_per_area * g / (1.225 * 1.2)).sqrt();
    let v = simulation.velocities();
    let mean = v.iter().map(|v| v.y).sum::<f64>() / v.len() as f64;
    assert!((-mean / terminal - 1.0).abs() < 1e-3, "falls at {mean} m/s, terminal {terminal}");
    let y = simulation.positions().iter().map(|p| p.y);
    let (lo, hi) = y.clone().fold((f64::MAX, f64::MIN), |(a, b), y| (a.min(y), b.max(y)));
    assert!(hi - lo < 1e-6, "the sheet stays flat: {lo}..{hi}");
    // A side wind: the sheet drifts along it, never faster than the air.
    let windy = text.replace("velocity = [0.0, 0.0, 0.0]", "velocity = [5.0, 0.0, 0.0]");
    let scene =
        Scene::parse(&windy, SceneFormat::Toml, std::path::Path::new("sheet.toml"), Default::default()).unwrap();
    let mut simulation = scene.load().unwrap().start_simulation().unwrap();
    for _ in 0..100 {
        simulation.step().unwrap();
    }
    let drift = simulation.velocities().iter().map(|v| v.x).sum::<f64>() / v.len() as f64;
    assert!(drift > 0.0 && drift < 5.0, "drifts at {drift} m/s in a 5 m/s wind");
    // Static: refused, naming [loads].
    let mut loaded = Scene::parse(text, SceneFormat::Toml, std::path::Path::new("sheet.toml"), Default::default())
        .unwrap()
        .load()
        .unwrap();
    let e = loaded.solve_static(None).unwrap_err().to_string();
    assert!(e.contains("[loads]") && e.contains("simulate"), "{e}");
}
