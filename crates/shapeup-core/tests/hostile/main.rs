//! Hostile inputs, one test program: files and scenes of a few KB that claim huge counts, nest
//! deeply, repeat keys or hold very long lines are refused with one line, or read, in time and
//! memory in proportion to their real size.
//!
//! Memory is measured with the one counting global allocator below, so this program holds only
//! these tests, and every measurement holds [`SERIAL`]: the peak is that test's alone. Each
//! input runs on its own thread under a watchdog (a hang check, far above the real time, not a
//! timing assertion).
#![allow(clippy::unwrap_used, clippy::expect_used)]
// The counting allocator is the only unsafe code, and it only forwards to `System`.
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

mod ply_msh;
mod scene;
mod text;

/// Bytes allocated now.
static CURRENT: AtomicUsize = AtomicUsize::new(0);
/// The peak of [`CURRENT`] since a measurement reset it.
static PEAK: AtomicUsize = AtomicUsize::new(0);

/// One measurement at a time, across every module, so that the peak is that test's.
static SERIAL: Mutex<()> = Mutex::new(());

fn grew(by: usize) {
    let now = CURRENT.fetch_add(by, Ordering::Relaxed) + by;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

/// The system allocator, counting the bytes allocated and their peak.
struct Counting;

// SAFETY: every call is forwarded to the system allocator unchanged; the counters are atomics.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            // Counted as the new block allocated before the old one is freed (a move's peak;
            // the strictest of the three counts the old per-file allocators kept).
            grew(new_size);
            CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Held for the whole of every test here: a test builds its inputs (megabytes, for the long
/// lines) before it measures, and another test's measurement must not count them. Measurements
/// still take [`SERIAL`] inside, as each module did when it was a program of its own.
static WHOLE_TEST: Mutex<()> = Mutex::new(());

fn whole_test() -> std::sync::MutexGuard<'static, ()> {
    WHOLE_TEST.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}
