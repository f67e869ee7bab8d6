//! The binary's logger and progress bars.
//!
//! Log records (the `log` facade: shapeup's own warnings, shapeup-core's notes such as TetGen's
//! output, and the GUI stack's wgpu / winit / eframe diagnostics) go to stderr through
//! env_logger, one record a line: `shapeup: LEVEL: MESSAGE`, with the record's module in front
//! of the message for other crates' records (`shapeup: warning: wgpu_hal::vulkan: …`).
//!
//! Level: `warn` by default; `RUST_LOG` (env_logger's syntax, e.g. `RUST_LOG=info` or
//! `RUST_LOG=wgpu_core=debug`) changes it; `-q` (errors only) and `-v`/`-vv`/`-vvv` (info,
//! debug, trace) set the default level over `RUST_LOG`'s, keeping its per-module directives.
//! shapeup's own warnings (`shapeup: warning: FILE: …`) are warn records of target `shapeup`,
//! so `-q` silences them; errors (`shapeup: error: …`) are always printed.
//!
//! Other crates' records (wgpu, winit, eframe, naga, …) are held back by default rather than
//! printed: they come out, before the error line, only when the command fails (a window or GPU
//! that cannot start), so that a run that works is not buried in probing noise (wgpu reports
//! each graphics backend it fails to start as an error even when another one works). With `-v`
//! or `RUST_LOG` set they are printed as they come.
//!
//! Progress bars are drawn on stderr only when it is a terminal and without `-q`; they belong
//! to one [`MultiProgress`] that every log line suspends (indicatif-log-bridge), so a log line
//! never lands in the middle of a bar.

use indicatif::{MultiProgress, ProgressBar, ProgressFinish, ProgressStyle};
use log::{Level, LevelFilter, Log, Metadata, Record};
use std::collections::VecDeque;
use std::io::{IsTerminal, Write};
use std::sync::{Mutex, OnceLock, PoisonError};
use std::time::Duration;

/// The target of shapeup's own records (`shapeup: warning: …` lines).
pub const TARGET: &str = "shapeup";

/// What [`init`] decided, for the progress bars and the messages that are not log records.
struct Settings {
    // Read by `shapeup view` only.
    #[cfg_attr(not(feature = "gui"), allow(dead_code))]
    quiet: bool,
    bars: bool,
    multi: MultiProgress,
}

static SETTINGS: OnceLock<Settings> = OnceLock::new();

/// The default level for `-q` / `-v` counts: `None` when neither is given (then `RUST_LOG`, or
/// warn).
fn flag_level(quiet: bool, verbose: u8) -> Option<LevelFilter> {
    match (quiet, verbose) {
        (true, _) => Some(LevelFilter::Error),
        (false, 0) => None,
        (false, 1) => Some(LevelFilter::Info),
        (false, 2) => Some(LevelFilter::Debug),
        (false, _) => Some(LevelFilter::Trace),
    }
}

fn level_name(level: Level) -> &'static str {
    match level {
        Level::Error => "error",
        Level::Warn => "warning",
        Level::Info => "info",
        Level::Debug => "debug",
        Level::Trace => "trace",
    }
}

/// Whether a record's target is one of ours (printed without its module).
fn is_own(target: &str) -> bool {
    ["shapeup", "shapeup_core", "shapeup_app"]
        .iter()
        .any(|own| target == *own || target.strip_prefix(own).is_some_and(|rest| rest.starts_with("::")))
}

/// A record as one stderr line (without the newline).
fn line(record: &Record<'_>) -> String {
    let level = level_name(record.level());
    if is_own(record.target()) {
        format!("shapeup: {level}: {}", record.args())
    } else {
        format!("shapeup: {level}: {}: {}", record.target(), record.args())
    }
}

/// The most held records kept (the latest ones): a failing GPU says what it has to say in a
/// few lines; a chatty one must not grow memory without bound.
const MAX_HELD: usize = 100;

/// Records of other crates held back until the command fails ([`print_held`]).
static HELD: Mutex<VecDeque<String>> = Mutex::new(VecDeque::new());

/// env_logger, holding back other crates' records unless asked for them.
struct Logger {
    inner: env_logger::Logger,
    hold_others: bool,
}

impl Log for Logger {
    fn enabled(&self, metadata: &Metadata<'_>) -> bool {
        self.inner.enabled(metadata)
    }

    fn log(&self, record: &Record<'_>) {
        if !self.inner.matches(record) {
            return;
        }
        if self.hold_others && !is_own(record.target()) {
            let mut held = HELD.lock().unwrap_or_else(PoisonError::into_inner);
            if held.len() == MAX_HELD {
                held.pop_front();
            }
            held.push_back(line(record));
        } else {
            self.inner.log(record);
        }
    }

    fn flush(&self) {
        self.inner.flush();
    }
}

/// Prints the records [`Logger`] held back (before the error line of a failed command).
pub fn print_held() {
    let held = std::mem::take(&mut *HELD.lock().unwrap_or_else(PoisonError::into_inner));
    let mut err = std::io::stderr().lock();
    for line in held {
        let _ = writeln!(err, "{line}");
    }
}

/// Installs the logger; call once, first thing.
pub fn init(quiet: bool, verbose: u8) {
    let mut builder = env_logger::Builder::new();
    builder.filter_level(LevelFilter::Warn).parse_default_env();
    if let Some(level) = flag_level(quiet, verbose) {
        builder.filter_level(level);
    }
    builder.format(|buf, record| writeln!(buf, "{}", line(record)));
    let inner = builder.build();
    let max_level = inner.filter();
    let hold_others = verbose == 0 && std::env::var_os("RUST_LOG").is_none();
    let multi = MultiProgress::new();
    // Fails only when a logger is already installed: keep that one.
    let logger = Logger { inner, hold_others };
    if indicatif_log_bridge::LogWrapper::new(multi.clone(), logger).try_init().is_ok() {
        log::set_max_level(max_level);
    }
    let bars = !quiet && std::io::stderr().is_terminal();
    let _ = SETTINGS.set(Settings { quiet, bars, multi });
}

/// Whether `-q` was given: messages that are not log records (the viewer's notes) stay silent.
#[cfg_attr(not(feature = "gui"), allow(dead_code))]
pub fn quiet() -> bool {
    SETTINGS.get().is_some_and(|s| s.quiet)
}

/// A progress bar of `len` steps drawn with `template` (indicatif's syntax), or a hidden one when
/// stderr is not a terminal or with `-q`. It is cleared when dropped, whether the work finished
/// or failed, so that an error line is all that is left.
pub fn bar(len: u64, template: &str) -> Progress {
    let Some(settings) = SETTINGS.get().filter(|s| s.bars) else {
        return Progress { bar: ProgressBar::hidden(), multi: None };
    };
    let bar = ProgressBar::new(len).with_finish(ProgressFinish::AndClear);
    if let Ok(style) = ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    let bar = settings.multi.add(bar);
    Progress { bar, multi: Some(settings.multi.clone()) }
}

/// A spinner with `message`, for work of unknown length (loading a scene); as [`bar`].
pub fn spinner(message: String) -> Progress {
    let progress = bar(0, "{spinner} {msg}  {elapsed}");
    progress.bar.set_message(message);
    if progress.multi.is_some() {
        progress.bar.enable_steady_tick(Duration::from_millis(100));
    }
    progress
}

/// A progress bar that clears itself when dropped.
pub struct Progress {
    /// The bar (hidden when none is drawn).
    pub bar: ProgressBar,
    multi: Option<MultiProgress>,
}

impl Progress {
    /// Whether a bar is drawn (callers may skip work that only feeds it).
    pub fn is_drawn(&self) -> bool {
        self.multi.is_some()
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
        if let Some(multi) = &self.multi {
            multi.remove(&self.bar);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_set_the_level() {
        assert_eq!(flag_level(false, 0), None);
        assert_eq!(flag_level(true, 0), Some(LevelFilter::Error));
        assert_eq!(flag_level(false, 1), Some(LevelFilter::Info));
        assert_eq!(flag_level(false, 2), Some(LevelFilter::Debug));
        assert_eq!(flag_level(false, 9), Some(LevelFilter::Trace));
    }

    #[test]
    fn own_targets_are_recognised() {
        assert!(is_own("shapeup"));
        assert!(is_own("shapeup::simulate"));
        assert!(is_own("shapeup_core::tetrahedralize"));
        assert!(!is_own("shapeup_corex"));
        assert!(!is_own("wgpu_hal::vulkan"));
    }
}
