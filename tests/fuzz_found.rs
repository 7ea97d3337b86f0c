//! What fuzzing found, replayed: every input under `tests/fuzz-found/<target>/` goes through
//! its target's harness (`inbetween::fuzz`) and must end in an error or a success, within a
//! bounded allocation (the process runs these under the test's memory: an input that once
//! reserved gigabytes must now be refused before that).

use std::path::Path;

fn found(target: &str) -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz-found")
        .join(target);
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files
}

/// decoders, draco-points-claim-17gb.bin: a 60-byte Draco stream whose header claims points
/// enough for 17 GB of attribute values; draco-core reserved them (try_reserve, so no abort,
/// but libFuzzer's 2 GiB malloc limit caught it after 5 minutes, 494,369 runs). The primitive's
/// accessor counts now cap the decode: refused at the header.
#[test]
fn decoders_inputs_are_refused_cleanly() {
    let files = found("decoders");
    assert!(!files.is_empty());
    for f in files {
        let data = std::fs::read(&f).unwrap();
        let r = inbetween::fuzz::decoders(&data).expect("a harness input");
        let e = r.expect_err("these inputs are malformed");
        let msg = format!("{e:#}");
        eprintln!("{}: {msg}", f.display());
        // Refused by the limits, before the decoder sized anything by the claim.
        assert!(
            msg.to_lowercase().contains("limit exceeded"),
            "{}: {msg}",
            f.display()
        );
    }
}
