//! The constraint contract: a term's rows, projection and weight ([`Constraint`]), and how a
//! type builds its terms on a selection ([`ConstraintType`], [`BuildContext`]).
//!
//! Rows are numbered from 0 inside a constraint: a constraint never learns where its rows land
//! in the global system (the assembler adds the offset and the weight).

use super::error::ConstraintError;
use super::options::OptionSpec;
use super::params::Params;
use super::selection::{Element, Selection};
use crate::geometry::{RestGeometry, WorkingFrame};
use glam::DVec3;
use std::any::Any;
use std::fmt::Debug;

/// One entry of a constraint's selection matrix C_i: `C[row, vertex] = coeff`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RowEntry {
    /// Row within the constraint, `0..num_rows()`.
    pub row: u32,
    /// Vertex index (column of C).
    pub vertex: u32,
    /// Coefficient.
    pub coeff: f64,
}

/// Collects the rows of C a constraint emits ([`Constraint::rows`]).
#[derive(Debug, Default, Clone)]
pub struct RowSink {
    /// Entries in emission order.
    pub entries: Vec<RowEntry>,
}

impl RowSink {
    /// Adds `C[row, vertex] += coeff`.
    pub fn push(&mut self, row: usize, vertex: u32, coeff: f64) {
        self.entries.push(RowEntry { row: row as u32, vertex, coeff });
    }
}

/// A constant load ([`Constraint::load`]): forces on vertices and the rest points their
/// potential is measured from (all working frame).
#[derive(Debug, Clone, Copy)]
pub struct Load<'a> {
    /// The vertices loaded.
    pub vertices: &'a [u32],
    /// The force on each (working frame).
    pub forces: &'a [DVec3],
    /// Each vertex's rest position x⁰_v.
    pub rest: &'a [DVec3],
}

impl Load<'_> {
    /// −2 Σ_v f_v · (q_v − x⁰_v): the load's share of E without the multiplier.
    pub fn energy(&self, q: &[DVec3]) -> f64 {
        let work: f64 =
            self.vertices.iter().zip(self.forces).zip(self.rest).map(|((&v, f), x0)| f.dot(q[v as usize] - *x0)).sum();
        -2.0 * work
    }
}

/// A constraint term `ω ‖C q − p(q)‖²_F` (the group multiplier g is applied by its group).
///
/// - `C q` is `num_rows()×3`: each row is a linear combination of vertex positions, given by
///   [`Constraint::rows`].
/// - `p(q)` is the closest point to `C q` on the constraint set, written by
///   [`Constraint::project`].
///
/// Implementations are immutable during a solve (`&self`): the local step projects all
/// constraints in parallel into disjoint slices of one buffer.
pub trait Constraint: Any + Send + Sync + Debug {
    /// The type's name, as in scene files (`"edge_spring"`, …).
    fn kind(&self) -> &'static str;
    /// The vertices the constraint reads (every column of its rows).
    fn vertices(&self) -> &[u32];
    /// The vertices this constraint pulls to points and those points, when it can hold them
    /// there exactly instead (a position handle): what a hard group fixes
    /// ([`ConstraintGroup::hard`](super::ConstraintGroup::hard)). `None` (the default):
    /// the constraint cannot be hard.
    fn held_points(&self) -> Option<(&[u32], &[DVec3])> {
        None
    }
    /// Moves the points [`Constraint::held_points`] gives (a handle's targets, working frame),
    /// one per held vertex; returns `false` (and changes nothing) for a constraint without
    /// targets or the wrong count. Only the projection may change, so the factorization stays
    /// valid.
    fn set_targets(&mut self, _targets: &[DVec3]) -> bool {
        false
    }
    /// A constant load instead of (or besides) a projective term: forces f_v on vertices v at
    /// rest points x⁰_v, adding −2 Σ_v f_v · (q_v − x⁰_v) to E (times the group multiplier),
    /// so that the global step's right-hand side gains Σ g f_v as in ShapeOp (math reference,
    /// "Forces"). `None` (the default): no load.
    fn load(&self) -> Option<Load<'_>> {
        None
    }
    /// The element weight ω_i (rest length, area, volume, … as in the math reference).
    fn element_weight(&self) -> f64;
    /// Number of rows k_i of C_i; fixed after construction.
    fn num_rows(&self) -> usize;
    /// Emits the rows of C_i, numbered `0..num_rows()`.
    fn rows(&self, sink: &mut RowSink);
    /// Writes the projection p_i(q) (`num_rows()` rows) into `out`.
    fn project(&self, q: &[DVec3], out: &mut [DVec3]);
    /// How far `p` (`num_rows()` rows, as [`Constraint::project`] writes them) is from the
    /// constraint set, in the rows' units: 0 on the set. The shared test suite checks every
    /// projection with it (`tests/catalogue.rs`).
    fn set_residual(&self, p: &[DVec3]) -> f64;
    /// The error a report gives for `C q` (`num_rows()` rows), in the rows' units: by default
    /// [`Constraint::set_residual`]; a type whose field measures its error otherwise (plane:
    /// the largest distance of a corner from the best-fit plane) says so here.
    fn violation(&self, cq: &[DVec3]) -> f64 {
        self.set_residual(cq)
    }
    /// The unit of the rows (and of [`Constraint::violation`]) as a power of length: 1, a
    /// length, by default (edges, positions, fits to planes and spheres); 0 for rows that are a
    /// deformation gradient (strain, area, volume: a ratio); −1 for a mean-curvature normal
    /// (bending, smoothing). Reports divide the violation by the mean edge length to this power,
    /// so that it is scale-free for every type.
    fn length_power(&self) -> i32 {
        1
    }

    /// Whether the term is `ω ‖C q − p(q)‖²` with p a closest point (`true`, the default).
    /// A term that is not (a hyperelastic material, [`crate::materials`]) gives its energy from
    /// C q in [`Constraint::energy_from_rows`], and its [`Constraint::project`] writes the point
    /// p that makes ω (C q − p) half its energy's gradient with respect to C q; the solver then
    /// minimizes with a line search, since a plain local-global step no longer lowers E.
    fn is_projective(&self) -> bool {
        true
    }
    /// The energy of a term that is not projective ([`Constraint::is_projective`]) at
    /// `cq` = C q (`num_rows()` rows), without the group multiplier; `None` (the default) for a
    /// projective term, whose energy is ω ‖C q − p(q)‖².
    fn energy_from_rows(&self, _cq: &[DVec3]) -> Option<f64> {
        None
    }

    /// `C_i q`, computed from [`Constraint::rows`] (for tests and diagnostics, not the solver's
    /// hot path, which uses the assembled matrix).
    fn apply(&self, q: &[DVec3]) -> Vec<DVec3> {
        let mut sink = RowSink::default();
        self.rows(&mut sink);
        let mut cq = vec![DVec3::ZERO; self.num_rows()];
        for e in &sink.entries {
            cq[e.row as usize] += e.coeff * q[e.vertex as usize];
        }
        cq
    }

    /// The term's energy without the group multiplier: ω ‖C q − p(q)‖², or
    /// [`Constraint::energy_from_rows`] for a term that is not projective.
    fn energy(&self, q: &[DVec3]) -> f64 {
        let cq = self.apply(q);
        if let Some(energy) = self.energy_from_rows(&cq) {
            return energy;
        }
        let mut p = vec![DVec3::ZERO; self.num_rows()];
        self.project(q, &mut p);
        self.element_weight() * cq.iter().zip(&p).map(|(a, b)| (*a - *b).length_squared()).sum::<f64>()
    }
}

/// What a [`ConstraintType`] needs to build constraints.
#[derive(Debug, Clone, Copy)]
pub struct BuildContext<'a> {
    /// Rest shape (working frame) with its topology and rest quantities.
    pub rest: &'a RestGeometry,
    /// The vertices the group applies to.
    pub selection: &'a Selection,
    /// The working frame, to convert options given in input units (e.g. a floor height).
    pub frame: &'a WorkingFrame,
}

/// A constraint type's static description, one `const` in its file: what scenes, menus, the
/// catalogue and the shared tests read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TypeInfo {
    /// Name used in scene files and the editor (`"edge_spring"`).
    pub name: &'static str,
    /// One line for menus and `--help`.
    pub summary: &'static str,
    /// The options [`ConstraintType::build`] takes (besides the common ones: selection,
    /// weight, name, hard, targets), with their ranges and defaults.
    pub options: &'static [OptionSpec],
    /// The elements it builds constraints on.
    pub element: Element,
    /// The editor's default group multiplier g (math reference, "Notes").
    pub default_multiplier: f64,
    /// Whether its constraints have targets a scene or the editor moves
    /// ([`Constraint::set_targets`]): the group takes `translate`, `rotate`, `targets` and
    /// `spin`, and the editor treats it as a handle.
    pub has_targets: bool,
    /// Whether moving the input rigidly (and turning its vector options with it) moves the
    /// result the same way; `false` only for types tied to the world frame (a floor at y = h).
    /// The shared tests check it.
    pub rigidly_invariant: bool,
}

/// A kind of constraint as users see it: its description ([`TypeInfo`]) and how to build its
/// constraints on a selection. The other methods read [`ConstraintType::info`].
pub trait ConstraintType: Sync {
    /// The type's static description.
    fn info(&self) -> &'static TypeInfo;
    /// Builds this type's constraints on `ctx.selection`, taking its options from `params`.
    ///
    /// # Errors
    /// [`ConstraintError`] for a bad option or a selection with nothing to constrain.
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError>;

    /// [`TypeInfo::name`].
    fn name(&self) -> &'static str {
        self.info().name
    }
    /// [`TypeInfo::summary`].
    fn summary(&self) -> &'static str {
        self.info().summary
    }
    /// [`TypeInfo::options`].
    fn options(&self) -> &'static [OptionSpec] {
        self.info().options
    }
    /// [`TypeInfo::element`].
    fn element(&self) -> Element {
        self.info().element
    }
    /// [`TypeInfo::has_targets`].
    fn has_targets(&self) -> bool {
        self.info().has_targets
    }
    /// [`TypeInfo::rigidly_invariant`].
    fn is_rigidly_invariant(&self) -> bool {
        self.info().rigidly_invariant
    }
    /// [`TypeInfo::default_multiplier`].
    fn default_multiplier(&self) -> f64 {
        self.info().default_multiplier
    }
}
