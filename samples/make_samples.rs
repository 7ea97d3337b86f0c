//! Regenerate the inputs in `samples/`: `cargo run --release --example make-samples [DIR]`.
//! The files are deterministic; a test checks that the committed ones are current.

fn main() -> anyhow::Result<()> {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/samples").into());
    for (name, file) in inbetween::synth::samples() {
        let path = std::path::Path::new(&dir).join(name);
        file.write(&path)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
