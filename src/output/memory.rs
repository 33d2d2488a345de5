//! Whether a still fits in memory, checked before anything is allocated: a render that cannot
//! fit stops at once with the size it needs and what is available, instead of running for
//! minutes and being killed.
//!
//! Available memory is the smallest of: `MemAvailable` in `/proc/meminfo` (Linux), the room
//! left under the cgroup's `memory.max` (a container or a batch job's allotment), and
//! `NLIFS_MEMORY_LIMIT` (bytes, or with a K, M, G or T suffix: a limit the user sets, e.g. a farm
//! job's share). Where none is known, the check passes.

use std::path::Path;

use crate::splat::SplatView;

/// Where a still's memory goes, in bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryNeed {
    /// The accumulation (one shared framebuffer, or one per thread while they are small).
    pub accumulation: u64,
    /// Writing the output: a streamed PNG's compressed stream, or the float layers of the other
    /// formats.
    pub output: u64,
}

impl MemoryNeed {
    pub fn total(&self) -> u64 {
        self.accumulation + self.output
    }
}

/// Bytes per pixel of the float layers (colour, coverage, depth, id or count) plus the copies
/// the EXR and 16-bit PNG writers make of them.
pub const LAYER_BYTES_PER_PIXEL: u64 = 56;
/// A streamed 8-bit PNG holds its compressed stream; this share of the raw RGB bytes is what
/// the estimate allows (attractors on a flat background compress far better).
pub const STREAMED_PNG_SHARE: f64 = 0.25;

/// The memory a still of `view` needs with `accumulation_bytes` for its accumulation, written
/// as a streamed 8-bit PNG (`streamed`) or through the float layers.
pub fn still_need(view: &SplatView, accumulation_bytes: u64, streamed: bool) -> MemoryNeed {
    let pixels = view.width as u64 * view.height as u64;
    let output =
        if streamed { (pixels as f64 * 3.0 * STREAMED_PNG_SHARE) as u64 } else { pixels * LAYER_BYTES_PER_PIXEL };
    MemoryNeed { accumulation: accumulation_bytes, output }
}

/// Available memory in bytes (see the module comment), None where nothing says.
pub fn available_bytes() -> Option<u64> {
    let limit = std::env::var("NLIFS_MEMORY_LIMIT").ok().and_then(|v| parse_bytes(&v));
    [limit, mem_available(), cgroup_room()].into_iter().flatten().min()
}

/// `NLIFS_MEMORY_LIMIT`'s value: bytes, or a number with a K, M, G or T suffix (powers of 1024).
pub fn parse_bytes(text: &str) -> Option<u64> {
    let t = text.trim();
    let (number, unit) = match t.char_indices().last()? {
        (i, c) if c.is_ascii_alphabetic() => (&t[..i], c.to_ascii_uppercase()),
        _ => (t, 'B'),
    };
    let scale: u64 = match unit {
        'B' => 1,
        'K' => 1 << 10,
        'M' => 1 << 20,
        'G' => 1 << 30,
        'T' => 1 << 40,
        _ => return None,
    };
    let value: f64 = number.trim().parse().ok()?;
    (value.is_finite() && value >= 0.0).then_some((value * scale as f64) as u64)
}

fn mem_available() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Room under the cgroup (v2) memory limit of this process, if it has one.
fn cgroup_room() -> Option<u64> {
    let cgroup = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let rel = cgroup.lines().find_map(|l| l.strip_prefix("0::"))?;
    let dir = Path::new("/sys/fs/cgroup").join(rel.trim_start_matches('/'));
    let max: u64 = std::fs::read_to_string(dir.join("memory.max")).ok()?.trim().parse().ok()?;
    let current: u64 = std::fs::read_to_string(dir.join("memory.current")).ok()?.trim().parse().ok()?;
    Some(max.saturating_sub(current))
}

/// A request that does not fit.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "{what} needs about {} ({} for the accumulation, {} to write it) but only {} is available; \
     ask for a smaller image, closest mode (4 bytes a pixel against 16) or a machine with more memory",
    gib(need.total()), gib(need.accumulation), gib(need.output), gib(*available)
)]
pub struct TooLarge {
    pub what: String,
    pub need: MemoryNeed,
    pub available: u64,
}

/// Ok when `need` fits in `available` (None: unknown, so it passes).
pub fn check(what: &str, need: MemoryNeed, available: Option<u64>) -> Result<(), TooLarge> {
    match available {
        Some(available) if need.total() > available => Err(TooLarge { what: what.to_string(), need, available }),
        _ => Ok(()),
    }
}

/// Bytes as GiB (or MiB below one GiB) with two decimals.
pub fn gib(bytes: u64) -> String {
    if bytes >= 1 << 30 {
        format!("{:.2} GiB", bytes as f64 / (1u64 << 30) as f64)
    } else {
        format!("{:.2} MiB", bytes as f64 / (1u64 << 20) as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_parse_with_units() {
        assert_eq!(parse_bytes("1234"), Some(1234));
        assert_eq!(parse_bytes("2K"), Some(2048));
        assert_eq!(parse_bytes("1.5g"), Some(3 << 29));
        assert_eq!(parse_bytes(" 3 M "), Some(3 << 20));
        assert_eq!(parse_bytes("x"), None);
        assert_eq!(parse_bytes("-1"), None);
        assert_eq!(parse_bytes("5Q"), None);
    }

    #[test]
    fn check_compares_the_total() {
        let need = MemoryNeed { accumulation: 3 << 30, output: 1 << 29 };
        assert!(check("x", need, None).is_ok());
        assert!(check("x", need, Some(4 << 30)).is_ok());
        let err = check("a 16384×16384 density render", need, Some(1 << 30)).unwrap_err();
        let text = err.to_string();
        assert!(text.contains("3.50 GiB") && text.contains("1.00 GiB"), "{text}");
    }

    #[test]
    fn this_machine_says_something_on_linux() {
        if cfg!(target_os = "linux") {
            assert!(mem_available().is_some_and(|b| b > 0));
        }
    }
}
