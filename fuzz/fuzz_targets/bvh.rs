//! The BVH reader, and the analysis blend runs on a capture (legs, contacts, cycles).
#![no_main]

use inbetween::blend::{analyze, parse_bvh, CycleMethod};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok((rig, clip)) = parse_bvh(text) else {
        return;
    };
    if rig.len() <= 64 && clip.duration() * clip.key_rate.max(120.0) <= 20_000.0 {
        let _ = analyze(&rig, &[&clip], CycleMethod::Legs);
    }
});
