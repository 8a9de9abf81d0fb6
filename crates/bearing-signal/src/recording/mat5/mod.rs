//! The MATLAB v5 / v7 file format (`save -v6`, `save -v7`, `scipy.io.savemat`): bytes in, a
//! tree of variables out: numeric arrays, structs (nested, and struct arrays), cell arrays,
//! and a description of everything else (text, sparse matrices, objects).
//!
//! Why our own decoder: the `matfile` crate reads numeric arrays only; MATLAB files in the
//! wild put their signals in structs (the MFPT data set: `bearing.gs`, `bearing.sr`, ...).
//! The format is small: a 128-byte header, then data elements, each a tag (type, byte count)
//! and its data. `miCOMPRESSED` elements hold one zlib-compressed element; `miMATRIX` elements
//! hold sub-elements: array flags, dimensions, name, then the data (real and imaginary parts
//! for numbers; field names and one `miMATRIX` per element and field for structs; one
//! `miMATRIX` per cell for cell arrays).
//!
//! Every read is bounds-checked against the element it belongs to; nesting depth and the
//! decompressed size are bounded; nothing here can panic or allocate more than the input
//! justifies. A file-level problem (header, a top-level element cut off by the end of the
//! file) is a [`RecordingError`] naming the byte offset; a problem inside one variable skips
//! that variable with a warning naming it and the offset, so the others stay readable.
//!
//! The files: this one the header, the walk over the top-level elements and their
//! decompression; `matrix` one `miMATRIX` body, into a [`Value`].

mod matrix;

use super::RecordingError;
use matrix::{decode_matrix, top_level_name, Context};
use std::io::Read;
use std::ops::Range;
use std::path::Path;

const MAGIC: &[u8] = b"MATLAB 5.0 MAT-file";
pub(super) const HEADER_LEN: usize = 128;

// The top-level data types (the tag's first word); the others are in `matrix`.
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;

/// Largest decompressed size of one compressed variable (1 GiB: 2.5 hours of float64 samples
/// at 12 kHz). A few bytes of zlib can claim gigabytes; this bounds the memory spent.
const MAX_INFLATED_BYTES: u64 = 1 << 30;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Endian {
    Little,
    Big,
}

fn u32_at(bytes: &[u8], at: usize, endian: Endian) -> Option<u32> {
    let b: [u8; 4] = bytes.get(at..at.checked_add(4)?)?.try_into().ok()?;
    Some(match endian {
        Endian::Little => u32::from_le_bytes(b),
        Endian::Big => u32::from_be_bytes(b),
    })
}

/// A whole file: its variables in file order, and what was skipped.
pub(super) struct MatFile {
    pub variables: Vec<Variable>,
    /// Variables that could not be decoded, as `'name' (cannot be decoded)` or
    /// `at byte N (cannot be decoded)`, for listings.
    pub undecodable: Vec<String>,
    pub warnings: Vec<String>,
}

/// A top-level variable.
pub(super) struct Variable {
    pub name: String,
    pub value: Value,
}

/// What a variable (or a struct field, or a cell) holds.
pub(super) enum Value {
    Numeric(NumericArray),
    Struct(StructArray),
    /// A cell array's cells, column-major.
    Cell(Vec<Value>),
    /// Text, sparse matrices, function handles, objects: described, not decoded.
    Other {
        dims: Vec<usize>,
        kind: &'static str,
    },
}

/// A numeric (or logical) array, converted to f64, column-major as stored.
pub(super) struct NumericArray {
    pub dims: Vec<usize>,
    pub real: Vec<f64>,
    pub complex: bool,
}

/// A struct array: `elements[k][f]` is field `fields[f]` of element `k` (column-major).
pub(super) struct StructArray {
    pub fields: Vec<String>,
    pub elements: Vec<Vec<Value>>,
}

/// `2x3`, the way MATLAB writes sizes.
pub(super) fn dims_text(dims: &[usize]) -> String {
    let parts: Vec<String> = dims.iter().map(|d| d.to_string()).collect();
    parts.join("x")
}

/// Checks the 128-byte header: text starting with `MATLAB 5.0 MAT-file`, version 0x0100,
/// endian indicator `IM` or `MI`.
pub(super) fn check_header(path: &Path, bytes: &[u8]) -> Result<Endian, RecordingError> {
    let not_matlab = |reason: String| RecordingError::NotMatlab {
        path: path.to_path_buf(),
        reason,
    };
    let n = bytes.len().min(MAGIC.len());
    if bytes[..n] != MAGIC[..n] {
        let reason = if bytes.starts_with(b"MATLAB 7.3") {
            "it is a MATLAB 7.3 (HDF5) file; save it again in MATLAB with save(file, '-v7')"
                .to_string()
        } else if bytes.starts_with(b"RIFF") {
            "it starts like a WAV file; rename it to .wav".to_string()
        } else {
            let start: String = String::from_utf8_lossy(&bytes[..bytes.len().min(24)])
                .chars()
                .map(|c| if c.is_control() { ' ' } else { c })
                .collect();
            format!(
                "it starts with \"{}\" instead of \"MATLAB 5.0 MAT-file\"; check that it is the right file (a .mat from MATLAB 5 to 7.2, or scipy.io.savemat)",
                start.trim_end()
            )
        };
        return Err(not_matlab(reason));
    }
    if bytes.len() < HEADER_LEN {
        return Err(RecordingError::Truncated {
            path: path.to_path_buf(),
            what: "the MATLAB header".to_string(),
            expected: HEADER_LEN as u64,
            present: bytes.len() as u64,
        });
    }
    let endian = match &bytes[126..128] {
        b"IM" => Endian::Little,
        b"MI" => Endian::Big,
        other => {
            return Err(not_matlab(format!(
                "the endian indicator at byte 126 is {other:?}, not \"IM\" or \"MI\"; the header is damaged, fetch the file again"
            )))
        }
    };
    let version = match endian {
        Endian::Little => u16::from_le_bytes([bytes[124], bytes[125]]),
        Endian::Big => u16::from_be_bytes([bytes[124], bytes[125]]),
    };
    if version != 0x0100 {
        return Err(not_matlab(format!(
            "the header gives version 0x{version:04x} at byte 124, not 0x0100; save it again in MATLAB with save(file, '-v7')"
        )));
    }
    Ok(endian)
}

/// A top-level data element: where it starts and the bytes it covers (tag included).
struct Element {
    offset: usize,
    bytes: Range<usize>,
    compressed: bool,
}

/// Walks the top-level data elements, checking that each fits in the file: a variable cut off
/// by the end of the file is an error (the copy is incomplete), never silently dropped.
fn elements(
    path: &Path,
    bytes: &[u8],
    endian: Endian,
    warnings: &mut Vec<String>,
) -> Result<Vec<Element>, RecordingError> {
    let truncated = |what: String, expected: usize| RecordingError::Truncated {
        path: path.to_path_buf(),
        what,
        expected: expected as u64,
        present: bytes.len() as u64,
    };
    let mut out = Vec::new();
    let mut off = HEADER_LEN;
    while off < bytes.len() {
        let (Some(kind), Some(size)) = (u32_at(bytes, off, endian), u32_at(bytes, off + 4, endian))
        else {
            return Err(truncated(
                format!("the data element tag at byte {off}"),
                off + 8,
            ));
        };
        if kind & 0xFFFF_0000 != 0 {
            return Err(RecordingError::DamagedMat {
                path: path.to_path_buf(),
                detail: format!(
                    "the data element tag at byte {off} is not valid here (type word 0x{kind:08x})"
                ),
            });
        }
        let end = off.saturating_add(8).saturating_add(size as usize);
        if end > bytes.len() {
            let what = match top_level_name(&bytes[off..], endian) {
                Some(name) if kind == MI_MATRIX => format!("variable '{name}' (at byte {off})"),
                _ => format!("the data element at byte {off}"),
            };
            return Err(truncated(what, end));
        }
        match kind {
            MI_MATRIX | MI_COMPRESSED => out.push(Element {
                offset: off,
                bytes: off..end,
                compressed: kind == MI_COMPRESSED,
            }),
            _ => warnings.push(format!(
                "skipped a data element of type {kind} at byte {off}: not a variable"
            )),
        }
        // Uncompressed elements are padded to 8 bytes; compressed ones are not.
        off = if kind == MI_COMPRESSED {
            end
        } else {
            end.checked_next_multiple_of(8).unwrap_or(end)
        };
    }
    Ok(out)
}

/// Decodes a whole file. Fails only on file-level damage; a variable that cannot be decoded
/// is skipped with a warning.
pub(super) fn parse(path: &Path, bytes: &[u8]) -> Result<MatFile, RecordingError> {
    let endian = check_header(path, bytes)?;
    let mut file = MatFile {
        variables: Vec::new(),
        undecodable: Vec::new(),
        warnings: Vec::new(),
    };
    let elements = elements(path, bytes, endian, &mut file.warnings)?;
    for el in elements {
        let body = &bytes[el.bytes.start + 8..el.bytes.end];
        if el.compressed {
            match inflate(body) {
                Ok(inner) => decode_elements(&inner, el.offset, true, endian, &mut file),
                Err(problem) => file.skip(None, el.offset, &problem),
            }
        } else {
            decode_matrix_element(body, el.offset, el.offset + 8, false, endian, &mut file);
        }
    }
    Ok(file)
}

impl MatFile {
    fn skip(&mut self, name: Option<&str>, offset: usize, problem: &str) {
        let what = match name {
            Some(n) if !n.is_empty() => format!("'{n}' (at byte {offset})"),
            _ => format!("at byte {offset}"),
        };
        self.warnings
            .push(format!("skipped the variable {what}: {problem}"));
        self.undecodable.push(match name {
            Some(n) if !n.is_empty() => format!("{n} (cannot be decoded)"),
            _ => format!("the variable at byte {offset} (cannot be decoded)"),
        });
    }
}

/// The elements inside a decompressed `miCOMPRESSED` element (normally one `miMATRIX`).
fn decode_elements(
    inner: &[u8],
    file_offset: usize,
    compressed: bool,
    endian: Endian,
    file: &mut MatFile,
) {
    let mut at = 0usize;
    while at < inner.len() {
        let (Some(kind), Some(size)) = (u32_at(inner, at, endian), u32_at(inner, at + 4, endian))
        else {
            file.skip(
                None,
                file_offset,
                &format!("its decompressed data ends inside an element tag (offset {at} of the decompressed data)"),
            );
            return;
        };
        let end = (at + 8).saturating_add(size as usize);
        if kind != MI_MATRIX || end > inner.len() {
            file.skip(
                None,
                file_offset,
                &format!(
                    "its decompressed data holds an element of type {kind} and {size} bytes at offset {at}, of which {} are present",
                    inner.len().saturating_sub(at + 8)
                ),
            );
            return;
        }
        decode_matrix_element(
            &inner[at + 8..end],
            file_offset,
            at + 8,
            compressed,
            endian,
            file,
        );
        at = end.checked_next_multiple_of(8).unwrap_or(end);
    }
}

/// One `miMATRIX` element's data (after its tag) at top level.
fn decode_matrix_element(
    body: &[u8],
    file_offset: usize,
    body_offset: usize,
    compressed: bool,
    endian: Endian,
    file: &mut MatFile,
) {
    let ctx = Context {
        endian,
        base: body_offset,
        compressed,
    };
    match decode_matrix(body, 0, &ctx, 0) {
        // MATLAB's own hidden data (the subsystem element) has an empty name.
        Ok((name, _)) if name.is_empty() => {}
        Ok((name, value)) => file.variables.push(Variable { name, value }),
        Err(e) => file.skip(e.name.as_deref(), file_offset, &e.describe(&ctx)),
    }
}

/// zlib-inflates a compressed element, at most [`MAX_INFLATED_BYTES`].
fn inflate(data: &[u8]) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    let mut decoder = flate2::read::ZlibDecoder::new(data).take(MAX_INFLATED_BYTES + 1);
    match decoder.read_to_end(&mut out) {
        Ok(_) if out.len() as u64 > MAX_INFLATED_BYTES => Err(format!(
            "it expands to more than {} MiB; save that variable in a file of its own or as several shorter ones",
            MAX_INFLATED_BYTES >> 20
        )),
        Ok(_) => Ok(out),
        Err(e) => Err(format!("its compressed data is damaged ({e})")),
    }
}
