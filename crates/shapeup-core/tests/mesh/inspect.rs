//! `shapeup_core::inspect::MeshInfo` against independent computations: the bundled meshes, the
//! generators, hand-made broken meshes and random ones.

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet, VecDeque};
use std::path::Path;

use glam::DVec3;
use proptest::prelude::*;
use shapeup_core::generate::{cloth_grid, tet_box};
use shapeup_core::inspect::{MeshInfo, UnitsGuess};
use shapeup_core::io::read_mesh;
use shapeup_core::mesh::{Mesh, Polygons};

fn data(name: &str) -> Mesh {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data").join(name);
    read_mesh(&path).unwrap_or_else(|e| panic!("{e}")).mesh
}

/// A mesh made of the given faces as they stand (no triangulation checks), with the
/// triangulation `Mesh::from_polygons` gives.
fn polygon_mesh(positions: Vec<DVec3>, faces: &[&[u32]]) -> Mesh {
    let polygons: Polygons = faces.iter().copied().collect();
    Mesh::from_polygons(positions, polygons).unwrap().0
}

/// Everything the tests compare, recomputed with hash maps and breadth-first searches, written
/// apart from the library's sorted-array code.
#[derive(Debug)]
struct Reference {
    unreferenced: usize,
    by_size: [usize; 4],
    edges: usize,
    pieces: usize,
    surface_faces: usize,
    surface_vertices: usize,
    surface_edges: usize,
    boundary_edges: usize,
    boundary_loops: usize,
    non_manifold_edges: usize,
    inconsistent_edges: usize,
    non_manifold_vertices: usize,
}

fn merge_repeats(face: &[u32]) -> Vec<u32> {
    let mut out: Vec<u32> = Vec::new();
    for &v in face {
        if out.last() != Some(&v) {
            out.push(v);
        }
    }
    while out.len() > 1 && out[0] == out[out.len() - 1] {
        out.pop();
    }
    out
}

/// Number of connected components of the graph on `nodes` with `adjacency`.
fn components(nodes: &BTreeSet<u32>, adjacency: &HashMap<u32, Vec<u32>>) -> usize {
    let mut seen = HashSet::new();
    let mut count = 0;
    for &start in nodes {
        if !seen.insert(start) {
            continue;
        }
        count += 1;
        let mut queue = VecDeque::from([start]);
        while let Some(v) = queue.pop_front() {
            for &w in adjacency.get(&v).into_iter().flatten() {
                if seen.insert(w) {
                    queue.push_back(w);
                }
            }
        }
    }
    count
}

fn reference(mesh: &Mesh) -> Reference {
    let faces: Vec<Vec<u32>> = mesh.polygons.iter().map(|f| f.to_vec()).collect();
    let mut used = HashSet::new();
    let mut adjacency: HashMap<u32, Vec<u32>> = HashMap::new();
    let mut join = |element: &[u32]| {
        for &v in element {
            used.insert(v);
            adjacency.entry(v).or_default().extend_from_slice(element);
        }
    };
    faces.iter().for_each(|f| join(f.as_slice()));
    mesh.triangles.iter().for_each(|t| join(t.as_slice()));
    mesh.tetrahedra.iter().for_each(|t| join(t.as_slice()));
    let pieces = components(&used.iter().copied().collect(), &adjacency);

    let mut by_size = [0; 4];
    for f in &faces {
        by_size[match f.len() {
            0..=2 => 0,
            3 => 1,
            4 => 2,
            _ => 3,
        }] += 1;
    }
    let mut edges: HashSet<(u32, u32)> = HashSet::new();
    for f in &faces {
        for k in 0..f.len() {
            let (a, b) = (f[k], f[(k + 1) % f.len()]);
            if a != b {
                edges.insert((a.min(b), a.max(b)));
            }
        }
    }
    for t in &mesh.tetrahedra {
        for i in 0..4 {
            for j in i + 1..4 {
                edges.insert((t[i].min(t[j]), t[i].max(t[j])));
            }
        }
    }

    // The surface: directed sides per undirected edge.
    let surface: Vec<Vec<u32>> = faces.iter().map(|f| merge_repeats(f)).filter(|f| f.len() >= 3).collect();
    let mut sides: HashMap<(u32, u32), Vec<(u32, u32)>> = HashMap::new();
    let mut surface_vertices = HashSet::new();
    for f in &surface {
        for k in 0..f.len() {
            let (a, b) = (f[k], f[(k + 1) % f.len()]);
            sides.entry((a.min(b), a.max(b))).or_default().push((a, b));
            surface_vertices.insert(a);
        }
    }
    let boundary: Vec<(u32, u32)> = sides.iter().filter(|(_, s)| s.len() == 1).map(|(&e, _)| e).collect();
    let mut boundary_adjacency: HashMap<u32, Vec<u32>> = HashMap::new();
    for &(a, b) in &boundary {
        boundary_adjacency.entry(a).or_default().push(b);
        boundary_adjacency.entry(b).or_default().push(a);
    }
    let boundary_nodes: BTreeSet<u32> = boundary_adjacency.keys().copied().collect();

    // A vertex is manifold when the faces around it are joined, through the edges at the vertex,
    // into one chain: no edge at it in more than two of them, and one connected set of faces.
    let mut around: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
    for (i, f) in surface.iter().enumerate() {
        for &v in f {
            around.entry(v).or_default().push(i);
        }
    }
    let mut non_manifold_vertices = 0;
    for (&v, fs) in &mut around {
        fs.dedup(); // a face that visits v twice is listed twice, next to each other
        // Neighbour x of v → the corners (face, position) at v that have x next to them.
        let mut by_neighbour: HashMap<u32, Vec<u32>> = HashMap::new();
        let mut corner_ids = BTreeSet::new();
        for &i in fs.iter() {
            let f = &surface[i];
            for k in 0..f.len() {
                if f[k] == v {
                    let id = (i * 1000 + k) as u32; // corners of small faces only
                    corner_ids.insert(id);
                    by_neighbour.entry(f[(k + 1) % f.len()]).or_default().push(id);
                    by_neighbour.entry(f[(k + f.len() - 1) % f.len()]).or_default().push(id);
                }
            }
        }
        let mut joined: HashMap<u32, Vec<u32>> = HashMap::new();
        let mut branched = false;
        for ids in by_neighbour.values() {
            branched |= ids.len() > 2;
            for &a in ids {
                joined.entry(a).or_default().extend(ids);
            }
        }
        if branched || components(&corner_ids, &joined) != 1 {
            non_manifold_vertices += 1;
        }
    }

    Reference {
        unreferenced: mesh.num_vertices() - used.len(),
        by_size,
        edges: edges.len(),
        pieces,
        surface_faces: surface.len(),
        surface_vertices: surface_vertices.len(),
        surface_edges: sides.len(),
        boundary_edges: boundary.len(),
        boundary_loops: components(&boundary_nodes, &boundary_adjacency),
        non_manifold_edges: sides.values().filter(|s| s.len() > 2).count(),
        inconsistent_edges: sides.values().filter(|s| s.len() == 2 && s[0] == s[1]).count(),
        non_manifold_vertices,
    }
}

/// Checks every count of `info` that [`reference`] recomputes.
fn check_against_reference(mesh: &Mesh, info: &MeshInfo) {
    let r = reference(mesh);
    let (c, s) = (&info.counts, &info.surface);
    assert_eq!(c.vertices, mesh.num_vertices());
    assert_eq!(c.unreferenced_vertices, r.unreferenced, "unreferenced vertices");
    assert_eq!([c.faces_under_3_corners, c.triangles, c.quads, c.ngons], r.by_size, "faces by size");
    assert_eq!(c.faces, mesh.num_polygons());
    assert_eq!(c.triangulation_triangles, mesh.num_triangles());
    assert_eq!(c.tetrahedra, mesh.num_tetrahedra());
    assert_eq!(c.edges, r.edges, "edges");
    assert_eq!(info.pieces.pieces, r.pieces, "pieces");
    assert_eq!(s.faces, r.surface_faces, "surface faces");
    assert_eq!(s.vertices, r.surface_vertices, "surface vertices");
    assert_eq!(s.edges, r.surface_edges, "surface edges");
    assert_eq!(s.boundary_edges, r.boundary_edges, "boundary edges");
    assert_eq!(s.boundary_loops, r.boundary_loops, "boundary loops");
    assert_eq!(s.non_manifold_edges.count, r.non_manifold_edges, "non-manifold edges");
    assert_eq!(s.inconsistent_orientation_edges.count, r.inconsistent_edges, "inconsistent edges");
    assert_eq!(s.non_manifold_vertices.count, r.non_manifold_vertices, "non-manifold vertices");
    assert_eq!(
        s.euler_characteristic,
        r.surface_vertices as i64 - r.surface_edges as i64 + r.surface_faces as i64,
        "Euler characteristic"
    );
    assert_eq!(s.closed, r.surface_faces > 0 && r.boundary_edges == 0);
    if let Some(g) = s.genus {
        // χ = 2c − 2g − b for c orientable pieces with b boundary loops.
        assert_eq!(s.euler_characteristic, 2 * s.pieces as i64 - 2 * g as i64 - s.boundary_loops as i64);
    }
    let text = info.to_string();
    assert!(text.contains(&format!("vertices:        {} (", c.vertices)), "{text}");
    serde_json::to_string(info).unwrap();
}

#[test]
fn bundled_meshes_match_independent_counts() {
    let mut names: Vec<String> = std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".obj"))
        .collect();
    names.sort();
    assert!(names.len() >= 5, "{names:?}");
    for name in names {
        let mesh = data(&name);
        let info = MeshInfo::of(&mesh);
        check_against_reference(&mesh, &info);
    }
}

/// Facts about the bundled meshes, each checked by [`reference`] too: the bunny (the scan as
/// distributed by Stanford) has holes in its base, Spot is a closed genus-0 surface, the roof is
/// a 100 × 100 grid of quads.
#[test]
fn bundled_meshes_known_facts() {
    let bunny = MeshInfo::of(&data("stanford-bunny.obj"));
    assert_eq!(bunny.counts.vertices, 35_947);
    assert_eq!(bunny.counts.unreferenced_vertices, 35_947 - 34_834, "data/README.md");
    assert_eq!(bunny.counts.triangles, 69_451);
    // Five holes in the base, found here and by the reference; the scan is otherwise one
    // manifold, consistently oriented disc-like piece (χ = 2 − 5).
    assert_eq!((bunny.surface.boundary_loops, bunny.surface.boundary_edges), (5, 223));
    assert_eq!((bunny.pieces.pieces, bunny.surface.euler_characteristic, bunny.surface.genus), (1, -3, Some(0)));
    assert_eq!(bunny.units_guess, UnitsGuess::MetresOrNormalized);

    let spot = MeshInfo::of(&data("spot.obj"));
    assert!(spot.surface.closed);
    assert_eq!(spot.surface.euler_characteristic, 2);
    assert_eq!(spot.surface.genus, Some(0));
    assert_eq!(spot.pieces.pieces, 1);

    let roof = MeshInfo::of(&data("roof-quads.obj"));
    assert_eq!((roof.counts.quads, roof.counts.vertices), (100 * 100, 101 * 101));
    assert_eq!((roof.surface.boundary_loops, roof.surface.boundary_edges), (1, 400));
    assert_eq!(roof.counts.edges, 2 * 100 * 101);
    assert_eq!(roof.surface.genus, Some(0));
    assert_eq!(roof.units_guess, UnitsGuess::CentimetresOrInches, "{:?}", roof.bounding_box);

    // The head and two eyes; the eyes' and the head's open rims are the boundary loops.
    let suzanne = MeshInfo::of(&data("suzanne.obj"));
    assert_eq!((suzanne.counts.quads, suzanne.counts.triangles), (468, 32));
    assert_eq!((suzanne.pieces.pieces, suzanne.surface.boundary_loops, suzanne.surface.genus), (3, 4, Some(0)));

    // The cow is closed but pinched at one vertex (two fans meet there): χ = 1, no genus.
    let cow = MeshInfo::of(&data("cow.obj"));
    assert!(cow.surface.closed);
    assert_eq!(cow.surface.non_manifold_vertices.first, vec![253]);
    assert_eq!((cow.surface.euler_characteristic, cow.surface.genus), (1, None));

    // The beetle has fins (edges of 3+ faces) and is open.
    let beetle = MeshInfo::of(&data("beetle.obj"));
    assert!(beetle.surface.non_manifold_edges.count > 0 && !beetle.surface.closed);
}

#[test]
fn cloth_has_one_piece_and_one_boundary_loop() {
    for (nx, nz) in [(2, 2), (5, 5), (7, 3)] {
        let mesh = cloth_grid(nx, nz, 2.0, 1.0);
        let info = MeshInfo::of(&mesh);
        check_against_reference(&mesh, &info);
        assert_eq!(info.pieces.pieces, 1);
        assert_eq!(info.surface.boundary_loops, 1);
        assert_eq!(info.surface.boundary_edges, 2 * (nx - 1) + 2 * (nz - 1));
        assert_eq!(info.surface.genus, Some(0), "a disc");
        assert_eq!(info.surface.euler_characteristic, 1);
        assert_eq!(info.surface.non_manifold_vertices.count, 0);
        assert_eq!(info.surface.inconsistent_orientation_edges.count, 0);
        assert!((info.surface.area - 2.0).abs() < 1e-12);
        assert_eq!(info.degenerate.zero_area_triangles.count, 0);
        assert_eq!(info.volume, None);
    }
    let n = 6;
    let info = MeshInfo::of(&cloth_grid(n, n, 1.0, 1.0));
    assert_eq!(info.surface.boundary_edges, 4 * (n - 1));
}

#[test]
fn tet_box_has_a_closed_boundary_and_no_inverted_tets() {
    let size = DVec3::new(2.0, 1.0, 0.5);
    let mesh = tet_box([3, 2, 2], size);
    let info = MeshInfo::of(&mesh);
    check_against_reference(&mesh, &info);
    let volume = info.volume.as_ref().unwrap();
    assert!(volume.boundary_closed);
    assert_eq!(volume.boundary_open_edges, 0);
    assert_eq!(volume.boundary_faces, mesh.num_triangles());
    assert!((volume.volume - 1.0).abs() < 1e-12);
    assert_eq!(info.degenerate.inverted_tetrahedra.count, 0);
    assert_eq!(info.degenerate.flat_tetrahedra.count, 0);
    assert_eq!(info.pieces.pieces, 1);
    assert!(info.surface.closed);
    assert_eq!(info.surface.genus, Some(0), "a box is a sphere");
    assert_eq!(MeshInfo::of(&tet_box([1, 1, 1], DVec3::ONE)).counts.edges, 19, "Kuhn split of one cube");
}

/// Two triangles meeting only at vertex 0.
#[test]
fn bow_tie_vertex_is_non_manifold() {
    let p = vec![
        DVec3::ZERO,
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(-1.0, 0.0, 0.0),
        DVec3::new(-1.0, -1.0, 0.0),
    ];
    let mesh = Mesh::new(p, vec![[0, 1, 2], [0, 3, 4]]).unwrap();
    let info = MeshInfo::of(&mesh);
    check_against_reference(&mesh, &info);
    assert_eq!(info.surface.non_manifold_vertices.count, 1);
    assert_eq!(info.surface.non_manifold_vertices.first, vec![0]);
    assert_eq!(info.surface.non_manifold_edges.count, 0);
    assert_eq!(info.surface.genus, None);
    assert_eq!(info.pieces.pieces, 1, "joined at the vertex");
    assert_eq!(info.surface.boundary_edges, 6);
    assert!(info.to_string().contains("vertices (not one fan) 1 (first: 0)"), "{info}");
}

/// Three triangles on the edge 0–1.
#[test]
fn fin_edge_is_non_manifold() {
    let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::new(0.5, -1.0, 0.0)];
    let mesh = Mesh::new(p, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
    let info = MeshInfo::of(&mesh);
    check_against_reference(&mesh, &info);
    assert_eq!(info.surface.non_manifold_edges.count, 1);
    assert_eq!(info.surface.non_manifold_edges.first, vec![[0, 1]]);
    assert_eq!(info.surface.non_manifold_vertices.first, vec![0, 1], "the fin's ends");
    assert_eq!(info.surface.boundary_edges, 6);
    assert_eq!(info.surface.genus, None);
}

#[test]
fn zero_area_triangle_and_repeated_corners_are_degenerate() {
    // Triangle 1 has three collinear corners; face 2 repeats vertex 0 (not triangulated).
    let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(2.0, 0.0, 0.0), DVec3::new(0.0, 2.0, 0.0)];
    let mesh = polygon_mesh(p, &[&[0, 1, 2], &[0, 1, 3], &[0, 2, 0, 4], &[2, 2], &[4]]);
    let info = MeshInfo::of(&mesh);
    check_against_reference(&mesh, &info);
    let d = &info.degenerate;
    assert_eq!(d.zero_area_faces.first, vec![1, 2], "collinear, and folded onto itself");
    // Triangle 1 is face 1's; face 2 may or may not be triangulated (a bridge polygon).
    assert_eq!(&mesh.triangles[..2], &[[0, 1, 2], [0, 1, 3]]);
    assert_eq!(d.zero_area_triangles.first[0], 1);
    assert_eq!(d.faces_repeating_a_corner.first, vec![2, 3]);
    assert_eq!(info.counts.faces_under_3_corners, 2);
    let triangulated: HashSet<u32> = mesh.triangle_polygon.iter().copied().collect();
    assert_eq!(info.counts.faces_not_triangulated, 5 - triangulated.len());
    assert!(info.counts.faces_not_triangulated >= 2, "faces 3 and 4 have no triangle");
    assert_eq!(info.surface.genus, None);
    assert_eq!(d.zero_length_edges.count, 0);

    // Two vertices at one place joined by an edge: a zero-length edge and a zero-area triangle.
    let p = vec![DVec3::ZERO, DVec3::X, DVec3::X, DVec3::Y];
    let info = MeshInfo::of(&Mesh::new(p, vec![[0, 1, 3], [1, 2, 3]]).unwrap());
    assert_eq!(info.degenerate.zero_length_edges.first, vec![[1, 2]]);
    assert_eq!(info.degenerate.zero_area_triangles.first, vec![1]);

    // The tolerance is relative: the same shapes a million times smaller are not degenerate.
    let p: Vec<DVec3> = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 1e-3)].map(|v| v * 1e-6).to_vec();
    let info = MeshInfo::of(&Mesh::new(p, vec![[0, 1, 2], [1, 3, 2]]).unwrap());
    assert_eq!(info.degenerate.zero_area_triangles.count, 0);
    assert_eq!(info.units_guess, UnitsGuess::Small);
}

#[test]
fn inverted_and_flat_tetrahedra_are_found() {
    let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::new(1.0, 1.0, 0.0), -DVec3::Z];
    // 0: positive; 1: inverted (the mirror image across z = 0, same order); 2: flat (z = 0 plane).
    let tets = vec![[0, 1, 2, 3], [0, 1, 2, 5], [0, 1, 4, 2]];
    let mesh = Mesh::with_tetrahedra(p, vec![], tets).unwrap();
    let info = MeshInfo::of(&mesh);
    check_against_reference(&mesh, &info);
    assert_eq!(info.degenerate.inverted_tetrahedra.first, vec![1]);
    assert_eq!(info.degenerate.flat_tetrahedra.first, vec![2]);
    let volume = info.volume.as_ref().unwrap();
    assert!((volume.volume - (1.0 / 6.0 - 1.0 / 6.0)).abs() < 1e-12);
    assert!(info.to_string().contains("inverted tetrahedra 1 (first: 1)"), "{info}");
}

#[test]
fn tet_boundary_with_a_face_in_three_tets_is_reported() {
    let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, -DVec3::Z, DVec3::new(1.0, 1.0, 1.0)];
    let one = Mesh::with_tetrahedra(p.clone(), vec![], vec![[0, 1, 2, 3]]).unwrap();
    let v = MeshInfo::of(&one).volume.unwrap();
    assert!(v.boundary_closed && v.boundary_faces == 4 && v.faces_in_more_than_two_tetrahedra == 0);
    let fan = Mesh::with_tetrahedra(p, vec![], vec![[0, 1, 2, 3], [0, 2, 1, 4], [0, 1, 2, 5]]).unwrap();
    let v = MeshInfo::of(&fan).volume.unwrap();
    assert_eq!(v.faces_in_more_than_two_tetrahedra, 1);
    assert_eq!(v.boundary_faces, 9);
}

#[test]
fn two_pieces_and_an_isolated_vertex() {
    let mut p: Vec<DVec3> = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)];
    p.extend(p.clone().iter().map(|v| *v + DVec3::new(5.0, 0.0, 0.0)));
    p.push(DVec3::new(0.0, 0.0, 3.0)); // vertex 8: in nothing
    let mesh = Mesh::new(p, vec![[0, 1, 3], [0, 3, 2], [4, 5, 7], [4, 7, 6]]).unwrap();
    let info = MeshInfo::of(&mesh);
    check_against_reference(&mesh, &info);
    assert_eq!(info.pieces.pieces, 2);
    assert_eq!(info.pieces.largest_piece_vertices, 4);
    assert_eq!(info.counts.unreferenced_vertices, 1);
    assert_eq!(info.surface.boundary_loops, 2);
    assert_eq!(info.surface.pieces, 2);
    assert_eq!(info.surface.genus, Some(0), "two discs");
    assert_eq!(info.bounding_box.size, [6.0, 1.0, 3.0]);
    assert!((info.bounding_box.diagonal - 46f64.sqrt()).abs() < 1e-15);
    assert_eq!(info.units_guess, UnitsGuess::CentimetresOrInches);
}

#[test]
fn inconsistent_orientation_is_found() {
    let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)];
    let mesh = Mesh::new(p, vec![[0, 1, 3], [0, 2, 3]]).unwrap();
    let info = MeshInfo::of(&mesh);
    check_against_reference(&mesh, &info);
    assert_eq!(info.surface.inconsistent_orientation_edges.first, vec![[0, 3]]);
    assert_eq!(info.surface.non_manifold_vertices.count, 0, "still one fan at each vertex");
    assert_eq!(info.surface.genus, None);
}

/// A closed torus of quads: χ = 0, genus 1.
#[test]
fn torus_has_genus_one() {
    let (n, m) = (12u32, 8u32);
    let mut p = Vec::new();
    for i in 0..n {
        for j in 0..m {
            let (u, v) = (std::f64::consts::TAU * i as f64 / n as f64, std::f64::consts::TAU * j as f64 / m as f64);
            p.push(DVec3::new((2.0 + v.cos()) * u.cos(), (2.0 + v.cos()) * u.sin(), v.sin()));
        }
    }
    let id = |i: u32, j: u32| (i % n) * m + j % m;
    let faces: Vec<Vec<u32>> = (0..n)
        .flat_map(|i| (0..m).map(move |j| vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]))
        .collect();
    let refs: Vec<&[u32]> = faces.iter().map(|f| f.as_slice()).collect();
    let mesh = polygon_mesh(p, &refs);
    let info = MeshInfo::of(&mesh);
    check_against_reference(&mesh, &info);
    assert!(info.surface.closed);
    assert_eq!(info.surface.euler_characteristic, 0);
    assert_eq!(info.surface.genus, Some(1));
}

#[test]
fn units_guess_follows_the_diagonal() {
    let cases = [
        (0.0, UnitsGuess::Point),
        (0.01, UnitsGuess::Small),
        (0.05, UnitsGuess::MetresOrNormalized),
        (5.0, UnitsGuess::MetresOrNormalized),
        (5.1, UnitsGuess::CentimetresOrInches),
        (500.0, UnitsGuess::CentimetresOrInches),
        (2_000.0, UnitsGuess::Millimetres),
        (1e6, UnitsGuess::Large),
    ];
    for (d, guess) in cases {
        assert_eq!(UnitsGuess::from_diagonal(d), guess, "{d}");
    }
    // One vertex, no elements: every vertex at one point, nothing else to say.
    let info = MeshInfo::of(&Mesh::new(vec![DVec3::ONE], vec![]).unwrap());
    assert_eq!(info.units_guess, UnitsGuess::Point);
    assert_eq!((info.pieces.pieces, info.counts.unreferenced_vertices), (0, 1));
    assert!(info.to_string().contains("units (a guess): none"), "{info}");
}

#[test]
fn json_has_the_documented_keys() {
    let value = serde_json::to_value(MeshInfo::of(&tet_box([1, 1, 1], DVec3::ONE))).unwrap();
    for key in ["counts", "pieces", "surface", "volume", "degenerate", "bounding_box", "units_guess"] {
        assert!(value.get(key).is_some(), "{key} in {value}");
    }
    assert_eq!(value["units_guess"], "metres_or_normalized");
    assert_eq!(value["counts"]["tetrahedra"], 6);
    assert_eq!(value["surface"]["genus"], 0);
    assert_eq!(value["degenerate"]["inverted_tetrahedra"]["count"], 0);
    assert_eq!(value["bounding_box"]["min"], serde_json::json!([-0.5, -0.5, -0.5]));
}

/// One polygon of 200,000 corners and a vertex in 100,000 triangles: per-face and per-vertex
/// work is linear-log in their size (a quadratic step would take minutes). A watchdog, not a
/// timing assertion.
#[test]
fn huge_faces_and_vertex_degrees_finish() {
    let (sender, receiver) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let k = 200_000u32;
        let p: Vec<DVec3> = (0..k)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / k as f64;
                DVec3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        let mut polygons = Polygons::new();
        polygons.push(&(0..k).collect::<Vec<u32>>());
        let ngon = Mesh { positions: p.clone(), polygons, ..Mesh::default() };
        ngon.validate().unwrap();
        let info = MeshInfo::of(&ngon);
        assert_eq!((info.counts.ngons, info.surface.boundary_edges, info.surface.genus), (1, k as usize, Some(0)));
        let fan: Vec<[u32; 3]> = (1..k / 2).map(|i| [0, i, i + 1]).collect();
        let info = MeshInfo::of(&Mesh::new(p, fan).unwrap());
        assert_eq!(info.surface.non_manifold_vertices.count, 0);
        sender.send(()).unwrap();
    });
    receiver.recv_timeout(std::time::Duration::from_secs(60)).expect("MeshInfo::of hangs on a huge face or fan");
}

fn arbitrary_mesh() -> impl Strategy<Value = Mesh> {
    (1usize..9).prop_flat_map(|n| {
        let point = (-2i32..3, -2i32..3, -2i32..3).prop_map(|(x, y, z)| DVec3::new(x as f64, y as f64, z as f64));
        let positions = proptest::collection::vec(point, n);
        let face = proptest::collection::vec(0..n as u32, 1..7);
        let faces = proptest::collection::vec(face, 0..12);
        let tets = proptest::collection::vec(proptest::array::uniform4(0..n as u32), 0..5);
        (positions, faces, tets).prop_map(|(positions, faces, tets)| {
            let polygons: Polygons = faces.iter().map(|f| f.as_slice()).collect();
            let mut mesh = Mesh::from_polygons(positions, polygons).unwrap().0;
            mesh.tetrahedra = tets;
            mesh
        })
    })
}

proptest! {
    /// Any valid mesh — repeated corners, 1–2 corner faces, coincident vertices, tets of any
    /// shape — is inspected without a panic, and the counts agree with the reference.
    #[test]
    fn any_valid_mesh_is_inspected(mesh in arbitrary_mesh()) {
        prop_assert!(mesh.validate().is_ok());
        let info = MeshInfo::of(&mesh);
        check_against_reference(&mesh, &info);
        prop_assert!(info.surface.boundary_edges <= info.surface.edges);
        prop_assert!(info.surface.edges <= info.counts.edges);
        prop_assert_eq!(info.counts.triangles + info.counts.quads + info.counts.ngons + info.counts.faces_under_3_corners, info.counts.faces);
        prop_assert!(info.bounding_box.diagonal.is_finite());
        prop_assert!(!info.to_string().is_empty());
    }
}
