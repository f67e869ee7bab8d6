//! The measurements behind [`MeshInfo::of`]: counts, pieces, the surface's boundary and
//! manifoldness, degenerate elements and the volume, each relative to the mesh's scale.

use glam::DVec3;
use rayon::prelude::*;

use super::{
    BoundingBox, Counts, Degenerate, Found, MeshInfo, Pieces, RELATIVE_TOLERANCE, Surface, UnitsGuess, Volume,
};
use crate::geometry::{tet_volume, triangle_area};
use crate::mesh::{Mesh, Polygons};
use crate::topology::{connected_pieces, polygon_edges, tetrahedron_boundary, tetrahedron_edges, unique_edges};

impl MeshInfo {
    /// [`MeshInfo::of`] a mesh read from a file, with what only the file says: its left-handed
    /// tetrahedra ([`Volume::left_handed_tetrahedra`]) and physical groups.
    pub fn of_loaded(loaded: &crate::io::LoadedMesh) -> MeshInfo {
        let mut info = MeshInfo::of(&loaded.mesh);
        info.physical_groups = loaded
            .attributes
            .physical_groups()
            .iter()
            .map(|g| super::PhysicalGroupInfo {
                name: g.label(),
                dimension: g.dim,
                tag: g.tag,
                vertices: g.vertices.len(),
            })
            .collect();
        if let (Some(volume), Some(order)) = (&mut info.volume, loaded.attributes.tetrahedron_order()) {
            for &t in &order.left_handed {
                volume.left_handed_tetrahedra.add(t);
            }
        }
        info
    }

    /// Inspects `mesh`. Never panics on a mesh that passes [`Mesh::validate`] (faces may repeat
    /// corners or have 1–2 corners). [O(c log c) for c corners; see the [module docs](super)]
    pub fn of(mesh: &Mesh) -> MeshInfo {
        let bounding_box = bounding_box(mesh);
        let scale = bounding_box.diagonal;
        let tolerance = Tolerances {
            area: RELATIVE_TOLERANCE * scale * scale,
            length: RELATIVE_TOLERANCE * scale,
            volume: RELATIVE_TOLERANCE * scale * scale * scale,
        };
        let edges = all_edges(mesh);
        let (surface, merged) = surface(mesh);
        let degenerate = degenerate(mesh, &edges, &tolerance);
        let volume = (!mesh.tetrahedra.is_empty()).then(|| volume(mesh));
        let genus_ok = degenerate.faces_repeating_a_corner.count == 0;
        let referenced = referenced(mesh);
        MeshInfo {
            counts: counts(mesh, &referenced, edges.len()),
            pieces: pieces(mesh, &referenced),
            surface: surface.finish(mesh, &merged, genus_ok),
            volume,
            degenerate,
            units_guess: UnitsGuess::from_diagonal(scale),
            physical_groups: Vec::new(),
            bounding_box,
        }
    }
}

struct Tolerances {
    area: f64,
    length: f64,
    volume: f64,
}

fn bounding_box(mesh: &Mesh) -> BoundingBox {
    let (min, max) = if mesh.positions.is_empty() { (DVec3::ZERO, DVec3::ZERO) } else { mesh.bounding_box() };
    let size = max - min;
    BoundingBox { min: min.to_array(), max: max.to_array(), size: size.to_array(), diagonal: size.length() }
}

/// Unique undirected edges of the faces and the tetrahedra, sorted.
fn all_edges(mesh: &Mesh) -> Vec<[u32; 2]> {
    let mut edges = polygon_edges(mesh.polygons.iter());
    if !mesh.tetrahedra.is_empty() {
        edges.extend(tetrahedron_edges(&mesh.tetrahedra));
        edges.sort_unstable();
        edges.dedup();
    }
    edges
}

/// Whether each vertex is a corner of a face, triangle or tetrahedron.
fn referenced(mesh: &Mesh) -> Vec<bool> {
    let mut referenced = vec![false; mesh.num_vertices()];
    let corners =
        mesh.polygons.indices().iter().chain(mesh.triangles.as_flattened()).chain(mesh.tetrahedra.as_flattened());
    for &v in corners {
        referenced[v as usize] = true;
    }
    referenced
}

fn counts(mesh: &Mesh, referenced: &[bool], edges: usize) -> Counts {
    let mut by_size = [0usize; 4]; // under 3, 3, 4, more
    for face in mesh.polygons.iter() {
        by_size[face.len().clamp(2, 5) - 2] += 1;
    }
    let mut triangulated = vec![false; mesh.num_polygons()];
    for &p in &mesh.triangle_polygon {
        triangulated[p as usize] = true;
    }
    Counts {
        vertices: mesh.num_vertices(),
        unreferenced_vertices: referenced.iter().filter(|&&r| !r).count(),
        faces: mesh.num_polygons(),
        triangles: by_size[1],
        quads: by_size[2],
        ngons: by_size[3],
        faces_under_3_corners: by_size[0],
        triangulation_triangles: mesh.num_triangles(),
        faces_not_triangulated: triangulated.iter().filter(|&&t| !t).count(),
        tetrahedra: mesh.num_tetrahedra(),
        edges,
    }
}

fn pieces(mesh: &Mesh, referenced: &[bool]) -> Pieces {
    let links = mesh
        .polygons
        .iter()
        .chain(mesh.triangles.iter().map(|t| t.as_slice()))
        .chain(mesh.tetrahedra.iter().map(|t| t.as_slice()));
    let (label, count) = connected_pieces(mesh.num_vertices(), links);
    let mut size = vec![0usize; count];
    for (v, &l) in label.iter().enumerate() {
        if referenced[v] {
            size[l as usize] += 1;
        }
    }
    Pieces {
        pieces: size.iter().filter(|&&s| s > 0).count(),
        largest_piece_vertices: size.into_iter().max().unwrap_or(0),
    }
}

/// The faces with repeated neighbouring corners merged, those left with 3 corners or more.
fn merged_faces(polygons: &Polygons) -> Polygons {
    let mut merged = Polygons::new();
    let mut corners: Vec<u32> = Vec::new();
    for face in polygons.iter() {
        corners.clear();
        for &v in face {
            if corners.last() != Some(&v) {
                corners.push(v);
            }
        }
        while corners.len() > 1 && corners.first() == corners.last() {
            corners.pop();
        }
        if corners.len() >= 3 {
            merged.push(&corners);
        }
    }
    merged
}

/// What [`surface`] finds before the triangulation's area and the genus are added.
struct SurfaceParts {
    faces: usize,
    edges: usize,
    boundary: Vec<[u32; 2]>,
    non_manifold_edges: Found<[u32; 2]>,
    inconsistent: Found<[u32; 2]>,
}

fn surface(mesh: &Mesh) -> (SurfaceParts, Polygons) {
    let merged = merged_faces(&mesh.polygons);
    // Every side once, as (undirected edge, runs from the larger vertex to the smaller).
    let mut sides: Vec<([u32; 2], bool)> = merged
        .iter()
        .flat_map(|f| (0..f.len()).map(move |k| (f[k], f[(k + 1) % f.len()])))
        .map(|(a, b)| ([a.min(b), a.max(b)], a > b))
        .collect();
    sides.par_sort_unstable();
    let mut parts = SurfaceParts {
        faces: merged.len(),
        edges: 0,
        boundary: Vec::new(),
        non_manifold_edges: Found::default(),
        inconsistent: Found::default(),
    };
    for group in sides.chunk_by(|x, y| x.0 == y.0) {
        parts.edges += 1;
        let edge = group[0].0;
        match group {
            [_] => parts.boundary.push(edge),
            [(_, a), (_, b)] => {
                if a == b {
                    parts.inconsistent.add(edge);
                }
            }
            _ => parts.non_manifold_edges.add(edge),
        }
    }
    (parts, merged)
}

impl SurfaceParts {
    fn finish(self, mesh: &Mesh, merged: &Polygons, repeat_free: bool) -> Surface {
        let n = mesh.num_vertices();
        let mut used = vec![false; n];
        for &v in merged.indices() {
            used[v as usize] = true;
        }
        let vertices = used.iter().filter(|&&u| u).count();
        let (label, _) = connected_pieces(n, merged.iter());
        let pieces = count_labels(&label, used.iter().copied());
        let (label, _) = connected_pieces(n, self.boundary.iter().map(|e| e.as_slice()));
        let mut on_boundary = vec![false; n];
        for &v in self.boundary.as_flattened() {
            on_boundary[v as usize] = true;
        }
        let boundary_loops = count_labels(&label, on_boundary.into_iter());
        let non_manifold_vertices = non_manifold_vertices(merged);
        let euler_characteristic = vertices as i64 - self.edges as i64 + self.faces as i64;
        let manifold = self.non_manifold_edges.count == 0
            && non_manifold_vertices.count == 0
            && self.inconsistent.count == 0
            && repeat_free;
        // χ = 2c − 2g − b for c orientable pieces with b boundary loops in all.
        let twice_genus = 2 * pieces as i64 - boundary_loops as i64 - euler_characteristic;
        let genus = (manifold && twice_genus >= 0 && twice_genus % 2 == 0).then_some(twice_genus as u64 / 2);
        let area = mesh
            .triangles
            .iter()
            .map(|t| {
                triangle_area(
                    mesh.positions[t[0] as usize],
                    mesh.positions[t[1] as usize],
                    mesh.positions[t[2] as usize],
                )
            })
            .sum();
        Surface {
            faces: self.faces,
            vertices,
            edges: self.edges,
            area,
            pieces,
            boundary_edges: self.boundary.len(),
            boundary_loops,
            closed: self.faces > 0 && self.boundary.is_empty(),
            non_manifold_edges: self.non_manifold_edges,
            non_manifold_vertices,
            inconsistent_orientation_edges: self.inconsistent,
            euler_characteristic,
            genus,
        }
    }
}

/// Number of distinct labels among the vertices where `member` is true.
fn count_labels(label: &[u32], member: impl Iterator<Item = bool>) -> usize {
    let mut seen = vec![false; label.len()];
    let mut count = 0;
    for (&l, m) in label.iter().zip(member) {
        if m && !std::mem::replace(&mut seen[l as usize], true) {
            count += 1;
        }
    }
    count
}

/// Vertices whose link (for each face corner at the vertex, the undirected pair of its two
/// neighbouring corners) is not a single path or cycle: some link vertex has more than two link
/// edges, or the link falls apart. [O(c log c): one sort of all corners, then each vertex's
/// own links]
fn non_manifold_vertices(merged: &Polygons) -> Found<u32> {
    let mut links: Vec<(u32, u32, u32)> = merged
        .iter()
        .flat_map(|f| {
            let k = f.len();
            (0..k).map(move |i| {
                let (prev, next) = (f[(i + k - 1) % k], f[(i + 1) % k]);
                (f[i], prev.min(next), prev.max(next))
            })
        })
        .collect();
    links.par_sort_unstable();
    let mut found = Found::default();
    let mut nodes: Vec<u32> = Vec::new();
    let mut local: Vec<[u32; 2]> = Vec::new();
    for group in links.chunk_by(|x, y| x.0 == y.0) {
        let v = group[0].0;
        nodes.clear();
        nodes.extend(group.iter().flat_map(|&(_, a, b)| [a, b]));
        nodes.sort_unstable();
        // Degree of each link vertex: the length of its run in the sorted endpoints.
        let branched = nodes.chunk_by(|a, b| a == b).any(|run| run.len() > 2);
        nodes.dedup();
        let single = !branched && {
            let index = |x: u32| nodes.binary_search(&x).unwrap_or(0) as u32;
            local.clear();
            local.extend(group.iter().map(|&(_, a, b)| [index(a), index(b)]));
            connected_pieces(nodes.len(), local.iter().map(|e| e.as_slice())).1 == 1
        };
        if !single {
            found.add(v);
        }
    }
    found
}

fn degenerate(mesh: &Mesh, edges: &[[u32; 2]], tolerance: &Tolerances) -> Degenerate {
    let p = |v: u32| mesh.positions[v as usize];
    let mut zero_area_faces = Found::default();
    let mut repeating = Found::default();
    let mut sorted: Vec<u32> = Vec::new();
    for (i, face) in mesh.polygons.iter().enumerate() {
        sorted.clear();
        sorted.extend_from_slice(face);
        sorted.sort_unstable();
        if sorted.windows(2).any(|w| w[0] == w[1]) {
            repeating.add(i as u32);
        }
        if let Some((&first, _)) = face.split_first().filter(|_| face.len() >= 3) {
            let origin = p(first);
            let twice: DVec3 = (1..face.len() - 1).map(|k| (p(face[k]) - origin).cross(p(face[k + 1]) - origin)).sum();
            if 0.5 * twice.length() <= tolerance.area {
                zero_area_faces.add(i as u32);
            }
        }
    }
    let mut zero_area_triangles = Found::default();
    for (i, t) in mesh.triangles.iter().enumerate() {
        if triangle_area(p(t[0]), p(t[1]), p(t[2])) <= tolerance.area {
            zero_area_triangles.add(i as u32);
        }
    }
    let mut zero_length_edges = Found::default();
    for &[a, b] in edges {
        if p(a).distance(p(b)) <= tolerance.length {
            zero_length_edges.add([a, b]);
        }
    }
    let (mut flat, mut inverted) = (Found::default(), Found::default());
    for (i, t) in mesh.tetrahedra.iter().enumerate() {
        let v = tet_volume(p(t[0]), p(t[1]), p(t[2]), p(t[3]));
        if v.abs() <= tolerance.volume {
            flat.add(i as u32);
        } else if v < 0.0 {
            inverted.add(i as u32);
        }
    }
    Degenerate {
        area_tolerance: tolerance.area,
        length_tolerance: tolerance.length,
        volume_tolerance: tolerance.volume,
        zero_area_faces,
        zero_area_triangles,
        faces_repeating_a_corner: repeating,
        zero_length_edges,
        flat_tetrahedra: flat,
        inverted_tetrahedra: inverted,
    }
}

fn volume(mesh: &Mesh) -> Volume {
    let p = |v: u32| mesh.positions[v as usize];
    let total = mesh.tetrahedra.iter().map(|t| tet_volume(p(t[0]), p(t[1]), p(t[2]), p(t[3]))).sum();
    let boundary = tetrahedron_boundary(&mesh.tetrahedra);
    let (_, edge_faces) = unique_edges(&boundary);
    let open = edge_faces.iter().filter(|&&c| c == 1).count();
    let mut faces: Vec<[u32; 3]> = mesh
        .tetrahedra
        .iter()
        .flat_map(|&[a, b, c, d]| [[b, c, d], [a, c, d], [a, b, d], [a, b, c]])
        .map(|mut f| {
            f.sort_unstable();
            f
        })
        .collect();
    faces.par_sort_unstable();
    Volume {
        volume: total,
        boundary_faces: boundary.len(),
        boundary_open_edges: open,
        boundary_non_manifold_edges: edge_faces.iter().filter(|&&c| c > 2).count(),
        boundary_closed: !boundary.is_empty() && open == 0,
        faces_in_more_than_two_tetrahedra: faces.chunk_by(|a, b| a == b).filter(|g| g.len() > 2).count(),
        left_handed_tetrahedra: Found::default(),
    }
}
