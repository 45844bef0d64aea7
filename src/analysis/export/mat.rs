//! `.mat`: a MATLAB Level-5 MAT-file (what `save -v7` writes, here uncompressed; MATLAB's
//! `load` and `scipy.io.loadmat` read it), written with matrw. Its text is ASCII: other
//! characters (in the scene's name, say) are written as `?`.

use matrw::{CellArray, MatFile, MatVariable, MatlabType, NumericArray};

use super::Contents;

/// The `.mat` bytes: `A`…`D` as double matrices, the value vectors as double columns, the
/// names as n×1 cell arrays of char row vectors and `scene` as a char row vector.
pub fn to_mat(contents: &Contents) -> Result<Vec<u8>, String> {
    let mut file = MatFile::new();
    for (name, m) in contents.matrices {
        file.insert(name, doubles(m.nrows(), m.ncols(), m.as_slice())?);
    }
    for (name, v) in contents.vectors {
        file.insert(name, doubles(v.len(), 1, v)?);
    }
    for (name, list) in contents.names {
        let cells = list
            .iter()
            .map(|s| MatVariable::from(ascii(s).as_str()))
            .collect();
        let cells = CellArray::new(vec![list.len(), 1], cells).map_err(|e| e.to_string())?;
        file.insert(name, MatVariable::CellArray(cells));
    }
    file.insert("scene", MatVariable::from(ascii(contents.scene).as_str()));
    let expected: Vec<String> = file.iter().map(|(name, _)| name.clone()).collect();
    let bytes = serialize(file)?;
    // matrw's writer does not report I/O errors: read the bytes back before trusting them.
    let back = matrw::load_matfile_from_u8(&bytes).map_err(|e| {
        let first = e.to_string().lines().next().unwrap_or_default().to_string();
        format!("the MAT-file written does not read back: {first}")
    })?;
    if let Some(missing) = expected.iter().find(|name| !back.contains(name)) {
        return Err(format!("the MAT-file written lacks `{missing}`"));
    }
    Ok(bytes)
}

/// `text` with every character outside ASCII as `?`: matrw 0.1.4 writes a character as
/// its UTF-8 bytes but counts it as one, so any other text makes a file that neither it
/// nor MATLAB reads back.
fn ascii(text: &str) -> String {
    text.chars()
        .map(|c| if c.is_ascii() { c } else { '?' })
        .collect()
}

/// A double matrix from column-major values (nalgebra's and MATLAB's order).
fn doubles(rows: usize, cols: usize, values: &[f64]) -> Result<MatVariable, String> {
    NumericArray::new(vec![rows, cols], MatlabType::from(values.to_vec()), None)
        .map(MatVariable::NumericArray)
        .map_err(|e| e.to_string())
}

/// The bytes `matrw::save_matfile_v7` would write (uncompressed), written into memory:
/// matrw's own function writes to a path and ignores write errors.
fn serialize(file: MatFile) -> Result<Vec<u8>, String> {
    use binrw::BinWrite;
    use matrw::parser::header::{MatFileHeader, MatFileVerFlag};
    use matrw::parser::v7::matfile7::MatFile7;
    let header = MatFileHeader::new(MatFileVerFlag::V7);
    let mut bytes = std::io::Cursor::new(Vec::new());
    header
        .write_options(&mut bytes, header.matfile_endian, ())
        .and_then(|()| MatFile7::from(file).write_options(&mut bytes, header.matfile_endian, ()))
        .map_err(|e| format!("cannot encode the MAT-file: {e}"))?;
    Ok(bytes.into_inner())
}
