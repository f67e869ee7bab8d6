//! Reading text: UTF-16 files transcoded to UTF-8 ([`decode_text`]), line-by-line reading with
//! line numbers ([`Lines`]), the errors for text that is not valid in its encoding, and the
//! helpers every parser shares (numbers, bounded preallocation).

use std::fs;
use std::io::{self, BufRead};
use std::path::Path;

use super::{IoError, MAX_PREALLOCATION};
use crate::text::shown;

/// The name of the UTF-16 encoding whose byte-order mark `prefix` starts with (`FF FE`:
/// "UTF-16 little endian", `FE FF`: "UTF-16 big endian"), or `None`. Readers decode such text
/// files ([`decode_text`]) or refuse them with one line naming the encoding, instead of
/// misreading their bytes.
pub(crate) fn utf16_encoding(prefix: &[u8]) -> Option<&'static str> {
    utf16_of(prefix).map(|(name, _)| name)
}

fn utf16_of(prefix: &[u8]) -> Option<(&'static str, &'static encoding_rs::Encoding)> {
    match prefix {
        [0xFF, 0xFE, ..] => Some(("UTF-16 little endian", encoding_rs::UTF_16LE)),
        [0xFE, 0xFF, ..] => Some(("UTF-16 big endian", encoding_rs::UTF_16BE)),
        _ => None,
    }
}

/// Text that is not valid in its encoding: the payload of the [`io::Error`] (kind
/// `InvalidData`) that [`TextReader`] and [`read_text_file`] return; [`read_error`] turns it
/// into an [`IoError::Binary`] naming the byte offset.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct DecodeError {
    /// "UTF-16 little endian", "UTF-16 big endian" or "UTF-8".
    pub(crate) encoding: &'static str,
    /// Offset in the file of the first byte that is not valid text.
    pub(crate) offset: u64,
}

impl std::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let why = if self.encoding.starts_with("UTF-16") {
            "an unpaired surrogate, or an odd number of bytes"
        } else {
            "a byte sequence that is no character"
        };
        write!(f, "not valid {} text at byte offset {} ({why})", self.encoding, self.offset)
    }
}

impl std::error::Error for DecodeError {}

impl DecodeError {
    fn into_io(self) -> io::Error {
        io::Error::new(io::ErrorKind::InvalidData, self)
    }

    /// The decoding error that `error` carries, if it is one.
    pub(crate) fn of(error: &io::Error) -> Option<&DecodeError> {
        error.get_ref().and_then(|e| e.downcast_ref::<DecodeError>())
    }
}

/// The error for a failed read of `path`: [`IoError::Binary`] at the offset for text that is
/// not valid in its encoding ([`DecodeError`]), else [`IoError::Read`].
pub(crate) fn read_error(path: &Path, source: io::Error) -> IoError {
    match DecodeError::of(&source) {
        Some(e) => IoError::Binary {
            path: path.to_path_buf(),
            offset: e.offset,
            message: format!("the file is not valid {} text (the byte-order mark at its start says it is)", e.encoding),
        },
        None => IoError::Read { path: path.to_path_buf(), source },
    }
}

/// [`read_error`] for an error already made: an [`IoError::Read`] whose cause is a
/// [`DecodeError`] (from a line reader that maps every error to `Read`) becomes
/// [`IoError::Binary`]; any other error is returned as it is.
pub(crate) fn with_decode_errors(error: IoError) -> IoError {
    match error {
        IoError::Read { path, source } => read_error(&path, source),
        other => other,
    }
}

/// A text file's bytes as UTF-8 for the line readers: the bytes themselves, or, after a UTF-16
/// byte-order mark (`FF FE`, `FE FF`), their transcoding to UTF-8 (without the mark). Malformed
/// UTF-16 (an unpaired surrogate, an odd number of bytes) is an `InvalidData` error carrying a
/// [`DecodeError`] with its byte offset in the file, never a replacement character. Anything
/// else passes through untouched (UTF-8, a UTF-8 byte-order mark, invalid UTF-8, binary data),
/// so readers keep their own handling of those.
///
/// Every text reader (OBJ, OFF, ascii STL, TetGen) reads through one; PLY and MSH can do the
/// same with [`decode_text`].
pub(crate) struct TextReader<R> {
    inner: TextInner<R>,
}

enum TextInner<R> {
    /// The bytes sniffed for a byte-order mark, then the rest of the reader.
    Plain(io::Chain<io::Cursor<Vec<u8>>, R>),
    Utf16(Box<Utf16Decoder<R>>),
}

/// Wraps `reader` in a [`TextReader`], looking at its first two bytes for a UTF-16 byte-order
/// mark.
///
/// # Errors
/// Any error reading those bytes.
pub(crate) fn decode_text<R: BufRead>(mut reader: R) -> io::Result<TextReader<R>> {
    let mut prefix = Vec::with_capacity(2);
    while prefix.len() < 2 {
        let buf = match reader.fill_buf() {
            Ok(buf) => buf,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if buf.is_empty() {
            break;
        }
        let take = buf.len().min(2 - prefix.len());
        prefix.extend_from_slice(&buf[..take]);
        reader.consume(take);
    }
    let inner = match utf16_of(&prefix) {
        Some((name, encoding)) => TextInner::Utf16(Box::new(Utf16Decoder {
            reader,
            decoder: encoding.new_decoder_without_bom_handling(),
            name,
            out: vec![0; 16 * 1024],
            start: 0,
            end: 0,
            offset: prefix.len() as u64,
            done: false,
        })),
        None => TextInner::Plain(io::Read::chain(io::Cursor::new(prefix), reader)),
    };
    Ok(TextReader { inner })
}

/// Streaming UTF-16 → UTF-8 through `encoding_rs` (a thin adapter: `encoding_rs_io` would
/// replace malformed text by U+FFFD silently, where a reader must say where the file is broken).
struct Utf16Decoder<R> {
    reader: R,
    decoder: encoding_rs::Decoder,
    name: &'static str,
    /// UTF-8 decoded and not yet consumed: `out[start..end]`.
    out: Vec<u8>,
    start: usize,
    end: usize,
    /// Bytes of the file taken by the decoder so far (the byte-order mark included).
    offset: u64,
    done: bool,
}

impl<R: BufRead> Utf16Decoder<R> {
    fn fill_buf(&mut self) -> io::Result<&[u8]> {
        while self.start == self.end && !self.done {
            let src = match self.reader.fill_buf() {
                Ok(src) => src,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e),
            };
            let last = src.is_empty();
            let (result, read, written) = self.decoder.decode_to_utf8_without_replacement(src, &mut self.out, last);
            self.reader.consume(read);
            self.offset += read as u64;
            self.start = 0;
            self.end = written;
            match result {
                encoding_rs::DecoderResult::InputEmpty => self.done = last,
                encoding_rs::DecoderResult::OutputFull => {}
                encoding_rs::DecoderResult::Malformed(bad, after) => {
                    self.done = true;
                    let offset = self.offset - u64::from(bad) - u64::from(after);
                    return Err(DecodeError { encoding: self.name, offset }.into_io());
                }
            }
        }
        Ok(&self.out[self.start..self.end])
    }
}

impl<R: BufRead> io::Read for TextReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let available = self.fill_buf()?;
        let n = available.len().min(buf.len());
        buf[..n].copy_from_slice(&available[..n]);
        self.consume(n);
        Ok(n)
    }
}

impl<R: BufRead> BufRead for TextReader<R> {
    fn fill_buf(&mut self) -> io::Result<&[u8]> {
        match &mut self.inner {
            TextInner::Plain(r) => r.fill_buf(),
            TextInner::Utf16(d) => d.fill_buf(),
        }
    }

    fn consume(&mut self, amount: usize) {
        match &mut self.inner {
            TextInner::Plain(r) => r.consume(amount),
            TextInner::Utf16(d) => d.start = (d.start + amount).min(d.end),
        }
    }
}

/// A whole text file (a scene) as a string: UTF-8, with or without a byte-order mark (removed),
/// or UTF-16 after its byte-order mark, transcoded ([`decode_text`]).
///
/// # Errors
/// The operating system's error, or an `InvalidData` error carrying a [`DecodeError`] (with the
/// byte offset) for text that is not valid UTF-8 or UTF-16.
pub(crate) fn read_text_file(path: &Path) -> io::Result<String> {
    let bytes = fs::read(path)?;
    if utf16_encoding(&bytes).is_some() {
        let mut text = String::new();
        io::Read::read_to_string(&mut decode_text(&bytes[..])?, &mut text)?;
        return Ok(text);
    }
    let skip = if bytes.starts_with(UTF8_BOM) { UTF8_BOM.len() } else { 0 };
    let mut bytes = bytes;
    bytes.drain(..skip);
    String::from_utf8(bytes)
        .map_err(|e| DecodeError { encoding: "UTF-8", offset: (skip + e.utf8_error().valid_up_to()) as u64 }.into_io())
}

/// The UTF-8 byte-order mark, skipped at the start of every text file.
pub const UTF8_BOM: &[u8] = b"\xEF\xBB\xBF";

/// Line-by-line reading of a text file with 1-based line numbers, `\n` or `\r\n` endings, a
/// UTF-8 byte-order mark at the start skipped, and invalid UTF-8 replaced (it only ever occurs
/// in comments and names).
pub(crate) struct Lines<R> {
    reader: R,
    bytes: Vec<u8>,
    text: String,
    /// Number of the line last returned (0 before the first).
    pub(crate) number: usize,
    /// Bytes consumed so far, line endings included.
    pub(crate) consumed: u64,
}

impl<R: BufRead> Lines<R> {
    pub(crate) fn new(reader: R) -> Self {
        Self { reader, bytes: Vec::new(), text: String::new(), number: 0, consumed: 0 }
    }

    /// The next line's number and text without its line ending, or `None` at the end of the file.
    pub(crate) fn next_line(&mut self) -> io::Result<Option<(usize, &str)>> {
        self.bytes.clear();
        let read = self.reader.read_until(b'\n', &mut self.bytes)?;
        if read == 0 {
            return Ok(None);
        }
        self.number += 1;
        self.consumed += read as u64;
        if self.number == 1 && self.bytes.starts_with(UTF8_BOM) {
            // A UTF-8 byte-order mark is not part of the first line (editors on Windows add it).
            self.bytes.drain(..UTF8_BOM.len());
        }
        if self.bytes.last() == Some(&b'\n') {
            self.bytes.pop();
        }
        if self.bytes.last() == Some(&b'\r') {
            self.bytes.pop();
        }
        self.text.clear();
        self.text.push_str(&String::from_utf8_lossy(&self.bytes));
        Ok(Some((self.number, &self.text)))
    }

    /// The underlying reader, positioned just after the last line returned.
    pub(crate) fn into_inner(self) -> R {
        self.reader
    }
}

/// A token that should be a number and is not: `{what} '{token}' is not a number`, the token
/// cut short ([`shown`]). Readers place it at its line or byte offset in an [`IoError`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{what} '{token}' is not a number")]
pub(crate) struct NotANumber {
    /// What the token was meant to be (`vertex 3 x coordinate`, …).
    what: String,
    /// The token, cut short.
    token: String,
}

/// Parses one coordinate, naming it (`what`) in the error.
///
/// # Errors
/// [`NotANumber`] when `token` is not an `f64`.
pub(crate) fn parse_coordinate(token: &str, what: &str) -> Result<f64, NotANumber> {
    token.parse::<f64>().map_err(|_| NotANumber { what: what.to_owned(), token: shown(token).into_owned() })
}

/// Most bytes [`bounded_vec`] reserves up front: a few such vectors for a header's claim stay
/// well under 100 MB whatever the element size.
const PREALLOCATION_BYTES: usize = 16 << 20;

/// `Vec::with_capacity` bounded by [`MAX_PREALLOCATION`] elements and 16 MiB, for counts read
/// from a file.
pub(crate) fn bounded_vec<T>(claimed: usize) -> Vec<T> {
    let by_size = PREALLOCATION_BYTES / size_of::<T>().max(1);
    Vec::with_capacity(claimed.min(MAX_PREALLOCATION).min(by_size))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use std::io::BufReader;

    use super::*;

    #[test]
    fn lines_strip_crlf_and_count() {
        let mut lines = Lines::new(&b"a\r\nb\n\nc"[..]);
        assert_eq!(lines.next_line().unwrap(), Some((1, "a")));
        assert_eq!(lines.next_line().unwrap(), Some((2, "b")));
        assert_eq!(lines.next_line().unwrap(), Some((3, "")));
        assert_eq!(lines.next_line().unwrap(), Some((4, "c")));
        assert_eq!(lines.number, 4);
        assert_eq!(lines.next_line().unwrap(), None);
        let mut lines = Lines::new(&b"\xEF\xBB\xBFv 1 2 3\n\xEF\xBB\xBF"[..]);
        assert_eq!(lines.next_line().unwrap(), Some((1, "v 1 2 3")), "the mark is skipped at the start");
        assert_eq!(lines.next_line().unwrap(), Some((2, "\u{feff}")), "and only there");
    }

    fn utf16(text: &str, big_endian: bool) -> Vec<u8> {
        let mut bytes = if big_endian { vec![0xFE, 0xFF] } else { vec![0xFF, 0xFE] };
        for unit in text.encode_utf16() {
            bytes.extend_from_slice(&if big_endian { unit.to_be_bytes() } else { unit.to_le_bytes() });
        }
        bytes
    }

    fn decode_all(reader: impl BufRead) -> io::Result<String> {
        let mut text = String::new();
        io::Read::read_to_string(&mut decode_text(reader)?, &mut text)?;
        Ok(text)
    }

    #[test]
    fn utf16_is_decoded_however_the_bytes_arrive() {
        let text = "v 1 2 3\r\n# caf\u{e9} \u{1D11E}\n";
        for big in [false, true] {
            let bytes = utf16(text, big);
            assert_eq!(decode_all(&bytes[..]).unwrap(), text);
            // One byte at a time: the mark and surrogate pairs split across reads.
            assert_eq!(decode_all(BufReader::with_capacity(1, &bytes[..])).unwrap(), text);
        }
        let crlf = utf16("a\r\nb", false);
        let mut lines = Lines::new(decode_text(&crlf[..]).unwrap());
        assert_eq!(lines.next_line().unwrap(), Some((1, "a")));
        assert_eq!(lines.next_line().unwrap(), Some((2, "b")));
        assert_eq!(lines.next_line().unwrap(), None);
        assert_eq!(decode_all(&[0xFF, 0xFE][..]).unwrap(), "", "only the mark");
    }

    #[test]
    fn other_bytes_pass_through_untouched() {
        for bytes in [&b""[..], b"x", b"\xFF", b"\xFE", b"\xEF\xBB\xBFv 1\n", b"caf\xe9 \x00\xFF\xFE"] {
            let mut out = Vec::new();
            io::Read::read_to_end(&mut decode_text(BufReader::with_capacity(1, bytes)).unwrap(), &mut out).unwrap();
            assert_eq!(out, bytes);
        }
    }

    #[test]
    fn malformed_utf16_says_encoding_and_offset() {
        let error = |bytes: &[u8]| {
            let e = decode_all(BufReader::with_capacity(3, bytes)).unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidData);
            DecodeError::of(&e).cloned().unwrap()
        };
        let mut odd = utf16("ab", false);
        odd.push(b'c');
        assert_eq!(error(&odd), DecodeError { encoding: "UTF-16 little endian", offset: 6 });
        // A high surrogate followed by a letter, a low surrogate alone.
        let lone_high = [0xFE, 0xFF, 0x00, b'a', 0xD8, 0x00, 0x00, b'b'];
        assert_eq!(error(&lone_high), DecodeError { encoding: "UTF-16 big endian", offset: 4 });
        let lone_low = [0xFF, 0xFE, b'a', 0x00, b'b', 0x00, 0x00, 0xDC];
        assert_eq!(error(&lone_low), DecodeError { encoding: "UTF-16 little endian", offset: 6 });
        let high_at_end = [0xFF, 0xFE, 0x00, 0xD8];
        assert_eq!(error(&high_at_end).offset, 2);
        let e = read_error(Path::new("x.obj"), DecodeError { encoding: "UTF-16 big endian", offset: 4 }.into_io());
        assert_eq!(
            e.to_string(),
            "x.obj: byte offset 4: the file is not valid UTF-16 big endian text (the byte-order mark at its start says it is)"
        );
        let e = read_error(Path::new("x.obj"), io::Error::other("disk"));
        assert!(matches!(e, IoError::Read { .. }));
    }

    #[test]
    fn preallocation_is_bounded_in_bytes_too() {
        assert_eq!(bounded_vec::<u8>(10).capacity(), 10);
        assert_eq!(bounded_vec::<u8>(usize::MAX).capacity(), MAX_PREALLOCATION);
        assert!(bounded_vec::<[f64; 8]>(usize::MAX).capacity() * 64 <= PREALLOCATION_BYTES);
    }
}
