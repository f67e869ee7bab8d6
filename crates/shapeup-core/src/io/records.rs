//! Line records of a text file: its non-blank lines, trimmed, comments removed, with errors that
//! name the file and line (the ASCII MSH and TetGen readers').

use std::io::BufRead;
use std::path::Path;
use std::str::SplitWhitespace;

use super::{IoError, Lines, read_error, shown};

/// The non-blank lines of a text file, trimmed, with `comment` and what follows it removed, and
/// errors that name the file and line (the ASCII MSH and TetGen readers').
pub(super) struct Records<'p, R> {
    pub(super) lines: Lines<R>,
    path: &'p Path,
    comment: Option<char>,
    text: String,
    /// 1-based number of the current line.
    pub(super) line: usize,
}

impl<'p, R> Records<'p, R> {
    /// The current line's text.
    pub(super) fn text(&self) -> &str {
        &self.text
    }

    /// The current line's tokens.
    pub(super) fn tokens(&self) -> SplitWhitespace<'_> {
        self.text.split_whitespace()
    }

    /// A parse error at the current line.
    pub(super) fn error(&self, message: impl Into<String>) -> IoError {
        self.error_at(self.line, message)
    }

    /// A parse error at `line`.
    pub(super) fn error_at(&self, line: usize, message: impl Into<String>) -> IoError {
        IoError::Parse { path: self.path.to_path_buf(), line, message: message.into() }
    }

    /// The error for a file that ends where `what` was expected (at the line after the last).
    pub(super) fn eof_error(&self, what: String) -> IoError {
        self.error_at(self.lines.number + 1, format!("file ends early: expected {what}"))
    }

    /// The current line as exactly `N` non-negative integers.
    pub(super) fn counts<const N: usize>(&self, what: &str) -> Result<[usize; N], IoError> {
        let mut out = [0; N];
        let mut tokens = self.tokens();
        for slot in &mut out {
            *slot = tokens.next().and_then(|t| t.parse().ok()).ok_or_else(|| self.bad_counts(what))?;
        }
        if tokens.next().is_some() {
            return Err(self.bad_counts(what));
        }
        Ok(out)
    }

    fn bad_counts(&self, what: &str) -> IoError {
        self.error(format!("expected {what}, found '{}'", shown(&self.text)))
    }
}

impl<'p, R: BufRead> Records<'p, R> {
    /// Records of `reader`; `path` names the file in errors.
    pub(super) fn new(reader: R, path: &'p Path, comment: Option<char>) -> Self {
        Self { lines: Lines::new(reader), path, comment, text: String::new(), line: 0 }
    }

    /// Moves to the next non-blank line; `false` at the end of the file.
    pub(super) fn advance(&mut self) -> Result<bool, IoError> {
        loop {
            // A malformed UTF-16 file fails here, named by its byte offset.
            let next = self.lines.next_line().map_err(|source| read_error(self.path, source))?;
            let Some((number, text)) = next else { return Ok(false) };
            let content = match self.comment {
                Some(c) => text.split(c).next().unwrap_or(""),
                None => text,
            }
            .trim();
            if !content.is_empty() {
                self.text.clear();
                self.text.push_str(content);
                self.line = number;
                return Ok(true);
            }
        }
    }

    /// Moves to the next non-blank line, which must exist: `what` names what was expected.
    pub(super) fn require_line(&mut self, what: impl FnOnce() -> String) -> Result<(), IoError> {
        if self.advance()? { Ok(()) } else { Err(self.eof_error(what())) }
    }

    /// Moves to the next line, which must be exactly `keyword`; `context` is added to errors.
    pub(super) fn expect_line(&mut self, keyword: &str, context: &str) -> Result<(), IoError> {
        self.require_line(|| format!("'{keyword}'{context}"))?;
        if self.text != keyword {
            return Err(self.error(format!("expected '{keyword}'{context}, found '{}'", shown(&self.text))));
        }
        Ok(())
    }
}
