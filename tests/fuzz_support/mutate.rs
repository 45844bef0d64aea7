//! Real scene files, the fuzzer's corpus, with their bytes mutated.

use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::select;

use tensegrity_fmu::scene;

use super::generate::Input;

/// Real scenes: the files under fmu/scenes and every built-in, in TOML and in JSON.
pub fn corpus() -> Vec<(bool, String)> {
    let mut texts = Vec::new();
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/fmu/scenes");
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .expect("fmu/scenes")
        .map(|e| e.expect("a file").path())
        .collect();
    files.sort();
    for path in files {
        texts.push((false, std::fs::read_to_string(path).expect("a scene file")));
    }
    for name in scene::builtin_names() {
        let scene = scene::builtin(name).expect("a built-in");
        texts.push((false, scene.to_toml_string()));
        texts.push((true, serde_json::to_string(&scene).expect("JSON")));
    }
    texts
}

/// One change to a text's bytes.
#[derive(Debug, Clone)]
enum Mutation {
    FlipBit(usize, u8),
    SetByte(usize, u8),
    Insert(usize, &'static str),
    Delete(usize, usize),
    Repeat(usize, usize),
    Truncate(usize),
}

/// Tokens that mean something to TOML, JSON or a scene.
const TOKENS: [&str; 24] = [
    "nan",
    "-inf",
    "inf",
    "-1",
    "0",
    "1e308",
    "-0.0",
    "1e-320",
    "9223372036854775807",
    "[",
    "]",
    "{",
    "}",
    "\"",
    "=",
    ",",
    "\n",
    "\n[[bars]]\nnodes = [1, 1]\nmass = 1.0\n",
    "\n[solver]\n",
    "\n[[cables]]\nnodes = [1, 2]\nstiffness = 1e14\nrest_length = 0.1\n",
    "\u{0}",
    "é",
    "\"equilibrium\"",
    "null",
];

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        3 => (any::<usize>(), 0u8..8).prop_map(|(p, b)| Mutation::FlipBit(p, b)),
        2 => (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Mutation::SetByte(p, b)),
        3 => (any::<usize>(), select(&TOKENS[..])).prop_map(|(p, t)| Mutation::Insert(p, t)),
        2 => (any::<usize>(), 1usize..40).prop_map(|(p, n)| Mutation::Delete(p, n)),
        1 => (any::<usize>(), 1usize..200).prop_map(|(p, n)| Mutation::Repeat(p, n)),
        1 => any::<usize>().prop_map(Mutation::Truncate),
    ]
}

fn mutate(bytes: &mut Vec<u8>, m: &Mutation) {
    let len = bytes.len().max(1);
    match *m {
        Mutation::FlipBit(p, b) if !bytes.is_empty() => bytes[p % len] ^= 1 << b,
        Mutation::SetByte(p, b) if !bytes.is_empty() => bytes[p % len] = b,
        Mutation::Insert(p, t) => {
            let p = p % (bytes.len() + 1);
            bytes.splice(p..p, t.bytes());
        }
        Mutation::Delete(p, n) => {
            let p = p % len;
            bytes.drain(p.min(bytes.len())..(p + n).min(bytes.len()));
        }
        Mutation::Repeat(p, n) => {
            let p = p % len;
            let piece = bytes[p.min(bytes.len())..(p + n).min(bytes.len())].to_vec();
            bytes.splice(p..p, piece);
        }
        Mutation::Truncate(p) => bytes.truncate(p % len),
        _ => {}
    }
}

/// A real scene with one to eight byte-level mutations.
pub fn mutated(corpus: Vec<(bool, String)>) -> impl Strategy<Value = Input> {
    (
        select(corpus),
        vec(mutation(), 1..8),
        prop::bool::weighted(0.1),
    )
        .prop_map(|((json, text), mutations, fmu)| {
            let mut bytes = text.into_bytes();
            for m in &mutations {
                mutate(&mut bytes, m);
            }
            Input {
                json,
                text: String::from_utf8_lossy(&bytes).into_owned(),
                fmu,
            }
        })
}
