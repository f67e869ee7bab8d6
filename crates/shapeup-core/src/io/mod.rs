//! Mesh input and output.
//!
//! | format | read | write |
//! |--------|------|-------|
//! | Wavefront `.obj` | `v` (colours, `w`), `vt`, `vn`, `f` in every index form (negative too), and every other line kept | the file line for line with `v` moved and `vn` recomputed ([`obj`]); other meshes: `v`, `vt`, `vn`, `f` per polygon |
//! | Stanford `.ply` | ascii, binary little and big endian, any numeric types; every element and property kept; faces and `tristrips` | every element and property with its type, in the file's (or a chosen) encoding ([`ply`]); other meshes: `double` x y z, normals, colours, polygons |
//! | `.stl` | ascii and binary | binary (triangles only: vertex indices are not kept, a warning says so) |
//! | `.off` | `OFF`, `COFF`, `NOFF`, `STOFF`…; per-vertex and per-face values kept | the keyword and values as read, `N` normals recomputed ([`off`]) |
//! | Gmsh `.msh` | ASCII 4.1 and 2.2: 4-node tetrahedra, 3-node triangles (other elements skipped) | ASCII 4.1 |
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
//! [`Mesh::attributes`](crate::attributes::Attributes). Every writer returns [`Warnings`] for
//! what it recomputed (normals) or what its format cannot hold; readers return theirs in
//! [`LoadedMesh::warnings`]. Only `.msh` and `.node`/`.ele` store tetrahedra; a mesh read from
//! them has the boundary of its tetrahedra as triangles (see [`msh`], [`tetgen`]). A UTF-8
//! byte-order mark at the start of a text file is skipped.
//!
//! Every reader is hand-written (the crates available reorder or drop vertices, or do not report
//! where a file is broken); no input makes them panic, and counts from a header never size an
//! allocation beyond [`MAX_PREALLOCATION`]. Every writer goes through [`write_atomic`].

pub mod msh;
pub mod obj;
pub mod off;
pub mod ply;
pub mod stl;
pub mod tetgen;
pub mod vtu;

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::attributes::AttributeKind;
use crate::mesh::{Mesh, MeshError, Polygons};
use crate::warnings::Warnings;

pub use ply::PlyEncoding;

/// Most elements any reader reserves room for up front, whatever a header claims; vectors grow
/// past it as data actually arrives.
pub const MAX_PREALLOCATION: usize = 1 << 20;

/// An error reading or writing a mesh file. Each message is one line naming the file and, where
/// there is one, the line (text formats) or byte offset and element (binary formats).
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The file could not be opened.
    #[error("cannot open {}: {source}", path.display())]
    Open {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: io::Error,
    },
    /// Reading failed part-way (not a format problem).
    #[error("error reading {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: io::Error,
    },
    /// A text file (or the text header of a binary one) is malformed at a line.
    #[error("{}: line {line}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A binary file is malformed (usually truncated) at a byte offset.
    #[error("{}: byte offset {offset}: {message}", path.display())]
    Binary {
        /// The file.
        path: PathBuf,
        /// Offset from the start of the file where the problem was found.
        offset: u64,
        /// What is wrong (naming the element and its index) and what was expected.
        message: String,
    },
    /// A well-formed file that holds no usable mesh (no vertices, no triangles).
    #[error("{}: {message}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is missing.
        message: String,
    },
    /// The file extension is not one of the supported formats.
    #[error("{}: unsupported mesh format {} (supported: {})", path.display(), describe_extension(extension), SUPPORTED)]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
        /// Its extension (empty when it has none).
        extension: String,
    },
    /// The elements read do not form a valid mesh (index out of range, non-finite coordinate).
    #[error("{}: invalid mesh: {source}", path.display())]
    Mesh {
        /// The file.
        path: PathBuf,
        /// What is wrong with the mesh.
        source: MeshError,
    },
    /// Writing (or replacing) the file failed; the previous file, if any, is untouched.
    #[error("cannot write {}: {source}", path.display())]
    Write {
        /// The target file.
        path: PathBuf,
        /// The operating system's (or the writer's) error.
        source: io::Error,
    },
}

const SUPPORTED: &str = ".obj, .ply, .stl, .off, .msh, .node/.ele";

fn describe_extension(extension: &str) -> String {
    if extension.is_empty() { "(no extension)".to_owned() } else { format!("'.{extension}'") }
}

/// A mesh read from a file, with what reading changed.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedMesh {
    /// The mesh, vertices in file order, with the file's polygons and attributes.
    pub mesh: Mesh,
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
    /// Gmsh MSH, ASCII 4.1 or 2.2.
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

/// Writes a mesh in the default encoding for the extension (see [`WriteFormat::from_path`]),
/// atomically. Returns what the format could not keep or what was recomputed (normals), each
/// naming `path`.
///
/// # Errors
/// [`IoError::UnsupportedFormat`], [`IoError::Mesh`] if the mesh does not validate, or
/// [`IoError::Write`].
pub fn write_mesh(path: &Path, mesh: &Mesh) -> Result<Warnings, IoError> {
    write_mesh_with(path, mesh, WriteFormat::from_path(path)?)
}

/// Writes a mesh in the given encoding, whatever the extension, atomically ([`WriteFormat::TetGen`]
/// writes the pair `X.node`, `X.ele` next to `path`, each atomically). Returns the warnings, as
/// [`write_mesh`].
///
/// # Errors
/// [`IoError::Mesh`] if the mesh does not validate (nothing is written), [`IoError::Invalid`] for
/// TetGen without tetrahedra (nothing is written), or [`IoError::Write`].
pub fn write_mesh_with(path: &Path, mesh: &Mesh, format: WriteFormat) -> Result<Warnings, IoError> {
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
        WriteFormat::Obj => write_atomic(path, |w| obj::write_obj(w, mesh, warn))?,
        WriteFormat::Ply(encoding) => write_atomic(path, |w| ply::write_ply(w, mesh, encoding, warn))?,
        WriteFormat::StlBinary => write_atomic(path, |w| stl::write_stl_binary(w, mesh, warn))?,
        WriteFormat::Off => write_atomic(path, |w| off::write_off(w, mesh, warn))?,
        WriteFormat::Msh => {
            report_dropped(mesh, &[], "MSH", warn);
            write_atomic(path, |w| msh::write_msh(w, mesh))?;
        }
        WriteFormat::TetGen => {
            report_dropped(mesh, &[], "TetGen files", warn);
            tetgen::write_tetgen_files(path, mesh)?;
        }
        WriteFormat::Vtu => write_atomic(path, |w| vtu::write_vtu(w, mesh, &[], warn))?,
    }
    Ok(warnings.for_file(path))
}

/// Names, in one warning, every kind of `mesh`'s attributes that a writer of `format` does not
/// keep (`kept`).
pub(crate) fn report_dropped(mesh: &Mesh, kept: &[AttributeKind], format: &str, warnings: &mut Warnings) {
    let dropped: Vec<String> =
        mesh.attributes.kinds().into_iter().filter(|k| !kept.contains(k)).map(|k| k.describe()).collect();
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

/// Distinguishes temp files of concurrent writes from one process.
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Writes a file atomically: `write` fills a temp file `.NAME.tmp-PID-N` in the target's
/// directory (buffered), which is flushed, synced to disk and renamed over `path`. Readers see
/// either the old file or the complete new one; on any error the temp file is removed and the
/// target is untouched.
///
/// # Errors
/// [`IoError::Write`] naming `path`, from creating the temp file, from `write`, or from the
/// rename.
pub fn write_atomic(path: &Path, write: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<(), IoError> {
    let write_error = |source| IoError::Write { path: path.to_path_buf(), source };
    let (dir, temp) = temp_path(path).map_err(write_error)?;

    let file = OpenOptions::new().write(true).create(true).truncate(true).open(&temp).map_err(write_error)?;
    let result = (|| {
        let mut buffered = BufWriter::new(file);
        write(&mut buffered)?;
        let file = buffered.into_inner().map_err(io::IntoInnerError::into_error)?;
        file.sync_all()?;
        drop(file);
        fs::rename(&temp, path)
    })();
    if let Err(source) = result {
        // Best effort: the temp file is ours and must not linger; the original error matters more.
        let _ = fs::remove_file(&temp);
        return Err(write_error(source));
    }
    // Make the rename itself durable where directories can be synced (not on Windows).
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// The folder of `path` (`.` for a bare name) and a fresh temp file name `.NAME.tmp-PID-N` in
/// it, as [`write_atomic`] writes through.
fn temp_path(path: &Path) -> io::Result<(&Path, PathBuf)> {
    let file_name =
        path.file_name().ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "the path names no file"))?;
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    Ok((dir, dir.join(format!(".{}.tmp-{}-{n}", file_name.to_string_lossy(), std::process::id()))))
}

/// The mesh formats a result can be written in, by extension (`shapeup deform -o`,
/// `Scene.deform(output=…)`).
pub const MESH_OUTPUT_EXTENSIONS: &[&str] = &["obj", "ply", "off", "stl", "vtu", "msh"];

/// Why a result cannot go where it was asked to: checked before any work, so that a run that
/// writes a mesh and a report never writes one and then fails on the other.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// An extension that is not one of `allowed`.
    #[error("{}: unsupported output format \"{ext}\" (use one of: {})", path.display(), allowed.join(", "))]
    Extension {
        /// The output.
        path: PathBuf,
        /// Its extension, lower case.
        ext: String,
        /// What may be written there.
        allowed: &'static [&'static str],
    },
    /// The folder it goes in does not exist.
    #[error("{}: the folder {} does not exist", path.display(), dir.display())]
    MissingFolder {
        /// The output.
        path: PathBuf,
        /// Its folder.
        dir: PathBuf,
    },
    /// The folder cannot take a new file (read-only, no permission, not a file system).
    #[error("{}: cannot write in {}: {source}", path.display(), dir.display())]
    Unwritable {
        /// The output.
        path: PathBuf,
        /// Its folder.
        dir: PathBuf,
        /// Why.
        source: io::Error,
    },
}

/// Fails unless `path`'s extension (case-insensitive) is one of `allowed`.
///
/// # Errors
/// [`OutputError::Extension`].
pub fn check_output_extension(path: &Path, allowed: &'static [&'static str]) -> Result<(), OutputError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
    if allowed.contains(&ext.as_str()) {
        Ok(())
    } else {
        Err(OutputError::Extension { path: path.to_path_buf(), ext, allowed })
    }
}

/// Fails unless the folder `path` goes in exists and takes a new file: it creates (and
/// removes) the kind of temp file [`write_atomic`] writes through.
///
/// # Errors
/// [`OutputError::MissingFolder`] or [`OutputError::Unwritable`].
pub fn check_output_folder(path: &Path) -> Result<(), OutputError> {
    let unwritable = |dir: &Path, source| OutputError::Unwritable { path: path.to_path_buf(), dir: dir.into(), source };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty() && !d.is_dir()) {
        return Err(OutputError::MissingFolder { path: path.to_path_buf(), dir: dir.into() });
    }
    let (dir, temp) = temp_path(path).map_err(|e| unwritable(Path::new("."), e))?;
    OpenOptions::new().write(true).create_new(true).open(&temp).map_err(|e| unwritable(dir, e))?;
    fs::remove_file(&temp).map_err(|e| unwritable(dir, e))
}

/// The UTF-8 byte-order mark, skipped at the start of every text file.
pub const UTF8_BOM: &[u8] = b"\xEF\xBB\xBF";

/// Line-by-line reading of a text file with 1-based line numbers, `\n` or `\r\n` endings, a
/// UTF-8 byte-order mark at the start skipped, and invalid UTF-8 replaced (it only ever occurs
/// in comments and names).
pub(crate) struct Lines<R> {
    reader: R,
    bytes: Vec<u8>,
    text: String,
    /// Number of the line last returned (0 before the first).
    pub(crate) number: usize,
    /// Bytes consumed so far, line endings included.
    pub(crate) consumed: u64,
}

impl<R: BufRead> Lines<R> {
    pub(crate) fn new(reader: R) -> Self {
        Self { reader, bytes: Vec::new(), text: String::new(), number: 0, consumed: 0 }
    }

    /// The next line's number and text without its line ending, or `None` at the end of the file.
    pub(crate) fn next_line(&mut self) -> io::Result<Option<(usize, &str)>> {
        self.bytes.clear();
        let read = self.reader.read_until(b'\n', &mut self.bytes)?;
        if read == 0 {
            return Ok(None);
        }
        self.number += 1;
        self.consumed += read as u64;
        if self.number == 1 && self.bytes.starts_with(UTF8_BOM) {
            // A UTF-8 byte-order mark is not part of the first line (editors on Windows add it).
            self.bytes.drain(..UTF8_BOM.len());
        }
        if self.bytes.last() == Some(&b'\n') {
            self.bytes.pop();
        }
        if self.bytes.last() == Some(&b'\r') {
            self.bytes.pop();
        }
        self.text.clear();
        self.text.push_str(&String::from_utf8_lossy(&self.bytes));
        Ok(Some((self.number, &self.text)))
    }

    /// The underlying reader, positioned just after the last line returned.
    pub(crate) fn into_inner(self) -> R {
        self.reader
    }
}

/// Builds the mesh from polygons, attributing any error (and every warning) to `path`.
pub(crate) fn build_mesh(path: &Path, positions: Vec<glam::DVec3>, polygons: Polygons) -> Result<LoadedMesh, IoError> {
    let (mesh, warnings) = Mesh::from_polygons(positions, polygons)
        .map_err(|source| IoError::Mesh { path: path.to_path_buf(), source })?;
    Ok(LoadedMesh { mesh, warnings: warnings.for_file(path) })
}

/// Parses one coordinate, naming it in the error.
pub(crate) fn parse_coordinate(token: &str, what: &str) -> Result<f64, String> {
    token.parse::<f64>().map_err(|_| format!("{what} '{token}' is not a number"))
}

/// `Vec::with_capacity` bounded by [`MAX_PREALLOCATION`], for counts read from a file.
pub(crate) fn bounded_vec<T>(claimed: usize) -> Vec<T> {
    Vec::with_capacity(claimed.min(MAX_PREALLOCATION))
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
    fn lines_strip_crlf_and_count() {
        let mut lines = Lines::new(&b"a\r\nb\n\nc"[..]);
        assert_eq!(lines.next_line().unwrap(), Some((1, "a")));
        assert_eq!(lines.next_line().unwrap(), Some((2, "b")));
        assert_eq!(lines.next_line().unwrap(), Some((3, "")));
        assert_eq!(lines.next_line().unwrap(), Some((4, "c")));
        assert_eq!(lines.number, 4);
        assert_eq!(lines.next_line().unwrap(), None);
        let mut lines = Lines::new(&b"\xEF\xBB\xBFv 1 2 3\n\xEF\xBB\xBF"[..]);
        assert_eq!(lines.next_line().unwrap(), Some((1, "v 1 2 3")), "the mark is skipped at the start");
        assert_eq!(lines.next_line().unwrap(), Some((2, "\u{feff}")), "and only there");
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
