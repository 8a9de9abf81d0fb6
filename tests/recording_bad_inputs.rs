//! The readers on synthetic and damaged files, written to a scratch directory: every bad input
//! must give a typed error (or a warning) that names the problem, and nothing may panic.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use bearingd::recording::{
    list_channels, read_recording, ReadOptions, Recording, RecordingError, RecordingFormat,
    SampleUnit,
};
use bearingd_testdata::{scratch_dir, shared_data_dir};
use std::path::{Path, PathBuf};

fn channel(name: &str) -> ReadOptions {
    ReadOptions {
        channel: Some(name.to_string()),
        column: None,
        unit: None,
    }
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn read(path: &Path) -> Result<Recording, RecordingError> {
    read_recording(path, &ReadOptions::default())
}

fn err(path: &Path, options: &ReadOptions) -> String {
    let e = read_recording(path, options).expect_err("should fail");
    let text = e.to_string();
    let name = path.file_name().unwrap().to_string_lossy();
    assert!(
        text.contains(&*name),
        "message does not name the file: {text}"
    );
    assert!(!text.contains('\n'), "message is not one line: {text}");
    text
}

// ---------- a minimal MATLAB v5 writer (little endian, uncompressed) ----------

fn pad8(v: &mut Vec<u8>) {
    v.resize(v.len().next_multiple_of(8), 0);
}

fn sub(out: &mut Vec<u8>, ty: u32, data: &[u8]) {
    out.extend_from_slice(&ty.to_le_bytes());
    out.extend_from_slice(&(data.len() as u32).to_le_bytes());
    out.extend_from_slice(data);
    pad8(out);
}

/// The first sub-elements of a `miMATRIX`: array flags (class and complex bit), a 2-D size,
/// the name.
fn array_header(flags: u32, rows: i32, cols: i32, name: &str) -> Vec<u8> {
    let mut body = Vec::new();
    sub(
        &mut body,
        6,
        &[flags.to_le_bytes(), 0u32.to_le_bytes()].concat(),
    );
    sub(
        &mut body,
        5,
        &[rows.to_le_bytes(), cols.to_le_bytes()].concat(),
    );
    sub(&mut body, 1, name.as_bytes());
    body
}

/// A double matrix variable; `imag` makes it complex.
fn mat_var(name: &str, rows: usize, cols: usize, real: &[f64], imag: Option<&[f64]>) -> Vec<u8> {
    let flags: u32 = 6 | if imag.is_some() { 0x0800 } else { 0 };
    let mut body = array_header(flags, rows as i32, cols as i32, name);
    let f64s = |v: &[f64]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    sub(&mut body, 9, &f64s(real));
    if let Some(im) = imag {
        sub(&mut body, 9, &f64s(im));
    }
    let mut el = Vec::new();
    sub(&mut el, 14, &body);
    el
}

fn mat_file(vars: &[Vec<u8>]) -> Vec<u8> {
    let mut text = b"MATLAB 5.0 MAT-file, Platform: test, Created by bearingd tests".to_vec();
    text.resize(116, b' ');
    text.extend_from_slice(&[0; 8]);
    text.extend_from_slice(&0x0100u16.to_le_bytes());
    text.extend_from_slice(b"IM");
    for v in vars {
        text.extend_from_slice(v);
    }
    text
}

fn column(name: &str, values: &[f64]) -> Vec<u8> {
    mat_var(name, values.len(), 1, values, None)
}

fn cwru_like() -> Vec<u8> {
    mat_file(&[
        column("X106_DE_time", &[9.0, 9.0]),
        column("X105_DE_time", &[0.5, -0.25, 0.125]),
        column("X105_FE_time", &[1.0, 2.0, 3.0]),
        column("X105RPM", &[1797.0]),
    ])
}

// ---------- MATLAB ----------

#[test]
fn mat_default_channel_is_the_files_own_record() {
    let dir = scratch_dir("mat-own-record");
    let path = write(&dir, "12k_Drive_End_IR007_0_105.mat", &cwru_like());
    let r = read(&path).unwrap();
    assert_eq!(r.format, RecordingFormat::Matlab);
    assert_eq!(r.channel, "X105_DE_time");
    assert_eq!(r.samples, [0.5, -0.25, 0.125]);
    assert_eq!((r.fs_hz, r.rpm), (Some(12_000.0), Some(1797.0)));
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    assert_eq!(
        read_recording(&path, &channel("FE")).unwrap().samples,
        [1.0, 2.0, 3.0]
    );
    assert_eq!(
        list_channels(&path).unwrap(),
        ["X106_DE_time", "X105_DE_time", "X105_FE_time", "X105RPM"]
    );
    // The other record's variable by name: no RPM variable for record 106.
    let other = read_recording(&path, &channel("x106_de_time")).unwrap();
    assert_eq!((other.channel.as_str(), other.rpm), ("X106_DE_time", None));
}

#[test]
fn mat_single_de_of_another_record_is_read_with_a_warning() {
    let dir = scratch_dir("mat-other-record");
    let path = write(
        &dir,
        "48k_x_105.mat",
        &mat_file(&[column("X106_DE_time", &[1.0])]),
    );
    let r = read(&path).unwrap();
    assert_eq!(
        (r.channel.as_str(), r.fs_hz),
        ("X106_DE_time", Some(48_000.0))
    );
    assert!(r.warnings[0].contains("record 105"), "{:?}", r.warnings);
}

#[test]
fn mat_ambiguous_and_missing_variables_list_what_is_there() {
    let dir = scratch_dir("mat-ambiguous");
    let two = mat_file(&[
        column("X001_DE_time", &[1.0]),
        column("X002_DE_time", &[2.0]),
    ]);
    let path = write(&dir, "mine.mat", &two);
    let e = err(&path, &ReadOptions::default());
    assert!(e.contains("2 DE variables"), "{e}");
    assert!(e.contains("X001_DE_time, X002_DE_time"), "{e}");

    let e = err(&path, &channel("X003_DE_time"));
    assert!(e.contains("no variable 'X003_DE_time'"), "{e}");
    assert!(
        e.contains("variables present: X001_DE_time, X002_DE_time"),
        "{e}"
    );

    // A plain MATLAB file with one vector: nothing to choose, and no rate is known.
    let path = write(
        &dir,
        "plain.mat",
        &mat_file(&[column("signal", &[1.0, 2.0])]),
    );
    let r = read(&path).unwrap();
    assert_eq!((r.channel.as_str(), r.fs_hz, r.rpm), ("signal", None, None));
    let two_plain = mat_file(&[column("a", &[1.0]), column("b", &[2.0])]);
    let path = write(&dir, "two.mat", &two_plain);
    let e = err(&path, &ReadOptions::default());
    assert!(
        e.contains("no variable holds a vector of samples; variables present: a, b"),
        "{e}"
    );
}

#[test]
fn mat_matrices_complex_and_empty_variables_are_refused() {
    let dir = scratch_dir("mat-unsupported");
    let vars = [
        mat_var("m", 2, 2, &[1.0, 2.0, 3.0, 4.0], None),
        mat_var("c", 2, 1, &[1.0, 2.0], Some(&[0.0, 1.0])),
        mat_var("e", 0, 0, &[], None),
        column("n", &[1.0, f64::NAN, 2.0, f64::INFINITY]),
    ];
    let path = write(&dir, "odd.mat", &mat_file(&vars));
    assert!(err(&path, &channel("m")).contains("is a 2x2 matrix, not a vector"));
    assert!(err(&path, &channel("c")).contains("is complex"));
    assert!(err(&path, &channel("e")).contains("no samples"));
    let e = err(&path, &channel("n"));
    assert!(
        e.contains("2 NaN or infinite") && e.contains("sample index 1"),
        "{e}"
    );
}

/// A struct variable of `rows`x`cols` elements with no fields (MATLAB's `repmat(struct(), r, c)`).
fn mat_struct_without_fields(name: &str, rows: i32, cols: i32) -> Vec<u8> {
    let mut body = array_header(2, rows, cols, name);
    sub(&mut body, 5, &32i32.to_le_bytes());
    sub(&mut body, 1, &[]);
    let mut el = Vec::new();
    sub(&mut el, 14, &body);
    el
}

/// Found by the `recordings` fuzz target: a 4,194,305-element struct with no fields, in 2 kB,
/// made the reader reserve 96 MiB (one empty element each). It is now listed, and costs nothing.
#[test]
fn mat_struct_with_no_fields_is_listed_whatever_its_size() {
    let dir = scratch_dir("mat-struct-no-fields");
    let vars = [
        mat_struct_without_fields("huge", 0x0040_0001, 1),
        mat_struct_without_fields("one", 1, 1),
    ];
    let path = write(&dir, "no_fields.mat", &mat_file(&vars));
    let e = err(&path, &ReadOptions::default());
    assert!(
        e.contains("huge (4194305x1 struct with no fields)")
            && e.contains("one (1x1 struct with no fields)"),
        "{e}"
    );
    let e = err(&path, &channel("huge"));
    assert!(e.contains("struct with no fields"), "{e}");
}

#[test]
fn mat_truncated_anywhere_is_an_error_not_a_panic() {
    let dir = scratch_dir("mat-truncated");
    let full = cwru_like();
    let first_end = 128 + 8 + u32::from_le_bytes(full[132..136].try_into().unwrap()) as usize;
    let mut cuts = vec![
        10,
        100,
        116,
        127,
        130,
        135,
        136,
        200,
        full.len() / 2,
        full.len() - 1,
    ];
    cuts.retain(|&c| c != first_end); // a cut between two elements cannot be seen as such
    for cut in cuts {
        let path = write(&dir, "12k_cut_105.mat", &full[..cut]);
        let e = err(&path, &ReadOptions::default());
        assert!(e.contains("truncated"), "cut at {cut}: {e}");
        assert!(
            e.contains(&format!("has only {cut} bytes")),
            "cut at {cut}: {e}"
        );
        if cut > 300 {
            assert!(e.contains("variable 'X105"), "cut at {cut}: {e}");
        }
    }
    let e = err(
        &write(&dir, "12k_cut_105.mat", &full[..10]),
        &ReadOptions::default(),
    );
    assert!(
        e.contains("the MATLAB header ends at byte 128 but the file has only 10 bytes"),
        "{e}"
    );
    // Cut exactly between elements: the lost variables are simply absent. Here the only DE
    // variable left is of another record: it is read, and the warning says so.
    let path = write(&dir, "12k_cut_105.mat", &full[..first_end]);
    let r = read(&path).unwrap();
    assert_eq!(r.channel, "X106_DE_time");
    assert!(
        r.warnings[0].contains("file name says record 105"),
        "{:?}",
        r.warnings
    );
    let e = err(&path, &channel("FE"));
    assert!(
        e.contains("no variable 'X105_FE_time'; variables present: X106_DE_time"),
        "{e}"
    );
    let e = err(
        &write(&dir, "12k_cut_105.mat", b""),
        &ReadOptions::default(),
    );
    assert!(e.contains("empty (0 bytes)"), "{e}");
}

#[test]
fn real_cwru_file_truncated_is_an_error() {
    let Some(data) = shared_data_dir("cwru") else {
        return;
    };
    let full = std::fs::read(data.join("12k_Drive_End_IR007_0_105.mat")).unwrap();
    let dir = scratch_dir("cwru-truncated");
    for cut in [10, 100, 130, full.len() / 2, full.len() - 1] {
        let path = write(&dir, "12k_Drive_End_IR007_0_105.mat", &full[..cut]);
        let e = err(&path, &ReadOptions::default());
        assert!(
            e.contains("truncated") && e.contains(&format!("only {cut}")),
            "{e}"
        );
    }
}

#[test]
fn files_that_are_not_matlab_v5() {
    let dir = scratch_dir("not-matlab");
    let path = write(&dir, "notes.mat", b"time,accel\n0,1\n");
    let e = err(&path, &ReadOptions::default());
    assert!(
        e.contains("not a MATLAB v5 file") && e.contains("time,accel"),
        "{e}"
    );
    let path = write(
        &dir,
        "h5.mat",
        b"MATLAB 7.3 MAT-file, Platform: GLNXA64, HDF5 schema 1.00",
    );
    assert!(err(&path, &ReadOptions::default()).contains("'-v7'"));
    let mut bad = cwru_like();
    bad[126..128].copy_from_slice(b"XX");
    let e = err(&write(&dir, "endian.mat", &bad), &ReadOptions::default());
    assert!(e.contains("endian indicator"), "{e}");
    let mut bad = cwru_like();
    bad[124..126].copy_from_slice(&0x0200u16.to_le_bytes());
    let e = err(&write(&dir, "version.mat", &bad), &ReadOptions::default());
    assert!(e.contains("version 0x0200"), "{e}");
}

/// A MATLAB v7 compressed element around `inner`, as a zlib stream of stored deflate blocks.
fn compressed(inner: &[u8]) -> Vec<u8> {
    let mut z = vec![0x78, 0x01];
    let chunks: Vec<&[u8]> = inner.chunks(65535).collect();
    for (i, chunk) in chunks.iter().enumerate() {
        z.push(u8::from(i + 1 == chunks.len()));
        let len = chunk.len() as u16;
        z.extend_from_slice(&len.to_le_bytes());
        z.extend_from_slice(&(!len).to_le_bytes());
        z.extend_from_slice(chunk);
    }
    let (mut a, mut b) = (1u32, 0u32);
    for &byte in inner {
        a = (a + u32::from(byte)) % 65521;
        b = (b + a) % 65521;
    }
    z.extend_from_slice(&((b << 16) | a).to_be_bytes());
    let mut el = Vec::new();
    el.extend_from_slice(&15u32.to_le_bytes());
    el.extend_from_slice(&(z.len() as u32).to_le_bytes());
    el.extend_from_slice(&z);
    el
}

#[test]
fn mat_compressed_variables_and_one_that_cannot_be_decoded() {
    let dir = scratch_dir("mat-compressed");
    // A 65536 x 65536 matrix holding one value: that variable is reported by name and
    // skipped, the others stay readable.
    let huge = mat_var("X105_FE_time", 65536, 65536, &[1.0], None);
    let file = mat_file(&[
        compressed(&column("X105_DE_time", &[0.5, 1.5])),
        compressed(&huge),
    ]);
    let path = write(&dir, "12k_z_105.mat", &file);
    let r = read(&path).unwrap();
    assert_eq!(
        (r.channel.as_str(), r.samples.as_slice()),
        ("X105_DE_time", &[0.5, 1.5][..])
    );
    assert!(
        r.warnings[0].contains("skipped the variable 'X105_FE_time' (at byte 235)")
            && r.warnings[0].contains("65536x65536"),
        "{:?}",
        r.warnings
    );
    let e = err(&path, &channel("FE"));
    assert!(e.contains("(cannot be decoded)"), "{e}");
}

/// A tiny deterministic generator for the mutation test.
fn xorshift(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
}

#[test]
fn mutated_files_never_panic() {
    let dir = scratch_dir("mutations");
    let wav = wav_bytes(2, 16, hound::SampleFormat::Int, &[1, -2, 3, -4, 5, -6]);
    let seeds: [(&str, Vec<u8>); 4] = [
        ("12k_m_105.mat", cwru_like()),
        ("m.wav", wav),
        (
            "acc_00001.csv",
            b"8,47,5,1.9691e+05,0.05,-0.253\n8,47,5,1.97e+05,0.1,0.2\n".to_vec(),
        ),
        (
            "2003.10.22.12.14.13",
            b"1\t2\t3\t4\t5\t6\t7\t8\n1\t2\t3\t4\t5\t6\t7\t8\n".to_vec(),
        ),
    ];
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    for (name, seed) in &seeds {
        for round in 0..400 {
            let mut bytes = seed.clone();
            for _ in 0..1 + xorshift(&mut state) % 4 {
                let at = (xorshift(&mut state) % bytes.len() as u64) as usize;
                bytes[at] = xorshift(&mut state) as u8;
            }
            if round % 5 == 0 {
                bytes.truncate((xorshift(&mut state) % bytes.len() as u64) as usize);
            }
            let path = write(&dir, name, &bytes);
            let outcome = std::panic::catch_unwind(|| {
                let _ = read(&path);
                let _ = list_channels(&path);
            });
            assert!(
                outcome.is_ok(),
                "{name} round {round} panicked on {bytes:?}"
            );
        }
    }
}

// ---------- text ----------

#[test]
fn csv_with_nan_names_the_index_and_line() {
    let dir = scratch_dir("csv-nan");
    let path = write(&dir, "x.csv", b"accel\n0.1\n0.2\nNaN\n0.4\ninf\n");
    let e = err(&path, &ReadOptions::default());
    assert!(e.contains("2 NaN or infinite"), "{e}");
    assert!(e.contains("sample index 2 (0-based) (line 4)"), "{e}");
}

#[test]
fn csv_cut_mid_row_keeps_the_rows_before_with_a_warning() {
    let dir = scratch_dir("csv-cut");
    let path = write(&dir, "x.csv", b"t,a\n0,0.5\n1,0.25\n2,");
    let r = read_recording(
        &path,
        &ReadOptions {
            channel: None,
            column: Some("a".into()),
            unit: None,
        },
    )
    .unwrap();
    assert_eq!(r.samples, [0.5, 0.25]);
    assert_eq!(r.warnings.len(), 1);
    assert!(r.warnings[0].contains("line 4 is incomplete") && r.warnings[0].contains("kept the 2"));

    // PRONOSTIA cut inside the last row; a last row without newline that is complete is kept.
    let path = write(
        &dir,
        "acc_00007.csv",
        b"8,47,5,1,0.05,-0.25\n8,47,5,2,0.1,0.2\n8,47,5,3,0.",
    );
    let r = read(&path).unwrap();
    assert_eq!((r.samples.len(), r.warnings.len()), (2, 1));
    let path = write(
        &dir,
        "acc_00008.csv",
        b"8,47,5,1,0.05,-0.25\n8,47,5,2,0.1,0.2",
    );
    let r = read(&path).unwrap();
    assert_eq!((r.samples.len(), r.warnings.len()), (2, 0));
}

#[test]
fn malformed_rows_name_their_line() {
    let dir = scratch_dir("csv-malformed");
    let path = write(&dir, "x.csv", b"a;b\n1;2\n\n3\n4;5\n");
    let e = err(&path, &channel("b"));
    assert!(e.contains("line 4: 1 field(s) where line 1 has 2"), "{e}");
    let path = write(&dir, "y.csv", b"1,2\n3,x\n");
    let e = err(&path, &channel("2"));
    assert!(
        e.contains("line 2: column 'column 2': 'x' is not a number"),
        "{e}"
    );
    // A cut row that is not the last line is an error, not a warning.
    let path = write(
        &dir,
        "acc_00001.csv",
        b"8,47,5,1,0.05,-0.25\n8,47,5\n8,47,5,3,0.1,0.2\n",
    );
    assert!(err(&path, &ReadOptions::default()).contains("line 2: 3 field(s)"));
    let path = write(&dir, "bin.csv", &[b'1', b'\n', 0xff, 0xfe, b'\n']);
    assert!(err(&path, &ReadOptions::default()).contains("line 2: not text"));
}

#[test]
fn empty_inputs() {
    let dir = scratch_dir("empty");
    for (name, bytes) in [
        ("e.csv", &b""[..]),
        ("e.wav", b""),
        ("b.csv", b"\n \n"),
        ("h.csv", b"time,accel\n"),
        ("2003.10.22.12.14.13", b""),
    ] {
        let e = err(&write(&dir, name, bytes), &channel("1"));
        assert!(e.contains("no samples"), "{name}: {e}");
    }
}

#[test]
fn ims_by_name_and_by_content() {
    let dir = scratch_dir("ims");
    let rows = b"-0.054\t-0.049\t-0.208\t-0.081\t-0.122\t-0.222\t-0.085\t-0.129\n\
                 -0.215\t-0.044\t-0.151\t-0.149\t-0.244\t-0.142\t-0.059\t-0.146\n";
    let path = write(&dir, "2003.10.22.12.14.13", rows);
    let r = read_recording(&path, &channel("b3X")).unwrap();
    assert_eq!(
        (r.channel.as_str(), r.samples.as_slice()),
        ("B3x", &[-0.122, -0.244][..])
    );
    let e = err(&path, &channel("9"));
    assert!(
        e.contains("no channel '9'") && e.contains("B4y, or an index 1..8"),
        "{e}"
    );
    let path = write(&dir, "snapshot", rows);
    assert_eq!(read(&path).unwrap().format, RecordingFormat::ImsText);
}

// ---------- detection and options ----------

#[test]
fn unknown_missing_and_conflicting() {
    let dir = scratch_dir("detect");
    let e = err(&dir.join("nope.csv"), &ReadOptions::default());
    assert!(e.contains("file not found"), "{e}");
    let e = err(&write(&dir, "x.dat", b"1\n2\n"), &ReadOptions::default());
    assert!(
        e.contains("unknown recording format") && e.contains("rename it to .csv"),
        "{e}"
    );
    let e = err(
        &write(&dir, "blob", b"\x00\x01binary"),
        &ReadOptions::default(),
    );
    assert!(e.contains("no extension"), "{e}");
    let path = write(&dir, "x.csv", b"1\n2\n");
    let both = ReadOptions {
        channel: Some("1".into()),
        column: Some("2".into()),
        unit: None,
    };
    assert!(err(&path, &both).contains("give only one"));
    // A .mat-looking file without extension is found by content.
    // Without a record number in the name, two DE variables are a choice left to the user.
    let path = write(&dir, "noext", &cwru_like());
    assert!(err(&path, &ReadOptions::default()).contains("2 DE variables"));
    assert_eq!(
        read_recording(&path, &channel("X105_DE_time")).unwrap().rpm,
        Some(1797.0)
    );
}

// ---------- WAV ----------

fn wav_bytes(channels: u16, bits: u16, format: hound::SampleFormat, samples: &[i32]) -> Vec<u8> {
    let spec = hound::WavSpec {
        channels,
        sample_rate: 25_600,
        bits_per_sample: bits,
        sample_format: format,
    };
    let mut cursor = std::io::Cursor::new(Vec::new());
    {
        let mut w = hound::WavWriter::new(&mut cursor, spec).unwrap();
        for &s in samples {
            match format {
                hound::SampleFormat::Int => w.write_sample(s).unwrap(),
                hound::SampleFormat::Float => w.write_sample(s as f32 / 8.0).unwrap(),
            }
        }
        w.finalize().unwrap();
    }
    cursor.into_inner()
}

/// Inserts a LIST/INFO chunk before the data chunk, as many editors do.
fn with_list_chunk(wav: &[u8]) -> Vec<u8> {
    let data_at = wav.windows(4).position(|w| w == b"data").unwrap();
    let info = b"INFOISFT\x06\x00\x00\x00tests\x00";
    let mut out = wav[..data_at].to_vec();
    out.extend_from_slice(b"LIST");
    out.extend_from_slice(&(info.len() as u32).to_le_bytes());
    out.extend_from_slice(info);
    out.extend_from_slice(&wav[data_at..]);
    let riff_len = (out.len() - 8) as u32;
    out[4..8].copy_from_slice(&riff_len.to_le_bytes());
    out
}

#[test]
fn wav_round_trips() {
    let dir = scratch_dir("wav");
    let ints = [16384, -32768, 0, 32767, -16384, 8192];
    let path = write(
        &dir,
        "s16.wav",
        &wav_bytes(2, 16, hound::SampleFormat::Int, &ints),
    );
    assert_eq!(list_channels(&path).unwrap(), ["1", "2"]);
    let left = read(&path).unwrap();
    assert_eq!(left.format, RecordingFormat::Wav);
    assert_eq!((left.channel.as_str(), left.fs_hz), ("1", Some(25_600.0)));
    assert_eq!(left.samples, [0.5, 0.0, -0.5]);
    assert_eq!(left.unit, SampleUnit::FullScale);
    assert!(
        left.warnings[0].contains("fractions of full scale"),
        "{:?}",
        left.warnings
    );
    let right = read_recording(&path, &channel("2")).unwrap();
    assert_eq!(right.samples, [-1.0, 32767.0 / 32768.0, 0.25]);
    assert!(err(&path, &channel("3")).contains("no channel '3'"));

    let path = write(
        &dir,
        "s24.wav",
        &wav_bytes(1, 24, hound::SampleFormat::Int, &[-(1 << 23), 1 << 22]),
    );
    assert_eq!(read(&path).unwrap().samples, [-1.0, 0.5]);
    let path = write(
        &dir,
        "s8.wav",
        &wav_bytes(1, 8, hound::SampleFormat::Int, &[-128, 64]),
    );
    assert_eq!(read(&path).unwrap().samples, [-1.0, 0.5]);
    let float = wav_bytes(1, 32, hound::SampleFormat::Float, &[1, -2, 12]);
    let path = write(&dir, "f32.wav", &with_list_chunk(&float));
    let float = read(&path).unwrap();
    assert_eq!(float.samples, [0.125, -0.25, 1.5]);
    assert_eq!(float.unit, SampleUnit::G);
    assert!(float.warnings.is_empty(), "{:?}", float.warnings);
    assert!(float.notes[0].contains("taken as g"), "{:?}", float.notes);
}

#[test]
fn wav_damaged() {
    let dir = scratch_dir("wav-damaged");
    let full = wav_bytes(2, 16, hound::SampleFormat::Int, &[1, 2, 3, 4, 5, 6]);
    // Cut inside the third frame: two complete frames survive.
    let r = read(&write(&dir, "cut.wav", &full[..full.len() - 3])).unwrap();
    assert_eq!(r.samples.len(), 2);
    assert!(
        r.warnings[1].contains("declares 3 frames but the file ends after 2"),
        "{:?}",
        r.warnings
    );
    let e = err(
        &write(&dir, "head.wav", &full[..20]),
        &ReadOptions::default(),
    );
    assert!(e.contains("cannot read the WAV file"), "{e}");
    let e = err(
        &write(&dir, "text.wav", b"hello world\n"),
        &ReadOptions::default(),
    );
    assert!(e.contains("cannot read the WAV file"), "{e}");
    let mut nan = wav_bytes(1, 32, hound::SampleFormat::Float, &[1, 2]);
    let n = nan.len();
    nan[n - 4..].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = err(&write(&dir, "nan.wav", &nan), &ReadOptions::default());
    assert!(
        e.contains("1 NaN or infinite sample(s), the first at sample index 1"),
        "{e}"
    );
}
