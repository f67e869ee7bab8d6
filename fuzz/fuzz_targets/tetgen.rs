//! `io::tetgen::read_tetgen` on a `.node` and an `.ele` file: the input up to its first 0x00 byte
//! is the `.node` file, the rest the `.ele` file (empty when there is no 0x00). No panic, and
//! either one error line naming one of the two files or a valid mesh.
#![no_main]

use libfuzzer_sys::fuzz_target;
use shapeup_fuzz::{check_read, path};

fuzz_target!(|data: &[u8]| {
    let (node, ele) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[][..]),
    };
    let result = shapeup_core::io::tetgen::read_tetgen(node, path("fuzz.node"), ele, path("fuzz.ele"));
    check_read(&result, &["fuzz.node", "fuzz.ele"]);
});
