//! Filling a closed triangle surface with tetrahedra, with TetGen (Hang Si) through the tritet
//! crate. TetGen is AGPL-3.0, so this module exists only with the `tetgen` feature; without it,
//! give a tetrahedral mesh file instead (.msh or .node/.ele, e.g. made with Gmsh or TetGen).
//!
//! The surface's vertices keep their indices: the result's first vertices are the input's (all
//! of them, also those no triangle uses), the points TetGen adds come after, and the triangles
//! are the input's. So the input surface is drawn from the first vertices, as in the seed
//! framework, even where TetGen split a surface triangle.

use crate::geometry::tet_volume;
use crate::mesh::Mesh;
use glam::DVec3;

/// Why a surface could not be filled.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TetrahedralizeError {
    /// TetGen refused the surface or failed.
    #[error("TetGen could not fill the surface ({0}); it must be closed, without holes or self-intersections")]
    TetGen(String),
    /// The input has no triangles, or too few points.
    #[error("cannot tetrahedralize: {0}")]
    BadInput(String),
}

/// Tetrahedra filling the closed surface `mesh` (its triangles), with TetGen's default quality
/// bound (radius-edge ratio 2) and, if given, a largest tetrahedron volume (in the mesh's
/// units³). See the [module docs](self) for the vertex numbering.
///
/// # Errors
/// [`TetrahedralizeError`] for an open or self-intersecting surface, or an empty one.
pub fn tetrahedralize(mesh: &Mesh, max_volume: Option<f64>) -> Result<Mesh, TetrahedralizeError> {
    if mesh.triangles.is_empty() {
        return Err(TetrahedralizeError::BadInput("the mesh has no triangles".into()));
    }
    // TetGen drops points no facet uses ("jettison"), which would shift indices: give it only
    // the surface's vertices, numbered densely, and map back.
    let n = mesh.num_vertices();
    let mut compact = vec![u32::MAX; n];
    let mut original = Vec::new();
    for &v in mesh.triangles.iter().flatten() {
        if compact[v as usize] == u32::MAX {
            compact[v as usize] = original.len() as u32;
            original.push(v);
        }
    }
    let tetgen_error = |e: &str| TetrahedralizeError::TetGen(e.to_string());
    let mut tetgen =
        tritet::Tetgen::new(original.len(), Some(vec![3; mesh.num_triangles()]), None, None).map_err(tetgen_error)?;
    for (i, &v) in original.iter().enumerate() {
        let p = mesh.positions[v as usize];
        tetgen.set_point(i, 0, p.x, p.y, p.z).map_err(tetgen_error)?;
    }
    for (f, t) in mesh.triangles.iter().enumerate() {
        for (m, &v) in t.iter().enumerate() {
            tetgen.set_facet_point(f, m, compact[v as usize] as usize).map_err(tetgen_error)?;
        }
    }
    let (generated, printed) = capture_stdout(|| tetgen.generate_mesh(false, false, max_volume, None));
    let said = printed.as_deref().map(tetgen_said).unwrap_or_default();
    generated.map_err(|e| TetrahedralizeError::TetGen(format!("{e}{said}")))?;

    let m = original.len();
    let out_points = tetgen.out_npoint();
    if out_points < m {
        // What TetGen refuses ends here: tritet catches TetGen's exception, prints
        // `status = N` and reports success with an empty output.
        let reason = printed.as_deref().and_then(status_reason).unwrap_or("it made no solid");
        return Err(TetrahedralizeError::TetGen(format!("{reason}{said}")));
    }
    if let Some(text) = printed.as_deref().map(str::trim).filter(|t| !t.is_empty()) {
        log::warn!("TetGen: {}", one_line(text));
    }
    // TetGen numbers the input points first; check it kept them in place.
    for (i, &v) in original.iter().enumerate() {
        let p = DVec3::new(tetgen.out_point(i, 0), tetgen.out_point(i, 1), tetgen.out_point(i, 2));
        if p != mesh.positions[v as usize] {
            return Err(TetrahedralizeError::TetGen(format!("input point {i} moved or was renumbered")));
        }
    }
    let mut positions = mesh.positions.clone();
    positions.extend(
        (m..out_points).map(|i| DVec3::new(tetgen.out_point(i, 0), tetgen.out_point(i, 1), tetgen.out_point(i, 2))),
    );
    let map = |i: usize| if i < m { original[i] } else { (n + i - m) as u32 };
    let tetrahedra: Vec<[u32; 4]> = (0..tetgen.out_ncell())
        .map(|c| {
            let mut t = [0, 1, 2, 3].map(|k| map(tetgen.out_cell_point(c, k)));
            let p = t.map(|v| positions[v as usize]);
            if tet_volume(p[0], p[1], p[2], p[3]) < 0.0 {
                t.swap(2, 3);
            }
            t
        })
        .collect();
    // The input's faces stay (and so do its file's attributes): its vertices keep their indices.
    let mut filled = mesh.with_positions(positions);
    filled.tetrahedra = tetrahedra;
    filled.validate().map_err(|e| TetrahedralizeError::TetGen(format!("invalid output: {e}")))?;
    Ok(filled)
}

/// Runs `run` with the process's standard output (file descriptor 1) redirected into a
/// temporary file (the gag crate), and what was printed there: TetGen and tritet print on
/// standard output (`status = 3`, "Found two facets intersect each other", …), which a library
/// must not do. `None` when the output could not be redirected (another redirection of stdout is
/// active in this process, or no temporary file): then `run` runs all the same, uncaptured.
///
/// The redirection is process-wide: while TetGen runs, whatever any other thread writes to
/// standard output lands in the capture too (and becomes part of the log line). Tetrahedralizations
/// take turns (a lock), so that each gets its own output.
fn capture_stdout<T>(run: impl FnOnce() -> T) -> (T, Option<String>) {
    use std::io::Read;
    use std::sync::{Mutex, PoisonError};
    static TURN: Mutex<()> = Mutex::new(());
    let _turn = TURN.lock().unwrap_or_else(PoisonError::into_inner);
    let redirect = match gag::BufferRedirect::stdout() {
        Ok(redirect) => redirect,
        Err(e) => {
            log::debug!("TetGen's standard output is not captured: {e}");
            return (run(), None);
        }
    };
    let value = run();
    // C's stdio buffers what TetGen prints when standard output is not a terminal: flush it
    // into the capture before the descriptor goes back.
    flush_c_stdout();
    let mut text = String::new();
    let mut buffer = redirect.into_inner();
    match buffer.read_to_string(&mut text) {
        Ok(_) => (value, Some(text)),
        Err(e) => {
            log::debug!("TetGen's captured output cannot be read: {e}");
            (value, None)
        }
    }
}

/// Writes out what C's stdio holds for standard output (`fflush(NULL)`), so that TetGen's
/// `printf`s reach the redirected descriptor. C buffers a non-terminal standard output, so
/// without this the text stays in its buffer past the redirection and comes out on the real
/// standard output at exit. No crate offers a safe `fflush`; this call is the one exception to
/// the crate's `unsafe_code` denial.
#[allow(unsafe_code)]
fn flush_c_stdout() {
    // SAFETY: fflush(NULL) flushes every output stream; it has no preconditions (C11 7.21.5.2)
    // and glibc locks each stream while flushing it.
    unsafe {
        libc::fflush(std::ptr::null_mut());
    }
}

/// Lines of text as one line (`a; b; c`), for an error message or a log record.
fn one_line(text: &str) -> String {
    let lines: Vec<&str> = text.lines().map(str::trim).filter(|l| !l.is_empty()).collect();
    lines.join("; ")
}

/// `; it printed: …` for an error message, without tritet's `status = N` line (which
/// [`status_reason`] words); empty when TetGen printed nothing else.
fn tetgen_said(printed: &str) -> String {
    let rest: Vec<&str> = printed.lines().filter(|l| !l.trim_start().starts_with("status = ")).collect();
    let text = one_line(&rest.join("\n"));
    if text.is_empty() { String::new() } else { format!("; it printed: {text}") }
}

/// What TetGen's exit status (as tritet prints it: `status = N`) means, in TetGen's words.
fn status_reason(printed: &str) -> Option<&'static str> {
    let status = printed.lines().find_map(|l| l.trim().strip_prefix("status = "))?;
    Some(match status.trim() {
        "1" => "it ran out of memory",
        "2" => "it failed with an internal error",
        "3" => "it detected a self-intersection",
        "4" => "it detected a very small input feature size",
        "5" => "it detected two very close input facets",
        "10" => "it detected an input error",
        _ => "it stopped with an unknown status",
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_closed_box_is_filled_and_keeps_its_vertices_first() {
        // The boundary of a tet box, as a plain surface, plus one unused vertex in front.
        let solid = crate::generate::tet_box([2, 2, 2], DVec3::ONE);
        let mut positions = vec![DVec3::new(5.0, 5.0, 5.0)];
        positions.extend(&solid.positions);
        let triangles: Vec<[u32; 3]> = solid.triangles.iter().map(|t| t.map(|v| v + 1)).collect();
        let surface = Mesh::new(positions.clone(), triangles.clone()).unwrap_or_else(|e| panic!("{e}"));
        let filled = tetrahedralize(&surface, None).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(&filled.positions[..positions.len()], &positions[..], "input vertices first, unchanged");
        assert_eq!(filled.triangles, triangles);
        let volume: f64 = filled
            .tetrahedra
            .iter()
            .map(|t| {
                let p = t.map(|v| filled.positions[v as usize]);
                let v = tet_volume(p[0], p[1], p[2], p[3]);
                assert!(v > 0.0);
                v
            })
            .sum();
        assert!((volume - 1.0).abs() < 1e-9, "the tets fill the unit box: {volume}");
        assert!(filled.tetrahedra.iter().flatten().all(|&v| v != 0), "the unused vertex is in no tet");
    }

    #[test]
    fn a_self_intersecting_surface_is_an_error_that_says_why() {
        // Two overlapping tetrahedra: each closed, together self-intersecting.
        let corners =
            |o: f64| [DVec3::splat(o), DVec3::new(o + 1.0, o, o), DVec3::new(o, o + 1.0, o), DVec3::new(o, o, o + 1.0)];
        let positions: Vec<DVec3> = corners(0.0).into_iter().chain(corners(0.2)).collect();
        let faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let triangles: Vec<[u32; 3]> =
            faces.iter().chain(&faces).enumerate().map(|(i, f)| f.map(|v| v + 4 * (i as u32 / 4))).collect();
        let crossed = Mesh::new(positions, triangles).unwrap_or_else(|e| panic!("{e}"));
        let message = tetrahedralize(&crossed, None).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(message.contains("self-intersection"), "{message}");
        assert!(!message.contains("status = "), "TetGen's status is worded: {message}");
    }

    #[test]
    fn tetgen_output_is_worded() {
        assert_eq!(status_reason("status = 3\n"), Some("it detected a self-intersection"));
        assert_eq!(
            status_reason("Found two facets intersect each other.\nstatus = 5\n"),
            Some("it detected two very close input facets")
        );
        assert_eq!(status_reason("nothing\n"), None);
        assert_eq!(tetgen_said("status = 3\n"), "");
        assert_eq!(
            tetgen_said("Found two facets.\n  1st: [1, 2, 3] #4\nstatus = 3\n"),
            "; it printed: Found two facets.; 1st: [1, 2, 3] #4"
        );
    }

    #[test]
    fn an_open_surface_is_an_error() {
        let open = Mesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z], vec![[0, 2, 1], [0, 1, 3]])
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(tetrahedralize(&open, None).is_err());
    }
}
