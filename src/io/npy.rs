//! Reading and writing grids as NumPy `.npy` files (format versions 1.0, 2.0 and 3.0).
//!
//! Layout: magic `\x93NUMPY`, major and minor version bytes, the header length (`u16` little-endian in
//! version 1, `u32` in 2 and 3), then a Python dict literal such as
//! `{'descr': '<f4', 'fortran_order': False, 'shape': (nz, ny, nx), }` padded with spaces and a newline
//! so that the data starts on a 64-byte boundary, then the data in C order. A grid is a 3-D array of shape
//! `[nz, ny, nx]` (x fastest). We write `'<f4'`; we read `'<f4'` and also `'<f8'` (NumPy's default
//! float type, converted to `f32`), nothing else.

use crate::error::{Error, Result};
use crate::sdf::GridData;
use std::io::Write;
use std::path::Path;

const MAGIC: &[u8] = b"\x93NUMPY";

/// Read a grid from a `.npy` file: a C-order 3-D array of shape `[nz, ny, nx]`, dtype `<f4` (or `<f8`),
/// every dimension at least 4, all values finite. Errors are [`Error::File`] with a one-line message.
pub fn read_npy(path: &Path) -> Result<GridData> {
    let bytes = std::fs::read(path).map_err(|e| Error::file(path, format!("cannot read: {e}")))?;
    parse_npy(&bytes).map_err(|m| Error::file(path, m))
}

/// A C-order array of any number of dimensions read from a `.npy` file ([`read_npy_array`]).
#[derive(Clone, Debug, PartialEq)]
pub struct NpyArray {
    /// The shape, outermost first (as NumPy writes it).
    pub shape: Vec<usize>,
    /// The values in C order (last index fastest).
    pub values: Vec<f32>,
}

/// Read a C-order array of any shape from a `.npy` file, dtype `<f4` (or `<f8`, converted). Values are
/// not checked (a caller that needs finite values checks them). Errors are [`Error::File`] with a
/// one-line message.
pub fn read_npy_array(path: &Path) -> Result<NpyArray> {
    let bytes = std::fs::read(path).map_err(|e| Error::file(path, format!("cannot read: {e}")))?;
    parse_array(&bytes).map_err(|m| Error::file(path, m))
}

/// Parse the bytes of a `.npy` file (see [`read_npy`]); the error is the message.
fn parse_npy(bytes: &[u8]) -> std::result::Result<GridData, String> {
    let (shape, header_end, size) = parse_header(bytes)?;
    let &[nz, ny, nx] = shape.as_slice() else {
        return Err(format!(
            "grid must be a 3-D array [nz, ny, nx], got {} dimension(s)",
            shape.len()
        ));
    };
    if nx < 4 || ny < 4 || nz < 4 {
        return Err(format!(
            "grid dimensions must be at least 4 (cubic B-spline), got shape ({nz}, {ny}, {nx})"
        ));
    }
    let values = parse_values(&bytes[header_end..], &shape, size)?;
    let grid = GridData {
        dims: [nx, ny, nz],
        values,
    };
    grid.validate("npy").map_err(|e| match e {
        Error::File { message, .. } => message,
        e => e.to_string(),
    })?;
    Ok(grid)
}

/// Parse the bytes of a `.npy` file of any shape (see [`read_npy_array`]).
fn parse_array(bytes: &[u8]) -> std::result::Result<NpyArray, String> {
    let (shape, header_end, size) = parse_header(bytes)?;
    let values = parse_values(&bytes[header_end..], &shape, size)?;
    Ok(NpyArray { shape, values })
}

/// The shape, the offset of the data and the size of one value (4 or 8) of a `.npy` file's bytes.
fn parse_header(bytes: &[u8]) -> std::result::Result<(Vec<usize>, usize, usize), String> {
    if bytes.len() < 10 || &bytes[..6] != MAGIC {
        return Err("not a .npy file (bad magic)".into());
    }
    let major = bytes[6];
    let (header_len, start): (usize, usize) = match major {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 => {
            if bytes.len() < 12 {
                return Err("truncated .npy header".into());
            }
            let n = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
            (n as usize, 12)
        }
        v => return Err(format!("unsupported .npy format version {v}.{}", bytes[7])),
    };
    let end = start
        .checked_add(header_len)
        .filter(|&e| e <= bytes.len())
        .ok_or("truncated .npy header")?;
    let header = std::str::from_utf8(&bytes[start..end]).map_err(|_| "header is not text")?;

    let descr = dict_value(header, "descr")?;
    let descr = descr.trim_matches(|c| c == '\'' || c == '"');
    let size = match descr {
        "<f4" => 4,
        "<f8" => 8,
        d => {
            return Err(format!(
                "dtype must be '<f4' or '<f8' (float32 or float64 little-endian), got '{d}'"
            ));
        }
    };
    match dict_value(header, "fortran_order")? {
        "False" => {}
        "True" => return Err("fortran_order arrays are not supported; save in C order".into()),
        v => return Err(format!("bad fortran_order value '{v}'")),
    }
    let shape = dict_value(header, "shape")?;
    let shape = shape
        .strip_prefix('(')
        .and_then(|s| s.strip_suffix(')'))
        .ok_or_else(|| format!("bad shape '{shape}'"))?;
    let shape: Vec<usize> = shape
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.parse::<usize>()
                .map_err(|_| format!("bad shape entry '{s}'"))
        })
        .collect::<std::result::Result<_, _>>()?;
    Ok((shape, end, size))
}

/// The values of an array of `shape` whose data (`size` bytes a value) starts `data`.
fn parse_values(
    data: &[u8],
    shape: &[usize],
    size: usize,
) -> std::result::Result<Vec<f32>, String> {
    let count = (shape.iter())
        .try_fold(1usize, |a, &n| a.checked_mul(n))
        .ok_or("shape overflows")?;
    let need = count.checked_mul(size).ok_or("shape overflows")?;
    if data.len() < need {
        let dims: Vec<String> = shape.iter().map(|n| n.to_string()).collect();
        return Err(format!(
            "truncated data: shape ({}) needs {need} bytes, file has {}",
            dims.join(", "),
            data.len()
        ));
    }
    Ok(if size == 4 {
        data[..need]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    } else {
        data[..need]
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8-byte chunk")) as f32)
            .collect()
    })
}

/// The text of `key`'s value in a `.npy` header dict: up to the next top-level comma or closing brace.
fn dict_value<'a>(header: &'a str, key: &str) -> std::result::Result<&'a str, String> {
    let missing = || format!("header has no '{key}' entry");
    let i = header
        .find(&format!("'{key}'"))
        .or_else(|| header.find(&format!("\"{key}\"")))
        .ok_or_else(missing)?;
    let rest = &header[i + key.len() + 2..];
    let rest = rest
        .trim_start()
        .strip_prefix(':')
        .ok_or_else(missing)?
        .trim_start();
    let mut depth = 0usize;
    for (j, ch) in rest.char_indices() {
        match ch {
            '(' | '[' => depth += 1,
            ')' | ']' => {
                if depth == 0 {
                    return Ok(rest[..j].trim());
                }
                depth -= 1;
                if depth == 0 && ch == ')' {
                    return Ok(rest[..=j].trim());
                }
            }
            ',' | '}' if depth == 0 => return Ok(rest[..j].trim()),
            _ => {}
        }
    }
    Err(format!("unterminated '{key}' entry in header"))
}

/// The bytes of a version 1.0 `.npy` file holding `grid` as `<f4`, shape `[nz, ny, nx]`.
fn encode_npy(grid: &GridData) -> Vec<u8> {
    let [nx, ny, nz] = grid.dims;
    encode_array(&[nz, ny, nx], &grid.values)
}

/// The bytes of a version 1.0 `.npy` file holding `values` as `<f4` with `shape`.
fn encode_array(shape: &[usize], values: &[f32]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(|n| n.to_string()).collect();
    // A one-element tuple needs its trailing comma.
    let tuple = if dims.len() == 1 {
        format!("({},)", dims[0])
    } else {
        format!("({})", dims.join(", "))
    };
    let mut header = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': {tuple}, }}");
    // Pad with spaces and end with '\n' so that magic + version + length + header is a multiple of 64.
    let total = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - total % 64) % 64));
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len() + 4 * values.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&[1, 0]);
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// Write `values` (C order, as many as `shape` holds) as a `.npy` file (version 1.0, `<f4`), through a
/// temporary file renamed over `path` as [`write_npy`] does.
pub fn write_npy_array(path: &Path, shape: &[usize], values: &[f32]) -> Result<()> {
    if shape.iter().product::<usize>() != values.len() {
        return Err(Error::file(
            path,
            format!(
                "shape {shape:?} needs {} values, got {}",
                shape.iter().product::<usize>(),
                values.len()
            ),
        ));
    }
    write_bytes(path, &encode_array(shape, values))
}

/// Write `grid` as a `.npy` file (version 1.0, `<f4`, C order, shape `[nz, ny, nx]`). The bytes go to a
/// temporary file beside `path` that is then renamed over it, so a failure never leaves a partial file.
pub fn write_npy(path: &Path, grid: &GridData) -> Result<()> {
    grid.validate(&path.display().to_string())?;
    write_bytes(path, &encode_npy(grid))
}

/// Writes `bytes` to a temporary file beside `path`, then renames it over `path`.
fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    super::create_parent(path)?;
    let mut tmp_name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    tmp_name.push(format!(".tmp{}", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    let write = || -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    };
    write().map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::file(path, format!("cannot write: {e}"))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_is_64_byte_aligned_and_parses_back() {
        let g = GridData {
            dims: [5, 4, 6],
            values: (0..120).map(|i| i as f32 * 0.5 - 3.0).collect(),
        };
        let b = encode_npy(&g);
        let header_len = u16::from_le_bytes([b[8], b[9]]) as usize;
        assert_eq!((10 + header_len) % 64, 0);
        assert_eq!(b[10 + header_len - 1], b'\n');
        assert_eq!(parse_npy(&b).unwrap(), g);
    }

    #[test]
    fn dict_values_with_tuples_and_quotes() {
        let h = "{'descr': '<f4', 'fortran_order': False, 'shape': (7, 8, 9), }";
        assert_eq!(dict_value(h, "shape").unwrap(), "(7, 8, 9)");
        assert_eq!(dict_value(h, "descr").unwrap(), "'<f4'");
        assert_eq!(dict_value(h, "fortran_order").unwrap(), "False");
        assert!(dict_value(h, "nope").is_err());
    }
}
