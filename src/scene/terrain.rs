//! Terrain: planes, boxes and heightfields that bars touch along their whole length,
//! each with its own penalty contact and friction.

use serde::{Deserialize, Serialize};
use std::path::Path;

use super::validate::{finite, finite_vec};
use crate::error::SceneError;

/// Most heights in one heightfield: far beyond a robot's terrain (a 1000 × 1000 grid), and
/// small enough that reading one stays quick.
pub const MAX_HEIGHTS: usize = 1_000_000;

/// What a terrain shape is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TerrainKind {
    /// `point`, `normal`.
    Plane,
    /// `center`, `size`, `yaw`.
    Box,
    /// `file` (or `heights`), `origin`, `spacing`.
    Heightfield,
}

/// One terrain shape. The keys a kind does not use are refused.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TerrainSpec {
    /// plane, box or heightfield.
    pub kind: TerrainKind,
    /// Plane: a point on it, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<[f64; 3]>,
    /// Plane: outward normal (any length > 0); `[0, 0, 1]` by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal: Option<[f64; 3]>,
    /// Box: centre, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<[f64; 3]>,
    /// Box: full edge lengths along x, y, z before the yaw, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<[f64; 3]>,
    /// Box: rotation about z, degrees (0 by default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub yaw: Option<f64>,
    /// Heightfield: a CSV file of heights (m), relative to the scene file; row j at
    /// `y₀ + j dy`, column i at `x₀ + i dx`. Read when the scene is, into `heights`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// Heightfield: the heights themselves, rows along x (instead of `file`), m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heights: Option<Vec<Vec<f64>>>,
    /// Heightfield: `(x₀, y₀)` of the first height, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin: Option<[f64; 2]>,
    /// Heightfield: grid spacing `(dx, dy)`, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spacing: Option<[f64; 2]>,
    /// Penalty stiffness, N/m.
    pub stiffness: f64,
    /// Penalty damping on the normal approach speed, N·s/m.
    #[serde(default)]
    pub damping: f64,
    /// Coulomb friction coefficient μ.
    #[serde(default)]
    pub friction: f64,
    /// Tangential speed below which friction is viscous (regularised Coulomb), m/s.
    #[serde(default = "default_slip_velocity")]
    pub slip_velocity: f64,
    /// How friction acts at the bars' ends: it sticks below μ N (the default), or it is
    /// regularised Coulomb everywhere.
    #[serde(default, skip_serializing_if = "FrictionModel::is_default")]
    pub friction_model: FrictionModel,
}

/// A terrain shape's friction law at the capsules' ends (their sides slide regularised).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrictionModel {
    /// An elastic–plastic tangential spring per contact: static friction up to μ N without
    /// creep, kinetic friction μ N while sliding.
    #[default]
    StickSlip,
    /// Friction `μ N` against the tangential velocity, viscous below `slip_velocity`: a
    /// loaded contact creeps at a speed below it.
    Regularized,
}

impl FrictionModel {
    fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

fn default_slip_velocity() -> f64 {
    1e-2
}

impl TerrainKind {
    /// The scene name of the kind.
    pub fn name(self) -> &'static str {
        match self {
            Self::Plane => "plane",
            Self::Box => "box",
            Self::Heightfield => "heightfield",
        }
    }
}

impl TerrainSpec {
    /// Reads a heightfield's `file` (relative to `dir`) into `heights`, so that the scene
    /// holds all it needs (an FMU ships it whole).
    pub fn read_file(&mut self, key: &str, dir: &Path) -> Result<(), SceneError> {
        let Some(file) = self.file.take() else {
            return Ok(());
        };
        if self.heights.is_some() {
            return Err(SceneError::invalid(
                format!("{key}.file"),
                "give either file or heights, not both",
            ));
        }
        let path = dir.join(&file);
        let text = std::fs::read_to_string(&path).map_err(|e| {
            SceneError::invalid(
                format!("{key}.file"),
                format!("cannot read {}: {e}", path.display()),
            )
        })?;
        self.heights = Some(parse_heights(&text).map_err(|reason| {
            SceneError::invalid(
                format!("{key}.file"),
                format!("{}: {reason}", path.display()),
            )
        })?);
        Ok(())
    }

    /// Checks the keys of one shape; `key` is `terrain[i]`.
    pub fn validate(&self, key: &str) -> Result<(), SceneError> {
        let kind = self.kind.name();
        let used: &[&str] = match self.kind {
            TerrainKind::Plane => &["point", "normal"],
            TerrainKind::Box => &["center", "size", "yaw"],
            TerrainKind::Heightfield => &["file", "heights", "origin", "spacing"],
        };
        let given = [
            ("point", self.point.is_some()),
            ("normal", self.normal.is_some()),
            ("center", self.center.is_some()),
            ("size", self.size.is_some()),
            ("yaw", self.yaw.is_some()),
            ("file", self.file.is_some()),
            ("heights", self.heights.is_some()),
            ("origin", self.origin.is_some()),
            ("spacing", self.spacing.is_some()),
        ];
        for (name, present) in given {
            if present && !used.contains(&name) {
                return Err(SceneError::invalid(
                    format!("{key}.{name}"),
                    format!("a {kind} has no {name} (its keys: {})", used.join(", ")),
                ));
            }
        }
        let required = |name: &str, present: bool| {
            if present {
                Ok(())
            } else {
                Err(SceneError::invalid(
                    format!("{key}.{name}"),
                    format!("a {kind} needs {name}"),
                ))
            }
        };
        match self.kind {
            TerrainKind::Plane => {
                required("point", self.point.is_some())?;
                finite_vec(&format!("{key}.point"), &self.point.unwrap_or_default())?;
                let n = self.normal.unwrap_or([0.0, 0.0, 1.0]);
                finite_vec(&format!("{key}.normal"), &n)?;
                if n.iter().map(|x| x * x).sum::<f64>() == 0.0 {
                    return Err(SceneError::invalid(
                        format!("{key}.normal"),
                        "must not be the zero vector",
                    ));
                }
            }
            TerrainKind::Box => {
                required("center", self.center.is_some())?;
                required("size", self.size.is_some())?;
                finite_vec(&format!("{key}.center"), &self.center.unwrap_or_default())?;
                let size = self.size.unwrap_or_default();
                finite_vec(&format!("{key}.size"), &size)?;
                if size.iter().any(|&l| l <= 0.0) {
                    return Err(SceneError::invalid(
                        format!("{key}.size"),
                        format!("edge lengths must be positive, got {size:?}"),
                    ));
                }
                finite(&format!("{key}.yaw"), self.yaw.unwrap_or(0.0))?;
            }
            TerrainKind::Heightfield => self.validate_grid(key)?,
        }
        contact_law(
            key,
            [
                self.stiffness,
                self.damping,
                self.friction,
                self.slip_velocity,
            ],
        )
    }

    fn validate_grid(&self, key: &str) -> Result<(), SceneError> {
        let Some(rows) = &self.heights else {
            return Err(SceneError::invalid(
                format!("{key}.file"),
                if self.file.is_some() {
                    "a scene given as text cannot read a file: give the heights inline as `heights`, or load the scene from its file"
                } else {
                    "a heightfield needs file (a CSV of heights) or heights"
                },
            ));
        };
        let spacing = self.spacing.ok_or_else(|| {
            SceneError::invalid(
                format!("{key}.spacing"),
                "a heightfield needs spacing [dx, dy]",
            )
        })?;
        let origin = self.origin.unwrap_or([0.0, 0.0]);
        for (name, v) in [("origin", origin), ("spacing", spacing)] {
            finite_vec(&format!("{key}.{name}"), &[v[0], v[1], 0.0])?;
        }
        if spacing.iter().any(|&d| d <= 0.0) {
            return Err(SceneError::invalid(
                format!("{key}.spacing"),
                format!("must be positive, got {spacing:?}"),
            ));
        }
        if self.origin.is_none() {
            return Err(SceneError::invalid(
                format!("{key}.origin"),
                "a heightfield needs origin [x0, y0], the position of its first height",
            ));
        }
        let columns = rows.first().map_or(0, Vec::len);
        if rows.len() < 2 || columns < 2 {
            return Err(SceneError::invalid(
                format!("{key}.heights"),
                format!(
                    "needs at least 2 rows of at least 2 heights, got {} row(s) of {columns}",
                    rows.len()
                ),
            ));
        }
        if rows.len() * columns > MAX_HEIGHTS {
            return Err(SceneError::invalid(
                format!("{key}.heights"),
                format!(
                    "{} × {columns} heights exceed the limit of {MAX_HEIGHTS}: use a coarser grid",
                    rows.len()
                ),
            ));
        }
        for (j, row) in rows.iter().enumerate() {
            if row.len() != columns {
                return Err(SceneError::invalid(
                    format!("{key}.heights[{}]", j + 1),
                    format!("has {} heights but row 1 has {columns}", row.len()),
                ));
            }
            for (i, &h) in row.iter().enumerate() {
                finite(&format!("{key}.heights[{}][{}]", j + 1, i + 1), h)?;
            }
        }
        Ok(())
    }
}

/// Rows of comma-separated heights; blank lines and lines starting with `#` are skipped.
fn parse_heights(text: &str) -> Result<Vec<Vec<f64>>, String> {
    let mut rows = Vec::new();
    let mut count = 0usize;
    for (l, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut row = Vec::new();
        for (c, field) in line.split(',').enumerate() {
            let field = field.trim();
            let h: f64 = field.parse().map_err(|_| {
                let shown: String = field.chars().take(40).collect();
                format!(
                    "line {}, column {}: '{shown}' is not a number (heights in m, comma-separated)",
                    l + 1,
                    c + 1
                )
            })?;
            row.push(h);
            count += 1;
            if count > MAX_HEIGHTS {
                return Err(format!(
                    "more than {MAX_HEIGHTS} heights: use a coarser grid"
                ));
            }
        }
        rows.push(row);
    }
    Ok(rows)
}

/// Contact between the capsules of any two bars that share no node.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CollisionSpec {
    /// Penalty stiffness, N/m.
    pub stiffness: f64,
    /// Penalty damping on the normal approach speed, N·s/m.
    #[serde(default)]
    pub damping: f64,
    /// Coulomb friction coefficient μ.
    #[serde(default)]
    pub friction: f64,
    /// Tangential speed below which friction is viscous (regularised Coulomb), m/s.
    #[serde(default = "default_slip_velocity")]
    pub slip_velocity: f64,
}

impl CollisionSpec {
    /// Checks the settings.
    pub fn validate(&self) -> Result<(), SceneError> {
        contact_law(
            "collisions",
            [
                self.stiffness,
                self.damping,
                self.friction,
                self.slip_velocity,
            ],
        )
    }
}

/// Checks `[stiffness, damping, friction, slip_velocity]` under `key`.
fn contact_law(key: &str, values: [f64; 4]) -> Result<(), SceneError> {
    let names = ["stiffness", "damping", "friction", "slip_velocity"];
    for ((name, v), positive) in names.iter().zip(values).zip([true, false, false, true]) {
        finite(&format!("{key}.{name}"), v)?;
        if v < 0.0 || (positive && v == 0.0) {
            return Err(SceneError::invalid(
                format!("{key}.{name}"),
                format!(
                    "must be {}, got {v}",
                    if positive { "positive" } else { "≥ 0" }
                ),
            ));
        }
    }
    Ok(())
}
