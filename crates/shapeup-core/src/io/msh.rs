//! Gmsh `.msh`, ASCII versions 4.1 and 2.2 (2.0 and 2.1 read as 2.2).
//!
//! Read: `$MeshFormat`, `$Nodes` and `$Elements`; every other section (`$PhysicalNames`,
//! `$Entities`, `$NodeData`, …) is skipped up to its `$End…` line. Node tags may be sparse and in
//! any order: vertex *i* of the mesh is the *i*-th node of the file. Element type 4 (4-node
//! tetrahedron) and type 2 (3-node triangle) are read; every other type (points, lines, quads,
//! second-order elements, …) is skipped. With tetrahedra, the mesh's triangles are their boundary
//! ([`tetrahedron_boundary`]) and the file's triangles are ignored; without, the file's triangles
//! are the mesh. Tetrahedra of negative volume are reoriented silently by swapping their last two
//! vertices (so scene vertex indices stay valid, only the corner order changes); flat ones
//! (|volume| ≤ 1e-12 × the product of the edge lengths from the first corner) and ones that repeat
//! a vertex are an error naming the element and its line. Binary files are refused.
//!
//! Write: MSH 4.1 ASCII without `$Entities` (Gmsh creates discrete entities for it): one node
//! block, one block of tetrahedra if there are any and one of the surface triangles.

use std::collections::{BTreeSet, HashMap};
use std::io::{self, BufRead, Write};
use std::path::Path;
use std::str::SplitWhitespace;

use glam::DVec3;

use super::{IoError, Lines, LoadedMesh, bounded_vec, build_mesh, parse_coordinate, write_point};
use crate::mesh::{Mesh, MeshError};
use crate::topology::tetrahedron_boundary;

/// Gmsh element type of a 3-node triangle.
const TRIANGLE: usize = 2;
/// Gmsh element type of a 4-node tetrahedron.
const TETRAHEDRON: usize = 4;
/// A tetrahedron is flat when |(b−a)·((c−a)×(d−a))| ≤ this × |b−a| |c−a| |d−a| (the sine-like
/// ratio is 1 for a right corner; only numerically flat ones fall below).
const FLAT_TOLERANCE: f64 = 1e-12;

/// Reads a Gmsh ASCII `.msh` file (4.1 or 2.2) from `reader`; `path` only names it in errors.
///
/// # Errors
/// [`IoError::Parse`] with the line for a missing or binary `$MeshFormat`, an unsupported
/// version, a malformed or truncated section, a duplicate or undefined node tag, a non-numeric
/// coordinate, or a flat tetrahedron; [`IoError::Invalid`] for no nodes, or elements none of which
/// is a tetrahedron or triangle; [`IoError::Mesh`] for a non-finite coordinate;
/// [`IoError::Read`] if reading fails.
pub fn read_msh(reader: impl BufRead, path: &Path) -> Result<LoadedMesh, IoError> {
    let mut r = Records::new(reader, path, None);
    if !r.advance()? {
        return Err(r.error_at(1, "empty file (expected '$MeshFormat')"));
    }
    if r.text() != "$MeshFormat" {
        return Err(r.error(format!("not a Gmsh file: expected '$MeshFormat', found '{}'", r.text())));
    }
    r.expect(|| "the version line 'version file-type data-size'".to_owned())?;
    let fields: Vec<&str> = r.tokens().collect();
    let version_2 = match fields.first().copied().unwrap_or("") {
        "4.1" => false,
        "2" | "2.0" | "2.1" | "2.2" => true,
        v => return Err(r.error(format!("MSH version {v} is not supported (only 4.1 and 2.2 ASCII)"))),
    };
    match fields.get(1).copied() {
        Some("0") => {}
        Some("1") => return Err(r.error("binary .msh is not supported; save as ASCII")),
        _ => return Err(r.error(format!("bad version line '{}' (expected e.g. '4.1 0 8')", r.text()))),
    }
    r.expect_line("$EndMeshFormat", "")?;

    let mut nodes = Nodes::default();
    let mut elements = Elements::default();
    while r.advance()? {
        let section = r.text().to_owned();
        match section.as_str() {
            "$Nodes" if version_2 => read_nodes_2(&mut r, &mut nodes)?,
            "$Nodes" => read_nodes_41(&mut r, &mut nodes)?,
            "$Elements" => read_elements(&mut r, &nodes, &mut elements, version_2)?,
            s if s.starts_with('$') && !s.starts_with("$End") && !s.contains(char::is_whitespace) => {
                // A section we do not need: skip it whole.
                let end = format!("$End{}", &s[1..]);
                let start = r.line;
                while r.text() != end {
                    if !r.advance()? {
                        return Err(r.eof_error(format!("'{end}' (closing '{s}' of line {start})")));
                    }
                }
            }
            s => return Err(r.error(format!("expected a section such as '$Nodes', found '{s}'"))),
        }
    }

    if nodes.positions.is_empty() {
        return Err(IoError::Invalid { path: path.to_path_buf(), message: "no nodes (no $Nodes section)".to_owned() });
    }
    if !elements.tets.is_empty() {
        return tetrahedral_mesh(path, nodes.positions, elements.tets, &elements.tet_origins, "element");
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
    build_mesh(path, nodes.positions, elements.triangles.iter().map(Vec::as_slice).collect())
}

/// Nodes read so far: positions in file order and the index of each tag.
#[derive(Default)]
struct Nodes {
    positions: Vec<DVec3>,
    index: HashMap<u64, u32>,
}

impl Nodes {
    /// Gives `tag` the index after the positions read and `pending` tags still without one;
    /// returns the tag.
    fn add_tag<R>(&mut self, r: &Records<'_, R>, tag: &str, pending: usize) -> Result<u64, IoError> {
        let t = tag.parse::<u64>().ok().filter(|&t| t > 0);
        let t = t.ok_or_else(|| r.error(format!("node tag '{tag}' is not a positive integer")))?;
        let index = u32::try_from(self.positions.len() + pending).map_err(|_| r.error("too many nodes"))?;
        if self.index.insert(t, index).is_some() {
            return Err(r.error(format!("node tag {t} is defined twice")));
        }
        Ok(t)
    }

    /// The index of node `tag` as referenced by an element.
    fn lookup<R>(&self, r: &Records<'_, R>, tag: &str, element: &str) -> Result<u32, IoError> {
        tag.parse::<u64>()
            .ok()
            .and_then(|t| self.index.get(&t).copied())
            .ok_or_else(|| r.error(format!("element {element}: node tag '{tag}' is not defined in $Nodes")))
    }
}

/// The first three of `tokens` as a point (the rest is ignored), or a message naming the bad one.
pub(super) fn parse_point(tokens: &[&str]) -> Result<DVec3, String> {
    let mut xyz = [0.0; 3];
    for (i, (axis, slot)) in ["x", "y", "z"].iter().zip(&mut xyz).enumerate() {
        let token = tokens.get(i).ok_or_else(|| format!("no {axis} coordinate (expected 'x y z')"))?;
        *slot = parse_coordinate(token, &format!("{axis} coordinate"))?;
    }
    Ok(DVec3::from_array(xyz))
}

/// MSH 2.2 `$Nodes`: a count, then `tag x y z` lines.
fn read_nodes_2<R: BufRead>(r: &mut Records<'_, R>, nodes: &mut Nodes) -> Result<(), IoError> {
    let header = r.line;
    r.expect(|| "the number of nodes".to_owned())?;
    let [count] = r.counts("the number of nodes")?;
    nodes.positions.reserve(count.min(super::MAX_PREALLOCATION));
    for i in 0..count {
        r.expect(|| format!("node {} of {count} ($Nodes of line {header})", i + 1))?;
        let fields: Vec<&str> = r.tokens().collect();
        let tag = nodes.add_tag(r, fields[0], 0)?;
        let p = parse_point(&fields[1..]).map_err(|m| r.error(format!("node {tag}: {m}")))?;
        nodes.positions.push(p);
    }
    r.expect_line("$EndNodes", &format!(" ($Nodes of line {header} says {count} nodes)"))
}

/// MSH 4.1 `$Nodes`: `blocks nodes min max`, then per block `dim entity parametric n`, `n` tag
/// lines and `n` coordinate lines (parametric coordinates after `x y z` are ignored).
fn read_nodes_41<R: BufRead>(r: &mut Records<'_, R>, nodes: &mut Nodes) -> Result<(), IoError> {
    let header = r.line;
    r.expect(|| "'numEntityBlocks numNodes minNodeTag maxNodeTag'".to_owned())?;
    let [blocks, count, _, _] = r.counts("'numEntityBlocks numNodes minNodeTag maxNodeTag'")?;
    nodes.positions.reserve(count.min(super::MAX_PREALLOCATION));
    let mut total = 0usize;
    for b in 0..blocks {
        r.expect(|| format!("node block {} of {blocks} ($Nodes of line {header})", b + 1))?;
        let [_, _, parametric, n] = r.counts("'entityDim entityTag parametric numNodesInBlock'")?;
        if parametric > 1 {
            return Err(r.error(format!("parametric flag {parametric} is not 0 or 1")));
        }
        let mut tags = bounded_vec(n);
        for k in 0..n {
            r.expect(|| format!("tag {} of {n} of node block {}", k + 1, b + 1))?;
            let fields: Vec<&str> = r.tokens().collect();
            if fields.len() != 1 {
                return Err(r.error(format!("expected one node tag, found '{}'", r.text())));
            }
            tags.push(nodes.add_tag(r, fields[0], k)?);
        }
        for (k, tag) in tags.iter().enumerate() {
            r.expect(|| format!("coordinates {} of {n} of node block {}", k + 1, b + 1))?;
            let fields: Vec<&str> = r.tokens().collect();
            nodes.positions.push(parse_point(&fields).map_err(|m| r.error(format!("node {tag}: {m}")))?);
        }
        total = total.saturating_add(n);
    }
    r.expect_line("$EndNodes", &format!(" ($Nodes of line {header} has {blocks} blocks)"))?;
    if total != count {
        return Err(r.error(format!("$Nodes of line {header} says {count} nodes, but its blocks hold {total}")));
    }
    Ok(())
}

/// Elements kept so far and the types skipped.
#[derive(Default)]
struct Elements {
    tets: Vec<[u32; 4]>,
    /// Line and tag of each tetrahedron, for errors.
    tet_origins: Vec<(usize, u64)>,
    triangles: Vec<Vec<u32>>,
    skipped: BTreeSet<usize>,
}

impl Elements {
    /// Keeps element `tag` of `kind` with node tags `corners` (line `r.line`).
    fn add<R>(
        &mut self,
        r: &Records<'_, R>,
        nodes: &Nodes,
        kind: usize,
        tag: &str,
        corners: &[&str],
    ) -> Result<(), IoError> {
        let expected = if kind == TETRAHEDRON { 4 } else { 3 };
        if corners.len() != expected {
            return Err(
                r.error(format!("element {tag} of type {kind} lists {} nodes, expected {expected}", corners.len()))
            );
        }
        let id = tag.parse::<u64>().map_err(|_| r.error(format!("element tag '{tag}' is not an integer")))?;
        let mut v = [0u32; 4];
        for (slot, corner) in v.iter_mut().zip(corners) {
            *slot = nodes.lookup(r, corner, tag)?;
        }
        if kind == TETRAHEDRON {
            self.tets.push(v);
            self.tet_origins.push((r.line, id));
        } else {
            self.triangles.push(v[..3].to_vec());
        }
        Ok(())
    }
}

/// `$Elements` of either version. 2.2: a count, then `tag type ntags tag… node…` lines. 4.1:
/// `blocks elements min max`, then per block `dim entity type n` and `n` lines `tag node…`.
fn read_elements<R: BufRead>(
    r: &mut Records<'_, R>,
    nodes: &Nodes,
    out: &mut Elements,
    v2: bool,
) -> Result<(), IoError> {
    let header = r.line;
    let what = if v2 { "the number of elements" } else { "'numEntityBlocks numElements minElementTag maxElementTag'" };
    r.expect(|| what.to_owned())?;
    let (blocks, count) = if v2 {
        let [count] = r.counts(what)?;
        (1, count)
    } else {
        let [blocks, count, _, _] = r.counts(what)?;
        (blocks, count)
    };
    let mut total = 0usize;
    for b in 0..blocks {
        let (kind, n) = if v2 {
            (None, count)
        } else {
            r.expect(|| format!("element block {} of {blocks} ($Elements of line {header})", b + 1))?;
            let [_, _, kind, n] = r.counts("'entityDim entityTag elementType numElementsInBlock'")?;
            (Some(kind), n)
        };
        for k in 0..n {
            r.expect(|| format!("element {} of {n} ($Elements of line {header})", k + 1))?;
            let fields: Vec<&str> = r.tokens().collect();
            let (kind, tag, corners) = match kind {
                Some(kind) => (kind, fields[0], &fields[1..]),
                None => {
                    let number = |i: usize, name: &str| {
                        let token = fields.get(i).copied().unwrap_or("");
                        token.parse::<usize>().map_err(|_| {
                            r.error(format!("element line '{}': {name} '{token}' is not an integer", r.text()))
                        })
                    };
                    let kind = number(1, "element type")?;
                    let skip = number(2, "number of tags")?.saturating_add(3);
                    (kind, fields[0], fields.get(skip..).unwrap_or(&[]))
                }
            };
            match kind {
                TETRAHEDRON | TRIANGLE => out.add(r, nodes, kind, tag, corners)?,
                _ => {
                    out.skipped.insert(kind);
                }
            }
        }
        total = total.saturating_add(n);
    }
    r.expect_line("$EndElements", &format!(" ($Elements of line {header} says {count} elements)"))?;
    if total != count {
        return Err(r.error(format!("$Elements of line {header} says {count} elements, but its blocks hold {total}")));
    }
    Ok(())
}

/// Builds a tetrahedral mesh whose triangles are the boundary of `tets` (shared with the TetGen
/// reader). Each tetrahedron of negative volume gets its last two vertices swapped, so that all
/// are positively oriented and the boundary faces outward; `origins` gives the line and file
/// number of each tetrahedron, `element` what the file calls it, for errors.
///
/// # Errors
/// [`IoError::Mesh`] for an index out of range or a non-finite coordinate; [`IoError::Parse`]
/// for a tetrahedron that repeats a vertex or is flat (|volume| ≤ 1e-12 of the product of its
/// edge lengths from the first corner).
pub(super) fn tetrahedral_mesh(
    path: &Path,
    positions: Vec<DVec3>,
    tets: Vec<[u32; 4]>,
    origins: &[(usize, u64)],
    element: &str,
) -> Result<LoadedMesh, IoError> {
    let mesh_error = |source: MeshError| IoError::Mesh { path: path.to_path_buf(), source };
    // Validates indices and coordinates, so the positions can be indexed below.
    let mut mesh = Mesh::with_tetrahedra(positions, Vec::new(), tets).map_err(mesh_error)?;
    for (tet, &(line, id)) in mesh.tetrahedra.iter_mut().zip(origins) {
        let parse_error = |message: String| IoError::Parse { path: path.to_path_buf(), line, message };
        if (0..4).any(|i| tet[i + 1..].contains(&tet[i])) {
            return Err(parse_error(format!("{element} {id} repeats a vertex")));
        }
        let [a, b, c, d] = tet.map(|v| mesh.positions[v as usize]);
        let (e1, e2, e3) = (b - a, c - a, d - a);
        let volume6 = e1.dot(e2.cross(e3));
        if volume6.abs() <= FLAT_TOLERANCE * e1.length() * e2.length() * e3.length() {
            return Err(parse_error(format!("{element} {id} is flat (volume {:e})", volume6 / 6.0)));
        }
        if volume6 < 0.0 {
            tet.swap(2, 3);
        }
    }
    let boundary = tetrahedron_boundary(&mesh.tetrahedra);
    mesh.set_triangles(boundary);
    Ok(LoadedMesh { mesh, warnings: crate::warnings::Warnings::new() })
}

/// Writes `mesh` as MSH 4.1 ASCII: node tags are vertex indices + 1; element tags number the
/// tetrahedra, then the triangles, from 1. Coordinates read back exactly.
///
/// # Errors
/// Any error of `w`.
pub fn write_msh(w: &mut dyn Write, mesh: &Mesh) -> io::Result<()> {
    let (n, t, m) = (mesh.num_vertices(), mesh.num_tetrahedra(), mesh.num_triangles());
    let dim = if t > 0 { 3 } else { 2 };
    writeln!(w, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 {n} 1 {n}\n{dim} 1 0 {n}")?;
    for tag in 1..=n {
        writeln!(w, "{tag}")?;
    }
    for p in &mesh.positions {
        write_point(w, *p)?;
    }
    let blocks = usize::from(t > 0) + usize::from(m > 0);
    let min_tag = usize::from(t + m > 0);
    writeln!(w, "$EndNodes\n$Elements\n{blocks} {} {min_tag} {}", t + m, t + m)?;
    if t > 0 {
        writeln!(w, "3 1 {TETRAHEDRON} {t}")?;
        for (k, [a, b, c, d]) in mesh.tetrahedra.iter().enumerate() {
            writeln!(w, "{} {} {} {} {}", k + 1, a + 1, b + 1, c + 1, d + 1)?;
        }
    }
    if m > 0 {
        writeln!(w, "2 1 {TRIANGLE} {m}")?;
        for (k, [a, b, c]) in mesh.triangles.iter().enumerate() {
            writeln!(w, "{} {} {} {}", t + k + 1, a + 1, b + 1, c + 1)?;
        }
    }
    writeln!(w, "$EndElements")
}

/// The non-blank lines of a text file, trimmed, with `comment` and what follows it removed, and
/// errors that name the file and line (shared with the TetGen reader).
pub(super) struct Records<'p, R> {
    lines: Lines<R>,
    path: &'p Path,
    comment: Option<char>,
    text: String,
    /// 1-based number of the current line.
    pub(super) line: usize,
}

impl<'p, R> Records<'p, R> {
    /// The current line's text.
    pub(super) fn text(&self) -> &str {
        &self.text
    }

    /// The current line's tokens.
    pub(super) fn tokens(&self) -> SplitWhitespace<'_> {
        self.text.split_whitespace()
    }

    /// A parse error at the current line.
    pub(super) fn error(&self, message: impl Into<String>) -> IoError {
        self.error_at(self.line, message)
    }

    /// A parse error at `line`.
    pub(super) fn error_at(&self, line: usize, message: impl Into<String>) -> IoError {
        IoError::Parse { path: self.path.to_path_buf(), line, message: message.into() }
    }

    /// The error for a file that ends where `what` was expected (at the line after the last).
    pub(super) fn eof_error(&self, what: String) -> IoError {
        self.error_at(self.lines.number + 1, format!("file ends early: expected {what}"))
    }

    /// The current line as exactly `N` non-negative integers.
    pub(super) fn counts<const N: usize>(&self, what: &str) -> Result<[usize; N], IoError> {
        let mut out = [0; N];
        let mut tokens = self.tokens();
        for slot in &mut out {
            *slot = tokens.next().and_then(|t| t.parse().ok()).ok_or_else(|| self.bad_counts(what))?;
        }
        if tokens.next().is_some() {
            return Err(self.bad_counts(what));
        }
        Ok(out)
    }

    fn bad_counts(&self, what: &str) -> IoError {
        self.error(format!("expected {what}, found '{}'", self.text))
    }
}

impl<'p, R: BufRead> Records<'p, R> {
    /// Records of `reader`; `path` names the file in errors.
    pub(super) fn new(reader: R, path: &'p Path, comment: Option<char>) -> Self {
        Self { lines: Lines::new(reader), path, comment, text: String::new(), line: 0 }
    }

    /// Moves to the next non-blank line; `false` at the end of the file.
    pub(super) fn advance(&mut self) -> Result<bool, IoError> {
        loop {
            let next =
                self.lines.next_line().map_err(|source| IoError::Read { path: self.path.to_path_buf(), source })?;
            let Some((number, text)) = next else { return Ok(false) };
            let content = match self.comment {
                Some(c) => text.split(c).next().unwrap_or(""),
                None => text,
            }
            .trim();
            if !content.is_empty() {
                self.text.clear();
                self.text.push_str(content);
                self.line = number;
                return Ok(true);
            }
        }
    }

    /// Moves to the next non-blank line, which must exist: `what` names what was expected.
    pub(super) fn expect(&mut self, what: impl FnOnce() -> String) -> Result<(), IoError> {
        if self.advance()? { Ok(()) } else { Err(self.eof_error(what())) }
    }

    /// Moves to the next line, which must be exactly `keyword`; `context` is added to errors.
    fn expect_line(&mut self, keyword: &str, context: &str) -> Result<(), IoError> {
        self.expect(|| format!("'{keyword}'{context}"))?;
        if self.text != keyword {
            return Err(self.error(format!("expected '{keyword}'{context}, found '{}'", self.text)));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TET_41: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n\
                          0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n";

    #[test]
    fn one_tetrahedron_and_its_boundary() {
        let loaded = read_msh(TET_41.as_bytes(), Path::new("t.msh")).unwrap();
        assert_eq!(loaded.mesh.tetrahedra, vec![[0, 1, 2, 3]]);
        assert_eq!(loaded.mesh.triangles, tetrahedron_boundary(&[[0, 1, 2, 3]]));
    }

    #[test]
    fn written_file_reads_back() {
        let mesh = read_msh(TET_41.as_bytes(), Path::new("t.msh")).unwrap().mesh;
        let mut out = Vec::new();
        write_msh(&mut out, &mesh).unwrap();
        assert_eq!(read_msh(&out[..], Path::new("u.msh")).unwrap().mesh, mesh);
    }

    #[test]
    fn header_errors_name_the_line() {
        let err = read_msh(&b"$MeshFormat\n4.0 0 8\n"[..], Path::new("a.msh")).unwrap_err().to_string();
        assert!(err.contains("a.msh: line 2") && err.contains("4.0"), "{err}");
        let err = read_msh(&b"hello\n"[..], Path::new("a.msh")).unwrap_err().to_string();
        assert!(err.contains("line 1") && err.contains("$MeshFormat"), "{err}");
        let err = read_msh(&b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Comments\nhi\n"[..], Path::new("a.msh"));
        let err = err.unwrap_err().to_string();
        assert!(err.contains("line 6") && err.contains("$EndComments"), "{err}");
    }
}
