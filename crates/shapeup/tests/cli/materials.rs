//! `[material]` end to end: a cantilever against Euler–Bernoulli theory, its error falling with
//! refinement, units, masses, the dynamic mode settling where the static solve does, and
//! every bad material key refused in one line with nothing written.

use crate::common::shapeup_in;
use shapeup_core::io::read_mesh;
use shapeup_core::scene::Scene;
use std::path::{Path, PathBuf};

/// E (Pa), ρ (kg/m³) and g (m/s²) of the beam, 1 m × 0.1 m × 0.1 m.
const E: f64 = 1e8;
const RHO: f64 = 1000.0;
const G: f64 = 9.81;

/// A beam along x, `cells` = [n, n/10, n/10] tetrahedral cubes, clamped at x = −L/2, in
/// `units` (the sizes scaled to match), with `extra` appended.
fn beam_scene(dir: &Path, name: &str, n: usize, units: (&str, f64), extra: &str) -> PathBuf {
    let (unit, per_metre) = units;
    let (l, w) = (per_metre, 0.1 * per_metre);
    let text = format!(
        "[mesh]\ngenerate = {{ kind = \"tet_box\", cells = [{n}, {m}, {m}], size = [{l}, {w}, {w}] }}\nunits = \"{unit}\"\n\
         [material]\nmodel = \"neo_hookean\"\nyoungs_modulus = {E:e}\npoisson_ratio = 0.3\ndensity = {RHO}\n\
         [[constraints]]\ntype = \"position\"\nname = \"clamp\"\nhard = true\nbox = {{ min = [{lo}, {big}, {big}], max = [{hi}, {pos}, {pos}] }}\n{extra}",
        m = n / 10,
        lo = -0.51 * l,
        hi = -0.499 * l,
        big = -l,
        pos = l,
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// The mean downward displacement of the free end's vertices (x within 0.5 % of L of the end),
/// in the file's units.
fn tip_deflection(rest_scene: &Path, out: &Path) -> f64 {
    let rest = Scene::from_file(rest_scene).unwrap().read_mesh().unwrap().mesh;
    let moved = read_mesh(out).unwrap().mesh;
    let end = rest.positions.iter().map(|p| p.x).fold(f64::MIN, f64::max);
    let span = end - rest.positions.iter().map(|p| p.x).fold(f64::MAX, f64::min);
    let tip: Vec<usize> = (0..rest.positions.len()).filter(|&v| rest.positions[v].x > end - 0.005 * span).collect();
    -tip.iter().map(|&v| moved.positions[v].y - rest.positions[v].y).sum::<f64>() / tip.len() as f64
}

/// Euler–Bernoulli: a cantilever under its own weight q = ρ g A sags δ = q L⁴ / (8 E I) at
/// its tip, I = b h³ / 12 (metres).
fn euler_bernoulli() -> f64 {
    let (l, b) = (1.0_f64, 0.1_f64);
    let q = RHO * G * b * b;
    q * l.powi(4) / (8.0 * E * b.powi(4) / 12.0)
}

fn deform(scene: &Path, out: &Path) {
    let run = shapeup_in(None, ["deform".as_ref(), scene.as_os_str(), "-o".as_ref(), out.as_os_str()]);
    assert_eq!(run.code, Some(0), "{}", run.describe());
}

/// The tip deflection approaches Euler–Bernoulli's as the mesh is refined (linear tetrahedra
/// are too stiff in bending on coarse meshes: shear locking), and the same beam in millimetres
/// sags by the same amount in millimetres.
#[test]
fn a_cantilever_sags_as_euler_bernoulli_says_closer_with_each_refinement() {
    let dir = tempfile::tempdir().unwrap();
    let theory = euler_bernoulli();
    let mut errors = Vec::new();
    for n in [10, 20, 40, 80, 160] {
        let scene = beam_scene(dir.path(), &format!("beam{n}.toml"), n, ("m", 1.0), "");
        let out = dir.path().join(format!("beam{n}.obj"));
        deform(&scene, &out);
        errors.push((theory - tip_deflection(&scene, &out)) / theory);
    }
    // Measured: 77.6 %, 49.1 %, 20.7 %, 6.3 %, 1.6 % too stiff (the last 46,529 vertices).
    assert!(errors.windows(2).all(|e| e[1] < 0.7 * e[0] && e[1] > 0.0), "errors {errors:?}");
    assert!(errors[4] < 0.03, "the finest beam is {} % off Euler–Bernoulli", 100.0 * errors[4]);
    // Millimetres: the same beam, the same sag (in mm).
    let scene = beam_scene(dir.path(), "beam_mm.toml", 20, ("mm", 1000.0), "");
    let out = dir.path().join("beam_mm.obj");
    deform(&scene, &out);
    let mm = tip_deflection(&scene, &out) / 1000.0;
    let metres = theory * (1.0 - errors[1]);
    // Both stop at the default tolerance (1e-10 on the energy), which leaves about 1e-6 of the
    // motion: measured 1.6e-6 apart.
    assert!((mm - metres).abs() <= 1e-5 * metres, "in mm {mm} m, in m {metres} m");
}

/// Lumped masses are ρ |V| in total, whatever the units, and a beam of 1 mm sags as the 1 m
/// beam scaled: no floor on its vertex masses of 1e-14 kg, no cut-off of its 1e-12 m³
/// tetrahedra (the trial's small parts sagged 19× too far, or were refused as having none).
#[test]
fn the_masses_weigh_the_density_times_the_volume() {
    let dir = tempfile::tempdir().unwrap();
    let big = beam_scene(dir.path(), "big.toml", 20, ("m", 1.0), "");
    // 1 mm long in mm units: the same numbers as the 1 m beam in m, 1e-3 of its size.
    let small = beam_scene(dir.path(), "small.toml", 20, ("mm", 1.0), "");
    std::fs::write(&small, std::fs::read_to_string(&small).unwrap().replace(&format!("{E:e}"), "1e5")).unwrap();
    let (big_out, small_out) = (dir.path().join("big.obj"), dir.path().join("small.obj"));
    deform(&big, &big_out);
    deform(&small, &small_out);
    // δ ∝ L² ρ g / E: L × 1e-3 and E × 1e-3 give δ × 1e-3 (m), the same δ/L.
    let (big_tip, small_tip) = (tip_deflection(&big, &big_out), tip_deflection(&small, &small_out) * 1e-3);
    assert!((small_tip / big_tip - 1e-3).abs() < 1e-7, "1 mm part sags {small_tip} m, the 1 m beam {big_tip} m");
    for (unit, per_metre) in [("m", 1.0), ("cm", 100.0), ("mm", 1000.0), ("in", 1.0 / 0.0254)] {
        let scene = beam_scene(dir.path(), "beam.toml", 20, (unit, per_metre), "[solver]\nmode = \"dynamic\"\n");
        let loaded = Scene::from_file(&scene).unwrap().load().unwrap();
        let mass: f64 = loaded.masses().iter().sum();
        let expected = RHO * 1.0 * 0.1 * 0.1;
        assert!((mass - expected).abs() <= 1e-12 * expected, "{unit}: {mass} kg, expected {expected}");
    }
}

/// A clamped beam let go in dynamic mode swings and, damped, settles where the static solve
/// puts it.
#[test]
fn a_simulated_beam_settles_at_the_static_equilibrium() {
    let dir = tempfile::tempdir().unwrap();
    let static_scene = beam_scene(dir.path(), "static.toml", 20, ("m", 1.0), "");
    let out = dir.path().join("static.obj");
    deform(&static_scene, &out);
    let settled = tip_deflection(&static_scene, &out);
    let scene = beam_scene(
        dir.path(),
        "dynamic.toml",
        20,
        ("m", 1.0),
        "[solver]\nmode = \"dynamic\"\ntime_step = 0.01\ndamping = 0.05\n",
    );
    let frames = dir.path().join("frames");
    let run = shapeup_in(
        None,
        [
            "simulate".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            frames.as_os_str(),
            "--frames".as_ref(),
            "150".as_ref(),
        ],
    );
    assert_eq!(run.code, Some(0), "{}", run.describe());
    let deepest =
        (1..=150).map(|k| tip_deflection(&scene, &frames.join(format!("frame_{k:04}.obj")))).fold(f64::MIN, f64::max);
    let last = tip_deflection(&scene, &frames.join("frame_0150.obj"));
    assert!(deepest > 1.2 * settled, "the beam should swing past its rest sag: deepest {deepest}, static {settled}");
    assert!((last - settled).abs() < 0.05 * settled, "after 1.5 s the tip is at {last}, the static sag is {settled}");
    // Whatever the scene's mode: `deform` of the dynamic scene carries the self-weight, and
    // `simulate` of the static one neither counts it twice nor scales the material by k.
    let out = dir.path().join("dynamic-deformed.obj");
    deform(&scene, &out);
    let deformed = tip_deflection(&scene, &out);
    assert!((deformed - settled).abs() <= 1e-9 * settled, "deform of the dynamic scene: {deformed}, static {settled}");
    let frames = dir.path().join("static-frames");
    let run = shapeup_in(
        None,
        [
            "simulate".as_ref(),
            static_scene.as_os_str(),
            "-o".as_ref(),
            frames.as_os_str(),
            "--frames".as_ref(),
            "150".as_ref(),
        ],
    );
    assert_eq!(run.code, Some(0), "{}", run.describe());
    let deepest = (1..=150)
        .map(|k| tip_deflection(&static_scene, &frames.join(format!("frame_{k:04}.obj"))))
        .fold(f64::MIN, f64::max);
    assert!(
        deepest > settled && deepest < 2.5 * settled,
        "simulate of the static scene swings to {deepest}, static {settled}"
    );
}

/// Each bad material key: one line naming the scene and the key, exit 1, nothing written.
#[test]
fn bad_material_keys_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let material = |body: &str| {
        format!(
            "[mesh]\ngenerate = {{ kind = \"tet_box\", cells = [4, 1, 1], size = [1.0, 0.25, 0.25] }}\n[material]\n{body}\n"
        )
    };
    let good = "model = \"stvk\"\nyoungs_modulus = 1e6\npoisson_ratio = 0.3\ndensity = 1000.0";
    let cases: Vec<(String, &str)> = vec![
        (material(&good.replace("1e6", "0.0")), "youngs_modulus"),
        (material(&good.replace("1e6", "-5.0")), "youngs_modulus"),
        (material(&good.replace("0.3", "0.5")), "poisson_ratio"),
        (material(&good.replace("0.3", "-1.0")), "poisson_ratio"),
        (material(&good.replace("1000.0", "-1.0")), "density"),
        (material(&good.replace("stvk", "rubber")), "neo_hookean"),
        (material("model = \"stvk\"\npoisson_ratio = 0.3\ndensity = 1000.0"), "missing youngs_modulus"),
        (material(&format!("{good}\nthickness = 0.1")), "thickness"),
        (material("model = \"projective\"\nyoungs_modulus = 1e6"), "projective"),
        (
            material("model = \"projective\"")
                .replace("size = [1.0, 0.25, 0.25] }", "size = [1.0, 0.25, 0.25] }\nunits = \"m\""),
            "\"projective\" has none",
        ),
        (material(good).replace("size = [1.0, 0.25, 0.25] }", "size = [1.0, 0.25, 0.25] }\nunits = \"km\""), "km"),
        (
            "[mesh]\ngenerate = { kind = \"tet_box\", cells = [4, 1, 1], size = [1.0, 0.25, 0.25] }\nunits = \"mm\"\n"
                .to_string(),
            "units",
        ),
        (
            format!(
                "[mesh]\ngenerate = {{ kind = \"cloth\", vertices = [4, 4], size = [1.0, 1.0] }}\n[material]\n{good}\n"
            ),
            "needs tetrahedra",
        ),
        (
            format!("{}[[colliders]]\ntype = \"sphere\"\ncenter = [0, -2, 0]\nradius = 0.5\n", material(good)),
            "colliders",
        ),
        (material(&good.replace("stvk", "corotated").replace("0.3", "-0.2")), "corotated"),
        (balloon("thickness = 0.0", "pressure = 1000.0"), "thickness"),
        (balloon("thickness = -0.001", "pressure = 1000.0"), "thickness"),
        (balloon("thickness = 0.001", "pressure = nan"), "pressure"),
        (balloon("thickness = 0.001", "pressure = 1000.0\ngust = 3.0"), "unknown field `gust`"),
        (balloon("thickness = 0.001", "wind = { velocity = [1.0, 0.0, 0.0] }"), "shapeup simulate"),
        (balloon("thickness = 0.001", "wind = { velocity = [1.0, 0.0, 0.0], drag = -1.0 }"), "drag"),
        (balloon("thickness = 0.001", "wind = { velocity = [1.0, 0.0, 0.0], air_density = 0.0 }"), "air_density"),
        (balloon("thickness = 0.001", "pressure = 1000.0").replace("[0.0, 0.0, 0.0]", "[0.0, -9.81, 0.0]"), "ran away"),
        (balloon("thickness = 0.001", "pressure = 1.0e5"), "ran away"),
        (
            format!(
                "{}[[colliders]]\ntype = \"sphere\"\ncenter = [0, -2, 0]\nradius = 0.5\n",
                balloon("thickness = 0.001", "pressure = 1000.0")
            ),
            "colliders",
        ),
    ];
    for (text, needle) in cases {
        let scene = dir.path().join("bad.toml");
        std::fs::write(&scene, &text).unwrap();
        let out = dir.path().join("out.obj");
        let run = shapeup_in(None, ["deform".as_ref(), scene.as_os_str(), "-o".as_ref(), out.as_os_str()]);
        assert_eq!(run.code, Some(1), "{text}\n{}", run.describe());
        assert!(run.stderr.contains(needle) && run.stderr.contains("bad.toml"), "{text}\n{}", run.stderr);
        assert_eq!(run.stderr.lines().count(), 1, "{}", run.stderr);
        assert!(!out.exists(), "{text}: wrote an output");
    }
}

/// A rubber balloon: a sphere of `radius_mm` millimetres, 1 mm thick unless `thickness` says
/// otherwise, no gravity, with `loads` in `[loads]`.
fn balloon(thickness: &str, loads: &str) -> String {
    format!(
        "[mesh]\ngenerate = {{ kind = \"sphere\", subdivisions = 3, radius = 100.0 }}\nunits = \"mm\"\n\
         [solver]\ngravity = [0.0, 0.0, 0.0]\n\
         [material]\nmodel = \"neo_hookean\"\nyoungs_modulus = 1.0e6\npoisson_ratio = 0.45\ndensity = 1100.0\n{thickness}\n\
         [loads]\n{loads}\n"
    )
}

/// The enclosed volume of a closed, outward-oriented triangle mesh (divergence theorem).
fn enclosed_volume(mesh: &shapeup_core::Mesh) -> f64 {
    mesh.triangles.iter().map(|t| t.map(|v| mesh.positions[v as usize])).map(|[a, b, c]| a.dot(b.cross(c)) / 6.0).sum()
}

/// A rubber balloon (stable Neo-Hookean, E = 1 MPa, ν = 0.45, 1 mm thick, radius 0.1 m)
/// inflated from the command line, in millimetres and in metres: its stretch s = (V/V₀)^⅓
/// satisfies the membrane's pressure–stretch law within 1 %, written out here from the model's
/// formula in plane stress: p = A₀ h · 2P₁₁(s) / (3 V₀ s²) with P₁₁ = μs + (λ'(J − 1) − μ) s λ₃,
/// J = s²λ₃, λ₃ = (λ' + μ)s² / (μ + λ's⁴), λ' = λ + μ. The mass is ρ h A₀.
#[test]
fn a_balloon_inflates_as_its_membranes_law_says_in_any_units() {
    let dir = tempfile::tempdir().unwrap();
    let (e, nu, h) = (1.0e6_f64, 0.45_f64, 0.001_f64);
    let (mu, lambda) = (e / (2.0 * (1.0 + nu)), e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)));
    let lp = lambda + mu;
    let slope = |s: f64| {
        let l3 = (lp + mu) * s * s / (mu + lp * s.powi(4));
        2.0 * (mu * s + (lp * (s * s * l3 - 1.0) - mu) * s * l3)
    };
    for (unit, per_metre) in [("mm", 1000.0), ("m", 1.0)] {
        let text = balloon("thickness = 0.001", "pressure = 3000.0")
            .replace("units = \"mm\"", &format!("units = \"{unit}\""))
            .replace("radius = 100.0", &format!("radius = {}", 0.1 * per_metre));
        let scene = dir.path().join(format!("balloon-{unit}.toml"));
        std::fs::write(&scene, text).unwrap();
        let out = dir.path().join(format!("balloon-{unit}.obj"));
        deform(&scene, &out);
        let rest = Scene::from_file(&scene).unwrap().read_mesh().unwrap().mesh;
        let moved = read_mesh(&out).unwrap().mesh;
        let per_metre3 = per_metre * per_metre * per_metre;
        let (v0, v) = (enclosed_volume(&rest) / per_metre3, enclosed_volume(&moved) / per_metre3);
        let a0: f64 = rest
            .triangles
            .iter()
            .map(|t| t.map(|i| rest.positions[i as usize] / per_metre))
            .map(|[a, b, c]| 0.5 * (b - a).cross(c - a).length())
            .sum();
        let s = (v / v0).cbrt();
        let law = a0 * h * slope(s) / (3.0 * v0 * s * s);
        assert!(s > 1.1, "{unit}: barely inflated, s = {s}");
        assert!((law / 3000.0 - 1.0).abs() < 0.01, "{unit}: s = {s}, where the law gives {law} Pa, not 3000");
        let loaded = Scene::from_file(&scene).unwrap().load().unwrap();
        let mass: f64 = loaded.masses().iter().sum();
        assert!((mass - 1100.0 * h * a0).abs() < 1e-12 * mass, "{unit}: {mass} kg");
    }
}

/// A cotton-like sheet (a membrane, 0.5 mm thick) hung from two corners under gravity: it
/// settles, converged, with no NaN, in static and dynamic mode.
#[test]
fn a_membrane_sheet_hangs_under_its_own_weight() {
    let dir = tempfile::tempdir().unwrap();
    let text = "[mesh]\ngenerate = { kind = \"cloth\", vertices = [11, 11], size = [1.0, 1.0] }\n\
                [material]\nmodel = \"stvk\"\nyoungs_modulus = 5.0e6\npoisson_ratio = 0.3\ndensity = 1500.0\nthickness = 0.0005\n\
                [[constraints]]\ntype = \"position\"\nname = \"corners\"\nvertices = [0, 10]\nhard = true\n";
    let scene = dir.path().join("sheet.toml");
    std::fs::write(&scene, text).unwrap();
    let (out, report) = (dir.path().join("sheet.obj"), dir.path().join("sheet.json"));
    let run = shapeup_in(
        None,
        ["deform".as_ref(), scene.as_os_str(), "-o".as_ref(), out.as_os_str(), "--report".as_ref(), report.as_os_str()],
    );
    assert_eq!(run.code, Some(0), "{}", run.describe());
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    // null: converged to the tolerance (a residual is measured only for a solve that was not).
    assert_ne!(report["unconverged"], serde_json::json!(true), "{}", report["warnings"]);
    let moved = read_mesh(&out).unwrap().mesh;
    let lowest = moved.positions.iter().map(|p| p.y).fold(f64::MAX, f64::min);
    assert!(moved.positions.iter().all(|p| p.is_finite()) && lowest < -0.3, "lowest point {lowest} m");
    let frames = dir.path().join("frames");
    let run = shapeup_in(
        None,
        ["simulate".as_ref(), scene.as_os_str(), "--frames".as_ref(), "20".as_ref(), "-o".as_ref(), frames.as_os_str()],
    );
    assert_eq!(run.code, Some(0), "{}", run.describe());
}

/// A material's scene writes back with its `[material]` table and units, and reads back equal.
#[test]
fn a_material_scene_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let scene = beam_scene(dir.path(), "beam.toml", 10, ("cm", 100.0), "");
    let parsed = Scene::from_file(&scene).unwrap();
    let text = parsed.to_toml_string();
    assert!(text.contains("[material]") && text.contains("units = \"cm\""), "{text}");
    let again = Scene::parse(&text, shapeup_core::scene::SceneFormat::Toml, &scene, dir.path().to_path_buf()).unwrap();
    assert_eq!(again, parsed);
    // A shell's thickness and a pressure too.
    let shell = dir.path().join("balloon.toml");
    std::fs::write(&shell, balloon("thickness = 0.002", "pressure = 1500.0")).unwrap();
    let parsed = Scene::from_file(&shell).unwrap();
    let text = parsed.to_toml_string();
    assert!(text.contains("thickness = 0.002") && text.contains("[loads]\npressure = 1500"), "{text}");
    let again = Scene::parse(&text, shapeup_core::scene::SceneFormat::Toml, &shell, dir.path().to_path_buf()).unwrap();
    assert_eq!(again, parsed);
    // The material's defaults: a tolerance and an iteration guard, written out explicitly.
    assert_eq!(parsed.solver.iterations, shapeup_core::scene::MATERIAL_ITERATIONS);
    assert_eq!(parsed.solver.tolerance, shapeup_core::scene::MATERIAL_TOLERANCE);
}
