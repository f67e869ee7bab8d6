//! What an MSH file's sections add up to: its nodes (positions and the index of each tag) and
//! the elements kept, then the mesh they make ([`finish`]; tetrahedra through
//! [`tetrahedral_mesh`], which the TetGen reader shares).

use std::collections::{BTreeSet, HashMap};
use std::path::Path;

use glam::DVec3;

use super::TETRAHEDRON;
use crate::io::records::Records;
use crate::io::{IoError, LoadedMesh, NotANumber, bounded_vec, build_mesh, parse_coordinate, shown};
use crate::mesh::{Mesh, MeshError};
use crate::topology::tetrahedron_boundary;

/// A tetrahedron is flat when |(b−a)·((c−a)×(d−a))| ≤ this × |b−a| |c−a| |d−a| (the sine-like
/// ratio is 1 for a right corner; only numerically flat ones fall below).
const FLAT_TOLERANCE: f64 = 1e-12;

/// The mesh from the nodes and elements read.
pub(super) fn finish(path: &Path, nodes: Nodes, elements: Elements, place: Place) -> Result<LoadedMesh, IoError> {
    if nodes.positions.is_empty() {
        return Err(IoError::Invalid { path: path.to_path_buf(), message: "no nodes (no $Nodes section)".to_owned() });
    }
    if !elements.tets.is_empty() {
        return tetrahedra_to_mesh(path, nodes.positions, elements.tets, &elements.tet_origins, "element", place);
    }
    if elements.triangles.is_empty() && !elements.skipped.is_empty() {
        let types: Vec<String> = elements.skipped.iter().map(usize::to_string).collect();
        return Err(IoError::Invalid {
            path: path.to_path_buf(),
            message: format!(
                "no 4-node tetrahedra (type 4) or 3-node triangles (type 2); the elements are of type {}",
                types.join(", ")
            ),
        });
    }
    // Triangles only (or a bare point cloud): a surface mesh.
    build_mesh(path, nodes.positions, elements.triangles.iter().map(|t| &t[..]).collect())
}

/// Nodes read so far: positions in file order and the index of each tag.
#[derive(Default)]
pub(super) struct Nodes {
    pub(super) positions: Vec<DVec3>,
    pub(super) index: HashMap<u64, u32>,
    /// Where each node's coordinates are, by index: the 1-based line (ASCII files) or the byte
    /// offset of its x (binary files).
    pub(super) origins: Vec<u64>,
}

impl Nodes {
    /// Room for the `count` nodes a header announces, within bounds (the first `$Nodes` only).
    pub(super) fn reserve(&mut self, count: u64) {
        if self.positions.is_empty() {
            self.positions = bounded_vec(usize::try_from(count).unwrap_or(usize::MAX));
        }
    }

    /// Gives `tag` the index after the positions read and `pending` tags still without one.
    ///
    /// # Errors
    /// [`NodeTagError`]: tag 0, a tag defined twice, or more nodes than a `u32` index holds.
    pub(super) fn add(&mut self, tag: u64, pending: u64) -> Result<(), NodeTagError> {
        if tag == 0 {
            return Err(NodeTagError::Zero);
        }
        let index = u64::try_from(self.positions.len()).ok().and_then(|n| n.checked_add(pending));
        let index = index.and_then(|i| u32::try_from(i).ok()).ok_or(NodeTagError::TooMany)?;
        if self.index.insert(tag, index).is_some() {
            return Err(NodeTagError::Twice(tag));
        }
        Ok(())
    }

    /// [`Self::add`] for a tag as text.
    pub(super) fn add_text<R>(&mut self, r: &Records<'_, R>, tag: &str, pending: u64) -> Result<u64, IoError> {
        let t = tag.parse::<u64>().ok().filter(|&t| t > 0);
        let t = t.ok_or_else(|| r.error(format!("node tag '{}' is not a positive integer", shown(tag))))?;
        self.add(t, pending).map_err(|e| r.error(e.to_string()))?;
        Ok(t)
    }

    /// The index of node `tag` as referenced by an element.
    pub(super) fn lookup<R>(&self, r: &Records<'_, R>, tag: &str, element: &str) -> Result<u32, IoError> {
        tag.parse::<u64>().ok().and_then(|t| self.index.get(&t).copied()).ok_or_else(|| {
            r.error(format!("element {}: node tag '{}' is not defined in $Nodes", shown(element), shown(tag)))
        })
    }
}

/// Why a node tag cannot be given an index ([`Nodes::add`]); the readers place it at its line
/// or byte offset.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub(super) enum NodeTagError {
    /// Tag 0 (tags are positive).
    #[error("node tag 0 is not a positive integer")]
    Zero,
    /// More nodes than a `u32` index holds.
    #[error("too many nodes (more than 2³² − 1)")]
    TooMany,
    /// A tag already given an index.
    #[error("node tag {0} is defined twice")]
    Twice(u64),
}

/// What is wrong with the `x y z` of a node or point ([`parse_point`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(in crate::io) enum PointError {
    /// Fewer than three tokens.
    #[error("no {axis} coordinate (expected 'x y z')")]
    Missing {
        /// `x`, `y` or `z`.
        axis: &'static str,
    },
    /// A token that is not a number (`{axis} coordinate '…' is not a number`).
    #[error(transparent)]
    NotANumber(#[from] NotANumber),
}

/// The first three of `tokens` as a point (the rest is ignored).
///
/// # Errors
/// [`PointError`] naming the coordinate that is missing or not a number.
pub(in crate::io) fn parse_point(tokens: &[&str]) -> Result<DVec3, PointError> {
    let mut xyz = [0.0; 3];
    for (i, (&axis, slot)) in ["x", "y", "z"].iter().zip(&mut xyz).enumerate() {
        let token = tokens.get(i).ok_or(PointError::Missing { axis })?;
        *slot = parse_coordinate(token, &format!("{axis} coordinate"))?;
    }
    Ok(DVec3::from_array(xyz))
}

/// Where an element was found: the line (ASCII files) or the byte offset (binary files).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Place {
    Line,
    Offset,
}

/// Elements kept so far and the types skipped.
#[derive(Default)]
pub(super) struct Elements {
    pub(super) tets: Vec<[u32; 4]>,
    /// Line (or byte offset) and tag of each tetrahedron, for errors.
    pub(super) tet_origins: Vec<(u64, u64)>,
    pub(super) triangles: Vec<[u32; 3]>,
    pub(super) skipped: BTreeSet<usize>,
    /// How many elements of the skipped types the file has.
    pub(super) other: usize,
    /// The vertices of each physical group's elements, by (dimension, tag).
    pub(super) physical: HashMap<(i32, i64), Vec<u32>>,
}

impl Elements {
    /// Adds `vertices` (of an element of dimension `dim`) to each physical group of `groups`.
    pub(super) fn add_to_groups(&mut self, dim: i32, groups: &[i64], vertices: &[u32]) {
        for &g in groups {
            self.physical.entry((dim, g)).or_default().extend_from_slice(vertices);
        }
    }

    /// Keeps element `id` of `kind` (a tetrahedron or a triangle) with vertices `v`, found at
    /// `origin` (a line or byte offset).
    pub(super) fn push(&mut self, kind: usize, id: u64, v: [u32; 4], origin: u64) {
        if kind == TETRAHEDRON {
            self.tets.push(v);
            self.tet_origins.push((origin, id));
        } else {
            self.triangles.push([v[0], v[1], v[2]]);
        }
    }

    /// Keeps element `tag` of `kind` with node tags `corners`, of `listed` on its line (line
    /// `r.line`).
    pub(super) fn add<R>(
        &mut self,
        r: &Records<'_, R>,
        nodes: &Nodes,
        kind: usize,
        tag: &str,
        corners: &[&str],
        listed: usize,
    ) -> Result<(), IoError> {
        let expected = if kind == TETRAHEDRON { 4 } else { 3 };
        if listed != expected {
            return Err(
                r.error(format!("element {} of type {kind} lists {listed} nodes, expected {expected}", shown(tag)))
            );
        }
        let id = tag.parse::<u64>().map_err(|_| r.error(format!("element tag '{}' is not an integer", shown(tag))))?;
        let mut v = [0u32; 4];
        for (slot, corner) in v.iter_mut().zip(corners) {
            *slot = nodes.lookup(r, corner, tag)?;
        }
        self.push(kind, id, v, r.line as u64);
        Ok(())
    }
}

/// Builds a tetrahedral mesh whose triangles are the boundary of `tets` (shared with the TetGen
/// reader). Each tetrahedron of negative volume gets its last two vertices swapped, so that all
/// are positively oriented and the boundary faces outward, and is listed in the attributes
/// ([`crate::io::TetrahedronOrder`]) so that outputs swap it back; `origins` gives the line and file
/// number of each tetrahedron, `element` what the file calls it, for errors.
///
/// # Errors
/// [`IoError::Mesh`] for an index out of range or a non-finite coordinate; [`IoError::Parse`]
/// for a tetrahedron that repeats a vertex or is flat (|volume| ≤ 1e-12 of the product of its
/// edge lengths from the first corner).
pub(in crate::io) fn tetrahedral_mesh(
    path: &Path,
    positions: Vec<DVec3>,
    tets: Vec<[u32; 4]>,
    origins: &[(usize, u64)],
    element: &str,
) -> Result<LoadedMesh, IoError> {
    let origins: Vec<(u64, u64)> = origins.iter().map(|&(line, id)| (line as u64, id)).collect();
    tetrahedra_to_mesh(path, positions, tets, &origins, element, Place::Line)
}

/// [`tetrahedral_mesh`] with `origins` that are lines or byte offsets, as `place` says.
fn tetrahedra_to_mesh(
    path: &Path,
    positions: Vec<DVec3>,
    tets: Vec<[u32; 4]>,
    origins: &[(u64, u64)],
    element: &str,
    place: Place,
) -> Result<LoadedMesh, IoError> {
    let mesh_error = |source: MeshError| IoError::Mesh { path: path.to_path_buf(), source };
    // Validates indices and coordinates, so the positions can be indexed below.
    let mut mesh = Mesh::with_tetrahedra(positions, Vec::new(), tets).map_err(mesh_error)?;
    let mut left_handed = Vec::new();
    for (i, (tet, &(origin, id))) in mesh.tetrahedra.iter_mut().zip(origins).enumerate() {
        let error = |message: String| match place {
            Place::Line => IoError::Parse { path: path.to_path_buf(), line: origin as usize, message },
            Place::Offset => IoError::Binary { path: path.to_path_buf(), offset: origin, message },
        };
        if (0..4).any(|i| tet[i + 1..].contains(&tet[i])) {
            return Err(error(format!("{element} {id} repeats a vertex")));
        }
        let [a, b, c, d] = tet.map(|v| mesh.positions[v as usize]);
        let (e1, e2, e3) = (b - a, c - a, d - a);
        let volume6 = e1.dot(e2.cross(e3));
        if volume6.abs() <= FLAT_TOLERANCE * e1.length() * e2.length() * e3.length() {
            return Err(error(format!("{element} {id} is flat (volume {:e})", volume6 / 6.0)));
        }
        if volume6 < 0.0 {
            tet.swap(2, 3);
            left_handed.push(i as u32);
        }
    }
    let boundary = tetrahedron_boundary(&mesh.tetrahedra);
    mesh.set_triangles(boundary);
    let attributes = if left_handed.is_empty() {
        crate::io::Attributes::None
    } else {
        let tetrahedra = mesh.tetrahedra.len();
        crate::io::Attributes::Tetrahedra(Box::new(crate::io::TetrahedronOrder { tetrahedra, left_handed }))
    };
    Ok(LoadedMesh { mesh, attributes, warnings: crate::warnings::Warnings::new() })
}
