//! OBJ's physical lines: raw bytes with their line numbers ([`RawLines`]), a text view with the
//! same byte offsets ([`text_view`]), and tokens split at blanks, `\` continuations and `#`
//! comments ([`token_spans`]).

use std::io::{self, BufRead};
use std::ops::Range;

use crate::io::UTF8_BOM;

/// Physical lines of a file as bytes without their endings, remembering what the writer needs to
/// reproduce the file: a byte-order mark, the ending style and whether the last line has one.
pub(super) struct RawLines<R> {
    reader: R,
    bytes: Vec<u8>,
    number: usize,
    pub(super) bom: bool,
    /// Whether the first line ending is `\r\n` (`None` until a line ending was read).
    pub(super) crlf: Option<bool>,
    pub(super) final_newline: bool,
}

impl<R: BufRead> RawLines<R> {
    pub(super) fn new(reader: R) -> Self {
        Self { reader, bytes: Vec::new(), number: 0, bom: false, crlf: None, final_newline: false }
    }

    /// The next line's 1-based number and bytes, or `None` at the end of the file.
    pub(super) fn next_line(&mut self) -> io::Result<Option<(usize, &[u8])>> {
        self.bytes.clear();
        if self.reader.read_until(b'\n', &mut self.bytes)? == 0 {
            return Ok(None);
        }
        self.number += 1;
        if self.number == 1 && self.bytes.starts_with(UTF8_BOM) {
            self.bom = true;
            self.bytes.drain(..UTF8_BOM.len());
        }
        self.final_newline = self.bytes.last() == Some(&b'\n');
        if self.final_newline {
            self.bytes.pop();
            let cr = self.bytes.last() == Some(&b'\r');
            // Every `\r` before the `\n` is part of the line ending (files that went through
            // two CRLF conversions end lines in `\r\r\n`): the line is written back with the
            // file's one ending, so a kept `\r` would not read back the same.
            while self.bytes.last() == Some(&b'\r') {
                self.bytes.pop();
            }
            self.crlf.get_or_insert(cr);
        }
        Ok(Some((self.number, &self.bytes)))
    }
}

/// `bytes` as text to parse: themselves when they are UTF-8, else a copy in `replaced` with each
/// byte that is not part of a UTF-8 character replaced by `?`. Either way byte offsets are those
/// of `bytes` (so a token's range is also its range in the file's line), and the keywords,
/// numbers and indices that are parsed (ASCII) are unaffected.
pub(super) fn text_view<'a>(bytes: &'a [u8], replaced: &'a mut String) -> &'a str {
    match std::str::from_utf8(bytes) {
        Ok(text) => text,
        Err(_) => {
            replaced.clear();
            for chunk in bytes.utf8_chunks() {
                replaced.push_str(chunk.valid());
                replaced.extend(std::iter::repeat_n('?', chunk.invalid().len()));
            }
            replaced
        }
    }
}

/// Byte ranges of the tokens of a logical line (physical lines joined by `\n`): runs of
/// characters between whitespace and continuation backslashes (a `\` with only blanks after it
/// on its physical line), up to a `#` comment. Ranges into the raw text let a `v` line keep what
/// follows its z coordinate exactly as written.
pub(super) fn token_spans(raw: &str) -> Vec<Range<usize>> {
    let mut spans = Vec::new();
    let mut start = None;
    // Each physical line is looked at once for its continuation, so a line of many backslashes
    // stays linear.
    let mut continuation = continuation_at(raw, 0);
    for (i, c) in raw.char_indices() {
        if c == '\n' {
            continuation = continuation_at(raw, i + 1);
        }
        if c == '#' || c.is_whitespace() || (c == '\\' && continuation == Some(i)) {
            if let Some(s) = start.take() {
                spans.push(s..i);
            }
            if c == '#' {
                return spans;
            }
        } else if start.is_none() {
            start = Some(i);
        }
    }
    if let Some(s) = start {
        spans.push(s..raw.len());
    }
    spans
}

/// The byte offset of the continuation backslash of the physical line that starts at `from` in
/// `raw` (its last character before trailing blanks), if it ends in one.
pub(super) fn continuation_at(raw: &str, from: usize) -> Option<usize> {
    let line = raw.get(from..)?.split('\n').next()?.trim_end();
    line.ends_with('\\').then(|| from + line.len() - 1)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn tokens_split_at_blanks_continuations_and_comments() {
        let raw = "v 1\t2 \\\n 3 0.5# c \\ d";
        let tokens: Vec<&str> = token_spans(raw).into_iter().map(|r| &raw[r]).collect();
        assert_eq!(tokens, ["v", "1", "2", "3", "0.5"]);
        let raw = "f a\\b \\\\  ";
        let tokens: Vec<&str> = token_spans(raw).into_iter().map(|r| &raw[r]).collect();
        assert_eq!(tokens, ["f", "a\\b", "\\"], "only a backslash ending its line continues it");
    }

    #[test]
    fn text_view_keeps_byte_offsets() {
        let mut replaced = String::new();
        assert_eq!(text_view("v 1 é".as_bytes(), &mut replaced), "v 1 é");
        let bytes = b"g caf\xe9 \xff\xfe x";
        let view = text_view(bytes, &mut replaced);
        assert_eq!(view, "g caf? ?? x");
        assert_eq!(view.len(), bytes.len());
    }
}
