//! Files of a linear model: `.json`, `.npz` (numpy) and `.mat` (MATLAB), chosen by the
//! extension. Every file names the states, inputs and outputs (the FMU's variable names).

use std::path::Path;

use nalgebra::DMatrix;
use serde_json::json;

use super::linear::LinearModel;
use crate::partial;

/// Writes `model` to `path` in the format its extension names.
pub fn write(path: &Path, model: &LinearModel, scene: &str) -> Result<(), String> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    let bytes = match ext {
        "json" => to_json(model, scene).into_bytes(),
        _ => {
            return Err(format!(
                "-o {}: unknown format `.{ext}`; use .json, .npz or .mat",
                path.display()
            ))
        }
    };
    partial::write(path, &bytes)
}

fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    m.row_iter().map(|r| r.iter().copied().collect()).collect()
}

/// The JSON text: names, the four matrices by rows, the operating point and frequencies.
pub fn to_json(model: &LinearModel, scene: &str) -> String {
    let value = json!({
        "scene": scene,
        "states": model.states,
        "inputs": model.inputs,
        "outputs": model.outputs,
        "A": rows(&model.a),
        "B": rows(&model.b),
        "C": rows(&model.c),
        "D": rows(&model.d),
        "input_values": model.input_values,
        "output_values": model.output_values,
        "frequencies_hz": model.frequencies_hz,
    });
    serde_json::to_string_pretty(&value).expect("plain numbers and strings") + "\n"
}
