//! Limits that keep a scene within what the numerics and the FMU's importers can carry:
//! names and text that XML, file systems and C accept, masses whose ratios the
//! constraint equations can resolve, node positions and speeds a double resolves, and no
//! two bars on the same pair of nodes. Restored FMU states are held to the same position
//! and speed limits.

use super::Scene;
use crate::error::SceneError;
use crate::numbers::shortest;

/// Longest `name`, in characters: it names the FMU file and its folder when unzipped,
/// and file systems allow 255 bytes.
pub const MAX_NAME_CHARS: usize = 100;
/// Longest `name` in UTF-8 bytes: `.<name>.fmu.partial-<pid>` must fit in 255 bytes.
pub const MAX_NAME_BYTES: usize = 200;
/// Longest `description`, in characters.
pub const MAX_DESCRIPTION_CHARS: usize = 10_000;
/// Masses outside this range (kg) overflow the inverse-mass products.
pub const MASS_RANGE: (f64, f64) = (1e-15, 1e15);
/// Largest ratio of two masses (bars and payloads): beyond it the mass matrix is so ill
/// conditioned that λ and the reactions keep few correct digits.
pub const MAX_MASS_RATIO: f64 = 1e8;
/// Farthest a node may be from the origin along any axis, m: beyond it a double resolves
/// less than 1e-7 m, too coarse to hold a bar's length.
pub const MAX_COORDINATE: f64 = 1e9;
/// Fastest a node may move along any axis, m/s: the speed of light, which nothing a
/// scene in SI units describes reaches.
pub const MAX_SPEED: f64 = 299_792_458.0;

/// Refuses a node position outside ±[`MAX_COORDINATE`] on some axis (or not finite).
pub fn check_position(key: &str, x: &[f64; 3]) -> Result<(), SceneError> {
    check_bound(key, x, MAX_COORDINATE, "m", "coordinates")
}

/// Refuses a node velocity outside ±[`MAX_SPEED`] on some axis (or not finite).
pub fn check_velocity(key: &str, v: &[f64; 3]) -> Result<(), SceneError> {
    check_bound(key, v, MAX_SPEED, "m/s", "velocity components")
}

fn check_bound(
    key: &str,
    x: &[f64; 3],
    bound: f64,
    unit: &str,
    what: &str,
) -> Result<(), SceneError> {
    let Some(axis) = x.iter().position(|c| c.is_nan() || c.abs() > bound) else {
        return Ok(());
    };
    let (name, c) = (["x", "y", "z"][axis], shortest(x[axis]));
    let reason = if x[axis].is_finite() {
        format!("{name} = {c} {unit} is outside ±{bound:e} {unit}, the range of node {what}")
    } else {
        format!("{name} = {c} is not a finite number")
    };
    Err(SceneError::invalid(key, reason))
}

/// Checks `name`, `description`, the masses and duplicated bars.
pub(super) fn check(scene: &Scene) -> Result<(), SceneError> {
    check_name(&scene.name)?;
    if let Some(d) = &scene.description {
        check_text("description", d, MAX_DESCRIPTION_CHARS, true)?;
    }
    check_masses(scene)?;
    check_duplicate_bars(scene)
}

fn check_name(name: &str) -> Result<(), SceneError> {
    check_text("name", name, MAX_NAME_CHARS, false)?;
    if name.len() > MAX_NAME_BYTES {
        return Err(SceneError::invalid(
            "name",
            format!(
                "takes {} bytes in UTF-8; at most {MAX_NAME_BYTES} are allowed (it becomes file \
                 names, which hold 255 bytes). Shorten it",
                name.len()
            ),
        ));
    }
    if let Some(c) = name.chars().find(|c| matches!(c, '/' | '\\')) {
        return Err(SceneError::invalid(
            "name",
            format!(
                "contains '{c}', a path separator: the name becomes file names (<name>.fmu, \
                 <name>.csv). Use letters, digits, spaces, '-', '_' or '.'"
            ),
        ));
    }
    if name.starts_with('.') || name.starts_with('-') {
        return Err(SceneError::invalid(
            "name",
            "must not start with '.' or '-' (it becomes a file name); start with a letter or digit",
        ));
    }
    Ok(())
}

/// Control characters (XML 1.0 cannot carry most of them, and none belongs in a name)
/// and the non-characters U+FFFE/U+FFFF; tabs and line breaks only where the text may
/// span lines.
fn forbidden(c: char, multiline: bool) -> bool {
    if matches!(c, '\t' | '\n' | '\r') {
        return !multiline;
    }
    c.is_control() || matches!(c, '\u{FFFE}' | '\u{FFFF}')
}

fn check_text(key: &str, text: &str, max_chars: usize, multiline: bool) -> Result<(), SceneError> {
    let count = text.chars().count();
    if count > max_chars {
        return Err(SceneError::invalid(
            key,
            format!("has {count} characters; at most {max_chars} are allowed. Shorten it"),
        ));
    }
    if let Some((at, c)) = text
        .chars()
        .enumerate()
        .find(|&(_, c)| forbidden(c, multiline))
    {
        return Err(SceneError::invalid(
            key,
            format!(
                "character {} is U+{:04X}, a control or non-character that modelDescription.xml \
                 cannot hold; remove it",
                at + 1,
                u32::from(c)
            ),
        ));
    }
    Ok(())
}

fn check_masses(scene: &Scene) -> Result<(), SceneError> {
    let masses = scene
        .bars
        .iter()
        .enumerate()
        .map(|(i, b)| (format!("bars[{}].mass", i + 1), b.mass))
        .chain(
            scene
                .point_masses
                .iter()
                .enumerate()
                .map(|(k, p)| (format!("point_masses[{}].mass", k + 1), p.mass)),
        )
        .filter(|(_, m)| *m > 0.0);
    let (lo, hi) = MASS_RANGE;
    let mut lightest: Option<(String, f64)> = None;
    let mut heaviest: Option<(String, f64)> = None;
    for (key, m) in masses {
        if !(lo..=hi).contains(&m) {
            return Err(SceneError::invalid(
                key,
                format!("{m} kg is outside {lo:e} to {hi:e} kg; express the scene in other units (e.g. g or t) to bring masses near 1"),
            ));
        }
        if lightest.as_ref().is_none_or(|(_, l)| m < *l) {
            lightest = Some((key.clone(), m));
        }
        if heaviest.as_ref().is_none_or(|(_, h)| m > *h) {
            heaviest = Some((key, m));
        }
    }
    if let (Some((light_key, light)), Some((heavy_key, heavy))) = (lightest, heaviest) {
        if heavy > MAX_MASS_RATIO * light {
            return Err(SceneError::invalid(
                heavy_key,
                format!(
                    "{heavy} kg is {:.1e} times {light_key} = {light} kg; mass ratios above \
                     {MAX_MASS_RATIO:e} leave the constraint forces with few correct digits. \
                     Pin the heavy part instead, or bring the masses closer",
                    heavy / light
                ),
            ));
        }
    }
    Ok(())
}

fn check_duplicate_bars(scene: &Scene) -> Result<(), SceneError> {
    let mut pairs: Vec<([usize; 2], usize)> = scene
        .bars
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let [a, c] = b.nodes;
            ([a.min(c), a.max(c)], i)
        })
        .collect();
    pairs.sort_unstable();
    for w in pairs.windows(2) {
        if w[0].0 == w[1].0 {
            let (first, second) = (w[0].1.min(w[1].1), w[0].1.max(w[1].1));
            return Err(SceneError::invalid(
                format!("bars[{}].nodes", second + 1),
                format!(
                    "bars[{}] already joins nodes {} and {}: two rigid bars on one pair of \
                     nodes are one bar (their constraints are redundant). Remove one, or merge \
                     their masses into one bar",
                    first + 1,
                    w[0].0[0],
                    w[0].0[1]
                ),
            ));
        }
    }
    Ok(())
}
