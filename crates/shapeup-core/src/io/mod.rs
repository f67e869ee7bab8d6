//! Mesh input and output.
//!
//! | format | read | write |
//! |--------|------|-------|
//! | Wavefront `.obj` | `v` (colours, `w`), `vt`, `vn`, `f` in every index form (negative too), and every other line kept | the file line for line with `v` moved and `vn` recomputed ([`obj`]); other meshes: `v`, `vt`, `vn`, `f` per polygon |
//! | Stanford `.ply` | ascii, binary little and big endian, any numeric types; every element and property kept; faces and `tristrips` | every element and property with its type, in the file's (or a chosen) encoding ([`ply`]); other meshes: `double` x y z, normals, colours, polygons |
//! | `.stl` | ascii and binary | binary (triangles only: vertex indices are not kept, a warning says so) |
//! | `.off` | `OFF`, `COFF`, `NOFF`, `STOFF`…; per-vertex and per-face values kept | the keyword and values as read, `N` normals recomputed ([`off`]) |
//! | Gmsh `.msh` | 4.1 and 2.2, ASCII and binary (little or big endian; 4.1 with a `size_t` of 8 or 4 bytes): 4-node tetrahedra, 3-node triangles (other elements skipped) | ASCII 4.1 |
//! | TetGen `.node` + `.ele` | either path names the pair; 0- or 1-based, attributes and markers ignored | both files, 1-based |
//! | VTK `.vtu` | — | polygons or tetrahedra, point data ([`vtu`]); `.pvd` time series |
//!
//! **Vertex order is preserved**: every reader returns the file's vertices, all of them (also
//! those no face uses), in file order, so that vertex indices in scene files and selections stay
//! valid. STL is the exception as it stores no shared vertices: its readers merge exactly equal
//! coordinates into one vertex, numbered in order of first occurrence, so an STL file we wrote
//! reads back with the same connectivity (but without unreferenced vertices, see [`stl`]).
//!
//! **Nothing is lost**: faces stay polygons ([`Mesh::polygons`]; the solver uses their
//! triangulation) and what a file carries besides positions and faces is kept in
//! [`LoadedMesh::attributes`], which the writers take beside the mesh. Every writer returns [`Warnings`] for
//! what it recomputed (normals) or what its format cannot hold; readers return theirs in
//! [`LoadedMesh::warnings`]. Only `.msh` and `.node`/`.ele` store tetrahedra; a mesh read from
//! them has the boundary of its tetrahedra as triangles (see [`msh`], [`tetgen`]).
//!
//! **Text encodings**: text files (OBJ, OFF, ascii STL, TetGen) are UTF-8 (ASCII), a UTF-8
//! byte-order mark at the start skipped; a file that starts with a UTF-16 byte-order mark
//! (`FF FE` little endian, `FE FF` big endian, as Windows editors save "Unicode" text) is
//! transcoded and reads exactly as its UTF-8 copy, and malformed UTF-16 is refused with the
//! encoding and byte offset. Binary STL is told from ascii by its size (`84 + 50·n` bytes), so
//! a binary header that happens to start with `FF FE` stays binary.
//!
//! Every reader is hand-written (the crates available reorder or drop vertices, or do not report
//! where a file is broken); no input makes them panic, and counts from a header never size an
//! allocation beyond [`MAX_PREALLOCATION`]. Every writer goes through [`write_atomic`].

mod atomic;
pub mod attributes;
mod decode;
pub mod msh;
pub mod obj;
pub mod off;
pub mod ply;
mod records;
pub mod stl;
pub mod tetgen;
pub mod vtu;

use std::fs::File;
use std::io::{self, BufReader, Write};
use std::path::{Path, PathBuf};

use crate::mesh::{Mesh, MeshError, Polygons};
use crate::warnings::Warnings;

pub use crate::text::one_line;
pub(crate) use crate::text::shown;
pub use atomic::{
    MESH_OUTPUT_EXTENSIONS, OutputError, check_output_extension, check_output_folder, create_output_folder,
    file_in_the_way, write_atomic,
};
pub use attributes::{AttributeKind, NO_INDEX, TexCoords, VertexScalar};
pub use decode::UTF8_BOM;
pub(crate) use decode::{
    DecodeError, Lines, NotANumber, TextReader, bounded_vec, decode_text, parse_coordinate, read_error, read_text_file,
    utf16_encoding, with_decode_errors,
};
pub use msh::{MshSource, PhysicalGroup};
pub use ply::PlyEncoding;

use obj::ObjAttributes;
use off::OffAttributes;
use ply::PlyAttributes;

/// Most elements any reader reserves room for up front, whatever a header claims; vectors grow
/// past it as data actually arrives.
pub const MAX_PREALLOCATION: usize = 1 << 20;

/// An error reading or writing a mesh file. Each message is one line naming the file and, where
/// there is one, the line (text formats) or byte offset and element (binary formats).
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The file could not be opened.
    #[error("cannot open {}: {source}", one_line(path.display()))]
    Open {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: io::Error,
    },
    /// Reading failed part-way (not a format problem).
    #[error("error reading {}: {source}", one_line(path.display()))]
    Read {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: io::Error,
    },
    /// A text file (or the text header of a binary one) is malformed at a line.
    #[error("{}: line {line}: {}", one_line(path.display()), one_line(message))]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A binary file is malformed (usually truncated) at a byte offset.
    #[error("{}: byte offset {offset}: {}", one_line(path.display()), one_line(message))]
    Binary {
        /// The file.
        path: PathBuf,
        /// Offset from the start of the file where the problem was found.
        offset: u64,
        /// What is wrong (naming the element and its index) and what was expected.
        message: String,
    },
    /// A well-formed file that holds no usable mesh (no vertices, no triangles).
    #[error("{}: {}", one_line(path.display()), one_line(message))]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is missing.
        message: String,
    },
    /// The file extension is not one of the supported formats.
    #[error("{}: unsupported mesh format {} (supported: {})", one_line(path.display()), describe_extension(extension), SUPPORTED)]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
        /// Its extension (empty when it has none).
        extension: String,
    },
    /// The elements read do not form a valid mesh (index out of range, non-finite coordinate).
    #[error("{}: invalid mesh: {source}", one_line(path.display()))]
    Mesh {
        /// The file.
        path: PathBuf,
        /// What is wrong with the mesh.
        source: MeshError,
    },
    /// Writing (or replacing) the file failed; the previous file, if any, is untouched.
    #[error("cannot write {}: {source}", one_line(path.display()))]
    Write {
        /// The target file.
        path: PathBuf,
        /// The operating system's (or the writer's) error.
        source: io::Error,
    },
}

const SUPPORTED: &str = ".obj, .ply, .stl, .off, .msh, .node/.ele";

fn describe_extension(extension: &str) -> String {
    if extension.is_empty() { "(no extension)".to_owned() } else { format!("'.{}'", one_line(extension)) }
}

/// A mesh read from a file, with what reading changed.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedMesh {
    /// The mesh, vertices in file order, with the file's polygons.
    pub mesh: Mesh,
    /// What the file carried besides positions and faces, for writing the mesh back.
    pub attributes: Attributes,
    /// What was split, dropped or recomputed (polygons triangulated, faces left out of the
    /// triangulation, …), each naming the file.
    pub warnings: Warnings,
}

/// The formats [`read_mesh`] understands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ.
    Obj,
    /// Stanford PLY.
    Ply,
    /// STL, ascii or binary.
    Stl,
    /// Object File Format.
    Off,
    /// Gmsh MSH, 4.1 or 2.2, ASCII or binary.
    Msh,
    /// TetGen `.node` + `.ele` pair (either extension).
    TetGen,
}

impl MeshFormat {
    /// The format named by a path's extension (case-insensitive).
    ///
    /// # Errors
    /// [`IoError::UnsupportedFormat`] for any other extension.
    pub fn from_path(path: &Path) -> Result<Self, IoError> {
        let extension = path.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_default();
        match extension.to_ascii_lowercase().as_str() {
            "obj" => Ok(Self::Obj),
            "ply" => Ok(Self::Ply),
            "stl" => Ok(Self::Stl),
            "off" => Ok(Self::Off),
            "msh" => Ok(Self::Msh),
            "node" | "ele" => Ok(Self::TetGen),
            _ => Err(IoError::UnsupportedFormat { path: path.to_path_buf(), extension }),
        }
    }
}

/// What a mesh file carries besides positions and faces, kept so that outputs lose nothing.
///
/// It holds the data of the format a mesh was read from, complete: written back in the same
/// format it reproduces the file (OBJ line for line, PLY property by property with their types,
/// OFF value by value), with only positions (and normals, recomputed from the moved geometry)
/// changed. Written to another format, the writer keeps what that format can hold through the
/// format-neutral views ([`Attributes::texcoords`], [`Attributes::vertex_colors`],
/// [`Attributes::has_normals`], [`Attributes::vertex_scalars`]) and reports the rest
/// ([`Attributes::kinds`]) as a warning.
#[derive(Debug, Clone, Default, PartialEq)]
pub enum Attributes {
    /// Nothing besides positions and faces (generated meshes, STL, MSH, TetGen files).
    #[default]
    None,
    /// Everything an OBJ file held: its lines in order, texture coordinates, normals.
    Obj(Box<ObjAttributes>),
    /// Everything a PLY file held: header, every element and property with its type.
    Ply(Box<PlyAttributes>),
    /// Everything an OFF file held: its header keyword and the values after each vertex and face.
    Off(Box<OffAttributes>),
    /// The node order of a TetGen file's tetrahedra, where some are left-handed.
    Tetrahedra(Box<TetrahedronOrder>),
    /// A `.msh` file as read: its bytes (written back with only the coordinates changed),
    /// physical groups and the node order of its tetrahedra.
    Msh(Box<msh::MshSource>),
}

/// Which tetrahedra a `.msh` or TetGen file lists left-handed: negative volume
/// (b − a) · ((c − a) × (d − a)) < 0 in the file's node order a, b, c, d. The readers swap
/// such a tetrahedron's last two nodes (the solver, the boundary and every volume take
/// tetrahedra right-handed); the writers of tetrahedra (`.msh`, TetGen, VTU) swap them back, so
/// an output lists every tetrahedron's nodes as its input did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TetrahedronOrder {
    /// How many tetrahedra the mesh read has (the order applies to a mesh with as many).
    pub tetrahedra: usize,
    /// The left-handed ones, by index, ascending.
    pub left_handed: Vec<u32>,
}

impl TetrahedronOrder {
    /// `tetrahedra` with the left-handed ones in the file's order again; `None` when the mesh
    /// does not have as many tetrahedra as the file (another mesh), or none was left-handed.
    pub fn file_order(&self, tetrahedra: &[[u32; 4]]) -> Option<Vec<[u32; 4]>> {
        if self.left_handed.is_empty() || tetrahedra.len() != self.tetrahedra {
            return None;
        }
        let mut out = tetrahedra.to_vec();
        for &t in &self.left_handed {
            out.get_mut(t as usize)?.swap(2, 3);
        }
        Some(out)
    }
}

impl Attributes {
    /// The same attributes as a file written from them holds them (OFF drops comment lines).
    pub fn with_comments(self, comments: usize) -> Self {
        match self {
            Attributes::Off(a) => Attributes::Off(Box::new(a.with_comments(comments))),
            other => other,
        }
    }

    /// Texture coordinates per corner, if the file has any.
    pub fn texcoords(&self, polygons: &Polygons) -> Option<TexCoords> {
        match self {
            Attributes::None => None,
            Attributes::Obj(a) => a.texcoords(polygons),
            Attributes::Ply(a) => a.texcoords(polygons),
            Attributes::Off(a) => a.texcoords(polygons),
            Attributes::Tetrahedra(_) | Attributes::Msh(_) => None,
        }
    }

    /// Per-vertex colours (r, g, b in [0, 1]), if the file has them for every vertex.
    pub fn vertex_colors(&self) -> Option<Vec<[f64; 3]>> {
        match self {
            Attributes::None => None,
            Attributes::Obj(a) => a.vertex_colors(),
            Attributes::Ply(a) => a.vertex_colors(),
            Attributes::Off(a) => a.vertex_colors(),
            Attributes::Tetrahedra(_) | Attributes::Msh(_) => None,
        }
    }

    /// Whether the file stores vertex normals (outputs then write recomputed ones).
    pub fn has_normals(&self) -> bool {
        match self {
            Attributes::None => false,
            Attributes::Obj(a) => a.has_normals(),
            Attributes::Ply(a) => a.has_normals(),
            Attributes::Off(a) => a.has_normals(),
            Attributes::Tetrahedra(_) | Attributes::Msh(_) => false,
        }
    }

    /// Per-vertex scalar properties other than positions, normals and colours (PLY).
    pub fn vertex_scalars(&self) -> Vec<VertexScalar> {
        match self {
            Attributes::Ply(a) => a.vertex_scalars(),
            _ => Vec::new(),
        }
    }

    /// Every kind of attribute the file carries, for writers of another format to say what
    /// they drop.
    pub fn kinds(&self) -> Vec<AttributeKind> {
        match self {
            Attributes::None => Vec::new(),
            Attributes::Obj(a) => a.kinds(),
            Attributes::Ply(a) => a.kinds(),
            Attributes::Off(a) => a.kinds(),
            // Kept by every writer of tetrahedra; the others write no tetrahedra (and say so).
            Attributes::Tetrahedra(_) => Vec::new(),
            Attributes::Msh(a) => a.kinds(),
        }
    }

    /// Which tetrahedra the file listed left-handed (`.msh`, TetGen), if any.
    pub fn tetrahedron_order(&self) -> Option<&TetrahedronOrder> {
        match self {
            Attributes::Tetrahedra(order) => Some(order),
            Attributes::Msh(source) => source.order.as_ref(),
            _ => None,
        }
    }

    /// The physical groups of a `.msh` file (empty for any other).
    pub fn physical_groups(&self) -> &[msh::PhysicalGroup] {
        match self {
            Attributes::Msh(source) => &source.physical_groups,
            _ => &[],
        }
    }
}

/// How [`write_mesh_with`] encodes a mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WriteFormat {
    /// Wavefront OBJ, coordinates with enough digits to read back exactly; a mesh read from
    /// OBJ comes back line for line.
    Obj,
    /// PLY: a mesh read from PLY keeps every element and property with its type, in the given
    /// encoding (`None`: the file's own); others get `double` coordinates and
    /// `list uchar int vertex_indices` faces (`None`: binary little endian).
    Ply(Option<PlyEncoding>),
    /// Binary STL (`f32` coordinates, one normal per face; unreferenced vertices are lost).
    StlBinary,
    /// OFF, coordinates with enough digits to read back exactly.
    Off,
    /// Gmsh MSH 4.1 ASCII: nodes, tetrahedra and triangles, exactly round-tripping coordinates.
    Msh,
    /// TetGen `X.node` + `X.ele` (for a path `X.*`), 1-based; needs tetrahedra.
    TetGen,
    /// VTK XML unstructured grid (`.vtu`): tetrahedra when the mesh has them, else its polygons.
    Vtu,
}

impl WriteFormat {
    /// The default encoding for a path's extension: `.obj`, `.ply` (the input's encoding, else
    /// binary little endian), `.stl` (binary), `.off`, `.msh` (4.1 ASCII), `.node` or `.ele`
    /// (the TetGen pair), `.vtu`.
    ///
    /// # Errors
    /// [`IoError::UnsupportedFormat`] for any other extension.
    pub fn from_path(path: &Path) -> Result<Self, IoError> {
        if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("vtu")) {
            return Ok(Self::Vtu);
        }
        Ok(match MeshFormat::from_path(path)? {
            MeshFormat::Obj => Self::Obj,
            MeshFormat::Ply => Self::Ply(None),
            MeshFormat::Stl => Self::StlBinary,
            MeshFormat::Off => Self::Off,
            MeshFormat::Msh => Self::Msh,
            MeshFormat::TetGen => Self::TetGen,
        })
    }
}

/// Reads a mesh, choosing the format from the extension (`.obj`, `.ply`, `.stl`, `.off`, `.msh`,
/// `.node`, `.ele`, case-insensitive). Vertices keep their file order (see the [module docs](self)).
///
/// # Errors
/// [`IoError`] naming `path`: unsupported extension, file not found, malformed content (with the
/// line or byte offset), or an invalid mesh.
pub fn read_mesh(path: &Path) -> Result<LoadedMesh, IoError> {
    let format = MeshFormat::from_path(path)?;
    let open = || {
        let file = File::open(path).map_err(|source| IoError::Open { path: path.to_path_buf(), source })?;
        Ok::<_, IoError>(BufReader::new(file))
    };
    match format {
        MeshFormat::Obj => obj::read_obj(open()?, path),
        MeshFormat::Ply => ply::read_ply(open()?, path),
        MeshFormat::Stl => stl::read_stl(open()?, path),
        MeshFormat::Off => off::read_off(open()?, path),
        MeshFormat::Msh => msh::read_msh(open()?, path),
        // Two files: the TetGen reader opens both.
        MeshFormat::TetGen => tetgen::read_tetgen_files(path),
    }
}

/// Writes a mesh with the attributes of the file it was read from ([`LoadedMesh::attributes`],
/// or [`Attributes::None`]) in the default encoding for the extension (see
/// [`WriteFormat::from_path`]), atomically. Returns what the format could not keep or what was
/// recomputed (normals), each naming `path`.
///
/// # Errors
/// [`IoError::UnsupportedFormat`], [`IoError::Mesh`] if the mesh does not validate, or
/// [`IoError::Write`].
pub fn write_mesh(path: &Path, mesh: &Mesh, attributes: &Attributes) -> Result<Warnings, IoError> {
    write_mesh_with(path, mesh, attributes, WriteFormat::from_path(path)?)
}

/// Writes a mesh in the given encoding, whatever the extension, atomically ([`WriteFormat::TetGen`]
/// writes the pair `X.node`, `X.ele` next to `path`, each atomically). Returns the warnings, as
/// [`write_mesh`].
///
/// # Errors
/// [`IoError::Mesh`] if the mesh does not validate (nothing is written), [`IoError::Invalid`] for
/// TetGen without tetrahedra (nothing is written), or [`IoError::Write`].
pub fn write_mesh_with(
    path: &Path,
    mesh: &Mesh,
    attributes: &Attributes,
    format: WriteFormat,
) -> Result<Warnings, IoError> {
    // A `Mesh` has public fields; refuse to write indices that would not read back.
    mesh.validate().map_err(|source| IoError::Mesh { path: path.to_path_buf(), source })?;
    let mut warnings = Warnings::new();
    let warn = &mut warnings;
    if !mesh.tetrahedra.is_empty() && !matches!(format, WriteFormat::Msh | WriteFormat::TetGen | WriteFormat::Vtu) {
        warn.add_many(
            "tetrahedra_not_written",
            "tetrahedra not written: this format stores surfaces (use .vtu or .msh to keep them)",
            mesh.num_tetrahedra(),
            || "tetrahedron 0".into(),
        );
    }
    match format {
        WriteFormat::Obj => write_atomic(path, |w| obj::write_obj(w, mesh, attributes, warn))?,
        WriteFormat::Ply(encoding) => write_atomic(path, |w| ply::write_ply(w, mesh, attributes, encoding, warn))?,
        WriteFormat::StlBinary => write_atomic(path, |w| stl::write_stl_binary(w, mesh, attributes, warn))?,
        WriteFormat::Off => write_atomic(path, |w| off::write_off(w, mesh, attributes, warn))?,
        WriteFormat::Msh => match attributes {
            // The file read, its coordinates replaced: tags, groups and every element kept.
            Attributes::Msh(source) if !source.text.is_empty() && source.fits(mesh) => {
                write_atomic(path, |w| source.write(w, mesh))?;
            }
            _ => {
                report_dropped(attributes, &[], "MSH", warn);
                write_atomic(path, |w| msh::write_msh(w, &in_file_order(mesh, attributes)))?;
            }
        },
        WriteFormat::TetGen => {
            report_dropped(attributes, &[], "TetGen files", warn);
            tetgen::write_tetgen_files(path, &in_file_order(mesh, attributes))?;
        }
        WriteFormat::Vtu => write_atomic(path, |w| vtu::write_vtu(w, mesh, attributes, &[], warn))?,
    }
    Ok(warnings.for_file(path))
}

/// `mesh` with its tetrahedra as the file of `attributes` ordered their nodes (see
/// [`TetrahedronOrder`]): what the writers of tetrahedra write.
pub(crate) fn in_file_order<'a>(mesh: &'a Mesh, attributes: &Attributes) -> std::borrow::Cow<'a, Mesh> {
    let file_order = attributes.tetrahedron_order().and_then(|order| order.file_order(&mesh.tetrahedra));
    match file_order {
        Some(tetrahedra) => {
            let mut copy = mesh.clone();
            copy.tetrahedra = tetrahedra;
            std::borrow::Cow::Owned(copy)
        }
        None => std::borrow::Cow::Borrowed(mesh),
    }
}

/// Names, in one warning, every kind of `attributes` that a writer of `format` does not keep
/// (`kept`).
pub(crate) fn report_dropped(attributes: &Attributes, kept: &[AttributeKind], format: &str, warnings: &mut Warnings) {
    let dropped: Vec<String> =
        attributes.kinds().into_iter().filter(|k| !kept.contains(k)).map(|k| k.describe()).collect();
    if let Some(first) = dropped.first().cloned() {
        warnings.add_many(
            "attributes_dropped",
            &format!("kinds of attribute not written to {format} ({})", dropped.join(", ")),
            dropped.len(),
            || first,
        );
    }
}

/// Smooth per-vertex normals of `mesh` at its positions ([`crate::geometry::indexed_normals`]
/// indexed by vertex; `None` for a vertex no polygon uses or whose normal vanishes), counted in
/// `warnings` as recomputed (what every writer that stores vertex normals reports).
pub(crate) fn recompute_vertex_normals(mesh: &Mesh, warnings: &mut Warnings) -> Vec<Option<glam::DVec3>> {
    let normals =
        crate::geometry::indexed_normals(&mesh.positions, &mesh.polygons, mesh.polygons.indices(), mesh.num_vertices());
    let mut recomputed = normals.iter().enumerate().filter(|(_, n)| n.is_some());
    if let Some((first, _)) = recomputed.next() {
        warnings.add_many(
            "normals_recomputed",
            "normals recomputed from the moved geometry",
            1 + recomputed.count(),
            || format!("vertex {first}"),
        );
    }
    normals
}

/// Counts, in `warnings`, the polygons with more than 3 corners that a triangles-only format
/// (`format`) writes as their triangles.
pub(crate) fn report_polygons_split(mesh: &Mesh, format: &str, warnings: &mut Warnings) {
    let mut split = mesh.polygons.iter().enumerate().filter(|(_, p)| p.len() > 3);
    if let Some((first, p)) = split.next() {
        let corners = p.len();
        warnings.add_many(
            "polygons_split",
            &format!("polygons written as triangles ({format} stores triangles only)"),
            1 + split.count(),
            || format!("face {first} ({corners} corners)"),
        );
    }
}

/// Builds the mesh from polygons, attributing any error (and every warning) to `path`; no
/// attributes (the readers that have some set them).
pub(crate) fn build_mesh(path: &Path, positions: Vec<glam::DVec3>, polygons: Polygons) -> Result<LoadedMesh, IoError> {
    let (mesh, warnings) = Mesh::from_polygons(positions, polygons)
        .map_err(|source| IoError::Mesh { path: path.to_path_buf(), source })?;
    Ok(LoadedMesh { mesh, attributes: Attributes::None, warnings: warnings.for_file(path) })
}

/// Writes an `f64` with the shortest representation that parses back to the same value.
pub(crate) fn write_f64(w: &mut dyn Write, x: f64) -> io::Result<()> {
    // `Debug` is shortest-round-trip and switches to exponent notation for tiny/huge values
    // (unlike `Display`, which would spell out 300 zeros).
    write!(w, "{x:?}")
}

/// Writes `x y z`, each coordinate as [`write_f64`] does (a vertex or normal, before whatever
/// else its line holds).
pub(crate) fn write_xyz(w: &mut dyn Write, p: glam::DVec3) -> io::Result<()> {
    write_f64(w, p.x)?;
    w.write_all(b" ")?;
    write_f64(w, p.y)?;
    w.write_all(b" ")?;
    write_f64(w, p.z)
}

/// Writes `x y z` and a newline ([`write_xyz`]): every text writer's vertex line, after its
/// own prefix.
pub(crate) fn write_point(w: &mut dyn Write, p: glam::DVec3) -> io::Result<()> {
    write_xyz(w, p)?;
    w.write_all(b"\n")
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn format_from_extension_is_case_insensitive() {
        assert_eq!(MeshFormat::from_path(Path::new("a/b.OBJ")).unwrap(), MeshFormat::Obj);
        assert_eq!(MeshFormat::from_path(Path::new("b.Ply")).unwrap(), MeshFormat::Ply);
        assert_eq!(
            WriteFormat::from_path(Path::new("x.stl")).unwrap(),
            WriteFormat::StlBinary,
            "binary STL by default"
        );
        let err = MeshFormat::from_path(Path::new("mesh.dae")).unwrap_err().to_string();
        assert!(err.contains("mesh.dae") && err.contains("'.dae'") && err.contains(".obj, .ply, .stl, .off"), "{err}");
        let err = MeshFormat::from_path(Path::new("mesh")).unwrap_err().to_string();
        assert!(err.contains("(no extension)"), "{err}");
    }

    #[test]
    fn f64_written_round_trips() {
        for x in [0.1, -1.0 / 3.0, 1e-300, 1.7976931348623157e308, 5e-324, -0.0, 123_456_789.123_456_79] {
            let mut out = Vec::new();
            write_f64(&mut out, x).unwrap();
            let back: f64 = String::from_utf8(out).unwrap().parse().unwrap();
            assert_eq!(back.to_bits(), x.to_bits());
        }
    }
}
