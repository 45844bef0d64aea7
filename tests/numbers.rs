//! Every text writer writes plain numbers: the shortest decimal that reads back as the
//! same `f64`, never a long fixed-notation expansion (`-1.0605752387249069e-16`, not
//! `-0.00000000000000010605752387249069`). "Shortest" is checked against the standard
//! library's `{:e}` (its significant digits are the shortest round-trip ones), the
//! round trip bit for bit.

mod cli_support;

use tensegrity_fmu::numbers::{number, plain_toml, toml_float};
use tensegrity_fmu::scene::{builtin, builtin_names};
use tensegrity_fmu::Scene;

const AWKWARD: [f64; 12] = [
    1e-16,
    -1.0605752387249069e-16,
    0.1,
    1.0 / 3.0,
    1e21,
    5e-324,
    1.7976931348623157e308,
    -0.0,
    0.0,
    2.0,
    1e20,
    -123456.789,
];

/// Significant digits of a decimal, without sign, point, exponent, leading or trailing zeros.
fn digits(text: &str) -> String {
    let mantissa = text.split(['e', 'E']).next().unwrap();
    let d: String = mantissa.chars().filter(char::is_ascii_digit).collect();
    d.trim_start_matches('0').trim_end_matches('0').to_string()
}

/// `text` reads back as `x` bit for bit, has the shortest round-trip digits, and is no
/// longer than those digits with a sign, a point, an exponent and a `.0` (a fixed-notation
/// expansion of 1e-16 or 1e21 is not).
fn assert_plain(text: &str, x: f64) {
    let back: f64 = text
        .parse()
        .unwrap_or_else(|_| panic!("{text:?} does not parse"));
    assert_eq!(
        back.to_bits(),
        x.to_bits(),
        "{text:?} reads back as {back:e}, not {x:e}"
    );
    let shortest = digits(&format!("{x:e}"));
    assert_eq!(
        digits(text),
        shortest,
        "{text:?} is not the shortest form of {x:e}"
    );
    assert!(
        text.len() <= shortest.len().max(1) + 9,
        "{text:?}: a long expansion of {x:e}"
    );
}

/// Every number token (outside strings) of a CSV/JSON text is plain.
fn assert_all_plain(what: &str, text: &str) -> usize {
    let mut count = 0;
    let mut in_string = false;
    let mut token = String::new();
    for c in text.chars().chain([' ']) {
        if c == '"' {
            in_string = !in_string;
        }
        if !in_string && (c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '+')) {
            token.push(c);
            continue;
        }
        if let Ok(x) = token.parse::<f64>() {
            if token.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '.') {
                assert_plain(&token, x);
                count += 1;
            }
        } else {
            assert!(
                !token.starts_with(|c: char| c.is_ascii_digit()),
                "{what}: {token:?} is not a number"
            );
        }
        token.clear();
    }
    count
}

#[test]
fn csv_cells_are_plain() {
    let mut digits = zmij::Buffer::new();
    for x in AWKWARD {
        let text = number(&mut digits, x).to_string();
        println!("CSV {x:e}: {text}");
        assert_plain(&text, x);
    }
    assert_eq!(number(&mut digits, 2.0), "2");
    assert_eq!(number(&mut digits, 0.1), "0.1");
}

#[test]
fn toml_floats_are_plain_and_stay_floats() {
    for x in AWKWARD {
        let text = toml_float(x);
        println!("TOML {x:e}: {text}");
        assert_plain(&text, x);
        let v: toml::Table = toml::from_str(&format!("x = {text}")).unwrap();
        let back = v["x"]
            .as_float()
            .unwrap_or_else(|| panic!("{text} is not a TOML float"));
        assert_eq!(back.to_bits(), x.to_bits());
    }
    // Strings, keys and integers are left alone.
    let text =
        "name = \"0.00000000000000010605752387249069\"\n'1.50' = 0.0000000000000001\nn = [1, 2]\n";
    assert_eq!(
        plain_toml(text),
        "name = \"0.00000000000000010605752387249069\"\n'1.50' = 1e-16\nn = [1, 2]\n"
    );
}

/// Every built-in scene's dump, and one holding the awkward values, read back bit for bit,
/// floats as floats, and with plain numbers only.
#[test]
fn scene_dumps_read_back_exactly() {
    let mut scenes: Vec<Scene> = builtin_names()
        .iter()
        .map(|n| builtin(n).unwrap())
        .collect();
    let mut awkward = builtin("prism2").unwrap();
    for (k, node) in awkward.nodes.iter_mut().enumerate() {
        for (i, x) in node.iter_mut().enumerate() {
            *x = AWKWARD[(3 * k + i) % AWKWARD.len()];
        }
    }
    awkward.name = "awkward".into();
    scenes.push(awkward);
    for scene in &scenes {
        let ours = scene.to_toml_string();
        // The toml crate's own dump is exact too (fixed notation): the same values.
        let theirs = toml::to_string(scene).unwrap();
        let (a, b): (toml::Table, toml::Table) = (
            toml::from_str(&ours).unwrap(),
            toml::from_str(&theirs).unwrap(),
        );
        assert_eq!(a, b, "{}: the dump reads back differently", scene.name);
        let back: Scene = toml::from_str(&ours).unwrap();
        assert_eq!(toml::to_string(&back).unwrap(), theirs, "{}", scene.name);
        let floats = toml_floats(&toml::Value::Table(a));
        for x in &floats {
            // Each float appears in the text in its shortest form.
            let plain = toml_float(*x);
            assert!(ours.contains(&plain), "{}: {plain} missing", scene.name);
            assert_plain(&plain, *x);
        }
        let n = assert_all_plain(&scene.name, &ours);
        println!(
            "{}: {} floats, {n} numbers, all plain",
            scene.name,
            floats.len()
        );
    }
    // The CLI prints the same text.
    let (ok, out, err) = cli_support::run(&["scene", "prism2"]);
    assert!(ok, "{err}");
    assert!(out.contains("-1.0605752387249069e-16"), "{out}");
    assert_eq!(
        out.trim_end(),
        builtin("prism2").unwrap().to_toml_string().trim_end()
    );
}

fn toml_floats(v: &toml::Value) -> Vec<f64> {
    match v {
        toml::Value::Float(x) => vec![*x],
        toml::Value::Array(a) => a.iter().flat_map(toml_floats).collect(),
        toml::Value::Table(t) => t.values().flat_map(toml_floats).collect(),
        _ => Vec::new(),
    }
}

#[test]
fn json_numbers_are_plain() {
    for x in AWKWARD {
        let text = serde_json::to_string(&x).unwrap();
        println!("JSON {x:e}: {text}");
        assert_plain(&text, x);
    }
    for name in builtin_names() {
        if name == "tower20" {
            continue; // the same writer; keeps the test short
        }
        let (ok, out, err) = cli_support::run(&["modes", name, "--json"]);
        assert!(ok, "{name}: {err}");
        let n = assert_all_plain("modes --json", &out);
        let path = cli_support::temp(&format!("{name}-linear.json"));
        let (ok, _, err) = cli_support::run(&["linearize", name, "-o", path.to_str().unwrap()]);
        assert!(ok, "{name}: {err}");
        let m = assert_all_plain("linearize", &std::fs::read_to_string(&path).unwrap());
        println!("{name}: {n} numbers in modes --json, {m} in the linear model, all plain");
    }
}

#[test]
fn csv_files_are_plain() {
    let csv = cli_support::temp("prism2.csv");
    let (ok, _, err) = cli_support::run(&[
        "simulate",
        "prism2",
        "--time",
        "0.05",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let n = assert_all_plain("simulate", text.split_once('\n').unwrap().1);
    let shapes = cli_support::temp("prism2-shapes.csv");
    let (ok, _, err) = cli_support::run(&["modes", "prism2", "-o", shapes.to_str().unwrap()]);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&shapes).unwrap();
    let m = assert_all_plain("modes --shapes", text.split_once('\n').unwrap().1);
    println!("simulate: {n} numbers, modes --shapes: {m}, all plain");
    assert!(n > 1000 && m > 100);
}

/// `report accuracy`'s `accuracy.csv` (a short sweep): every figure plain.
#[test]
fn accuracy_csv_is_plain() {
    use tensegrity_fmu::report::{self, Options};
    let dir = cli_support::temp("accuracy-report");
    let options = Options {
        horizon: 0.2,
        fixed_steps: 2,
        dopri5_tols: vec![1e-6],
        min_repeats: 1,
        min_timing_s: 0.0,
        ..Options::default()
    };
    let r = report::accuracy(&builtin("prism2").unwrap(), &options, &dir).expect("report");
    let text = std::fs::read_to_string(&r.csv).unwrap();
    let n = assert_all_plain("accuracy.csv", text.split_once('\n').unwrap().1);
    println!("accuracy.csv: {n} numbers, all plain\n{text}");
    assert!(n >= 7 * r.runs.len());
}
