//! `io::off::read_off` on arbitrary bytes: no panic, and either one error line naming the file or
//! a valid mesh.
#![no_main]

use libfuzzer_sys::fuzz_target;
use shapeup_fuzz::{check_read, path};

fuzz_target!(|data: &[u8]| {
    let result = shapeup_core::io::off::read_off(data, path("fuzz.off"));
    check_read(&result, &["fuzz.off"]);
});
