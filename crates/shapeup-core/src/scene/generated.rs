//! A mesh the scene generates instead of reading a file, and the memory cap that keeps a typo
//! from asking for terabytes.

use crate::mesh::Mesh;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// A mesh the scene generates instead of reading a file (`[mesh] generate = { kind = … }`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum GeneratedMesh {
    /// A flat cloth in the plane y = 0 ([`crate::generate::cloth_grid`]): `vertices = [nx, nz]`,
    /// `size = [width, depth]`.
    Cloth {
        /// Vertices along x and z (each ≥ 2).
        vertices: [usize; 2],
        /// Extent along x and z.
        size: [f64; 2],
    },
    /// A sphere of triangles ([`crate::generate::icosphere`]): `subdivisions` (0: the
    /// icosahedron), `radius`.
    Sphere {
        /// Times each triangle of the icosahedron is split into four.
        subdivisions: usize,
        /// Its radius.
        radius: f64,
    },
    /// A box of tetrahedra ([`crate::generate::tet_box`]): `cells = [nx, ny, nz]`,
    /// `size = [x, y, z]`.
    TetBox {
        /// Cubes along x, y and z (each ≥ 1).
        cells: [usize; 3],
        /// Extent along x, y and z.
        size: [f64; 3],
    },
}

/// A generated mesh that cannot be made ([`GeneratedMesh::validate`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GenerateError {
    /// A count below its minimum (2 vertices, 1 cell along each axis).
    #[error("generate: every count must be at least {minimum}, found {found}")]
    Count {
        /// The least allowed.
        minimum: usize,
        /// The count given.
        found: usize,
    },
    /// A size that is not a finite number > 0.
    #[error("generate: every size must be a finite number > 0, found {0}")]
    Size(f64),
    /// More memory than [`MAX_GENERATED_BYTES`]: the estimate, the cap and the largest counts
    /// of the same proportions that fit.
    #[error("{0}")]
    TooLarge(String),
}

/// The most memory, in bytes, that loading a scene's generated mesh may take: 1 GB, a tet_box
/// of about 138 × 138 × 138 cells (16 million tetrahedra) or a cloth of about 1,400 × 1,400
/// vertices, each loaded in 1–3 s; a typo in `cells` or `vertices` must not ask for terabytes.
/// Checked against [`GeneratedMesh::estimated_bytes`] when the scene is parsed and again when
/// it loads. Constraint groups come on top (`tet_strain` about 120 bytes per tetrahedron).
pub const MAX_GENERATED_BYTES: u64 = 1_000_000_000;

// Peak bytes that loading a generated mesh takes per element (the mesh, its polygons and
// boundary, the rest geometry with its topology, the solver's set-up; constraint groups come on
// top), measured with a counting allocator (tests/hostile_scene.rs checks them) and rounded up.
const BYTES_PER_VERTEX: f64 = 176.0;
const BYTES_PER_TRIANGLE: f64 = 160.0;
const BYTES_PER_TETRAHEDRON: f64 = 32.0;
// The cap keeps vertex indices far inside u32.
const _: () = assert!(MAX_GENERATED_BYTES as f64 / BYTES_PER_VERTEX < u32::MAX as f64);

impl GeneratedMesh {
    /// Checks the counts and sizes, and the memory the mesh needs against
    /// [`MAX_GENERATED_BYTES`].
    ///
    /// # Errors
    /// A one-line message naming the bad value; for too large a mesh, the estimate, the cap and
    /// the largest counts of the same proportions that fit.
    pub fn validate(&self) -> Result<(), GenerateError> {
        let (counts, minimum, sizes): (&[usize], usize, &[f64]) = match self {
            GeneratedMesh::Cloth { vertices, size } => (vertices, 2, size),
            GeneratedMesh::TetBox { cells, size } => (cells, 1, size),
            GeneratedMesh::Sphere { subdivisions, radius } => {
                (std::slice::from_ref(subdivisions), 0, std::slice::from_ref(radius))
            }
        };
        if let Some(n) = counts.iter().find(|&&n| n < minimum) {
            return Err(GenerateError::Count { minimum, found: *n });
        }
        if let Some(x) = sizes.iter().find(|x| !(x.is_finite() && **x > 0.0)) {
            return Err(GenerateError::Size(*x));
        }
        let bytes = self.estimated_bytes();
        if bytes <= MAX_GENERATED_BYTES as f64 {
            return Ok(());
        }
        let (what, unit, elements) = match self {
            GeneratedMesh::Cloth { .. } => {
                ("cloth", "vertices", format!("{} triangles", count(self.element_counts()[1])))
            }
            GeneratedMesh::TetBox { .. } => {
                ("tet_box", "cells", format!("{} tetrahedra", count(self.element_counts()[2])))
            }
            GeneratedMesh::Sphere { .. } => {
                ("sphere", "subdivisions", format!("{} triangles", count(self.element_counts()[1])))
            }
        };
        let shown = |c: &[usize]| c.iter().map(|&n| grouped(n as u64)).collect::<Vec<_>>().join(" × ");
        let advice = match self.largest_that_fits() {
            Some(fits) => format!(": use at most about {} {unit}", shown(&fits)),
            None => String::new(),
        };
        Err(GenerateError::TooLarge(format!(
            "generate: a {what} of {} {unit} ({elements}) needs about {} to load; the cap is {}{advice}",
            shown(counts_of(self)),
            gigabytes(bytes),
            gigabytes(MAX_GENERATED_BYTES as f64),
        )))
    }

    /// Its vertices, triangles and tetrahedra, as floating-point numbers (exact up to 2⁵³,
    /// finite for any counts: no overflow).
    pub fn element_counts(&self) -> [f64; 3] {
        match *self {
            GeneratedMesh::Cloth { vertices, .. } => {
                let [x, z] = vertices.map(|n| n.max(2) as f64);
                [x * z, 2.0 * (x - 1.0) * (z - 1.0), 0.0]
            }
            GeneratedMesh::TetBox { cells, .. } => {
                let [x, y, z] = cells.map(|n| n.max(1) as f64);
                [(x + 1.0) * (y + 1.0) * (z + 1.0), 4.0 * (x * y + y * z + z * x), 6.0 * x * y * z]
            }
            GeneratedMesh::Sphere { subdivisions, .. } => {
                let faces = 20.0 * 4f64.powi(subdivisions.min(1000) as i32);
                [faces / 2.0 + 2.0, faces, 0.0]
            }
        }
    }

    /// The bytes that loading a scene with this mesh takes at its peak, estimated from its
    /// element counts (constraint groups come on top).
    pub fn estimated_bytes(&self) -> f64 {
        let [v, t, k] = self.element_counts();
        BYTES_PER_VERTEX * v + BYTES_PER_TRIANGLE * t + BYTES_PER_TETRAHEDRON * k
    }

    /// The largest counts in the same proportions whose estimate fits the cap (bisection on
    /// the scale), or `None` if not even the smallest does.
    fn largest_that_fits(&self) -> Option<Vec<usize>> {
        let scaled = |s: f64| -> GeneratedMesh {
            let f = |n: usize, minimum: usize| ((n as f64 * s).floor() as usize).max(minimum);
            match *self {
                GeneratedMesh::Cloth { vertices, size } => {
                    GeneratedMesh::Cloth { vertices: vertices.map(|n| f(n, 2)), size }
                }
                GeneratedMesh::TetBox { cells, size } => GeneratedMesh::TetBox { cells: cells.map(|n| f(n, 1)), size },
                // Each subdivision quadruples the mesh: one fewer per halving of the scale.
                GeneratedMesh::Sphere { subdivisions, radius } => GeneratedMesh::Sphere {
                    subdivisions: subdivisions.saturating_sub((-s.max(1e-300).log2()).ceil() as usize),
                    radius,
                },
            }
        };
        let fits = |s: f64| scaled(s).estimated_bytes() <= MAX_GENERATED_BYTES as f64;
        if !fits(0.0) {
            return None;
        }
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if fits(mid) { lo = mid } else { hi = mid }
        }
        Some(counts_of(&scaled(lo)).to_vec())
    }

    /// The mesh.
    pub fn mesh(&self) -> Mesh {
        match *self {
            GeneratedMesh::Cloth { vertices: [nx, nz], size: [w, d] } => crate::generate::cloth_grid(nx, nz, w, d),
            GeneratedMesh::TetBox { cells, size } => crate::generate::tet_box(cells, DVec3::from_array(size)),
            GeneratedMesh::Sphere { subdivisions, radius } => crate::generate::icosphere(subdivisions, radius),
        }
    }
}

fn counts_of(generated: &GeneratedMesh) -> &[usize] {
    match generated {
        GeneratedMesh::Cloth { vertices, .. } => vertices,
        GeneratedMesh::TetBox { cells, .. } => cells,
        GeneratedMesh::Sphere { subdivisions, .. } => std::slice::from_ref(subdivisions),
    }
}

/// A count with thousands separators (`14,762,250`), in scientific notation past 10¹⁵.
fn count(n: f64) -> String {
    if n >= 1e15 { format!("{n:.2e}") } else { grouped(n as u64) }
}

/// `n` with thousands separators.
fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, d) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(d);
    }
    out
}

/// Bytes in GB (10⁹ bytes), or MB below 0.1 GB.
fn gigabytes(bytes: f64) -> String {
    match bytes {
        b if b < 1e8 => format!("{:.0} MB", b / 1e6),
        b if b < 1e15 => format!("{:.1} GB", b / 1e9),
        b => format!("{:.1e} GB", b / 1e9),
    }
}
