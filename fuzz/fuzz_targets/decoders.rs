//! The decoders of compressed glTF data, fed through the reader: the input's first bytes pick
//! a meshopt buffer view (mode, filter, stride, count) or a Draco primitive, the rest is the
//! compressed stream (harness in `inbetween::fuzz`, shared with tests/fuzz_found.rs).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = inbetween::fuzz::decoders(data);
});
