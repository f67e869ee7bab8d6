//! Contact: colliders of every kind, friction against tan θ = μ, self-collision checked by an
//! independent triangle–triangle test, tunnelling, moving colliders, one factorization per run.

use glam::DVec3;
use shapeup_core::scene::{Scene, SceneFormat, SceneSimulation};
use std::path::PathBuf;

/// A scene from TOML text (paths relative to the crate's test data).
fn scene(text: &str) -> Scene {
    Scene::parse(text, SceneFormat::Toml, &PathBuf::from("contact.toml"), PathBuf::from("tests/data")).unwrap()
}

fn start(text: &str) -> (shapeup_core::scene::LoadedScene, SceneSimulation) {
    let mut loaded = scene(text).load().unwrap();
    let sim = loaded.start_scene_simulation().unwrap();
    (loaded, sim)
}

const CLOTH: &str = r#"
[mesh]
generate = { kind = "cloth", vertices = [31, 31], size = [1.0, 1.0] }
normalize = false

[solver]
mode = "dynamic"
iterations = 10

[[constraints]]
type = "triangle_strain"
weight = 1.0

[[constraints]]
type = "bending"
weight = 0.001
"#;

#[test]
fn cloth_drapes_over_a_sphere_without_entering_it() {
    let text =
        format!("{CLOTH}\n[[colliders]]\ntype = \"sphere\"\ncenter = [0.0, -0.4, 0.0]\nradius = 0.3\nfriction = 0.3\n");
    let (_, mut sim) = start(&text);
    let center = DVec3::new(0.0, -0.4, 0.0);
    let thickness = sim.simulation.contact().unwrap().params().thickness;
    for k in 0..120 {
        let report = sim.step().unwrap();
        if k > 20 {
            assert!(report.contact.touching > 0, "step {k}: the cloth lies on the sphere, no contact counted");
        }
        let inside =
            sim.simulation.positions().iter().map(|p| (*p - center).length() - 0.3).fold(f64::INFINITY, f64::min);
        assert!(inside >= thickness * (1.0 - 1e-6) - 1e-12, "step {k}: a vertex {inside} from the sphere");
        assert_eq!(report.contact.inside, 0, "step {k}");
    }
    assert_eq!(sim.simulation.system().factorizations(), 1);
}

#[test]
fn a_cloth_squeezed_between_a_sphere_and_the_floor_is_said_once_with_a_count() {
    // A sphere comes down at 1 m/s through a cloth lying on a plane and on through the plane:
    // no place is out of both, and the run says how many vertex-steps ended inside one. The
    // plane, which stays put, has the last word: the cloth is not dragged under it.
    let text = format!(
        "{CLOTH}\n[[colliders]]\ntype = \"plane\"\npoint = [0.0, -0.02, 0.0]\nnormal = [0.0, 1.0, 0.0]\n\
         [[colliders]]\ntype = \"sphere\"\ncenter = [0.0, 0.25, 0.0]\nradius = 0.2\nvelocity = [0.0, -1.0, 0.0]\n"
    );
    let (_, mut sim) = start(&text);
    let (sphere, radius) = (|t: f64| DVec3::new(0.0, 0.25 - t, 0.0), 0.2);
    let mut inside_by_hand = 0;
    let totals = sim
        .run(30, 1, false, |_, simulation, _| -> Result<(), ()> {
            let (t, q) = (simulation.time(), simulation.positions());
            let lowest = q.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
            assert!(lowest > -0.02, "t = {t}: a vertex {lowest} under the plane");
            inside_by_hand += q.iter().filter(|p| p.y < -0.02 || (**p - sphere(t)).length() < radius).count();
            Ok(())
        })
        .unwrap();
    assert!(inside_by_hand > 0, "the sphere should have squeezed the cloth");
    assert_eq!(totals.ended_inside, inside_by_hand);
    let mut warnings = shapeup_core::warnings::Warnings::new();
    totals.add_warnings(&mut warnings);
    assert_eq!(warnings.count("inside_collider"), inside_by_hand, "{:?}", warnings.to_json());
}

/// A block of tetrahedra resting on the plane y = −0.1 − thickness under gravity tilted by θ
/// (the same as a plane inclined by θ): the x-acceleration of its centre of mass from 0.25 s
/// to 1.25 s, from its slide Δx = v₀T + ½aT² (and Δx itself).
fn incline_acceleration(theta_deg: f64, mu: f64) -> (f64, f64) {
    let theta = theta_deg.to_radians();
    let g = [9.81 * theta.sin(), -9.81 * theta.cos(), 0.0];
    let text = format!(
        r#"
[mesh]
generate = {{ kind = "tet_box", cells = [2, 2, 2], size = [0.2, 0.2, 0.2] }}
normalize = false

[solver]
mode = "dynamic"
iterations = 20
gravity = [{}, {}, 0.0]
stiffness = 10000

[[constraints]]
type = "tet_strain"
weight = 1.0

[contact]
thickness = 0.001

[[colliders]]
type = "plane"
point = [0.0, -0.101, 0.0]
normal = [0.0, 1.0, 0.0]
friction = {mu}
"#,
        g[0], g[1]
    );
    let (_, mut sim) = start(&text);
    let h = sim.simulation.params().time_step;
    // The face on the plane: what sticks or slides (the body above it also shears elastically).
    let bottom: Vec<usize> =
        (0..sim.simulation.positions().len()).filter(|&v| sim.simulation.positions()[v].y < -0.09).collect();
    let centre = |s: &SceneSimulation| {
        let p = s.simulation.positions();
        bottom.iter().map(|&v| p[v]).sum::<DVec3>() / bottom.len() as f64
    };
    let velocity = |s: &SceneSimulation| {
        let v = s.simulation.velocities();
        v.iter().copied().sum::<DVec3>() / v.len() as f64
    };
    let (t0, t1) = ((0.25 / h).round() as usize, (1.25 / h).round() as usize);
    let (mut v0, mut x0) = (DVec3::ZERO, DVec3::ZERO);
    for k in 1..=t1 {
        sim.step().unwrap();
        let c = centre(&sim);
        assert!(c.y > -0.101 - 1e-9, "step {k}: the block's face sank to {}", c.y);
        if k == t0 {
            v0 = velocity(&sim);
            x0 = c;
        }
    }
    let time = (t1 - t0) as f64 * h;
    let slide = centre(&sim).x - x0.x;
    (2.0 * (slide - v0.x * time) / (time * time), slide)
}

#[test]
fn a_block_on_an_incline_sticks_below_the_friction_angle_and_slides_above_it() {
    let g = 9.81;
    for (theta, mu) in [(20.0f64, 0.5), (30.0, 0.5), (30.0, 0.7), (40.0, 0.5), (15.0, 0.2)] {
        let (a, slide) = incline_acceleration(theta, mu);
        let t = theta.to_radians();
        let expected = (g * (t.sin() - mu * t.cos())).max(0.0);
        if expected == 0.0 {
            // Position-level static friction creeps a little: within 3 mm (1.5 % of the block) in 1 s.
            assert!(slide.abs() < 3e-3, "θ = {theta}°, μ = {mu} (tan θ < μ): slid {slide} in 1 s, should stick");
        } else {
            assert!(
                (a - expected).abs() < 0.05 * expected + 0.02,
                "θ = {theta}°, μ = {mu}: a = {a}, expected {expected}"
            );
        }
    }
}

#[test]
fn a_cloth_lying_on_a_sphere_comes_to_rest() {
    // A big sphere the cloth lies on (its edges droop without swinging far), with friction.
    let text = format!(
        "{CLOTH}\n[[colliders]]\ntype = \"sphere\"\ncenter = [0.0, -1.05, 0.0]\nradius = 1.0\nfriction = 0.8\n"
    );
    let (_, mut sim) = start(&text);
    let steps = (2.0 / sim.simulation.params().time_step).round() as usize;
    for _ in 0..steps {
        sim.step().unwrap();
    }
    // ½ Σ m v² of a cloth of mass 1 whose vertices still move by more than 1 cm/s: > 5e-5 J.
    let kinetic = sim.simulation.kinetic_energy();
    assert!(kinetic < 5e-5, "kinetic energy after 2 s: {kinetic}");
}

/// Whether segment pq crosses triangle abc (Möller–Trumbore, both ends strictly apart).
fn segment_crosses_triangle(p: DVec3, q: DVec3, [a, b, c]: [DVec3; 3]) -> bool {
    let d = q - p;
    let (e1, e2) = (b - a, c - a);
    let h = d.cross(e2);
    let det = e1.dot(h);
    if det.abs() < 1e-18 {
        return false;
    }
    let s = p - a;
    let u = s.dot(h) / det;
    let qv = s.cross(e1);
    let v = d.dot(qv) / det;
    let t = e2.dot(qv) / det;
    (1e-9..=1.0 - 1e-9).contains(&t) && u > 1e-9 && v > 1e-9 && u + v < 1.0 - 1e-9
}

/// Every pair of triangles sharing no vertex whose interiors intersect (an edge of one
/// crossing the other), by brute force over all pairs.
fn intersecting_pairs(q: &[DVec3], triangles: &[[u32; 3]]) -> usize {
    // Boxes only skip pairs that cannot meet.
    let boxes: Vec<(DVec3, DVec3)> = triangles
        .iter()
        .map(|t| {
            let p = t.map(|v| q[v as usize]);
            (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]))
        })
        .collect();
    let mut count = 0;
    for (i, s) in triangles.iter().enumerate() {
        for (j, t) in triangles.iter().enumerate().skip(i + 1) {
            let ((lo, hi), (lo2, hi2)) = (boxes[i], boxes[j]);
            if lo.cmpgt(hi2).any() || lo2.cmpgt(hi).any() || s.iter().any(|v| t.contains(v)) {
                continue;
            }
            let (ps, pt) = (s.map(|v| q[v as usize]), t.map(|v| q[v as usize]));
            let crosses =
                |x: [DVec3; 3], y: [DVec3; 3]| (0..3).any(|k| segment_crosses_triangle(x[k], x[(k + 1) % 3], y));
            if crosses(ps, pt) || crosses(pt, ps) {
                count += 1;
            }
        }
    }
    count
}

#[test]
fn a_cloth_folding_onto_itself_never_intersects_itself() {
    // A cloth dropped across a bar onto a floor: both halves fold down and pile up on the floor.
    let text = r#"
[mesh]
generate = { kind = "cloth", vertices = [17, 17], size = [1.0, 1.0] }
normalize = false

[solver]
mode = "dynamic"
iterations = 10

[[constraints]]
type = "triangle_strain"
weight = 1.0

[[constraints]]
type = "bending"
weight = 0.0001

[contact]
self_collision = true
thickness = 0.01
friction = 0.2

[[colliders]]
type = "capsule"
a = [0.0, -0.1, -1.0]
b = [0.0, -0.1, 1.0]
radius = 0.04

[[colliders]]
type = "plane"
point = [0.0, -0.3, 0.0]
normal = [0.0, 1.0, 0.0]
"#;
    let (loaded, mut sim) = start(text);
    let triangles = loaded.mesh.triangles.clone();
    let mut most_self = 0;
    for k in 0..150 {
        let report = sim.step().unwrap();
        most_self = most_self.max(report.contact.self_touching);
        let bad = intersecting_pairs(sim.simulation.positions(), &triangles);
        assert_eq!(bad, 0, "step {k}: {bad} pairs of triangles intersect");
        // The colliders' thickness holds with self-collision on too.
        for p in sim.simulation.positions() {
            let bar = (p.x * p.x + (p.y + 0.1) * (p.y + 0.1)).sqrt() - 0.04;
            assert!(bar.min(p.y + 0.3) > 0.01 * (1.0 - 1e-6), "step {k}: {p:?} too close to a collider");
        }
    }
    assert!(most_self > 0, "the halves never touched: the scene tests nothing");
    assert_eq!(sim.simulation.system().factorizations(), 1);
}

#[test]
fn a_self_collision_thickness_near_the_edge_length_is_warned_about_once() {
    // An 11 × 11 sheet has edges of 0.1 (and diagonals of 0.14): a thickness of 0.11 puts
    // non-neighbouring pairs within it at rest, 0.01 none.
    let text = |t: f64| {
        format!(
            "[mesh]\ngenerate = {{ kind = \"cloth\", vertices = [11, 11], size = [1.0, 1.0] }}\nnormalize = false\n\
             [solver]\nmode = \"dynamic\"\n[[constraints]]\ntype = \"triangle_strain\"\nweight = 1.0\n\
             [contact]\nself_collision = true\nthickness = {t}\n"
        )
    };
    // 0.11: each vertex is 0.1 from the triangles two rings away. Over the mean edge length
    // (about 0.114) the scene is refused, naming [contact].
    let thick = scene(&text(0.11)).load().unwrap();
    assert!(thick.warnings.count("self_contact_at_rest") > 100, "{:?}", thick.warnings.to_json());
    let refused = scene(&text(0.5)).load().map(|_| ()).unwrap_err().to_string();
    assert!(refused.contains("[contact]: thickness 0.5 is over the mean edge length"), "{refused}");
    assert_eq!(thick.warnings.iter().filter(|w| w.kind == "self_contact_at_rest").count(), 1, "one warning");
    let thin = scene(&text(0.01)).load().unwrap();
    assert_eq!(thin.warnings.count("self_contact_at_rest"), 0, "{:?}", thin.warnings.to_json());
}

#[test]
fn a_rest_shape_caught_in_itself_is_warned_about_once_with_a_count() {
    // Two 5 × 5 sheets, one flat (y = 0) and one upright (x = 0.55) passing through it: the
    // upright sheet's edges that cross y = 0 pierce the flat sheet's triangles. Self-collision
    // would keep them so; the load says it once, with the number of edge–triangle pairs an
    // independent test finds. The flat sheet moved aside (x = 2.55) is not caught.
    let sheets = |x: f64| {
        let mut obj = String::new();
        for (k, upright) in [false, true].into_iter().enumerate() {
            for i in 0..5 {
                for j in 0..5 {
                    let (a, b) = (i as f64 / 4.0, j as f64 / 4.0);
                    let p = if upright { [x, a - 0.5 + 0.013, b] } else { [a, 0.0, b] };
                    obj.push_str(&format!("v {} {} {}\n", p[0], p[1], p[2]));
                }
            }
            for i in 0..4 {
                for j in 0..4 {
                    let v = |i: usize, j: usize| 25 * k + 5 * i + j + 1;
                    obj.push_str(&format!(
                        "f {} {} {}\nf {} {} {}\n",
                        v(i, j),
                        v(i + 1, j),
                        v(i, j + 1),
                        v(i + 1, j),
                        v(i + 1, j + 1),
                        v(i, j + 1)
                    ));
                }
            }
        }
        obj
    };
    let dir = tempfile::tempdir().unwrap();
    let load = |x: f64| {
        let path = dir.path().join(format!("sheets{x}.obj"));
        std::fs::write(&path, sheets(x)).unwrap();
        let text = format!(
            "[mesh]\npath = {:?}\nnormalize = false\n[solver]\nmode = \"dynamic\"\n[[constraints]]\n\
             type = \"triangle_strain\"\nweight = 1.0\n[contact]\nself_collision = true\nthickness = 0.005\n",
            path.display().to_string()
        );
        scene(&text).load().unwrap()
    };
    let caught = load(0.55);
    // Independent count: each sheet's edges against the other's triangles, by where the edge
    // crosses the other sheet's plane (y = 0, x = 0.55) lying inside the triangle, a
    // barycentric test in that plane. Two sheets crossing along a line pierce each other both
    // ways.
    let mesh = &caught.mesh;
    let edges = shapeup_core::topology::indexed_edges(&mesh.triangles).0;
    let mut expected = 0;
    // (axis across the plane, the plane's offset, the two axes in it, the other sheet's vertices)
    for (across, offset, (u, w), upright) in [(1, 0.0, (0, 2), false), (0, 0.55, (1, 2), true)] {
        for e in edges.iter().filter(|e| (e[0] < 25) == upright) {
            let (p, q) = (mesh.positions[e[0] as usize], mesh.positions[e[1] as usize]);
            let (a, b) = (p[across] - offset, q[across] - offset);
            if a * b >= 0.0 {
                continue;
            }
            let x = p + (a / (a - b)) * (q - p);
            for t in mesh.triangles.iter().filter(|t| (t[0] >= 25) == upright) {
                let [r0, r1, r2] = t.map(|v| mesh.positions[v as usize]);
                let area = |o: DVec3, v: DVec3, z: DVec3| (v[u] - o[u]) * (z[w] - o[w]) - (z[u] - o[u]) * (v[w] - o[w]);
                let (d, s0, s1, s2) = (area(r0, r1, r2), area(x, r1, r2), area(r0, x, r2), area(r0, r1, x));
                if [s0, s1, s2].iter().all(|&s| s * d >= 0.0) {
                    expected += 1;
                }
            }
        }
    }
    assert!(expected > 0);
    assert_eq!(caught.warnings.count("self_intersection_at_rest"), expected, "{:?}", caught.warnings.to_json());
    assert_eq!(caught.warnings.iter().filter(|w| w.kind == "self_intersection_at_rest").count(), 1);
    let apart = load(2.55);
    assert_eq!(apart.warnings.count("self_intersection_at_rest"), 0, "{:?}", apart.warnings.to_json());
}

/// A self-colliding step gives the same bits at 1 and 2 threads (examples/cloth-fold.toml, 60
/// steps): the mean motions that place the self-collision trees were summed by rayon's
/// thread-dependent split, and the runs drifted apart (all 1,681 vertices by step 60).
#[test]
fn a_self_colliding_cloth_gives_the_same_bits_at_one_and_two_threads() {
    const STEPS: usize = 60;
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/cloth-fold.toml"));
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut loaded = Scene::from_file(&path).unwrap().load().unwrap();
            let mut sim = loaded.start_scene_simulation().unwrap();
            let mut touching = 0;
            for _ in 0..STEPS {
                touching += sim.step().unwrap().contact.self_touching;
            }
            (sim.simulation.positions().to_vec(), touching)
        })
    };
    let (one, touching) = run(1);
    let (two, _) = run(2);
    assert!(touching > 0, "the layers never touched: nothing was compared");
    let differ = one.iter().zip(&two).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "{differ} vertices differ between 1 and 2 threads");
}

#[test]
fn the_cloth_fold_example_never_intersects_itself() {
    // examples/cloth-fold.toml as shipped (41 × 41, folding over a bar onto the ground), 4 s:
    // no two triangles intersect after any step. Before a collider's push was followed by a
    // second pass of self corrections, the bar pushed the inner layer through the outer one.
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/cloth-fold.toml"));
    let mut loaded = Scene::from_file(&path).unwrap().load().unwrap();
    assert_eq!(loaded.warnings.count("self_intersection_at_rest"), 0);
    let mut sim = loaded.start_scene_simulation().unwrap();
    let mut most_self = 0;
    for k in 0..240 {
        most_self = most_self.max(sim.step().unwrap().contact.self_touching);
        let bad = intersecting_pairs(sim.simulation.positions(), &loaded.mesh.triangles);
        assert_eq!(bad, 0, "step {k}: {bad} pairs of triangles intersect");
    }
    assert!(most_self > 100, "the layers hardly touched ({most_self})");
}

#[test]
fn a_cloth_crumpling_on_the_floor_beside_a_sphere_never_passes_through_itself() {
    // The Stop 42 trial's scene: a 41 × 41 cloth over an off-centre sphere, its free side
    // crumpling on the floor. The floor's projection, which has the last word, pushed a
    // vertex of a tight fold through a neighbouring triangle from step 31. Every step is
    // checked by the independent test.
    let text = r#"
[mesh]
generate = { kind = "cloth", vertices = [41, 41], size = [1.0, 1.0] }
normalize = false
[solver]
mode = "dynamic"
iterations = 10
[[constraints]]
type = "triangle_strain"
weight = 10.0
[[constraints]]
type = "bending"
weight = 0.001
[contact]
self_collision = true
friction = 0.3
[[colliders]]
type = "sphere"
center = [0.3, -0.4, 0.2]
radius = 0.25
friction = 0.3
[[colliders]]
type = "plane"
point = [0.0, -0.7, 0.0]
normal = [0.0, 1.0, 0.0]
friction = 0.3
"#;
    let (loaded, mut sim) = start(text);
    let mut stopped = 0;
    for k in 0..90 {
        stopped += sim.step().unwrap().contact.stopped;
        let bad = intersecting_pairs(sim.simulation.positions(), &loaded.mesh.triangles);
        assert_eq!(bad, 0, "step {k}: {bad} pairs of triangles intersect");
    }
    // Since the self corrections after a collider's push leave the layer it pushed where it
    // is (and move the one above), the fold no longer needs the check here; where it acts, it
    // acts locally.
    assert!(stopped < 90 * 1681 / 10, "{stopped} vertices stopped");
}

#[test]
fn a_strain_only_cloth_folding_on_itself_settles_without_gaining_energy() {
    // No bending: the halves crumple as they pile up, the case where self contacts that push
    // layers apart too hard (or too few contacts) feed the cloth energy step after step.
    let text = r#"
[mesh]
generate = { kind = "cloth", vertices = [41, 41], size = [1.0, 1.0] }
normalize = false

[solver]
mode = "dynamic"
iterations = 10

[[constraints]]
type = "triangle_strain"
weight = 10.0

[contact]
self_collision = true
thickness = 0.008
friction = 0.2

[[colliders]]
type = "capsule"
a = [0.0, -0.1, -1.0]
b = [0.0, -0.1, 1.0]
radius = 0.04
friction = 0.5

[[colliders]]
type = "plane"
point = [0.0, -0.3, 0.0]
normal = [0.0, 1.0, 0.0]
"#;
    let (loaded, mut sim) = start(text);
    // The layers must lie on each other for most of the run. (The largest count of one step,
    // asked to exceed 100 before, is chaotic: it was 106, and 59 to 137 when only the order
    // in which the BVH traversal meets the pairs changed.)
    let mut touching_steps = 0;
    for _ in 0..200 {
        touching_steps += usize::from(sim.step().unwrap().contact.self_touching > 20);
    }
    assert!(touching_steps > 120, "the layers hardly touched ({touching_steps} steps): the scene tests nothing");
    // Settled: it moves by millimetres a second and holds little elastic energy (about 0.03;
    // layers pushed apart by their whole overlap each step, or edge–edge contacts at edge ends
    // left out, ended near 5 and still rising).
    let kinetic = sim.simulation.kinetic_energy();
    let elastic = sim.simulation.energy().unwrap();
    assert!(kinetic < 5e-3, "kinetic energy after 200 steps: {kinetic}");
    assert!(elastic < 0.2, "elastic energy after 200 steps: {elastic}");
    let bad = intersecting_pairs(sim.simulation.positions(), &loaded.mesh.triangles);
    assert_eq!(bad, 0, "{bad} pairs of triangles intersect at the end");
}

#[test]
fn a_cloth_falling_from_5_m_stays_above_a_1_mm_plate() {
    let text = format!(
        "{CLOTH}\n[contact]\nthickness = 0.002\n\n[[colliders]]\ntype = \"box\"\nmin = [-2.0, -5.0005, -2.0]\nmax = [2.0, -4.9995, 2.0]\n"
    );
    let (_, mut sim) = start(&text);
    let mut landed = false;
    for k in 0..150 {
        sim.step().unwrap();
        let lowest = sim.simulation.positions().iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        assert!(lowest > -4.9995, "step {k}: a vertex at y = {lowest}, below the plate's top");
        landed |= lowest < -4.99;
    }
    assert!(landed, "the cloth never reached the plate");
}

#[test]
fn a_rising_sphere_lifts_the_cloth_and_never_enters_it() {
    // The cloth rests on a floor; a sphere rises through the floor at 0.5 m/s and lifts it.
    let text = format!(
        "{CLOTH}\n[[colliders]]\ntype = \"plane\"\npoint = [0.0, -0.01, 0.0]\nnormal = [0.0, 1.0, 0.0]\n\n[[colliders]]\ntype = \"sphere\"\ncenter = [0.0, -0.5, 0.0]\nradius = 0.3\nvelocity = [0.0, 0.5, 0.0]\n"
    );
    let (_, mut sim) = start(&text);
    let h = sim.simulation.params().time_step;
    let thickness = sim.simulation.contact().unwrap().params().thickness;
    for k in 1..=120 {
        sim.step().unwrap();
        let center = DVec3::new(0.0, -0.5 + 0.5 * k as f64 * h, 0.0);
        let nearest =
            sim.simulation.positions().iter().map(|p| (*p - center).length() - 0.3).fold(f64::INFINITY, f64::min);
        assert!(nearest > thickness * (1.0 - 1e-6), "step {k}: a vertex {nearest} from the moving sphere");
    }
    let highest = sim.simulation.positions().iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max);
    // After 2 s the sphere's top is at 0.8: the cloth rides on it.
    assert!(highest > 0.75, "the cloth was not lifted: highest y {highest}");
}

#[test]
fn a_thin_fast_plate_carries_the_cloth_instead_of_passing_through_it() {
    // A 2 cm plate rising at 3 m/s moves 5 cm per step, 2.5 of its thicknesses: checked only
    // where it is at each step's end, it would pass by every vertex of the cloth above it. The
    // path test in the plate's own frame sees it sweep over them. The cloth (0.4 m, no gravity)
    // lies within the plate's 0.6 m: all of it is carried.
    let cloth = CLOTH
        .replace("vertices = [31, 31], size = [1.0, 1.0]", "vertices = [21, 21], size = [0.4, 0.4]")
        .replace("iterations = 10\n", "iterations = 10\ngravity = [0.0, 0.0, 0.0]\n");
    let text = format!(
        "{cloth}\n[[colliders]]\ntype = \"box\"\nmin = [-0.3, -0.32, -0.3]\nmax = [0.3, -0.3, 0.3]\nvelocity = [0.0, 3.0, 0.0]\n"
    );
    let (_, mut sim) = start(&text);
    let h = sim.simulation.params().time_step;
    assert!(3.0 * h > 2.0 * 0.02, "the plate must move more than its thickness per step (h = {h})");
    let mut carried = 0;
    for k in 1..=40 {
        sim.step().unwrap();
        let top = -0.3 + 3.0 * k as f64 * h;
        if top <= 0.0 {
            continue;
        }
        let (v, lowest) = sim
            .simulation
            .positions()
            .iter()
            .map(|p| p.y)
            .enumerate()
            .fold((0, f64::INFINITY), |a, (v, y)| if y < a.1 { (v, y) } else { a });
        assert!(lowest > top, "step {k}: vertex {v} at y {lowest} is behind the plate's top {top}");
        carried += 1;
    }
    assert!(carried > 10, "the plate never passed the cloth's plane");
}

#[test]
fn a_thin_plate_at_20_m_per_s_pushes_a_body_without_crushing_it() {
    // A 1 cm plate at 20 m/s moves 33 of its thicknesses per step. Each vertex takes its
    // contact from the side of the plate it started on, so every vertex stays ahead of the
    // front face. The impact squeezes the 0.5 m body (its back does not move until the
    // compression reaches it), then it springs back and flies off ahead of the plate. Taking
    // the contact from where the plate is at the step's end put the vertices it swept past
    // onto its back face: the body was pressed to zero width and carried flat.
    let text = r#"
[mesh]
generate = { kind = "tet_box", cells = [4, 4, 4], size = [0.5, 0.5, 0.5] }
normalize = false

[solver]
mode = "dynamic"
iterations = 10
gravity = [0.0, 0.0, 0.0]

[[constraints]]
type = "tet_strain"
weight = 1.0

[[colliders]]
type = "box"
min = [-1.0, -1.0, -1.0]
max = [-0.99, 1.0, 1.0]
velocity = [20.0, 0.0, 0.0]
"#;
    let (_, mut sim) = start(text);
    let h = sim.simulation.params().time_step;
    let mut after_impact = 0;
    for k in 1..=30 {
        sim.step().unwrap();
        let front = -0.99 + 20.0 * k as f64 * h;
        let xs = sim.simulation.positions().iter().map(|p| p.x);
        let (lowest, highest) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
        assert!(lowest > front - 1e-6, "step {k}: a vertex at x {lowest} is behind the plate's front {front}");
        if front > -0.25 {
            after_impact += 1;
            // Six steps (0.1 s) after the impact the body is back to most of its width.
            if after_impact > 6 {
                assert!(highest - lowest > 0.4, "step {k}: the body is squeezed to a width of {}", highest - lowest);
            }
        }
    }
    assert!(after_impact > 20, "the plate never reached the body");
}

#[test]
fn a_tetrahedral_body_lands_on_a_mesh_terrain() {
    // A bumpy terrain y = f(x, z) as an OBJ grid; a box of tetrahedra dropped on it.
    let f = |x: f64, z: f64| 0.08 * (3.0 * x).sin() * (2.0 * z).cos() - 0.3;
    let n = 41;
    let mut obj = String::new();
    for i in 0..n {
        for j in 0..n {
            let (x, z) = (-1.0 + 2.0 * i as f64 / (n - 1) as f64, -1.0 + 2.0 * j as f64 / (n - 1) as f64);
            obj.push_str(&format!("v {x} {} {z}\n", f(x, z)));
        }
    }
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            let v = |a: usize, b: usize| a * n + b + 1;
            // Counter-clockwise seen from above: normals up.
            obj.push_str(&format!(
                "f {} {} {}\nf {} {} {}\n",
                v(i, j),
                v(i, j + 1),
                v(i + 1, j),
                v(i + 1, j),
                v(i, j + 1),
                v(i + 1, j + 1)
            ));
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let terrain = dir.path().join("terrain.obj");
    std::fs::write(&terrain, obj).unwrap();
    let text = format!(
        r#"
[mesh]
generate = {{ kind = "tet_box", cells = [3, 3, 3], size = [0.3, 0.3, 0.3] }}
normalize = false

[solver]
mode = "dynamic"
iterations = 10
stiffness = 10000

[[constraints]]
type = "tet_strain"
weight = 1.0

[contact]
thickness = 0.005

[[colliders]]
type = "mesh"
path = "{}"
friction = 0.3
"#,
        terrain.display()
    );
    let (_, mut sim) = start(&text);
    // Linear interpolation of f over a cell of 0.05 is within |f''| h²/8 of it.
    let interpolation = (0.08 * 9.0 + 0.08 * 4.0) * 0.05 * 0.05 / 8.0;
    let mut lowest_gap = f64::INFINITY;
    for k in 0..120 {
        sim.step().unwrap();
        for p in sim.simulation.positions() {
            let gap = p.y - f(p.x, p.z);
            lowest_gap = lowest_gap.min(gap);
            assert!(gap > -interpolation, "step {k}: a vertex {gap} below the terrain");
        }
    }
    assert!(lowest_gap < 0.02, "the body never reached the terrain (closest {lowest_gap})");
}

#[test]
fn a_static_drag_stops_at_the_collider() {
    // deform: the whole cloth pulled 0.6 down, through a sphere just under its middle.
    let text = r#"
[mesh]
generate = { kind = "cloth", vertices = [21, 21], size = [1.0, 1.0] }
normalize = false

[solver]
iterations = 50
steps = 10

[[constraints]]
type = "triangle_strain"
weight = 10.0

[[constraints]]
type = "position"
translate = [0.0, -0.6, 0.0]
weight = 1.0

[[colliders]]
type = "sphere"
center = [0.0, -0.35, 0.0]
radius = 0.3
"#;
    let mut loaded = scene(text).load().unwrap();
    let thickness = loaded.contact.as_ref().unwrap().params().thickness;
    let (q, _) = loaded.solve_static(None).unwrap();
    let center = DVec3::new(0.0, -0.35, 0.0);
    let nearest = q.iter().map(|p| (*p - center).length() - 0.3).fold(f64::INFINITY, f64::min);
    assert!(nearest > thickness * (1.0 - 1e-6), "a vertex {nearest} from the sphere");
    assert!(q[0].y < -0.3, "the corners were pulled down: {}", q[0].y);
    // Without the sphere the middle would go down 0.6 with the rest; with it, the cloth rests
    // on top: the nearest point of its triangles (not only of its vertices) is the thickness
    // from the sphere. The pull stretches the triangles over it about 4 times, and their
    // chords keep the middle vertex above that (by about ℓ²/8R).
    let nearest = nearest_on_triangles(&q, &loaded.mesh.triangles, center) - 0.3;
    assert!(
        nearest > 0.9 * thickness && nearest < thickness + 0.002,
        "the cloth's nearest point is {nearest} from the sphere (thickness {thickness})"
    );
    assert!(q[220].y > -0.05 + thickness && q[220].y < 0.05, "the middle rests on the sphere: {}", q[220].y);
}

#[test]
fn a_cloth_starting_inside_the_thickness_is_not_thrown_off() {
    // The cloth starts 0.01 above a plane with a thickness of 0.07: moved out before the first
    // step, it must not gain the correction as velocity.
    let text = format!(
        "{CLOTH}\n[contact]\nthickness = 0.07\n\n[[colliders]]\ntype = \"plane\"\npoint = [0.0, -0.01, 0.0]\nnormal = [0.0, 1.0, 0.0]\n"
    );
    let (_, mut sim) = start(&text);
    for _ in 0..30 {
        sim.step().unwrap();
        let fastest = sim.simulation.velocities().iter().map(|v| v.length()).fold(0.0, f64::max);
        assert!(fastest < 0.2, "a vertex moves at {fastest} m/s");
        let lowest = sim.simulation.positions().iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        assert!(lowest > -0.01 + 0.07 - 1e-9, "a vertex at {lowest}");
    }
}

/// An 11 × 11 cloth whose middle vertex is a sphere's centre (25 vertices inside it).
const CLOTH_THROUGH_SPHERE: &str = r#"
[mesh]
generate = { kind = "cloth", vertices = [11, 11], size = [1.0, 1.0] }
normalize = false
[solver]
mode = "dynamic"
iterations = 5
[[constraints]]
type = "triangle_strain"
[[colliders]]
type = "sphere"
center = [0.0, 0.0, 0.0]
radius = 0.3
"#;

#[test]
fn a_cloth_placed_through_a_sphere_with_a_vertex_at_its_centre_is_pushed_out_and_runs() {
    // A new user's scene: the 11 × 11 cloth's middle vertex at the sphere's centre, 25 inside.
    // Pushed out along their rays, collinear vertices landed on one point; the closest point
    // on such a triangle was 0/0 and the first step failed with "kinetic energy not finite".
    let (loaded, mut sim) = start(CLOTH_THROUGH_SPHERE);
    // 25 inside, more within the thickness.
    let overlapping = loaded.warnings.count("collider_overlaps_rest_shape");
    assert!((25..50).contains(&overlapping), "{:?}", loaded.warnings.to_json());
    let thickness = sim.simulation.contact().expect("contact").params().thickness;
    for k in 0..60 {
        sim.step().unwrap_or_else(|e| panic!("step {k}: {e}"));
        let q = sim.simulation.positions();
        assert!(q.iter().all(|p| p.is_finite()), "step {k}");
        let deepest = q.iter().map(|p| 0.3 + thickness - p.length()).fold(f64::NEG_INFINITY, f64::max);
        assert!(deepest < 1e-9, "step {k}: a vertex {deepest} inside the thickness");
    }
}

#[test]
fn vertices_pushed_onto_one_point_go_on_moving_with_self_collision() {
    // The scene above with self-collision: the vertices a sphere pushed onto one point touch
    // exactly, with no side to keep. The crossing check took each such pair for a crossing and
    // put its vertices back where their step started, every step: 53 of 121 stood still for
    // good. Now they move with the cloth (rigid impact zones, neighbours when at one place).
    let (_, mut sim) = start(&format!("{CLOTH_THROUGH_SPHERE}[contact]\nself_collision = true\n"));
    let mut still = 0;
    let steps = 30;
    for k in 0..steps {
        let before = sim.simulation.positions().to_vec();
        sim.step().unwrap_or_else(|e| panic!("step {k}: {e}"));
        if k > 0 {
            still += before.iter().zip(sim.simulation.positions()).filter(|(a, b)| a == b).count();
        }
    }
    let n = sim.simulation.positions().len();
    assert!(still * 50 < n * (steps - 1), "{still} vertex-steps of {} stood still", n * (steps - 1));
}

/// Whether segment pq passes through the inside of the box [lo, hi] (slab test, strictly).
fn segment_enters_box(p: DVec3, q: DVec3, lo: DVec3, hi: DVec3) -> bool {
    let d = q - p;
    let (mut enter, mut leave) = (0.0f64, 1.0f64);
    for k in 0..3 {
        if d[k].abs() < 1e-15 {
            if p[k] <= lo[k] || p[k] >= hi[k] {
                return false;
            }
            continue;
        }
        let (a, b) = ((lo[k] - p[k]) / d[k], (hi[k] - p[k]) / d[k]);
        enter = enter.max(a.min(b));
        leave = leave.min(a.max(b));
    }
    leave - enter > 1e-9
}

/// A finer, stiffer cloth (41 × 41 vertices, 2.5 cm edges) that a thin bar or a box's corner
/// stretches over itself.
const HEAVY_CLOTH: &str = r#"
[mesh]
generate = { kind = "cloth", vertices = [41, 41], size = [1.0, 1.0] }
normalize = false

[solver]
mode = "dynamic"
iterations = 10
damping = 0.01

[[constraints]]
type = "triangle_strain"
weight = 10.0

[[constraints]]
type = "bending"
weight = 0.01
"#;

/// The box collider [lo, hi] the cloth drapes over in the next two tests.
const BOX: (DVec3, DVec3) = (DVec3::new(-0.2, -0.6, -0.2), DVec3::new(0.2, -0.2, 0.2));

/// Drops `cloth` on the box `BOX` given as `collider` (a `[[colliders]]` entry), turned by
/// `turn` about its centre, and checks independently at every step that no box edge crosses a
/// triangle of the cloth and no edge of the cloth passes through the box.
fn drape_over_the_box(cloth: &str, collider: &str, turn: glam::DQuat) {
    let (lo, hi) = BOX;
    let center = 0.5 * (lo + hi);
    let (loaded, mut sim) = start(&format!("{cloth}\n{collider}"));
    let triangles = loaded.mesh.triangles.clone();
    let corner = |k: usize| {
        let local = DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        center + turn * (local - center)
    };
    // The cloth's points in the box's own frame, where it is [lo, hi].
    let unturn = |p: DVec3| center + turn.inverse() * (p - center);
    let box_edges: Vec<(DVec3, DVec3)> = (0..8)
        .flat_map(|k| (0..3).map(move |b| (k, k | (1 << b))))
        .filter(|(k, l)| k != l)
        .map(|(k, l)| (corner(k), corner(l)))
        .collect();
    assert_eq!(box_edges.len(), 12);
    let top = (0..8).map(|k| corner(k).y).fold(f64::NEG_INFINITY, f64::max);
    let mut draped = false;
    for k in 0..90 {
        sim.step().unwrap();
        let q = sim.simulation.positions();
        let cut = triangles
            .iter()
            .filter(|t| {
                let p = t.map(|v| q[v as usize]);
                box_edges.iter().any(|&(a, b)| segment_crosses_triangle(a, b, p))
                    || (0..3).any(|e| segment_enters_box(unturn(p[e]), unturn(p[(e + 1) % 3]), lo, hi))
            })
            .count();
        assert_eq!(cut, 0, "step {k}: {cut} triangles of the cloth cut into the box");
        draped |= q.iter().any(|p| p.y < top - 0.1);
    }
    assert!(draped, "the cloth never hung over the box's sides");
    assert_eq!(sim.simulation.system().factorizations(), 1);
}

#[test]
fn a_cloth_draped_over_a_box_is_not_cut_by_its_edges() {
    // Each vertex is kept out of the box by its own contact, but a triangle straddling an edge
    // of the box, its vertices a and b from the edge on the two faces, dips
    // (ab − t²)/√((a + t)² + (b + t)²) into it: the box's edges and corners have contacts with
    // the cloth's edges and triangles of their own.
    let (lo, hi) = BOX;
    drape_over_the_box(
        CLOTH,
        &format!(
            "[[colliders]]\ntype = \"box\"\nmin = [{}, {}, {}]\nmax = [{}, {}, {}]\nfriction = 0.2\n",
            lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
        ),
        glam::DQuat::IDENTITY,
    );
}

#[test]
fn a_box_with_a_corner_pointing_up_does_not_pierce_the_cloth() {
    // Turned 45° about (1, 0, 1), the box's top corner pokes up into the cloth's triangles and
    // stretches them over it: once a triangle's inside is over the corner, the offset from the
    // corner points into the triangle from below, so the contact takes its side from the
    // triangle's vertices, which lie on the box's faces around the corner.
    let (lo, hi) = BOX;
    let axis = DVec3::new(1.0, 0.0, 1.0).normalize();
    drape_over_the_box(
        HEAVY_CLOTH,
        &format!(
            "[[colliders]]\ntype = \"box\"\nmin = [{}, {}, {}]\nmax = [{}, {}, {}]\n\
             rotate = {{ axis = [1, 0, 1], angle_deg = 45 }}\n",
            lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
        ),
        glam::DQuat::from_axis_angle(axis, 45f64.to_radians()),
    );
}

#[test]
fn a_cloth_draped_over_a_mesh_cube_is_not_cut_by_its_ridges() {
    // The same box as a closed OBJ mesh collider: its 12 edges are ridges (90°), its 6 face
    // diagonals are flat and make no contacts.
    let (lo, hi) = BOX;
    let mut obj = String::new();
    for k in 0..8 {
        let x = if k & 1 == 0 { lo.x } else { hi.x };
        let y = if k & 2 == 0 { lo.y } else { hi.y };
        let z = if k & 4 == 0 { lo.z } else { hi.z };
        obj.push_str(&format!("v {x} {y} {z}\n"));
    }
    // Outward, counter-clockwise (1-based).
    obj.push_str(
        "f 1 3 2\nf 2 3 4\nf 5 6 7\nf 6 8 7\nf 1 2 5\nf 2 6 5\nf 3 7 4\nf 4 7 8\nf 1 5 3\nf 3 5 7\nf 2 4 6\nf 4 8 6\n",
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cube.obj");
    std::fs::write(&path, obj).unwrap();
    drape_over_the_box(
        CLOTH,
        &format!("[[colliders]]\ntype = \"mesh\"\npath = \"{}\"\nfriction = 0.2\n", path.display()),
        glam::DQuat::IDENTITY,
    );
}

/// The distance from `x` to the nearest of 21 × 21 samples of each triangle: within
/// δ²/(2d) of the exact distance d, δ the samples' spacing (independent of the solver's own
/// closest-point routine).
fn nearest_on_triangles(q: &[DVec3], triangles: &[[u32; 3]], x: DVec3) -> f64 {
    let mut best = f64::INFINITY;
    for t in triangles {
        let p = t.map(|v| q[v as usize]);
        for i in 0..=20 {
            for j in 0..=20 - i {
                let (u, w) = (i as f64 / 20.0, j as f64 / 20.0);
                best = best.min((p[0] * (1.0 - u - w) + p[1] * u + p[2] * w - x).length());
            }
        }
    }
    best
}

#[test]
fn a_small_fast_sphere_does_not_pass_between_the_vertices_of_a_coarse_cloth() {
    // A 3 cm sphere rising at 3 m/s under a 10 cm grid: it reaches no vertex first (its centre
    // is under a triangle's inside, 4.7 cm and more from its corners), so only its contact
    // with the triangles holds it. The cloth (no gravity) is lifted and carried instead.
    let cloth = CLOTH
        .replace("vertices = [31, 31], size = [1.0, 1.0]", "vertices = [11, 11], size = [1.0, 1.0]")
        .replace("iterations = 10\n", "iterations = 10\ngravity = [0.0, 0.0, 0.0]\n");
    let radius = 0.03;
    let center0 = DVec3::new(0.0333, -0.3, 0.0333);
    let text = format!(
        "{cloth}\n[[colliders]]\ntype = \"sphere\"\ncenter = [{}, {}, {}]\nradius = {radius}\nvelocity = [0.0, 3.0, 0.0]\n",
        center0.x, center0.y, center0.z
    );
    let (loaded, mut sim) = start(&text);
    let triangles: Vec<[u32; 3]> = loaded.mesh.triangles.clone();
    let h = sim.simulation.params().time_step;
    let mut lifted = false;
    for k in 1..=40 {
        sim.step().unwrap();
        let center = center0 + DVec3::new(0.0, 3.0 * k as f64 * h, 0.0);
        let nearest = nearest_on_triangles(sim.simulation.positions(), &triangles, center);
        assert!(
            nearest > radius + 0.004,
            "step {k}: the cloth is {nearest} from the sphere's centre (radius {radius})"
        );
        lifted |= sim.simulation.positions().iter().any(|p| p.y > 0.2);
    }
    assert!(lifted, "the sphere never lifted the cloth");
}

/// The distance from `x` to the segment [a, b].
fn to_segment(x: DVec3, a: DVec3, b: DVec3) -> f64 {
    let t = ((x - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
    (x - (a + t * (b - a))).length()
}

#[test]
fn a_cloth_hanging_on_a_thin_bar_is_not_cut_by_it() {
    // A 5 mm bar under a 1 m cloth of 41 × 41 vertices (2.5 cm edges): the cloth folds over
    // it and slides; the solve pulls an edge across the bar beyond its prediction, so the end
    // of the step looks for the edges that ended within reach, with the side they came from.
    let text = format!(
        "{HEAVY_CLOTH}\n[[colliders]]\ntype = \"capsule\"\na = [-0.7, -0.1, 0.0]\nb = [0.7, -0.1, 0.0]\nradius = 0.005\n"
    );
    let (a, b, radius) = (DVec3::new(-0.7, -0.1, 0.0), DVec3::new(0.7, -0.1, 0.0), 0.005);
    let (loaded, mut sim) = start(&text);
    let triangles = loaded.mesh.triangles.clone();
    let mut hanging = false;
    for k in 1..=60 {
        sim.step().unwrap();
        let q = sim.simulation.positions();
        for t in &triangles {
            let p = t.map(|v| q[v as usize]);
            assert!(!segment_crosses_triangle(a, b, p), "step {k}: the bar passes through triangle {t:?}");
            // Each edge near the bar sampled every 1/200 of its length (within 0.2 mm).
            for e in 0..3 {
                let (u, v) = (p[e], p[(e + 1) % 3]);
                if (0.5 * (u + v) - DVec3::new(u.x, -0.1, 0.0)).length() > 0.05 {
                    continue;
                }
                let nearest =
                    (0..=200).map(|i| to_segment(u + (v - u) * (i as f64 / 200.0), a, b)).fold(f64::INFINITY, f64::min);
                assert!(nearest > radius, "step {k}: an edge of triangle {t:?} is {nearest} from the bar's axis");
            }
        }
        hanging |= q.iter().any(|p| p.y < -0.3);
    }
    assert!(hanging, "the cloth never hung down from the bar");
    let top = sim.simulation.positions().iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max);
    assert!(top > -0.1, "the cloth fell off the bar");
}

/// Two 21 × 21 sheets of 0.6 m, 3 cm apart, the upper one turned 0.3 rad and moved 5 cm
/// along x, as one OBJ in `dir`.
fn two_turned_sheets(dir: &std::path::Path) -> PathBuf {
    let (n, size) = (21, 0.6);
    let mut obj = String::new();
    for (sheet, (y, turn, dx)) in [(0.0f64, 0.0f64, 0.0), (0.03, 0.3, 0.05)].into_iter().enumerate() {
        let (c, s) = (turn.cos(), turn.sin());
        for i in 0..n {
            for j in 0..n {
                let (x, z) = (size * (i as f64 / (n - 1) as f64 - 0.5), size * (j as f64 / (n - 1) as f64 - 0.5));
                obj.push_str(&format!("v {} {y} {}\n", c * x - s * z + dx, s * x + c * z));
            }
        }
        let v = |i: usize, j: usize| sheet * n * n + i * n + j + 1;
        for i in 0..n - 1 {
            for j in 0..n - 1 {
                let (a, b, c, d) = (v(i, j), v(i, j + 1), v(i + 1, j), v(i + 1, j + 1));
                obj.push_str(&format!("f {a} {c} {b}\nf {b} {c} {d}\n"));
            }
        }
    }
    let path = dir.join("two_sheets.obj");
    std::fs::write(&path, obj).unwrap();
    path
}

#[test]
fn two_sheets_pressed_flat_on_a_box_keep_their_order_and_do_not_freeze() {
    // A user trial's scene: two sheets fall onto a box's top face and hang over its sides. The
    // self corrections after the box's push were shared by both layers, so they pushed the
    // lower one back into the box; the box put it out again, level with the upper one, and
    // two coplanar layers crossed in the plane, where no path check sees it (in 72 of 120
    // steps at 2 iterations). At 10 iterations the crossing check stopped the zones lying on
    // the box instead, and 16 vertices of the hanging sides stood still for good.
    let dir = tempfile::tempdir().unwrap();
    let mesh = two_turned_sheets(dir.path());
    let (lo, hi) = (DVec3::new(-0.1, -0.4, -0.1), DVec3::new(0.1, -0.1, 0.1));
    let thickness = 0.005;
    for iterations in [2, 10] {
        let text = format!(
            "[mesh]\npath = {mesh:?}\nnormalize = false\n\
             [solver]\nmode = \"dynamic\"\niterations = {iterations}\ntime_step = 0.0333333333\ndensity = 50.0\n\
             [[constraints]]\ntype = \"triangle_strain\"\nweight = 10.0\n\
             [contact]\nself_collision = true\nthickness = {thickness}\n\
             [[colliders]]\ntype = \"box\"\nmin = [{}, {}, {}]\nmax = [{}, {}, {}]\n\
             [[colliders]]\ntype = \"plane\"\npoint = [0.0, -0.4, 0.0]\nnormal = [0.0, 1.0, 0.0]\n",
            lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
        );
        let (loaded, mut sim) = start(&text);
        // How long each vertex has stood exactly still while clear of the box and floor.
        let mut still = vec![0usize; loaded.mesh.positions.len()];
        let mut longest = 0;
        for k in 0..120 {
            let before = sim.simulation.positions().to_vec();
            sim.step().unwrap_or_else(|e| panic!("{iterations} iterations, step {k}: {e}"));
            let q = sim.simulation.positions();
            let bad = intersecting_pairs(q, &loaded.mesh.triangles);
            assert_eq!(bad, 0, "{iterations} iterations, step {k}: {bad} pairs of triangles intersect");
            for (v, (a, b)) in before.iter().zip(q).enumerate() {
                let clear = (*b - b.clamp(lo, hi)).length() > 5.0 * thickness && b.y > -0.4 + 5.0 * thickness;
                still[v] = if a == b && clear { still[v] + 1 } else { 0 };
                longest = longest.max(still[v]);
            }
        }
        if iterations == 10 {
            assert!(longest < 10, "a vertex clear of the colliders stood still for {longest} steps");
        }
    }
}
