//! `render` to GIF and from CSV: one frame per requested time, the CSV of `simulate` and
//! an fmpy-style quoted header read back as the run itself, missing columns named.

mod cli_support;

use cli_support::{run, temp};
use tensegrity_fmu::render::animation::GIF_SIZE;
use tensegrity_fmu::render::Frames;
use tensegrity_fmu::scene::builtin;

/// The frames of a GIF: their delays (centiseconds) and the last frame as RGBA.
fn decode(path: &std::path::Path) -> (Vec<u16>, Vec<u8>) {
    let (delays, _, last) = decode_ends(path);
    (delays, last)
}

/// The delays, the first frame and the last frame.
fn decode_ends(path: &std::path::Path) -> (Vec<u16>, Vec<u8>, Vec<u8>) {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut dec = options
        .read_info(std::fs::File::open(path).unwrap())
        .unwrap();
    assert_eq!((u32::from(dec.width()), u32::from(dec.height())), GIF_SIZE);
    let mut delays = Vec::new();
    let (mut first, mut last) = (Vec::new(), Vec::new());
    while let Some(frame) = dec.read_next_frame().unwrap() {
        assert_eq!((frame.left, frame.top), (0, 0));
        assert_eq!((u32::from(frame.width), u32::from(frame.height)), GIF_SIZE);
        delays.push(frame.delay);
        last = frame.buffer.to_vec();
        if first.is_empty() {
            first = last.clone();
        }
    }
    (delays, first, last)
}

#[test]
fn gif_has_one_frame_per_recorded_time() {
    let out = temp("prism2.gif");
    let o = out.to_str().unwrap();
    let (ok, _, stderr) = run(&["render", "prism2", "-o", o, "--time", "1", "--fps", "10"]);
    assert!(ok, "{stderr}");
    let (delays, first, last) = decode_ends(&out);
    assert_eq!(delays.len(), 11, "0, 0.1, …, 1 s");
    // Each frame is stamped with its time: the title band (top 40 rows) differs.
    let band = 4 * GIF_SIZE.0 as usize * 40;
    assert_ne!(first[..band], last[..band]);
    assert!(delays.iter().all(|&d| d == 10), "{delays:?}");
    // The last frame shows the structure (dark bar pixels), saved for a look.
    let dark = last
        .chunks(4)
        .filter(|p| p[0] < 60 && p[1] < 60 && p[2] < 60)
        .count();
    assert!(dark > 2000, "{dark} dark pixels in the last frame");
    let png = temp("prism2-last-frame.png");
    image::save_buffer(&png, &last, GIF_SIZE.0, GIF_SIZE.1, image::ColorType::Rgba8).unwrap();
    println!("last frame: {}", png.display());
    // A --time off the frame grid ends with a frame at --time.
    let (ok, _, stderr) = run(&["render", "prism2", "-o", o, "--time", "0.27", "--fps", "20"]);
    assert!(ok, "{stderr}");
    let (delays, _) = decode(&out);
    assert_eq!(delays.len(), 7, "0, 0.05, …, 0.25, 0.27 s");
    assert!(delays.iter().all(|&d| d == 5), "{delays:?}");
}

fn simulate_csv(name: &str, scene: &str, time: &str, interval: &str) -> std::path::PathBuf {
    let csv = temp(name);
    let (ok, _, stderr) = run(&[
        "simulate",
        scene,
        "--time",
        time,
        "--interval",
        interval,
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    csv
}

#[test]
fn csv_of_simulate_and_fmpy_style_header_read_back_as_the_run() {
    let scene = builtin("prism2-elastic").unwrap();
    let csv = simulate_csv("elastic.csv", "prism2-elastic", "0.5", "0.05");
    let read = Frames::from_csv(&scene, &csv).unwrap();
    let times: Vec<f64> = (0..=10).map(|k| f64::from(k) * 0.05).collect();
    let simulated = Frames::from_run(&scene, &times).unwrap();
    assert_eq!(read.times.len(), 11);
    for k in 0..11 {
        assert!((read.times[k] - simulated.times[k]).abs() < 1e-12);
        for (p, q) in read.positions[k].iter().zip(&simulated.positions[k]) {
            assert!((0..3).all(|i| (p[i] - q[i]).abs() < 1e-12), "{p:?} {q:?}");
        }
        for (a, b) in read.tensions[k].iter().zip(&simulated.tensions[k]) {
            assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0));
        }
        assert_eq!(read.bar_forces[k].len(), simulated.bar_forces[k].len());
    }
    assert!(read.max_tension() > 0.0);
    // fmpy's write_csv quotes the names.
    let text = std::fs::read_to_string(&csv).unwrap();
    let (header, rows) = text.split_once('\n').unwrap();
    let quoted: Vec<String> = header.split(',').map(|n| format!("\"{n}\"")).collect();
    let fmpy = temp("elastic-fmpy.csv");
    std::fs::write(&fmpy, format!("{}\n{rows}", quoted.join(","))).unwrap();
    assert_eq!(Frames::from_csv(&scene, &fmpy).unwrap(), read);
    // Thinned to the frame rate: a GIF at 4 fps from rows every 0.05 s.
    let gif = temp("elastic.gif");
    let (ok, _, stderr) = run(&[
        "render",
        "prism2-elastic",
        "--csv",
        fmpy.to_str().unwrap(),
        "--fps",
        "4",
        "-o",
        gif.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert_eq!(decode(&gif).0.len(), 3, "0, 0.25, 0.5 s");
}

#[test]
fn csv_without_positions_names_the_column_and_without_tensions_reads_zeros() {
    let scene = builtin("prism2").unwrap();
    let csv = simulate_csv("p.csv", "prism2", "0.1", "0.05");
    let text = std::fs::read_to_string(&csv).unwrap();
    let keep = |drop: &dyn Fn(&str) -> bool| {
        let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        let cols: Vec<usize> = (0..header.len()).filter(|&c| !drop(header[c])).collect();
        text.lines()
            .map(|l| {
                let cells: Vec<&str> = l.split(',').collect();
                cols.iter().map(|&c| cells[c]).collect::<Vec<_>>().join(",")
            })
            .collect::<Vec<_>>()
            .join("\n")
    };
    let missing = temp("missing.csv");
    std::fs::write(&missing, keep(&|n| n == "node[3].x")).unwrap();
    let e = Frames::from_csv(&scene, &missing).unwrap_err();
    assert!(
        e.contains("`node[3].x`") && e.contains("`outputs`") && e.contains("positions"),
        "{e}"
    );
    let png = temp("missing.png");
    let (ok, _, stderr) = run(&[
        "render",
        "prism2",
        "--csv",
        missing.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(!ok && stderr.contains("`node[3].x`"), "{stderr}");
    let positions_only = temp("positions.csv");
    std::fs::write(
        &positions_only,
        keep(&|n| n.contains(".v") || n.contains("tension") || n.contains("force")),
    )
    .unwrap();
    let frames = Frames::from_csv(&scene, &positions_only).unwrap();
    assert_eq!(frames.len(), 3);
    assert!(frames.tensions.iter().flatten().all(|&t| t == 0.0));
    assert!(frames.velocities.iter().flatten().all(|v| *v == [0.0; 3]));
    let full = Frames::from_csv(&scene, &csv).unwrap();
    assert_eq!(frames.positions, full.positions);
    // --at picks the nearest row within the CSV's span and refuses outside it.
    let (ok, _, stderr) = run(&[
        "render",
        "prism2",
        "--csv",
        csv.to_str().unwrap(),
        "--at",
        "0.2",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(
        !ok && stderr.contains("--at 0.2") && stderr.contains("0 to 0.1 s"),
        "{stderr}"
    );
    let (ok, _, stderr) = run(&[
        "render",
        "prism2",
        "--csv",
        csv.to_str().unwrap(),
        "--at",
        "0.06",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
}

/// Prints (does not assert) how long a 10 s tower20 animation takes to render.
#[test]
fn tower20_ten_seconds_to_gif_takes_seconds() {
    let out = temp("tower20.gif");
    let start = std::time::Instant::now();
    let (ok, _, stderr) = run(&[
        "render",
        "tower20",
        "--time",
        "10",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let wall = start.elapsed().as_secs_f64();
    let frames = decode(&out).0.len();
    assert_eq!(frames, 101);
    println!(
        "render tower20 --time 10 -o t.gif: {frames} frames, {wall:.2} s wall, {:.1} MB",
        std::fs::metadata(&out).unwrap().len() as f64 / 1e6
    );
}
