//! Without bearingd's log reader, an MCAP log is recognised and refused with a line that says
//! what reads it; the data sets' formats need no reader from outside.

use bearing_signal::recording::{read_recording, ReadOptions, RecordingFormat, MCAP_MAGIC};

#[test]
fn without_a_log_reader_an_mcap_log_is_refused_saying_what_reads_it() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("bearingd-20261125T000000Z-000000.mcap");
    let mut bytes = MCAP_MAGIC.to_vec();
    bytes.extend_from_slice(&[0; 64]);
    std::fs::write(&log, bytes).unwrap();
    let err = read_recording(&log, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("bearingd MCAP log") && err.contains("bearingd analyze"),
        "{err}"
    );
    assert!(err.contains(log.to_str().unwrap()), "{err}");

    let csv = dir.path().join("plain.csv");
    std::fs::write(&csv, "accel_g\n0.1\n-0.2\n0.3\n").unwrap();
    let read = read_recording(&csv, &ReadOptions::default()).unwrap();
    assert_eq!(read.format, RecordingFormat::PlainCsv);
    assert_eq!(read.samples, [0.1, -0.2, 0.3]);
}
