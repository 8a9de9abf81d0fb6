//! Reading a model file: the safetensors layout `bearingd train` writes (an 8-byte
//! little-endian header length, a JSON header naming each tensor's dtype, shape and byte range,
//! then the tensors' bytes), read by hand so that the service needs neither candle nor the
//! safetensors crate to use a model.
//!
//! A model file is input like any other: every way it can be malformed (truncated, a header
//! length past the file or absurdly large, a header that is not JSON, a tensor of another dtype
//! or shape, bytes outside the file) is a [`FileError::Malformed`] saying what is wrong, never a
//! panic, and nothing is allocated beyond the capped file size.

use serde::Deserialize;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

/// A model file larger than this is refused before it is read (the shipped model is 109 KiB).
pub const MAX_FILE_BYTES: u64 = 64 << 20;
/// A JSON header longer than this is refused (the shipped model's is 3.4 KiB).
pub const MAX_HEADER_BYTES: u64 = 1 << 20;
/// The header entry that holds the string metadata (the model card) rather than a tensor.
const METADATA_ENTRY: &str = "__metadata__";
/// The only dtype the network is stored in.
const F32: &str = "F32";

/// Why a model file could not be used; the caller names the file.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    #[error("cannot read: {0}")]
    Read(#[from] std::io::Error),
    #[error("{0}")]
    Malformed(String),
}

fn malformed(why: impl Into<String>) -> FileError {
    FileError::Malformed(why.into())
}

/// One tensor's entry in the header.
#[derive(Debug, Deserialize)]
struct TensorEntry {
    dtype: String,
    shape: Vec<usize>,
    /// Byte range in the data that follows the header: `[begin, end)`.
    data_offsets: [usize; 2],
}

/// A model file's header and the bytes of its tensors.
#[derive(Debug)]
pub struct ModelFile {
    metadata: BTreeMap<String, String>,
    tensors: BTreeMap<String, TensorEntry>,
    /// The whole file; tensor data starts at `data_start`.
    bytes: Vec<u8>,
    data_start: usize,
}

impl ModelFile {
    /// Reads a model file of at most [`MAX_FILE_BYTES`].
    pub fn read(path: &Path) -> Result<Self, FileError> {
        let file = std::fs::File::open(path)?;
        let stated = file.metadata()?.len();
        if stated > MAX_FILE_BYTES {
            return Err(too_large(stated));
        }
        // The length from the metadata may be wrong (a growing file, a device): read one byte
        // past the cap to notice.
        let mut bytes = Vec::with_capacity(usize::try_from(stated).unwrap_or(0));
        file.take(MAX_FILE_BYTES + 1).read_to_end(&mut bytes)?;
        if bytes.len() as u64 > MAX_FILE_BYTES {
            return Err(too_large(bytes.len() as u64));
        }
        Self::parse(bytes)
    }

    /// Splits a model file's bytes into its header and data, checking that every tensor's byte
    /// range lies inside the data.
    pub fn parse(bytes: Vec<u8>) -> Result<Self, FileError> {
        let not_safetensors = |why: String| malformed(format!("not a safetensors file: {why}"));
        let Some(length_bytes) = bytes.first_chunk::<8>() else {
            return Err(not_safetensors(format!(
                "{} bytes, too short for the 8-byte header length",
                bytes.len()
            )));
        };
        let header_len = u64::from_le_bytes(*length_bytes);
        if header_len > MAX_HEADER_BYTES {
            return Err(not_safetensors(format!(
                "its header length says {header_len} bytes, more than the {MAX_HEADER_BYTES} a model's header may have"
            )));
        }
        // Bounded by MAX_HEADER_BYTES above, so it fits in usize.
        let data_start = 8 + header_len as usize;
        if data_start > bytes.len() {
            return Err(not_safetensors(format!(
                "its header length says {header_len} bytes, but only {} follow (truncated?)",
                bytes.len() - 8
            )));
        }
        let mut header: BTreeMap<String, serde_json::Value> =
            serde_json::from_slice(&bytes[8..data_start])
                .map_err(|e| not_safetensors(format!("its header is not a JSON object: {e}")))?;
        let metadata = match header.remove(METADATA_ENTRY) {
            None => BTreeMap::new(),
            Some(value) => serde_json::from_value(value).map_err(|e| {
                not_safetensors(format!("its {METADATA_ENTRY} is not a map of strings: {e}"))
            })?,
        };
        let data_len = bytes.len() - data_start;
        let mut tensors = BTreeMap::new();
        for (name, value) in header {
            let entry: TensorEntry = serde_json::from_value(value)
                .map_err(|e| not_safetensors(format!("tensor {name:?}: {e}")))?;
            let [begin, end] = entry.data_offsets;
            if begin > end || end > data_len {
                return Err(not_safetensors(format!(
                    "tensor {name:?} lies at bytes {begin}..{end} of the data, which holds {data_len} bytes (truncated?)"
                )));
            }
            tensors.insert(name, entry);
        }
        Ok(ModelFile {
            metadata,
            tensors,
            bytes,
            data_start,
        })
    }

    /// A metadata string of the header.
    pub fn metadata(&self, key: &str) -> Option<&str> {
        self.metadata.get(key).map(String::as_str)
    }

    /// The values of the f32 tensor `name`, which must have shape `shape`.
    pub fn tensor(&self, name: &str, shape: &[usize]) -> Result<Vec<f32>, FileError> {
        let entry = self
            .tensors
            .get(name)
            .ok_or_else(|| malformed(format!("it has no tensor {name:?}")))?;
        if entry.dtype != F32 {
            return Err(malformed(format!(
                "tensor {name:?} is {}, a model's tensors are {F32}",
                entry.dtype
            )));
        }
        if entry.shape != shape {
            return Err(malformed(format!(
                "tensor {name:?} has shape {:?}, the network needs {shape:?}",
                entry.shape
            )));
        }
        let [begin, end] = entry.data_offsets;
        let needed = shape.iter().try_fold(4usize, |n, &d| n.checked_mul(d));
        if needed != Some(end - begin) {
            return Err(malformed(format!(
                "tensor {name:?} has {} bytes, not the 4 per value its shape {shape:?} needs",
                end - begin
            )));
        }
        let data = &self.bytes[self.data_start + begin..self.data_start + end];
        Ok(data
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect())
    }
}

fn too_large(bytes: u64) -> FileError {
    malformed(format!(
        "{bytes} bytes, more than the {MAX_FILE_BYTES} a model file may have"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model-like file: `header` as the JSON header, then `data`.
    fn file_with(header: &str, data: &[u8]) -> Vec<u8> {
        let mut bytes = (header.len() as u64).to_le_bytes().to_vec();
        bytes.extend_from_slice(header.as_bytes());
        bytes.extend_from_slice(data);
        bytes
    }

    fn one_tensor(dtype: &str, shape: &str, offsets: &str) -> String {
        format!(
            r#"{{"__metadata__":{{"card":"{{}}"}},"w":{{"dtype":"{dtype}","shape":{shape},"data_offsets":{offsets}}}}}"#
        )
    }

    fn values(v: &[f32]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    fn why(result: Result<impl std::fmt::Debug, FileError>) -> String {
        match result {
            Err(FileError::Malformed(why)) => why,
            other => panic!("expected a malformed file, got {other:?}"),
        }
    }

    #[test]
    fn a_well_formed_file_gives_its_metadata_and_tensors() {
        let bytes = file_with(
            &one_tensor("F32", "[2,2]", "[0,16]"),
            &values(&[1.0, -2.0, 0.5, 3.0]),
        );
        let file = ModelFile::parse(bytes).unwrap();
        assert_eq!(file.metadata("card"), Some("{}"));
        assert_eq!(file.metadata("other"), None);
        assert_eq!(file.tensor("w", &[2, 2]).unwrap(), [1.0, -2.0, 0.5, 3.0]);
    }

    #[test]
    fn a_truncated_header_is_refused() {
        for bytes in [vec![], vec![4, 0, 0]] {
            assert!(why(ModelFile::parse(bytes)).contains("too short"));
        }
        let mut bytes = file_with(&one_tensor("F32", "[1]", "[0,4]"), &values(&[1.0]));
        bytes.truncate(20);
        assert!(why(ModelFile::parse(bytes)).contains("truncated"));
    }

    #[test]
    fn a_header_length_beyond_the_file_is_refused() {
        let mut bytes = 1000u64.to_le_bytes().to_vec();
        bytes.extend_from_slice(b"{}");
        let why = why(ModelFile::parse(bytes));
        assert!(why.contains("1000 bytes, but only 2 follow"), "{why}");
    }

    #[test]
    fn a_huge_header_length_is_refused_without_allocating_it() {
        for length in [MAX_HEADER_BYTES + 1, u64::MAX] {
            let mut bytes = length.to_le_bytes().to_vec();
            bytes.extend_from_slice(b"{}");
            let why = why(ModelFile::parse(bytes));
            assert!(why.contains("more than the 1048576"), "{why}");
        }
    }

    #[test]
    fn a_header_that_is_not_json_or_not_tensors_is_refused() {
        for (header, expected) in [
            ("not json", "not a JSON object"),
            ("[1,2]", "not a JSON object"),
            (r#"{"__metadata__":{"a":1}}"#, "not a map of strings"),
            (r#"{"w":{"dtype":"F32"}}"#, "tensor \"w\""),
        ] {
            let why = why(ModelFile::parse(file_with(header, &[])));
            assert!(why.contains(expected), "{header}: {why}");
        }
    }

    #[test]
    fn a_tensor_outside_the_data_is_refused() {
        for offsets in ["[0,8]", "[4,2]", "[0,18446744073709551615]"] {
            let bytes = file_with(&one_tensor("F32", "[2]", offsets), &values(&[1.0]));
            let why = why(ModelFile::parse(bytes));
            assert!(why.contains("which holds 4 bytes"), "{offsets}: {why}");
        }
    }

    #[test]
    fn a_wrong_dtype_is_refused() {
        let file = ModelFile::parse(file_with(
            &one_tensor("F64", "[1]", "[0,8]"),
            &1f64.to_le_bytes(),
        ))
        .unwrap();
        let why = why(file.tensor("w", &[1]));
        assert!(why.contains("is F64, a model's tensors are F32"), "{why}");
    }

    #[test]
    fn a_missing_tensor_is_refused() {
        let file = ModelFile::parse(file_with(
            &one_tensor("F32", "[1]", "[0,4]"),
            &values(&[1.0]),
        ))
        .unwrap();
        let why = why(file.tensor("hidden.weight", &[1]));
        assert!(why.contains("no tensor \"hidden.weight\""), "{why}");
    }

    #[test]
    fn a_wrong_shape_or_byte_count_is_refused() {
        let file = ModelFile::parse(file_with(
            &one_tensor("F32", "[2,2]", "[0,16]"),
            &values(&[1.0; 4]),
        ))
        .unwrap();
        let why_shape = why(file.tensor("w", &[4]));
        assert!(
            why_shape.contains("shape [2, 2], the network needs [4]"),
            "{why_shape}"
        );
        let file = ModelFile::parse(file_with(
            &one_tensor("F32", "[2,2]", "[0,12]"),
            &values(&[1.0; 4]),
        ))
        .unwrap();
        let why_bytes = why(file.tensor("w", &[2, 2]));
        assert!(why_bytes.contains("has 12 bytes"), "{why_bytes}");
    }

    #[test]
    fn a_file_over_the_cap_is_refused_before_it_is_read() {
        let dir = std::env::temp_dir().join(format!("bearingd-model-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("huge.safetensors");
        let file = std::fs::File::create(&path).unwrap();
        file.set_len(MAX_FILE_BYTES + 1).unwrap();
        let why = why(ModelFile::read(&path));
        assert!(why.contains("more than the"), "{why}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
