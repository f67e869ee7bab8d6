//! What every end-to-end test of the `shapeup` binary needs: run it, keep what it printed.


use std::ffi::OsStr;
use std::path::Path;
use std::process::Command;

/// What a finished `shapeup` process left behind.
pub struct Output {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

impl Output {
    pub fn describe(&self) -> String {
        format!("exit {:?}\n--- stdout ---\n{}\n--- stderr ---\n{}", self.code, self.stdout, self.stderr)
    }

    /// Panics (with the process output) unless it exited 0.
    pub fn success(self) -> Output {
        assert_eq!(self.code, Some(0), "expected success\n{}", self.describe());
        assert!(!self.stderr.contains("panicked"), "{}", self.describe());
        self
    }
}

/// Runs `shapeup ARGS…` from `cwd` (or the test's own directory).
pub fn shapeup_in<I, S>(cwd: Option<&Path>, args: I) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_shapeup"));
    cmd.args(args);
    if let Some(dir) = cwd {
        cmd.current_dir(dir);
    }
    let out = cmd.output().expect("cannot run the shapeup binary");
    Output {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}
