//! Animated GIFs of a recorded run: one frame per recorded time, drawn as the still
//! pictures are (one camera fit and one tension colour scale for the whole run), each with
//! its time in the title.

use std::path::Path;

use plotters::prelude::*;

use super::picture::{draw_frame, drawing, fit, Style};
use super::Frames;

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
    let root = BitMapBackend::gif(path, GIF_SIZE, delay_ms)
        .map_err(drawing(&what))?
        .into_drawing_area();
    for k in 0..frames.len() {
        root.fill(&WHITE).map_err(drawing(&what))?;
        draw_frame(&root, frames, k, &fit, max, style)?;
        root.present().map_err(drawing(&what))?;
    }
    Ok(())
}
