//! Generated meshes for examples, tests and benchmarks: a cloth grid, an icosphere and a
//! tetrahedral box.

use crate::geometry::tet_volume;
use crate::mesh::Mesh;
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

/// A sphere of `radius` centred at the origin: the icosahedron with each triangle split into
/// four `subdivisions` times, every new vertex pushed out onto the sphere (10·4ˢ + 2 vertices,
/// 20·4ˢ triangles, counter-clockwise seen from outside). Its triangles are near-equal (within
/// about 20 % in area), which a membrane or a pressure wants.
pub fn icosphere(subdivisions: usize, radius: f64) -> Mesh {
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let mut p: Vec<DVec3> = [
        (-1.0, g, 0.0),
        (1.0, g, 0.0),
        (-1.0, -g, 0.0),
        (1.0, -g, 0.0),
        (0.0, -1.0, g),
        (0.0, 1.0, g),
        (0.0, -1.0, -g),
        (0.0, 1.0, -g),
        (g, 0.0, -1.0),
        (g, 0.0, 1.0),
        (-g, 0.0, -1.0),
        (-g, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut t: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid = std::collections::HashMap::new();
        let mut next = Vec::with_capacity(4 * t.len());
        for [a, b, c] in t {
            let mut m = |i: u32, j: u32| {
                *mid.entry((i.min(j), i.max(j))).or_insert_with(|| {
                    p.push(((p[i as usize] + p[j as usize]) * 0.5).normalize());
                    (p.len() - 1) as u32
                })
            };
            let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        t = next;
    }
    p.iter_mut().for_each(|x| *x *= radius);
    Mesh::from_parts_unchecked(p, t, Vec::new())
}

/// A box of `cells[0]` × `cells[1]` × `cells[2]` cubes (each count at least 1) of total `size`,
/// centred at the origin, each cube split into six tetrahedra around its main diagonal (the
/// Kuhn split, conforming across cubes), all positively oriented. The triangles are the
/// boundary faces, outward, in the order [`crate::topology::tetrahedron_boundary`] gives them (found here from
/// the cube indices, without its sort: a face is on the boundary exactly when its three
/// corners lie on one side of the box). Vertex (i, j, k) has index (i·(ny+1) + j)·(nz+1) + k
/// with ny, nz the cell counts along y and z. The vertex count must fit a `u32` index (scenes
/// cap generated meshes far below; see `scene::GeneratedMesh::validate`).
pub fn tet_box(cells: [usize; 3], size: DVec3) -> Mesh {
    let [nx, ny, nz] = cells.map(|c| c.max(1));
    let index = |[i, j, k]: [usize; 3]| ((i * (ny + 1) + j) * (nz + 1) + k) as u32;
    let mut positions = Vec::with_capacity((nx + 1) * (ny + 1) * (nz + 1));
    for i in 0..=nx {
        for j in 0..=ny {
            for k in 0..=nz {
                let t = DVec3::new(i as f64 / nx as f64, j as f64 / ny as f64, k as f64 / nz as f64);
                positions.push((t - DVec3::splat(0.5)) * size);
            }
        }
    }
    // The six monotone paths from corner 000 to 111, one per order of the axes, each as its
    // four corner offsets, positively oriented (one cube decides for all: they are translates).
    const ORDERS: [[usize; 3]; 6] = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
    let cell = size / DVec3::new(nx as f64, ny as f64, nz as f64);
    let paths = ORDERS.map(|order| {
        let mut path = [[0usize; 3]; 4];
        for (step, &axis) in order.iter().enumerate() {
            path[step + 1] = path[step];
            path[step + 1][axis] += 1;
        }
        let p = path.map(|o| DVec3::new(o[0] as f64, o[1] as f64, o[2] as f64) * cell);
        if tet_volume(p[0], p[1], p[2], p[3]) < 0.0 {
            path.swap(2, 3);
        }
        path
    });
    let n = [nx, ny, nz];
    let boundary_squares = 2 * (nx * ny + ny * nz + nz * nx);
    let mut tetrahedra = Vec::with_capacity(6 * nx * ny * nz);
    let mut triangles = Vec::with_capacity(2 * boundary_squares);
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nz {
                let inner = (0 < i && i + 1 < nx) && (0 < j && j + 1 < ny) && (0 < k && k + 1 < nz);
                for path in &paths {
                    let corners = path.map(|o| [i + o[0], j + o[1], k + o[2]]);
                    let [a, b, c, d] = corners.map(index);
                    tetrahedra.push([a, b, c, d]);
                    if inner {
                        continue;
                    }
                    // The faces in `tetrahedron_boundary`'s order.
                    let [ca, cb, cc, cd] = corners;
                    for (face, at) in [
                        ([b, c, d], [cb, cc, cd]),
                        ([a, d, c], [ca, cd, cc]),
                        ([a, b, d], [ca, cb, cd]),
                        ([a, c, b], [ca, cc, cb]),
                    ] {
                        let on_side = (0..3).any(|axis| {
                            let x = at[0][axis];
                            (x == 0 || x == n[axis]) && at[1][axis] == x && at[2][axis] == x
                        });
                        if on_side {
                            triangles.push(face);
                        }
                    }
                }
            }
        }
    }
    Mesh::from_parts_unchecked(positions, triangles, tetrahedra)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::topology::tetrahedron_boundary;

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
    fn tet_box_boundary_is_tetrahedron_boundary_in_the_same_order() {
        for cells in [[1, 1, 1], [1, 2, 3], [3, 1, 1], [4, 3, 2], [2, 5, 1]] {
            let m = tet_box(cells, DVec3::new(1.0, 0.7, 0.4));
            assert_eq!(m.triangles, tetrahedron_boundary(&m.tetrahedra), "{cells:?}");
        }
    }

    #[test]
    fn one_cube_has_the_19_edges_of_the_kuhn_split() {
        // 12 cube edges, 6 face diagonals, 1 main diagonal.
        let m = tet_box([1, 1, 1], DVec3::ONE);
        assert_eq!(crate::topology::tetrahedron_edges(&m.tetrahedra).len(), 19);
    }
}
