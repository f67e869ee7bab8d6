//! Random small meshes for the property tests (proptest strategies): a grid of wavy quads or a
//! box of tetrahedra, jittered, with degenerate elements (coincident and collinear points, flat
//! and collapsed configurations), inverted ones (faces and tetrahedra flipped at rest, mirrored
//! current shapes), at scales from 1e-12 to 1e12 and far from the origin; and a current
//! configuration q of the same vertices, deformed from the rest shape the same ways.

use glam::{DQuat, DVec3};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use shapeup_core::geometry::RestGeometry;
use shapeup_core::mesh::Polygons;

/// Most vertices a base has (a 2×2×2 box of cubes: 27); noise vectors are this long.
pub const MAX_VERTICES: usize = 27;

/// What the random mesh starts from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Base {
    /// An `nx` × `ny` grid of quads on the wavy surface of [`super::wavy`], one unit across;
    /// triangles are the quads' fans.
    Quads {
        /// Quads along x.
        nx: u32,
        /// Quads along y.
        ny: u32,
    },
    /// A box of `cells` cubes of side 1 in all, six tetrahedra each; triangles are its boundary.
    Tets {
        /// Cubes along x, y, z.
        cells: [usize; 3],
    },
}

/// A change that makes a configuration degenerate or inverted (unit coordinates). Vertex numbers
/// are taken modulo the vertex count.
#[derive(Debug, Clone)]
pub enum Degeneration {
    /// Vertex i moved onto vertex j: coincident points, a zero-length edge.
    Coincide(usize, usize),
    /// Vertex i moved onto the line through j and k, at parameter t: collinear points,
    /// zero-area triangles, flat tetrahedra.
    Collinear(usize, usize, usize, f64),
    /// Every vertex onto the plane `axis` = 0.
    Flatten(usize),
    /// Every vertex onto the line along `axis`.
    OntoLine(usize),
    /// Every vertex at the origin.
    Collapse,
    /// x → −x: every element inverted.
    Mirror,
}

/// A configuration: noise of a given amplitude on every vertex, then degenerations.
#[derive(Clone)]
pub struct Shape {
    /// Amplitude of the noise (unit coordinates).
    pub amplitude: f64,
    /// Noise in [-1, 1]³ per vertex (the first n are used).
    pub noise: Vec<[f64; 3]>,
    /// Applied in order after the noise.
    pub degenerations: Vec<Degeneration>,
}

impl std::fmt::Debug for Shape {
    /// One line, listing only the vertices with noise.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let noisy: Vec<(usize, [f64; 3])> =
            self.noise.iter().copied().enumerate().filter(|(_, e)| e.iter().any(|x| *x != 0.0)).collect();
        write!(
            f,
            "Shape {{ amplitude: {:?}, noise (vertex, value): {:?}, degenerations: {:?} }}",
            self.amplitude, noisy, self.degenerations
        )
    }
}

impl Shape {
    /// No noise, and the given degenerations.
    pub fn still(degenerations: Vec<Degeneration>) -> Self {
        Shape { amplitude: 0.0, noise: vec![[0.0; 3]; MAX_VERTICES], degenerations }
    }

    /// Noise of `amplitude` on the listed vertices (vertex, value) only, then `degenerations`.
    pub fn noisy(amplitude: f64, noise: &[(usize, [f64; 3])], degenerations: Vec<Degeneration>) -> Self {
        let mut shape = Shape { amplitude, ..Shape::still(degenerations) };
        for &(v, e) in noise {
            shape.noise[v] = e;
        }
        shape
    }

    fn apply(&self, positions: &mut [DVec3]) {
        let n = positions.len();
        for (p, e) in positions.iter_mut().zip(&self.noise) {
            *p += self.amplitude * DVec3::from(*e);
        }
        for d in &self.degenerations {
            match *d {
                Degeneration::Coincide(i, j) => positions[i % n] = positions[j % n],
                Degeneration::Collinear(i, j, k, t) => {
                    let (a, b) = (positions[j % n], positions[k % n]);
                    positions[i % n] = a + t * (b - a);
                }
                Degeneration::Flatten(axis) => positions.iter_mut().for_each(|p| p[axis] = 0.0),
                Degeneration::OntoLine(axis) => positions.iter_mut().for_each(|p| {
                    let x = p[axis];
                    *p = DVec3::ZERO;
                    p[axis] = x;
                }),
                Degeneration::Collapse => positions.iter_mut().for_each(|p| *p = DVec3::ZERO),
                Degeneration::Mirror => positions.iter_mut().for_each(|p| p.x = -p.x),
            }
        }
    }

    /// Whether it is well-conditioned and free of symmetries: no degeneration, noise of
    /// moderate amplitude that moves every vertex (the base grids are symmetric, and nearest
    /// points of symmetric input tie: a cube's best-fit line).
    pub fn is_generic(&self) -> bool {
        self.degenerations.is_empty()
            && (0.02..=0.3).contains(&self.amplitude)
            && self.noise.iter().all(|e| DVec3::from(*e).length() >= 0.05)
    }
}

/// A random mesh with a rest shape and a current configuration q.
#[derive(Debug, Clone)]
pub struct MeshCase {
    /// The base mesh.
    pub base: Base,
    /// Faces (quads) or tetrahedra inverted at rest: corners reversed, or two swapped (numbers
    /// taken modulo the element count).
    pub flips: Vec<usize>,
    /// The rest shape, from the base.
    pub rest: Shape,
    /// The current configuration, from the rest shape (unit coordinates).
    pub current: Shape,
    /// q's stretch about its centroid (1: as deformed; 1e12: a huge stretch; 0: collapsed).
    pub stretch: f64,
    /// Size of the whole: coordinates are `scale` × unit coordinates + offset.
    pub scale: f64,
    /// Offset direction (unit coordinates).
    pub offset: [f64; 3],
    /// The offset's distance from the origin in units of `scale`.
    pub distance: f64,
}

/// A realized case: the rest geometry (working frame = identity) and q.
#[derive(Debug, Clone)]
pub struct Realized {
    /// Rest shape, topology and rest quantities.
    pub rest: RestGeometry,
    /// The current configuration.
    pub q: Vec<DVec3>,
}

/// A base mesh in unit coordinates.
struct BaseMesh {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    tetrahedra: Vec<[u32; 4]>,
    /// The quads, for a grid (the rest geometry's faces).
    polygons: Option<Polygons>,
}

impl MeshCase {
    /// The base with its flips, in unit coordinates.
    fn base_mesh(&self) -> BaseMesh {
        match self.base {
            Base::Quads { nx, ny } => {
                let mut positions = Vec::new();
                for j in 0..=ny {
                    for i in 0..=nx {
                        positions.push(super::wavy(i as f64 / nx as f64 - 0.5, j as f64 / ny as f64 - 0.5));
                    }
                }
                let at = |i: u32, j: u32| j * (nx + 1) + i;
                let mut quads: Vec<[u32; 4]> = Vec::new();
                for j in 0..ny {
                    for i in 0..nx {
                        quads.push([at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
                    }
                }
                let n = quads.len();
                for f in &self.flips {
                    quads[f % n].reverse();
                }
                let mut polygons = Polygons::new();
                let mut triangles = Vec::new();
                for q in &quads {
                    polygons.push(q);
                    triangles.push([q[0], q[1], q[2]]);
                    triangles.push([q[0], q[2], q[3]]);
                }
                BaseMesh { positions, triangles, tetrahedra: Vec::new(), polygons: Some(polygons) }
            }
            Base::Tets { cells } => {
                let mesh = shapeup_core::generate::tet_box(cells, DVec3::ONE);
                let mut tets = mesh.tetrahedra.clone();
                let n = tets.len();
                for f in &self.flips {
                    tets[f % n].swap(0, 1);
                }
                BaseMesh { positions: mesh.positions, triangles: mesh.triangles, tetrahedra: tets, polygons: None }
            }
        }
    }

    /// `base` at rest and as q, without noise, flips, stretch or offset, one unit across.
    pub fn still(base: Base) -> Self {
        MeshCase {
            base,
            flips: Vec::new(),
            rest: Shape::still(Vec::new()),
            current: Shape::still(Vec::new()),
            stretch: 1.0,
            scale: 1.0,
            offset: [0.0; 3],
            distance: 0.0,
        }
    }

    /// Whether rest and q are well-conditioned: no degeneration, no flip, moderate noise, q not
    /// stretched, an offset that costs few digits. Rigid motions then move projections exactly
    /// (up to round-off); on other inputs nearest points may tie.
    pub fn is_generic(&self) -> bool {
        self.rest.is_generic()
            && self.current.is_generic()
            && self.flips.is_empty()
            && self.stretch == 1.0
            && self.distance <= 1e4
    }

    /// The rest geometry and q, in unit coordinates times `scale` plus the offset, moved by
    /// `motion` (turn, then shift in units of `scale`).
    pub fn realize_moved(&self, turn: DQuat, shift: DVec3) -> Realized {
        let BaseMesh { positions: mut unit, triangles, tetrahedra, polygons } = self.base_mesh();
        self.rest.apply(&mut unit);
        let mut current = unit.clone();
        self.current.apply(&mut current);
        let centroid = current.iter().copied().sum::<DVec3>() / current.len() as f64;
        current.iter_mut().for_each(|p| *p = centroid + self.stretch * (*p - centroid));
        let offset = DVec3::from(self.offset) * self.distance;
        let place = |p: DVec3| turn * ((p + offset) * self.scale) + shift * self.scale;
        let mut rest = RestGeometry::new(unit.into_iter().map(place).collect(), triangles, tetrahedra);
        if let Some(polygons) = polygons {
            rest.faces = polygons;
        }
        Realized { rest, q: current.into_iter().map(place).collect() }
    }

    /// [`MeshCase::realize_moved`] without a motion.
    pub fn realize(&self) -> Realized {
        self.realize_moved(DQuat::IDENTITY, DVec3::ZERO)
    }
}

fn base() -> impl Strategy<Value = Base> {
    prop_oneof![
        3 => (1u32..=3, 1u32..=3).prop_map(|(nx, ny)| Base::Quads { nx, ny }),
        2 => (1usize..=2, 1usize..=2, 1usize..=2).prop_map(|(x, y, z)| Base::Tets { cells: [x, y, z] }),
    ]
}

/// A vertex number (modulo the vertex count where the base has fewer).
pub fn vertex() -> impl Strategy<Value = usize> {
    0..MAX_VERTICES
}

fn degeneration() -> impl Strategy<Value = Degeneration> {
    prop_oneof![
        4 => (vertex(), vertex()).prop_map(|(i, j)| Degeneration::Coincide(i, j)),
        4 => (vertex(), vertex(), vertex(), -1.0..2.0f64)
            .prop_map(|(i, j, k, t)| Degeneration::Collinear(i, j, k, t)),
        1 => (0usize..3).prop_map(Degeneration::Flatten),
        1 => (0usize..3).prop_map(Degeneration::OntoLine),
        1 => Just(Degeneration::Collapse),
        1 => Just(Degeneration::Mirror),
    ]
}

fn noise() -> impl Strategy<Value = Vec<[f64; 3]>> {
    prop::collection::vec(prop::array::uniform3(-1.0..1.0f64), MAX_VERTICES)
}

/// A configuration: mostly generic, sometimes wild noise or degenerations.
pub fn shape(max_amplitude: f64) -> impl Strategy<Value = Shape> {
    let amplitude = prop_oneof![3 => 0.0..0.3f64, 1 => 0.0..max_amplitude];
    let degenerations = prop_oneof![2 => Just(Vec::new()), 1 => prop::collection::vec(degeneration(), 1..4)];
    (amplitude, noise(), degenerations).prop_map(|(amplitude, noise, degenerations)| Shape {
        amplitude,
        noise,
        degenerations,
    })
}

/// Sizes from tiny to huge (shrinking goes to the first, 1).
pub fn magnitude() -> impl Strategy<Value = f64> {
    prop::sample::select(vec![1.0, 1e-12, 1e-6, 1e6, 1e12])
}

/// A random mesh case: rest noise up to 0.5, q noise up to 3 (tangled), flips, stretches, any
/// scale and offset.
pub fn mesh_case() -> impl Strategy<Value = MeshCase> {
    // A 2×2×2 box has 48 tetrahedra.
    let flips = prop_oneof![3 => Just(Vec::new()), 1 => prop::collection::vec(0usize..48, 1..3)];
    let stretch = prop_oneof![6 => Just(1.0), 1 => prop::sample::select(vec![0.0, 1e-12, 1e-6, 1e6, 1e12])];
    let distance = prop::sample::select(vec![0.0, 1.0, 1e4, 1e8]);
    (base(), flips, shape(0.5), shape(3.0), stretch, magnitude(), prop::array::uniform3(-1.0..1.0f64), distance)
        .prop_map(|(base, flips, rest, current, stretch, scale, offset, distance)| MeshCase {
            base,
            flips,
            rest,
            current,
            stretch,
            scale,
            offset,
            distance,
        })
}

/// A rigid motion: a turn about a random axis and a shift (units of the case's scale).
pub fn motion() -> impl Strategy<Value = (DQuat, DVec3)> {
    (prop::array::uniform3(-1.0..1.0f64), -3.2..3.2f64, prop::array::uniform3(-2.0..2.0f64)).prop_map(
        |(axis, angle, shift)| {
            let axis = DVec3::from(axis).try_normalize().unwrap_or(DVec3::X);
            (DQuat::from_axis_angle(axis, angle), DVec3::from(shift))
        },
    )
}

/// Seed of the property tests' runs: the same cases on every run and machine.
pub const SEED: u64 = 0x13_5eed;

/// `cases` per property and the fixed [`SEED`] (PROPTEST_CASES and PROPTEST_RNG_SEED override
/// them, for longer or other runs); failures are not persisted (no proptest-regressions/ files:
/// the cases they found are kept as plain tests).
pub fn config(cases: u32) -> Config {
    let defaults = Config::default(); // reads PROPTEST_CASES and PROPTEST_RNG_SEED
    let cases = if std::env::var_os("PROPTEST_CASES").is_some() { defaults.cases } else { cases };
    let rng_seed =
        if std::env::var_os("PROPTEST_RNG_SEED").is_some() { defaults.rng_seed } else { RngSeed::Fixed(SEED) };
    Config { cases, rng_seed, failure_persistence: None, ..defaults }
}
