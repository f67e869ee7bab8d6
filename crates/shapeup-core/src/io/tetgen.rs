//! TetGen `.node` + `.ele` pairs.
//!
//! Read: `X.node` holds `points 3 [attributes [markers]]`, then one `index x y z [attribute…]
//! [marker]` line per point; `X.ele` holds `tetrahedra [nodes-per-tet [attributes]]` (4, or 10
//! for second-order tetrahedra, of which the four corners are kept), then one
//! `index n₀ n₁ n₂ n₃ […]` line per tetrahedron. Numbering is 0- or 1-based as the first point's
//! index says, and points must be numbered consecutively; attributes and boundary markers are
//! ignored; `#` starts a comment. Either path names the pair, the partner is found by swapping
//! the extension. Vertex *i* of the mesh is point *i* of the file; the mesh's triangles are the
//! boundary of the tetrahedra, which are reoriented as in [`msh`](super::msh). UTF-16 files
//! (byte-order mark) are decoded ([`super`]).
//!
//! Write: both files, 1-based (TetGen's default), without attributes or markers; each is written
//! atomically, the pair is not (a failure writing `X.ele` leaves the new `X.node`).

use std::fs::File;
use std::io::{self, BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

use super::msh::{parse_point, tetrahedral_mesh};
use super::records::Records;
use super::{
    IoError, LoadedMesh, bounded_vec, decode_text, read_error, shown, with_decode_errors, write_atomic, write_point,
};
use crate::mesh::{Mesh, MeshError};

/// The `.node` and `.ele` paths of the pair that `path` (with any extension) names; an
/// upper-case extension gives upper-case partners (`X.NODE`, `X.ELE`).
pub fn tetgen_paths(path: &Path) -> (PathBuf, PathBuf) {
    let upper = path.extension().is_some_and(|e| {
        let e = e.to_string_lossy();
        !e.is_empty() && e.chars().all(|c| c.is_ascii_uppercase())
    });
    let (node, ele) = if upper { ("NODE", "ELE") } else { ("node", "ele") };
    (path.with_extension(node), path.with_extension(ele))
}

/// Reads the pair named by `path` (`X.node` or `X.ele`).
///
/// # Errors
/// [`IoError::Open`] naming whichever file of the pair is missing, and those of [`read_tetgen`].
pub fn read_tetgen_files(path: &Path) -> Result<LoadedMesh, IoError> {
    let (node_path, ele_path) = tetgen_paths(path);
    let open = |p: &Path| {
        let file = File::open(p).map_err(|source| IoError::Open { path: p.to_path_buf(), source })?;
        Ok::<_, IoError>(BufReader::new(file))
    };
    let node = open(&node_path)?;
    let ele = open(&ele_path)?;
    read_tetgen(node, &node_path, ele, &ele_path)
}

/// Reads a `.node` file from `node` and an `.ele` file from `ele`; the paths only name them in
/// errors.
///
/// # Errors
/// [`IoError::Parse`] naming the file and line for a bad header, a dimension other than 3, a
/// point index that is not 0 or 1 first or not consecutive after, a non-numeric coordinate, a
/// node index out of range, a flat tetrahedron or one that repeats a vertex, content past the
/// announced counts, or a file that ends early; [`IoError::Invalid`] for no points or no
/// tetrahedra; [`IoError::Mesh`] for a non-finite coordinate; [`IoError::Binary`] for malformed
/// UTF-16; [`IoError::Read`] if reading fails.
pub fn read_tetgen(
    node: impl BufRead,
    node_path: &Path,
    ele: impl BufRead,
    ele_path: &Path,
) -> Result<LoadedMesh, IoError> {
    // The line reader reports every failed read as `Read`; malformed UTF-16 is a format error.
    read_pair(node, node_path, ele, ele_path).map_err(with_decode_errors)
}

fn read_pair(node: impl BufRead, node_path: &Path, ele: impl BufRead, ele_path: &Path) -> Result<LoadedMesh, IoError> {
    let node = decode_text(node).map_err(|e| read_error(node_path, e))?;
    let (positions, base) = read_node(node, node_path)?;
    let ele = decode_text(ele).map_err(|e| read_error(ele_path, e))?;
    let n = positions.len() as u64;

    let mut r = Records::new(ele, ele_path, Some('#'));
    if !r.advance()? {
        return Err(r.error_at(1, "empty file (expected '<tetrahedra> <nodes per tetrahedron> <attributes>')"));
    }
    let header = r.line;
    let fields: Vec<&str> = r.tokens().collect();
    let bad_header = || {
        r.error(format!(
            "bad header '{}' (expected '<tetrahedra> <nodes per tetrahedron> <attributes>')",
            shown(r.text())
        ))
    };
    if fields.len() > 3 {
        return Err(bad_header());
    }
    let numbers: Vec<usize> = fields.iter().map(|t| t.parse().map_err(|_| bad_header())).collect::<Result<_, _>>()?;
    let count = numbers[0];
    let corners = numbers.get(1).copied().unwrap_or(4);
    if corners != 4 && corners != 10 {
        return Err(r.error(format!("{corners} nodes per tetrahedron is not supported (4 or 10)")));
    }
    if count == 0 {
        return Err(IoError::Invalid {
            path: ele_path.to_path_buf(),
            message: "the header says 0 tetrahedra".to_owned(),
        });
    }
    let mut tets = bounded_vec(count);
    let mut origins = Vec::new();
    for k in 0..count {
        r.require_line(|| format!("tetrahedron {} of {count} (header line {header})", k + 1))?;
        let fields: Vec<&str> = r.tokens().collect();
        let id = fields[0]
            .parse::<u64>()
            .map_err(|_| r.error(format!("tetrahedron index '{}' is not an integer", shown(fields[0]))))?;
        if fields.len() < 1 + corners {
            return Err(r.error(format!("tetrahedron {id} lists {} nodes, expected {corners}", fields.len() - 1)));
        }
        let mut tet = [0u32; 4];
        for (slot, token) in tet.iter_mut().zip(&fields[1..]) {
            // In range 0..n after removing the base, so it fits a u32 like the point count.
            let v = token.parse::<u64>().ok().and_then(|v| v.checked_sub(base)).filter(|&v| v < n);
            *slot = v.map(|v| v as u32).ok_or_else(|| {
                r.error(format!(
                    "tetrahedron {id}: node '{}' is out of range: {} numbers its {n} points {base}..={}",
                    shown(token),
                    node_path.display(),
                    base + n - 1
                ))
            })?;
        }
        tets.push(tet);
        origins.push((r.line, id));
    }
    if r.advance()? {
        return Err(
            r.error(format!("unexpected '{}' after the {count} tetrahedra of header line {header}", shown(r.text())))
        );
    }
    tetrahedral_mesh(ele_path, positions, tets, &origins, "tetrahedron")
}

/// Reads a `.node` file: the points and the number of the first one (0 or 1).
fn read_node(reader: impl BufRead, path: &Path) -> Result<(Vec<glam::DVec3>, u64), IoError> {
    let mut r = Records::new(reader, path, Some('#'));
    let expected = "'<points> 3 <attributes> <boundary markers>'";
    if !r.advance()? {
        return Err(r.error_at(1, format!("empty file (expected {expected})")));
    }
    let header = r.line;
    let fields: Vec<&str> = r.tokens().collect();
    let bad_header = || r.error(format!("bad header '{}' (expected {expected})", shown(r.text())));
    if fields.len() > 4 {
        return Err(bad_header());
    }
    let numbers: Vec<usize> = fields.iter().map(|t| t.parse().map_err(|_| bad_header())).collect::<Result<_, _>>()?;
    let count = numbers[0];
    if let Some(&dim) = numbers.get(1).filter(|&&d| d != 3) {
        return Err(r.error(format!("dimension {dim} is not supported (only 3)")));
    }
    if count == 0 {
        return Err(IoError::Invalid { path: path.to_path_buf(), message: "the header says 0 points".to_owned() });
    }
    if count > u32::MAX as usize {
        return Err(r.error(format!("{count} points is more than a mesh can index")));
    }
    let mut positions = bounded_vec(count);
    let mut base = 0;
    for i in 0..count as u64 {
        r.require_line(|| format!("point {} of {count} (header line {header})", i + 1))?;
        let fields: Vec<&str> = r.tokens().collect();
        let index = fields[0].parse::<u64>().ok();
        if i == 0 {
            base = index.filter(|&b| b <= 1).ok_or_else(|| {
                r.error(format!("the first point is numbered '{}', expected 0 or 1", shown(fields[0])))
            })?;
        } else if index != Some(base + i) {
            return Err(r.error(format!("point '{}' is out of sequence: expected {}", shown(fields[0]), base + i)));
        }
        positions.push(parse_point(&fields[1..]).map_err(|m| r.error(format!("point {}: {m}", base + i)))?);
    }
    if r.advance()? {
        return Err(
            r.error(format!("unexpected '{}' after the {count} points of header line {header}", shown(r.text())))
        );
    }
    // A NaN would otherwise be reported against the .ele file, where the mesh is assembled.
    if let Some((vertex, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
        let source = MeshError::NonFinite { vertex, value: p.to_array() };
        return Err(IoError::Mesh { path: path.to_path_buf(), source });
    }
    Ok((positions, base))
}

/// Writes the points of `mesh` as a 1-based `.node` file with exactly round-tripping coordinates.
///
/// # Errors
/// Any error of `w`.
pub fn write_node(w: &mut dyn Write, mesh: &Mesh) -> io::Result<()> {
    writeln!(w, "# points, dimension, attributes, boundary markers\n{} 3 0 0", mesh.num_vertices())?;
    for (i, p) in mesh.positions.iter().enumerate() {
        write!(w, "{} ", i + 1)?;
        write_point(w, *p)?;
    }
    Ok(())
}

/// Writes the tetrahedra of `mesh` as a 1-based `.ele` file (triangles are not written: a reader
/// derives them from the tetrahedra).
///
/// # Errors
/// Any error of `w`.
pub fn write_ele(w: &mut dyn Write, mesh: &Mesh) -> io::Result<()> {
    writeln!(w, "# tetrahedra, nodes per tetrahedron, attributes\n{} 4 0", mesh.num_tetrahedra())?;
    for (k, [a, b, c, d]) in mesh.tetrahedra.iter().enumerate() {
        writeln!(w, "{} {} {} {} {}", k + 1, a + 1, b + 1, c + 1, d + 1)?;
    }
    Ok(())
}

/// Writes `X.node` and then `X.ele` for `path` = `X.*` (see [`tetgen_paths`]), each atomically.
///
/// # Errors
/// [`IoError::Invalid`] if the mesh has no tetrahedra and [`IoError::Mesh`] if it does not
/// validate (nothing is written in either case); [`IoError::Write`] naming the file that failed.
pub fn write_tetgen_files(path: &Path, mesh: &Mesh) -> Result<(), IoError> {
    if mesh.tetrahedra.is_empty() {
        return Err(IoError::Invalid {
            path: path.to_path_buf(),
            message: "TetGen .node/.ele files hold tetrahedra, and the mesh has none (write .msh, .obj, … instead)"
                .to_owned(),
        });
    }
    mesh.validate().map_err(|source| IoError::Mesh { path: path.to_path_buf(), source })?;
    let (node_path, ele_path) = tetgen_paths(path);
    write_atomic(&node_path, |w| write_node(w, mesh))?;
    write_atomic(&ele_path, |w| write_ele(w, mesh))
}

#[cfg(test)]
mod tests {
    use super::*;

    const NODE: &str = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";

    fn read(node: &str, ele: &str) -> Result<LoadedMesh, IoError> {
        read_tetgen(node.as_bytes(), Path::new("x.node"), ele.as_bytes(), Path::new("x.ele"))
    }

    #[test]
    fn partner_paths_keep_the_extension_case() {
        assert_eq!(tetgen_paths(Path::new("a/b.ele")), (PathBuf::from("a/b.node"), PathBuf::from("a/b.ele")));
        assert_eq!(tetgen_paths(Path::new("B.NODE")), (PathBuf::from("B.NODE"), PathBuf::from("B.ELE")));
    }

    #[test]
    fn negative_tetrahedron_is_reoriented_and_second_order_corners_kept() {
        let loaded = read(NODE, "1 10 0\n1 1 3 2 4 9 9 9 9 9 9\n").unwrap();
        assert_eq!(loaded.mesh.tetrahedra, vec![[0, 2, 3, 1]], "last two vertices swapped");
    }

    #[test]
    fn header_errors() {
        let err = read("4 2 0 0\n", "").unwrap_err().to_string();
        assert!(err.contains("x.node: line 1") && err.contains("dimension 2"), "{err}");
        let err = read(NODE, "1 4 0\n1 1 2 3 4\n2 1 2 3 4\n").unwrap_err().to_string();
        assert!(err.contains("x.ele: line 3") && err.contains("unexpected"), "{err}");
        let err = read(NODE, "1 6\n").unwrap_err().to_string();
        assert!(err.contains("x.ele: line 1") && err.contains("6 nodes per tetrahedron"), "{err}");
    }
}
