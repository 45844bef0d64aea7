//! Reading a scene from TOML or JSON text or a file. A parse error names the key (with
//! 1-based list indices), the line and column, and quotes the line, cut to a readable
//! length.

use std::path::Path;

use super::Scene;
use crate::error::SceneError;

impl Scene {
    /// Parses a TOML scene. Errors name the key (1-based list indices, as everywhere),
    /// the line and column, and quote the line, cut to a readable length.
    pub fn from_toml_str(text: &str) -> Result<Self, SceneError> {
        let parse = |e: toml::de::Error, key: String| SceneError::Parse {
            format: "TOML",
            message: toml_message(text, &key, &e),
        };
        let de = toml::de::Deserializer::parse(text).map_err(|e| parse(e, String::new()))?;
        serde_path_to_error::deserialize(de).map_err(|e| {
            let key = key_path(e.path());
            parse(e.into_inner(), key)
        })
    }

    /// Parses a JSON scene. Errors name the key (1-based list indices), line and column.
    pub fn from_json_str(text: &str) -> Result<Self, SceneError> {
        let mut de = serde_json::Deserializer::from_str(text);
        let scene: Self = serde_path_to_error::deserialize(&mut de).map_err(|e| {
            let key = key_path(e.path());
            SceneError::Parse {
                format: "JSON",
                message: with_key(&key, &cut(&e.into_inner().to_string(), MAX_MESSAGE)),
            }
        })?;
        de.end().map_err(|e| SceneError::Parse {
            format: "JSON",
            message: e.to_string(),
        })?;
        Ok(scene)
    }

    /// Reads a scene file; `.json` is JSON, anything else TOML.
    pub fn from_file(path: &Path) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|e| SceneError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        let is_json = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        let mut scene = if is_json {
            Self::from_json_str(&text)
        } else {
            Self::from_toml_str(&text)
        }?;
        let dir = path.parent().unwrap_or(Path::new("."));
        for (i, t) in scene.terrain.iter_mut().enumerate() {
            t.read_file(&format!("terrain[{}]", i + 1), dir)?;
        }
        Ok(scene)
    }
}

/// Longest parser message or quoted line kept in an error, in characters.
const MAX_MESSAGE: usize = 300;
/// Longest quoted scene line in an error, in characters.
const MAX_SNIPPET: usize = 80;
/// Longest key in an error, in characters (an unknown key can be a whole line of text).
const MAX_KEY: usize = 80;

/// A serde path with 1-based list indices: `bars[2].mass`.
fn key_path(path: &serde_path_to_error::Path) -> String {
    use serde_path_to_error::Segment;
    let mut key = String::new();
    for segment in path.iter() {
        match segment {
            Segment::Seq { index } => key.push_str(&format!("[{}]", index + 1)),
            Segment::Map { key: k } => {
                if !key.is_empty() {
                    key.push('.');
                }
                key.push_str(k);
            }
            Segment::Enum { .. } | Segment::Unknown => {}
        }
    }
    key
}

/// `key: message` on one line: a key may hold any character, line breaks included, and
/// the parser's message quotes it.
fn with_key(key: &str, message: &str) -> String {
    let text = if key.is_empty() {
        message.to_string()
    } else {
        format!("{}: {message}", cut(key, MAX_KEY))
    };
    text.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// `key: message (line L, column C: `the line`)`, the line cut around the column.
fn toml_message(text: &str, key: &str, e: &toml::de::Error) -> String {
    let message = cut(e.message().trim_end(), MAX_MESSAGE);
    let Some(span) = e.span() else {
        return with_key(key, &message);
    };
    let start = span.start.min(text.len());
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[start..].find('\n').map_or(text.len(), |i| start + i);
    let line_no = text[..start].matches('\n').count() + 1;
    let line = text[line_start..line_end].trim_end_matches('\r');
    let column = text[line_start..start].chars().count();
    let snippet = cut_around(line, column, MAX_SNIPPET);
    with_key(
        key,
        &format!(
            "{message} (line {line_no}, column {}: `{snippet}`)",
            column + 1
        ),
    )
}

/// `text` cut to at most `max` characters, with an ellipsis where it was cut.
fn cut(text: &str, max: usize) -> String {
    if text.chars().count() <= max {
        return text.to_string();
    }
    let head: String = text.chars().take(max * 3 / 4).collect();
    let tail: String = {
        let tail: Vec<char> = text.chars().rev().take(max / 4).collect();
        tail.into_iter().rev().collect()
    };
    format!("{head}…{tail}")
}

/// At most `max` characters of `line` around character `column`, with ellipses.
fn cut_around(line: &str, column: usize, max: usize) -> String {
    let chars: Vec<char> = line.chars().collect();
    if chars.len() <= max {
        return line.to_string();
    }
    let from = column.saturating_sub(max / 4).min(chars.len() - max);
    let to = from + max;
    let mut out = String::new();
    if from > 0 {
        out.push('…');
    }
    out.extend(&chars[from..to]);
    if to < chars.len() {
        out.push('…');
    }
    out
}
