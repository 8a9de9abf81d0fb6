//! Whether the analysis' memory can be in transparent huge pages, and what to set if not.
//!
//! (why) On a VM whose host takes back the memory a guest has left alone for some 100 ms, the
//! next touch of each 4 KiB page costs microseconds, with no page fault the guest could see.
//! Every channel's window ring and transform buffers (about 0.5 MB) are touched once a window,
//! every half second: the deciding block's FFT then waits on the host, up to milliseconds. In
//! a 2 MiB huge page the host works once per huge page (`benches/probes/idle.c`: 10 µs
//! against 3.6 ms for 2 MB). glibc (2.35 and later) puts its heap in huge pages when asked at
//! start, through two tunables ([`HEAP_TUNABLES`]): `glibc.malloc.hugetlb=1` (advise the heap
//! for huge pages) and `glibc.malloc.mmap_threshold` (big buffers from the heap rather than a
//! mapping each, which is too small for a huge page). A process cannot set them for itself
//! (glibc reads them before `main`), so the systemd unit sets them (`Environment=`), the
//! benches take the unit's environment, and `bearingd run` started by hand says what is
//! missing ([`heap_pages`]). Measured in docs/PERFORMANCE.md ("memory left alone").

/// The tunables the systemd unit sets, as `GLIBC_TUNABLES` takes them. 32 MiB is the ceiling
/// glibc's own threshold rises to once it has freed a big mapping; below it every per-channel
/// buffer comes from the heap.
pub const HEAP_TUNABLES: &str = "glibc.malloc.hugetlb=1:glibc.malloc.mmap_threshold=33554432";

/// Where the kernel says which transparent huge page mode it runs.
pub const THP_MODE_FILE: &str = "/sys/kernel/mm/transparent_hugepage/enabled";

/// The smallest `glibc.malloc.mmap_threshold` that keeps a channel's buffers (up to about
/// 0.5 MB each) in the heap.
const SMALLEST_THRESHOLD: u64 = 2 << 20;

/// What the environment gives the heap.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum HeapPages {
    /// The tunables are set and the kernel gives huge pages (`always` or `madvise`).
    Huge,
    /// The kernel gives huge pages, but glibc is not told to use them for the heap: these of
    /// [`HEAP_TUNABLES`] are missing (or too small) in `GLIBC_TUNABLES`.
    Small { missing: Vec<&'static str> },
    /// The kernel gives none (`never`, or no THP at all): nothing to set.
    NoneFromKernel,
}

/// Reads the process' `GLIBC_TUNABLES` and the kernel's THP mode.
pub fn this_process() -> HeapPages {
    let tunables = std::env::var("GLIBC_TUNABLES").ok();
    let mode = std::fs::read_to_string(THP_MODE_FILE).ok();
    heap_pages(tunables.as_deref(), mode.as_deref())
}

/// What `glibc_tunables` (the variable's value, if set) gives the heap under the kernel's
/// `thp_mode` (the contents of [`THP_MODE_FILE`], the selected mode in brackets, if readable).
pub fn heap_pages(glibc_tunables: Option<&str>, thp_mode: Option<&str>) -> HeapPages {
    let kernel_gives = thp_mode
        .and_then(selected_mode)
        .is_some_and(|mode| mode == "always" || mode == "madvise");
    if !kernel_gives {
        return HeapPages::NoneFromKernel;
    }
    let value_of = |name: &str| {
        // glibc takes the last of a name given twice.
        glibc_tunables?
            .split(':')
            .filter_map(|pair| pair.split_once('='))
            .rfind(|(key, _)| *key == name)
            .map(|(_, value)| value)
    };
    let mut missing = Vec::new();
    if !matches!(value_of("glibc.malloc.hugetlb"), Some("1" | "2")) {
        missing.push("glibc.malloc.hugetlb=1");
    }
    let threshold = value_of("glibc.malloc.mmap_threshold").and_then(|v| v.parse::<u64>().ok());
    if threshold.is_none_or(|t| t < SMALLEST_THRESHOLD) {
        missing.push("glibc.malloc.mmap_threshold=33554432");
    }
    if missing.is_empty() {
        HeapPages::Huge
    } else {
        HeapPages::Small { missing }
    }
}

/// The mode in brackets of `always [madvise] never`.
fn selected_mode(modes: &str) -> Option<&str> {
    let start = modes.find('[')? + 1;
    let end = start + modes[start..].find(']')?;
    Some(&modes[start..end])
}

#[cfg(test)]
mod tests {
    use super::*;

    const MADVISE: Option<&str> = Some("always [madvise] never\n");

    #[test]
    fn the_units_tunables_give_huge_pages() {
        let unit = include_str!("../../systemd/bearingd.service");
        let set = unit
            .lines()
            .rev()
            .find_map(|line| line.strip_prefix("Environment=GLIBC_TUNABLES="));
        assert_eq!(set, Some(HEAP_TUNABLES), "the unit sets HEAP_TUNABLES");
        assert_eq!(heap_pages(set, MADVISE), HeapPages::Huge);
        assert_eq!(
            heap_pages(set, Some("[always] madvise never")),
            HeapPages::Huge
        );
    }

    #[test]
    fn what_is_missing_is_named() {
        let both = vec![
            "glibc.malloc.hugetlb=1",
            "glibc.malloc.mmap_threshold=33554432",
        ];
        assert_eq!(
            heap_pages(None, MADVISE),
            HeapPages::Small {
                missing: both.clone()
            }
        );
        assert_eq!(
            heap_pages(Some("glibc.malloc.hugetlb=1"), MADVISE),
            HeapPages::Small {
                missing: vec![both[1]]
            }
        );
        // A threshold too small to keep a channel's buffers in the heap, a value glibc
        // would not take, a huge page setting taken back by a later one.
        for tunables in [
            "glibc.malloc.hugetlb=1:glibc.malloc.mmap_threshold=131072",
            "glibc.malloc.hugetlb=1:glibc.malloc.mmap_threshold=big",
        ] {
            assert_eq!(
                heap_pages(Some(tunables), MADVISE),
                HeapPages::Small {
                    missing: vec![both[1]]
                },
                "{tunables}"
            );
        }
        assert_eq!(
            heap_pages(
                Some("glibc.malloc.hugetlb=1:glibc.malloc.mmap_threshold=33554432:glibc.malloc.hugetlb=0"),
                MADVISE
            ),
            HeapPages::Small {
                missing: vec![both[0]]
            }
        );
    }

    #[test]
    fn a_kernel_without_huge_pages_asks_for_nothing() {
        for mode in [Some("always madvise [never]"), Some(""), None] {
            assert_eq!(
                heap_pages(None, mode),
                HeapPages::NoneFromKernel,
                "{mode:?}"
            );
        }
    }
}
