//! What fuzzing found, replayed: every input under `tests/fuzz-found/<target>/` goes through
//! its target's harness (`inbetween::fuzz`; for `keyframes`, the commands themselves) and must
//! end in an error or a success, within a bounded allocation (the process runs these under the
//! test's memory: an input that once reserved gigabytes must now be refused before that).

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

/// keyframes, flamingo-target-deltas-1.7e38.glb: Flamingo with bytes of its targets changed by
/// the fuzzer (target 7's deltas reach 1.7e38, target 6's 1.3e13; the file reads: every value
/// is finite). The spline's stretches at those keys overflow float32 and a frame came out NaN:
/// 362 NaN floats in the .glb, found by the keyframes target's finite-frames check after 5
/// minutes. Now refused in a line, for every output and the preview, with no file written.
#[test]
fn keyframes_inputs_give_finite_frames_or_a_refusal() {
    let files = found("keyframes");
    assert!(!files.is_empty());
    let dir = tempfile::tempdir().unwrap();
    for f in files {
        for (cmd, out) in [
            ("tween", "out.glb"),
            ("tween", "out.usda"),
            ("preview", "out.png"),
        ] {
            let out = dir.path().join(out);
            let r = std::process::Command::new(env!("CARGO_BIN_EXE_inbetween"))
                .args([cmd, f.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"])
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&r.stderr);
            assert_eq!(r.status.code(), Some(2), "{cmd} {}: {err}", f.display());
            assert_eq!(err.trim_end().lines().count(), 1, "{err}");
            assert!(
                err.contains(f.file_name().unwrap().to_str().unwrap())
                    && err.contains("not finite"),
                "{err}"
            );
            assert!(!out.exists(), "{cmd}: no output");
        }
    }
}

/// usd_stage, light-index-past-the-list.gltf: a node naming light 0 of a file whose lights
/// list the fuzzer had cut (its `extensions` key mangled), found within seconds of the cameras
/// and lights reaching the USD stage: the stage indexed the missing light and panicked. Built
/// as the harness builds it (every clip on the timeline), the stage now names the light in a
/// line and goes on.
#[test]
fn usd_stage_inputs_build_or_are_refused() {
    use inbetween::gltf::{Access, Document};
    use inbetween::usd::build_stage;
    let files = found("usd_stage");
    assert!(!files.is_empty());
    for f in files {
        let data = std::fs::read(&f).unwrap();
        let doc = Document::from_bytes(&f, &data, &Access::default()).expect("it reads");
        let stage = build_stage(&doc, &[], Vec::new(), 30.0, "x_").expect("a stage");
        let said = stage.look.left_out.join("\n");
        eprintln!("{}: {said}", f.display());
        assert!(said.contains("light 0 is not a valid"), "{said}");
    }
}

/// The tween_write target's harness, on the samples small enough for it: each is written in
/// both layouts with `--compact` (so the harness the fuzzer runs stays in step with the job).
#[test]
fn the_tween_write_harness_writes_the_samples() {
    let dir = tempfile::tempdir().unwrap();
    let mut written = 0;
    for name in ["bar_twist.glb", "flag_wave.glb"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("samples")
            .join(name);
        let data = std::fs::read(&path).unwrap();
        let runs = inbetween::fuzz::tween_write(&data, dir.path()).expect("small enough");
        for r in runs {
            r.unwrap_or_else(|e| panic!("{name}: {e:#}"));
            written += 1;
        }
    }
    assert_eq!(written, 4);
}

/// tween_write, bin-chunk-past-a-short-header.glb: bar_twist.glb with its header's length cut
/// to 8,972 of its 11,840 bytes and its binary chunk's to 4,294,909,680 (found by the
/// tween_write target at its first run, 18k runs): the reader took the chunk as a file cut short
/// and said the file ended "declared - length" bytes before the header's length, which
/// overflowed (a panic where overflow is checked, "18446744073709548748 bytes" in the line
/// where not). Now the line says the chunk runs past the file, with both lengths.
#[test]
fn tween_write_inputs_are_written_or_refused() {
    let files = found("tween_write");
    assert!(!files.is_empty());
    let dir = tempfile::tempdir().unwrap();
    for f in files {
        let data = std::fs::read(&f).unwrap();
        for r in inbetween::fuzz::tween_write(&data, dir.path())
            .into_iter()
            .flatten()
        {
            eprintln!("{}: {:?}", f.display(), r.err());
        }
        let r = std::process::Command::new(env!("CARGO_BIN_EXE_inbetween"))
            .args(["inspect", f.to_str().unwrap()])
            .output()
            .unwrap();
        let said = String::from_utf8_lossy(&r.stdout);
        assert_eq!(r.status.code(), Some(0), "{said}");
        assert!(
            said.contains("binary chunk runs past the end of the file (its header declares 8972 bytes, the file has 11840)"),
            "{said}"
        );
    }
}
