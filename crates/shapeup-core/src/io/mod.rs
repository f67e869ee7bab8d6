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

pub mod attributes;
pub mod msh;
pub mod obj;
pub mod off;
pub mod ply;
pub mod stl;
pub mod tetgen;
pub mod vtu;

use std::fs::{self, File};
use std::io::{self, BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::mesh::{Mesh, MeshError, Polygons};
use crate::warnings::Warnings;

pub use attributes::{AttributeKind, NO_INDEX, TexCoords, VertexScalar};
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
        }
    }

    /// Per-vertex colours (r, g, b in [0, 1]), if the file has them for every vertex.
    pub fn vertex_colors(&self) -> Option<Vec<[f64; 3]>> {
        match self {
            Attributes::None => None,
            Attributes::Obj(a) => a.vertex_colors(),
            Attributes::Ply(a) => a.vertex_colors(),
            Attributes::Off(a) => a.vertex_colors(),
        }
    }

    /// Whether the file stores vertex normals (outputs then write recomputed ones).
    pub fn has_normals(&self) -> bool {
        match self {
            Attributes::None => false,
            Attributes::Obj(a) => a.has_normals(),
            Attributes::Ply(a) => a.has_normals(),
            Attributes::Off(a) => a.has_normals(),
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
/// [`WriteFormat::from_path`]), atomically. Returns what the format could not keep or what was recomputed (normals), each
/// naming `path`.
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
        WriteFormat::Msh => {
            report_dropped(attributes, &[], "MSH", warn);
            write_atomic(path, |w| msh::write_msh(w, mesh))?;
        }
        WriteFormat::TetGen => {
            report_dropped(attributes, &[], "TetGen files", warn);
            tetgen::write_tetgen_files(path, mesh)?;
        }
        WriteFormat::Vtu => write_atomic(path, |w| vtu::write_vtu(w, mesh, attributes, &[], warn))?,
    }
    Ok(warnings.for_file(path))
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

/// Writes a file atomically: `write` fills a temporary file in the target's folder (buffered),
/// which is flushed, synced to disk and renamed over `path`. Readers see either the old file or
/// the complete new one; on any error the temporary file is removed and the target is untouched.
///
/// The temporary file (`.NAME.XXXXXX.tmp`, random letters) is created exclusively (`O_EXCL`)
/// with an unpredictable name, so a symbolic link planted in a shared folder is never followed;
/// the rename replaces a link at `path` itself by the new file, leaving the link's target
/// untouched. On Unix the new file has the mode of the regular file it replaces, else the usual
/// `0666` less the umask.
///
/// # Errors
/// [`IoError::Write`] naming `path`, from creating the temporary file, from `write`, or from the
/// rename.
pub fn write_atomic(path: &Path, write: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<(), IoError> {
    let write_error = |source| IoError::Write { path: path.to_path_buf(), source };
    let (dir, mut temp) = create_temp(path).map_err(write_error)?;
    let result = (|| {
        keep_mode_of(path, temp.as_file())?;
        let mut buffered = BufWriter::new(temp.as_file_mut());
        write(&mut buffered)?;
        buffered.into_inner().map_err(io::IntoInnerError::into_error)?.sync_all()?;
        // On failure the temporary file comes back inside the error and is removed with it.
        temp.persist(path).map(drop).map_err(|e| e.error)
    })();
    result.map_err(write_error)?;
    // Make the rename itself durable where directories can be synced (not on Windows).
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// A new temporary file for `path` in its folder, as [`write_atomic`] (and
/// [`check_output_folder`]) write through: hidden, `.NAME.` + random letters + `.tmp`, created
/// exclusively by the `tempfile` crate (which retries on a name taken) and removed when dropped,
/// with mode `0666` before the umask on Unix (tempfile's own default, `0600`, would make every
/// written mesh private).
fn create_temp(path: &Path) -> io::Result<(&Path, tempfile::NamedTempFile)> {
    let name = path.file_name().ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "the path names no file"))?;
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    let mut prefix = std::ffi::OsString::from(".");
    prefix.push(name);
    prefix.push(".");
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp").rand_bytes(12);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(fs::Permissions::from_mode(0o666));
    }
    Ok((dir, builder.tempfile_in(dir)?))
}

/// Gives `file` the permission bits of the regular file at `path`, if there is one (replacing a
/// file keeps its mode); a symbolic link or nothing at `path` leaves `file` as created.
fn keep_mode_of(path: &Path, file: &File) -> io::Result<()> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        if let Ok(meta) = fs::symlink_metadata(path)
            && meta.is_file()
        {
            file.set_permissions(fs::Permissions::from_mode(meta.permissions().mode() & 0o777))?;
        }
    }
    #[cfg(not(unix))]
    let _ = (path, file);
    Ok(())
}

/// The mesh formats a result can be written in, by extension (`shapeup deform -o`,
/// `Scene.deform(output=…)`).
pub const MESH_OUTPUT_EXTENSIONS: &[&str] = &["obj", "ply", "off", "stl", "vtu", "msh"];

/// Why a result cannot go where it was asked to: checked before any work, so that a run that
/// writes a mesh and a report never writes one and then fails on the other.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// An extension that is not one of `allowed`.
    #[error("{}: unsupported output format \"{}\" (use one of: {})", one_line(path.display()), one_line(ext), allowed.join(", "))]
    Extension {
        /// The output.
        path: PathBuf,
        /// Its extension, lower case.
        ext: String,
        /// What may be written there.
        allowed: &'static [&'static str],
    },
    /// The folder it goes in does not exist.
    #[error("{}: the folder {} does not exist", one_line(path.display()), one_line(dir.display()))]
    MissingFolder {
        /// The output.
        path: PathBuf,
        /// Its folder.
        dir: PathBuf,
    },
    /// The folder cannot take a new file (read-only, no permission, not a file system).
    #[error("{}: cannot write in {}: {source}", one_line(path.display()), one_line(dir.display()))]
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
/// removes) the kind of temporary file [`write_atomic`] writes through.
///
/// # Errors
/// [`OutputError::MissingFolder`] or [`OutputError::Unwritable`].
pub fn check_output_folder(path: &Path) -> Result<(), OutputError> {
    let unwritable = |dir: &Path, source| OutputError::Unwritable { path: path.to_path_buf(), dir: dir.into(), source };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty() && !d.is_dir()) {
        return Err(OutputError::MissingFolder { path: path.to_path_buf(), dir: dir.into() });
    }
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let (_, temp) = create_temp(path).map_err(|e| unwritable(dir, e))?;
    temp.close().map_err(|e| unwritable(dir, e))
}

/// The name of the UTF-16 encoding whose byte-order mark `prefix` starts with (`FF FE`:
/// "UTF-16 little endian", `FE FF`: "UTF-16 big endian"), or `None`. Readers decode such text
/// files ([`decode_text`]) or refuse them with one line naming the encoding, instead of
/// misreading their bytes.
pub(crate) fn utf16_encoding(prefix: &[u8]) -> Option<&'static str> {
    utf16_of(prefix).map(|(name, _)| name)
}

fn utf16_of(prefix: &[u8]) -> Option<(&'static str, &'static encoding_rs::Encoding)> {
    match prefix {
        [0xFF, 0xFE, ..] => Some(("UTF-16 little endian", encoding_rs::UTF_16LE)),
        [0xFE, 0xFF, ..] => Some(("UTF-16 big endian", encoding_rs::UTF_16BE)),
        _ => None,
    }
}

/// Text that is not valid in its encoding: the payload of the [`io::Error`] (kind
/// `InvalidData`) that [`TextReader`] and [`read_text_file`] return; [`read_error`] turns it
/// into an [`IoError::Binary`] naming the byte offset.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct DecodeError {
    /// "UTF-16 little endian", "UTF-16 big endian" or "UTF-8".
    pub(crate) encoding: &'static str,
    /// Offset in the file of the first byte that is not valid text.
    pub(crate) offset: u64,
}

impl std::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let why = if self.encoding.starts_with("UTF-16") {
            "an unpaired surrogate, or an odd number of bytes"
        } else {
            "a byte sequence that is no character"
        };
        write!(f, "not valid {} text at byte offset {} ({why})", self.encoding, self.offset)
    }
}

impl std::error::Error for DecodeError {}

impl DecodeError {
    fn into_io(self) -> io::Error {
        io::Error::new(io::ErrorKind::InvalidData, self)
    }

    /// The decoding error that `error` carries, if it is one.
    pub(crate) fn of(error: &io::Error) -> Option<&DecodeError> {
        error.get_ref().and_then(|e| e.downcast_ref::<DecodeError>())
    }
}

/// The error for a failed read of `path`: [`IoError::Binary`] at the offset for text that is
/// not valid in its encoding ([`DecodeError`]), else [`IoError::Read`].
pub(crate) fn read_error(path: &Path, source: io::Error) -> IoError {
    match DecodeError::of(&source) {
        Some(e) => IoError::Binary {
            path: path.to_path_buf(),
            offset: e.offset,
            message: format!("the file is not valid {} text (the byte-order mark at its start says it is)", e.encoding),
        },
        None => IoError::Read { path: path.to_path_buf(), source },
    }
}

/// [`read_error`] for an error already made: an [`IoError::Read`] whose cause is a
/// [`DecodeError`] (from a line reader that maps every error to `Read`) becomes
/// [`IoError::Binary`]; any other error is returned as it is.
pub(crate) fn with_decode_errors(error: IoError) -> IoError {
    match error {
        IoError::Read { path, source } => read_error(&path, source),
        other => other,
    }
}

/// A text file's bytes as UTF-8 for the line readers: the bytes themselves, or, after a UTF-16
/// byte-order mark (`FF FE`, `FE FF`), their transcoding to UTF-8 (without the mark). Malformed
/// UTF-16 (an unpaired surrogate, an odd number of bytes) is an `InvalidData` error carrying a
/// [`DecodeError`] with its byte offset in the file, never a replacement character. Anything
/// else passes through untouched (UTF-8, a UTF-8 byte-order mark, invalid UTF-8, binary data),
/// so readers keep their own handling of those.
///
/// Every text reader (OBJ, OFF, ascii STL, TetGen) reads through one; PLY and MSH can do the
/// same with [`decode_text`].
pub(crate) struct TextReader<R> {
    inner: TextInner<R>,
}

enum TextInner<R> {
    /// The bytes sniffed for a byte-order mark, then the rest of the reader.
    Plain(io::Chain<io::Cursor<Vec<u8>>, R>),
    Utf16(Box<Utf16Decoder<R>>),
}

/// Wraps `reader` in a [`TextReader`], looking at its first two bytes for a UTF-16 byte-order
/// mark.
///
/// # Errors
/// Any error reading those bytes.
pub(crate) fn decode_text<R: BufRead>(mut reader: R) -> io::Result<TextReader<R>> {
    let mut prefix = Vec::with_capacity(2);
    while prefix.len() < 2 {
        let buf = match reader.fill_buf() {
            Ok(buf) => buf,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if buf.is_empty() {
            break;
        }
        let take = buf.len().min(2 - prefix.len());
        prefix.extend_from_slice(&buf[..take]);
        reader.consume(take);
    }
    let inner = match utf16_of(&prefix) {
        Some((name, encoding)) => TextInner::Utf16(Box::new(Utf16Decoder {
            reader,
            decoder: encoding.new_decoder_without_bom_handling(),
            name,
            out: vec![0; 16 * 1024],
            start: 0,
            end: 0,
            offset: prefix.len() as u64,
            done: false,
        })),
        None => TextInner::Plain(io::Read::chain(io::Cursor::new(prefix), reader)),
    };
    Ok(TextReader { inner })
}

/// Streaming UTF-16 → UTF-8 through `encoding_rs` (a thin adapter: `encoding_rs_io` would
/// replace malformed text by U+FFFD silently, where a reader must say where the file is broken).
struct Utf16Decoder<R> {
    reader: R,
    decoder: encoding_rs::Decoder,
    name: &'static str,
    /// UTF-8 decoded and not yet consumed: `out[start..end]`.
    out: Vec<u8>,
    start: usize,
    end: usize,
    /// Bytes of the file taken by the decoder so far (the byte-order mark included).
    offset: u64,
    done: bool,
}

impl<R: BufRead> Utf16Decoder<R> {
    fn fill_buf(&mut self) -> io::Result<&[u8]> {
        while self.start == self.end && !self.done {
            let src = match self.reader.fill_buf() {
                Ok(src) => src,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e),
            };
            let last = src.is_empty();
            let (result, read, written) = self.decoder.decode_to_utf8_without_replacement(src, &mut self.out, last);
            self.reader.consume(read);
            self.offset += read as u64;
            self.start = 0;
            self.end = written;
            match result {
                encoding_rs::DecoderResult::InputEmpty => self.done = last,
                encoding_rs::DecoderResult::OutputFull => {}
                encoding_rs::DecoderResult::Malformed(bad, after) => {
                    self.done = true;
                    let offset = self.offset - u64::from(bad) - u64::from(after);
                    return Err(DecodeError { encoding: self.name, offset }.into_io());
                }
            }
        }
        Ok(&self.out[self.start..self.end])
    }
}

impl<R: BufRead> io::Read for TextReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let available = self.fill_buf()?;
        let n = available.len().min(buf.len());
        buf[..n].copy_from_slice(&available[..n]);
        self.consume(n);
        Ok(n)
    }
}

impl<R: BufRead> BufRead for TextReader<R> {
    fn fill_buf(&mut self) -> io::Result<&[u8]> {
        match &mut self.inner {
            TextInner::Plain(r) => r.fill_buf(),
            TextInner::Utf16(d) => d.fill_buf(),
        }
    }

    fn consume(&mut self, amount: usize) {
        match &mut self.inner {
            TextInner::Plain(r) => r.consume(amount),
            TextInner::Utf16(d) => d.start = (d.start + amount).min(d.end),
        }
    }
}

/// A whole text file (a scene) as a string: UTF-8, with or without a byte-order mark (removed),
/// or UTF-16 after its byte-order mark, transcoded ([`decode_text`]).
///
/// # Errors
/// The operating system's error, or an `InvalidData` error carrying a [`DecodeError`] (with the
/// byte offset) for text that is not valid UTF-8 or UTF-16.
pub(crate) fn read_text_file(path: &Path) -> io::Result<String> {
    let bytes = fs::read(path)?;
    if utf16_encoding(&bytes).is_some() {
        let mut text = String::new();
        io::Read::read_to_string(&mut decode_text(&bytes[..])?, &mut text)?;
        return Ok(text);
    }
    let skip = if bytes.starts_with(UTF8_BOM) { UTF8_BOM.len() } else { 0 };
    let mut bytes = bytes;
    bytes.drain(..skip);
    String::from_utf8(bytes)
        .map_err(|e| DecodeError { encoding: "UTF-8", offset: (skip + e.utf8_error().valid_up_to()) as u64 }.into_io())
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

/// Builds the mesh from polygons, attributing any error (and every warning) to `path`; no
/// attributes (the readers that have some set them).
pub(crate) fn build_mesh(path: &Path, positions: Vec<glam::DVec3>, polygons: Polygons) -> Result<LoadedMesh, IoError> {
    let (mesh, warnings) = Mesh::from_polygons(positions, polygons)
        .map_err(|source| IoError::Mesh { path: path.to_path_buf(), source })?;
    Ok(LoadedMesh { mesh, attributes: Attributes::None, warnings: warnings.for_file(path) })
}

/// Parses one coordinate, naming it in the error.
pub(crate) fn parse_coordinate(token: &str, what: &str) -> Result<f64, String> {
    token.parse::<f64>().map_err(|_| format!("{what} '{}' is not a number", shown(token)))
}

/// `text` as an error message quotes it: its first 40 characters and `…` when longer (a
/// megabyte-long token must not make a megabyte-long message), control characters escaped as
/// Rust writes them (`\r`, `\u{1b}`) so that the message stays on one line and a terminal
/// shows what the file holds instead of obeying it.
pub(crate) fn shown(text: &str) -> std::borrow::Cow<'_, str> {
    let cut = text.char_indices().nth(SHOWN_CHARS).map(|(end, _)| end);
    let head = &text[..cut.unwrap_or(text.len())];
    if cut.is_none() && !head.contains(char::is_control) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(head.len() + 4);
    push_escaped(&mut out, head);
    if cut.is_some() {
        out.push('…');
    }
    std::borrow::Cow::Owned(out)
}

/// Characters of a file's text that [`shown`] quotes.
const SHOWN_CHARS: usize = 40;

/// `text` (a message, a path) with control characters escaped as [`shown`] does: what an error
/// variant's message goes through, so that every error stays one line whatever a file, a scene
/// key or a file name holds.
pub fn one_line(text: impl std::fmt::Display) -> String {
    let text = text.to_string();
    if !text.contains(char::is_control) {
        return text;
    }
    let mut out = String::with_capacity(text.len() + 8);
    push_escaped(&mut out, &text);
    out
}

/// Appends `text` to `out`, each control character as its Rust escape (`\n`, `\u{1b}`).
fn push_escaped(out: &mut String, text: &str) {
    for c in text.chars() {
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
}

/// Most bytes [`bounded_vec`] reserves up front: a few such vectors for a header's claim stay
/// well under 100 MB whatever the element size.
const PREALLOCATION_BYTES: usize = 16 << 20;

/// `Vec::with_capacity` bounded by [`MAX_PREALLOCATION`] elements and 16 MiB, for counts read
/// from a file.
pub(crate) fn bounded_vec<T>(claimed: usize) -> Vec<T> {
    let by_size = PREALLOCATION_BYTES / size_of::<T>().max(1);
    Vec::with_capacity(claimed.min(MAX_PREALLOCATION).min(by_size))
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

    fn utf16(text: &str, big_endian: bool) -> Vec<u8> {
        let mut bytes = if big_endian { vec![0xFE, 0xFF] } else { vec![0xFF, 0xFE] };
        for unit in text.encode_utf16() {
            bytes.extend_from_slice(&if big_endian { unit.to_be_bytes() } else { unit.to_le_bytes() });
        }
        bytes
    }

    fn decode_all(reader: impl BufRead) -> io::Result<String> {
        let mut text = String::new();
        io::Read::read_to_string(&mut decode_text(reader)?, &mut text)?;
        Ok(text)
    }

    #[test]
    fn utf16_is_decoded_however_the_bytes_arrive() {
        let text = "v 1 2 3\r\n# caf\u{e9} \u{1D11E}\n";
        for big in [false, true] {
            let bytes = utf16(text, big);
            assert_eq!(decode_all(&bytes[..]).unwrap(), text);
            // One byte at a time: the mark and surrogate pairs split across reads.
            assert_eq!(decode_all(BufReader::with_capacity(1, &bytes[..])).unwrap(), text);
        }
        let crlf = utf16("a\r\nb", false);
        let mut lines = Lines::new(decode_text(&crlf[..]).unwrap());
        assert_eq!(lines.next_line().unwrap(), Some((1, "a")));
        assert_eq!(lines.next_line().unwrap(), Some((2, "b")));
        assert_eq!(lines.next_line().unwrap(), None);
        assert_eq!(decode_all(&[0xFF, 0xFE][..]).unwrap(), "", "only the mark");
    }

    #[test]
    fn other_bytes_pass_through_untouched() {
        for bytes in [&b""[..], b"x", b"\xFF", b"\xFE", b"\xEF\xBB\xBFv 1\n", b"caf\xe9 \x00\xFF\xFE"] {
            let mut out = Vec::new();
            io::Read::read_to_end(&mut decode_text(BufReader::with_capacity(1, bytes)).unwrap(), &mut out).unwrap();
            assert_eq!(out, bytes);
        }
    }

    #[test]
    fn malformed_utf16_says_encoding_and_offset() {
        let error = |bytes: &[u8]| {
            let e = decode_all(BufReader::with_capacity(3, bytes)).unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidData);
            DecodeError::of(&e).cloned().unwrap()
        };
        let mut odd = utf16("ab", false);
        odd.push(b'c');
        assert_eq!(error(&odd), DecodeError { encoding: "UTF-16 little endian", offset: 6 });
        // A high surrogate followed by a letter, a low surrogate alone.
        let lone_high = [0xFE, 0xFF, 0x00, b'a', 0xD8, 0x00, 0x00, b'b'];
        assert_eq!(error(&lone_high), DecodeError { encoding: "UTF-16 big endian", offset: 4 });
        let lone_low = [0xFF, 0xFE, b'a', 0x00, b'b', 0x00, 0x00, 0xDC];
        assert_eq!(error(&lone_low), DecodeError { encoding: "UTF-16 little endian", offset: 6 });
        let high_at_end = [0xFF, 0xFE, 0x00, 0xD8];
        assert_eq!(error(&high_at_end).offset, 2);
        let e = read_error(Path::new("x.obj"), DecodeError { encoding: "UTF-16 big endian", offset: 4 }.into_io());
        assert_eq!(
            e.to_string(),
            "x.obj: byte offset 4: the file is not valid UTF-16 big endian text (the byte-order mark at its start says it is)"
        );
        let e = read_error(Path::new("x.obj"), io::Error::other("disk"));
        assert!(matches!(e, IoError::Read { .. }));
    }

    #[test]
    fn preallocation_is_bounded_in_bytes_too() {
        assert_eq!(bounded_vec::<u8>(10).capacity(), 10);
        assert_eq!(bounded_vec::<u8>(usize::MAX).capacity(), MAX_PREALLOCATION);
        assert!(bounded_vec::<[f64; 8]>(usize::MAX).capacity() * 64 <= PREALLOCATION_BYTES);
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
