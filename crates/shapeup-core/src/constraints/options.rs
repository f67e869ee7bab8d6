//! The options a constraint type takes, as data: key, meaning, value type, range, default.
//! Scenes, the editor's widgets, the catalogue and the shared tests all read them.

/// What an option of a constraint type takes, and its default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OptionKind {
    /// A finite number in [`min`, `max`]; `default` `None` means the value comes from the rest
    /// shape (the option's doc says how).
    Number {
        /// Default, or `None` for "from the rest shape".
        default: Option<f64>,
        /// Smallest value allowed.
        min: f64,
        /// Largest value allowed.
        max: f64,
    },
    /// `true` or `false`.
    Bool {
        /// Default.
        default: bool,
    },
    /// Three finite numbers `[x, y, z]`.
    Vector {
        /// Default.
        default: [f64; 3],
    },
}

/// One option of a constraint type: its scene key, what it means, what it takes. Scenes,
/// the editor's widgets and the shared tests all read it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OptionSpec {
    /// Scene key.
    pub key: &'static str,
    /// One line: meaning, units, default.
    pub doc: &'static str,
    /// Value type, range and default.
    pub kind: OptionKind,
}

/// One option as [`catalogue_markdown`](super::catalogue_markdown) lists it: `key = default` and its range.
pub fn option_markdown(o: &OptionSpec) -> String {
    match o.kind {
        OptionKind::Number { default, min, max } => {
            let d = default.map_or("rest".to_string(), |d| format!("{d}"));
            let range = match (min > -f64::MAX, max < f64::MAX) {
                (true, true) => format!(" in [{}, {}]", fmt_bound(min), fmt_bound(max)),
                (true, false) => format!(" ≥ {}", fmt_bound(min)),
                (false, true) => format!(" ≤ {}", fmt_bound(max)),
                (false, false) => String::new(),
            };
            format!("`{}` = {d}{range}", o.key)
        }
        OptionKind::Bool { default } => format!("`{}` = {default}", o.key),
        OptionKind::Vector { default } => format!("`{}` = [{}, {}, {}]", o.key, default[0], default[1], default[2]),
    }
}

/// A range bound for messages: π for 3.14159…, else the number.
pub(crate) fn fmt_bound(x: f64) -> String {
    if x == std::f64::consts::PI {
        "π".into()
    } else if x == f64::MAX {
        "∞".into()
    } else {
        format!("{x}")
    }
}
