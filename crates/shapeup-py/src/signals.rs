//! Ctrl+C during long runs without the GIL: a check that takes the GIL for a moment to ask.

use pyo3::prelude::*;
use std::ops::ControlFlow;
use std::time::{Duration, Instant};

/// How often a long solve looks for Ctrl+C (it takes the GIL for a moment to ask).
pub(crate) const SIGNAL_CHECK: Duration = Duration::from_millis(50);

/// Asks Python for pending signals at most every [`SIGNAL_CHECK`], keeping the first error
/// (the `KeyboardInterrupt`) to return once the run has stopped.
pub(crate) struct Interrupt {
    last_check: Instant,
    /// The signal handler's error, once it raised.
    pub(crate) error: Option<PyErr>,
}

impl Interrupt {
    pub(crate) fn new() -> Self {
        Interrupt { last_check: Instant::now(), error: None }
    }

    /// `Break` when a signal handler raised (the error kept in [`Interrupt::error`]); to be
    /// called without the GIL, after each iteration or step.
    pub(crate) fn poll(&mut self) -> ControlFlow<()> {
        if self.last_check.elapsed() < SIGNAL_CHECK {
            return ControlFlow::Continue(());
        }
        self.last_check = Instant::now();
        match Python::attach(|py| py.check_signals()) {
            Ok(()) => ControlFlow::Continue(()),
            Err(e) => {
                self.error = Some(e);
                ControlFlow::Break(())
            }
        }
    }
}
