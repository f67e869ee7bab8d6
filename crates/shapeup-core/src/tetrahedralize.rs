//! Filling a closed triangle surface with tetrahedra, with TetGen (Hang Si) through the tritet
//! crate. TetGen is AGPL-3.0, so this module exists only with the `tetgen` feature; without it,
//! give a tetrahedral mesh file instead (.msh or .node/.ele, e.g. made with Gmsh or TetGen).
//!
//! The surface's vertices keep their indices: the result's first vertices are the input's (all
//! of them, also those no triangle uses), the points TetGen adds come after, and the triangles
//! are the input's. So the input surface is drawn from the first vertices, as in the seed
//! framework, even where TetGen split a surface triangle.

use crate::geometry::tet_volume;
use crate::mesh::Mesh;
use glam::DVec3;

/// Why a surface could not be filled.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TetrahedralizeError {
    /// TetGen refused the surface or failed.
    #[error("TetGen could not fill the surface ({0}); it must be closed, without holes or self-intersections")]
    TetGen(String),
    /// The input has no triangles, or too few points.
    #[error("cannot tetrahedralize: {0}")]
    BadInput(String),
}

/// Tetrahedra filling the closed surface `mesh` (its triangles), with TetGen's default quality
/// bound (radius-edge ratio 2) and, if given, a largest tetrahedron volume (in the mesh's
/// units³). See the [module docs](self) for the vertex numbering.
///
/// # Errors
/// [`TetrahedralizeError`] for an open or self-intersecting surface, or an empty one.
pub fn tetrahedralize(mesh: &Mesh, max_volume: Option<f64>) -> Result<Mesh, TetrahedralizeError> {
    if mesh.triangles.is_empty() {
        return Err(TetrahedralizeError::BadInput("the mesh has no triangles".into()));
    }
    // TetGen drops points no facet uses ("jettison"), which would shift indices: give it only
    // the surface's vertices, numbered densely, and map back.
    let n = mesh.num_vertices();
    let mut compact = vec![u32::MAX; n];
    let mut original = Vec::new();
    for &v in mesh.triangles.iter().flatten() {
        if compact[v as usize] == u32::MAX {
            compact[v as usize] = original.len() as u32;
            original.push(v);
        }
    }
    let tetgen_error = |e: &str| TetrahedralizeError::TetGen(e.to_string());
    let mut tetgen =
        tritet::Tetgen::new(original.len(), Some(vec![3; mesh.num_triangles()]), None, None).map_err(tetgen_error)?;
    for (i, &v) in original.iter().enumerate() {
        let p = mesh.positions[v as usize];
        tetgen.set_point(i, 0, p.x, p.y, p.z).map_err(tetgen_error)?;
    }
    for (f, t) in mesh.triangles.iter().enumerate() {
        for (m, &v) in t.iter().enumerate() {
            tetgen.set_facet_point(f, m, compact[v as usize] as usize).map_err(tetgen_error)?;
        }
    }
    tetgen.generate_mesh(false, false, max_volume, None).map_err(tetgen_error)?;

    let m = original.len();
    let out_points = tetgen.out_npoint();
    if out_points < m {
        return Err(TetrahedralizeError::TetGen(format!(
            "it returned {out_points} points for the {m} of the surface, so no solid"
        )));
    }
    // TetGen numbers the input points first; check it kept them in place.
    for (i, &v) in original.iter().enumerate() {
        let p = DVec3::new(tetgen.out_point(i, 0), tetgen.out_point(i, 1), tetgen.out_point(i, 2));
        if p != mesh.positions[v as usize] {
            return Err(TetrahedralizeError::TetGen(format!("input point {i} moved or was renumbered")));
        }
    }
    let mut positions = mesh.positions.clone();
    positions.extend(
        (m..out_points).map(|i| DVec3::new(tetgen.out_point(i, 0), tetgen.out_point(i, 1), tetgen.out_point(i, 2))),
    );
    let map = |i: usize| if i < m { original[i] } else { (n + i - m) as u32 };
    let tetrahedra: Vec<[u32; 4]> = (0..tetgen.out_ncell())
        .map(|c| {
            let mut t = [0, 1, 2, 3].map(|k| map(tetgen.out_cell_point(c, k)));
            let p = t.map(|v| positions[v as usize]);
            if tet_volume(p[0], p[1], p[2], p[3]) < 0.0 {
                t.swap(2, 3);
            }
            t
        })
        .collect();
    // The input's faces and attributes stay: its vertices keep their indices.
    let mut filled = mesh.with_positions(positions);
    filled.tetrahedra = tetrahedra;
    filled.validate().map_err(|e| TetrahedralizeError::TetGen(format!("invalid output: {e}")))?;
    Ok(filled)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_closed_box_is_filled_and_keeps_its_vertices_first() {
        // The boundary of a tet box, as a plain surface, plus one unused vertex in front.
        let solid = crate::generate::tet_box([2, 2, 2], DVec3::ONE);
        let mut positions = vec![DVec3::new(5.0, 5.0, 5.0)];
        positions.extend(&solid.positions);
        let triangles: Vec<[u32; 3]> = solid.triangles.iter().map(|t| t.map(|v| v + 1)).collect();
        let surface = Mesh::new(positions.clone(), triangles.clone()).unwrap_or_else(|e| panic!("{e}"));
        let filled = tetrahedralize(&surface, None).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(&filled.positions[..positions.len()], &positions[..], "input vertices first, unchanged");
        assert_eq!(filled.triangles, triangles);
        let volume: f64 = filled
            .tetrahedra
            .iter()
            .map(|t| {
                let p = t.map(|v| filled.positions[v as usize]);
                let v = tet_volume(p[0], p[1], p[2], p[3]);
                assert!(v > 0.0);
                v
            })
            .sum();
        assert!((volume - 1.0).abs() < 1e-9, "the tets fill the unit box: {volume}");
        assert!(filled.tetrahedra.iter().flatten().all(|&v| v != 0), "the unused vertex is in no tet");
    }

    #[test]
    fn an_open_surface_is_an_error() {
        let open = Mesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z], vec![[0, 2, 1], [0, 1, 3]])
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(tetrahedralize(&open, None).is_err());
    }
}
