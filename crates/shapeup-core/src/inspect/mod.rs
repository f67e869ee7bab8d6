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
//!
//! The report's types are here; [`MeshInfo::of`] measures (in `measure.rs`), its
//! [`Display`](std::fmt::Display) text is in `text.rs`.

mod measure;
mod text;

use std::fmt;

use serde::Serialize;

#[cfg(doc)]
use crate::{geometry::tet_volume, mesh::Mesh, topology::tetrahedron_boundary};

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
    /// A `.msh` file's physical groups, which scenes select with `physical = "NAME"` (empty
    /// for other files and for [`MeshInfo::of`] a bare mesh).
    pub physical_groups: Vec<PhysicalGroupInfo>,
}

/// A physical group of a `.msh` file, as `info` lists it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct PhysicalGroupInfo {
    /// Its name, or for an unnamed group its tag as text: what `physical = "…"` takes.
    pub name: String,
    /// Dimension of its elements (0 points … 3 volumes).
    pub dimension: i32,
    /// Its tag.
    pub tag: i64,
    /// Vertices of its elements.
    pub vertices: usize,
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
    /// Tetrahedra the file lists left-handed (negative volume in its node order), by index: the
    /// readers turn them right-handed for the solver and the writers back
    /// ([`crate::io::TetrahedronOrder`]). Filled by [`MeshInfo::of_loaded`]; 0 from
    /// [`MeshInfo::of`], which sees the mesh as the solver does.
    pub left_handed_tetrahedra: Found<u32>,
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
