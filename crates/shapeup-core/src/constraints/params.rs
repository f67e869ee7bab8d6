//! [`Params`]: a group's type-specific options, taken one by one by the builder.

use super::error::ConstraintError;
use super::options::{OptionKind, OptionSpec, fmt_bound};
use glam::DVec3;

/// Type-specific options of a constraint group (e.g. `strain_freedom`), taken one by one by the
/// builder; whatever is left is reported as an unknown key.
#[derive(Debug, Clone, Default)]
pub struct Params {
    map: serde_json::Map<String, serde_json::Value>,
}

impl Params {
    /// Options from a JSON object (scene entries are converted to JSON values first).
    pub fn new(map: serde_json::Map<String, serde_json::Value>) -> Self {
        Params { map }
    }

    /// Sets an option (used by the editor and tests).
    pub fn with(mut self, key: &str, value: impl Into<serde_json::Value>) -> Self {
        self.map.insert(key.to_string(), value.into());
        self
    }

    /// Takes a boolean option, or `default` when absent.
    ///
    /// # Errors
    /// [`ConstraintError::BadOption`] if the value is not a boolean.
    pub fn take_bool(&mut self, kind: &'static str, key: &str, default: bool) -> Result<bool, ConstraintError> {
        match self.map.remove(key) {
            None => Ok(default),
            Some(v) => v.as_bool().ok_or_else(|| ConstraintError::BadOption {
                kind,
                key: key.into(),
                problem: format!("expected true or false, found {v}"),
            }),
        }
    }

    /// Takes a number option as `spec` describes it: its default when absent (`None` for a
    /// default from the rest shape), else a finite number within its range.
    ///
    /// # Errors
    /// [`ConstraintError::BadOption`] naming the key, for a value that is not a number or is
    /// out of range.
    pub fn number(&mut self, kind: &'static str, spec: &OptionSpec) -> Result<Option<f64>, ConstraintError> {
        let OptionKind::Number { default, min, max } = spec.kind else {
            return Err(ConstraintError::BadOption {
                kind,
                key: spec.key.into(),
                problem: "is not a number option".into(),
            });
        };
        let bad = |problem: String| ConstraintError::BadOption { kind, key: spec.key.into(), problem };
        match self.map.remove(spec.key) {
            None => Ok(default),
            Some(v) => {
                let x =
                    v.as_f64().filter(|x| x.is_finite()).ok_or_else(|| bad(format!("expected a number, found {v}")))?;
                if (min..=max).contains(&x) {
                    Ok(Some(x))
                } else {
                    Err(bad(format!("must be in [{}, {}], found {x}", fmt_bound(min), fmt_bound(max))))
                }
            }
        }
    }

    /// Takes a boolean option as `spec` describes it.
    ///
    /// # Errors
    /// [`ConstraintError::BadOption`] naming the key.
    pub fn flag(&mut self, kind: &'static str, spec: &OptionSpec) -> Result<bool, ConstraintError> {
        let default = match spec.kind {
            OptionKind::Bool { default } => default,
            _ => false,
        };
        self.take_bool(kind, spec.key, default)
    }

    /// Takes a vector option `[x, y, z]` as `spec` describes it.
    ///
    /// # Errors
    /// [`ConstraintError::BadOption`] naming the key, for anything but three finite numbers.
    pub fn vector(&mut self, kind: &'static str, spec: &OptionSpec) -> Result<DVec3, ConstraintError> {
        let default = match spec.kind {
            OptionKind::Vector { default } => default,
            _ => [0.0; 3],
        };
        match self.map.remove(spec.key) {
            None => Ok(DVec3::from(default)),
            Some(v) => serde_json::from_value::<[f64; 3]>(v.clone())
                .ok()
                .filter(|a| a.iter().all(|x| x.is_finite()))
                .map(DVec3::from)
                .ok_or_else(|| ConstraintError::BadOption {
                    kind,
                    key: spec.key.into(),
                    problem: format!("expected three finite numbers [x, y, z], found {v}"),
                }),
        }
    }

    /// Fails on the first option nobody took.
    ///
    /// # Errors
    /// [`ConstraintError::UnknownOption`] naming the key.
    pub fn finish(self, kind: &'static str, allowed: &'static [OptionSpec]) -> Result<(), ConstraintError> {
        match self.map.into_iter().next() {
            None => Ok(()),
            Some((key, _)) => Err(ConstraintError::UnknownOption { kind, key, allowed }),
        }
    }

    /// Whether no option is left.
    pub fn is_empty(&self) -> bool {
        self.map.is_empty()
    }
}
