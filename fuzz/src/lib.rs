//! What the fuzz targets share: the allocation limiter, the byte readers that turn fuzz input
//! into frames and payloads, and a scratch file for the readers that take a path.
//!
//! Why an allocation limiter: issue 32 asks for "no allocation larger than the input
//! justifies". Without a sanitizer (stable toolchain: `cargo fuzz -s none`), libFuzzer's
//! `-malloc_limit_mb` has no malloc hooks, and `-rss_limit_mb` misses a 4 GiB reservation that
//! is never touched. So every allocation of a target's body goes through [`Limited`], which
//! aborts (a crash libFuzzer saves as an artifact) on any single allocation over the budget
//! [`with_budget`] set for that input.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The largest single allocation allowed now; `usize::MAX` outside a target's body.
static BUDGET: AtomicUsize = AtomicUsize::new(usize::MAX);

/// The system allocator, refusing (by aborting) any single allocation over [`BUDGET`].
pub struct Limited;

// SAFETY: every method forwards to `System` with the caller's own arguments, unchanged, so the
// `GlobalAlloc` contract holds as it does for `System`; the check before it only reads an atomic
// and, on failure, writes to stderr from a stack buffer (no allocation) and aborts.
#[allow(unsafe_code)]
unsafe impl GlobalAlloc for Limited {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        check(layout.size());
        // SAFETY: forwarded as received (see the impl's comment).
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        check(layout.size());
        // SAFETY: forwarded as received.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded as received.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        check(new_size);
        // SAFETY: forwarded as received.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Limited = Limited;

fn check(size: usize) {
    let budget = BUDGET.load(Ordering::Relaxed);
    if size > budget {
        // Never allocate here: format into a stack buffer.
        let mut line = [0u8; 160];
        let mut cursor = std::io::Cursor::new(&mut line[..]);
        let _ = write!(
            cursor,
            "==fuzz allocation limit== one allocation of {size} bytes, over this input's budget of {budget} bytes\n"
        );
        let written = cursor.position() as usize;
        let _ = std::io::stderr().write_all(&line[..written]);
        std::process::abort();
    }
}

/// The budget most parsers get: 1 MiB for fixed tables and buffers, plus 16 bytes per input
/// byte (a number's text of 2 bytes becomes an 8-byte f64, and a growing `Vec` may double).
pub fn default_budget(input_len: usize) -> usize {
    (1 << 20) + 16 * input_len
}

/// Runs `body` with every single allocation limited to `budget` bytes.
pub fn with_budget<T>(budget: usize, body: impl FnOnce() -> T) -> T {
    BUDGET.store(budget, Ordering::Relaxed);
    let result = body();
    BUDGET.store(usize::MAX, Ordering::Relaxed);
    result
}

/// Reads fuzz input as a little-endian byte stream; reading past the end gives zeros, so every
/// input decodes to something.
pub struct Bytes<'a> {
    rest: &'a [u8],
}

impl<'a> Bytes<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Bytes { rest: data }
    }

    pub fn is_empty(&self) -> bool {
        self.rest.is_empty()
    }

    /// The next `n` bytes (fewer at the end).
    pub fn take(&mut self, n: usize) -> &'a [u8] {
        let (head, tail) = self.rest.split_at(n.min(self.rest.len()));
        self.rest = tail;
        head
    }

    /// The next `N` bytes, zero-padded at the end.
    pub fn array<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        let head = self.take(N);
        out[..head.len()].copy_from_slice(head);
        out
    }

    pub fn u8(&mut self) -> u8 {
        self.array::<1>()[0]
    }

    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.array())
    }

    pub fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.array())
    }

    pub fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.array())
    }
}

/// One CAN frame of fuzz input: `[id u32 LE][len u8][len bytes]`, the length taken modulo 65
/// (a CAN FD frame carries at most 64 bytes); `None` once the input is used up.
pub fn next_can_frame<'a>(bytes: &mut Bytes<'a>) -> Option<(u32, &'a [u8])> {
    if bytes.is_empty() {
        return None;
    }
    let id = bytes.u32();
    let len = usize::from(bytes.u8()) % 65;
    Some((id, bytes.take(len)))
}

/// A private scratch directory for the targets whose readers take a path: on tmpfs
/// (`/dev/shm`) when there is one, so that writing each input costs no disk I/O.
pub fn scratch_dir(target: &str) -> PathBuf {
    let base = if Path::new("/dev/shm").is_dir() {
        PathBuf::from("/dev/shm")
    } else {
        std::env::temp_dir()
    };
    base.join(format!("bearingd-fuzz-{target}-{}", std::process::id()))
}

/// Writes `data` to `dir/name` (the directory made if needed, emptied first) and returns the
/// path. A failure here is the machine's, not the input's: it panics, which stops the run.
pub fn write_scratch(dir: &Path, name: &str, data: &[u8]) -> PathBuf {
    empty_dir(dir);
    #[allow(clippy::expect_used)]
    std::fs::create_dir_all(dir).expect("fuzz scratch directory");
    let path = dir.join(name);
    #[allow(clippy::expect_used)]
    std::fs::write(&path, data).expect("fuzz scratch file");
    path
}

/// Removes what a reader or the recovery left in `dir` (copies, quarantined files).
pub fn empty_dir(dir: &Path) {
    if let Ok(entries) = std::fs::read_dir(dir) {
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                let _ = std::fs::remove_dir_all(&path);
            } else {
                let _ = std::fs::remove_file(&path);
            }
        }
    }
}
