//! Numbers as the project writes them in text (CSV, TOML scene dumps, JSON): the shortest
//! decimal that reads back as the same `f64`, in exponent form where fixed notation would
//! be long (`-1.0605752387249069e-16`, `1e+21`, `0.1`). All of it is zmij's shortest
//! round-trip formatting, which serde_json uses for JSON as well.

use std::io::Write;

/// Writes a number as people write it in a CSV cell: the shortest decimal that reads back
/// as the same `f64` (`0`, `0.5773502691896258`, `-12.5`, `1e-7`, `1.5e+20`), `NaN`, `inf`
/// or `-inf`.
pub fn write_number(w: &mut impl Write, x: f64) -> std::io::Result<()> {
    w.write_all(number(&mut zmij::Buffer::new(), x).as_bytes())
}

/// The text of [`write_number`], for a message.
pub fn shortest(x: f64) -> String {
    number(&mut zmij::Buffer::new(), x).to_string()
}

/// The text of [`write_number`], formatted in `digits`.
pub fn number(digits: &mut zmij::Buffer, x: f64) -> &str {
    if x == 0.0 {
        return if x.is_sign_negative() { "-0" } else { "0" };
    }
    if !x.is_finite() {
        return if x.is_nan() {
            "NaN"
        } else if x > 0.0 {
            "inf"
        } else {
            "-inf"
        };
    }
    // zmij prints integers as `12.0`, large and small magnitudes as `1.5e+20`, `1e-7`.
    let s = digits.format_finite(x);
    s.strip_suffix(".0").unwrap_or(s)
}

/// A TOML float: the shortest round-trip decimal that TOML still reads as a float (`2.0`,
/// `0.1`, `1e-16`, `-0.0`, `inf`, `nan`).
pub fn toml_float(x: f64) -> String {
    if x.is_nan() {
        return "nan".into();
    }
    if x.is_infinite() {
        return if x > 0.0 { "inf" } else { "-inf" }.into();
    }
    zmij::Buffer::new().format_finite(x).to_string()
}

/// TOML text (as the `toml` crate writes it) with every float rewritten by [`toml_float`]:
/// the crate writes floats in fixed notation, `-0.00000000000000010605752387249069` for
/// −1.06e-16. Strings are left alone; a float is a bare value token (after `=`, `[` or
/// `,`, not a key) with a `.`, an exponent, `inf` or `nan` that parses as an `f64`.
pub fn plain_toml(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let mut value_position = false;
    while i < bytes.len() {
        let b = bytes[i];
        match b {
            b'"' | b'\'' => {
                let end = string_end(bytes, i);
                out.push_str(&text[i..end]);
                i = end;
                value_position = false;
            }
            b'=' | b'[' | b',' => {
                out.push(b as char);
                i += 1;
                value_position = true;
            }
            b' ' | b'\t' | b'\n' | b'\r' => {
                out.push(b as char);
                i += 1;
            }
            _ => {
                let end = (i..bytes.len())
                    .find(|&k| !is_bare(bytes[k]))
                    .unwrap_or(bytes.len())
                    .max(i + 1);
                let token = &text[i..end];
                let is_key = text[end..].trim_start_matches([' ', '\t']).starts_with('=');
                match token.parse::<f64>() {
                    Ok(x) if value_position && !is_key && is_float_literal(token) => {
                        out.push_str(&toml_float(x));
                    }
                    _ => out.push_str(token),
                }
                i = end;
                value_position = false;
            }
        }
    }
    out
}

/// Characters of a bare TOML token (key, number, boolean).
fn is_bare(b: u8) -> bool {
    b.is_ascii_alphanumeric() || matches!(b, b'_' | b'-' | b'+' | b'.')
}

/// A TOML float literal, not an integer (TOML reads `2` as an integer, `2.0` as a float).
fn is_float_literal(token: &str) -> bool {
    let t = token.trim_start_matches(['+', '-']);
    t == "inf" || t == "nan" || t.contains(['.', 'e', 'E'])
}

/// The index just past the TOML string starting at `start` (basic or literal, single- or
/// triple-quoted).
fn string_end(bytes: &[u8], start: usize) -> usize {
    let quote = bytes[start];
    let triple = bytes[start..].starts_with(&[quote; 3]);
    let mut i = start + if triple { 3 } else { 1 };
    while i < bytes.len() {
        if quote == b'"' && bytes[i] == b'\\' {
            i += 2;
            continue;
        }
        if triple {
            if bytes[i..].starts_with(&[quote; 3]) {
                // A closing run may hold up to two more quotes that belong to the string.
                let mut end = i + 3;
                while end < bytes.len() && bytes[end] == quote && end < i + 5 {
                    end += 1;
                }
                return end;
            }
        } else if bytes[i] == quote {
            return i + 1;
        }
        i += 1;
    }
    bytes.len()
}
