//! Text as messages show it: one line, control characters escaped, long quotes cut, serde's
//! Rust type names in plain words. Every error message that quotes a file, a path or a scene
//! key goes through here.

/// `text` as an error message quotes it: its first 40 characters and `…` when longer (a
/// megabyte-long token must not make a megabyte-long message), control characters escaped as
/// Rust writes them (`\r`, `\u{1b}`) so that the message stays on one line and a terminal
/// shows what the file holds instead of obeying it.
pub(crate) fn shown(text: &str) -> std::borrow::Cow<'_, str> {
    let cut = text.char_indices().nth(SHOWN_CHARS).map(|(end, _)| end);
    let head = &text[..cut.unwrap_or(text.len())];
    if cut.is_none() && !head.contains(char::is_control) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(head.len() + 4);
    push_escaped(&mut out, head);
    if cut.is_some() {
        out.push('…');
    }
    std::borrow::Cow::Owned(out)
}

/// A number as a message shows it: plainly at ordinary magnitudes, in exponent form beyond
/// (1e300 would print as 301 digits).
pub(crate) fn number(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e7).contains(&v.abs()) { format!("{v}") } else { format!("{v:e}") }
}

/// A measured ratio to three significant digits, as a message shows it: 0.00123, 0.76, 859,
/// 1.23e7.
pub(crate) fn three_digits(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    if !(1e-3..1e6).contains(&v.abs()) {
        return format!("{v:.2e}");
    }
    let decimals = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}

/// Characters of a file's text that [`shown`] quotes.
const SHOWN_CHARS: usize = 40;

/// `text` (a message, a path) with control characters escaped as [`shown`] does: what an error
/// variant's message goes through, so that every error stays one line whatever a file, a scene
/// key or a file name holds.
pub fn one_line(text: impl std::fmt::Display) -> String {
    let text = text.to_string();
    if !text.contains(char::is_control) {
        return text;
    }
    let mut out = String::with_capacity(text.len() + 8);
    push_escaped(&mut out, &text);
    out
}

/// Appends `text` to `out`, each control character as its Rust escape (`\n`, `\u{1b}`).
fn push_escaped(out: &mut String, text: &str) {
    for c in text.chars() {
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
}

/// A value of an entry as a `T`, the error in the scene's words with the key inside it that is
/// wrong (`angle_deg: invalid type: string "x", expected a number`).
pub(crate) fn value_as<T: serde::de::DeserializeOwned>(value: serde_json::Value) -> Result<T, String> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let (path, words) = (e.path().to_string(), plain_words(&e.inner().to_string()));
        if path == "." { words } else { format!("{path}: {words}") }
    })
}

/// serde's words for Rust types in a message, in the scene's words: `expected usize` is
/// "expected a whole number ≥ 0", `expected f64` "expected a number", `expected struct
/// MeshSettings` "expected a [mesh] table".
pub(crate) fn plain_words(message: &str) -> String {
    const WORDS: [(&str, &str); 19] = [
        ("` as i128", "` (too large)"),
        (
            "expected internally tagged enum GeneratedMesh",
            "expected a table such as { kind = \"cloth\", vertices = [41, 41], size = [1.0, 1.0] }",
        ),
        ("expected variant identifier", "expected a name (a string)"),
        ("wanted string or table", "expected a name (a string)"),
        ("expected usize", "expected a whole number ≥ 0"),
        ("expected u64", "expected a whole number ≥ 0"),
        ("expected u32", "expected a whole number ≥ 0"),
        ("expected u8", "expected a whole number ≥ 0"),
        ("expected i64", "expected a whole number"),
        ("expected i32", "expected a whole number"),
        ("expected f64", "expected a number"),
        ("expected f32", "expected a number"),
        ("expected struct MeshSettings", "expected a [mesh] table"),
        ("expected struct SolverSettings", "expected a [solver] table"),
        ("expected struct OutputSettings", "expected an [output] table"),
        ("expected struct ContactSettings", "expected a [contact] table"),
        ("expected struct RawScene", "expected a scene (tables [mesh], [solver], …)"),
        ("expected a sequence", "expected a list"),
        ("expected a map", "expected a table"),
    ];
    let mut out = message.to_owned();
    for (rust, words) in WORDS {
        out = out.replace(rust, words);
    }
    // Any other struct's name: a table.
    while let Some(at) = out.find("expected struct ") {
        let end = out[at + 16..].find(|c: char| !c.is_alphanumeric()).map_or(out.len(), |e| at + 16 + e);
        out.replace_range(at..end, "expected a table");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_digits_keeps_three_significant_digits() {
        for (v, shown) in [(0.76, "0.760"), (859.23, "859"), (0.001234, "0.00123"), (12.345, "12.3"), (1.5e7, "1.50e7")]
        {
            assert_eq!(three_digits(v), shown);
        }
    }
}
