//! Laplacian rows of one vertex: the cotan row (bending, smoothing) and the uniform row
//! (laplacian, laplacian_displacement).

use crate::constraints::contract::RowSink;
use crate::geometry::RestGeometry;
use glam::DVec3;

/// The cotan Laplacian row of one vertex: H(q) = Σ_j (c_ij / A_i)(q_i − q_j). Shared by
/// bending and smoothing.
#[derive(Debug, Clone)]
pub(crate) struct LaplacianRow {
    /// `[i, j₁, …, j_k]`: the centre first.
    pub vertices: Vec<u32>,
    /// Coefficient of each vertex of `vertices` in H (the centre's is Σ_j c_ij / A_i).
    pub coeffs: Vec<f64>,
}

impl LaplacianRow {
    /// The row of vertex `i` from the rest geometry's cotan weights and vertex area.
    pub fn new(rest: &RestGeometry, i: usize) -> Self {
        let stencil = rest.laplacian_stencil(i);
        let mut vertices = vec![i as u32];
        let mut coeffs = vec![stencil.iter().map(|&(_, w)| w).sum()];
        for (j, w) in stencil {
            vertices.push(j);
            coeffs.push(-w);
        }
        LaplacianRow { vertices, coeffs }
    }

    /// H(q).
    #[inline]
    pub fn apply(&self, q: &[DVec3]) -> DVec3 {
        self.vertices.iter().zip(&self.coeffs).map(|(&v, &c)| c * q[v as usize]).sum()
    }

    /// Emits the row as row 0.
    pub fn rows(&self, sink: &mut RowSink) {
        for (&v, &c) in self.vertices.iter().zip(&self.coeffs) {
            sink.push(0, v, c);
        }
    }
}

/// The uniform Laplacian row of one vertex: L_i q = q_i − (1/k) Σ_j q_j. Shared by
/// `laplacian` and `laplacian_displacement`.
#[derive(Debug, Clone)]
pub(crate) struct UniformLaplacianRow {
    /// `[i, j₁, …, j_k]`: the centre first.
    pub vertices: Box<[u32]>,
}

impl UniformLaplacianRow {
    /// The row of vertex `i` over its one-ring in `rest`; `None` without neighbours.
    pub fn new(rest: &RestGeometry, i: usize) -> Option<Self> {
        let ring = rest.topology.one_rings.get(i)?;
        if ring.is_empty() {
            return None;
        }
        Some(UniformLaplacianRow { vertices: std::iter::once(i as u32).chain(ring.iter().copied()).collect() })
    }

    /// Number of neighbours k.
    #[inline]
    pub fn degree(&self) -> usize {
        self.vertices.len() - 1
    }

    /// L_i q.
    #[inline]
    pub fn apply(&self, q: &[DVec3]) -> DVec3 {
        let mean = self.vertices[1..].iter().map(|&j| q[j as usize]).sum::<DVec3>() / self.degree() as f64;
        q[self.vertices[0] as usize] - mean
    }

    /// Emits the row as row `row`.
    pub fn rows(&self, sink: &mut RowSink, row: usize) {
        sink.push(row, self.vertices[0], 1.0);
        let c = -1.0 / self.degree() as f64;
        for &j in &self.vertices[1..] {
            sink.push(row, j, c);
        }
    }
}
