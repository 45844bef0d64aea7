//! The shipped scenes' modelDescription.xml files under `modelDescription/` match the
//! generator, so that interface changes show up in review. Regenerate them with
//! `cargo run --release -- golden`.

use tensegrity_fmu::fmi::package::golden_model_description;
use tensegrity_fmu::scene::{builtin, builtin_names};

#[test]
fn golden_model_descriptions_match_the_generator() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("modelDescription");
    for name in builtin_names() {
        let path = dir.join(format!("{name}.xml"));
        let golden = std::fs::read_to_string(&path).unwrap_or_else(|e| {
            panic!(
                "{}: {e}; run `cargo run --release -- golden`",
                path.display()
            )
        });
        let generated = golden_model_description(&builtin(name).unwrap()).unwrap();
        if golden != generated {
            let line = golden
                .lines()
                .zip(generated.lines())
                .position(|(a, b)| a != b)
                .map_or("the length".to_string(), |i| format!("line {}", i + 1));
            panic!(
                "{} differs from the generator at {line}; review the interface change and \
                 regenerate with `cargo run --release -- golden`",
                path.display()
            );
        }
    }
}
