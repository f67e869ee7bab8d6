//! A `.msh` file as read, to write it back moved: its bytes, where each node's coordinates are
//! (a line, or a byte offset in a binary file) and its physical groups. Writing a mesh of the same nodes and elements back to
//! `.msh` rewrites only the coordinates on those lines; everything else (`$PhysicalNames`,
//! `$Entities`, node and element tags, every element of every type with its tags, any other
//! section) comes back byte for byte.

use std::io::{self, Write};

use crate::io::{AttributeKind, TetrahedronOrder, write_xyz};
use crate::mesh::Mesh;

/// A physical group of a `.msh` file: the vertices of its elements (of any type).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PhysicalGroup {
    /// Dimension of its elements (0 points, 1 lines, 2 surfaces, 3 volumes).
    pub dim: i32,
    /// Its tag.
    pub tag: i64,
    /// Its name in `$PhysicalNames`, if it has one.
    pub name: Option<String>,
    /// Mesh vertex indices of its elements' nodes, ascending.
    pub vertices: Vec<u32>,
}

impl PhysicalGroup {
    /// How scenes name it: its name, or for an unnamed group its tag as text (`"3"`).
    pub fn label(&self) -> String {
        self.name.clone().unwrap_or_else(|| self.tag.to_string())
    }
}

/// How a `.msh` file holds its node coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// ASCII 2.2: `tag x y z` lines.
    Text22,
    /// ASCII 4.1: `x y z [u v]` lines.
    Text41,
    /// Binary: three `double`s, big or little endian.
    Binary {
        /// Big endian.
        big_endian: bool,
    },
}

/// What a `.msh` file carries besides the mesh ([`crate::io::Attributes::Msh`]).
#[derive(Debug, Clone, PartialEq)]
pub struct MshSource {
    /// The file as read (empty for a UTF-16 file, which is written anew).
    pub(crate) text: Vec<u8>,
    /// Per mesh vertex, where its coordinates are (ascending: nodes in file order): the 1-based
    /// line (text) or the byte offset of its x (binary).
    pub(crate) node_origins: Vec<u64>,
    /// How the coordinates are written.
    pub(crate) layout: Layout,
    /// Tetrahedra and triangles the mesh was read with: a mesh with other counts is another
    /// mesh, which the source does not describe.
    pub(crate) elements: (usize, usize),
    /// Elements of other types in the file (points, lines, quads, …), which only this source
    /// keeps.
    pub(crate) other_elements: usize,
    /// The left-handed tetrahedra, if any ([`TetrahedronOrder`]).
    pub(crate) order: Option<TetrahedronOrder>,
    /// Its physical groups, by dimension and tag.
    pub physical_groups: Vec<PhysicalGroup>,
}

impl MshSource {
    /// Whether `mesh` has this file's nodes and elements (positions aside), so that the file
    /// can be written back with its coordinates replaced.
    pub fn fits(&self, mesh: &Mesh) -> bool {
        // With tetrahedra, the mesh's triangles are their boundary, not the file's.
        mesh.num_vertices() == self.node_origins.len()
            && mesh.num_tetrahedra() == self.elements.0
            && (self.elements.0 > 0 || mesh.num_triangles() == self.elements.1)
    }

    /// What only this source carries, for the writers of other formats to say they drop.
    pub fn kinds(&self) -> Vec<AttributeKind> {
        let mut kinds = Vec::new();
        if !self.physical_groups.is_empty() {
            kinds.push(AttributeKind::Other("Gmsh physical groups".into()));
        }
        if self.other_elements > 0 {
            kinds.push(AttributeKind::Other("Gmsh elements other than tetrahedra and triangles".into()));
        }
        kinds
    }

    /// Writes the file with each node's coordinates replaced by `mesh`'s (which [`Self::fits`]):
    /// an ASCII 2.2 node line keeps its tag, a 4.1 one its parametric coordinates, a binary node
    /// its three `double`s' place and byte order; every other byte is the file's.
    ///
    /// # Errors
    /// Any error of `w`.
    pub(crate) fn write(&self, w: &mut dyn Write, mesh: &Mesh) -> io::Result<()> {
        if let Layout::Binary { big_endian } = self.layout {
            let mut bytes = self.text.clone();
            for (&at, p) in self.node_origins.iter().zip(&mesh.positions) {
                for (k, x) in p.to_array().into_iter().enumerate() {
                    let value = if big_endian { x.to_be_bytes() } else { x.to_le_bytes() };
                    let start = usize::try_from(at).unwrap_or(usize::MAX).saturating_add(8 * k);
                    if let Some(slot) = bytes.get_mut(start..start.saturating_add(8)) {
                        slot.copy_from_slice(&value);
                    }
                }
            }
            return w.write_all(&bytes);
        }
        let mut next = self.node_origins.iter().zip(&mesh.positions).peekable();
        for (i, line) in self.text.split_inclusive(|&b| b == b'\n').enumerate() {
            let number = i as u64 + 1;
            let Some(&(_, &p)) = next.peek().filter(|&&(&l, _)| l == number) else {
                w.write_all(line)?;
                continue;
            };
            next.next();
            let body = line.strip_suffix(b"\n").unwrap_or(line);
            let body = body.strip_suffix(b"\r").unwrap_or(body);
            let ending = &line[body.len()..];
            let text = String::from_utf8_lossy(body);
            let mut tokens = text.split_whitespace();
            if self.layout == Layout::Text22 {
                write!(w, "{} ", tokens.next().unwrap_or_default())?;
                write_xyz(w, p)?;
            } else {
                write_xyz(w, p)?;
                for parametric in tokens.skip(3) {
                    write!(w, " {parametric}")?;
                }
            }
            w.write_all(ending)?;
        }
        Ok(())
    }
}

/// The dimension of Gmsh element type `kind` (Gmsh's table of element types), `None` for a
/// type not in it.
pub(super) fn element_dim(kind: usize) -> Option<i32> {
    match kind {
        15 => Some(0),
        1 | 8 | 26 | 27 | 28 => Some(1),
        2 | 3 | 9 | 10 | 16 | 20..=25 => Some(2),
        4..=7 | 11..=14 | 17..=19 | 29..=31 | 92 | 93 => Some(3),
        _ => None,
    }
}
