//! Text as messages show it: one line, control characters escaped, long quotes cut. Every
//! error message that quotes a file, a path or a scene key goes through here.

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
