//! What a mesh is made of: counts, pieces, boundary loops, degenerate and non-manifold elements,
//! bounding box and a units guess ([`MeshInfo::of`]), printed by `shapeup info MESH` (its
//! [`Display`](std::fmt::Display) text, or `--json` through [`serde::Serialize`]).
//!
//! # Which elements each part looks at
//! - The **surface** is the mesh's faces as read ([`Mesh::polygons`]), each with repeated
//!   neighbouring corners merged (`a b b c` → `a b c`, also across the end, as the triangulation
//!   does); a face left with fewer than 3 corners is not part of it. A *side* is a pair of
//!   neighbouring corners; an edge is a side's undirected vertex pair, and the number of faces an
//!   edge is "used by" counts its sides (a bridge edge that one face runs along twice counts 2).
//! - The **triangulation** ([`Mesh::triangles`], what the solver uses) is checked for zero-area
//!   triangles and gives the surface area.
//! - The **tetrahedra** ([`Mesh::tetrahedra`]) are checked for flat and inverted elements and for
//!   a closed boundary ([`tetrahedron_boundary`]).
//! - **Pieces** join the corners of every face (of any size), triangle and tetrahedron.
//!
//! # Tolerances
//! Degeneracy is relative to the mesh's scale L, the diagonal of its bounding box, so that a
//! mesh means the same in any unit: a face or triangle has zero area when A ≤ 1e-12·L², an edge
//! zero length when ℓ ≤ 1e-12·L, a tetrahedron is flat when |V| ≤ 1e-12·L³ and inverted when
//! V < −1e-12·L³ (V signed, positive for the orientation of [`tet_volume`]). The factor 1e-12
//! leaves four orders of magnitude above f64 round-off (≈ 1e-16 relative) for coordinates that
//! went through text files and transforms, and is far below any element a modeller or mesher
//! makes on purpose. For a mesh whose vertices all coincide (L = 0) every element is degenerate.
//!
//! # Cost
//! O(c log c) for c corners of faces, triangles and tetrahedra: edges are found by sorting
//! (no per-element search), per-vertex checks sort that vertex's own corners.

use std::fmt;

use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

use crate::geometry::{tet_volume, triangle_area};
use crate::mesh::{Mesh, Polygons};
use crate::topology::{connected_pieces, polygon_edges, tetrahedron_boundary, tetrahedron_edges, unique_edges};

/// Relative tolerance of the degeneracy tests (see the [module docs](self)).
pub const RELATIVE_TOLERANCE: f64 = 1e-12;

/// How many examples each [`Found`] keeps.
pub const EXAMPLES: usize = 5;

/// A summary of a mesh's contents and defects; see the [module docs](self) for which elements
/// each part looks at and for the tolerances.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshInfo {
    /// Element counts.
    pub counts: Counts,
    /// Connected pieces.
    pub pieces: Pieces,
    /// Boundary, manifoldness, orientation and topology of the surface (the faces).
    pub surface: Surface,
    /// The tetrahedra's volume and boundary; `None` for a mesh without tetrahedra.
    pub volume: Option<Volume>,
    /// Degenerate elements and the tolerances used.
    pub degenerate: Degenerate,
    /// Axis-aligned bounding box of all vertices (unreferenced ones included).
    pub bounding_box: BoundingBox,
    /// A guess at the length unit from the bounding box's diagonal (see [`UnitsGuess`]).
    pub units_guess: UnitsGuess,
}

/// Element counts.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Counts {
    /// Vertices (positions), in file order.
    pub vertices: usize,
    /// Vertices used by no face, triangle or tetrahedron.
    pub unreferenced_vertices: usize,
    /// Faces as read ([`Mesh::polygons`]), of any size.
    pub faces: usize,
    /// Faces with exactly 3 corners (as stored: repeated corners count).
    pub triangles: usize,
    /// Faces with exactly 4 corners.
    pub quads: usize,
    /// Faces with more than 4 corners.
    pub ngons: usize,
    /// Faces with 1 or 2 corners (points and segments some files carry; not part of the surface).
    pub faces_under_3_corners: usize,
    /// Triangles of the triangulation ([`Mesh::triangles`]), which the solver uses.
    pub triangulation_triangles: usize,
    /// Faces that have no triangle in the triangulation (fewer than 3 distinct corners, or a
    /// vertex repeated; see [`Mesh::from_polygons`]).
    pub faces_not_triangulated: usize,
    /// Tetrahedra.
    pub tetrahedra: usize,
    /// Unique undirected edges: the sides of the faces (not the triangulation's diagonals; a side
    /// from a corner to itself is skipped) and the six edges of each tetrahedron.
    pub edges: usize,
}

/// Connected pieces.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Pieces {
    /// Pieces: sets of vertices joined through faces, triangles and tetrahedra (two elements
    /// sharing a vertex are in one piece). Unreferenced vertices are not counted here (see
    /// [`Counts::unreferenced_vertices`]).
    pub pieces: usize,
    /// Vertices in the largest piece (0 when there are none).
    pub largest_piece_vertices: usize,
}

/// Boundary, manifoldness, orientation and topology of the surface: the faces with at least 3
/// corners once repeated neighbouring corners are merged.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Surface {
    /// Faces of the surface.
    pub faces: usize,
    /// Vertices used by them.
    pub vertices: usize,
    /// Unique undirected edges (sides) of them.
    pub edges: usize,
    /// Total area of the triangulation, Σ ½‖(b − a) × (c − a)‖.
    pub area: f64,
    /// Pieces of the surface alone (faces joined through shared vertices).
    pub pieces: usize,
    /// Edges used by exactly one face.
    pub boundary_edges: usize,
    /// Boundary loops: connected sets of boundary edges. Two holes that touch at a vertex (only
    /// possible at a non-manifold vertex) count as one.
    pub boundary_loops: usize,
    /// Whether the surface has faces and no boundary edge (watertight).
    pub closed: bool,
    /// Edges used by more than two faces (fins), as vertex pairs `[i, j]`, `i < j`.
    pub non_manifold_edges: Found<[u32; 2]>,
    /// Vertices whose faces do not form one fan (a disc, or a half-disc on the boundary): the
    /// link — the sides opposite the vertex in its faces, joined end to end — is not one path
    /// or one cycle. Includes the ends of non-manifold edges and bow-tie (pinched) vertices.
    pub non_manifold_vertices: Found<u32>,
    /// Edges of exactly two faces that run along them in the same direction (neighbouring faces
    /// oriented inconsistently).
    pub inconsistent_orientation_edges: Found<[u32; 2]>,
    /// Euler characteristic χ = V − E + F of the surface (its vertices, edges and faces above).
    pub euler_characteristic: i64,
    /// Total genus g (number of handles, summed over the surface's pieces), from
    /// χ = 2·pieces − 2g − boundary loops. `None` unless the surface is a consistently oriented
    /// manifold (no non-manifold edge or vertex, no inconsistent edge) whose faces repeat no
    /// vertex, where the formula holds.
    pub genus: Option<u64>,
}

/// The tetrahedra's volume and boundary surface.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Volume {
    /// Sum of the signed volumes V = (b − a)·((c − a) × (d − a))/6.
    pub volume: f64,
    /// Boundary faces: triangles that belong to exactly one tetrahedron ([`tetrahedron_boundary`]).
    pub boundary_faces: usize,
    /// Edges of the boundary faces that belong to only one of them (holes in the boundary).
    pub boundary_open_edges: usize,
    /// Edges of the boundary faces that belong to more than two of them (tetrahedra touching
    /// along an edge only).
    pub boundary_non_manifold_edges: usize,
    /// Whether the boundary surface is closed: it has faces and no open edge.
    pub boundary_closed: bool,
    /// Triangles shared by more than two tetrahedra (each triangle once).
    pub faces_in_more_than_two_tetrahedra: usize,
}

/// Degenerate elements, with the tolerances used (absolute, from the mesh's scale L; see the
/// [module docs](self)).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Degenerate {
    /// Area below or at which a face or triangle counts as zero-area: 1e-12·L².
    pub area_tolerance: f64,
    /// Length below or at which an edge counts as zero-length: 1e-12·L.
    pub length_tolerance: f64,
    /// Volume magnitude below or at which a tetrahedron counts as flat: 1e-12·L³.
    pub volume_tolerance: f64,
    /// Faces (of at least 3 corners) whose vector area ½‖Σ (p_i − p_0) × (p_{i+1} − p_0)‖ is at
    /// most the area tolerance (collinear corners, or a polygon folded onto itself), by face index.
    pub zero_area_faces: Found<u32>,
    /// Triangles of the triangulation with area at most the area tolerance, by triangle index.
    pub zero_area_triangles: Found<u32>,
    /// Faces in which a vertex appears more than once, by face index.
    pub faces_repeating_a_corner: Found<u32>,
    /// Edges (of [`Counts::edges`]) between two distinct vertices at most the length tolerance
    /// apart (duplicated vertices joined by an edge).
    pub zero_length_edges: Found<[u32; 2]>,
    /// Tetrahedra with |V| at most the volume tolerance, by index (also those repeating a corner).
    pub flat_tetrahedra: Found<u32>,
    /// Tetrahedra with V below minus the volume tolerance (inside out), by index.
    pub inverted_tetrahedra: Found<u32>,
}

/// Axis-aligned bounding box of all vertices.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BoundingBox {
    /// Smallest x, y, z.
    pub min: [f64; 3],
    /// Largest x, y, z.
    pub max: [f64; 3],
    /// max − min.
    pub size: [f64; 3],
    /// Length of the diagonal, ‖max − min‖: the mesh's scale L.
    pub diagonal: f64,
}

/// How many elements of one kind were found, with the first few ([`EXAMPLES`], in index order,
/// 0-based).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Found<T> {
    /// How many.
    pub count: usize,
    /// The first few.
    pub first: Vec<T>,
}

impl<T> Default for Found<T> {
    fn default() -> Self {
        Found { count: 0, first: Vec::new() }
    }
}

impl<T> Found<T> {
    fn add(&mut self, item: T) {
        self.count += 1;
        if self.first.len() < EXAMPLES {
            self.first.push(item);
        }
    }
}

/// A guess at the length unit from the bounding box's diagonal d, assuming the mesh is an
/// object of everyday size (about 5 cm to 5 m, what people mostly model and scan) in one of the
/// usual units. Each range is that span of sizes written in a unit; files carry no unit, so this
/// is a guess, never a fact.
///
/// | d | guess |
/// |---|---|
/// | 0 | [`UnitsGuess::Point`] |
/// | (0, 0.05) | [`UnitsGuess::Small`] |
/// | [0.05, 5] | [`UnitsGuess::MetresOrNormalized`] |
/// | (5, 500] | [`UnitsGuess::CentimetresOrInches`] |
/// | (500, 50 000] | [`UnitsGuess::Millimetres`] |
/// | above 50 000 | [`UnitsGuess::Large`] |
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum UnitsGuess {
    /// Every vertex at one point: no size.
    Point,
    /// Below 0.05: metres for a small part (under 5 cm), or kilometres, or scaled down.
    Small,
    /// 0.05 to 5: metres, or a mesh normalized to about unit size (scanned and research meshes).
    MetresOrNormalized,
    /// 5 to 500: centimetres or inches (5 cm to 5 m, 2 in to 40 ft).
    CentimetresOrInches,
    /// 500 to 50 000: millimetres (CAD and 3D printing; 0.5 m to 50 m).
    Millimetres,
    /// Above 50 000: millimetres for a large structure, or survey/geographic coordinates.
    Large,
}

impl UnitsGuess {
    /// The guess for a bounding-box diagonal (see the table on [`UnitsGuess`]).
    pub fn from_diagonal(diagonal: f64) -> Self {
        match diagonal {
            d if d <= 0.0 => Self::Point,
            d if d < 0.05 => Self::Small,
            d if d <= 5.0 => Self::MetresOrNormalized,
            d if d <= 500.0 => Self::CentimetresOrInches,
            d if d <= 50_000.0 => Self::Millimetres,
            _ => Self::Large,
        }
    }
}

impl fmt::Display for UnitsGuess {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Point => "none (every vertex at one point)",
            Self::Small => "small: metres for a part under 5 cm, or scaled down (diagonal under 0.05)",
            Self::MetresOrNormalized => "metres, or normalized to unit size (diagonal 0.05 to 5)",
            Self::CentimetresOrInches => "centimetres or inches (diagonal 5 to 500)",
            Self::Millimetres => "millimetres (diagonal 500 to 50,000)",
            Self::Large => "large: millimetres for a big structure, or survey coordinates (diagonal over 50,000)",
        })
    }
}

impl MeshInfo {
    /// Inspects `mesh`. Never panics on a mesh that passes [`Mesh::validate`] (faces may repeat
    /// corners or have 1–2 corners). [O(c log c) for c corners; see the [module docs](self)]
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
    }
}

/// `12 (e.g. 3, 40, 77)`, or `0`.
struct Shown<'a, T>(&'a Found<T>, fn(&T) -> String);

impl<T> fmt::Display for Shown<'_, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0.count)?;
        if !self.0.first.is_empty() {
            let shown: Vec<String> = self.0.first.iter().map(self.1).collect();
            let more = if self.0.count > self.0.first.len() { ", …" } else { "" };
            write!(f, " (first: {}{more})", shown.join(", "))?;
        }
        Ok(())
    }
}

fn index(i: &u32) -> String {
    i.to_string()
}

fn pair(e: &[u32; 2]) -> String {
    format!("{}–{}", e[0], e[1])
}

fn triple(v: &[f64; 3]) -> String {
    format!("({}, {}, {})", number(v[0]), number(v[1]), number(v[2]))
}

/// Six significant digits, without trailing noise.
fn number(x: f64) -> String {
    if x == 0.0 || (1e-4..1e7).contains(&x.abs()) {
        let digits = (5 - x.abs().log10().floor().max(-5.0) as i32).clamp(0, 10) as usize;
        let s = format!("{x:.digits$}");
        if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
    } else {
        let s = format!("{x:.5e}");
        match s.split_once('e') {
            Some((mantissa, exponent)) if mantissa.contains('.') => {
                format!("{}e{exponent}", mantissa.trim_end_matches('0').trim_end_matches('.'))
            }
            _ => s,
        }
    }
}

fn plural(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// The summary `shapeup info` prints: one aspect per line, a label then the values; element
/// indices are 0-based as in scenes.
impl fmt::Display for MeshInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (c, s, d) = (&self.counts, &self.surface, &self.degenerate);
        writeln!(f, "vertices:        {} ({} unreferenced)", c.vertices, c.unreferenced_vertices)?;
        write!(
            f,
            "faces:           {}: {}, {}, {}",
            c.faces,
            plural(c.triangles, "triangle", "triangles"),
            plural(c.quads, "quad", "quads"),
            plural(c.ngons, "n-gon", "n-gons")
        )?;
        if c.faces_under_3_corners > 0 {
            write!(f, ", {} with 1 or 2 corners", c.faces_under_3_corners)?;
        }
        writeln!(f)?;
        write!(f, "triangulation:   {}", plural(c.triangulation_triangles, "triangle", "triangles"))?;
        if c.faces_not_triangulated > 0 {
            write!(f, " ({} not triangulated)", plural(c.faces_not_triangulated, "face", "faces"))?;
        }
        writeln!(f)?;
        writeln!(f, "tetrahedra:      {}", c.tetrahedra)?;
        writeln!(f, "edges:           {}", c.edges)?;
        writeln!(
            f,
            "pieces:          {} (largest: {} vertices)",
            self.pieces.pieces, self.pieces.largest_piece_vertices
        )?;
        writeln!(
            f,
            "boundary:        {}, {}{}",
            plural(s.boundary_loops, "loop", "loops"),
            plural(s.boundary_edges, "edge", "edges"),
            if s.closed { " (closed surface)" } else { "" }
        )?;
        writeln!(f, "non-manifold:    edges in 3+ faces {}", Shown(&s.non_manifold_edges, pair))?;
        writeln!(f, "                 vertices (not one fan) {}", Shown(&s.non_manifold_vertices, index))?;
        writeln!(
            f,
            "orientation:     edges run the same way by both faces {}",
            Shown(&s.inconsistent_orientation_edges, pair)
        )?;
        write!(
            f,
            "topology:        V − E + F = {} − {} + {} = χ {}",
            s.vertices, s.edges, s.faces, s.euler_characteristic
        )?;
        match s.genus {
            Some(g) => writeln!(f, ", genus {g}")?,
            None => writeln!(f, ", genus not defined (not an oriented manifold)")?,
        }
        writeln!(f, "surface area:    {}", number(s.area))?;
        if let Some(v) = &self.volume {
            writeln!(
                f,
                "volume:          {}; boundary {} faces, {}, {} open edges, {} non-manifold edges; {} faces in 3+ tetrahedra",
                number(v.volume),
                v.boundary_faces,
                if v.boundary_closed { "closed" } else { "not closed" },
                v.boundary_open_edges,
                v.boundary_non_manifold_edges,
                v.faces_in_more_than_two_tetrahedra
            )?;
        }
        writeln!(
            f,
            "degenerate:      zero-area faces {} (area ≤ {})",
            Shown(&d.zero_area_faces, index),
            number(d.area_tolerance)
        )?;
        writeln!(f, "                 zero-area triangles {}", Shown(&d.zero_area_triangles, index))?;
        writeln!(f, "                 faces repeating a corner {}", Shown(&d.faces_repeating_a_corner, index))?;
        writeln!(
            f,
            "                 zero-length edges {} (length ≤ {})",
            Shown(&d.zero_length_edges, pair),
            number(d.length_tolerance)
        )?;
        if c.tetrahedra > 0 {
            writeln!(
                f,
                "                 flat tetrahedra {} (|volume| ≤ {})",
                Shown(&d.flat_tetrahedra, index),
                number(d.volume_tolerance)
            )?;
            writeln!(f, "                 inverted tetrahedra {}", Shown(&d.inverted_tetrahedra, index))?;
        }
        let b = &self.bounding_box;
        writeln!(f, "bounding box:    min {} max {}", triple(&b.min), triple(&b.max))?;
        writeln!(f, "size:            {}, diagonal {}", triple(&b.size), number(b.diagonal))?;
        write!(f, "units (a guess): {}", self.units_guess)
    }
}
