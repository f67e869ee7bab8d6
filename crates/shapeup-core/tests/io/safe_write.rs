//! Safe writes: `write_atomic` (every writer's path) and `check_output_folder` go through
//! temporary files with unpredictable names created exclusively in the target's folder; a
//! symbolic link at a temporary or final path is never followed into another file; a failed
//! write leaves nothing behind; written files get the usual mode (or that of the file they
//! replace).

use std::fs;
use std::path::{Path, PathBuf};

use shapeup_core::Mesh;
use shapeup_core::io::{Attributes, check_output_folder, read_mesh, tetgen, write_atomic, write_mesh};

/// The folder's entries, sorted.
fn entries(dir: &Path) -> Vec<PathBuf> {
    let mut entries: Vec<PathBuf> = fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    entries
}

/// One tetrahedron and its four boundary triangles.
fn tet() -> Mesh {
    let node = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";
    let ele = "1 4 0\n1 1 2 3 4\n";
    tetgen::read_tetgen(node.as_bytes(), Path::new("t.node"), ele.as_bytes(), Path::new("t.ele")).unwrap().mesh
}

#[test]
fn a_failing_writer_leaves_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("out.obj");
    for _ in 0..20 {
        let err = write_atomic(&target, |w| {
            w.write_all(&[b'x'; 100_000])?;
            Err(std::io::Error::other("writer gave up"))
        })
        .unwrap_err();
        assert!(err.to_string().contains("out.obj") && err.to_string().contains("writer gave up"), "{err}");
    }
    assert!(entries(dir.path()).is_empty(), "{:?}", entries(dir.path()));
    // A panicking writer too: the temporary file is removed as the panic unwinds.
    let result = std::panic::catch_unwind(|| {
        let _ = write_atomic(&target, |w| {
            w.write_all(b"half")?;
            panic!("writer panicked");
        });
    });
    assert!(result.is_err());
    assert!(entries(dir.path()).is_empty(), "{:?}", entries(dir.path()));
}

#[test]
fn the_folder_check_leaves_nothing_visible() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("keep.obj"), "old").unwrap();
    let before = entries(dir.path());
    for name in ["keep.obj", "new.obj", "report.json"] {
        check_output_folder(&dir.path().join(name)).unwrap();
    }
    assert_eq!(entries(dir.path()), before);
    assert_eq!(fs::read_to_string(dir.path().join("keep.obj")).unwrap(), "old");
    let missing = dir.path().join("missing").join("x.obj");
    let err = check_output_folder(&missing).unwrap_err().to_string();
    assert!(err.contains("does not exist"), "{err}");
    // A file where the folder (or one above it) should be is named as such.
    for under in [dir.path().join("keep.obj").join("x.obj"), dir.path().join("keep.obj").join("sub").join("x.obj")] {
        let err = check_output_folder(&under).unwrap_err().to_string();
        assert!(err.ends_with("keep.obj is a file, not a folder"), "{err}");
    }
}

#[test]
fn concurrent_writes_to_one_target_each_land_whole() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("shared.txt");
    std::thread::scope(|scope| {
        for k in 0..8u8 {
            let target = &target;
            scope.spawn(move || {
                for _ in 0..20 {
                    write_atomic(target, |w| w.write_all(&[b'a' + k; 4096])).unwrap();
                }
            });
        }
    });
    let contents = fs::read(&target).unwrap();
    assert_eq!(contents.len(), 4096);
    assert!(contents.iter().all(|&b| b == contents[0]), "one writer's whole contents");
    assert_eq!(entries(dir.path()), vec![target]);
}

#[cfg(unix)]
mod unix {
    use super::*;
    use std::os::unix::fs::{PermissionsExt, symlink};

    fn mode(path: &Path) -> u32 {
        fs::symlink_metadata(path).unwrap().permissions().mode() & 0o7777
    }

    #[test]
    fn a_symlink_at_the_final_path_is_replaced_not_followed() {
        let dir = tempfile::tempdir().unwrap();
        let victim = dir.path().join("victim.txt");
        fs::write(&victim, "precious").unwrap();
        fs::set_permissions(&victim, fs::Permissions::from_mode(0o600)).unwrap();
        let target = dir.path().join("out.txt");
        symlink(&victim, &target).unwrap();
        write_atomic(&target, |w| w.write_all(b"new contents")).unwrap();
        assert_eq!(fs::read_to_string(&victim).unwrap(), "precious");
        assert_eq!(mode(&victim), 0o600);
        let meta = fs::symlink_metadata(&target).unwrap();
        assert!(meta.file_type().is_file(), "a regular file replaces the link");
        assert_eq!(fs::read_to_string(&target).unwrap(), "new contents");
        // The new file does not take the link target's mode: it is a new file.
        let fresh = dir.path().join("fresh.txt");
        fs::File::create(&fresh).unwrap();
        assert_eq!(mode(&target), mode(&fresh));

        // A mesh written through the link, and a TetGen pair whose .node is a link.
        let mesh_link = dir.path().join("mesh.obj");
        symlink(&victim, &mesh_link).unwrap();
        write_mesh(&mesh_link, &tet(), &Attributes::None).unwrap();
        assert_eq!(fs::read_to_string(&victim).unwrap(), "precious");
        assert_eq!(read_mesh(&mesh_link).unwrap().mesh.num_vertices(), 4);
        let node = dir.path().join("pair.node");
        symlink(&victim, &node).unwrap();
        symlink(dir.path().join("nowhere.txt"), dir.path().join("pair.ele")).unwrap();
        write_mesh(&dir.path().join("pair.ele"), &tet(), &Attributes::None).unwrap();
        assert_eq!(fs::read_to_string(&victim).unwrap(), "precious");
        assert!(!dir.path().join("nowhere.txt").exists(), "a dangling link's target is not created");
        assert!(fs::symlink_metadata(&node).unwrap().file_type().is_file());
        assert_eq!(read_mesh(&node).unwrap().mesh.tetrahedra.len(), 1);
    }

    #[test]
    fn symlinks_at_the_old_predictable_temporary_names_are_not_followed() {
        let dir = tempfile::tempdir().unwrap();
        let victim = dir.path().join("victim.txt");
        fs::write(&victim, "precious").unwrap();
        let target = dir.path().join("out.obj");
        // The old scheme: `.NAME.tmp-PID-N` with a per-process counter.
        let pid = std::process::id();
        let mut planted = Vec::new();
        for n in 0..2000 {
            let link = dir.path().join(format!(".out.obj.tmp-{pid}-{n}"));
            symlink(&victim, &link).unwrap();
            planted.push(link);
        }
        for _ in 0..5 {
            write_mesh(&target, &tet(), &Attributes::None).unwrap();
            check_output_folder(&target).unwrap();
        }
        assert_eq!(fs::read_to_string(&victim).unwrap(), "precious");
        for link in &planted {
            assert!(fs::symlink_metadata(link).unwrap().file_type().is_symlink());
        }
        // Nothing but the victim, the links and the output.
        assert_eq!(entries(dir.path()).len(), planted.len() + 2);
        assert_eq!(read_mesh(&target).unwrap().mesh.num_vertices(), 4);
    }

    #[test]
    fn written_files_have_the_usual_mode_or_keep_the_replaced_ones() {
        let dir = tempfile::tempdir().unwrap();
        // What `File::create` gives: 0666 less this process's umask.
        let reference = dir.path().join("reference");
        fs::File::create(&reference).unwrap();
        let usual = mode(&reference);
        assert_eq!(usual & 0o600, 0o600);
        let new = dir.path().join("new.ply");
        write_mesh(&new, &tet(), &Attributes::None).unwrap();
        assert_eq!(mode(&new), usual, "not tempfile's private 0600");
        let pair = dir.path().join("pair.node");
        write_mesh(&pair, &tet(), &Attributes::None).unwrap();
        assert_eq!((mode(&pair), mode(&pair.with_extension("ele"))), (usual, usual));
        // Replacing a file keeps its mode, whatever the umask.
        for kept in [0o600, 0o640, 0o755, 0o444] {
            let path = dir.path().join(format!("kept{kept:o}.off"));
            fs::write(&path, "old").unwrap();
            fs::set_permissions(&path, fs::Permissions::from_mode(kept)).unwrap();
            write_mesh(&path, &tet(), &Attributes::None).unwrap();
            assert_eq!(mode(&path), kept, "{path:?}");
            assert!(read_mesh(&path).is_ok());
        }
    }
}
