//! `render --mode`: one mode shape animated about the start equilibrium. The frames are
//! `x* + A φ s(t)` (checked against the spectrum at the quarter periods), tensions are those
//! of the displaced geometry, a GIF has one frame per step of the loop, a PNG shows the peak,
//! and bad requests are refused naming --mode.

mod cli_support;

use cli_support::{run, temp};
use tensegrity_fmu::analysis::modes::{ModeKind, Spectrum};
use tensegrity_fmu::render::animation::GIF_SIZE;
use tensegrity_fmu::render::mode::{self, STILL_LOOP};
use tensegrity_fmu::render::Frames;
use tensegrity_fmu::scene::builtin;
use tensegrity_fmu::{Scene, Simulation};

/// The spectrum of a scene's start state.
fn spectrum(scene: &Scene) -> Spectrum {
    let sim = Simulation::new(tensegrity_fmu::analysis::load(scene).unwrap());
    let y = &sim.state().y;
    Spectrum::new(sim.model(), &sim.inputs, sim.time(), &y[..y.len() / 2])
}

fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
    (0..3).all(|i| (a[i] - b[i]).abs() <= tol)
}

/// `x* + c A φ` for every node.
fn displaced(x: &[[f64; 3]], shape: &[nalgebra::Vector3<f64>], c: f64) -> Vec<[f64; 3]> {
    x.iter()
        .zip(shape)
        .map(|(p, d)| [p[0] + c * d.x, p[1] + c * d.y, p[2] + c * d.z])
        .collect()
}

/// prism2 without its pinned bottom ring: free in space, so rigid-body modes and mechanisms.
fn free_prism() -> Scene {
    let text = builtin("prism2").unwrap().to_toml_string();
    let text: Vec<&str> = text.lines().filter(|l| !l.starts_with("fixed")).collect();
    Scene::from_toml_str(&text.join("\n")).unwrap()
}

#[test]
fn frames_are_the_mode_shape_at_quarter_periods_with_displaced_tensions() {
    let scene = builtin("prism2-elastic").unwrap();
    let modes = spectrum(&scene).modes;
    let phi = &modes[0];
    assert_eq!(phi.kind, ModeKind::Vibration);
    let (a, fps) = (0.2, 20.0);
    let anim = mode::animate(&scene, 1, Some(a), fps).unwrap();
    let frames = &anim.frames;
    let period = 1.0 / phi.frequency_hz();
    assert!((anim.period - period).abs() < 1e-12);
    let n = frames.len();
    assert_eq!(
        n,
        4 * (period * fps / 4.0).round() as usize,
        "{period} s at {fps} fps"
    );
    assert_eq!(n % 4, 0);
    assert_eq!(anim.peak, n / 4);
    for (k, &t) in frames.times.iter().enumerate() {
        assert!((t - k as f64 * period / n as f64).abs() < 1e-12);
    }
    assert!(anim.title.starts_with("mode 1, 0.869 Hz"), "{}", anim.title);
    assert_eq!(frames.name, format!("prism2-elastic — {}", anim.title));
    // x* is the simulation's start; the quarters are x* + A φ, x*, x* − A φ, to first
    // order: the bars are then restored to their lengths, a move of about A²/l.
    let rest = Frames::from_run(&scene, &[0.0]).unwrap();
    let x = &rest.positions[0];
    let length = |p: &[[f64; 3]], [i, j]: [usize; 2]| {
        (0..3)
            .map(|c| (p[j][c] - p[i][c]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let shortest = frames
        .bars
        .iter()
        .map(|&b| length(x, b))
        .fold(f64::INFINITY, f64::min);
    let second_order = a * a / shortest;
    let expect = [
        (0, 0.0, 1e-12),
        (n / 4, a, second_order),
        (n / 2, 0.0, 1e-12),
        (3 * n / 4, -a, second_order),
    ];
    for (k, c, tol) in expect {
        let want = displaced(x, &phi.shape, c);
        for (i, (p, q)) in frames.positions[k].iter().zip(&want).enumerate() {
            assert!(
                close(*p, *q, tol),
                "frame {k}, node {}: {p:?} vs {q:?}",
                i + 1
            );
        }
    }
    // The bars keep their lengths in every frame.
    for (k, p) in frames.positions.iter().enumerate() {
        for &b in &frames.bars {
            assert!(
                (length(p, b) - length(x, b)).abs() < 1e-12,
                "frame {k}, bar {b:?}"
            );
        }
    }
    // At a small amplitude the peak is x* + A φ to round-off and its largest node
    // displacement is A.
    let small = 1e-5;
    let tiny = mode::animate(&scene, 1, Some(small), fps).unwrap();
    let want = displaced(x, &phi.shape, small);
    assert!(tiny.frames.positions[n / 4]
        .iter()
        .zip(&want)
        .all(|(p, q)| close(*p, *q, 1e-9)));
    let largest = tiny.frames.positions[n / 4]
        .iter()
        .zip(x)
        .map(|(p, q)| (0..3).map(|i| (p[i] - q[i]).powi(2)).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    assert!((largest - small).abs() < 1e-9, "{largest}");
    // Pinned nodes stay put.
    for &i in &frames.pinned {
        assert!(frames.positions.iter().all(|f| close(f[i], x[i], 0.0)));
    }
    // Velocities are the motion's: A φ 2π f at t = 0, zero at the peak.
    let omega = 2.0 * std::f64::consts::PI / period;
    let v0 = displaced(&vec![[0.0; 3]; x.len()], &phi.shape, a * omega);
    assert!(frames.velocities[0]
        .iter()
        .zip(&v0)
        .all(|(p, q)| close(*p, *q, 1e-12)));
    assert!(frames.velocities[n / 4]
        .iter()
        .all(|v| close(*v, [0.0; 3], 1e-12)));
    // Tensions are those of each geometry: at x* the equilibrium's, elsewhere not.
    for (t, t0) in frames.tensions[0].iter().zip(&rest.tensions[0]) {
        assert!((t - t0).abs() <= 1e-9 * t0.abs().max(1.0), "{t} vs {t0}");
    }
    let changed = |k: usize| {
        frames.tensions[k]
            .iter()
            .zip(&rest.tensions[0])
            .map(|(t, t0)| (t - t0).abs())
            .fold(0.0, f64::max)
    };
    assert!(
        changed(n / 4) > 0.1,
        "peak tensions differ by {}",
        changed(n / 4)
    );
    assert!(changed(3 * n / 4) > 0.1);
    assert_ne!(frames.tensions[n / 4], frames.tensions[3 * n / 4]);
    // Default amplitude: a tenth of the structure's largest extent (prism2 is 1.577 m tall).
    let default = mode::animate(&scene, 1, None, fps).unwrap();
    assert!((default.amplitude - 0.1 * 1.5773502691896257).abs() < 1e-12);
}

#[test]
fn zero_frequency_modes_loop_linearly_over_two_seconds() {
    let scene = free_prism();
    let modes = spectrum(&scene).modes;
    for (number, kind) in [(1, ModeKind::RigidBody), (7, ModeKind::Mechanism)] {
        let phi = &modes[number - 1];
        assert_eq!(phi.kind, kind);
        let anim = mode::animate(&scene, number as i64, Some(1e-3), 10.0).unwrap();
        let frames = &anim.frames;
        assert_eq!(anim.period, STILL_LOOP);
        assert_eq!(frames.len(), 20);
        assert_eq!(anim.title, format!("mode {number}, 0 Hz ({})", kind.name()));
        let x = &frames.positions[0];
        // Linear there and back: 0.4 A at 1/10 of the loop, the peak at 1/4 (to within
        // the bar-length correction, about A²/l).
        for (k, c) in [(5, 1e-3), (2, 4e-4), (10, 0.0), (15, -1e-3), (18, -4e-4)] {
            let want = displaced(x, &phi.shape, c);
            assert!(
                frames.positions[k]
                    .iter()
                    .zip(&want)
                    .all(|(p, q)| close(*p, *q, 2e-6)),
                "mode {number} frame {k}"
            );
        }
    }
}

/// Decodes a GIF: the delays (centiseconds) and every frame as RGBA.
fn decode(path: &std::path::Path) -> (Vec<u16>, Vec<Vec<u8>>) {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut dec = options
        .read_info(std::fs::File::open(path).unwrap())
        .unwrap();
    let (mut delays, mut frames) = (Vec::new(), Vec::new());
    while let Some(frame) = dec.read_next_frame().unwrap() {
        delays.push(frame.delay);
        frames.push(frame.buffer.to_vec());
    }
    (delays, frames)
}

#[test]
fn gif_html_pvd_and_png_of_a_mode() {
    let scene = builtin("prism2-elastic").unwrap();
    let f = spectrum(&scene).modes[0].frequency_hz();
    let gif = temp("prism2-elastic-mode1.gif");
    let (ok, _, stderr) = run(&[
        "render",
        "prism2-elastic",
        "--mode",
        "1",
        "--fps",
        "20",
        "-o",
        gif.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(stderr.contains("mode 1, 0.869 Hz"), "{stderr}");
    let (delays, frames) = decode(&gif);
    let n = 4 * (20.0 / f / 4.0).round() as usize;
    assert_eq!(delays.len(), n, "one period of {} s at 20 fps", 1.0 / f);
    assert!(delays.iter().all(|&d| d == 5), "{delays:?}");
    // The peak and the trough differ; saved for a look.
    assert_ne!(frames[n / 4], frames[3 * n / 4]);
    for k in [0, n / 4, 3 * n / 4] {
        let png = temp(&format!("prism2-elastic-mode1-frame{k}.png"));
        let (w, h) = GIF_SIZE;
        image::save_buffer(&png, &frames[k], w, h, image::ColorType::Rgba8).unwrap();
        println!("frame {k}: {}", png.display());
    }
    let png = temp("prism2-elastic-mode3.png");
    let (ok, _, stderr) = run(&[
        "render",
        "prism2-elastic",
        "--mode",
        "3",
        "--amplitude",
        "0.25",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(stderr.contains("mode 3, 1.27 Hz"), "{stderr}");
    assert!(image::open(&png).is_ok());
    println!("peak of mode 3: {}", png.display());
    let html = temp("mode.html");
    let (ok, _, stderr) = run(&[
        "render",
        "prism2-elastic",
        "--mode",
        "2",
        "-o",
        html.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("prism2-elastic — mode 2, 1.27 Hz"));
    let pvd = temp("mode.pvd");
    let (ok, _, stderr) = run(&[
        "render",
        "prism2-elastic",
        "--mode",
        "1",
        "-o",
        pvd.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let n10 = 4 * (10.0 / f / 4.0).round() as usize;
    let vtp = std::fs::read_dir(temp("mode_vtp")).unwrap().count();
    assert_eq!(vtp, n10);
}

#[test]
fn bad_mode_requests_are_refused_naming_mode() {
    let png = temp("bad.png");
    let o = png.to_str().unwrap();
    let refused = |args: &[&str]| {
        let mut all = vec!["render"];
        all.extend_from_slice(args);
        all.extend_from_slice(&["-o", o]);
        let (ok, _, stderr) = run(&all);
        assert!(!ok, "{args:?} was accepted");
        stderr
    };
    for k in ["0", "13", "-1"] {
        let e = refused(&["prism2-elastic", "--mode", k]);
        assert!(
            e.contains(&format!("--mode {k}"))
                && e.contains("has 12 modes")
                && e.contains("between 1 and 12"),
            "{e}"
        );
    }
    let csv = temp("run.csv");
    std::fs::write(&csv, "time\n0\n").unwrap();
    let e = refused(&[
        "prism2-elastic",
        "--mode",
        "1",
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert!(
        e.contains("--mode and --csv") && e.contains("drop --csv"),
        "{e}"
    );
    let e = refused(&["prism2-elastic", "--mode", "1", "--time", "3"]);
    assert!(
        e.contains("--mode and --time") && e.contains("drop --time"),
        "{e}"
    );
    let e = refused(&["prism2-elastic", "--mode", "1", "--at", "0.1"]);
    assert!(e.contains("--mode and --at"), "{e}");
    let e = refused(&["prism2-elastic", "--amplitude", "0.1"]);
    assert!(e.contains("--amplitude") && e.contains("add --mode"), "{e}");
    let e = refused(&["prism2-elastic", "--mode", "1", "--amplitude", "-0.1"]);
    assert!(e.contains("--amplitude must be above 0"), "{e}");
    // A start that is not at rest: the dropped icosahedron is released above the ground.
    let dropped = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fmu/scenes/icosahedron-dropped.toml"
    );
    let e = refused(&[dropped, "--mode", "1"]);
    assert!(
        e.contains("--mode 1")
            && e.contains("not an equilibrium")
            && e.contains("start = \"equilibrium\""),
        "{e}"
    );
}
