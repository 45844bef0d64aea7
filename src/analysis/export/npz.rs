//! `.npz`: a zip of `.npy` arrays, as `numpy.savez_compressed` writes. npyz encodes each
//! array; the zip crate the FMU packaging already uses packs them (npyz's own `npz`
//! feature would pull in a second, older zip).

use std::io::{Cursor, Write};

use nalgebra::DMatrix;
use npyz::{DType, TypeStr, WriteOptions, WriterBuilder};
use zip::write::SimpleFileOptions;

use super::Contents;

/// The `.npz` bytes: `A`…`D` as 2-D float64 (C order), the value vectors as 1-D float64,
/// the names as 1-D unicode arrays and `scene` as a 0-d unicode array.
pub fn to_npz(contents: &Contents) -> Result<Vec<u8>, String> {
    let mut arrays = Vec::new();
    for (name, m) in contents.matrices {
        arrays.push((name, matrix(m)));
    }
    for (name, v) in contents.vectors {
        arrays.push((name, floats(&[v.len() as u64], v.iter().copied())));
    }
    for (name, list) in contents.names {
        arrays.push((name, strings(&[list.len() as u64], list)));
    }
    arrays.push((
        "scene",
        strings(&[], std::slice::from_ref(&contents.scene.to_string())),
    ));
    let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let options = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    for (name, npy) in arrays {
        let npy = npy.map_err(|e| format!("array `{name}`: {e}"))?;
        zip.start_file(format!("{name}.npy"), options)
            .map_err(|e| e.to_string())?;
        zip.write_all(&npy).map_err(|e| e.to_string())?;
    }
    let cursor = zip.finish().map_err(|e| e.to_string())?;
    Ok(cursor.into_inner())
}

/// A matrix in row-major (C) order.
fn matrix(m: &DMatrix<f64>) -> std::io::Result<Vec<u8>> {
    let shape = [m.nrows() as u64, m.ncols() as u64];
    floats(&shape, m.transpose().iter().copied())
}

fn floats(shape: &[u64], values: impl Iterator<Item = f64>) -> std::io::Result<Vec<u8>> {
    let mut out = Vec::new();
    let mut writer = WriteOptions::<f64>::new()
        .default_dtype()
        .shape(shape)
        .writer(&mut out)
        .begin_nd()?;
    writer.extend(values)?;
    writer.finish()?;
    Ok(out)
}

/// Strings as numpy's fixed-width unicode (`<U{longest}`).
fn strings(shape: &[u64], values: &[String]) -> std::io::Result<Vec<u8>> {
    let width = values.iter().map(|s| s.chars().count()).max().unwrap_or(0);
    let type_str: TypeStr = format!("<U{}", width.max(1))
        .parse()
        .expect("a valid unicode type string");
    let mut out = Vec::new();
    let mut writer = WriteOptions::<str>::new()
        .dtype(DType::Plain(type_str))
        .shape(shape)
        .writer(&mut out)
        .begin_nd()?;
    for s in values {
        writer.push(s.as_str())?;
    }
    writer.finish()?;
    Ok(out)
}
