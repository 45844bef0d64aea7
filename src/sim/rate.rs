//! A rate the stability guard sees, with what causes it, and how its figures are written.

/// Where a rate comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum Cause {
    /// Cables carrying most of the mode's stiffness.
    Cables {
        /// Their indices (0-based), largest term first.
        cables: Vec<usize>,
        /// Their share of the mode's stiffness, 0–1.
        share: f64,
        /// Every cable at least as stiff as the weakest of them (the ones a fix softens).
        family: Vec<usize>,
        /// The family's share of the mode's stiffness, 0–1.
        family_share: f64,
    },
    /// The ground's penalty oscillator `√(k w) + c w`.
    GroundPenalty,
    /// Ground friction, viscous below the slip velocity: `μ W w / v_s`.
    Friction,
    /// Terrain shape k's penalty oscillator (0-based), as the ground's.
    TerrainPenalty(usize),
    /// Terrain shape k's friction, viscous below its slip velocity, as the ground's.
    TerrainFriction(usize),
    /// Bar–bar contact's penalty oscillator, as the ground's.
    CollisionPenalty,
    /// Bar–bar friction, viscous below its slip velocity, as the ground's.
    CollisionFriction,
    /// The structure's fastest mode with no cable or contact dominating its stiffness
    /// (bars' constraint forces, many comparable terms).
    Structure,
    /// A damped cable's extension decaying at `c (w_a + w_b)` (index 0-based).
    CableDamping(usize),
    /// Gravity moving the structure over its size: `√(|a| / L)`.
    Gravity,
    /// Scripted load `k` (0-based) moving its node over the structure's size: `√(|F| w / L)`.
    Load(usize),
    /// Forces unbalanced at the start (a geometry out of equilibrium) moving the structure
    /// over its size: `√(|a| / L)`.
    Unbalanced,
}

/// A rate, 1/s (an angular frequency for an oscillation), with its cause and the node
/// whose mass it moves (0-based; the most compliant contact end for the contact bounds).
#[derive(Debug, Clone, PartialEq)]
pub struct Rate {
    /// ω, 1/s.
    pub omega: f64,
    /// What sets it.
    pub cause: Cause,
    /// The node that moves most in it, if known.
    pub node: Option<usize>,
}

/// Four significant digits, plainly between 1e-3 and 1e5 (58.86, 0.01, 100), else as
/// 1e8 or 5.292e6.
pub fn num(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let rounded: f64 = format!("{x:.3e}").parse().unwrap_or(x);
    if (1e-3..1e5).contains(&rounded.abs()) {
        format!("{rounded}")
    } else {
        format!("{rounded:e}")
    }
}

/// `x` rounded up to two significant digits (0.0706 → 0.071).
pub fn round_up(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return x;
    }
    let unit = 10f64.powi(x.log10().floor() as i32 - 1);
    let y = (x / unit * (1.0 - 1e-12)).ceil() * unit;
    num(y).parse().unwrap_or(y)
}
