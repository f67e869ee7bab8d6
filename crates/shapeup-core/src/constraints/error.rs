//! [`ConstraintError`]: what goes wrong building constraints from a scene entry or the editor.

use super::options::OptionSpec;

/// "an" before a vowel ("an edge_spring", "an iso_one_ring"), else "a".
fn indefinite_article(word: &str) -> &'static str {
    if word.starts_with(['a', 'e', 'i', 'o', 'u']) { "an" } else { "a" }
}

/// An error building constraints from a scene entry or the editor.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConstraintError {
    /// No constraint type has this name.
    #[error("unknown constraint type \"{}\" (known: {})", crate::text::one_line(name), known.join(", "))]
    UnknownType {
        /// The name as written.
        name: String,
        /// Every registered name, in registry order (the error is built by the registry, which
        /// lies above this file).
        known: Vec<&'static str>,
    },
    /// An option that this constraint type does not take.
    #[error("unknown key \"{}\" for {article} {kind} constraint{hint}", crate::text::one_line(key), article = indefinite_article(kind), hint = hint_for(&allowed_hint(allowed)))]
    UnknownOption {
        /// Constraint type.
        kind: &'static str,
        /// The key as written.
        key: String,
        /// The keys it does take.
        allowed: &'static [OptionSpec],
    },
    /// An option with a value of the wrong type or out of range.
    #[error("{kind} option \"{}\": {}", crate::text::one_line(key), crate::text::one_line(problem))]
    BadOption {
        /// Constraint type.
        kind: &'static str,
        /// The key.
        key: String,
        /// What is wrong, and what is expected.
        problem: String,
    },
    /// The selection contains no element this type can constrain.
    #[error("the {kind} group selects no {element} (check its vertices, faces, box or sphere)")]
    NothingSelected {
        /// Constraint type.
        kind: &'static str,
        /// "vertices", "edges", "triangles", …
        element: &'static str,
    },
    /// A group that cannot be built as described (too few vertices, no face of the needed
    /// size, targets that do not match…).
    #[error("{kind}: {problem}")]
    Invalid {
        /// Constraint type.
        kind: &'static str,
        /// What is wrong.
        problem: String,
    },
}

fn allowed_hint(allowed: &[OptionSpec]) -> String {
    allowed.iter().map(|o| o.key).collect::<Vec<_>>().join(", ")
}

fn hint_for(list: &str) -> String {
    if list.is_empty() { " (it takes no options)".into() } else { format!(" (allowed: {list})") }
}
