//! End-to-end tests of the `shapeup` binary against the CLI and scene contract
//! (`docs/scenes-and-cli.md`): real processes, real files, outcomes read back with `shapeup_core`.

use glam::DVec3;
use shapeup_core::Mesh;
use shapeup_core::io::{read_mesh, write_mesh};
use shapeup_core::scene::{Scene, SelectionSpec};
use std::ffi::OsStr;
use std::path::{Path, PathBuf};

use crate::common::{Output, shapeup_in};

const SPOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/spot.obj");
const COW: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/cow.obj");
const SUZANNE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/suzanne.obj");
const EXAMPLES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples");

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

fn shapeup<I, S>(args: I) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    shapeup_in(None, args)
}

/// `shapeup simulate SCENE -o DIR EXTRA…`, from `cwd` when given.
fn simulate_in<S: AsRef<OsStr>>(cwd: Option<&Path>, scene: &Path, dir: &Path, extra: &[S]) -> Output {
    let mut args: Vec<&OsStr> = vec!["simulate".as_ref(), scene.as_os_str(), "-o".as_ref(), dir.as_os_str()];
    args.extend(extra.iter().map(AsRef::as_ref));
    shapeup_in(cwd, args)
}

/// `shapeup deform SCENE -o OUT EXTRA…`.
fn deform_to(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args: Vec<&OsStr> = vec!["deform".as_ref(), scene.as_os_str(), "-o".as_ref(), out.as_os_str()];
    args.extend(extra.iter().map(OsStr::new));
    shapeup(args)
}

fn read(path: &Path) -> Mesh {
    read_mesh(path).unwrap_or_else(|e| panic!("cannot read back {}: {e}", path.display())).mesh
}

fn spot() -> Mesh {
    read(Path::new(SPOT))
}

/// A TOML scene on `mesh` (an absolute path, as a TOML literal string) with `body` after `[mesh]`.
fn toml_scene(mesh: &Path, mesh_options: &str, body: &str) -> String {
    format!("[mesh]\npath = '{}'\n{mesh_options}\n{body}", mesh.display())
}

fn write(path: &Path, text: &str) -> PathBuf {
    std::fs::write(path, text).unwrap();
    path.to_path_buf()
}

/// The standard test scene on spot, with every length multiplied by `s`: edge springs on the
/// part z ≥ −0.2 only (the vertices below are touched by no constraint), a fixed handle on the
/// slab −0.2 ≤ z ≤ −0.1 and the head (z ≥ 0.8) moved by `s · HEAD_TRANSLATE`.
fn handle_body(s: f64) -> String {
    let [tx, ty, tz] = HEAD_TRANSLATE.map(|t| t * s);
    format!(
        r#"
[solver]
iterations = 20

[[constraints]]
type = "edge_spring"
name = "shape"
weight = 10.0
box = {{ min = [{lo}, {lo}, {z0}], max = [{hi}, {hi}, {hi}] }}

[[constraints]]
type = "position"
name = "fixed"
weight = 100.0
box = {{ min = [{lo}, {lo}, {z0}], max = [{hi}, {hi}, {z1}] }}

[[constraints]]
type = "position"
name = "moved"
weight = 100.0
box = {{ min = [{lo}, {lo}, {z2}], max = [{hi}, {hi}, {hi}] }}
translate = [{tx:?}, {ty:?}, {tz:?}]
"#,
        lo = -2.0 * s,
        hi = 2.0 * s,
        z0 = -0.2 * s,
        z1 = -0.1 * s,
        z2 = 0.8 * s,
    )
}

const HEAD_TRANSLATE: [f64; 3] = [0.0, 0.2, 0.1];

/// Vertex classes of the standard scene on the unscaled spot.
fn spot_classes(mesh: &Mesh) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let z = |i: &usize| mesh.positions[*i].z;
    let all = 0..mesh.num_vertices();
    let fixed: Vec<usize> = all.clone().filter(|i| (-0.2..=-0.1).contains(&z(i))).collect();
    let moved: Vec<usize> = all.clone().filter(|i| z(i) >= 0.8).collect();
    let untouched: Vec<usize> = all.filter(|i| z(i) < -0.2).collect();
    assert!(fixed.len() > 10 && moved.len() > 10 && untouched.len() > 10);
    (fixed, moved, untouched)
}

fn diagonal(mesh: &Mesh) -> f64 {
    let (lo, hi) = mesh.bounding_box();
    (hi - lo).length()
}

fn max_abs_coordinate(mesh: &Mesh) -> f64 {
    mesh.positions.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max)
}

/// Largest distance between corresponding vertices.
fn max_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(p, q)| (*p - *q).length()).fold(0.0, f64::max)
}

fn report(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("no report {}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("report {} is not JSON ({e}):\n{text}", path.display()))
}

fn energies(report: &serde_json::Value) -> Vec<f64> {
    report["energy"]
        .as_array()
        .unwrap_or_else(|| panic!("report has no \"energy\" array: {report}"))
        .iter()
        .map(|e| e.as_f64().unwrap_or_else(|| panic!("energy entry {e} is not a number")))
        .collect()
}

fn assert_non_increasing(e: &[f64], what: &str) {
    for (k, w) in e.windows(2).enumerate() {
        assert!(
            w[1] <= w[0] * (1.0 + 1e-12) + 1e-300,
            "{what}: E increased at iteration {}: {} -> {}",
            k + 2,
            w[0],
            w[1]
        );
    }
}

/// The total `E = …` printed by `shapeup energy`.
fn printed_energy(out: &Output) -> f64 {
    let line = out
        .stdout
        .lines()
        .find_map(|l| l.trim().strip_prefix("E = "))
        .unwrap_or_else(|| panic!("no `E = …` line\n{}", out.describe()));
    line.trim().parse().unwrap_or_else(|e| panic!("cannot parse E from {line:?}: {e}"))
}

fn relative_difference(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(f64::MIN_POSITIVE)
}

/// A clear message says each thing once: anyhow's `{:#}` chain must not repeat a cause that an
/// error's own message already includes ("X: why: why").
fn assert_not_repeated(message: &str) {
    let parts: Vec<&str> = message.split(": ").map(str::trim).filter(|p| p.len() > 10).collect();
    for (i, p) in parts.iter().enumerate() {
        assert!(!parts[i + 1..].contains(p), "the error message repeats {p:?}:\n{message}");
    }
}

/// A temp dir with an empty `out/` subdirectory for outputs.
struct Workspace {
    dir: tempfile::TempDir,
}

impl Workspace {
    fn new() -> Workspace {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("out")).unwrap();
        Workspace { dir }
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    fn out(&self, name: &str) -> PathBuf {
        self.dir.path().join("out").join(name)
    }

    fn scene(&self, name: &str, text: &str) -> PathBuf {
        write(&self.path(name), text)
    }

    fn out_entries(&self) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(self.path("out"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    /// Runs `shapeup` with `args` and checks the failure contract: a non-zero exit, exactly one
    /// line on stderr containing every needle, no panic, and nothing left in `out/`.
    fn expect_failure<S: AsRef<OsStr>>(&self, args: &[S], needles: &[&str]) -> String {
        let out = shapeup(args);
        let what = out.describe();
        assert!(matches!(out.code, Some(c) if c != 0), "expected a non-zero exit\n{what}");
        assert!(!out.stderr.contains("panicked"), "panic on bad input\n{what}");
        let lines: Vec<&str> = out.stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(lines.len(), 1, "expected exactly one line on stderr\n{what}");
        for needle in needles {
            assert!(lines[0].contains(needle), "stderr does not mention {needle:?}\n{what}");
        }
        assert_eq!(self.out_entries(), Vec::<String>::new(), "a failed run left files in the output directory\n{what}");
        assert_not_repeated(lines[0]);
        lines[0].to_owned()
    }

    /// The arguments `deform SCENE -o out/result.obj --report out/report.json`.
    fn deform_args(&self, scene: &Path) -> Vec<std::ffi::OsString> {
        let (o, r) = (self.out("result.obj"), self.out("report.json"));
        vec!["deform".into(), scene.into(), "-o".into(), o.into(), "--report".into(), r.into()]
    }

    /// `deform SCENE -o out/result.obj --report out/report.json`, expected to fail.
    fn deform_fails(&self, scene: &Path, needles: &[&str]) -> String {
        self.expect_failure(&self.deform_args(scene), needles)
    }

    /// A scene on spot with `body`, expected to fail naming the scene file and `needles`.
    fn spot_scene_fails(&self, body: &str, needles: &[&str]) -> String {
        let scene = self.scene("bad.toml", &toml_scene(Path::new(SPOT), "", body));
        let mut all = vec!["bad.toml"];
        all.extend_from_slice(needles);
        self.deform_fails(&scene, &all)
    }
}

/// `deform` with `-o out/NAME` (and a report), expected to succeed; returns the output mesh
/// and the report.
fn deform_ok(ws: &Workspace, scene: &Path, name: &str, extra: &[&str]) -> (Mesh, serde_json::Value, Output) {
    let (o, r) = (ws.out(name), ws.out(&format!("{name}.report.json")));
    let mut args: Vec<&OsStr> = vec!["deform".as_ref(), scene.as_os_str(), "-o".as_ref(), o.as_os_str()];
    args.extend(["--report".as_ref(), r.as_os_str()]);
    args.extend(extra.iter().map(OsStr::new));
    let out = shapeup(&args).success();
    assert!(o.is_file(), "no output file {}\n{}", o.display(), out.describe());
    let temps: Vec<String> = ws.out_entries().into_iter().filter(|n| n.starts_with('.')).collect();
    assert!(temps.is_empty(), "temp files left behind: {temps:?}");
    (read(&o), report(&r), out)
}

// ---------------------------------------------------------------------------------------------
// deform
// ---------------------------------------------------------------------------------------------

#[test]
fn deform_keeps_the_mesh_and_moves_the_handles() {
    let ws = Workspace::new();
    let rest = spot();
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", &handle_body(1.0)));
    let (out_mesh, _, out) = deform_ok(&ws, &scene, "spot.obj", &[]);
    assert!(out.stdout.contains("deformed"), "{}", out.describe());

    assert_eq!(out_mesh.num_vertices(), 2930);
    assert_eq!(out_mesh.num_vertices(), rest.num_vertices());
    assert_eq!(out_mesh.triangles, rest.triangles, "the triangles changed");
    assert!(out_mesh.positions.iter().all(|p| p.is_finite()));

    let d = diagonal(&rest);
    let (fixed, moved, untouched) = spot_classes(&rest);
    let delta = |i: usize| out_mesh.positions[i] - rest.positions[i];
    let t = DVec3::from(HEAD_TRANSLATE);
    let worst_fixed = fixed.iter().map(|&i| delta(i).length()).fold(0.0, f64::max);
    assert!(worst_fixed < 0.01 * t.length(), "the fixed handle moved by up to {worst_fixed}");
    let worst_moved = moved.iter().map(|&i| (delta(i) - t).length()).fold(0.0, f64::max);
    assert!(worst_moved < 0.01 * t.length(), "the moved handle is off its target by up to {worst_moved}");
    let worst_untouched = untouched.iter().map(|&i| delta(i).length()).fold(0.0, f64::max);
    assert!(worst_untouched <= 1e-12 * d, "vertices in no constraint moved by up to {worst_untouched}");
    // And the shape in between actually deformed.
    let middle = (0..rest.num_vertices()).filter(|&i| (0.2..0.6).contains(&rest.positions[i].z));
    assert!(
        middle.map(|i| delta(i).length()).fold(0.0, f64::max) > 0.01 * t.length(),
        "nothing between the handles moved"
    );
}

/// `hard = true` holds the handles exactly (the output's handle vertices are their targets, to
/// the file's printed precision), and is refused where it cannot apply.
#[test]
fn hard_handles_hold_their_vertices_exactly() {
    let ws = Workspace::new();
    let rest = spot();
    let body = handle_body(1.0).replace("name = \"moved\"\n", "name = \"moved\"\nhard = true\n");
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", &body));
    let (out_mesh, report, _) = deform_ok(&ws, &scene, "spot.obj", &[]);
    let hard: Vec<bool> = report["groups"].as_array().unwrap().iter().map(|g| g["hard"].as_bool().unwrap()).collect();
    assert_eq!(hard, [false, false, true], "the report marks the hard group");
    let (_, moved, _) = spot_classes(&rest);
    let t = DVec3::from(HEAD_TRANSLATE);
    let worst = moved.iter().map(|&i| (out_mesh.positions[i] - rest.positions[i] - t).length()).fold(0.0, f64::max);
    assert!(worst < 1e-9, "a hard handle is off its target by {worst}");

    let ws = Workspace::new();
    ws.spot_scene_fails(&body.replace("hard = true", "hard = \"yes\""), &["moved", "hard", "true or false"]);
    let ws = Workspace::new();
    ws.spot_scene_fails(
        &body.replace("name = \"shape\"\n", "name = \"shape\"\nhard = true\n"),
        &["shape", "hard", "edge_spring"],
    );
}

#[test]
fn deform_writes_obj_ply_and_stl() {
    let ws = Workspace::new();
    let rest = spot();
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", &handle_body(1.0)));
    let (obj, _, _) = deform_ok(&ws, &scene, "spot.obj", &[]);
    let (ply, _, _) = deform_ok(&ws, &scene, "spot.ply", &[]);
    let (stl, _, _) = deform_ok(&ws, &scene, "spot.stl", &[]);
    let (upper, _, _) = deform_ok(&ws, &scene, "SPOT_UPPER.OBJ", &[]);
    let d = diagonal(&rest);

    assert_eq!(ply.num_vertices(), rest.num_vertices());
    assert_eq!(ply.triangles, rest.triangles);
    assert!(max_distance(&ply.positions, &obj.positions) <= 1e-12 * d, "ply and obj outputs differ");
    assert_eq!(upper.triangles, rest.triangles);
    assert!(max_distance(&upper.positions, &obj.positions) <= 1e-12 * d, "upper-case .OBJ output differs");

    // STL stores no shared vertices (f32, renumbered on read): compare triangle corners.
    assert_eq!(stl.num_triangles(), rest.num_triangles());
    assert_eq!(stl.num_vertices(), rest.num_vertices(), "spot has no unreferenced or coincident vertices");
    for (k, (a, b)) in stl.triangles.iter().zip(&obj.triangles).enumerate() {
        for c in 0..3 {
            let (p, q) = (stl.positions[a[c] as usize], obj.positions[b[c] as usize]);
            assert!((p - q).length() <= 1e-6 * d, "stl triangle {k} corner {c}: {p} vs {q}");
        }
    }
}

#[test]
fn report_has_the_contract_fields() {
    let ws = Workspace::new();
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", &handle_body(1.0)));
    let (_, r, _) = deform_ok(&ws, &scene, "spot.obj", &[]);
    assert_eq!(r["vertices"].as_u64(), Some(2930), "{r}");
    let constraints = r["constraints"].as_u64().unwrap_or_else(|| panic!("no constraints count: {r}"));
    assert!(constraints > 2, "{r}");
    let e = energies(&r);
    assert_eq!(e.len(), 20, "the scene asks for 20 iterations: {r}");
    assert!(e.iter().all(|x| x.is_finite() && *x >= 0.0), "{e:?}");
    assert_non_increasing(&e, "spot");
    assert!(e[e.len() - 1] < e[0], "the energy did not decrease: {e:?}");
    for key in ["load_s", "setup_s", "local_s", "global_s", "total_s"] {
        let v = r["timings"][key].as_f64().unwrap_or_else(|| panic!("timings.{key} missing: {r}"));
        assert!(v.is_finite() && v >= 0.0, "timings.{key} = {v}");
    }
    let t = |k: &str| r["timings"][k].as_f64().unwrap();
    assert!(t("total_s") >= t("local_s") + t("global_s"), "total_s smaller than its parts: {r}");

    for n in [1, 7] {
        let (_, r, out) = deform_ok(&ws, &scene, &format!("spot{n}.obj"), &["--iterations", &n.to_string()]);
        assert_eq!(energies(&r).len(), n, "--iterations {n}\n{}", out.describe());
    }
}

#[test]
fn normalized_frame_is_scale_invariant() {
    let ws = Workspace::new();
    let rest = spot();
    let scale = 1000.0;
    let big = rest.with_positions(rest.positions.iter().map(|&p| p * scale).collect());
    let big_path = ws.path("spot1000.obj");
    write_mesh(&big_path, &big, &read_mesh(Path::new(SPOT)).unwrap().attributes).unwrap();

    let small_scene = ws.scene("small.toml", &toml_scene(Path::new(SPOT), "", &handle_body(1.0)));
    let big_scene = ws.scene("big.toml", &toml_scene(&big_path, "normalize = true", &handle_body(scale)));
    let (small_out, small_r, _) = deform_ok(&ws, &small_scene, "small.obj", &[]);
    let (big_out, big_r, _) = deform_ok(&ws, &big_scene, "big.obj", &[]);

    let expected: Vec<DVec3> = small_out.positions.iter().map(|&p| p * scale).collect();
    let error = max_distance(&big_out.positions, &expected) / max_abs_coordinate(&big_out);
    assert!(error < 1e-9, "output on the ×{scale} mesh is not {scale} × the output (relative error {error})");
    // E is measured in the working frame: the same for both.
    let (es, eb) = (energies(&small_r), energies(&big_r));
    assert_eq!(es.len(), eb.len());
    for (a, b) in es.iter().zip(&eb) {
        assert!(relative_difference(*a, *b) < 1e-8, "working-frame energies differ: {a} vs {b}");
    }

    // Without normalization the scene means something else on the big mesh (edge-spring
    // weights are rest lengths in input units).
    let raw_scene = ws.scene("raw.toml", &toml_scene(&big_path, "normalize = false", &handle_body(scale)));
    let (raw_out, _, _) = deform_ok(&ws, &raw_scene, "raw.obj", &[]);
    let raw_error = max_distance(&raw_out.positions, &expected) / max_abs_coordinate(&big_out);
    assert!(raw_error > 1e-6, "normalize = false had no effect (relative difference {raw_error})");
}

#[test]
fn normalize_false_works_in_input_units() {
    let ws = Workspace::new();
    let rest = spot();
    // One vertex pulled by t; edge springs are at rest: E(rest) = |t|² in the input frame and
    // |t|² σ² in the working frame (σ = 0.5 / distance of the farthest vertex from the centroid).
    let t = [0.3, 0.4, 0.0];
    let body = format!(
        "[[constraints]]\ntype = \"edge_spring\"\n\n[[constraints]]\ntype = \"position\"\nvertices = [7]\ntranslate = {t:?}\n"
    );
    let centroid = rest.positions.iter().copied().sum::<DVec3>() / rest.num_vertices() as f64;
    let radius = rest.positions.iter().map(|p| (*p - centroid).length()).fold(0.0, f64::max);
    let sigma = 0.5 / radius;
    for (options, expected) in
        [("normalize = false", 0.25), ("normalize = true", 0.25 * sigma * sigma), ("", 0.25 * sigma * sigma)]
    {
        let scene = ws.scene("pull.toml", &toml_scene(Path::new(SPOT), options, &body));
        let out = shapeup(["energy".as_ref(), scene.as_os_str(), OsStr::new(SPOT)]).success();
        let e = printed_energy(&out);
        assert!(
            relative_difference(e, expected) < 1e-9,
            "[{options}] E = {e}, expected {expected}\n{}",
            out.describe()
        );
    }

    // A deform with normalize = false: vertices touched by no constraint keep their exact
    // coordinates (the identity frame is exact).
    let scene = ws.scene("raw.toml", &toml_scene(Path::new(SPOT), "normalize = false", &handle_body(1.0)));
    let (out_mesh, _, _) = deform_ok(&ws, &scene, "raw.obj", &[]);
    assert_eq!(out_mesh.num_vertices(), rest.num_vertices());
    assert_eq!(out_mesh.triangles, rest.triangles);
    let (_, moved, untouched) = spot_classes(&rest);
    for &i in &untouched {
        assert_eq!(out_mesh.positions[i], rest.positions[i], "untouched vertex {i} moved (normalize = false)");
    }
    let shift = moved.iter().map(|&i| out_mesh.positions[i] - rest.positions[i]).sum::<DVec3>() / moved.len() as f64;
    assert!(
        (shift - DVec3::from(HEAD_TRANSLATE)).length() < 0.05 * DVec3::from(HEAD_TRANSLATE).length(),
        "head moved by {shift}"
    );
}

#[test]
fn json_scene_equals_toml_scene() {
    let ws = Workspace::new();
    let body = r#"
[solver]
iterations = 15

[[constraints]]
type = "edge_spring"
name = "shape"
weight = 10.0

[[constraints]]
type = "bending"
weight = 10.0
prevent_flips = false

[[constraints]]
type = "position"
name = "feet"
box = { min = [-1.0, -1.0, -1.0], max = [1.0, -0.6, 2.0] }
weight = 10.0

[[constraints]]
type = "position"
name = "head"
box = { min = [-1.0, -1.0, 0.8], max = [1.0, 2.0, 2.0] }
translate = [0.0, 0.25, 0.1]
rotate = { axis = [1.0, 0.0, 0.0], angle_deg = 20.0 }
weight = 10.0
"#;
    let toml = ws.scene("scene.toml", &toml_scene(Path::new(SPOT), "", body));
    let json_value = serde_json::json!({
        "mesh": {"path": SPOT},
        "solver": {"iterations": 15},
        "constraints": [
            {"type": "edge_spring", "name": "shape", "weight": 10.0},
            {"type": "bending", "weight": 10.0, "prevent_flips": false},
            {"type": "position", "name": "feet", "box": {"min": [-1.0, -1.0, -1.0], "max": [1.0, -0.6, 2.0]}, "weight": 10.0},
            {"type": "position", "name": "head", "box": {"min": [-1.0, -1.0, 0.8], "max": [1.0, 2.0, 2.0]},
             "translate": [0.0, 0.25, 0.1], "rotate": {"axis": [1.0, 0.0, 0.0], "angle_deg": 20.0}, "weight": 10.0}
        ]
    });
    let json = ws.scene("scene.json", &serde_json::to_string_pretty(&json_value).unwrap());
    let (a, ra, _) = deform_ok(&ws, &toml, "toml.obj", &[]);
    let (b, rb, _) = deform_ok(&ws, &json, "json.obj", &[]);
    assert_eq!(a.triangles, b.triangles);
    let error = max_distance(&a.positions, &b.positions) / diagonal(&a);
    assert!(error <= 1e-12, "TOML and JSON scenes give different outputs (relative {error})");
    assert_eq!(ra["constraints"], rb["constraints"]);
    let (ea, eb) = (energies(&ra), energies(&rb));
    assert_eq!(ea.len(), 15);
    assert!(relative_difference(ea[14], eb[14]) < 1e-12, "{ea:?} vs {eb:?}");
}

#[test]
fn threads_1_gives_the_same_result() {
    let ws = Workspace::new();
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", &handle_body(1.0)));
    let (a, _, _) = deform_ok(&ws, &scene, "default.obj", &[]);
    let (b, _, _) = deform_ok(&ws, &scene, "one.obj", &["--threads", "1"]);
    // `--threads` is global: also accepted before the subcommand.
    let o = ws.out("first.obj");
    shapeup(["--threads".as_ref(), "1".as_ref(), "deform".as_ref(), scene.as_os_str(), "-o".as_ref(), o.as_os_str()])
        .success();
    let c = read(&o);
    let d = diagonal(&a);
    assert!(max_distance(&a.positions, &b.positions) <= 1e-12 * d);
    assert!(max_distance(&a.positions, &c.positions) <= 1e-12 * d);
}

#[test]
fn deform_resolves_mesh_paths_against_the_scene_file() {
    // A relative mesh path, run from another working directory.
    let ws = Workspace::new();
    std::fs::create_dir(ws.path("scenes")).unwrap();
    std::fs::create_dir(ws.path("meshes")).unwrap();
    std::fs::copy(SUZANNE, ws.path("meshes/suzanne.obj")).unwrap();
    // Suzanne's eyes are separate pieces: a weak position group on every vertex anchors them.
    let body = "[[constraints]]\ntype = \"edge_spring\"\n\n[[constraints]]\ntype = \"position\"\nname = \"anchor\"\nweight = 0.01\n\n\
                [[constraints]]\ntype = \"position\"\nvertices = [0, 1, 2]\ntranslate = [0.0, 0.1, 0.0]\n";
    write(&ws.path("scenes/s.toml"), &format!("[mesh]\npath = \"../meshes/suzanne.obj\"\n{body}"));
    let out = shapeup_in(Some(&ws.path("out")), ["deform", "../scenes/s.toml", "-o", "suzanne.ply"]).success();
    let mesh = read(&ws.out("suzanne.ply"));
    let rest = read(Path::new(SUZANNE));
    assert_eq!(mesh.num_vertices(), 507, "{}", out.describe());
    // The quads come back as quads (their triangulation follows the moved geometry).
    assert_eq!(mesh.polygons, rest.polygons, "the faces must come back as they were");
    assert!(rest.num_triangles() > 500, "suzanne's quads were not split into triangles");
    let moved = (0..3).map(|i| mesh.positions[i] - rest.positions[i]).sum::<DVec3>() / 3.0;
    assert!((moved - DVec3::new(0.0, 0.1, 0.0)).length() < 0.05, "the handle moved by {moved}");
}

#[test]
fn deform_and_simulate_write_where_the_output_table_says() {
    let ws = Workspace::new();
    let body = format!("{}\n[output]\npath = \"out/spot.obj\"\nreport = \"out/spot.json\"\n", handle_body(1.0));
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", &body));
    let explicit = deform_ok(&ws, &scene, "explicit.obj", &[]).0;
    shapeup(["deform".as_ref(), scene.as_os_str()]).success();
    let from_table = read(&ws.out("spot.obj"));
    assert_eq!(from_table.positions, explicit.positions, "[output] path and -o give the same result");
    assert!(report(&ws.out("spot.json"))["energy"].is_array());

    // Without -o and without [output]: one line saying what to give, nothing written.
    let bare = ws.scene("bare.toml", &toml_scene(Path::new(SPOT), "", &handle_body(1.0)));
    for f in ["explicit.obj", "explicit.obj.report.json", "spot.obj", "spot.json"] {
        std::fs::remove_file(ws.out(f)).unwrap();
    }
    ws.expect_failure(&["deform".as_ref(), bare.as_os_str()], &["bare.toml", "-o", "[output]"]);
    ws.expect_failure(
        &["simulate".as_ref(), bare.as_os_str(), "--frames".as_ref(), "2".as_ref()],
        &["bare.toml", "-o DIR"],
    );

    // simulate: [output] path is the frames' folder.
    let dynamic = ws.scene(
        "cloth.toml",
        "[mesh]\ngenerate = { kind = \"cloth\", vertices = [5, 5], size = [1.0, 1.0] }\n[solver]\nmode = \"dynamic\"\n\
         [[constraints]]\ntype = \"edge_spring\"\n[[constraints]]\ntype = \"position\"\nvertices = [0]\n\
         [output]\npath = \"out/frames\"\n",
    );
    shapeup(["simulate".as_ref(), dynamic.as_os_str(), "--frames".as_ref(), "2".as_ref()]).success();
    assert!(ws.out("frames/frame_0002.obj").is_file());
}

// ---------------------------------------------------------------------------------------------
// energy
// ---------------------------------------------------------------------------------------------

#[test]
fn energy_of_the_rest_shape_is_zero() {
    let ws = Workspace::new();
    let body = r#"
[[constraints]]
type = "edge_spring"
name = "springs"
weight = 10.0

[[constraints]]
type = "bending"
weight = 10.0

[[constraints]]
type = "position"
name = "fixed"
box = { min = [-1.0, -1.0, -1.0], max = [1.0, -0.6, 2.0] }
"#;
    for mesh in [SPOT, COW] {
        let scene = ws.scene("rest.toml", &toml_scene(Path::new(mesh), "", body));
        let out = shapeup(["energy".as_ref(), scene.as_os_str(), OsStr::new(mesh)]).success();
        let e = printed_energy(&out);
        assert!(e.abs() < 1e-20, "{mesh}: E(rest) = {e}\n{}", out.describe());
        for name in ["springs", "bending", "fixed"] {
            assert!(out.stdout.contains(name), "no per-group line for {name}\n{}", out.describe());
        }
    }
}

#[test]
fn energy_of_the_rest_shape_is_zero_for_every_shape_type() {
    let ws = Workspace::new();
    let body = r#"
[[constraints]]
type = "triangle_strain"
weight = 10.0
strain_freedom = 0.0

[[constraints]]
type = "iso_one_ring"
weight = 100.0

[[constraints]]
type = "edge_spring"

[[constraints]]
type = "bending"
prevent_flips = true

[[constraints]]
type = "position"
name = "fixed"
vertices = [0, 1, 2]
"#;
    let scene = ws.scene("rest.toml", &toml_scene(Path::new(SPOT), "", body));
    let out = shapeup(["energy".as_ref(), scene.as_os_str(), OsStr::new(SPOT)]).success();
    let e = printed_energy(&out);
    assert!(e.abs() < 1e-20, "E(rest) = {e}\n{}", out.describe());
}

#[test]
fn energy_of_the_deform_output_matches_the_report() {
    let ws = Workspace::new();
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", &handle_body(1.0)));
    for name in ["spot.obj", "spot.ply"] {
        let (_, r, _) = deform_ok(&ws, &scene, name, &[]);
        let last = *energies(&r).last().unwrap();
        let out = shapeup(["energy".as_ref(), scene.as_os_str(), ws.out(name).as_os_str()]).success();
        let e = printed_energy(&out);
        assert!(relative_difference(e, last) < 1e-9, "{name}: energy prints {e}, the report's last entry is {last}");
        assert!(out.stdout.contains("shape") && out.stdout.contains("moved"), "no per-group lines\n{}", out.describe());
    }
}

/// The report starts from the energy of the starting shape (`initial_energy`, what `shapeup
/// energy` gives for the input), and the printed line goes from it; with 0 iterations both ends
/// are that energy (it printed "E 0 -> 0").
#[test]
fn the_report_and_the_summary_start_from_the_initial_energy() {
    let ws = Workspace::new();
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", &handle_body(1.0)));
    let rest = printed_energy(&shapeup(["energy".as_ref(), scene.as_os_str(), OsStr::new(SPOT)]).success());
    assert!(rest > 0.0, "the moved handle's energy at rest is {rest}");
    for n in ["0", "3"] {
        let (_, r, out) = deform_ok(&ws, &scene, &format!("spot{n}.obj"), &["--iterations", n]);
        let initial = r["initial_energy"].as_f64().unwrap_or_else(|| panic!("no initial_energy: {r}"));
        assert!(relative_difference(initial, rest) < 1e-9, "--iterations {n}: initial {initial}, energy {rest}");
        let e = energies(&r);
        let change = r["relative_change"].as_array().unwrap_or_else(|| panic!("no relative_change: {r}"));
        assert_eq!(change.len(), e.len(), "{r}");
        if let Some(&e1) = e.first() {
            let first = change[0].as_f64().unwrap_or_else(|| panic!("first relative change: {r}"));
            assert!(relative_difference(first, (initial - e1).abs() / initial) < 1e-9, "{r}");
        }
        let summary = format!("E {initial:.6e} -> {:.6e}", e.last().copied().unwrap_or(initial));
        assert!(out.stdout.contains(&summary), "--iterations {n}: expected {summary:?}\n{}", out.describe());
    }
}

/// Each acceleration, chosen by the flag or the scene key: the report names it and counts its
/// rejected steps, E never increases, and L-BFGS (the default) ends lowest after 40 iterations;
/// a memory outside 1..=50 is one line naming the key.
#[test]
fn each_acceleration_is_reported_and_keeps_the_energy_monotone() {
    let ws = Workspace::new();
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", &handle_body(1.0)));
    let mut last = Vec::new();
    for acceleration in ["none", "anderson", "lbfgs"] {
        let extra = ["--iterations", "40", "--acceleration", acceleration];
        let (_, r, _) = deform_ok(&ws, &scene, &format!("spot-{acceleration}.obj"), &extra);
        assert_eq!(r["acceleration"], acceleration, "{r}");
        let rejected = r["rejected"].as_u64().unwrap_or_else(|| panic!("no rejected count: {r}"));
        assert!(acceleration != "none" || rejected == 0, "{r}");
        let e = energies(&r);
        assert!(e.windows(2).all(|w| w[1] <= w[0] * (1.0 + 1e-12)), "{acceleration}: E rose: {e:?}");
        last.push(*e.last().unwrap());
    }
    assert!(last[2] < last[0], "L-BFGS {} vs plain {}", last[2], last[0]);
    let (_, r, _) = deform_ok(&ws, &scene, "spot-default.obj", &["--iterations", "2"]);
    assert_eq!(r["acceleration"], "lbfgs", "the default\n{r}");
    let fresh = Workspace::new();
    let body = handle_body(1.0).replace("iterations = 20", "iterations = 20\nlbfgs_memory = 51");
    let bad = fresh.scene("bad.toml", &toml_scene(Path::new(SPOT), "", &body));
    let out = fresh.out("bad.obj");
    let args = [OsStr::new("deform"), bad.as_os_str(), OsStr::new("-o"), out.as_os_str()];
    fresh.expect_failure(&args, &["bad.toml", "lbfgs_memory", "51"]);
}

#[test]
fn energy_rejects_positions_with_another_vertex_count() {
    let ws = Workspace::new();
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", &handle_body(1.0)));
    ws.expect_failure(&[OsStr::new("energy"), scene.as_os_str(), OsStr::new(COW)], &["cow.obj", "2903", "2930"]);
    ws.expect_failure(&[OsStr::new("energy"), scene.as_os_str(), ws.path("missing.obj").as_os_str()], &["missing.obj"]);
    // The same count in another order: Spot as STL merges its vertices in the order its
    // triangles use them (the trial's E 577 for a shape of E 12, read without a word).
    deform_ok(&ws, &scene, "spot.stl", &[]);
    let stl = ws.path("spot.stl");
    std::fs::rename(ws.out("spot.stl"), &stl).unwrap();
    std::fs::remove_file(ws.out("spot.stl.report.json")).unwrap();
    ws.expect_failure(&[OsStr::new("energy"), scene.as_os_str(), stl.as_os_str()], &["spot.stl", "not a shape of"]);
}

// ---------------------------------------------------------------------------------------------
// Bad input: one line on stderr naming the problem, non-zero exit, nothing written
// ---------------------------------------------------------------------------------------------

const SHAPE_AND_HANDLE: &str =
    "[[constraints]]\ntype = \"edge_spring\"\n\n[[constraints]]\ntype = \"position\"\nvertices = [0]\n";

#[test]
fn unknown_top_level_key() {
    let ws = Workspace::new();
    // Before `[mesh]`, so that the key is at the top level (not in the `[mesh]` table).
    let scene = ws.scene("bad.toml", &format!("extra_key = 1\n{}", toml_scene(Path::new(SPOT), "", SHAPE_AND_HANDLE)));
    ws.deform_fails(&scene, &["bad.toml", "extra_key"]);
    let scene =
        ws.scene("bad.toml", &format!("{}\n[extra_table]\nx = 1\n", toml_scene(Path::new(SPOT), "", SHAPE_AND_HANDLE)));
    ws.deform_fails(&scene, &["bad.toml", "extra_table"]);
}

#[test]
fn unknown_mesh_key() {
    let ws = Workspace::new();
    let scene = ws.scene("bad.toml", &toml_scene(Path::new(SPOT), "normalise = true", SHAPE_AND_HANDLE));
    ws.deform_fails(&scene, &["bad.toml", "normalise"]);
}

#[test]
fn unknown_solver_key() {
    let ws = Workspace::new();
    ws.spot_scene_fails(&format!("[solver]\niteratons = 3\n\n{SHAPE_AND_HANDLE}"), &["iteratons"]);
}

#[test]
fn unknown_constraint_key() {
    let ws = Workspace::new();
    ws.spot_scene_fails(
        "[[constraints]]\ntype = \"edge_spring\"\nstrain_freedom = 0.1\n\n[[constraints]]\ntype = \"position\"\nvertices = [0]\n",
        &["strain_freedom", "constraints[0]"],
    );
    ws.spot_scene_fails(
        "[[constraints]]\ntype = \"edge_spring\"\n\n[[constraints]]\ntype = \"position\"\nvertices = [0]\ntranslation = [1.0, 0.0, 0.0]\n",
        &["translation", "constraints[1]"],
    );
}

#[test]
fn unknown_constraint_type() {
    let ws = Workspace::new();
    ws.spot_scene_fails("[[constraints]]\ntype = \"edge_sprin\"\n", &["edge_sprin", "constraints[0]"]);
}

#[test]
fn vertex_index_out_of_range() {
    let ws = Workspace::new();
    ws.spot_scene_fails(
        "[[constraints]]\ntype = \"edge_spring\"\n\n[[constraints]]\ntype = \"position\"\nname = \"handle\"\nvertices = [0, 5000]\n",
        &["5000", "constraints[1]", "2930"],
    );
}

#[test]
fn negative_weight() {
    let ws = Workspace::new();
    ws.spot_scene_fails(
        "[[constraints]]\ntype = \"edge_spring\"\nweight = -1.0\n\n[[constraints]]\ntype = \"position\"\nvertices = [0]\n",
        &["weight", "constraints[0]"],
    );
}

#[test]
fn duplicate_vertex_in_a_position_group() {
    let ws = Workspace::new();
    ws.spot_scene_fails(
        "[[constraints]]\ntype = \"edge_spring\"\n\n[[constraints]]\ntype = \"position\"\nvertices = [3, 8, 3]\n",
        &["3", "twice", "constraints[1]"],
    );
}

#[test]
fn box_selecting_nothing() {
    let ws = Workspace::new();
    ws.spot_scene_fails(
        "[[constraints]]\ntype = \"edge_spring\"\n\n[[constraints]]\ntype = \"position\"\nname = \"nowhere\"\nbox = { min = [10.0, 10.0, 10.0], max = [11.0, 11.0, 11.0] }\n",
        &["constraints[1]", "nowhere", "no vertices"],
    );
}

#[test]
fn malformed_toml_names_the_line() {
    let ws = Workspace::new();
    // The body starts on line 4 of the file (after `[mesh]`, `path` and an empty line).
    ws.spot_scene_fails("[solver\niterations = 3\n", &["line 4"]);
    ws.spot_scene_fails("\n[solver]\niterations = \"ten\"\n", &["line 6"]);
}

#[test]
fn malformed_json_is_rejected() {
    let ws = Workspace::new();
    let scene = ws.scene("bad.json", &format!("{{\"mesh\": {{\"path\": {:?}}},\n \"constraints\": [ }}", SPOT));
    ws.deform_fails(&scene, &["bad.json", "line 2"]);
    let scene = ws.scene("bad.json", &format!("{{\"mesh\": {{\"path\": {:?}}}, \"extra_key\": 1}}", SPOT));
    ws.deform_fails(&scene, &["bad.json", "extra_key"]);
}

#[test]
fn missing_mesh_file() {
    let ws = Workspace::new();
    let scene = ws.scene("bad.toml", &toml_scene(&ws.path("no-such-mesh.obj"), "", SHAPE_AND_HANDLE));
    ws.deform_fails(&scene, &["no-such-mesh.obj"]);
}

#[test]
fn malformed_mesh_names_the_file_and_line() {
    let ws = Workspace::new();
    let mesh = write(&ws.path("broken.obj"), "v 0 0 0\nv 1 2 x\nv 0 1 0\nf 1 2 3\n");
    let scene = ws.scene("bad.toml", &toml_scene(&mesh, "", SHAPE_AND_HANDLE));
    ws.deform_fails(&scene, &["broken.obj", "line 2"]);
}

#[test]
fn obj_face_index_out_of_range() {
    let ws = Workspace::new();
    let mesh = write(&ws.path("faces.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n");
    let scene = ws.scene("bad.toml", &toml_scene(&mesh, "", SHAPE_AND_HANDLE));
    ws.deform_fails(&scene, &["faces.obj", "9"]);
}

#[test]
fn empty_mesh() {
    let ws = Workspace::new();
    let mesh = write(&ws.path("empty.obj"), "");
    let scene = ws.scene("bad.toml", &toml_scene(&mesh, "", SHAPE_AND_HANDLE));
    ws.deform_fails(&scene, &["empty.obj"]);
    // Vertices but no faces.
    let mesh = write(&ws.path("points.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    let scene = ws.scene("bad.toml", &toml_scene(&mesh, "", SHAPE_AND_HANDLE));
    ws.deform_fails(&scene, &["points.obj"]);
}

#[test]
fn unsupported_output_extension() {
    let ws = Workspace::new();
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", SHAPE_AND_HANDLE));
    let o = ws.out("result.xyz");
    ws.expect_failure(&[OsStr::new("deform"), scene.as_os_str(), "-o".as_ref(), o.as_os_str()], &["result.xyz", "xyz"]);
    let (o, r) = (ws.out("result.obj"), ws.out("report.txt"));
    ws.expect_failure(
        &[OsStr::new("deform"), scene.as_os_str(), "-o".as_ref(), o.as_os_str(), "--report".as_ref(), r.as_os_str()],
        &["report.txt"],
    );
}

#[test]
fn output_directory_that_does_not_exist() {
    let ws = Workspace::new();
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", SHAPE_AND_HANDLE));
    let o = ws.out("no-such-dir/result.obj");
    ws.expect_failure(&[OsStr::new("deform"), scene.as_os_str(), "-o".as_ref(), o.as_os_str()], &["result.obj"]);
}

#[test]
fn scene_without_position_constraints_is_singular() {
    let ws = Workspace::new();
    ws.spot_scene_fails("[[constraints]]\ntype = \"edge_spring\"\nweight = 10.0\n", &["singular"]);
}

#[test]
fn failure_leaves_an_existing_output_untouched() {
    let ws = Workspace::new();
    let scene = ws.scene("bad.toml", &toml_scene(Path::new(SPOT), "", "[[constraints]]\ntype = \"edge_spring\"\n"));
    let (o, r) = (ws.out("result.obj"), ws.out("report.json"));
    write(&o, "old output\n");
    write(&r, "old report\n");
    let out = shapeup(ws.deform_args(&scene));
    assert!(matches!(out.code, Some(c) if c != 0), "{}", out.describe());
    assert_eq!(std::fs::read_to_string(&o).unwrap(), "old output\n", "the output was overwritten by a failed run");
    assert_eq!(std::fs::read_to_string(&r).unwrap(), "old report\n", "the report was overwritten by a failed run");
    assert_eq!(ws.out_entries(), ["report.json", "result.obj"], "temp files left behind");
}

#[test]
fn missing_scene_file() {
    let ws = Workspace::new();
    ws.deform_fails(&ws.path("no-such-scene.toml"), &["no-such-scene.toml"]);
}

#[test]
fn scene_with_an_unknown_extension() {
    let ws = Workspace::new();
    let scene = ws.scene("scene.yaml", &toml_scene(Path::new(SPOT), "", SHAPE_AND_HANDLE));
    ws.deform_fails(&scene, &["scene.yaml"]);
}

#[test]
fn threads_0_and_absurd_thread_counts_are_rejected() {
    let ws = Workspace::new();
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", SHAPE_AND_HANDLE));
    let o = ws.out("result.obj");
    for n in ["0", "99999"] {
        ws.expect_failure(
            &[OsStr::new("deform"), scene.as_os_str(), "-o".as_ref(), o.as_os_str(), "--threads".as_ref(), n.as_ref()],
            &["threads", n],
        );
    }
    // A benchmark of no iterations measures nothing.
    ws.expect_failure(&["bench", "--mesh", SPOT, "--iterations", "0"], &["iterations"]);
}

#[test]
fn iterations_must_be_a_number() {
    let ws = Workspace::new();
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", SHAPE_AND_HANDLE));
    let o = ws.out("result.obj");
    let out = shapeup([
        "deform".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        o.as_os_str(),
        "--iterations".as_ref(),
        "ten".as_ref(),
    ]);
    assert_eq!(out.code, Some(2), "clap usage error expected\n{}", out.describe());
    assert!(out.stderr.contains("--iterations") && out.stderr.contains("ten"), "{}", out.describe());
    assert!(!out.stderr.contains("panicked"), "{}", out.describe());
    assert_eq!(ws.out_entries(), Vec::<String>::new());
}

#[test]
fn missing_subcommand_or_arguments_are_usage_errors() {
    for args in [&[][..], &["deform"][..], &["frobnicate"][..]] {
        let out = shapeup(args);
        assert_eq!(out.code, Some(2), "{args:?}\n{}", out.describe());
        assert!(!out.stderr.contains("panicked"), "{}", out.describe());
    }
}

// ---------------------------------------------------------------------------------------------
// help, version, bench
// ---------------------------------------------------------------------------------------------

#[test]
fn help_for_every_subcommand() {
    for args in [
        &["--help"][..],
        &["-h"],
        &["help"],
        &["deform", "--help"],
        &["energy", "--help"],
        &["bench", "--help"],
        &["help", "deform"],
    ] {
        let out = shapeup(args).success();
        assert!(out.stdout.contains("Usage"), "{args:?}\n{}", out.describe());
    }
    let top = shapeup(["--help"]).success().stdout;
    for sub in ["deform", "energy", "bench", "--threads", "--version"] {
        assert!(top.contains(sub), "top-level help does not mention {sub}:\n{top}");
    }
    let deform = shapeup(["deform", "--help"]).success().stdout;
    for option in ["--output", "--iterations", "--report", "--threads"] {
        assert!(deform.contains(option), "deform help does not mention {option}:\n{deform}");
    }
}

#[test]
fn version_is_printed() {
    let out = shapeup(["--version"]).success();
    assert!(out.stdout.contains(env!("CARGO_PKG_VERSION")), "{}", out.describe());
    assert!(out.stdout.starts_with("shapeup"), "{}", out.describe());
}

#[test]
fn bench_prints_the_three_scenarios() {
    let out = shapeup(["bench", "--mesh", SPOT, "--iterations", "3", "--threads", "1"]).success();
    let lines: Vec<&str> = out.stdout.lines().collect();
    assert!(lines.iter().any(|l| l.contains("scenario")), "no table header\n{}", out.describe());
    for scenario in ["springs", "strain+bending", "iso"] {
        let row = lines
            .iter()
            .find(|l| l.split_whitespace().next() == Some(scenario))
            .unwrap_or_else(|| panic!("no row for {scenario}\n{}", out.describe()));
        let numbers: Vec<f64> = row.split_whitespace().skip(1).map(|x| x.parse().unwrap()).collect();
        assert!(numbers.len() >= 5 && numbers.iter().all(|x| x.is_finite() && *x >= 0.0), "bad row {row:?}");
    }
    let one = shapeup(["bench", "--mesh", SPOT, "--iterations", "2", "--scenario", "springs"]).success();
    assert!(
        one.stdout.lines().any(|l| l.starts_with("springs")) && !one.stdout.contains("strain+bending"),
        "{}",
        one.describe()
    );
    let ws = Workspace::new();
    ws.expect_failure(&["bench", "--mesh", SPOT, "--scenario", "nope"], &["nope"]);
    ws.expect_failure(&[OsStr::new("bench"), "--mesh".as_ref(), ws.path("none.obj").as_os_str()], &["none.obj"]);
}

/// `bench --converge`: a plain and an accelerated row per scenario; on one-rings (which converge
/// fast) both reach the 1 % gap within the cap, the accelerated one in fewer iterations.
#[test]
fn bench_converge_compares_time_to_a_converged_shape() {
    let out = shapeup([
        "bench",
        "--converge",
        "--mesh",
        SPOT,
        "--scenario",
        "iso",
        "--iterations",
        "150",
        "--reference-iterations",
        "300",
    ])
    .success();
    let rows: Vec<Vec<&str>> = out.stdout.lines().map(|l| l.split_whitespace().collect()).collect();
    let first_cell = |kind: &str| -> usize {
        let row = rows.iter().find(|r| r.len() > 2 && r[0] == "iso" && r[1] == kind);
        let row = row.unwrap_or_else(|| panic!("no {kind} row\n{}", out.describe()));
        row[2].parse().unwrap_or_else(|_| panic!("{kind} did not reach 1 %\n{}", out.describe()))
    };
    assert!(first_cell("anderson") < first_cell("plain"), "{}", out.describe());
    assert!(first_cell("lbfgs") < first_cell("plain"), "{}", out.describe());
}

// ---------------------------------------------------------------------------------------------
// The shipped examples, as they are
// ---------------------------------------------------------------------------------------------

/// Which vertices a scene selection picks (as in the scene contract: bounds included).
fn selected(selection: &SelectionSpec, mesh: &Mesh) -> Vec<bool> {
    let n = mesh.num_vertices();
    match selection {
        SelectionSpec::All => vec![true; n],
        SelectionSpec::Vertices(list) => {
            let mut s = vec![false; n];
            list.iter().for_each(|&v| s[v] = true);
            s
        }
        SelectionSpec::Box { min, max } => {
            let (lo, hi) = (DVec3::from(*min), DVec3::from(*max));
            mesh.positions.iter().map(|p| p.cmpge(lo).all() && p.cmple(hi).all()).collect()
        }
        SelectionSpec::Sphere { center, radius } => {
            mesh.positions.iter().map(|p| (*p - DVec3::from(*center)).length() <= *radius).collect()
        }
        SelectionSpec::Faces(list) => {
            let mut s = vec![false; n];
            list.iter().flat_map(|&f| mesh.polygons.get(f).unwrap_or(&[])).for_each(|&v| s[v as usize] = true);
            s
        }
        SelectionSpec::Physical(name) => panic!("no example selects a physical group ({name})"),
    }
}

fn check_example(ws: &Workspace, scene_path: &Path) -> Result<(), String> {
    let name = scene_path.file_stem().unwrap().to_string_lossy().into_owned();
    let scene = Scene::from_file(scene_path).map_err(|e| format!("{name}: the scene does not parse: {e}"))?;
    if scene.solver.mode == shapeup_core::scene::Mode::Dynamic {
        return check_dynamic_example(ws, scene_path, &scene);
    }
    // A generated mesh (form finding) has no file to read back.
    let rest = scene.read_mesh().map_err(|e| format!("{name}: {e}"))?.mesh;
    let (o, r) = (ws.out(&format!("{name}.obj")), ws.out(&format!("{name}.json")));
    // Run from an unrelated working directory: the mesh path is relative to the scene file.
    let out = shapeup_in(
        Some(ws.dir.path()),
        [
            OsStr::new("deform"),
            scene_path.as_os_str(),
            "-o".as_ref(),
            o.as_os_str(),
            "--report".as_ref(),
            r.as_os_str(),
        ],
    );
    if out.code != Some(0) {
        return Err(format!("{name}: deform failed\n{}", out.describe()));
    }
    let mesh = read(&o);
    let report = report(&r);
    let mut problems = Vec::new();
    if mesh.num_vertices() != rest.num_vertices() {
        problems.push(format!("{} vertices written, the input has {}", mesh.num_vertices(), rest.num_vertices()));
    }
    // The faces as written (a moved quad may be triangulated along its other diagonal).
    if mesh.polygons != rest.polygons {
        problems.push("the faces changed".into());
    }
    if report["vertices"].as_u64() != Some(rest.num_vertices() as u64) {
        problems.push(format!("report vertices = {}", report["vertices"]));
    }
    let e = energies(&report);
    let expected_iterations = scene.solver.iterations * scene.solver.steps;
    if scene.solver.tolerance == 0.0 && e.len() != expected_iterations {
        problems.push(format!("{} energies, expected {expected_iterations}", e.len()));
    }
    // E may be negative with a load (gravity, force): compare with a slack of its size.
    if let Some(k) = e.windows(2).position(|w| w[1] > w[0] + 1e-12 * w[0].abs()) {
        problems.push(format!("E increased at iteration {}: {} -> {}", k + 2, e[k], e[k + 1]));
    }
    if problems.is_empty() {
        let d = diagonal(&rest);
        // Vertices in no triangle, no tetrahedron (a material's) and no position group are
        // touched by no constraint.
        let largest_translate = scene
            .groups
            .iter()
            .filter(|g| g.kind == "position")
            .map(|g| DVec3::from(g.targets.translate).length())
            .fold(0.0, f64::max);
        let mut touched = vec![false; rest.num_vertices()];
        rest.triangles.iter().flatten().for_each(|&v| touched[v as usize] = true);
        rest.tetrahedra.iter().flatten().for_each(|&v| touched[v as usize] = true);
        for g in scene.groups.iter().filter(|g| g.kind == "position") {
            let s = selected(&g.selection, &rest);
            touched.iter_mut().zip(&s).for_each(|(t, s)| *t |= *s);
            let picked: Vec<usize> = (0..rest.num_vertices()).filter(|&i| s[i]).collect();
            if g.targets.rotate.is_some() || g.targets.explicit.is_some() || picked.is_empty() {
                continue;
            }
            let t = DVec3::from(g.targets.translate);
            let shift =
                picked.iter().map(|&i| mesh.positions[i] - rest.positions[i]).sum::<DVec3>() / picked.len() as f64;
            // Handles have finite weights: they follow their targets only roughly; a group that
            // stays (closeness, an anchor of small weight) may drift up to 1 % of the diagonal.
            let slack = if t == DVec3::ZERO { 0.01 * d } else { 0.25 * largest_translate.max(1e-3 * d) };
            if (shift - t).length() > slack {
                problems.push(format!("handle \"{}\" moved on average by {shift}, its translate is {t}", g.name));
            }
        }
        let untouched: Vec<usize> = (0..rest.num_vertices()).filter(|&i| !touched[i]).collect();
        let worst = untouched.iter().map(|&i| (mesh.positions[i] - rest.positions[i]).length()).fold(0.0, f64::max);
        if worst > 1e-12 * d {
            problems.push(format!("{} vertices touched by no constraint moved by up to {worst}", untouched.len()));
        }
        if name.starts_with("bunny") && untouched.is_empty() {
            problems.push("the bunny's unreferenced vertices should be untouched".into());
        }
    }
    if problems.is_empty() { Ok(()) } else { Err(format!("{name}: {}", problems.join("; "))) }
}

/// A dynamic example: 30 steps, every 10th frame, from an unrelated working directory.
fn check_dynamic_example(ws: &Workspace, scene_path: &Path, scene: &Scene) -> Result<(), String> {
    let name = scene_path.file_stem().unwrap().to_string_lossy().into_owned();
    let rest = scene.read_mesh().map_err(|e| format!("{name}: {e}"))?.mesh;
    let (dir, r) = (ws.out(&format!("{name}-frames")), ws.out(&format!("{name}.json")));
    let out = simulate_in(
        Some(ws.dir.path()),
        scene_path,
        &dir,
        &[
            OsStr::new("--frames"),
            OsStr::new("30"),
            OsStr::new("--every"),
            OsStr::new("10"),
            OsStr::new("--report"),
            r.as_os_str(),
        ],
    );
    if out.code != Some(0) {
        return Err(format!("{name}: simulate failed\n{}", out.describe()));
    }
    let mut frames: Vec<String> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    frames.sort();
    let expected = ["frame_0000.obj", "frame_0010.obj", "frame_0020.obj", "frame_0030.obj"];
    if frames != expected {
        return Err(format!("{name}: frames {frames:?}, expected {expected:?}"));
    }
    let first = read(&dir.join(expected[0]));
    let last = read(&dir.join(expected[3]));
    if first.triangles != rest.triangles || last.triangles != rest.triangles {
        return Err(format!("{name}: the frames do not have the mesh's surface"));
    }
    if last.positions.iter().any(|p| !p.is_finite()) || last.positions == first.positions {
        return Err(format!("{name}: the last frame is not finite or did not move"));
    }
    let report = report(&r);
    if report["steps"].as_u64() != Some(30) || report["energy"].as_array().map(Vec::len) != Some(30) {
        return Err(format!("{name}: report steps {} energy {}", report["steps"], report["energy"]));
    }
    Ok(())
}

#[test]
fn shipped_examples_deform() {
    let ws = Workspace::new();
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(EXAMPLES)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| matches!(p.extension().and_then(OsStr::to_str), Some("toml" | "json")))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 4, "expected the shipped examples in {EXAMPLES}");
    let failures: Vec<String> = scenes.iter().filter_map(|s| check_example(&ws, s).err()).collect();
    assert!(failures.is_empty(), "{} of {} examples failed:\n{}", failures.len(), scenes.len(), failures.join("\n\n"));
    // The bunny example keeps all 35,947 vertices, including those in no triangle.
    let bunny = read(&ws.out("bunny-springs.obj"));
    assert_eq!(bunny.num_vertices(), 35_947);
}

// ---- simulate ----

/// Plain time steps evaluate no energy, so an overflow (gravity 1e300) shows first in the
/// report's energy: one line saying so and a non-zero exit, as the accelerated steps give,
/// never `null` energies in a report.
#[test]
fn simulate_with_an_overflowing_energy_fails_with_or_without_acceleration() {
    let ws = Workspace::new();
    let scene = ws.scene(
        "g300.toml",
        "[mesh]\ngenerate = { kind = \"cloth\", vertices = [4, 4], size = [1.0, 1.0] }\n\
         [solver]\nmode = \"dynamic\"\ngravity = [0.0, -1e300, 0.0]\n\
         [[constraints]]\ntype = \"edge_spring\"\n",
    );
    for acceleration in ["lbfgs", "anderson", "none"] {
        let (dir, report) = (ws.out(&format!("g300-{acceleration}")), ws.out(&format!("g300-{acceleration}.json")));
        let extra = ["--frames", "3", "--acceleration", acceleration, "--report", report.to_str().unwrap()];
        let out = simulate_in(None, &scene, &dir, &extra);
        let what = out.describe();
        assert!(matches!(out.code, Some(c) if c != 0), "{acceleration}: expected a failure\n{what}");
        let lines: Vec<&str> = out.stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(lines.len(), 1, "{acceleration}: one line\n{what}");
        assert!(lines[0].contains("g300.toml") && lines[0].contains("not a finite number"), "{acceleration}\n{what}");
        assert!(!report.exists(), "{acceleration}: a report was written\n{what}");
    }
}

/// A 3×3 cloth with no constraints falling under `gravity`: frame k must be the discrete free
/// fall y_k = g h² k(k+1)/2 (x_{n+1} = x_n + h v_n + h² g from rest), in input units whether
/// or not the scene works in the normalized frame.
#[test]
fn simulate_free_fall_is_the_discrete_formula_in_input_units() {
    let ws = Workspace::new();
    let h = 0.01;
    for normalize in [false, true] {
        let scene = ws.scene(
            &format!("fall-{normalize}.toml"),
            &format!(
                "[mesh]\ngenerate = {{ kind = \"cloth\", vertices = [3, 3], size = [2.0, 2.0] }}\nnormalize = {normalize}\n\
                 [solver]\nmode = \"dynamic\"\ntime_step = {h}\ngravity = [0.0, -10.0, 0.0]\n"
            ),
        );
        let dir = ws.out(&format!("fall-{normalize}"));
        let out = simulate_in(None, &scene, &dir, &["--frames", "6"]);
        assert_eq!(out.code, Some(0), "{}", out.describe());
        let rest = read(&dir.join("frame_0000.obj"));
        let fallen = read(&dir.join("frame_0006.obj"));
        let drop = -10.0 * h * h * 21.0;
        for (a, b) in rest.positions.iter().zip(&fallen.positions) {
            assert!(
                (b.y - (a.y + drop)).abs() < 1e-12,
                "normalize {normalize}: {} -> {}, expected drop {drop}",
                a.y,
                b.y
            );
            assert!((b.x - a.x).abs() < 1e-12 && (b.z - a.z).abs() < 1e-12);
        }
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 7, "frames 0..=6");
    }
}

/// A report inside the frames' folder, which the run creates, is written there; the folder
/// need not exist before.
#[test]
fn simulate_writes_its_report_into_the_folder_it_creates() {
    let ws = Workspace::new();
    let scene = ws.scene(
        "s.toml",
        "[mesh]\ngenerate = { kind = \"cloth\", vertices = [4, 4], size = [1.0, 1.0] }\n[solver]\nmode = \"dynamic\"\n",
    );
    let dir = ws.out("new-run");
    let report = dir.join("report.json");
    let out = simulate_in(None, &scene, &dir, &["--frames", "2", "--report", report.to_str().unwrap()]);
    assert_eq!(out.code, Some(0), "{}", out.describe());
    assert!(report.is_file() && dir.join("frame_0002.obj").is_file(), "{}", out.describe());
}

/// A static solve with contact whose energy overflows (a handle moved 1e200 away) is refused
/// as the solve without contact is, writing nothing (it used to exit 0 with null energies).
#[test]
fn a_static_solve_with_contact_refuses_an_overflowing_energy() {
    let ws = Workspace::new();
    let scene = ws.scene(
        "far.toml",
        "[mesh]\ngenerate = { kind = \"cloth\", vertices = [4, 4], size = [1.0, 1.0] }\n\
         [[constraints]]\ntype = \"edge_spring\"\n[[constraints]]\ntype = \"position\"\nvertices = [0, 1]\n\
         translate = [1e200, 0.0, 0.0]\n[[colliders]]\ntype = \"sphere\"\ncenter = [0.0, -2.0, 0.0]\nradius = 0.5\n",
    );
    let out = shapeup(ws.deform_args(&scene));
    assert_eq!(out.code, Some(1), "{}", out.describe());
    assert!(out.stderr.contains("the energy is not a finite number"), "{}", out.describe());
    assert!(!ws.out("result.obj").exists() && !ws.out("report.json").exists(), "{}", out.describe());
}

#[test]
fn simulate_rejects_bad_requests_and_writes_nothing() {
    let ws = Workspace::new();
    let good =
        "[mesh]\ngenerate = { kind = \"cloth\", vertices = [4, 4], size = [1.0, 1.0] }\n[solver]\nmode = \"dynamic\"\n";
    let scene = ws.scene("good.toml", good);
    let dir = ws.out("frames");
    // --frames 0 and --every 0.
    let out = simulate_in(None, &scene, &dir, &["--frames", "0"]);
    assert_eq!(out.code, Some(2), "{}", out.describe());
    let out = simulate_in(None, &scene, &dir, &["--frames", "3", "--every", "0"]);
    assert_eq!(out.code, Some(2), "a usage error, as --frames 0 is: {}", out.describe());
    assert!(out.stderr.contains("--every"), "{}", out.stderr);
    // A report that is not JSON.
    let out = simulate_in(None, &scene, &dir, &["--frames", "3", "--report", "r.txt"]);
    assert_eq!(out.code, Some(1), "{}", out.describe());
    // A report named .json that is a folder: refused before any step (it used to fail after
    // the last frame was written).
    std::fs::create_dir(ws.out("folder.json")).unwrap();
    let out = simulate_in(None, &scene, &dir, &["--frames", "3", "--report", ws.out("folder.json").to_str().unwrap()]);
    assert_eq!(out.code, Some(1), "{}", out.describe());
    assert!(out.stderr.contains("is a folder") && !dir.exists(), "{}", out.describe());
    // Bad dynamic settings name the key.
    for (bad, key) in [("damping = 1.5", "damping"), ("time_step = -1.0", "time_step"), ("density = 0.0", "density")] {
        let scene = ws.scene("bad.toml", &format!("{good}{bad}\n"));
        let out = simulate_in(None, &scene, &dir, &["--frames", "3"]);
        assert_eq!(out.code, Some(1), "{}", out.describe());
        assert!(out.stderr.contains(key) && out.stderr.lines().count() == 1, "{}", out.stderr);
    }
    // A generated mesh with a bad count, and both a path and a generator.
    for (mesh, needle) in [
        ("generate = { kind = \"cloth\", vertices = [1, 4], size = [1.0, 1.0] }", "at least 2"),
        ("generate = { kind = \"tet_box\", cells = [2, 2, 2], size = [1.0, -1.0, 1.0] }", "size"),
        ("generate = { kind = \"sphere\" }", "sphere"),
        ("path = 'x.obj'\ngenerate = { kind = \"cloth\", vertices = [4, 4], size = [1.0, 1.0] }", "not both"),
    ] {
        let scene = ws.scene("gen.toml", &format!("[mesh]\n{mesh}\n[solver]\nmode = \"dynamic\"\n"));
        let out = simulate_in(None, &scene, &dir, &["--frames", "3"]);
        assert_eq!(out.code, Some(1), "{}", out.describe());
        assert!(out.stderr.contains(needle), "{mesh}: {}", out.stderr);
    }
    assert!(!dir.exists(), "no output directory after errors");
    // An output "directory" that is a file, or under one.
    let file = write(&ws.path("taken"), "x");
    let out = simulate_in(None, &scene, &file, &["--frames", "3"]);
    assert_eq!(out.code, Some(1), "{}", out.describe());
    assert!(
        out.stderr.contains("taken is a file, not a folder") && !out.stderr.contains("File exists"),
        "{}",
        out.stderr
    );
    let out = simulate_in(None, &scene, &file.join("sub"), &["--frames", "3"]);
    assert_eq!(out.code, Some(1), "{}", out.describe());
    assert!(out.stderr.contains("taken is a file, not a folder"), "{}", out.stderr);
}

#[test]
fn bad_colliders_name_the_entry_and_write_nothing() {
    let ws = Workspace::new();
    let good = "[mesh]\ngenerate = { kind = \"cloth\", vertices = [4, 4], size = [1.0, 1.0] }\n[solver]\nmode = \"dynamic\"\n\
                [[constraints]]\ntype = \"edge_spring\"\n";
    let dir = ws.out("frames");
    for (bad, needle) in [
        ("[[colliders]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = -1.0\n", "colliders[0]: `radius`"),
        ("[[colliders]]\ntype = \"cone\"\n", "colliders[0]: unknown collider type"),
        ("[[colliders]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 0]\n", "`normal` must be non-zero"),
        ("[[colliders]]\ntype = \"capsule\"\na = [0, 0, 0]\nb = [0, 0, 0]\nradius = 1.0\n", "axis is zero"),
        // Not zero, but too short for a direction.
        (
            "[[colliders]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [1e-300, 0, 0]\n",
            "`normal` is too small to give a direction: its length is 1e-300, under 1e-150",
        ),
        (
            "[[colliders]]\ntype = \"capsule\"\na = [0, 0, 0]\nb = [1e-300, 0, 0]\nradius = 1.0\n",
            "the capsule's axis is too short to give a direction: `a` and `b` are 1e-300 apart, under 1e-150",
        ),
        ("[[colliders]]\ntype = \"box\"\nmin = [0, 1, 0]\nmax = [1, 0, 1]\n", "`min` > `max`"),
        ("[[colliders]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1.0\nfriction = -1.0\n", "`friction`"),
        ("[[colliders]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1.0\nradus = 2\n", "unknown key `radus`"),
        ("[[colliders]]\ntype = \"mesh\"\npath = \"missing.obj\"\n", "missing.obj"),
        ("[contact]\nthickness = -0.1\n", "[contact]: thickness"),
        ("[contact]\nfriction = -0.1\n", "[contact]: friction"),
        // Edges of 1/3 and 0.47: at 0.5 every vertex would touch its neighbours' triangles.
        (
            "[contact]\nself_collision = true\nthickness = 0.5\n",
            "[contact]: thickness 0.5 is over the mean edge length",
        ),
        // A 1 m cloth (diagonal 1.41): at most 0.35.
        (
            "[contact]\nthickness = 5.0\n[[colliders]]\ntype = \"plane\"\npoint = [0, -1, 0]\nnormal = [0, 1, 0]\n",
            "[contact]: thickness 5 is over 0.25 of the mesh's size (its bounding-box diagonal 1.414",
        ),
        ("[[contact]]\nthickness = 0.1\n", "one [contact] table (not a list: [[contact]]"),
        ("[[colliders]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1e300\n", "found 1e300"),
    ] {
        let scene = ws.scene("bad.toml", &format!("{good}{bad}"));
        let out = simulate_in(None, &scene, &dir, &["--frames", "3"]);
        assert_eq!(out.code, Some(1), "{bad}: {}", out.describe());
        assert!(out.stderr.contains(needle) && out.stderr.contains("bad.toml"), "{bad}: {}", out.stderr);
        assert_eq!(out.stderr.lines().count(), 1, "{bad}: {}", out.stderr);
    }
    // A mesh with no faces, and an open mesh used as closed.
    write(&ws.path("points.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    write(&ws.path("open.obj"), "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 3 2\n");
    write(&ws.path("huge.obj"), "v 0 0 0\nv 1e100 0 0\nv 0 0 1\nf 1 3 2\n");
    write(&ws.path("segment.obj"), "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    // A tetrahedron with its faces inward, and a square with both sides as faces.
    write(&ws.path("inward.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 4 2\nf 1 3 4\nf 2 4 3\n");
    write(&ws.path("sheet.obj"), "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 2 3\nf 3 4 1\nf 2 1 4\nf 4 3 2\n");
    for (bad, needle) in [
        ("[[colliders]]\ntype = \"mesh\"\npath = \"inward.obj\"\n", "faces point inward"),
        ("[[colliders]]\ntype = \"mesh\"\npath = \"sheet.obj\"\n", "encloses no volume"),
        ("[[colliders]]\ntype = \"mesh\"\npath = \"huge.obj\"\n", "vertex 1 (from 0) is at (1e100, 0, 0)"),
        ("[[colliders]]\ntype = \"mesh\"\npath = \"segment.obj\"\n", "all 1 of its triangles have zero area"),
        ("[[colliders]]\ntype = \"mesh\"\npath = \"points.obj\"\n", "no faces"),
        ("[[colliders]]\ntype = \"mesh\"\npath = \"open.obj\"\nclosed = true\n", "is open"),
    ] {
        let scene = ws.scene("bad.toml", &format!("{good}{bad}"));
        let out = simulate_in(None, &scene, &dir, &["--frames", "3"]);
        assert_eq!(out.code, Some(1), "{bad}: {}", out.describe());
        assert!(out.stderr.contains(needle) && out.stderr.contains("colliders[0]"), "{bad}: {}", out.stderr);
    }
    // JSON lists with something other than a table in them: named by list and index.
    for (list, needle) in [
        ("colliders", "colliders[0]: must be a table, found null"),
        ("constraints", "constraints[1]: must be a table, found a number"),
    ] {
        let entries = if list == "colliders" { r#"[null]"# } else { r#"[{"type": "edge_spring"}, 3]"# };
        let text = format!(
            r#"{{"mesh": {{"generate": {{"kind": "cloth", "vertices": [4, 4], "size": [1.0, 1.0]}}}}, "solver": {{"mode": "dynamic"}}, "{list}": {entries}}}"#
        );
        let scene = ws.scene("bad.json", &text);
        let out = simulate_in(None, &scene, &dir, &["--frames", "3"]);
        assert_eq!(out.code, Some(1), "{list}: {}", out.describe());
        assert!(out.stderr.contains(needle) && out.stderr.contains("bad.json"), "{list}: {}", out.stderr);
    }
    // A whole key of the wrong type, or a number out of range, named by its key.
    for (entry, needle) in [
        (r#""colliders": null"#, "line 1, column 99: `colliders` must be a list of [[colliders]] tables, found null"),
        (r#""constraints": 5"#, "`constraints` must be a list of [[constraints]] tables, found a number"),
        (r#""contact": null"#, "`contact` must be one [contact] table, found null"),
        (r#""contact": {"thickness": 1e400}"#, "number out of range (in `contact.thickness`)"),
        (r#""colliders": [{"type": "sphere", "center": [0, 0, 1e400]}]"#, "(in `colliders[0].center[2]`)"),
    ] {
        let text = format!(
            r#"{{"mesh": {{"generate": {{"kind": "cloth", "vertices": [4, 4], "size": [1.0, 1.0]}}}}, {entry}}}"#
        );
        let scene = ws.scene("bad.json", &text);
        let out = simulate_in(None, &scene, &dir, &["--frames", "3"]);
        assert_eq!(out.code, Some(1), "{entry}: {}", out.describe());
        assert!(out.stderr.contains(needle) && out.stderr.contains("bad.json"), "{entry}: {}", out.stderr);
        assert_eq!(out.stderr.lines().count(), 1, "{entry}: {}", out.stderr);
    }
    // The same in TOML: the key's line is quoted.
    let out = simulate_in(None, &ws.scene("bad.toml", &format!("colliders = 5\n{good}")), &dir, &["--frames", "3"]);
    assert!(
        out.code == Some(1)
            && out.stderr.contains("`colliders` must be a list of [[colliders]] tables, found a number"),
        "{}",
        out.describe()
    );
    assert!(!dir.exists(), "no output directory after errors");
}

/// What a collider scene gives that is used other than as written is warned of, once: the
/// motion a static solve ignores (colliders' velocity and spin, handles' spin), and a mesh
/// collider's zero-area triangles.
#[test]
fn a_static_solve_warns_of_collider_motion_and_zero_area_collider_triangles() {
    let ws = Workspace::new();
    // The second triangle's corners are on one line.
    write(&ws.path("flat.obj"), "v 0 0 0\nv 1 0 0\nv 0 0 1\nv 2 0 0\nf 1 3 2\nf 1 2 4\n");
    let sphere = "[[colliders]]\ntype = \"sphere\"\ncenter = [0.0, -3.0, 0.0]\nradius = 0.1\n";
    let scene = ws.scene(
        "moving.toml",
        &format!(
            "[mesh]\ngenerate = {{ kind = \"cloth\", vertices = [4, 4], size = [1.0, 1.0] }}\n\
             [[constraints]]\ntype = \"edge_spring\"\n[[constraints]]\ntype = \"position\"\nvertices = [0]\n\
             [[constraints]]\ntype = \"position\"\nvertices = [15]\nspin = {{ axis = [0.0, 1.0, 0.0], deg_per_s = 30.0 }}\n\
             [[colliders]]\ntype = \"mesh\"\npath = \"flat.obj\"\ntranslate = [0.0, -2.0, 0.0]\n\
             {sphere}velocity = [0.0, 1.0, 0.0]\n{sphere}spin = {{ axis = [0.0, 1.0, 0.0], deg_per_s = 5.0 }}\n\
             {sphere}spin = {{ axis = [0.0, 1.0, 0.0], deg_per_s = 0.0 }}\n"
        ),
    );
    let out = shapeup(ws.deform_args(&scene));
    assert_eq!(out.code, Some(0), "{}", out.describe());
    let motion = "moving.toml: 2 collider(s) whose motion (velocity, spin) is ignored in static mode";
    let flat = "flat.obj: 1 zero-area (degenerate) triangles in a mesh collider";
    assert_eq!(out.stderr.matches(motion).count(), 1, "{}", out.describe());
    let spin = "moving.toml: 1 group(s) whose spin is ignored in static mode";
    assert_eq!(out.stderr.matches(spin).count(), 1, "{}", out.describe());
    assert!(out.stderr.contains("(first: constraints[2] (\"position_2\"))"), "{}", out.describe());
    assert_eq!(out.stderr.matches(flat).count(), 1, "{}", out.describe());
    assert!(out.stderr.contains("(first: colliders[0], triangle 1 (from 0))"), "{}", out.describe());
    let kinds: Vec<String> = report(&ws.out("report.json"))["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["kind"].as_str().unwrap().to_owned())
        .collect();
    assert!(kinds.contains(&"collider_motion_ignored".into()), "{kinds:?}");
    assert!(kinds.contains(&"handle_spin_ignored".into()), "{kinds:?}");
    assert!(kinds.contains(&"degenerate_collider_triangles".into()), "{kinds:?}");
    // Time steps move the colliders: no motion warning there.
    let out = simulate_in(None, &scene, &ws.out("frames"), &["--frames", "2"]);
    assert_eq!(out.code, Some(0), "{}", out.describe());
    assert!(!out.stderr.contains("ignored in static mode") && out.stderr.contains(flat), "{}", out.describe());
}

/// A static solve with contact factors its matrix once, as a simulation does (the contact
/// weights are made from the matrix's diagonal before its first factorization), and its report
/// says what touches the result.
#[test]
fn a_static_press_reports_one_factorization_and_what_touches_the_result() {
    let ws = Workspace::new();
    let (center, radius, thickness) = (DVec3::new(0.0, -0.25, 0.0), 0.3, 0.01);
    let cloth = "[mesh]\ngenerate = { kind = \"cloth\", vertices = [11, 11], size = [1.0, 1.0] }\nnormalize = false\n\
                 [[constraints]]\ntype = \"triangle_strain\"\n[[constraints]]\ntype = \"position\"\nvertices = [0, 10, 110, 120]\n";
    let sphere = format!(
        "[contact]\nthickness = {thickness}\n[[colliders]]\ntype = \"sphere\"\ncenter = [0.0, {}, 0.0]\nradius = {radius}\n",
        center.y
    );
    let scene = ws.scene("press.toml", &format!("{cloth}{sphere}"));
    let out = shapeup(ws.deform_args(&scene));
    assert_eq!(out.code, Some(0), "{}", out.describe());
    let r = report(&ws.out("report.json"));
    assert_eq!(r["factorizations"], 1, "{r}");
    let result = shapeup_core::io::read_mesh(&ws.out("result.obj")).unwrap().mesh;
    // Distances from the sphere's surface, independent of the contact model: of each vertex, and
    // of each triangle sampled on a barycentric grid (a triangle that touches marks its corners).
    let gap = |p: DVec3| (p - center).length() - radius;
    assert!(result.positions.iter().all(|&p| gap(p) > 0.0), "a vertex inside the sphere");
    let mut near: std::collections::HashSet<u32> =
        (0..result.positions.len() as u32).filter(|&v| gap(result.positions[v as usize]) <= 1.5 * thickness).collect();
    const N: usize = 20;
    for t in &result.triangles {
        let [a, b, c] = t.map(|v| result.positions[v as usize]);
        let closest = (0..=N)
            .flat_map(|i| (0..=N - i).map(move |j| (i as f64 / N as f64, j as f64 / N as f64)))
            .map(|(u, w)| gap(a + u * (b - a) + w * (c - a)))
            .fold(f64::INFINITY, f64::min);
        // The grid's spacing (edges of 0.1, 1/20 of them) bounds how far it can miss the closest point.
        if closest <= 1.5 * thickness + 0.1 / N as f64 {
            near.extend(t);
        }
    }
    let touching = r["contact_vertices"].as_u64().unwrap() as usize;
    assert!(touching > 0 && touching <= near.len(), "{touching} touching, {} near the sphere", near.len());
    assert!(r["contacts"].as_u64().unwrap() as usize >= touching, "{r}");
    assert_eq!((r["self_contacts"].as_u64(), r["ended_inside"].as_u64()), (Some(0), Some(0)), "{r}");
    // Without the collider: nothing touches, one factorization still.
    let free = ws.scene("free.toml", cloth);
    let out = shapeup(ws.deform_args(&free));
    assert_eq!(out.code, Some(0), "{}", out.describe());
    let r = report(&ws.out("report.json"));
    assert_eq!((r["factorizations"].as_u64(), r["contacts"].as_u64()), (Some(1), Some(0)), "{r}");
}

/// A pin held inside a collider is said once, with a count and the first vertex and group:
/// contact cannot move it out.
#[test]
fn pins_held_inside_a_collider_are_warned_about_once() {
    let ws = Workspace::new();
    let scene = |name: &str, y: f64| {
        ws.scene(
            name,
            &format!(
                "[mesh]\ngenerate = {{ kind = \"cloth\", vertices = [11, 11], size = [1.0, 1.0] }}\nnormalize = false\n\
                 [[constraints]]\ntype = \"triangle_strain\"\n\
                 [[constraints]]\nname = \"corners\"\ntype = \"position\"\nvertices = [0, 10, 60]\nhard = true\n\
                 [[constraints]]\nname = \"again\"\ntype = \"position\"\nvertices = [60]\n\
                 [[constraints]]\nname = \"off\"\ntype = \"position\"\nvertices = [61]\nweight = 0.0\n\
                 [[colliders]]\ntype = \"sphere\"\ncenter = [0.0, {y}, 0.0]\nradius = 0.2\n"
            ),
        )
    };
    // The sphere holds the middle vertex (60, at the origin) inside it: one pin of three, counted
    // once though a second group holds it too; a group of weight 0 (on vertex 61, also inside)
    // pulls nothing. The pin holds it there, and the report counts it inside.
    let inside = scene("inside.toml", 0.05);
    let out = shapeup(ws.deform_args(&inside));
    assert_eq!(out.code, Some(0), "{}", out.describe());
    let line = "inside.toml: 1 pinned vertices are held at a point inside a collider";
    assert_eq!(out.stderr.matches(line).count(), 1, "{}", out.describe());
    assert!(out.stderr.contains("(first: vertex 60, group \"corners\")"), "{}", out.describe());
    let r = report(&ws.out("report.json"));
    assert!(r["warnings"].to_string().contains("pin_inside_collider"), "{r}");
    assert_eq!(r["ended_inside"], 1, "{r}");
    let result = shapeup_core::io::read_mesh(&ws.out("result.obj")).unwrap().mesh.positions;
    assert_eq!(result[60], DVec3::ZERO, "the hard pin holds vertex 60 where it is, inside the sphere");
    // Below the cloth, clear of every pin: no such warning.
    let clear = scene("clear.toml", -0.5);
    let out = shapeup(ws.deform_args(&clear));
    assert_eq!(out.code, Some(0), "{}", out.describe());
    assert!(!out.stderr.contains("pinned vertices are held"), "{}", out.describe());
}

#[test]
fn a_drape_reports_one_factorization_and_contacts_per_step() {
    let ws = Workspace::new();
    let scene = ws.scene(
        "drape.toml",
        "[mesh]\ngenerate = { kind = \"cloth\", vertices = [11, 11], size = [1.0, 1.0] }\nnormalize = false\n\
         [solver]\nmode = \"dynamic\"\n[[constraints]]\ntype = \"triangle_strain\"\n\
         [[colliders]]\ntype = \"sphere\"\ncenter = [0.0, -0.35, 0.0]\nradius = 0.3\n",
    );
    let dir = ws.out("frames");
    let r = ws.out("r.json");
    let out = simulate_in(
        None,
        &scene,
        &dir,
        &["--frames", "60", "--every", "60", "--format", "vtu", "--report", r.to_str().unwrap()],
    );
    assert_eq!(out.code, Some(0), "{}", out.describe());
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&r).unwrap()).unwrap();
    assert_eq!(report["factorizations"], 1, "{report}");
    assert_eq!(report["acceleration"], "none", "contact iterates plainly: {report}");
    let contacts = report["contacts"].as_array().unwrap();
    assert_eq!(contacts.len(), 60);
    assert!(contacts.last().unwrap().as_u64().unwrap() > 0, "{contacts:?}");
    assert_eq!(report["ended_inside"], 0, "{report}");
    assert!(!out.stderr.contains("vertex-steps ended inside"), "{}", out.describe());
    let last = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.to_string_lossy().ends_with("60.vtu"))
        .expect("the last frame");
    let vtu = std::fs::read_to_string(last).unwrap();
    assert!(vtu.contains("Name=\"contact\""), "the frame carries the contact flag");
}

#[test]
fn a_cloth_squeezed_between_colliders_is_warned_about_once_naming_the_scene() {
    // A sphere comes down through a cloth lying on a plane, and on through the plane. The
    // drape above says nothing of the kind (its report's ended_inside is 0).
    let ws = Workspace::new();
    let scene = ws.scene(
        "squeeze.toml",
        "[mesh]\ngenerate = { kind = \"cloth\", vertices = [11, 11], size = [1.0, 1.0] }\nnormalize = false\n\
         [solver]\nmode = \"dynamic\"\n[[constraints]]\ntype = \"triangle_strain\"\n\
         [[colliders]]\ntype = \"plane\"\npoint = [0.0, -0.02, 0.0]\nnormal = [0.0, 1.0, 0.0]\n\
         [[colliders]]\ntype = \"sphere\"\ncenter = [0.0, 0.25, 0.0]\nradius = 0.2\nvelocity = [0.0, -1.0, 0.0]\n",
    );
    let r = ws.out("r.json");
    let out = simulate_in(None, &scene, &ws.out("frames"), &["--frames", "30", "--report", r.to_str().unwrap()]);
    assert_eq!(out.code, Some(0), "{}", out.describe());
    let report = report(&r);
    let inside = report["ended_inside"].as_u64().unwrap();
    assert!(inside > 0, "{report}");
    let line = format!("squeeze.toml: {inside} vertex-steps ended inside a collider");
    assert_eq!(out.stderr.matches(&line).count(), 1, "{}", out.describe());
    assert_eq!(out.stderr.matches("vertex-steps ended inside").count(), 1, "{}", out.describe());
}

#[test]
fn the_command_line_and_the_library_give_the_same_trajectory_with_contact() {
    let ws = Workspace::new();
    let text = "[mesh]\ngenerate = { kind = \"cloth\", vertices = [9, 9], size = [1.0, 1.0] }\nnormalize = false\n\
                [solver]\nmode = \"dynamic\"\n[[constraints]]\ntype = \"triangle_strain\"\n\
                [contact]\nself_collision = true\n\
                [[colliders]]\ntype = \"capsule\"\na = [0.0, -0.2, -1.0]\nb = [0.0, -0.2, 1.0]\nradius = 0.1\nfriction = 0.4\n";
    let scene = ws.scene("same.toml", text);
    let dir = ws.out("frames");
    let out = simulate_in(None, &scene, &dir, &["--frames", "40", "--every", "40"]);
    assert_eq!(out.code, Some(0), "{}", out.describe());
    let last = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.to_string_lossy().ends_with("40.obj"))
        .expect("the last frame");
    let cli = shapeup_core::io::read_mesh(&last).unwrap().mesh.positions;
    let mut loaded = shapeup_core::scene::Scene::from_file(&scene).unwrap().load().unwrap();
    let mut simulation = loaded.start_scene_simulation().unwrap();
    for _ in 0..40 {
        simulation.step().unwrap();
    }
    let library = loaded.to_input(simulation.simulation.positions());
    assert_eq!(cli.len(), library.len());
    let worst = cli.iter().zip(&library).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
    // OBJ keeps the shortest round-trip form of each coordinate: the same numbers.
    assert!(worst < 1e-12, "the frames differ by {worst}");
}

#[test]
fn simulate_every_k_writes_multiples_of_k_and_the_last_frame() {
    let ws = Workspace::new();
    let scene = ws.scene(
        "s.toml",
        "[mesh]\ngenerate = { kind = \"cloth\", vertices = [5, 5], size = [1.0, 1.0] }\n[solver]\nmode = \"dynamic\"\n\
         [[constraints]]\ntype = \"edge_spring\"\n[[constraints]]\ntype = \"position\"\nvertices = [0, 4]\nweight = 100.0\n",
    );
    let dir = ws.out("frames");
    let r = ws.out("r.json");
    let out = simulate_in(
        None,
        &scene,
        &dir,
        &[
            OsStr::new("--frames"),
            OsStr::new("11"),
            OsStr::new("--every"),
            OsStr::new("4"),
            OsStr::new("--report"),
            r.as_os_str(),
        ],
    );
    assert_eq!(out.code, Some(0), "{}", out.describe());
    let mut names: Vec<String> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    assert_eq!(names, ["frame_0000.obj", "frame_0004.obj", "frame_0008.obj", "frame_0011.obj"]);
    let report = report(&r);
    assert_eq!(report["frames_written"], 4);
    assert_eq!(report["energy"].as_array().map(Vec::len), Some(11));
    assert!(report["timings"]["total_s"].as_f64().is_some_and(|t| t > 0.0));
}

/// A handle with `spin` turns its targets at the given rate: after 1 s at 90°/s the end of a
/// bar (fixed at the other end) has turned a quarter turn about the bar's axis.
#[test]
fn simulate_spinning_handle_turns_the_end_of_a_bar() {
    let ws = Workspace::new();
    let scene = ws.scene(
        "spin.toml",
        "[mesh]\ngenerate = { kind = \"tet_box\", cells = [6, 2, 2], size = [1.5, 0.5, 0.5] }\nnormalize = false\n\
         [solver]\nmode = \"dynamic\"\ngravity = [0.0, 0.0, 0.0]\ndamping = 0.05\n\
         [[constraints]]\ntype = \"tet_strain\"\n\
         [[constraints]]\ntype = \"position\"\nbox = { min = [-0.8, -1, -1], max = [-0.7, 1, 1] }\nweight = 100.0\n\
         [[constraints]]\ntype = \"position\"\nbox = { min = [0.7, -1, -1], max = [0.8, 1, 1] }\nweight = 100.0\n\
         spin = { axis = [1.0, 0.0, 0.0], deg_per_s = 90.0, center = [0.75, 0.0, 0.0] }\n",
    );
    let dir = ws.out("spin");
    let out = simulate_in(None, &scene, &dir, &["--frames", "60", "--every", "60"]);
    assert_eq!(out.code, Some(0), "{}", out.describe());
    let rest = read(&dir.join("frame_0000.obj"));
    let turned = read(&dir.join("frame_0060.obj"));
    let mut checked = 0;
    for (r, p) in rest.positions.iter().zip(&turned.positions) {
        if (r.x - 0.75).abs() < 1e-9 {
            // A quarter turn about +x: (y, z) -> (-z, y).
            let expected = DVec3::new(r.x, -r.z, r.y);
            assert!((*p - expected).length() < 0.05, "{r} went to {p}, expected {expected}");
            checked += 1;
        } else if (r.x + 0.75).abs() < 1e-9 {
            assert!((*p - *r).length() < 0.02, "the fixed end moved: {r} -> {p}");
        }
    }
    assert_eq!(checked, 9, "the 3 × 3 vertices of the turning end");
    // A bad spin is refused with the key named.
    let bad = ws.scene(
        "bad-spin.toml",
        "[mesh]\ngenerate = { kind = \"cloth\", vertices = [3, 3], size = [1.0, 1.0] }\n[solver]\nmode = \"dynamic\"\n\
         [[constraints]]\ntype = \"position\"\nvertices = [0]\nspin = { axis = [0.0, 0.0, 0.0], deg_per_s = 1.0 }\n",
    );
    let out = simulate_in(None, &bad, &dir, &["--frames", "2"]);
    assert_eq!(out.code, Some(1), "{}", out.describe());
    assert!(out.stderr.contains("spin"), "{}", out.stderr);
}

// ---------------------------------------------------------------------------------------------
// Nothing lost: vertex count and order, warnings
// ---------------------------------------------------------------------------------------------

/// A 6 × 6 grid of quads in the plane z = 0 (x, y in [0, 1]) as OBJ, with vertices no face uses
/// at the start, in the middle and at the end of the file; returns the text and the indices
/// (0-based) of the unused vertices.
fn grid_with_unused_vertices() -> (String, Vec<usize>) {
    let n = 7;
    let mut lines = vec!["v 9 9 9".to_owned()]; // unused, first
    let mut index = vec![0usize; n * n];
    let mut unused = vec![0];
    for j in 0..n {
        for i in 0..n {
            if j == n / 2 && i == 0 {
                unused.push(lines.len());
                lines.push("v -5 -5 -5".to_owned()); // unused, in the middle
            }
            index[j * n + i] = lines.len();
            lines.push(format!("v {} {} 0", i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64));
        }
    }
    unused.push(lines.len());
    lines.push("v 7 7 7".to_owned()); // unused, last
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let c = [index[j * n + i], index[j * n + i + 1], index[(j + 1) * n + i + 1], index[(j + 1) * n + i]];
            lines.push(format!("f {} {} {} {}", c[0] + 1, c[1] + 1, c[2] + 1, c[3] + 1));
        }
    }
    (lines.join("\n") + "\n", unused)
}

const GRID_BODY: &str = r#"
[[constraints]]
type = "edge_spring"

[[constraints]]
type = "position"
name = "left"
box = { min = [-0.01, -0.01, -0.01], max = [0.01, 1.01, 0.01] }

[[constraints]]
type = "position"
name = "right"
box = { min = [0.99, -0.01, -0.01], max = [1.01, 1.01, 0.01] }
translate = [0.3, 0.0, 0.5]
"#;

#[test]
fn deform_keeps_unused_vertices_at_the_start_middle_and_end_in_every_format() {
    let ws = Workspace::new();
    let (text, unused) = grid_with_unused_vertices();
    let mesh_path = write(&ws.path("grid.obj"), &text);
    let rest = read(&mesh_path);
    let scene = ws.scene("grid.toml", &toml_scene(&mesh_path, "", GRID_BODY));
    for name in ["grid.obj", "grid.ply", "grid.off"] {
        let (out, report, _) = deform_ok(&ws, &scene, name, &[]);
        assert_eq!(out.num_vertices(), rest.num_vertices(), "{name}");
        assert_eq!(out.polygons, rest.polygons, "{name}: quads stay quads");
        for &v in &unused {
            assert_eq!(out.positions[v], rest.positions[v], "{name}: unused vertex {v} moved");
        }
        let moved = out.positions.iter().zip(&rest.positions).filter(|(a, b)| (**a - **b).length() > 0.1).count();
        assert!(moved > 5, "{name}: the right side moved");
        assert!(report["warnings"].is_array(), "{name}: the report lists warnings");
    }
}

#[test]
fn deform_says_each_change_once_with_a_count() {
    let ws = Workspace::new();
    let (text, _) = grid_with_unused_vertices();
    let mesh_path = write(&ws.path("grid.obj"), &text);
    let scene = ws.scene("grid.toml", &toml_scene(&mesh_path, "", GRID_BODY));
    let (_, report, out) = deform_ok(&ws, &scene, "grid.stl", &[]);
    let warnings: Vec<&str> = out.stderr.lines().filter(|l| l.contains("warning")).collect();
    let triangulated: Vec<&&str> = warnings.iter().filter(|l| l.contains("triangulated")).collect();
    assert_eq!(triangulated.len(), 1, "once: {warnings:?}");
    assert!(triangulated[0].contains("36 polygons") && triangulated[0].contains("grid.obj"), "{warnings:?}");
    let stl: Vec<&&str> = warnings.iter().filter(|l| l.contains("grid.stl") && l.contains("STL")).collect();
    assert!(stl.iter().any(|l| l.contains("vertices")), "{warnings:?}");
    let kinds: Vec<&str> = report["warnings"].as_array().unwrap().iter().filter_map(|w| w["kind"].as_str()).collect();
    assert!(kinds.contains(&"polygons_triangulated") && kinds.contains(&"vertices_not_kept"), "{kinds:?}");
    let count =
        report["warnings"].as_array().unwrap().iter().find(|w| w["kind"] == "polygons_triangulated").unwrap()["count"]
            .as_u64();
    assert_eq!(count, Some(36));
}

#[test]
fn bad_texture_and_normal_indices_name_the_file_and_line() {
    let ws = Workspace::new();
    for (name, text, needles) in [
        ("vt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n", vec!["vt.obj", "line 5"]),
        ("vn.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//-2 3//1\n", vec!["vn.obj", "line 5"]),
        ("mixed.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2 3/1\n", vec!["mixed.obj", "line 5"]),
    ] {
        let mesh = write(&ws.path(name), text);
        let scene = ws.scene(&format!("{name}.toml"), &toml_scene(&mesh, "", SHAPE_AND_HANDLE));
        ws.deform_fails(&scene, &needles);
    }
}

#[test]
fn ply_encoding_can_be_chosen() {
    let ws = Workspace::new();
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", &handle_body(1.0)));
    let (binary, _, _) = deform_ok(&ws, &scene, "spot.ply", &[]);
    let (ascii, _, _) = deform_ok(&ws, &scene, "ascii.ply", &["--ply-encoding", "ascii"]);
    let head = std::fs::read(ws.out("ascii.ply")).unwrap();
    assert!(head.starts_with(b"ply\nformat ascii 1.0\n"), "{:?}", String::from_utf8_lossy(&head[..40]));
    assert_eq!(ascii.positions, binary.positions, "the same numbers in either encoding");
    // A usage error (clap's own message, and a hint to --help): nothing is written.
    let o = ws.out("x.ply");
    let out = shapeup([
        OsStr::new("deform"),
        scene.as_os_str(),
        "-o".as_ref(),
        o.as_os_str(),
        "--ply-encoding".as_ref(),
        "utf8".as_ref(),
    ]);
    assert_eq!(out.code, Some(2), "{}", out.describe());
    assert!(out.stderr.contains("unknown PLY encoding \"utf8\"") && !o.exists(), "{}", out.describe());
}

#[test]
fn a_tetrahedralized_surface_comes_back_as_the_input_surface() {
    let ws = Workspace::new();
    let rest = spot();
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "tetrahedralize = true", &handle_body(1.0)));
    let (obj, _, out) = deform_ok(&ws, &scene, "spot.obj", &[]);
    assert_eq!(obj.num_vertices(), rest.num_vertices(), "TetGen's points are not written\n{}", out.describe());
    assert_eq!(obj.polygons, rest.polygons);
    let (msh, _, _) = deform_ok(&ws, &scene, "spot.msh", &[]);
    assert!(msh.num_tetrahedra() > 0 && msh.num_vertices() > rest.num_vertices(), "a volume output keeps them");
}

#[test]
fn an_output_or_report_that_is_an_input_is_refused_and_the_input_kept() {
    // The scene file, its mesh: however named (a `./` path, a link), a result or a report
    // written there would replace what the run reads.
    let ws = Workspace::new();
    let mesh = ws.path("in.obj");
    std::fs::copy(SPOT, &mesh).unwrap();
    let json = ws.path("scene.json");
    let text = r#"{"mesh": {"path": "in.obj"}, "constraints": [{"type": "edge_spring"}, {"type": "position", "vertices": [0]}]}"#;
    write(&json, text);
    let kept = std::fs::read(&mesh).unwrap();
    let o = ws.out("result.obj");
    ws.expect_failure(
        &[OsStr::new("deform"), json.as_os_str(), "-o".as_ref(), o.as_os_str(), "--report".as_ref(), json.as_os_str()],
        &["scene.json", "is the scene file", "never replaces its inputs"],
    );
    let relative = ws.path(".").join("in.obj");
    ws.expect_failure(
        &[OsStr::new("deform"), json.as_os_str(), "-o".as_ref(), relative.as_os_str()],
        &["is the scene's mesh"],
    );
    #[cfg(unix)]
    {
        let link = ws.path("link.obj");
        std::os::unix::fs::symlink(&mesh, &link).unwrap();
        ws.expect_failure(
            &[OsStr::new("deform"), json.as_os_str(), "-o".as_ref(), link.as_os_str()],
            &["is the scene's mesh"],
        );
    }
    let dir = ws.out("frames");
    ws.expect_failure(
        &[
            OsStr::new("simulate"),
            json.as_os_str(),
            "--frames".as_ref(),
            "1".as_ref(),
            "-o".as_ref(),
            dir.as_os_str(),
            "--report".as_ref(),
            json.as_os_str(),
        ],
        &["is the scene file"],
    );
    assert_eq!(std::fs::read_to_string(&json).unwrap(), text, "the scene was changed");
    assert_eq!(std::fs::read(&mesh).unwrap(), kept, "the mesh was changed");
    // A mesh that is a frame of an earlier run, simulated into that folder again: the first
    // frame would replace it. A frame number the run does not write is no conflict.
    let earlier = ws.path("earlier");
    std::fs::create_dir_all(&earlier).unwrap();
    std::fs::copy(SPOT, earlier.join("frame_0002.obj")).unwrap();
    let again = ws.path("again.json");
    write(&again, &text.replace("in.obj", "earlier/frame_0002.obj"));
    let frame = std::fs::read(earlier.join("frame_0002.obj")).unwrap();
    let simulate = |frames: &str, every: &str| {
        vec![
            OsStr::new("simulate").to_owned(),
            again.clone().into_os_string(),
            "--frames".into(),
            frames.into(),
            "--every".into(),
            every.into(),
            "-o".into(),
            earlier.clone().into_os_string(),
        ]
    };
    ws.expect_failure(&simulate("2", "1"), &["frame_0002.obj", "is the scene's mesh", "never replaces its inputs"]);
    assert_eq!(std::fs::read(earlier.join("frame_0002.obj")).unwrap(), frame, "the earlier frame was changed");
    assert!(!earlier.join("frame_0000.obj").exists(), "nothing written");
    // A run that would not write frame 2 would still remove it, as an earlier run's frame.
    ws.expect_failure(&simulate("3", "3"), &["frame_0002.obj", "is the scene's mesh"]);
    assert_eq!(std::fs::read(earlier.join("frame_0002.obj")).unwrap(), frame, "the earlier frame was changed");
}

/// A run into a folder that holds an earlier run's frames replaces that series: the frames it
/// does not write (a longer run's, another format's, a `frames.pvd`) are removed and said once
/// with their count and the first; other files in the folder stay.
#[test]
fn a_run_into_a_folder_of_an_earlier_runs_frames_replaces_that_series() {
    let ws = Workspace::new();
    let scene = ws.scene(
        "drop.toml",
        "[mesh]\ngenerate = { kind = \"cloth\", vertices = [4, 4], size = [1.0, 1.0] }\n\
         [solver]\nmode = \"dynamic\"\n[[constraints]]\ntype = \"edge_spring\"\n",
    );
    let dir = ws.out("frames");
    let first = simulate_in(None, &scene, &dir, &["--frames", "5", "--format", "vtu"]);
    assert_eq!(first.code, Some(0), "{}", first.describe());
    assert!(!first.stderr.contains("removed"), "{}", first.describe());
    // The user's own files stay, also those named almost like frames, and folders.
    write(&dir.join("notes.txt"), "mine");
    write(&dir.join("frame_notes.obj"), "mine");
    std::fs::create_dir(dir.join("frame_0099.obj")).unwrap();
    let out = simulate_in(None, &scene, &dir, &["--frames", "2"]);
    assert_eq!(out.code, Some(0), "{}", out.describe());
    let line = "7 frame files of an earlier run that this one did not write";
    assert_eq!(out.stderr.matches(line).count(), 1, "{}", out.describe());
    assert!(out.stderr.contains("(first: frame_0000.vtu)"), "{}", out.describe());
    let names = || {
        let mut names: Vec<String> =
            std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        names.sort();
        names
    };
    let kept = ["frame_0000.obj", "frame_0001.obj", "frame_0002.obj", "frame_0099.obj", "frame_notes.obj", "notes.txt"];
    assert_eq!(names(), kept);
    assert_eq!(ws.out_entries(), ["frames"], "no staging folder is left beside it");
    // A folder where a frame goes fails the run before anything moves.
    std::fs::remove_file(dir.join("frame_0001.obj")).unwrap();
    std::fs::create_dir(dir.join("frame_0001.obj")).unwrap();
    let before = std::fs::read(dir.join("frame_0000.obj")).unwrap();
    let out = simulate_in(None, &scene, &dir, &["--frames", "3"]);
    assert_eq!(out.code, Some(1), "{}", out.describe());
    assert!(
        out.stderr.contains("frame_0001.obj") && out.stderr.contains("a folder of that name is in the way"),
        "{}",
        out.describe()
    );
    assert_eq!(std::fs::read(dir.join("frame_0000.obj")).unwrap(), before, "the folder is as it was");
    assert!(!dir.join("frame_0003.obj").exists());
    assert_eq!(ws.out_entries(), ["frames"], "no staging folder is left beside it");
    // The folder one is in, as `.`: its own name is used for the staging folder beside it.
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::create_dir(&dir).unwrap();
    let out = simulate_in(Some(&dir), &scene, Path::new("."), &["--frames", "1"]);
    assert_eq!(out.code, Some(0), "{}", out.describe());
    assert!(dir.join("frame_0001.obj").exists());
    assert_eq!(ws.out_entries(), ["frames"], "no staging folder is left beside it");
}

/// A run that fails part-way writes nothing: not into a new folder (which is not created), not
/// into one that holds an earlier run's frames (which stay as they were), and no staging folder
/// is left beside it. One rule for where outputs go: shapeup creates the folder named, never
/// the folders above it, as `deform` does for its file.
/// What writing the frames says names them where they end, not in the staging folder.
#[test]
fn frame_warnings_name_the_output_folder() {
    let ws = Workspace::new();
    let scene = ws.scene(
        "bar.toml",
        "[mesh]\ngenerate = { kind = \"tet_box\", cells = [2, 1, 1], size = [2.0, 1.0, 1.0] }\n\
         [solver]\nmode = \"dynamic\"\n[[constraints]]\ntype = \"tet_strain\"\n",
    );
    let dir = ws.out("frames");
    let out = simulate_in(None, &scene, &dir, &["--frames", "1"]);
    assert_eq!(out.code, Some(0), "{}", out.describe());
    let line = out.stderr.lines().find(|l| l.contains("tetrahedra not written")).unwrap_or_default();
    assert!(
        line.contains(&format!("{}: ", dir.join("frame_0000.obj").display())) && !line.contains("partial"),
        "{}",
        out.describe()
    );
}

#[test]
fn a_run_that_fails_part_way_writes_nothing() {
    let ws = Workspace::new();
    let cloth = "[mesh]\ngenerate = { kind = \"cloth\", vertices = [4, 4], size = [1.0, 1.0] }\n\
                 [solver]\nmode = \"dynamic\"\n[[constraints]]\ntype = \"edge_spring\"\n\
                 [[constraints]]\ntype = \"position\"\nvertices = [0]\n";
    // Frame 0 is fine; the first step's energy overflows.
    let failing = ws.scene("far.toml", &format!("{cloth}translate = [1e200, 0.0, 0.0]\n"));
    let dir = ws.out("frames");
    let args = |scene: &Path, dir: &Path| {
        vec![OsStr::new("simulate").to_owned(), scene.into(), "--frames".into(), "3".into(), "-o".into(), dir.into()]
    };
    ws.expect_failure(&args(&failing, &dir), &["far.toml", "not a finite number"]);
    let good = ws.scene("good.toml", cloth);
    shapeup(args(&good, &dir)).success();
    let before: Vec<Vec<u8>> = (0..=3).map(|k| std::fs::read(dir.join(format!("frame_000{k}.obj"))).unwrap()).collect();
    let out = shapeup(args(&failing, &dir));
    assert_eq!(out.code, Some(1), "{}", out.describe());
    let after: Vec<Vec<u8>> = (0..=3).map(|k| std::fs::read(dir.join(format!("frame_000{k}.obj"))).unwrap()).collect();
    assert!(before == after, "the earlier run's frames were changed");
    assert_eq!(ws.out_entries(), ["frames"], "no staging folder is left beside it");
    std::fs::remove_dir_all(&dir).unwrap();
    // A report named as a folder (trailing slash) and a link to nothing as the output folder:
    // refused before any step.
    ws.expect_failure(
        &[
            OsStr::new("simulate"),
            good.as_os_str(),
            "--frames".as_ref(),
            "3".as_ref(),
            "-o".as_ref(),
            ws.out("frames").as_os_str(),
            "--report".as_ref(),
            format!("{}/", ws.path("r.json").display()).as_ref(),
        ],
        &["r.json/", "is a folder"],
    );
    #[cfg(unix)]
    {
        let link = ws.path("dangling");
        std::os::unix::fs::symlink(ws.path("nowhere"), &link).unwrap();
        let out = shapeup(args(&good, &link));
        assert_eq!(out.code, Some(1), "{}", out.describe());
        assert!(out.stderr.contains("nowhere does not exist"), "{}", out.describe());
        assert!(!ws.path("nowhere").exists() && out.stdout.is_empty(), "{}", out.describe());
    }
    // A missing folder above the output: refused, as deform refuses it, and nothing created.
    ws.expect_failure(&args(&good, &ws.out("missing/frames")), &["missing", "does not exist"]);
    ws.expect_failure(
        &[OsStr::new("deform"), good.as_os_str(), "-o".as_ref(), ws.out("missing/result.obj").as_os_str()],
        &["missing", "does not exist"],
    );
}

/// Ctrl+C stops a run between steps: one line saying so, a non-zero exit, nothing written and
/// no staging folder left (a process killed by the signal would leave it).
#[cfg(unix)]
#[test]
fn a_run_stopped_by_ctrl_c_writes_nothing() {
    let ws = Workspace::new();
    let scene = ws.scene(
        "long.toml",
        "[mesh]\ngenerate = { kind = \"cloth\", vertices = [30, 30], size = [1.0, 1.0] }\n\
         [solver]\nmode = \"dynamic\"\n[[constraints]]\ntype = \"edge_spring\"\n",
    );
    let dir = ws.out("frames");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_shapeup"))
        .args([OsStr::new("simulate"), scene.as_os_str(), "--frames".as_ref(), "100000".as_ref(), "-o".as_ref()])
        .arg(&dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until frames are being written (into the staging folder), then interrupt.
    let staged = || {
        std::fs::read_dir(ws.path("out")).unwrap().filter_map(Result::ok).any(|e| {
            std::fs::read_dir(e.path())
                .is_ok_and(|mut frames| frames.any(|f| f.is_ok_and(|f| f.file_name() == "frame_000010.obj")))
        })
    };
    let waited = std::time::Instant::now();
    while !staged() {
        assert!(waited.elapsed().as_secs() < 120, "no frame was staged");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let kill = std::process::Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(kill.success());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty() && l.contains("shapeup:")).collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(lines[0].contains("interrupted (Ctrl+C)") && lines[0].contains("nothing written"), "{stderr}");
    assert_eq!(ws.out_entries(), Vec::<String>::new(), "{stderr}");
}

#[test]
fn a_report_in_a_missing_folder_fails_before_anything_is_written() {
    let ws = Workspace::new();
    let scene = ws.scene("spot.toml", &toml_scene(Path::new(SPOT), "", SHAPE_AND_HANDLE));
    let (o, r) = (ws.out("result.obj"), ws.out("missing/report.json"));
    ws.expect_failure(
        &[OsStr::new("deform"), scene.as_os_str(), "-o".as_ref(), o.as_os_str(), "--report".as_ref(), r.as_os_str()],
        &["missing", "does not exist"],
    );
    let dir = ws.out("frames");
    ws.expect_failure(
        &[
            OsStr::new("simulate"),
            Path::new(EXAMPLES).join("cloth-drape.toml").as_os_str(),
            "--frames".as_ref(),
            "2".as_ref(),
            "-o".as_ref(),
            dir.as_os_str(),
            "--report".as_ref(),
            r.as_os_str(),
        ],
        &["missing", "does not exist"],
    );
    // A report under a file: the file is named as what is in the way.
    write(&ws.path("afile"), "x");
    let r = ws.path("afile").join("report.json");
    ws.expect_failure(
        &[OsStr::new("deform"), scene.as_os_str(), "-o".as_ref(), o.as_os_str(), "--report".as_ref(), r.as_os_str()],
        &["afile is a file, not a folder"],
    );
}

#[test]
fn an_energy_that_overflows_is_an_error_not_infinity() {
    let ws = Workspace::new();
    let body = "[[constraints]]\ntype = \"edge_spring\"\n[[constraints]]\ntype = \"position\"\nvertices = [0]\n\
                [[constraints]]\ntype = \"position\"\nvertices = [1]\ntranslate = [1e200, 0, 0]\n";
    ws.spot_scene_fails(body, &["not a finite number"]);
}

/// A static solve that stops at its iteration cap far from its minimum says so once, on stderr
/// and in the report, and still writes its result (exit 0).
#[test]
fn a_solve_stopped_short_of_its_minimum_says_so_once() {
    let ws = Workspace::new();
    let scene = ws.scene(
        "stiff.toml",
        "[mesh]\ngenerate = { kind = \"cloth\", vertices = [11, 11], size = [1.0, 1.0] }\nnormalize = false\n\
         [solver]\niterations = 200\n[[constraints]]\ntype = \"edge_spring\"\nweight = 1e8\n\
         [[constraints]]\ntype = \"position\"\nvertices = [0]\n\
         [[constraints]]\ntype = \"position\"\nvertices = [120]\ntranslate = [0.5, 0.3, 0.0]\n",
    );
    let out = shapeup(ws.deform_args(&scene));
    assert_eq!(out.code, Some(0), "{}", out.describe());
    let lines: Vec<&str> = out.stderr.lines().filter(|l| l.contains("short of its minimum")).collect();
    assert_eq!(lines.len(), 1, "{}", out.describe());
    assert!(lines[0].contains("stiff.toml: 1 static solve") && lines[0].contains("raise `iterations`"), "{}", lines[0]);
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(ws.out("report.json")).unwrap()).unwrap();
    assert_eq!(report["unconverged"], true);
    assert!(report["residual"].as_f64().unwrap() > 0.01, "{report}");
    let kinds: Vec<&str> = report["warnings"].as_array().unwrap().iter().filter_map(|w| w["kind"].as_str()).collect();
    assert_eq!(kinds, ["unconverged"]);

    // Time steps: a cloth of stiffness 1e8 barely moves in 10 iterations a step. One line for
    // the run, the checked steps' residuals in the report; the default stiffness says nothing.
    let cloth = |stiffness: &str| {
        format!(
            "[mesh]\ngenerate = {{ kind = \"cloth\", vertices = [9, 9], size = [1.0, 1.0] }}\n\
             [solver]\nmode = \"dynamic\"\nstiffness = {stiffness}\n\
             [[constraints]]\ntype = \"triangle_strain\"\nweight = 10.0\n\
             [[constraints]]\ntype = \"bending\"\nweight = 10.0\n\
             [[constraints]]\ntype = \"position\"\nvertices = [0, 8]\nweight = 100.0\n"
        )
    };
    for (stiffness, short) in [("1e8", true), ("100.0", false)] {
        let scene = ws.scene("cloth.toml", &cloth(stiffness));
        let report = ws.out("steps.json");
        let dir = ws.out(&format!("frames-{stiffness}"));
        let extra = [
            OsStr::new("--frames"),
            "70".as_ref(),
            "--every".as_ref(),
            "70".as_ref(),
            "--report".as_ref(),
            report.as_os_str(),
        ];
        let out = simulate_in(None, &scene, &dir, &extra);
        assert_eq!(out.code, Some(0), "{}", out.describe());
        let lines: Vec<&str> = out.stderr.lines().filter(|l| l.contains("short of the converged step")).collect();
        let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(report).unwrap()).unwrap();
        let checked: Vec<u64> =
            report["residuals"].as_array().unwrap().iter().map(|r| r[0].as_u64().unwrap()).collect();
        assert_eq!(checked, [1, 2, 4, 8, 16, 32, 64], "{report}");
        let unconverged = report["unconverged_steps"].as_u64().unwrap();
        if short {
            assert_eq!(lines.len(), 1, "{}", out.describe());
            assert!(
                lines[0].contains(&format!("cloth.toml: {unconverged} of the 7 time steps checked"))
                    && lines[0].contains("raise `iterations`"),
                "{}",
                lines[0]
            );
            assert!(unconverged >= 5, "{report}");
        } else {
            assert!(lines.is_empty() && unconverged == 0, "{}", out.describe());
        }
    }
}

/// Handles built in Gmsh: `physical = "NAME"` selects the vertices of a `.msh` file's physical
/// group, and `deform -o X.msh` gives the file back with its groups and tags, only the
/// coordinates moved. A name the file does not have is one line listing the ones it has.
#[test]
fn physical_groups_of_a_gmsh_file_select_vertices_and_come_back_out() {
    let ws = Workspace::new();
    let input = concat!(env!("CARGO_MANIFEST_DIR"), "/../shapeup-core/tests/data/cube-groups.msh");
    std::fs::copy(input, ws.path("cube.msh")).unwrap();
    let scene = |fixed: &str| {
        format!(
            "[mesh]\npath = 'cube.msh'\nnormalize = false\n[[constraints]]\ntype = \"tet_strain\"\nphysical = \"solid\"\n\
             [[constraints]]\ntype = \"position\"\nphysical = {fixed}\nhard = true\n\
             [[constraints]]\ntype = \"position\"\nbox = {{ min = [0.9, -0.1, -0.1], max = [1.1, 1.1, 1.1] }}\ntranslate = [0.2, 0.0, 0.0]\n"
        )
    };
    let good = ws.scene("good.toml", &scene("\"fixed\""));
    let out = ws.out("result.msh");
    shapeup([OsStr::new("deform"), good.as_os_str(), "-o".as_ref(), out.as_os_str()]).success();
    let (input_text, output_text) = (std::fs::read_to_string(input).unwrap(), std::fs::read_to_string(&out).unwrap());
    let elements = |t: &str| t.split("$Nodes").next().unwrap().to_owned() + t.split("$EndNodes").nth(1).unwrap();
    assert_eq!(elements(&output_text), elements(&input_text), "all but the nodes as the file has them");
    let (before, after) = (read(Path::new(input)), read(&out));
    // "fixed" is the face x = 0 (vertices 0, 3, 4, 7), held hard where it is; x = 1 moved.
    for v in 0..8 {
        let held = [0, 3, 4, 7].contains(&v);
        assert_eq!(after.positions[v] == before.positions[v], held, "vertex {v}");
    }
    // The tag of an unnamed group, or a name the file lacks.
    std::fs::remove_file(&out).unwrap();
    let bad = ws.scene("bad.toml", &scene("\"top\""));
    ws.expect_failure(
        &[OsStr::new("deform"), bad.as_os_str(), "-o".as_ref(), out.as_os_str()],
        &["bad.toml", "constraints[1]", "no physical group \"top\"", "cube.msh has \"fixed\", \"solid\""],
    );
    let by_tag = ws.scene("tag.toml", &scene("1"));
    shapeup([OsStr::new("deform"), by_tag.as_os_str(), "-o".as_ref(), out.as_os_str()]).success();
    assert_eq!(read(&out).positions, after.positions, "tag 1 is \"fixed\"");
}

/// A handle moving vertex 1500 up by 0.2.
const MOVED_VERTEX: &str = "[[constraints]]\ntype = \"position\"\nvertices = [1500]\ntranslate = [0.0, 0.2, 0.0]\n";

/// Edge springs and vertex 0 held where it rests.
const PINNED_SPRINGS: &str =
    "[[constraints]]\ntype = \"edge_spring\"\n[[constraints]]\ntype = \"position\"\nvertices = [0]\n";

#[test]
fn a_start_shape_is_where_the_solve_starts() {
    let dir = tempfile::tempdir().unwrap();
    let spot = spot();
    // The start: Spot moved 0.5 up and squashed (one of the shapes a drag leaves on screen).
    let start: Vec<DVec3> = spot.positions.iter().map(|p| DVec3::new(p.x, 0.5 + 0.7 * p.y, p.z)).collect();
    write_mesh(&dir.path().join("start.obj"), &Mesh { positions: start.clone(), ..spot.clone() }, &Default::default())
        .unwrap();
    let scene = write(&dir.path().join("s.toml"), &toml_scene(Path::new(SPOT), "start = 'start.obj'", PINNED_SPRINGS));
    // No iterations: the output is the start shape itself.
    let out = dir.path().join("out.obj");
    deform_to(&scene, &out, &["--iterations", "0"]).success();
    let worst = max_distance(&read(&out).positions, &start);
    assert!(worst < 1e-9, "{worst}");
    // The same scene simulated starts there too (frame 0 is the start at rest).
    let frames = dir.path().join("frames");
    let dynamic = write(
        &dir.path().join("d.toml"),
        &toml_scene(
            Path::new(SPOT),
            "start = 'start.obj'",
            &format!("[solver]\nmode = \"dynamic\"\nsteps = 1\ngravity = [0.0, 0.0, 0.0]\n{PINNED_SPRINGS}"),
        ),
    );
    simulate_in(None, &dynamic, &frames, &["--frames", "1"]).success();
    let worst = max_distance(&read(&frames.join("frame_0000.obj")).positions, &start);
    assert!(worst < 1e-9, "frame 0 is {worst} from the start shape");

    // From a converged start, a capped solve does not cry "short of the minimum": the gradient
    // it began with is round-off; the rest shape's is the reference.
    let converged = dir.path().join("converged.obj");
    let moved = toml_scene(Path::new(SPOT), "", &format!("{PINNED_SPRINGS}{MOVED_VERTEX}"));
    let from_rest = write(&dir.path().join("rest.toml"), &moved);
    deform_to(&from_rest, &converged, &["--iterations", "3000"]).success();
    let again = write(&dir.path().join("again.toml"), &moved.replacen("\n", "\nstart = 'converged.obj'\n", 1));
    let o = deform_to(&again, &dir.path().join("again.obj"), &["--iterations", "30"]).success();
    assert!(!o.stderr.contains("short of its minimum"), "{}", o.describe());

    // With a tolerance, a start that meets it at once (what the editor saves) is the result
    // as it is: 0 iterations, said so, the report names the start.
    let tolerant = format!("{moved}[solver]\niterations = 3000\ntolerance = 1e-6\n");
    let from_rest = write(&dir.path().join("tolerant.toml"), &tolerant);
    deform_to(&from_rest, &converged, &[]).success();
    let again = write(&dir.path().join("again.toml"), &tolerant.replacen("\n", "\nstart = 'converged.obj'\n", 1));
    let (kept, report) = (dir.path().join("kept.obj"), dir.path().join("kept.json"));
    let o = deform_to(&again, &kept, &["--report", report.to_str().unwrap()]).success();
    assert!(o.stdout.contains("0 iterations (the start shape already meets the tolerance"), "{}", o.describe());
    // Kept bit for bit (vertices where they started skip the working frame's round trip).
    assert!(read(&kept).positions == read(&converged).positions, "kept as it is");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(report["iterations"], 0);
    assert!(report["start"].as_str().unwrap().ends_with("converged.obj"), "{report}");
    // A start far from the minimum whose first iteration lands at E ≈ 0 is not converged:
    // Spot moved by 1 with vertex 0 held at rest goes back (the trial found it kept as it was).
    let shifted: Vec<DVec3> = spot.positions.iter().map(|p| *p + DVec3::X).collect();
    write_mesh(&dir.path().join("shifted.obj"), &Mesh { positions: shifted, ..spot.clone() }, &Default::default())
        .unwrap();
    let back = write(
        &dir.path().join("back.toml"),
        &toml_scene(Path::new(SPOT), "start = 'shifted.obj'", &format!("{PINNED_SPRINGS}[solver]\ntolerance = 1e-6\n")),
    );
    let o = deform_to(&back, &dir.path().join("back.obj"), &[]).success();
    assert!(!o.stdout.contains("kept as it is") && !o.stdout.contains(" 0 iterations"), "{}", o.describe());
    let off = max_distance(&read(&dir.path().join("back.obj")).positions, &spot.positions);
    assert!(off < 1e-6, "back at rest: {off:e} away");

    // Bad input: one line naming the key, nothing written.
    let refused = |start_line: &str, needle: &str| {
        let scene = write(&dir.path().join("bad.toml"), &toml_scene(Path::new(SPOT), start_line, PINNED_SPRINGS));
        let out = dir.path().join("bad.obj");
        let o = deform_to(&scene, &out, &[]);
        assert_eq!(o.code, Some(1), "{}", o.describe());
        assert_eq!(o.stderr.trim().lines().count(), 1, "{}", o.describe());
        assert!(o.stderr.contains("[mesh] start") && o.stderr.contains(needle), "{}", o.describe());
        assert!(!out.exists());
    };
    refused("start = 'missing.obj'", "missing.obj");
    refused("start = ''", "is empty");
    // Same count, other order: STL merges vertices in the order its triangles use them.
    write_mesh(&dir.path().join("start.stl"), &Mesh { positions: start.clone(), ..spot.clone() }, &Default::default())
        .unwrap();
    refused("start = 'start.stl'", "is not a shape of the mesh");
    // Finite coordinates too large for the energy: named as the start's fault.
    let mut huge = start.clone();
    huge[7] = DVec3::new(1e300, 0.0, 0.0);
    write_mesh(&dir.path().join("huge.obj"), &Mesh { positions: huge, ..spot.clone() }, &Default::default()).unwrap();
    refused("start = 'huge.obj'", "huge.obj is not finite");
    // Faces in another order, or from another first corner, are the same faces.
    let mut shuffled = Mesh { positions: start.clone(), ..spot.clone() };
    shuffled.polygons = shapeup_core::mesh::Polygons::new();
    for f in (0..spot.polygons.len()).rev() {
        let mut corners = spot.polygons.get(f).unwrap().to_vec();
        corners.rotate_left(1);
        shuffled.polygons.push(&corners);
    }
    write_mesh(&dir.path().join("shuffled.obj"), &shuffled, &Default::default()).unwrap();
    let scene = write(
        &dir.path().join("shuffled.toml"),
        &toml_scene(Path::new(SPOT), "start = 'shuffled.obj'", PINNED_SPRINGS),
    );
    let out = dir.path().join("shuffled-out.obj");
    deform_to(&scene, &out, &["--iterations", "0"]).success();

    // Contact's checks at time 0 look at the start shape: a sphere around its highest vertex
    // (above the whole rest shape) is said to hold start vertices, not rest ones.
    let top = start.iter().copied().fold(DVec3::splat(f64::NEG_INFINITY), |a, p| if p.y > a.y { p } else { a });
    let rest_top = spot.positions.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max);
    assert!(top.y - 0.05 > rest_top);
    let collider =
        format!("[[colliders]]\ntype = \"sphere\"\ncenter = [{}, {}, {}]\nradius = 0.05\n", top.x, top.y, top.z);
    let scene = write(
        &dir.path().join("contact.toml"),
        &toml_scene(Path::new(SPOT), "start = 'start.obj'", &format!("{PINNED_SPRINGS}{collider}")),
    );
    let o = deform_to(&scene, &dir.path().join("c.obj"), &["--iterations", "1"]).success();
    assert!(
        o.stderr.contains("vertices of the start shape ([mesh] start) start inside a collider"),
        "{}",
        o.describe()
    );
    write_mesh(&dir.path().join("cow.obj"), &read(Path::new(COW)), &Default::default()).unwrap();
    refused("start = 'cow.obj'", &format!("has 2903 vertices where the mesh {SPOT} has {}", spot.num_vertices()));
    // The start is an input: no output replaces it.
    let o = deform_to(&scene, &dir.path().join("start.obj"), &[]);
    assert_eq!(o.code, Some(1), "{}", o.describe());
    assert!(o.stderr.contains("start shape"), "{}", o.describe());
}
