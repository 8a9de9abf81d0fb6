//! The store-and-forward queue: a bounded, crash-safe FIFO of records on disk.
//!
//! Every record the bridge makes is appended here *before* it is published, and leaves only
//! when the broker has acknowledged it (QoS 1 PUBACK), so a broker outage, a lost connection
//! or a daemon crash loses nothing while the queue has room.
//!
//! # Layout
//!
//! A directory of segment files `<first record number, 20 digits>.seg` and a file `head` with
//! the number of the first record not yet acknowledged. A segment is a run of frames:
//!
//! | bytes | field |
//! |---|---|
//! | 4 | `len`: length of the data, little-endian u32 |
//! | 4 | CRC-32 of the record number's 8 bytes followed by the data |
//! | 8 | the record number, little-endian u64 (one more than the previous record's) |
//! | len | the data |
//!
//! # Discipline
//!
//! - Appends go to the newest segment; [`DiskQueue::sync`] fsyncs it (and the directory when
//!   a segment was created). The bridge syncs before it publishes anything appended, so a
//!   record the broker saw is on disk.
//! - Acknowledgements advance `head`, which is written to `head.new`, fsynced and renamed
//!   over `head` at each [`DiskQueue::sync`] (the bridge does that once a second and at its
//!   stop; [`DiskQueue::sync_appends`] before each publish makes only the appends durable).
//!   A crash between a PUBACK and that rename sends the record again
//!   after the restart: at-least-once. Each resend carries the same record number (the bridge
//!   puts it in the payload), which is how a subscriber sees the duplicate.
//! - At open, segments are read frame by frame; the first frame that is short, has a bad CRC
//!   or a number out of sequence ends the segment (a torn write from a crash), the file is cut
//!   there and the cut is reported.
//! - Bounded: when the segments would exceed `max_bytes`, the oldest segment is deleted and
//!   its unacknowledged records are counted as dropped (never silently). Segments are a
//!   sixteenth of the bound, so a drop loses the oldest ~6 % at a time.

use std::collections::{BTreeSet, VecDeque};
use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

const FRAME_HEADER: usize = 16;
const HEAD_FILE: &str = "head";
/// Largest record accepted; a DDATA of bearingd is under 0.5 KiB (docs/FLEET.md).
pub const MAX_RECORD_BYTES: usize = 1 << 20;

/// Why the queue could not do what was asked; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum QueueError {
    #[error("{path}: cannot {op}: {source}")]
    Io {
        path: PathBuf,
        op: &'static str,
        source: std::io::Error,
    },
    #[error(
        "a record of {len} bytes is larger than the queue's limit for one record ({limit} bytes)"
    )]
    TooLarge { len: usize, limit: usize },
}

type Result<T> = std::result::Result<T, QueueError>;

fn io<'a>(path: &'a Path, op: &'static str) -> impl FnOnce(std::io::Error) -> QueueError + 'a {
    move |source| QueueError::Io {
        path: path.to_path_buf(),
        op,
        source,
    }
}

/// What [`DiskQueue::open`] found.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct OpenReport {
    /// Records waiting to be sent.
    pub pending: u64,
    /// Segment files cut at a torn or corrupt frame, with the bytes cut from each.
    pub truncated: Vec<(PathBuf, u64)>,
}

struct Segment {
    path: PathBuf,
    first: u64,
    /// Offset of each record's frame in the file.
    offsets: Vec<u64>,
    bytes: u64,
}

impl Segment {
    fn end(&self) -> u64 {
        self.first + self.offsets.len() as u64
    }
}

/// Counters of the queue since it was opened (drops also since it was created: they are
/// persisted in no file, so a restart resets them; the log line at each drop is the record).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct QueueStats {
    /// Records appended.
    pub appended: u64,
    /// Records acknowledged by the broker.
    pub acknowledged: u64,
    /// Records dropped unsent because the queue was full.
    pub dropped: u64,
    /// Records waiting now.
    pub pending: u64,
    /// Bytes on disk now.
    pub bytes: u64,
}

/// The queue; see the module documentation.
pub struct DiskQueue {
    dir: PathBuf,
    max_bytes: u64,
    segment_bytes: u64,
    segments: VecDeque<Segment>,
    /// The newest segment, open for appending.
    tail: Option<File>,
    /// First record not acknowledged.
    head: u64,
    /// The head last written to disk.
    head_on_disk: u64,
    /// Acknowledged records above `head` (acks out of order).
    acked_above: BTreeSet<u64>,
    next: u64,
    tail_dirty: bool,
    dir_dirty: bool,
    stats: QueueStats,
}

impl DiskQueue {
    /// Opens (or creates) the queue in `dir`, bounded to `max_bytes` of segment files.
    pub fn open(dir: &Path, max_bytes: u64) -> Result<(DiskQueue, OpenReport)> {
        crate::fsafe::create_dir_all(dir).map_err(io(dir, "create the queue directory"))?;
        let head_path = dir.join(HEAD_FILE);
        let head = match std::fs::read_to_string(&head_path) {
            Ok(text) => text.trim().parse::<u64>().unwrap_or(0),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => 0,
            Err(e) => return Err(io(&head_path, "read")(e)),
        };
        let mut names: Vec<(u64, PathBuf)> = std::fs::read_dir(dir)
            .map_err(io(dir, "list the queue directory"))?
            .filter_map(|e| e.ok())
            .filter_map(|e| {
                let path = e.path();
                let first = path
                    .file_name()?
                    .to_str()?
                    .strip_suffix(".seg")?
                    .parse::<u64>()
                    .ok()?;
                Some((first, path))
            })
            .collect();
        names.sort();
        let mut report = OpenReport::default();
        let mut segments = VecDeque::new();
        let mut expected: Option<u64> = None;
        for (first, path) in names {
            if expected.is_some_and(|e| e != first) {
                // A segment that does not continue the previous one (a file removed by hand):
                // keep the newer run, so that records stay in order.
                for old in segments.drain(..) {
                    let old: Segment = old;
                    std::fs::remove_file(&old.path)
                        .map_err(io(&old.path, "remove a segment out of sequence"))?;
                }
            }
            let (segment, cut) = read_segment(&path, first)?;
            if cut > 0 {
                report.truncated.push((path.clone(), cut));
            }
            expected = Some(segment.end());
            if segment.offsets.is_empty() || segment.end() <= head {
                std::fs::remove_file(&path).map_err(io(&path, "remove an emptied segment"))?;
                continue;
            }
            segments.push_back(segment);
        }
        let next = segments
            .back()
            .map_or(head, |s| s.end())
            .max(expected.unwrap_or(0))
            .max(head);
        let head = head.max(segments.front().map_or(next, |s| s.first));
        let segment_bytes = (max_bytes / 16).clamp(4096, 16 << 20);
        let tail = match segments.back() {
            Some(last) => Some(
                crate::fsafe::no_follow(OpenOptions::new().append(true))
                    .open(&last.path)
                    .map_err(io(&last.path, "open the newest segment"))?,
            ),
            None => None,
        };
        let mut queue = DiskQueue {
            dir: dir.to_path_buf(),
            max_bytes: max_bytes.max(2 * segment_bytes),
            segment_bytes,
            segments,
            tail,
            head,
            head_on_disk: head,
            acked_above: BTreeSet::new(),
            next,
            tail_dirty: false,
            dir_dirty: true,
            stats: QueueStats::default(),
        };
        queue.write_head()?;
        queue.refresh_stats();
        report.pending = queue.pending();
        Ok((queue, report))
    }

    /// Records waiting (appended, not acknowledged).
    pub fn pending(&self) -> u64 {
        self.next - self.head - self.acked_above.len() as u64
    }

    /// The number the next record gets.
    pub fn next_number(&self) -> u64 {
        self.next
    }

    /// The first record not acknowledged (the sender starts here after a reconnect).
    pub fn first_pending(&self) -> u64 {
        self.head
    }

    pub fn stats(&self) -> QueueStats {
        self.stats
    }

    fn refresh_stats(&mut self) {
        self.stats.pending = self.pending();
        self.stats.bytes = self.segments.iter().map(|s| s.bytes).sum();
    }

    /// Appends a record; returns its number and how many old records were dropped for room.
    pub fn push(&mut self, data: &[u8]) -> Result<(u64, u64)> {
        if data.len() > MAX_RECORD_BYTES {
            return Err(QueueError::TooLarge {
                len: data.len(),
                limit: MAX_RECORD_BYTES,
            });
        }
        let frame = (FRAME_HEADER + data.len()) as u64;
        let needs_new = self.tail.is_none()
            || self
                .segments
                .back()
                .is_none_or(|s| s.bytes + frame > self.segment_bytes && !s.offsets.is_empty());
        if needs_new {
            self.start_segment()?;
        }
        let mut dropped = 0;
        while self.total_bytes() + frame > self.max_bytes && self.segments.len() > 1 {
            dropped += self.drop_oldest()?;
        }
        let number = self.next;
        let mut bytes = Vec::with_capacity(frame as usize);
        bytes.extend_from_slice(&(data.len() as u32).to_le_bytes());
        let mut crc = crc32fast::Hasher::new();
        crc.update(&number.to_le_bytes());
        crc.update(data);
        bytes.extend_from_slice(&crc.finalize().to_le_bytes());
        bytes.extend_from_slice(&number.to_le_bytes());
        bytes.extend_from_slice(data);
        let (Some(segment), Some(file)) = (self.segments.back_mut(), self.tail.as_mut()) else {
            return Err(io(&self.dir, "append a record")(std::io::Error::other(
                "no open segment (a bug in bearingd)",
            )));
        };
        file.write_all(&bytes)
            .map_err(io(&segment.path, "append a record"))?;
        segment.offsets.push(segment.bytes);
        segment.bytes += frame;
        self.next += 1;
        self.tail_dirty = true;
        self.stats.appended += 1;
        self.stats.dropped += dropped;
        self.refresh_stats();
        Ok((number, dropped))
    }

    fn total_bytes(&self) -> u64 {
        self.segments.iter().map(|s| s.bytes).sum()
    }

    fn start_segment(&mut self) -> Result<()> {
        // The previous tail is complete: make it durable before moving on.
        self.sync_tail()?;
        let path = self.dir.join(format!("{:020}.seg", self.next));
        let file =
            crate::fsafe::no_follow(OpenOptions::new().create(true).truncate(true).write(true))
                .open(&path)
                .map_err(io(&path, "create a queue segment"))?;
        self.tail = Some(file);
        self.segments.push_back(Segment {
            path,
            first: self.next,
            offsets: Vec::new(),
            bytes: 0,
        });
        self.dir_dirty = true;
        Ok(())
    }

    /// Deletes the oldest segment; returns how many of its records were never acknowledged.
    fn drop_oldest(&mut self) -> Result<u64> {
        let Some(oldest) = self.segments.pop_front() else {
            return Ok(0);
        };
        std::fs::remove_file(&oldest.path).map_err(io(&oldest.path, "remove a full segment"))?;
        self.dir_dirty = true;
        let end = oldest.end();
        let unacked = (self.head.max(oldest.first)..end)
            .filter(|n| !self.acked_above.contains(n))
            .count() as u64;
        self.acked_above = self.acked_above.split_off(&end);
        self.head = self.head.max(end);
        self.advance_head();
        Ok(unacked)
    }

    /// Reads record `number`; `None` if it was acknowledged, dropped or not yet appended.
    pub fn read(&mut self, number: u64) -> Result<Option<Vec<u8>>> {
        if number < self.head || number >= self.next || self.acked_above.contains(&number) {
            return Ok(None);
        }
        let Some(segment) = self
            .segments
            .iter()
            .find(|s| (s.first..s.end()).contains(&number))
        else {
            return Ok(None);
        };
        let offset = segment.offsets[(number - segment.first) as usize];
        let mut file = File::open(&segment.path).map_err(io(&segment.path, "open a segment"))?;
        file.seek(SeekFrom::Start(offset))
            .map_err(io(&segment.path, "seek in a segment"))?;
        let mut header = [0u8; FRAME_HEADER];
        file.read_exact(&mut header)
            .map_err(io(&segment.path, "read a record"))?;
        let len = u32::from_le_bytes(header[0..4].try_into().unwrap_or_default()) as usize;
        let mut data = vec![0; len];
        file.read_exact(&mut data)
            .map_err(io(&segment.path, "read a record"))?;
        Ok(Some(data))
    }

    /// Marks record `number` acknowledged by the broker.
    pub fn ack(&mut self, number: u64) {
        if number < self.head || number >= self.next || !self.acked_above.insert(number) {
            return;
        }
        self.stats.acknowledged += 1;
        self.advance_head();
        self.refresh_stats();
    }

    fn advance_head(&mut self) {
        while self.acked_above.remove(&self.head) {
            self.head += 1;
        }
    }

    fn sync_tail(&mut self) -> Result<()> {
        if self.tail_dirty {
            if let (Some(file), Some(segment)) = (self.tail.as_ref(), self.segments.back()) {
                file.sync_data()
                    .map_err(io(&segment.path, "fsync a segment"))?;
            }
            self.tail_dirty = false;
        }
        Ok(())
    }

    /// Makes every append durable (fsync of the newest segment, and of the directory when a
    /// segment was created), and nothing else: cheap when nothing was appended.
    pub fn sync_appends(&mut self) -> Result<()> {
        self.sync_tail()?;
        self.sync_dir()
    }

    fn sync_dir(&mut self) -> Result<()> {
        if self.dir_dirty {
            let dir = File::open(&self.dir).map_err(io(&self.dir, "open the queue directory"))?;
            dir.sync_all()
                .map_err(io(&self.dir, "fsync the queue directory"))?;
            self.dir_dirty = false;
        }
        Ok(())
    }

    /// Makes every append durable (fsync), records the acknowledgements (`head`) and deletes
    /// segments that are fully acknowledged.
    pub fn sync(&mut self) -> Result<()> {
        self.sync_tail()?;
        while self.segments.len() > 1 && self.segments.front().is_some_and(|s| s.end() <= self.head)
        {
            if let Some(done) = self.segments.pop_front() {
                std::fs::remove_file(&done.path)
                    .map_err(io(&done.path, "remove a delivered segment"))?;
                self.dir_dirty = true;
            }
        }
        if self.head != self.head_on_disk {
            self.write_head()?;
        }
        self.sync_dir()?;
        self.refresh_stats();
        Ok(())
    }

    fn write_head(&mut self) -> Result<()> {
        let path = self.dir.join(HEAD_FILE);
        crate::fsafe::replace(&path, format!("{}\n", self.head).as_bytes())
            .map_err(io(&path, "replace"))?;
        self.head_on_disk = self.head;
        self.dir_dirty = true;
        Ok(())
    }
}

/// Reads a segment's frames; cuts the file at the first bad one. Returns the segment and the
/// bytes cut.
fn read_segment(path: &Path, first: u64) -> Result<(Segment, u64)> {
    let bytes = std::fs::read(path).map_err(io(path, "read a queue segment"))?;
    let mut offsets = Vec::new();
    let mut at = 0usize;
    let mut expected = first;
    while at + FRAME_HEADER <= bytes.len() {
        let len = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap_or_default()) as usize;
        let crc = u32::from_le_bytes(bytes[at + 4..at + 8].try_into().unwrap_or_default());
        let number = u64::from_le_bytes(bytes[at + 8..at + 16].try_into().unwrap_or_default());
        let end = at + FRAME_HEADER + len;
        if len > MAX_RECORD_BYTES || end > bytes.len() || number != expected {
            break;
        }
        let mut hasher = crc32fast::Hasher::new();
        hasher.update(&number.to_le_bytes());
        hasher.update(&bytes[at + FRAME_HEADER..end]);
        if hasher.finalize() != crc {
            break;
        }
        offsets.push(at as u64);
        expected += 1;
        at = end;
    }
    let cut = (bytes.len() - at) as u64;
    if cut > 0 {
        let file = crate::fsafe::no_follow(OpenOptions::new().write(true))
            .open(path)
            .map_err(io(path, "open a torn segment"))?;
        file.set_len(at as u64)
            .map_err(io(path, "cut a torn segment"))?;
        file.sync_all().map_err(io(path, "fsync a cut segment"))?;
    }
    Ok((
        Segment {
            path: path.to_path_buf(),
            first,
            offsets,
            bytes: at as u64,
        },
        cut,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use bearingd_testdata::scratch_dir;

    fn record(n: u64) -> Vec<u8> {
        format!("record {n:06} {}", "x".repeat(100)).into_bytes()
    }

    #[test]
    fn records_come_back_in_order_and_leave_when_acknowledged() {
        let dir = scratch_dir("queue-order");
        let (mut q, report) = DiskQueue::open(&dir, 1 << 20).unwrap();
        assert_eq!(report.pending, 0);
        for n in 0..100 {
            assert_eq!(q.push(&record(n)).unwrap(), (n, 0));
        }
        q.sync().unwrap();
        assert_eq!(q.pending(), 100);
        for n in 0..100 {
            assert_eq!(q.read(n).unwrap().unwrap(), record(n));
        }
        // Acknowledged out of order: the head waits for the gap.
        q.ack(1);
        assert_eq!(q.first_pending(), 0);
        q.ack(0);
        assert_eq!(q.first_pending(), 2);
        assert_eq!(q.read(1).unwrap(), None);
        assert_eq!(q.pending(), 98);
    }

    #[test]
    fn what_was_not_acknowledged_survives_a_reopen() {
        let dir = scratch_dir("queue-reopen");
        {
            let (mut q, _) = DiskQueue::open(&dir, 1 << 20).unwrap();
            for n in 0..50 {
                q.push(&record(n)).unwrap();
            }
            for n in 0..20 {
                q.ack(n);
            }
            q.sync().unwrap();
            // Acknowledged after the last sync: not recorded, so sent again (at-least-once).
            q.ack(20);
        }
        let (mut q, report) = DiskQueue::open(&dir, 1 << 20).unwrap();
        assert_eq!(report.pending, 30);
        assert!(report.truncated.is_empty());
        assert_eq!(q.first_pending(), 20);
        assert_eq!(q.next_number(), 50);
        assert_eq!(q.read(20).unwrap().unwrap(), record(20));
        assert_eq!(q.read(49).unwrap().unwrap(), record(49));
        assert_eq!(q.push(&record(50)).unwrap().0, 50, "numbers go on");
    }

    #[test]
    fn a_torn_last_frame_is_cut_and_reported() {
        let dir = scratch_dir("queue-torn");
        {
            let (mut q, _) = DiskQueue::open(&dir, 1 << 20).unwrap();
            for n in 0..10 {
                q.push(&record(n)).unwrap();
            }
            q.sync().unwrap();
        }
        let segment = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| p.extension().is_some_and(|e| e == "seg"))
            .unwrap();
        let full = std::fs::metadata(&segment).unwrap().len();
        // A crash in the middle of the tenth frame's write.
        let file = OpenOptions::new().write(true).open(&segment).unwrap();
        file.set_len(full - 30).unwrap();
        drop(file);
        let (mut q, report) = DiskQueue::open(&dir, 1 << 20).unwrap();
        assert_eq!(report.pending, 9);
        assert_eq!(report.truncated.len(), 1);
        assert_eq!(q.read(8).unwrap().unwrap(), record(8));
        assert_eq!(q.read(9).unwrap(), None);
        assert_eq!(q.push(&record(9)).unwrap().0, 9);

        // A flipped byte in a frame ends the segment there too.
        q.sync().unwrap();
        drop(q);
        let mut bytes = std::fs::read(&segment).unwrap();
        let at = bytes.len() / 2;
        bytes[at] ^= 0xff;
        std::fs::write(&segment, &bytes).unwrap();
        let (q, report) = DiskQueue::open(&dir, 1 << 20).unwrap();
        assert_eq!(report.truncated.len(), 1);
        assert!(q.pending() < 10);
    }

    #[test]
    fn a_full_queue_drops_the_oldest_and_counts_them() {
        let dir = scratch_dir("queue-full");
        let max = 64 * 1024;
        let (mut q, _) = DiskQueue::open(&dir, max).unwrap();
        let mut dropped = 0;
        let total = 2000u64;
        for n in 0..total {
            dropped += q.push(&record(n)).unwrap().1;
            assert!(q.stats().bytes <= max, "{:?}", q.stats());
        }
        q.sync().unwrap();
        assert!(dropped > 0);
        assert_eq!(q.stats().dropped, dropped);
        // What is left is the newest records, contiguous, and nothing else was lost.
        assert_eq!(q.pending() + dropped, total);
        assert_eq!(q.first_pending(), dropped);
        assert_eq!(q.read(total - 1).unwrap().unwrap(), record(total - 1));
        assert_eq!(q.read(dropped).unwrap().unwrap(), record(dropped));
        assert_eq!(q.read(dropped - 1).unwrap(), None);
        // Reopened: the same.
        drop(q);
        let (q, report) = DiskQueue::open(&dir, max).unwrap();
        assert_eq!(report.pending, total - dropped);
        assert_eq!(q.first_pending(), dropped);
    }

    #[test]
    fn delivered_segments_are_deleted() {
        let dir = scratch_dir("queue-delivered");
        let (mut q, _) = DiskQueue::open(&dir, 64 * 1024).unwrap();
        for n in 0..500 {
            q.push(&record(n)).unwrap();
        }
        for n in 0..500 {
            q.ack(n);
        }
        q.sync().unwrap();
        let segments = std::fs::read_dir(&dir)
            .unwrap()
            .filter(|e| {
                e.as_ref()
                    .unwrap()
                    .path()
                    .extension()
                    .is_some_and(|x| x == "seg")
            })
            .count();
        assert_eq!(segments, 1, "only the open tail is kept");
        assert_eq!(q.pending(), 0);
        assert_eq!(q.stats().acknowledged, 500);
    }
}
