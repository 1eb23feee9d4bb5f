//! Fuzzes the partial-image reader of `caustic merge` and of a resuming shard: any bytes are
//! read or refused with an error, never a panic or an allocation the header did not justify.
#![no_main]

use caustic::farm::partial::read_partial_bytes;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let _ = read_partial_bytes(data, Path::new("fuzz.exr"));
});
