//! Generated meshes for examples, tests and benchmarks: a cloth grid and a tetrahedral box.

use crate::geometry::tet_volume;
use crate::mesh::Mesh;
use crate::topology::tetrahedron_boundary;
use glam::DVec3;

/// A flat rectangular cloth of `nx` × `nz` vertices (each at least 2) spanning `width` along x
/// and `depth` along z, in the plane y = 0, centred at the origin. Vertex (i, j), i along x and
/// j along z, has index i·nz + j, so vertices 0 and nz − 1 are the two corners of the edge at
/// x = −width/2. Each cell is split into two triangles along alternating diagonals (no
/// preferred shear direction); every triangle's normal points up (+y).
pub fn cloth_grid(nx: usize, nz: usize, width: f64, depth: f64) -> Mesh {
    let (nx, nz) = (nx.max(2), nz.max(2));
    let mut positions = Vec::with_capacity(nx * nz);
    for i in 0..nx {
        for j in 0..nz {
            let x = width * (i as f64 / (nx - 1) as f64 - 0.5);
            let z = depth * (j as f64 / (nz - 1) as f64 - 0.5);
            positions.push(DVec3::new(x, 0.0, z));
        }
    }
    let index = |i: usize, j: usize| (i * nz + j) as u32;
    let mut triangles = Vec::with_capacity(2 * (nx - 1) * (nz - 1));
    for i in 0..nx - 1 {
        for j in 0..nz - 1 {
            let (a, b, c, d) = (index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1));
            if (i + j) % 2 == 0 {
                triangles.extend([[a, c, b], [a, d, c]]);
            } else {
                triangles.extend([[a, d, b], [b, d, c]]);
            }
        }
    }
    Mesh::from_parts_unchecked(positions, triangles, Vec::new())
}

/// A box of `cells[0]` × `cells[1]` × `cells[2]` cubes (each count at least 1) of total `size`,
/// centred at the origin, each cube split into six tetrahedra around its main diagonal (the
/// Kuhn split, conforming across cubes), all positively oriented. The triangles are the
/// boundary faces, outward (see [`tetrahedron_boundary`]). Vertex (i, j, k) has index
/// (i·(ny+1) + j)·(nz+1) + k with ny, nz the cell counts along y and z.
pub fn tet_box(cells: [usize; 3], size: DVec3) -> Mesh {
    let [nx, ny, nz] = cells.map(|c| c.max(1));
    let index = |i: usize, j: usize, k: usize| ((i * (ny + 1) + j) * (nz + 1) + k) as u32;
    let mut positions = Vec::with_capacity((nx + 1) * (ny + 1) * (nz + 1));
    for i in 0..=nx {
        for j in 0..=ny {
            for k in 0..=nz {
                let t = DVec3::new(i as f64 / nx as f64, j as f64 / ny as f64, k as f64 / nz as f64);
                positions.push((t - DVec3::splat(0.5)) * size);
            }
        }
    }
    // The six monotone paths from corner 000 to 111, one per order of the axes.
    const ORDERS: [[usize; 3]; 6] = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
    let mut tetrahedra = Vec::with_capacity(6 * nx * ny * nz);
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nz {
                for order in ORDERS {
                    let mut corner = [i, j, k];
                    let mut tet = [index(i, j, k); 4];
                    for (step, &axis) in order.iter().enumerate() {
                        corner[axis] += 1;
                        tet[step + 1] = index(corner[0], corner[1], corner[2]);
                    }
                    let p = tet.map(|v| positions[v as usize]);
                    if tet_volume(p[0], p[1], p[2], p[3]) < 0.0 {
                        tet.swap(2, 3);
                    }
                    tetrahedra.push(tet);
                }
            }
        }
    }
    let triangles = tetrahedron_boundary(&tetrahedra);
    Mesh::from_parts_unchecked(positions, triangles, tetrahedra)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cloth_grid_is_flat_centred_and_faces_up() {
        let m = cloth_grid(4, 3, 2.0, 1.0);
        assert_eq!((m.num_vertices(), m.num_triangles()), (12, 12));
        assert!(m.validate().is_ok());
        assert_eq!(m.positions[0], DVec3::new(-1.0, 0.0, -0.5));
        assert_eq!(m.positions[2], DVec3::new(-1.0, 0.0, 0.5));
        for t in &m.triangles {
            let [a, b, c] = t.map(|v| m.positions[v as usize]);
            assert!((b - a).cross(c - a).y > 0.0);
        }
    }

    #[test]
    fn tet_box_fills_its_volume_with_positive_tets_and_a_closed_outward_surface() {
        let size = DVec3::new(2.0, 1.0, 0.5);
        let m = tet_box([3, 2, 2], size);
        assert!(m.validate().is_ok());
        assert_eq!(m.num_vertices(), 4 * 3 * 3);
        assert_eq!(m.num_tetrahedra(), 6 * 12);
        let volumes: Vec<f64> = m
            .tetrahedra
            .iter()
            .map(|t| {
                let p = t.map(|v| m.positions[v as usize]);
                tet_volume(p[0], p[1], p[2], p[3])
            })
            .collect();
        assert!(volumes.iter().all(|&v| v > 0.0));
        assert!((volumes.iter().sum::<f64>() - size.x * size.y * size.z).abs() < 1e-12);
        // Boundary: 2 triangles per boundary square; outward (divergence theorem: the signed
        // volume enclosed by the surface equals the box volume).
        assert_eq!(m.num_triangles(), 2 * 2 * (3 * 2 + 3 * 2 + 2 * 2));
        let enclosed: f64 = m
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| m.positions[v as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        assert!((enclosed - size.x * size.y * size.z).abs() < 1e-12, "{enclosed}");
    }

    #[test]
    fn one_cube_has_the_19_edges_of_the_kuhn_split() {
        // 12 cube edges, 6 face diagonals, 1 main diagonal.
        let m = tet_box([1, 1, 1], DVec3::ONE);
        assert_eq!(crate::topology::tetrahedron_edges(&m.tetrahedra).len(), 19);
    }
}
