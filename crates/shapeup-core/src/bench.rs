//! The standard benchmark scenarios (`shapeup bench`, criterion benches): a mesh with its
//! 2 % lowest vertices (by y) fixed and its 2 % highest moved by (0.25 D, 0.1 D, 0), D the
//! bounding-box diagonal, under one of three shape models.

use crate::constraints::ShapeModel;
use crate::mesh::Mesh;
use crate::scene::{GroupSpec, LoadedScene, MeshSettings, Scene, SceneError, SelectionSpec, SolverSettings, Targets};
use std::path::PathBuf;

/// A shape model of the benchmarks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scenario {
    /// Edge springs (multiplier 10).
    Springs,
    /// Triangle strain (10) + bending (10).
    StrainBending,
    /// Isometric one-rings (100).
    Iso,
}

impl Scenario {
    /// Every scenario, in table order.
    pub const ALL: [Scenario; 3] = [Scenario::Springs, Scenario::StrainBending, Scenario::Iso];

    /// Short name (`springs`, `strain+bending`, `iso`).
    pub fn name(self) -> &'static str {
        match self {
            Scenario::Springs => "springs",
            Scenario::StrainBending => "strain+bending",
            Scenario::Iso => "iso",
        }
    }

    /// Shape groups: (type, multiplier).
    fn shape(self) -> Vec<(&'static str, f64)> {
        match self {
            Scenario::Springs => ShapeModel::EdgeSprings,
            Scenario::StrainBending => ShapeModel::StrainBending,
            Scenario::Iso => ShapeModel::IsoOneRing,
        }
        .groups()
    }
}

/// The vertices used by a triangle, sorted by y: the lowest and highest `fraction` of them
/// (at least one each).
pub fn extreme_vertices(mesh: &Mesh, fraction: f64) -> (Vec<usize>, Vec<usize>) {
    let mut used = vec![false; mesh.num_vertices()];
    mesh.triangles.iter().flatten().for_each(|&v| used[v as usize] = true);
    let mut order: Vec<usize> = (0..mesh.num_vertices()).filter(|&v| used[v]).collect();
    order.sort_by(|&a, &b| mesh.positions[a].y.total_cmp(&mesh.positions[b].y));
    let k = ((order.len() as f64 * fraction).ceil() as usize).clamp(1, order.len() / 2);
    let low = order[..k].to_vec();
    let high = order[order.len() - k..].to_vec();
    (low, high)
}

/// The benchmark scene of `scenario` on `mesh`.
pub fn scenario_scene(scenario: Scenario, mesh: &Mesh, mesh_path: PathBuf) -> Scene {
    let (low, high) = extreme_vertices(mesh, 0.02);
    let (lo, hi) = mesh.bounding_box();
    let d = (hi - lo).length();
    let mut groups: Vec<GroupSpec> = scenario
        .shape()
        .iter()
        .map(|&(kind, weight)| GroupSpec {
            kind: kind.into(),
            name: kind.into(),
            weight,
            selection: SelectionSpec::All,
            targets: Targets::default(),
            options: Default::default(),
        })
        .collect();
    for (name, vertices, translate) in [("fixed", low, [0.0; 3]), ("moved", high, [0.25 * d, 0.1 * d, 0.0])] {
        groups.push(GroupSpec {
            kind: "position".into(),
            name: name.into(),
            weight: 1.0,
            selection: SelectionSpec::Vertices(vertices),
            targets: Targets { translate, ..Default::default() },
            options: Default::default(),
        });
    }
    Scene {
        mesh: MeshSettings {
            path: mesh_path.clone(),
            generate: None,
            normalize: true,
            tetrahedralize: false,
            start: None,
            units: None,
        },
        solver: SolverSettings::default(),
        groups,
        colliders: Vec::new(),
        contact: Default::default(),
        output: Default::default(),
        material: None,
        loads: Default::default(),
        base_dir: PathBuf::new(),
        file: mesh_path,
    }
}

/// Builds the benchmark system of `scenario` on an already loaded mesh.
///
/// # Errors
/// As [`Scene::build`].
pub fn load_scenario(scenario: Scenario, mesh: &Mesh, mesh_path: PathBuf) -> Result<LoadedScene, SceneError> {
    scenario_scene(scenario, mesh, mesh_path).build(mesh.clone(), crate::warnings::Warnings::new(), 0.0)
}

/// The dynamic (Projective Dynamics) benchmark scenarios: generated meshes, 10 iterations per
/// time step, measured in steps (frames) per second.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DynamicScenario {
    /// A 100 × 100 cloth (10,000 vertices), two corners pinned, strain (10) + bending (10).
    Cloth10k,
    /// A 200 × 200 cloth (40,000 vertices), the same constraints.
    Cloth40k,
    /// A box of 26 × 13 × 10 cubes (20,280 tetrahedra, 4,158 vertices), tet strain (10) over a
    /// floor, falling.
    TetBox20k,
}

impl DynamicScenario {
    /// Every scenario, in table order.
    pub const ALL: [DynamicScenario; 3] =
        [DynamicScenario::Cloth10k, DynamicScenario::Cloth40k, DynamicScenario::TetBox20k];

    /// Short name (`cloth-10k`, `cloth-40k`, `tet-box-20k`).
    pub fn name(self) -> &'static str {
        match self {
            DynamicScenario::Cloth10k => "cloth-10k",
            DynamicScenario::Cloth40k => "cloth-40k",
            DynamicScenario::TetBox20k => "tet-box-20k",
        }
    }

    /// The scenario as scene text (TOML).
    pub fn scene_text(self) -> String {
        let cloth = |n: usize| {
            format!(
                "[mesh]\ngenerate = {{ kind = \"cloth\", vertices = [{n}, {n}], size = [1.0, 1.0] }}\n\
                 [solver]\nmode = \"dynamic\"\niterations = 10\ndamping = 0.02\n\
                 [[constraints]]\ntype = \"triangle_strain\"\nweight = 10.0\n\
                 [[constraints]]\ntype = \"bending\"\nweight = 10.0\n\
                 [[constraints]]\ntype = \"position\"\nvertices = [0, {}]\nweight = 100.0\n",
                n - 1
            )
        };
        match self {
            DynamicScenario::Cloth10k => cloth(100),
            DynamicScenario::Cloth40k => cloth(200),
            DynamicScenario::TetBox20k => {
                "[mesh]\ngenerate = { kind = \"tet_box\", cells = [26, 13, 10], size = [2.6, 1.3, 1.0] }\n\
                 [solver]\nmode = \"dynamic\"\niterations = 10\ndamping = 0.02\n\
                 [[constraints]]\ntype = \"tet_strain\"\nweight = 10.0\n\
                 [[constraints]]\ntype = \"floor\"\nheight = -1.0\n"
                    .to_string()
            }
        }
    }

    /// The scene, loaded and ready to simulate.
    ///
    /// # Errors
    /// Never for the built-in texts; the error type is the scene loader's.
    pub fn load(self) -> Result<(LoadedScene, crate::dynamics::Simulation), SceneError> {
        let name = PathBuf::from(format!("{}.toml", self.name()));
        let scene = Scene::parse(&self.scene_text(), crate::scene::SceneFormat::Toml, &name, PathBuf::new())?;
        let mut loaded = scene.load()?;
        let simulation = loaded.start_simulation()?;
        Ok((loaded, simulation))
    }
}

/// The contact benchmark scenarios (`shapeup bench --contact`, the `contact` criterion
/// group): each runs with and without its contact, 10 iterations per time step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactScenario {
    /// A 101 × 101 cloth (10,201 vertices, strain + bending) dropped on a sphere.
    ClothOnSphere,
    /// The same cloth dropped across a bar onto a floor, folding onto itself (self-collision).
    ClothFolding,
    /// A box of 12 × 6 × 12 cubes of tetrahedra dropped on a bumpy mesh terrain (41 × 41).
    BodyOnTerrain,
    /// Two 61 × 61 cloths, one above the other, dropped on a sphere (self-collision between them).
    StackedCloths,
}

impl ContactScenario {
    /// Every scenario, in table order.
    pub const ALL: [ContactScenario; 4] = [
        ContactScenario::ClothOnSphere,
        ContactScenario::ClothFolding,
        ContactScenario::BodyOnTerrain,
        ContactScenario::StackedCloths,
    ];

    /// Short name.
    pub fn name(self) -> &'static str {
        match self {
            ContactScenario::ClothOnSphere => "cloth-on-sphere",
            ContactScenario::ClothFolding => "cloth-folding",
            ContactScenario::BodyOnTerrain => "body-on-terrain",
            ContactScenario::StackedCloths => "stacked-cloths",
        }
    }

    /// The scene text; `contact` false leaves out its colliders and `[contact]` table (the
    /// same simulation with nothing to touch).
    fn scene_text(self, contact: bool, terrain: &std::path::Path) -> String {
        const CLOTH: &str = "[solver]\nmode = \"dynamic\"\niterations = 10\n\
             [[constraints]]\ntype = \"triangle_strain\"\nweight = 10.0\n\
             [[constraints]]\ntype = \"bending\"\nweight = 0.01\n";
        let (mesh, shape, touch) = match self {
            ContactScenario::ClothOnSphere => (
                "[mesh]\ngenerate = { kind = \"cloth\", vertices = [101, 101], size = [1.0, 1.0] }\nnormalize = false\n",
                CLOTH.to_string(),
                "[[colliders]]\ntype = \"sphere\"\ncenter = [0.0, -0.4, 0.0]\nradius = 0.3\nfriction = 0.3\n"
                    .to_string(),
            ),
            ContactScenario::ClothFolding => (
                "[mesh]\ngenerate = { kind = \"cloth\", vertices = [101, 101], size = [1.0, 1.0] }\nnormalize = false\n",
                CLOTH.to_string(),
                "[contact]\nself_collision = true\nthickness = 0.004\nfriction = 0.2\n\
                 [[colliders]]\ntype = \"capsule\"\na = [0.0, -0.1, -1.0]\nb = [0.0, -0.1, 1.0]\nradius = 0.04\n\
                 [[colliders]]\ntype = \"plane\"\npoint = [0.0, -0.3, 0.0]\nnormal = [0.0, 1.0, 0.0]\n"
                    .to_string(),
            ),
            ContactScenario::BodyOnTerrain => (
                "[mesh]\ngenerate = { kind = \"tet_box\", cells = [12, 6, 12], size = [0.4, 0.2, 0.4] }\nnormalize = false\n",
                "[solver]\nmode = \"dynamic\"\niterations = 10\nstiffness = 1000\n\
                 [[constraints]]\ntype = \"tet_strain\"\nweight = 1.0\n"
                    .to_string(),
                format!(
                    "[contact]\nthickness = 0.005\n[[colliders]]\ntype = \"mesh\"\npath = {:?}\nfriction = 0.3\n",
                    terrain.display().to_string()
                ),
            ),
            ContactScenario::StackedCloths => (
                "",
                CLOTH.to_string(),
                "[contact]\nself_collision = true\nthickness = 0.005\nfriction = 0.3\n\
                 [[colliders]]\ntype = \"sphere\"\ncenter = [0.0, -0.4, 0.0]\nradius = 0.3\nfriction = 0.3\n"
                    .to_string(),
            ),
        };
        let mesh = if mesh.is_empty() { "[mesh]\npath = \"stacked.obj\"\nnormalize = false\n" } else { mesh };
        if contact { format!("{mesh}{shape}{touch}") } else { format!("{mesh}{shape}") }
    }

    /// The scenario loaded and ready to simulate, with or without contact. The terrain and the
    /// stacked cloths are generated meshes written to a temporary folder (kept while the
    /// returned guard lives).
    ///
    /// # Errors
    /// Writing the temporary meshes, or the scene loader's (never for the built-in texts).
    pub fn load(
        self,
        contact: bool,
    ) -> Result<(LoadedScene, crate::dynamics::Simulation, tempfile::TempDir), SceneError> {
        let dir = tempfile::tempdir().map_err(|source| SceneError::Read { path: std::env::temp_dir(), source })?;
        let write = |name: &str, mesh: &Mesh| {
            let path = dir.path().join(name);
            crate::io::write_mesh(&path, mesh, &crate::io::Attributes::None)
                .map_err(|e| SceneError::Invalid { path: path.clone(), entry: "[mesh]".into(), message: e.to_string() })
                .map(|_| path)
        };
        let terrain = write("terrain.obj", &terrain_mesh(41))?;
        if self == ContactScenario::StackedCloths {
            write("stacked.obj", &stacked_cloths(61, 0.05))?;
        }
        let name = dir.path().join(format!("{}.toml", self.name()));
        let scene = Scene::parse(
            &self.scene_text(contact, &terrain),
            crate::scene::SceneFormat::Toml,
            &name,
            dir.path().to_path_buf(),
        )?;
        let mut loaded = scene.load()?;
        let simulation = loaded.start_simulation()?;
        Ok((loaded, simulation, dir))
    }
}

/// A bumpy terrain y = 0.05 sin(3x) cos(2z) − 0.3 over [−1, 1]², `n` × `n` vertices, normals up.
pub fn terrain_mesh(n: usize) -> Mesh {
    let mut mesh = crate::generate::cloth_grid(n, n, 2.0, 2.0);
    for p in &mut mesh.positions {
        p.y = 0.05 * (3.0 * p.x).sin() * (2.0 * p.z).cos() - 0.3;
    }
    mesh
}

/// Two `n` × `n` unit cloths, the second `gap` above the first, as one mesh.
pub fn stacked_cloths(n: usize, gap: f64) -> Mesh {
    let one = crate::generate::cloth_grid(n, n, 1.0, 1.0);
    let mut positions = one.positions.clone();
    positions.extend(one.positions.iter().map(|p| *p + glam::DVec3::new(0.0, gap, 0.0)));
    let offset = one.positions.len() as u32;
    let mut triangles = one.triangles.clone();
    triangles.extend(one.triangles.iter().map(|t| t.map(|v| v + offset)));
    Mesh::from_parts_unchecked(positions, triangles, Vec::new())
}
