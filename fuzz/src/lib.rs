//! What every fuzz target checks besides "no panic": a read either fails with one line naming
//! the file, or gives a mesh that validates with finite coordinates.

use std::path::Path;
use std::sync::OnceLock;

use shapeup_core::io::{IoError, LoadedMesh};

/// Checks a reader's result: an error is one line naming one of `names` (the file, or either
/// file of a pair); a mesh validates and its coordinates are finite.
///
/// # Panics
/// When either does not hold: that is a finding.
pub fn check_read(result: &Result<LoadedMesh, IoError>, names: &[&str]) {
    match result {
        Err(e) if expect_valid() => panic!("SHAPEUP_FUZZ_EXPECT_VALID: this input does not read: {e}"),
        Err(e) => check_message(&e.to_string(), names),
        Ok(loaded) => {
            let mesh = &loaded.mesh;
            if let Err(e) = mesh.validate() {
                panic!("the reader returned a mesh that does not validate: {e}");
            }
            if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
                panic!("the reader returned a non-finite vertex {i}: {}", mesh.positions[i]);
            }
        }
    }
}

/// Checks an error message: one line (no `\n` or `\r`) that names one of `names`.
/// `SHAPEUP_FUZZ_MESSAGES=cr` lets `\r` pass, `=off` skips the check (to look past a known
/// finding while it is being fixed).
///
/// # Panics
/// When it does not.
pub fn check_message(message: &str, names: &[&str]) {
    static MODE: OnceLock<String> = OnceLock::new();
    let mode = MODE.get_or_init(|| std::env::var("SHAPEUP_FUZZ_MESSAGES").unwrap_or_default());
    let breaks: &[char] = match mode.as_str() {
        "off" => return,
        "cr" => &['\n'],
        _ => &['\n', '\r'],
    };
    assert!(!message.contains(breaks), "the error is not one line: {message:?}");
    assert!(names.iter().any(|n| message.contains(n)), "the error does not name the file ({names:?}): {message:?}");
}

/// Whether the environment variable `SHAPEUP_FUZZ_EXPECT_VALID` is set: then an input that
/// does not read (or a scene that does not load) is a panic too, which checks that the seed
/// corpus is made of valid files (`run-all.sh --check-seeds`).
pub fn expect_valid() -> bool {
    static EXPECT: OnceLock<bool> = OnceLock::new();
    *EXPECT.get_or_init(|| std::env::var_os("SHAPEUP_FUZZ_EXPECT_VALID").is_some())
}

/// A path with the given file name, for messages.
pub fn path(name: &str) -> &Path {
    Path::new(name)
}

pub mod scene;
