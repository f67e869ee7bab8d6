//! The solver's settings: [`SolverParams`], the [`Acceleration`] kinds and their limits.

use super::Factorization;

/// Solver settings, the one home of the iteration count and the tolerance: [`System::run`]
/// reads them. Each default is written once, here and in the scene contract.
///
/// [`System::run`]: super::System::run
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SolverParams {
    /// Local-global iterations per solve, or per time step in dynamic mode (default 10).
    pub iterations: usize,
    /// Stop early when the relative energy change of an iteration is below this (default 0: off).
    pub tolerance: f64,
    /// Factorization layout (default: chosen by faer).
    pub factorization: Factorization,
    /// How the local-global iterates are combined (default: L-BFGS).
    pub acceleration: Acceleration,
    /// Anderson acceleration: how many previous iterations are mixed, m (default 5).
    pub anderson_window: usize,
    /// L-BFGS: how many previous steps and gradient changes shape the Hessian estimate, m
    /// (default 5).
    pub lbfgs_memory: usize,
}

impl SolverParams {
    /// Whether iterations are accelerated (Anderson with a window, or L-BFGS with a memory, of
    /// at least 1).
    pub fn is_accelerated(&self) -> bool {
        match self.acceleration {
            Acceleration::None => false,
            Acceleration::Anderson => self.anderson_window > 0,
            Acceleration::Lbfgs => self.lbfgs_memory > 0,
        }
    }

    /// Whether a solve must evaluate E after each iteration: for the tolerance's test (when it is
    /// above 0) or the acceleration's safeguard. Otherwise the plain [`System::iterate`] does.
    ///
    /// [`System::iterate`]: super::System::iterate
    pub fn needs_energy(&self) -> bool {
        self.tolerance > 0.0 || self.is_accelerated()
    }
}

/// [`SolverParams::anderson_window`] by default: the m of Peng et al. 2018's experiments.
pub const DEFAULT_ANDERSON_WINDOW: usize = 5;

/// The largest [`SolverParams::anderson_window`] a scene may ask for: more mixed iterations
/// only cost time and conditioning.
pub const MAX_ANDERSON_WINDOW: usize = 50;

/// [`SolverParams::lbfgs_memory`] by default: the m of Liu, Bouaziz and Kavan 2017, and
/// within the 3–20 Nocedal and Wright recommend.
pub const DEFAULT_LBFGS_MEMORY: usize = 5;

/// The largest [`SolverParams::lbfgs_memory`] a scene may ask for: each pair costs four passes
/// over n points per iteration.
pub const MAX_LBFGS_MEMORY: usize = 50;

impl Default for SolverParams {
    fn default() -> Self {
        SolverParams {
            iterations: 10,
            tolerance: 0.0,
            factorization: Factorization::Auto,
            acceleration: Acceleration::default(),
            anderson_window: DEFAULT_ANDERSON_WINDOW,
            lbfgs_memory: DEFAULT_LBFGS_MEMORY,
        }
    }
}

/// How successive local-global iterates are combined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Acceleration {
    /// The plain iteration x_{k+1} = G(x_k): one local and one global step per iteration.
    None,
    /// Anderson acceleration (Peng, Deng, Zhang, Pauly, SIGGRAPH 2018): x_{k+1} mixes the last
    /// m iterates of G; a mixed iterate that does not lower the energy is replaced by the plain
    /// one (and the history restarts), so the energy never increases. An iteration costs one
    /// more energy evaluation, and a rejected one also a second local step.
    Anderson,
    /// L-BFGS with the global matrix as initial Hessian (Liu, Bouaziz, Kavan, ACM TOG 2017): the
    /// plain step is a gradient step preconditioned by the global matrix, and the last m
    /// iterates' gradients refine it into a quasi-Newton step; a step that misses the Armijo
    /// condition is replaced by the plain one (and the history restarts), so the energy never
    /// increases. An iteration costs one gradient (a right-hand-side pass) more than a plain
    /// one, and a rejected one a second solve and local step. The default: on the standard
    /// scenarios it reaches a converged shape in the fewest iterations and the least time (the
    /// README's performance section), and matches Anderson per time step in dynamic mode.
    #[default]
    Lbfgs,
}

impl Acceleration {
    /// Every kind, in the order the CLI and the editor list them.
    pub const ALL: [Acceleration; 3] = [Acceleration::Lbfgs, Acceleration::Anderson, Acceleration::None];

    /// The scene's and the CLI's name (`"anderson"`, `"lbfgs"`, `"none"`).
    pub fn name(self) -> &'static str {
        match self {
            Acceleration::None => "none",
            Acceleration::Anderson => "anderson",
            Acceleration::Lbfgs => "lbfgs",
        }
    }

    /// The kind named `name` ([`Acceleration::name`]).
    pub fn from_name(name: &str) -> Option<Acceleration> {
        Acceleration::ALL.into_iter().find(|a| a.name() == name)
    }
}
