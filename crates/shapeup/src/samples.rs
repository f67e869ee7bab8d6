//! The bundled sample meshes on the command line (the table is the editor's,
//! `shapeup_app::samples`): `shapeup samples` lists them, `--write DIR` writes them out, and
//! wherever the command line takes a MESH a sample's name stands for it when no file of that
//! name exists (`shapeup view spot`, `shapeup info suzanne`).

use anyhow::{Result, bail};
use shapeup_core::io::{LoadedMesh, create_output_folder, read_mesh, write_atomic};
use std::io::Write;
use std::path::{Path, PathBuf};

pub use shapeup_app::samples::{DEFAULT, SAMPLES, resolve};

/// Reads a MESH argument ([`resolve`]), and the path to name it by (`spot.obj (bundled)` for a
/// sample).
pub fn read_mesh_arg(arg: &Path) -> Result<(LoadedMesh, PathBuf)> {
    match resolve(arg) {
        Some(sample) => Ok((sample.read()?, PathBuf::from(format!("{} (bundled)", sample.file_name())))),
        None if !arg.exists() && arg.components().count() == 1 && arg.extension().is_none() => {
            bail!("{}: no such file, and no bundled sample of that name (`shapeup samples` lists them)", arg.display())
        }
        None => Ok((read_mesh(arg)?, arg.to_path_buf())),
    }
}

/// `shapeup samples`: a table of the samples, or with `write` each written to `DIR/NAME.obj`
/// (folder created if missing, each file atomically).
pub fn run(write: Option<&Path>) -> Result<()> {
    let mut out = std::io::stdout().lock();
    if let Some(dir) = write {
        // The folder is created; the folders above it must exist (the rule of every output).
        create_output_folder(dir)?;
        for sample in SAMPLES {
            let path = dir.join(sample.file_name());
            write_atomic(&path, |w| w.write_all(sample.bytes))?;
            writeln!(out, "wrote {}", shapeup_core::io::one_line(path.display()))?;
        }
        return Ok(());
    }
    writeln!(out, "{:<24} {:>9} {:>8}  source", "name", "vertices", "faces")?;
    for sample in SAMPLES {
        let mesh = sample.read()?.mesh;
        let name = match sample.alias {
            Some(alias) => format!("{} ({alias})", sample.name),
            None => sample.name.to_string(),
        };
        writeln!(out, "{name:<24} {:>9} {:>8}  {}", mesh.num_vertices(), mesh.num_polygons(), sample.source)?;
    }
    Ok(())
}
