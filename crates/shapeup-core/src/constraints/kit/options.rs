//! Options shared by several types: the strain band of the strain types and the range of the
//! ratio types (area, volume).

use crate::constraints::error::ConstraintError;
use crate::constraints::options::{OptionKind, OptionSpec};
use crate::constraints::params::Params;

/// Option: the strain freedom f ≥ 0.
pub(crate) const STRAIN_FREEDOM: &str = "strain_freedom";

/// Takes the `strain_freedom` option (a number ≥ 0, default 0) of a strain constraint type.
pub(crate) fn take_strain_freedom(kind: &'static str, params: &mut Params) -> Result<f64, ConstraintError> {
    Ok(params.number(kind, &STRAIN_FREEDOM_OPTION)?.unwrap_or(0.0))
}

/// `strain_freedom`: the band f of singular values [1 − f, 1 + f].
pub(crate) const STRAIN_FREEDOM_OPTION: OptionSpec = OptionSpec {
    key: STRAIN_FREEDOM,
    doc: "f ≥ 0: singular values of the deformation gradient stay in [1 − f, 1 + f]; default 0 (rigid)",
    kind: OptionKind::Number { default: Some(0.0), min: 0.0, max: f64::MAX },
};

/// Takes the options `min` and `max` of a range type (area, volume): numbers ≥ 0 with
/// min ≤ max, refused naming both keys otherwise.
pub(crate) fn take_range(
    kind: &'static str,
    params: &mut Params,
    min_spec: &OptionSpec,
    max_spec: &OptionSpec,
) -> Result<(f64, f64), ConstraintError> {
    let min = params.number(kind, min_spec)?.unwrap_or(1.0);
    let max = params.number(kind, max_spec)?.unwrap_or(1.0);
    if min > max {
        return Err(ConstraintError::Invalid {
            kind,
            problem: format!(
                "\"{}\" ({min}) is larger than \"{}\" ({max}); give both when moving the range past 1",
                min_spec.key, max_spec.key
            ),
        });
    }
    Ok((min, max))
}
