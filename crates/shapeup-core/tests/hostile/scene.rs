//! Hostile scene files: small inputs (under 10 KB) with deep nesting, repeated keys, huge counts
//! and long lists are refused with one line naming the key or line, or read in time and memory
//! in proportion to their size; generated meshes are capped by an estimate of the memory they
//! need, and the estimate is checked here against what loading really allocates.
//!
//! Memory is measured with a counting global allocator, so this file holds only these tests and
//! runs them one at a time; each runs on its own thread (the default 2 MiB stack) under a 60 s
//! watchdog (a hang check, far above the real time, not a timing assertion).

use shapeup_core::scene::{GeneratedMesh, MAX_GENERATED_BYTES, Scene, SceneError, SceneFormat};
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;

use crate::{CURRENT, PEAK, SERIAL};
use std::time::Duration;

fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

/// Runs `f` on a thread with the default 2 MiB stack (a stack overflow aborts the test), fails
/// after 60 s (a hang check, far above the real time), and returns its result and the peak
/// bytes it allocated above what was allocated before (the caller holds [`serial`]).
fn measured<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> (T, usize) {
    let base = CURRENT.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let (send, receive) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = send.send(f());
    });
    let value = receive.recv_timeout(Duration::from_secs(60)).expect("no answer within 60 s (a hang)");
    (value, PEAK.load(Ordering::Relaxed).saturating_sub(base))
}

fn parse(text: &str, format: SceneFormat) -> Result<Scene, SceneError> {
    let name = if format == SceneFormat::Toml { "hostile.toml" } else { "hostile.json" };
    Scene::parse(text, format, Path::new(name), PathBuf::new())
}

/// Parses (and, when it parses, loads) `text`, which must be under 10 KB, checking that it
/// takes under 32 MB; returns the one-line error, or `None` if it loaded.
fn refused(text: &str, format: SceneFormat) -> Option<String> {
    assert!(text.len() < 10 * 1024, "a hostile input is under 10 KB: {} bytes", text.len());
    let owned = text.to_owned();
    let (result, peak) = measured(move || parse(&owned, format).and_then(|s| s.load()).err().map(|e| e.to_string()));
    assert!(peak < 32 << 20, "{} bytes of scene took {peak} bytes", text.len());
    if let Some(message) = &result {
        assert_eq!(message.lines().count(), 1, "one line: {message}");
        assert!(message.starts_with("hostile."), "names the scene: {message}");
    }
    result
}

fn refused_with(text: &str, format: SceneFormat, needles: &[&str]) -> String {
    let message = refused(text, format).unwrap_or_else(|| panic!("accepted: {}", &text[..text.len().min(200)]));
    for needle in needles {
        assert!(message.contains(needle), "{needle:?} not in: {message}");
    }
    message
}

const MESH: &str = "[mesh]\ngenerate = { kind = \"cloth\", vertices = [4, 4], size = [1.0, 1.0] }\n";
const JSON_MESH: &str = r#""mesh": {"generate": {"kind": "cloth", "vertices": [4, 4], "size": [1.0, 1.0]}}"#;

#[test]
fn deeply_nested_toml_arrays_and_tables_are_refused() {
    let _whole_test = crate::whole_test();
    let _serial = serial();
    let depth = 4000;
    let arrays = format!("{}1{}", "[".repeat(depth), "]".repeat(depth));
    let tables = format!("{}1{}", "{ a = ".repeat(1000), " }".repeat(1000));
    for value in [&arrays, &tables] {
        // In a constraint's options (JSON values), in a known table and at the top.
        refused_with(
            &format!("{MESH}[[constraints]]\ntype = \"edge_spring\"\nx = {value}\n"),
            SceneFormat::Toml,
            &["line 5"],
        );
        refused_with(&format!("{MESH}[solver]\niterations = {value}\n"), SceneFormat::Toml, &["line 4"]);
        refused_with(&format!("x = {value}\n{MESH}"), SceneFormat::Toml, &["line 1"]);
    }
}

#[test]
fn deeply_dotted_toml_keys_are_refused() {
    let _whole_test = crate::whole_test();
    let _serial = serial();
    let path = vec!["a"; 3000].join(".");
    for text in [
        format!("{MESH}[[constraints]]\ntype = \"edge_spring\"\n{path} = 1\n"),
        format!("{MESH}[[constraints]]\ntype = \"edge_spring\"\n[constraints.{path}]\n"),
        format!("{path} = 1\n{MESH}"),
        format!("{MESH}[solver.{path}]\n"),
        format!("[mesh.{path}]\n"),
    ] {
        let line = text.lines().position(|l| l.contains("a.a.a")).unwrap() + 1;
        let message = refused(&text, SceneFormat::Toml).unwrap_or_else(|| panic!("accepted {}", &text[..100]));
        assert!(message.contains(&format!("line {line}")), "{message}");
    }
}

#[test]
fn deeply_nested_json_is_refused() {
    let _whole_test = crate::whole_test();
    let _serial = serial();
    let arrays = format!("{}1{}", "[".repeat(4000), "]".repeat(4000));
    let objects = format!("{}1{}", "{\"a\": ".repeat(1200), "}".repeat(1200));
    for value in [&arrays, &objects] {
        refused_with(
            &format!(r#"{{{JSON_MESH}, "constraints": [{{"type": "edge_spring", "x": {value}}}]}}"#),
            SceneFormat::Json,
            &["line 1"],
        );
        refused_with(
            &format!(r#"{{{JSON_MESH}, "solver": {{"iterations": {value}}}}}"#),
            SceneFormat::Json,
            &["line 1"],
        );
        refused_with(&format!(r#"{{"x": {value}, {JSON_MESH}}}"#), SceneFormat::Json, &["line 1"]);
    }
}

#[test]
fn repeated_keys_are_refused_naming_the_key() {
    let _whole_test = crate::whole_test();
    let _serial = serial();
    refused_with(
        &format!("{MESH}[solver]\niterations = 3\niterations = 4\n"),
        SceneFormat::Toml,
        &["line 5", "duplicate key"],
    );
    refused_with(&format!("{MESH}[mesh]\nnormalize = false\n"), SceneFormat::Toml, &["line 3"]);
    refused_with(
        &format!("{MESH}[[constraints]]\ntype = \"edge_spring\"\ntype = \"position\"\n"),
        SceneFormat::Toml,
        &["line 5", "duplicate key"],
    );
    refused_with(
        &format!(r#"{{{JSON_MESH}, "solver": {{"iterations": 3, "iterations": 4}}}}"#),
        SceneFormat::Json,
        &["iterations"],
    );
    refused_with(&format!(r#"{{{JSON_MESH}, {JSON_MESH}}}"#), SceneFormat::Json, &["mesh"]);
    // serde_json keeps the last of a repeated key in a free-form map: the entries refuse it.
    refused_with(
        &format!(r#"{{{JSON_MESH}, "constraints": [{{"type": "position", "type": "edge_spring"}}]}}"#),
        SceneFormat::Json,
        &["duplicate key", "type"],
    );
    refused_with(
        &format!(
            r#"{{{JSON_MESH}, "constraints": [{{"type": "position", "box": {{"min": [0, 0, 0], "min": [1, 1, 1], "max": [2, 2, 2]}}}}]}}"#
        ),
        SceneFormat::Json,
        &["duplicate key", "min"],
    );
}

#[test]
fn huge_generated_meshes_are_refused_with_the_estimate_and_the_largest_that_fits() {
    let _whole_test = crate::whole_test();
    let _serial = serial();
    let message = refused_with(
        "[mesh]\ngenerate = { kind = \"tet_box\", cells = [200, 200, 200], size = [1, 1, 1] }\n",
        SceneFormat::Toml,
        &[
            "[mesh]",
            "tet_box of 200 × 200 × 200 cells",
            "48,000,000 tetrahedra",
            "GB",
            "the cap is 1.0 GB",
            "use at most about",
        ],
    );
    // The advice fits, and is the largest of these proportions that does.
    let advised: Vec<usize> = message
        .rsplit("about ")
        .next()
        .unwrap()
        .trim_end_matches(" cells")
        .split(" × ")
        .map(|n| n.replace(',', "").parse().unwrap())
        .collect();
    assert_eq!(advised[0], advised[1]);
    let fits = |n: usize| GeneratedMesh::TetBox { cells: [n; 3], size: [1.0; 3] }.validate().is_ok();
    assert!(fits(advised[0]) && !fits(advised[0] + 1), "{advised:?}");

    refused_with(
        "[mesh]\ngenerate = { kind = \"cloth\", vertices = [100000, 100000], size = [1, 1] }\n",
        SceneFormat::Toml,
        &["cloth of 100,000 × 100,000 vertices", "triangles", "use at most about"],
    );
    // Counts up to the largest integers TOML and JSON hold: no overflow, one line.
    for cells in ["[9223372036854775807, 9223372036854775807, 9223372036854775807]", "[9223372036854775807, 1, 1]"] {
        refused_with(
            &format!("[mesh]\ngenerate = {{ kind = \"tet_box\", cells = {cells}, size = [1, 1, 1] }}\n"),
            SceneFormat::Toml,
            &["tet_box of 9,223,372,036,854,775,807", "cap"],
        );
    }
    refused_with(
        r#"{"mesh": {"generate": {"kind": "tet_box", "cells": [18446744073709551615, 18446744073709551615, 18446744073709551615], "size": [1, 1, 1]}}}"#,
        SceneFormat::Json,
        &["18,446,744,073,709,551,615", "cap"],
    );
    refused_with(
        r#"{"mesh": {"generate": {"kind": "tet_box", "cells": [18446744073709551616, 1, 1], "size": [1, 1, 1]}}}"#,
        SceneFormat::Json,
        &["line 1"],
    );
    // A scene edited after parsing is checked again when it loads.
    let mut scene = parse(MESH, SceneFormat::Toml).unwrap();
    scene.mesh.generate = Some(GeneratedMesh::Cloth { vertices: [1 << 40, 1 << 40], size: [1.0, 1.0] });
    let message = scene.load().unwrap_err().to_string();
    assert!(message.contains("cap"), "{message}");
}

#[test]
fn the_memory_estimate_covers_what_loading_a_generated_mesh_takes() {
    let _whole_test = crate::whole_test();
    let _serial = serial();
    // Mid-size meshes: the estimate is at least the measured peak and not far above it.
    let mut measurements = Vec::new();
    for (generated, text) in [
        (
            GeneratedMesh::TetBox { cells: [40, 40, 40], size: [1.0; 3] },
            "kind = \"tet_box\", cells = [40, 40, 40], size = [1, 1, 1]",
        ),
        (
            GeneratedMesh::TetBox { cells: [200, 10, 10], size: [1.0; 3] },
            "kind = \"tet_box\", cells = [200, 10, 10], size = [1, 1, 1]",
        ),
        (
            GeneratedMesh::TetBox { cells: [120, 120, 2], size: [1.0; 3] },
            "kind = \"tet_box\", cells = [120, 120, 2], size = [1, 1, 1]",
        ),
        (
            GeneratedMesh::Cloth { vertices: [400, 400], size: [1.0; 2] },
            "kind = \"cloth\", vertices = [400, 400], size = [1, 1]",
        ),
        (
            GeneratedMesh::Cloth { vertices: [2000, 40], size: [1.0; 2] },
            "kind = \"cloth\", vertices = [2000, 40], size = [1, 1]",
        ),
    ] {
        let text = format!("[mesh]\ngenerate = {{ {text} }}\n");
        let (loaded, peak) = measured(move || {
            let loaded = parse(&text, SceneFormat::Toml).unwrap().load().unwrap();
            loaded.mesh.num_vertices()
        });
        assert!(loaded > 0);
        let [v, t, k] = generated.element_counts();
        eprintln!("{generated:?}: {v} vertices, {t} triangles, {k} tetrahedra: peak {peak} bytes");
        measurements.push((generated, peak));
    }
    for (generated, peak) in measurements {
        let estimate = generated.estimated_bytes();
        assert!(estimate >= peak as f64, "{generated:?}: estimate {estimate} < peak {peak}");
        assert!(estimate <= 1.5 * peak as f64, "{generated:?}: estimate {estimate} ≫ peak {peak}");
    }
    assert_eq!(MAX_GENERATED_BYTES, 1_000_000_000);
}

#[test]
fn huge_iteration_and_step_counts_are_read_without_allocating_for_them() {
    let _whole_test = crate::whole_test();
    let _serial = serial();
    // A float where a count goes: refused naming the line.
    refused_with(&format!("{MESH}[solver]\niterations = 1e18\n"), SceneFormat::Toml, &["line 4", "iterations = 1e18"]);
    refused_with(&format!("{MESH}[solver]\nsteps = -1\n"), SceneFormat::Toml, &["line 4"]);
    // The largest integers load (nothing is sized by them) and multiply without overflow.
    let text = format!("{MESH}[solver]\niterations = 9223372036854775807\nsteps = 9223372036854775807\n");
    assert_eq!(refused(&text, SceneFormat::Toml), None);
    let loaded = parse(&text, SceneFormat::Toml).unwrap().load().unwrap();
    assert_eq!(loaded.static_iterations(None), usize::MAX);
    let json =
        format!(r#"{{{JSON_MESH}, "solver": {{"iterations": 18446744073709551615, "steps": 18446744073709551615}}}}"#);
    assert_eq!(refused(&json, SceneFormat::Json), None);
}

#[test]
fn long_selection_and_target_lists_are_read_in_proportion() {
    let _whole_test = crate::whole_test();
    let _serial = serial();
    // About 10 KB of indices: a repeated one, one out of range, a valid long list.
    let zeros = vec!["0"; 3000].join(",");
    refused_with(
        &format!("{MESH}[[constraints]]\ntype = \"position\"\nvertices = [{zeros}]\n"),
        SceneFormat::Toml,
        &["constraints[0]", "vertex 0 is listed twice"],
    );
    // A face listed twice is said as a vertex is, not merged quietly.
    refused_with(
        &format!("{MESH}[[constraints]]\ntype = \"triangle_strain\"\nfaces = [{zeros}]\n"),
        SceneFormat::Toml,
        &["constraints[0]", "face 0 is listed twice"],
    );
    refused_with(
        &format!("{MESH}[[constraints]]\ntype = \"position\"\nvertices = [18446744073709551615]\n"),
        SceneFormat::Toml,
        &["constraints[0]", "18446744073709551615", "out of range"],
    );
    refused_with(
        &format!("{MESH}[[constraints]]\ntype = \"position\"\nfaces = [{zeros}, 99999999999]\n"),
        SceneFormat::Toml,
        &["constraints[0]", "99999999999"],
    );
    let indices = (0..16).cycle().take(2000).map(|i| i.to_string()).collect::<Vec<_>>().join(",");
    assert_eq!(
        refused(&format!("{MESH}[[constraints]]\ntype = \"edge_spring\"\nvertices = [{indices}]\n"), SceneFormat::Toml),
        None
    );
    // A long targets list that does not match the selection.
    let targets = vec!["[0,0,0]"; 1200].join(",");
    refused_with(
        &format!("{MESH}[[constraints]]\ntype = \"position\"\nvertices = [0, 1]\ntargets = [{targets}]\n"),
        SceneFormat::Toml,
        &["constraints[0]", "targets"],
    );
    // Many groups: each is built, in proportion.
    let groups = "[[constraints]]\ntype = \"edge_spring\"\n".repeat(250);
    assert_eq!(refused(&format!("{MESH}{groups}"), SceneFormat::Toml), None);
}

#[test]
fn huge_and_tiny_generated_sizes_are_refused_or_stay_finite() {
    let _whole_test = crate::whole_test();
    let _serial = serial();
    for size in ["1e300", "1e-300"] {
        let text = format!(
            "[mesh]\ngenerate = {{ kind = \"tet_box\", cells = [2, 2, 2], size = [{size}, 1, 1] }}\n[[constraints]]\ntype = \"tet_strain\"\n"
        );
        // A clear error (here: the flattened tetrahedra count as degenerate), or finite results.
        match parse(&text, SceneFormat::Toml).and_then(|s| s.load()) {
            Err(e) => assert_eq!(e.to_string().lines().count(), 1, "{e}"),
            Ok(mut loaded) => {
                let (q, _) = loaded.solve_static(Some(2)).unwrap();
                assert!(loaded.to_input(&q).iter().all(|p| p.is_finite()), "size {size}");
            }
        }
    }
}
