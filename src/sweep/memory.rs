//! Peak resident memory of this process, for the records of points that run alone. Linux
//! keeps it as `VmHWM` in `/proc/self/status` and resets it when `5` is written to
//! `/proc/self/clear_refs` (since Linux 4.0); elsewhere nothing is measured.

/// The process's peak resident set size since it started or since the last
/// [`reset_peak_rss`] (bytes); `None` where the system does not say.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.trim_start_matches("VmHWM:").trim().trim_end_matches("kB").trim().parse().ok()?;
    Some(kib * 1024)
}

/// Resets the peak resident set size to the current one; false where that is not possible
/// (then a later [`peak_rss_bytes`] is the peak since the process started, not a point's).
pub fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_peak_follows_an_allocation_and_resets() {
        if !reset_peak_rss() {
            // Not Linux (or /proc is read-only): nothing is measured, and nothing may be claimed.
            return;
        }
        let before = peak_rss_bytes().expect("VmHWM on Linux");
        let big = std::hint::black_box(vec![1u8; 64 << 20]);
        let during = peak_rss_bytes().expect("VmHWM");
        assert!(during >= before + (60 << 20), "peak {during} B after touching 64 MiB from {before} B");
        drop(std::hint::black_box(big));
        assert!(reset_peak_rss());
        let after = peak_rss_bytes().expect("VmHWM");
        assert!(after + (32 << 20) < during, "reset peak {after} B not below {during} B");
    }
}
