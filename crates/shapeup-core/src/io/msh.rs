//! Gmsh `.msh`: versions 4.1 and 2.2 (2.0 and 2.1 read as 2.2), ASCII and binary.
//!
//! Read: `$MeshFormat`, `$Nodes` and `$Elements`; in binary 4.1 files `$Entities` is parsed (its
//! layout is binary there) only to step over it; every other section (`$PhysicalNames`,
//! `$Entities` in ASCII files, `$NodeData`, `$Periodic`, …) is skipped up to its `$End…` line,
//! which binary files always put on a line of its own after their data. Node tags may be sparse
//! and in any order: vertex *i* of the mesh is the *i*-th node of the file. Element type 4 (4-node
//! tetrahedron) and type 2 (3-node triangle) are read; every other type (points, lines, quads,
//! second-order elements, …) is skipped (in binary files by its number of nodes, from Gmsh's table
//! of element types: an unknown type is an error there). With tetrahedra, the mesh's triangles
//! are their boundary ([`tetrahedron_boundary`]) and the file's triangles are ignored; without,
//! the file's triangles are the mesh. Tetrahedra of negative volume are reoriented silently by
//! swapping their last two vertices (so scene vertex indices stay valid, only the corner order
//! changes); flat ones (|volume| ≤ 1e-12 × the product of the edge lengths from the first
//! corner) and ones that repeat a vertex are an error naming the element and its line (ASCII) or
//! byte offset (binary).
//!
//! Binary files (`4.1 1 8` or `4.1 1 4`: `size_t` of 8 or 4 bytes; `2.2 1 8`) are little or big
//! endian, as the integer 1 after the version line says; every error in them names the byte
//! offset. An ASCII file in UTF-16 (byte-order mark `FF FE` or `FE FF`) is decoded; a binary one
//! cannot be UTF-16 text and is refused naming the encoding. Counts in headers never size an
//! allocation beyond [`super::MAX_PREALLOCATION`], and every count is checked against the data
//! that actually follows, so a short file claiming 2⁶⁰ nodes fails quickly at its end.
//!
//! Write: MSH 4.1 ASCII without `$Entities` (Gmsh creates discrete entities for it): one node
//! block, one block of tetrahedra if there are any and one of the surface triangles.
//!
//! Hand-written rather than the `mshio` crate: mshio 0.4 (nom 5) reserves vectors of the sizes a
//! header claims (`count(parser, n)` calls `Vec::with_capacity(n)`, so a 1 KB file claiming 2⁶⁰
//! nodes aborts), reports errors as a parser backtrace into the byte slice rather than a byte
//! offset, needs the whole file in memory, and reads neither version 2.2 nor parametric nodes.

use std::collections::{BTreeSet, HashMap};
use std::io::{self, BufRead, Write};
use std::path::Path;
use std::str::SplitWhitespace;

use glam::DVec3;

use super::{
    IoError, Lines, LoadedMesh, bounded_vec, build_mesh, decode_text, parse_coordinate, read_error, shown,
    utf16_encoding, write_point,
};
use crate::mesh::{Mesh, MeshError};
use crate::topology::tetrahedron_boundary;

/// Gmsh element type of a 3-node triangle.
const TRIANGLE: usize = 2;
/// Gmsh element type of a 4-node tetrahedron.
const TETRAHEDRON: usize = 4;
/// A tetrahedron is flat when |(b−a)·((c−a)×(d−a))| ≤ this × |b−a| |c−a| |d−a| (the sine-like
/// ratio is 1 for a right corner; only numerically flat ones fall below).
const FLAT_TOLERANCE: f64 = 1e-12;

/// Reads a Gmsh `.msh` file (4.1 or 2.2, ASCII or binary) from `reader`; `path` only names it in
/// errors.
///
/// # Errors
/// [`IoError::Parse`] with the line for a missing `$MeshFormat`, an unsupported version, and, in
/// ASCII files, a malformed or truncated section, a duplicate or undefined node tag, a
/// non-numeric coordinate, or a flat tetrahedron; [`IoError::Binary`] with the byte offset for
/// the same in binary files (and for an unknown element type, a bad endianness mark, a binary
/// file in UTF-16, or malformed UTF-16); [`IoError::Invalid`] for no nodes, or elements none of
/// which is a tetrahedron or triangle; [`IoError::Mesh`] for a non-finite coordinate;
/// [`IoError::Read`] if reading fails.
pub fn read_msh(mut reader: impl BufRead, path: &Path) -> Result<LoadedMesh, IoError> {
    let utf16 = utf16_encoding(reader.fill_buf().map_err(|e| read_error(path, e))?);
    let reader = decode_text(reader).map_err(|e| read_error(path, e))?;
    let mut r = Records::new(reader, path, None);
    if !r.advance()? {
        return Err(r.error_at(1, "empty file (expected '$MeshFormat')"));
    }
    if r.text() != "$MeshFormat" {
        return Err(r.error(format!("not a Gmsh file: expected '$MeshFormat', found '{}'", shown(r.text()))));
    }
    r.require_line(|| "the version line 'version file-type data-size'".to_owned())?;
    let fields: Vec<&str> = r.tokens().take(4).collect();
    let version_2 = match fields.first().copied().unwrap_or("") {
        "4.1" => false,
        "2" | "2.0" | "2.1" | "2.2" => true,
        v => {
            return Err(
                r.error(format!("MSH version {} is not supported (only 4.1 and 2.2, ASCII or binary)", shown(v)))
            );
        }
    };
    let bad_version = || r.error(format!("bad version line '{}' (expected e.g. '4.1 0 8')", shown(r.text())));
    match fields.get(1).copied() {
        Some("0") => {}
        Some("1") => {
            if let Some(encoding) = utf16 {
                return Err(r.error(format!(
                    "a binary .msh file cannot be {encoding} text (the file starts with its byte-order mark)"
                )));
            }
            let size_t = match (version_2, fields.get(2).copied()) {
                (_, Some("8")) => 8,
                (false, Some("4")) => 4,
                (_, size) => {
                    let expected = if version_2 { "8 (sizeof(double))" } else { "8 or 4 (sizeof(size_t))" };
                    return Err(r.error(format!(
                        "data-size '{}' is not supported in a binary file (expected {expected})",
                        shown(size.unwrap_or(""))
                    )));
                }
            };
            let offset = r.lines.consumed;
            let mut b = Binary { reader: r.lines.into_inner(), offset, path, big_endian: false, size_t };
            return read_binary(&mut b, version_2);
        }
        _ => return Err(bad_version()),
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
            s if is_section(s) => {
                // A section we do not need: skip it whole.
                let end = format!("$End{}", &s[1..]);
                let start = r.line;
                while r.text() != end {
                    if !r.advance()? {
                        return Err(r.eof_error(format!("'{end}' (closing '{s}' of line {start})")));
                    }
                }
            }
            s => return Err(r.error(format!("expected a section such as '$Nodes', found '{}'", shown(s)))),
        }
    }
    finish(path, nodes, elements, Place::Line)
}

/// Whether `text` opens a section (`$Name`, one word, not `$End…`).
fn is_section(text: &str) -> bool {
    text.starts_with('$') && !text.starts_with("$End") && text.len() > 1 && !text.contains(char::is_whitespace)
}

/// The mesh from the nodes and elements read.
fn finish(path: &Path, nodes: Nodes, elements: Elements, place: Place) -> Result<LoadedMesh, IoError> {
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
struct Nodes {
    positions: Vec<DVec3>,
    index: HashMap<u64, u32>,
}

impl Nodes {
    /// Room for the `count` nodes a header announces, within bounds (the first `$Nodes` only).
    fn reserve(&mut self, count: u64) {
        if self.positions.is_empty() {
            self.positions = bounded_vec(usize::try_from(count).unwrap_or(usize::MAX));
        }
    }

    /// Gives `tag` the index after the positions read and `pending` tags still without one.
    fn add(&mut self, tag: u64, pending: u64) -> Result<(), String> {
        if tag == 0 {
            return Err("node tag 0 is not a positive integer".to_owned());
        }
        let index = u64::try_from(self.positions.len()).ok().and_then(|n| n.checked_add(pending));
        let index = index.and_then(|i| u32::try_from(i).ok()).ok_or("too many nodes (more than 2³² − 1)")?;
        if self.index.insert(tag, index).is_some() {
            return Err(format!("node tag {tag} is defined twice"));
        }
        Ok(())
    }

    /// [`Self::add`] for a tag as text.
    fn add_text<R>(&mut self, r: &Records<'_, R>, tag: &str, pending: u64) -> Result<u64, IoError> {
        let t = tag.parse::<u64>().ok().filter(|&t| t > 0);
        let t = t.ok_or_else(|| r.error(format!("node tag '{}' is not a positive integer", shown(tag))))?;
        self.add(t, pending).map_err(|m| r.error(m))?;
        Ok(t)
    }

    /// The index of node `tag` as referenced by an element.
    fn lookup<R>(&self, r: &Records<'_, R>, tag: &str, element: &str) -> Result<u32, IoError> {
        tag.parse::<u64>().ok().and_then(|t| self.index.get(&t).copied()).ok_or_else(|| {
            r.error(format!("element {}: node tag '{}' is not defined in $Nodes", shown(element), shown(tag)))
        })
    }
}

/// The first three of `tokens` as a point (the rest is ignored), or a message naming the bad one.
pub(super) fn parse_point(tokens: &[&str]) -> Result<DVec3, String> {
    let mut xyz = [0.0; 3];
    for (i, (axis, slot)) in ["x", "y", "z"].iter().zip(&mut xyz).enumerate() {
        let token = tokens.get(i).ok_or_else(|| format!("no {axis} coordinate (expected 'x y z')"))?;
        *slot = parse_coordinate(token, &format!("{axis} coordinate"))
            .map_err(|_| format!("{axis} coordinate '{}' is not a number", shown(token)))?;
    }
    Ok(DVec3::from_array(xyz))
}

/// MSH 2.2 `$Nodes`: a count, then `tag x y z` lines.
fn read_nodes_2<R: BufRead>(r: &mut Records<'_, R>, nodes: &mut Nodes) -> Result<(), IoError> {
    let header = r.line;
    r.require_line(|| "the number of nodes".to_owned())?;
    let [count] = r.counts("the number of nodes")?;
    nodes.reserve(count as u64);
    for i in 0..count {
        r.require_line(|| format!("node {} of {count} ($Nodes of line {header})", i + 1))?;
        let fields: Vec<&str> = r.tokens().take(4).collect();
        let tag = nodes.add_text(r, fields.first().copied().unwrap_or(""), 0)?;
        let p = parse_point(fields.get(1..).unwrap_or(&[])).map_err(|m| r.error(format!("node {tag}: {m}")))?;
        nodes.positions.push(p);
    }
    r.expect_line("$EndNodes", &format!(" ($Nodes of line {header} says {count} nodes)"))
}

/// MSH 4.1 `$Nodes`: `blocks nodes min max`, then per block `dim entity parametric n`, `n` tag
/// lines and `n` coordinate lines (parametric coordinates after `x y z` are ignored).
fn read_nodes_41<R: BufRead>(r: &mut Records<'_, R>, nodes: &mut Nodes) -> Result<(), IoError> {
    let header = r.line;
    r.require_line(|| "'numEntityBlocks numNodes minNodeTag maxNodeTag'".to_owned())?;
    let [blocks, count, _, _] = r.counts("'numEntityBlocks numNodes minNodeTag maxNodeTag'")?;
    nodes.reserve(count as u64);
    let mut total = 0usize;
    for b in 0..blocks {
        r.require_line(|| format!("node block {} of {blocks} ($Nodes of line {header})", b + 1))?;
        let [_, _, parametric, n] = r.counts("'entityDim entityTag parametric numNodesInBlock'")?;
        if parametric > 1 {
            return Err(r.error(format!("parametric flag {parametric} is not 0 or 1")));
        }
        let mut tags = bounded_vec(n);
        for k in 0..n {
            r.require_line(|| format!("tag {} of {n} of node block {}", k + 1, b + 1))?;
            let mut fields = r.tokens();
            let (Some(tag), None) = (fields.next(), fields.next()) else {
                return Err(r.error(format!("expected one node tag, found '{}'", shown(r.text()))));
            };
            let tag = tag.to_owned();
            tags.push(nodes.add_text(r, &tag, k as u64)?);
        }
        for (k, tag) in tags.iter().enumerate() {
            r.require_line(|| format!("coordinates {} of {n} of node block {}", k + 1, b + 1))?;
            let fields: Vec<&str> = r.tokens().take(3).collect();
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

/// Where an element was found: the line (ASCII files) or the byte offset (binary files).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Place {
    Line,
    Offset,
}

/// Elements kept so far and the types skipped.
#[derive(Default)]
struct Elements {
    tets: Vec<[u32; 4]>,
    /// Line (or byte offset) and tag of each tetrahedron, for errors.
    tet_origins: Vec<(u64, u64)>,
    triangles: Vec<[u32; 3]>,
    skipped: BTreeSet<usize>,
}

impl Elements {
    /// Keeps element `id` of `kind` (a tetrahedron or a triangle) with vertices `v`, found at
    /// `origin` (a line or byte offset).
    fn push(&mut self, kind: usize, id: u64, v: [u32; 4], origin: u64) {
        if kind == TETRAHEDRON {
            self.tets.push(v);
            self.tet_origins.push((origin, id));
        } else {
            self.triangles.push([v[0], v[1], v[2]]);
        }
    }

    /// Keeps element `tag` of `kind` with node tags `corners`, of `listed` on its line (line
    /// `r.line`).
    fn add<R>(
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
    r.require_line(|| what.to_owned())?;
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
            r.require_line(|| format!("element block {} of {blocks} ($Elements of line {header})", b + 1))?;
            let [_, _, kind, n] = r.counts("'entityDim entityTag elementType numElementsInBlock'")?;
            (Some(kind), n)
        };
        for k in 0..n {
            r.require_line(|| format!("element {} of {n} ($Elements of line {header})", k + 1))?;
            let mut tokens = r.tokens();
            let tag = tokens.next().unwrap_or("");
            let kind = match kind {
                Some(kind) => kind,
                None => {
                    let kind = integer_field(r, &mut tokens, "element type")?;
                    let tags = integer_field(r, &mut tokens, "number of tags")?;
                    // Stops at the end of the line, however many tags are claimed.
                    tokens.by_ref().take(tags).for_each(drop);
                    kind
                }
            };
            if kind != TETRAHEDRON && kind != TRIANGLE {
                out.skipped.insert(kind);
                continue;
            }
            // The first four node tags, and how many the line lists (without collecting them all).
            let mut corners = [""; 4];
            let mut listed = 0usize;
            for token in tokens {
                if let Some(slot) = corners.get_mut(listed) {
                    *slot = token;
                }
                listed += 1;
            }
            out.add(r, nodes, kind, tag, &corners[..listed.min(4)], listed)?;
        }
        total = total.saturating_add(n);
    }
    r.expect_line("$EndElements", &format!(" ($Elements of line {header} says {count} elements)"))?;
    if total != count {
        return Err(r.error(format!("$Elements of line {header} says {count} elements, but its blocks hold {total}")));
    }
    Ok(())
}

/// The next token of an ASCII 2.2 element line as a non-negative integer; `name` names it in errors.
fn integer_field<R>(r: &Records<'_, R>, tokens: &mut SplitWhitespace<'_>, name: &str) -> Result<usize, IoError> {
    let token = tokens.next().unwrap_or("");
    token.parse::<usize>().map_err(|_| {
        r.error(format!("element line '{}': {name} '{}' is not an integer", shown(r.text()), shown(token)))
    })
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
    for (tet, &(origin, id)) in mesh.tetrahedra.iter_mut().zip(origins) {
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
        }
    }
    let boundary = tetrahedron_boundary(&mesh.tetrahedra);
    mesh.set_triangles(boundary);
    Ok(LoadedMesh { mesh, attributes: super::Attributes::None, warnings: crate::warnings::Warnings::new() })
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
        self.error(format!("expected {what}, found '{}'", shown(&self.text)))
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
            // A malformed UTF-16 file fails here, named by its byte offset.
            let next = self.lines.next_line().map_err(|source| read_error(self.path, source))?;
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
    pub(super) fn require_line(&mut self, what: impl FnOnce() -> String) -> Result<(), IoError> {
        if self.advance()? { Ok(()) } else { Err(self.eof_error(what())) }
    }

    /// Moves to the next line, which must be exactly `keyword`; `context` is added to errors.
    fn expect_line(&mut self, keyword: &str, context: &str) -> Result<(), IoError> {
        self.require_line(|| format!("'{keyword}'{context}"))?;
        if self.text != keyword {
            return Err(self.error(format!("expected '{keyword}'{context}, found '{}'", shown(&self.text))));
        }
        Ok(())
    }
}

/// Number of nodes of each Gmsh element type (`None`: no such type, or one of variable size), as
/// Gmsh 4.8's `getElementProperties` gives them (prisms 90, 91 and 106–117 and type 140, which it
/// lacks, by their names in `GmshDefines.h`: `MSH_PRI_40` has 40 nodes, …). Binary files need
/// it to step over the elements of the types not read.
fn nodes_per_element(kind: i32) -> Option<u64> {
    Some(match kind {
        15 | 84..=89 | 132 => 1,
        1 => 2,
        2 | 8 => 3,
        3 | 4 | 26 | 140 => 4,
        7 | 27 => 5,
        6 | 9 | 28 => 6,
        62 => 7,
        5 | 16 | 63 => 8,
        10 | 20 | 64 => 9,
        11 | 21 | 65 => 10,
        66 => 11,
        22 | 39 => 12,
        19 => 13,
        14 => 14,
        18 | 23 | 24 => 15,
        36 | 40 | 137 => 16,
        13 | 52 => 18,
        17 | 29 | 41 => 20,
        25 | 53 | 125 => 21,
        32 => 22,
        54 | 57 | 111 => 24,
        37 => 25,
        12 | 55 => 27,
        33 | 42 | 58 => 28,
        126 => 29,
        56 | 118 => 30,
        59 | 99 => 32,
        112 => 33,
        79 => 34,
        30 => 35,
        38 | 43 | 60 => 36,
        127 => 37,
        61 | 80 | 90 => 40,
        113 => 42,
        100 => 44,
        44 | 128 => 45,
        81 => 46,
        47 => 49,
        114 => 51,
        82 => 52,
        129 => 53,
        45 | 119 => 55,
        31 | 101 => 56,
        83 => 58,
        115 => 60,
        130 => 61,
        48 | 92 => 64,
        46 => 66,
        102 => 68,
        116 | 131 => 69,
        91 => 75,
        117 => 78,
        103 => 80,
        49 => 81,
        71 => 84,
        120 => 91,
        104 => 92,
        50 => 100,
        105 => 104,
        72 => 120,
        51 => 121,
        93 => 125,
        106 => 126,
        121 => 140,
        73 => 165,
        107 => 196,
        122 => 204,
        94 => 216,
        74 => 220,
        123 => 285,
        75 => 286,
        108 => 288,
        95 => 343,
        124 => 385,
        109 => 405,
        96 => 512,
        110 => 550,
        97 => 729,
        98 => 1000,
        _ => return None,
    })
}

/// Most bytes of a text line kept in a binary file (section keywords, counts): a longer line is
/// no keyword, and binary data without line breaks must not pile up in memory.
const LINE_KEPT: usize = 256;

/// A binary `.msh` file after its version line: binary values, text lines between them, and the
/// byte offset of each for errors.
struct Binary<'p, R> {
    reader: R,
    offset: u64,
    path: &'p Path,
    big_endian: bool,
    /// Bytes of a `size_t` (4.1: 8 or 4, as the version line says).
    size_t: usize,
}

impl<R: BufRead> Binary<'_, R> {
    fn error(&self, offset: u64, message: impl Into<String>) -> IoError {
        IoError::Binary { path: self.path.to_path_buf(), offset, message: message.into() }
    }

    /// The next `N` bytes, in little-endian order; at the end of the file, an error that the
    /// file ends inside `what()`.
    fn bytes<const N: usize>(&mut self, what: &dyn Fn() -> String) -> Result<[u8; N], IoError> {
        let mut buf = [0; N];
        match self.reader.read_exact(&mut buf) {
            Ok(()) => {}
            Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => {
                return Err(self.error(self.offset, format!("file ends inside {}", what())));
            }
            Err(e) => return Err(read_error(self.path, e)),
        }
        self.offset += N as u64;
        if self.big_endian {
            buf.reverse();
        }
        Ok(buf)
    }

    /// An `int` (4 bytes).
    fn int(&mut self, what: &dyn Fn() -> String) -> Result<i32, IoError> {
        self.bytes::<4>(what).map(i32::from_le_bytes)
    }

    /// A `size_t` (8 or 4 bytes).
    fn size(&mut self, what: &dyn Fn() -> String) -> Result<u64, IoError> {
        if self.size_t == 4 {
            self.bytes::<4>(what).map(|b| u32::from_le_bytes(b).into())
        } else {
            self.bytes::<8>(what).map(u64::from_le_bytes)
        }
    }

    /// A `double`.
    fn double(&mut self, what: &dyn Fn() -> String) -> Result<f64, IoError> {
        self.bytes::<8>(what).map(f64::from_le_bytes)
    }

    /// Steps over `count` values of `size` bytes each, as [`Self::bytes`] would read them.
    fn skip(&mut self, count: u64, size: u64, what: &dyn Fn() -> String) -> Result<(), IoError> {
        let start = self.offset;
        let Some(mut left) = count.checked_mul(size) else {
            return Err(self.error(start, format!("{} claims more bytes than a file can hold", what())));
        };
        while left > 0 {
            let available = match self.reader.fill_buf() {
                Ok(buf) => buf.len(),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(read_error(self.path, e)),
            };
            if available == 0 {
                return Err(self.error(start, format!("file ends inside {}", what())));
            }
            let step = available.min(usize::try_from(left).unwrap_or(usize::MAX));
            self.reader.consume(step);
            self.offset += step as u64;
            left -= step as u64;
        }
        Ok(())
    }

    /// The next line (through its `\n`), trimmed, at most [`LINE_KEPT`] bytes of it kept, and
    /// its offset; `None` at the end of the file.
    fn raw_line(&mut self) -> Result<Option<(u64, String)>, IoError> {
        let start = self.offset;
        let mut kept = Vec::new();
        let mut any = false;
        loop {
            let (step, done) = {
                let buf = match self.reader.fill_buf() {
                    Ok(buf) => buf,
                    Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                    Err(e) => return Err(read_error(self.path, e)),
                };
                if buf.is_empty() {
                    break;
                }
                let (step, done) = match buf.iter().position(|&c| c == b'\n') {
                    Some(i) => (i + 1, true),
                    None => (buf.len(), false),
                };
                let room = LINE_KEPT.saturating_sub(kept.len()).min(step);
                kept.extend_from_slice(&buf[..room]);
                (step, done)
            };
            any = true;
            self.reader.consume(step);
            self.offset += step as u64;
            if done {
                break;
            }
        }
        Ok(any.then(|| (start, String::from_utf8_lossy(kept.trim_ascii()).into_owned())))
    }

    /// The next non-blank line, as [`Self::raw_line`].
    fn line(&mut self) -> Result<Option<(u64, String)>, IoError> {
        while let Some((offset, text)) = self.raw_line()? {
            if !text.is_empty() {
                return Ok(Some((offset, text)));
            }
        }
        Ok(None)
    }

    /// The next non-blank line, which must be `keyword`; `context` is added to errors.
    fn expect_line(&mut self, keyword: &str, context: &str) -> Result<(), IoError> {
        match self.line()? {
            Some((_, text)) if text == keyword => Ok(()),
            Some((offset, text)) => {
                Err(self.error(offset, format!("expected '{keyword}'{context}, found '{}'", shown(&text))))
            }
            None => Err(self.error(self.offset, format!("file ends early: expected '{keyword}'{context}"))),
        }
    }

    /// The next non-blank line as one non-negative integer (a count in MSH 2.2).
    fn count_line(&mut self, what: &str) -> Result<u64, IoError> {
        match self.line()? {
            Some((offset, text)) => {
                text.parse().map_err(|_| self.error(offset, format!("expected {what}, found '{}'", shown(&text))))
            }
            None => Err(self.error(self.offset, format!("file ends early: expected {what}"))),
        }
    }
}

/// The sections of a binary file after its version line.
fn read_binary<R: BufRead>(b: &mut Binary<'_, R>, version_2: bool) -> Result<LoadedMesh, IoError> {
    let mark = b.offset;
    let one = b.bytes::<4>(&|| "the integer 1 that gives a binary file's byte order".to_owned())?;
    b.big_endian = match one {
        [1, 0, 0, 0] => false,
        [0, 0, 0, 1] => true,
        _ => {
            return Err(b.error(
                mark,
                format!("expected the integer 1 in little or big endian (the byte order mark), found bytes {one:02X?}"),
            ));
        }
    };
    b.expect_line("$EndMeshFormat", "")?;

    let mut nodes = Nodes::default();
    let mut elements = Elements::default();
    while let Some((offset, section)) = b.line()? {
        match section.as_str() {
            "$Nodes" if version_2 => read_nodes_2_binary(b, &mut nodes, offset)?,
            "$Nodes" => read_nodes_41_binary(b, &mut nodes, offset)?,
            "$Elements" if version_2 => read_elements_2_binary(b, &nodes, &mut elements, offset)?,
            "$Elements" => read_elements_41_binary(b, &nodes, &mut elements, offset)?,
            "$Entities" if !version_2 => skip_entities_binary(b, offset)?,
            s if is_section(s) => {
                // Found by its line: Gmsh ends every section's binary data with a line break.
                let end = format!("$End{}", &s[1..]);
                loop {
                    match b.raw_line()? {
                        Some((_, text)) if text == end => break,
                        Some(_) => {}
                        None => {
                            return Err(b.error(
                                b.offset,
                                format!("file ends early: expected '{end}' (closing '{s}' at byte offset {offset})"),
                            ));
                        }
                    }
                }
            }
            s => return Err(b.error(offset, format!("expected a section such as '$Nodes', found '{}'", shown(s)))),
        }
    }
    finish(b.path, nodes, elements, Place::Offset)
}

/// Binary MSH 4.1 `$Entities`: four counts, then points (`int` tag, 3 `double`s, physical tags)
/// and curves, surfaces and volumes (`int` tag, 6 `double`s, physical tags, bounding entities),
/// each list a `size_t` count of `int`s. Only stepped over.
fn skip_entities_binary<R: BufRead>(b: &mut Binary<'_, R>, at: u64) -> Result<(), IoError> {
    let header = || format!("the counts of $Entities (at byte offset {at})");
    let counts = [b.size(&header)?, b.size(&header)?, b.size(&header)?, b.size(&header)?];
    for (dim, (&count, kind)) in counts.iter().zip(["point", "curve", "surface", "volume"]).enumerate() {
        for i in 0..count {
            let what = || format!("{kind} entity {} of {count} ($Entities at byte offset {at})", i + 1);
            b.int(&what)?;
            b.skip(if dim == 0 { 3 } else { 6 }, 8, &what)?;
            let lists = if dim == 0 { 1 } else { 2 };
            for _ in 0..lists {
                let n = b.size(&what)?;
                b.skip(n, 4, &what)?;
            }
        }
    }
    b.expect_line("$EndEntities", &format!(" (closing '$Entities' at byte offset {at})"))
}

/// Binary MSH 4.1 `$Nodes`: the `size_t`s `blocks nodes min max`, then per block the `int`s
/// `dim entity parametric` and a `size_t` count, the blocks' `size_t` tags, then per node x y z
/// and, if parametric, `dim` more `double`s (stepped over).
fn read_nodes_41_binary<R: BufRead>(b: &mut Binary<'_, R>, nodes: &mut Nodes, at: u64) -> Result<(), IoError> {
    let header =
        || format!("the header of $Nodes (at byte offset {at}): 'numEntityBlocks numNodes minNodeTag maxNodeTag'");
    let [blocks, count, _, _] = [b.size(&header)?, b.size(&header)?, b.size(&header)?, b.size(&header)?];
    nodes.reserve(count);
    let mut total = 0u64;
    for block in 1..=blocks {
        let start = b.offset;
        let what = || format!("node block {block} of {blocks} ($Nodes at byte offset {at})");
        let [dim, _, parametric] = [b.int(&what)?, b.int(&what)?, b.int(&what)?];
        let n = b.size(&what)?;
        let extra = match (parametric, dim) {
            (0, _) => 0,
            (1, 0..=3) => dim.unsigned_abs().into(),
            (1, _) => return Err(b.error(start, format!("node block {block}: entity dimension {dim} is not 0 to 3"))),
            _ => {
                return Err(
                    b.error(start + 8, format!("node block {block}: parametric flag {parametric} is not 0 or 1"))
                );
            }
        };
        let mut tags = bounded_vec(usize::try_from(n).unwrap_or(usize::MAX));
        for k in 0..n {
            let offset = b.offset;
            let tag = b.size(&|| format!("tag {} of {n} of node block {block}", k + 1))?;
            nodes.add(tag, k).map_err(|m| b.error(offset, m))?;
            tags.push(tag);
        }
        for (k, tag) in tags.iter().enumerate() {
            let what = || format!("the coordinates of node {tag} ({} of {n} of node block {block})", k + 1);
            let p = DVec3::new(b.double(&what)?, b.double(&what)?, b.double(&what)?);
            b.skip(extra, 8, &what)?;
            nodes.positions.push(p);
        }
        total = total.saturating_add(n);
    }
    let end = b.offset;
    b.expect_line("$EndNodes", &format!(" (closing '$Nodes' at byte offset {at}, which has {blocks} blocks)"))?;
    if total != count {
        return Err(b.error(end, format!("$Nodes at byte offset {at} says {count} nodes, but its blocks hold {total}")));
    }
    Ok(())
}

/// Binary MSH 4.1 `$Elements`: the `size_t`s `blocks elements min max`, then per block the
/// `int`s `dim entity type` and a `size_t` count, then per element its `size_t` tag and node tags.
fn read_elements_41_binary<R: BufRead>(
    b: &mut Binary<'_, R>,
    nodes: &Nodes,
    out: &mut Elements,
    at: u64,
) -> Result<(), IoError> {
    let header = || {
        format!(
            "the header of $Elements (at byte offset {at}): 'numEntityBlocks numElements minElementTag maxElementTag'"
        )
    };
    let [blocks, count, _, _] = [b.size(&header)?, b.size(&header)?, b.size(&header)?, b.size(&header)?];
    let size = b.size_t as u64;
    let mut total = 0u64;
    for block in 1..=blocks {
        let start = b.offset;
        let what = || format!("element block {block} of {blocks} ($Elements at byte offset {at})");
        let [_, _, kind] = [b.int(&what)?, b.int(&what)?, b.int(&what)?];
        let n = b.size(&what)?;
        let corners = nodes_per_element(kind).ok_or_else(|| {
            b.error(
                start + 8,
                format!("element block {block}: element type {kind} is not a Gmsh element type of fixed size"),
            )
        })?;
        let kind = usize::try_from(kind).unwrap_or(0);
        if kind == TETRAHEDRON || kind == TRIANGLE {
            for k in 1..=n {
                let offset = b.offset;
                let what = || format!("element {k} of {n} of element block {block} (type {kind})");
                let id = b.size(&what)?;
                let mut v = [0u32; 4];
                for slot in v.iter_mut().take(usize::try_from(corners).unwrap_or(0)) {
                    let tag = b.size(&what)?;
                    *slot = nodes.index.get(&tag).copied().ok_or_else(|| {
                        b.error(offset, format!("element {id}: node tag {tag} is not defined in $Nodes"))
                    })?;
                }
                out.push(kind, id, v, offset);
            }
        } else {
            out.skipped.insert(kind);
            let what = || format!("element block {block} of {blocks} ({n} elements of type {kind})");
            b.skip(n, (1 + corners) * size, &what)?;
        }
        total = total.saturating_add(n);
    }
    let end = b.offset;
    b.expect_line("$EndElements", &format!(" (closing '$Elements' at byte offset {at}, which has {blocks} blocks)"))?;
    if total != count {
        return Err(
            b.error(end, format!("$Elements at byte offset {at} says {count} elements, but its blocks hold {total}"))
        );
    }
    Ok(())
}

/// Binary MSH 2.2 `$Nodes`: a count on its own line, then per node an `int` tag and x y z.
fn read_nodes_2_binary<R: BufRead>(b: &mut Binary<'_, R>, nodes: &mut Nodes, at: u64) -> Result<(), IoError> {
    let count = b.count_line("the number of nodes")?;
    nodes.reserve(count);
    for k in 1..=count {
        let offset = b.offset;
        let what = || format!("node {k} of {count} ($Nodes at byte offset {at})");
        let tag = b.int(&what)?;
        let tag =
            u64::try_from(tag).map_err(|_| b.error(offset, format!("node tag {tag} is not a positive integer")))?;
        nodes.add(tag, 0).map_err(|m| b.error(offset, m))?;
        let p = DVec3::new(b.double(&what)?, b.double(&what)?, b.double(&what)?);
        nodes.positions.push(p);
    }
    b.expect_line("$EndNodes", &format!(" (closing '$Nodes' at byte offset {at}, which says {count} nodes)"))
}

/// Binary MSH 2.2 `$Elements`: a count on its own line, then groups of elements of one type:
/// the `int`s `type following tags`, then per element the `int`s `number tag… node…`.
fn read_elements_2_binary<R: BufRead>(
    b: &mut Binary<'_, R>,
    nodes: &Nodes,
    out: &mut Elements,
    at: u64,
) -> Result<(), IoError> {
    let count = b.count_line("the number of elements")?;
    let mut read = 0u64;
    while read < count {
        let start = b.offset;
        let what = || format!("the header of elements {} and on of {count} ($Elements at byte offset {at})", read + 1);
        let [kind, following, tags] = [b.int(&what)?, b.int(&what)?, b.int(&what)?];
        let corners = nodes_per_element(kind)
            .ok_or_else(|| b.error(start, format!("element type {kind} is not a Gmsh element type of fixed size")))?;
        let left = count - read;
        let following = u64::try_from(following).ok().filter(|&f| f > 0 && f <= left).ok_or_else(|| {
            b.error(start + 4, format!("{following} elements follow, expected 1 to the {left} left of {count}"))
        })?;
        let tags = u64::try_from(tags).map_err(|_| b.error(start + 8, format!("number of tags {tags} is negative")))?;
        let kind = usize::try_from(kind).unwrap_or(0);
        if kind == TETRAHEDRON || kind == TRIANGLE {
            for k in 1..=following {
                let offset = b.offset;
                let what = || format!("element {} of {count} ($Elements at byte offset {at})", read + k);
                let id = b.int(&what)?;
                let id = u64::try_from(id).map_err(|_| b.error(offset, format!("element tag {id} is negative")))?;
                b.skip(tags, 4, &what)?;
                let mut v = [0u32; 4];
                for slot in v.iter_mut().take(usize::try_from(corners).unwrap_or(0)) {
                    let tag = b.int(&what)?;
                    let index = u64::try_from(tag).ok().and_then(|t| nodes.index.get(&t).copied());
                    *slot = index.ok_or_else(|| {
                        b.error(offset, format!("element {id}: node tag {tag} is not defined in $Nodes"))
                    })?;
                }
                out.push(kind, id, v, offset);
            }
        } else {
            out.skipped.insert(kind);
            let what = || format!("elements {} to {} of {count} (type {kind})", read + 1, read + following);
            // `tags` comes from an `int`, so the sum cannot overflow.
            b.skip(following, (1 + tags + corners) * 4, &what)?;
        }
        read += following;
    }
    b.expect_line("$EndElements", &format!(" (closing '$Elements' at byte offset {at}, which says {count} elements)"))
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
