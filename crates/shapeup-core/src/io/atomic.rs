//! Safe writes: every output goes through a temporary file renamed over the target
//! ([`write_atomic`]), and the checks made before any work that the output can go where asked.

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use super::IoError;
use crate::text::one_line;

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
    /// A folder where a file is wanted (`-o out` for an existing folder `out`).
    #[error("{}: is a folder; give a file name in it, such as {}", one_line(path.display()), one_line(path.join(format!("result.{}", allowed.first().copied().unwrap_or("obj"))).display()))]
    IsAFolder {
        /// The output.
        path: PathBuf,
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
    /// What should be its folder (or one above it) is a file.
    #[error("{}: {} is a file, not a folder", one_line(path.display()), one_line(file.display()))]
    NotAFolder {
        /// The output.
        path: PathBuf,
        /// The file in the way.
        file: PathBuf,
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

/// Fails unless `path`'s extension (case-insensitive) is one of `allowed` and it is not a
/// folder.
///
/// # Errors
/// [`OutputError::IsAFolder`], [`OutputError::Extension`].
pub fn check_output_extension(path: &Path, allowed: &'static [&'static str]) -> Result<(), OutputError> {
    // `r.json/` names a folder (Path drops the trailing separator from its components).
    let trailing = path.as_os_str().as_encoded_bytes().last().is_some_and(|&b| std::path::is_separator(b as char));
    if path.is_dir() || trailing {
        return Err(OutputError::IsAFolder { path: path.to_path_buf(), allowed });
    }
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
    if allowed.contains(&ext.as_str()) {
        Ok(())
    } else {
        Err(OutputError::Extension { path: path.to_path_buf(), ext, allowed })
    }
}

/// The first of `dir` and the folders above it that exists as something other than a folder
/// (`afile/r.json`, `afile/sub/r.json`: `afile`): a missing folder that cannot be created.
pub fn file_in_the_way(dir: &Path) -> Option<PathBuf> {
    dir.ancestors()
        .filter(|d| !d.as_os_str().is_empty())
        .find(|d| fs::metadata(d).is_ok())
        .filter(|d| !d.is_dir())
        .map(Path::to_path_buf)
}

/// Fails unless the folder `path` goes in exists and takes a new file: it creates (and
/// removes) the kind of temporary file [`write_atomic`] writes through.
///
/// # Errors
/// [`OutputError::MissingFolder`], [`OutputError::NotAFolder`] or [`OutputError::Unwritable`].
pub fn check_output_folder(path: &Path) -> Result<(), OutputError> {
    let unwritable = |dir: &Path, source| OutputError::Unwritable { path: path.to_path_buf(), dir: dir.into(), source };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty() && !d.is_dir()) {
        return Err(match file_in_the_way(dir) {
            Some(file) => OutputError::NotAFolder { path: path.to_path_buf(), file },
            None => OutputError::MissingFolder { path: path.to_path_buf(), dir: dir.into() },
        });
    }
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let (_, temp) = create_temp(path).map_err(|e| unwritable(dir, e))?;
    temp.close().map_err(|e| unwritable(dir, e))
}

/// Creates the output folder `dir` when it is missing and checks that it takes files. The rule
/// of every output: shapeup creates the file or folder named, never the folders above it (a
/// typo in a path is refused, not made into a tree of folders).
///
/// # Errors
/// [`OutputError::NotAFolder`] when `dir` (or a folder above it) is a file; what
/// [`check_output_folder`] gives for `dir` (the folder above it is missing) and for a file in
/// it (it does not take files).
pub fn create_output_folder(dir: &Path) -> Result<(), OutputError> {
    if let Some(file) = file_in_the_way(dir) {
        return Err(OutputError::NotAFolder { path: dir.to_path_buf(), file });
    }
    if !dir.is_dir() {
        check_output_folder(dir)?;
        if let Err(source) = fs::create_dir(dir)
            && source.kind() != io::ErrorKind::AlreadyExists
        {
            let parent = dir.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
            return Err(OutputError::Unwritable { path: dir.to_path_buf(), dir: parent.to_path_buf(), source });
        }
    }
    check_output_folder(&dir.join("file"))
}
