//! Files of a linear model: `.json`, `.npz` (numpy) and `.mat` (MATLAB), chosen by the
//! extension. Every file names the states, inputs and outputs (the FMU's variable names)
//! and holds the same arrays under the same names ([`contents`]).

mod mat;
mod npz;

use std::path::Path;

use nalgebra::DMatrix;
use serde_json::json;

use super::linear::LinearModel;
use crate::partial;

/// Writes `model` to `path` in the format its extension names.
pub fn write(path: &Path, model: &LinearModel, scene: &str) -> Result<(), String> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    let bytes = match ext {
        "json" => Ok(to_json(model, scene).into_bytes()),
        "npz" => npz::to_npz(&contents(model, scene)),
        "mat" => mat::to_mat(&contents(model, scene)),
        _ => {
            return Err(format!(
                "-o {}: unknown format `.{ext}`; use .json, .npz or .mat",
                path.display()
            ))
        }
    }
    .map_err(|e| format!("-o {}: {e}", path.display()))?;
    partial::write(path, &bytes)
}

/// Everything a `.npz` or `.mat` file holds, by variable name.
pub struct Contents<'a> {
    /// The scene's name.
    pub scene: &'a str,
    /// `A`, `B`, `C`, `D`.
    pub matrices: [(&'static str, &'a DMatrix<f64>); 4],
    /// `input_values`, `output_values`, `frequencies_hz`.
    pub vectors: [(&'static str, &'a [f64]); 3],
    /// `states`, `inputs`, `outputs`.
    pub names: [(&'static str, &'a [String]); 3],
}

/// The arrays of `model`, named as in the JSON file.
pub fn contents<'a>(model: &'a LinearModel, scene: &'a str) -> Contents<'a> {
    Contents {
        scene,
        matrices: [
            ("A", &model.a),
            ("B", &model.b),
            ("C", &model.c),
            ("D", &model.d),
        ],
        vectors: [
            ("input_values", &model.input_values),
            ("output_values", &model.output_values),
            ("frequencies_hz", &model.frequencies_hz),
        ],
        names: [
            ("states", &model.states),
            ("inputs", &model.inputs),
            ("outputs", &model.outputs),
        ],
    }
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
