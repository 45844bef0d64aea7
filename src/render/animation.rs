//! Animated GIFs of a recorded run: one frame per recorded time, drawn as the still
//! pictures are (one camera fit and one tension colour scale for the whole run), each with
//! its time in the title.

use std::io::{BufWriter, Write};
use std::path::Path;

use plotters::prelude::*;

use super::picture::{draw_frame, drawing, fit, Style};
use super::Frames;
use crate::partial::{blank_rgb, Partial};

/// Size of a GIF frame, pixels: smaller than a PNG, so that a long run encodes in seconds.
pub const GIF_SIZE: (u32, u32) = (640, 540);

/// Writes every frame of `frames` to a GIF at `fps` frames per second (the delay is
/// rounded to GIF's 10 ms).
pub fn write_gif(frames: &Frames, fps: f64, style: &Style, path: &Path) -> Result<(), String> {
    if !(fps > 0.0 && fps <= 100.0) {
        return Err(format!(
            "--fps must be above 0 and at most 100 (GIF delays are whole 10 ms), got {fps}"
        ));
    }
    let what = path.display().to_string();
    let delay_ms = (1000.0 / fps).round() as u32;
    let fit = fit(frames, GIF_SIZE, style);
    let max = frames.max_tension();
    let (w, h) = GIF_SIZE;
    let mut rgb = blank_rgb(GIF_SIZE);
    // Encoded into the hidden temporary as plotters' GIF backend would (which writes the
    // target in place): frames quantised at speed 10, the delay in whole 10 ms, looping.
    let (partial, file) = Partial::create(path)?;
    let cannot = |e: gif::EncodingError| format!("cannot write {what}: {e}");
    let mut gif =
        gif::Encoder::new(BufWriter::new(file), w as u16, h as u16, &[]).map_err(cannot)?;
    gif.set_repeat(gif::Repeat::Infinite).map_err(cannot)?;
    for k in 0..frames.len() {
        {
            let root = BitMapBackend::with_buffer(&mut rgb, GIF_SIZE).into_drawing_area();
            root.fill(&WHITE).map_err(drawing(&what))?;
            draw_frame(&root, frames, k, &fit, max, style)?;
            root.present().map_err(drawing(&what))?;
        }
        let mut frame = gif::Frame::from_rgb_speed(w as u16, h as u16, &rgb, 10);
        frame.delay = ((delay_ms + 5) / 10) as u16;
        gif.write_frame(&frame).map_err(cannot)?;
    }
    let mut out = gif
        .into_inner()
        .map_err(|e| format!("cannot write {what}: {e}"))?;
    out.flush()
        .map_err(|e| format!("cannot write {what}: {e}"))?;
    drop(out);
    partial.commit()
}
