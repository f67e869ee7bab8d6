//! Helpers shared by integration tests (`mod common;`): distances between row lists, the wavy
//! quad grid, a mesh's rest geometry, options turned by a rigid motion, and ([`random`]) the
//! random small meshes of the property tests, and the xorshift [`Rng`].
#![allow(dead_code)]

pub mod random;
mod rng;

#[allow(unused_imports)] // not every test binary that includes `common` draws numbers
pub use rng::Rng;

use glam::{DQuat, DVec3};
use shapeup_core::constraints::{ConstraintType, OptionKind, Params};
use shapeup_core::geometry::RestGeometry;
use shapeup_core::mesh::{Mesh, Polygons};

/// `‖a − b‖_F²` of two row lists.
pub fn dist2(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (*x - *y).length_squared()).sum()
}

/// An n×n grid of quads on a wavy surface (non-planar quads, interior vertices, a boundary),
/// about one unit across.
pub fn quad_grid(n: u32) -> Mesh {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 / n as f64 - 0.5, j as f64 / n as f64 - 0.5);
            positions.push(wavy(x, y));
        }
    }
    let at = |i: u32, j: u32| j * (n + 1) + i;
    let mut polygons = Polygons::new();
    for j in 0..n {
        for i in 0..n {
            polygons.push(&[at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    let (mesh, _) = Mesh::from_polygons(positions, polygons).unwrap();
    mesh
}

/// The point of the wavy surface above (x, y): z = 0.15 sin 3x cos 2y + 0.1 xy.
pub fn wavy(x: f64, y: f64) -> DVec3 {
    DVec3::new(x, y, 0.15 * (3.0 * x).sin() * (2.0 * y).cos() + 0.1 * x * y)
}

/// The rest geometry of `mesh` at its own positions, with its polygon faces.
pub fn rest_of(mesh: &Mesh) -> RestGeometry {
    RestGeometry::of_mesh(mesh.positions.clone(), mesh)
}

/// Options of a type moved by a rigid motion: its vector options (directions, forces) at their
/// defaults turned with it.
pub fn turned_options(ty: &dyn ConstraintType, turn: DQuat) -> Params {
    let mut params = Params::default();
    for option in ty.options() {
        if let OptionKind::Vector { default } = option.kind {
            params = params.with(option.key, (turn * DVec3::from(default)).to_array().to_vec());
        }
    }
    params
}
