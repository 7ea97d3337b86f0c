//! The whole `tween` job on small inputs, to .glb with `--compact`, in both layouts (see
//! `inbetween::fuzz::tween_write`): what is read must be written or refused with an error,
//! never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("inbetween-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let _ = inbetween::fuzz::tween_write(data, &dir);
});
