//! Process memory as the kernel counts it (Linux `/proc/self/status`), for the bench's peak-memory
//! column. Elsewhere every reading is 0 and resetting does nothing.

/// A field of `/proc/self/status` in bytes (`VmHWM`: peak resident set; `VmRSS`: current).
fn status_bytes(field: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(field))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
        })
        .map_or(0, |kb| kb * 1024)
}

/// Peak resident memory of this process since the last [`reset_peak`] (or its start), bytes.
pub fn peak_rss_bytes() -> u64 {
    status_bytes("VmHWM:")
}

/// Resident memory of this process now, bytes.
pub fn rss_bytes() -> u64 {
    status_bytes("VmRSS:")
}

/// Restarts the peak at the current resident size (`echo 5 > /proc/self/clear_refs`), so that a
/// later [`peak_rss_bytes`] tells the peak of what ran in between.
pub fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// Measures the memory an engine adds while `f` runs: returns `f`'s value and the peak resident
/// bytes above what the process held just before (0 where /proc is unavailable).
pub fn peak_increment<T>(f: impl FnOnce() -> T) -> (T, u64) {
    let before = rss_bytes();
    reset_peak();
    let value = f();
    (value, peak_rss_bytes().saturating_sub(before))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_allocation_shows_in_the_peak_increment() {
        if rss_bytes() == 0 {
            return; // no /proc: nothing to measure
        }
        // The reading is process-wide: another test of this binary freeing memory between the
        // "before" reading and the reset hides growth. It cannot invent growth, so the best of a
        // few attempts must show the 64 MB.
        let mb = 64 << 20;
        let grew = (0..5)
            .map(|_| {
                peak_increment(|| {
                    let v = vec![1u8; mb];
                    std::hint::black_box(&v);
                })
                .1
            })
            .max()
            .unwrap_or(0);
        assert!(grew >= mb as u64 * 9 / 10, "peak grew by {grew} bytes");
    }
}
