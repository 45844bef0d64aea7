//! Finding where a switching function crosses zero inside a step: on the cubic Hermite
//! interpolant of the bar ends, by the Illinois method.

/// The crossing is located to this fraction of the step.
const TOLERANCE: f64 = 1e-12;

/// Most Illinois iterations per crossing.
const MAX_ITERATIONS: usize = 100;

/// The cubic Hermite weights of `(x₀, ẋ₀, x₁, ẋ₁)` at `u = θ/h`.
#[inline]
pub(super) fn hermite(u: f64, h: f64) -> [f64; 4] {
    let (u2, u3) = (u * u, u * u * u);
    [
        2.0 * u3 - 3.0 * u2 + 1.0,
        h * (u3 - 2.0 * u2 + u),
        -2.0 * u3 + 3.0 * u2,
        h * (u3 - u2),
    ]
}

/// Illinois (modified regula falsi) on a switch `g(θ)` with `g(0) = g0`, `g(h) = g1` of
/// opposite signs; the end of the final bracket on the far side of the crossing.
pub(super) fn crossing(g: impl Fn(f64) -> f64, g0: f64, g1: f64, h: f64) -> f64 {
    let (mut a, mut fa) = (0.0, g0);
    let (mut b, mut fb) = (h, g1);
    let after = g1 > 0.0;
    let mut side = 0i8;
    for _ in 0..MAX_ITERATIONS {
        if b - a <= TOLERANCE * h {
            break;
        }
        let mut c = (a * fb - b * fa) / (fb - fa);
        if !(c > a && c < b) {
            c = 0.5 * (a + b);
        }
        let fc = g(c);
        if (fc > 0.0) == after {
            b = c;
            fb = fc;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        } else {
            a = c;
            fa = fc;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        }
    }
    b
}
