//! What a run cost the machine: the process's peak resident memory (Linux's `VmHWM`), and that peak per
//! sample, the figure that says how far a data set can grow (issue #44: peak memory grows linearly
//! with the samples).

use serde::Serialize;

/// The peak resident memory of a run and what it comes to per sample.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MemoryUse {
    /// The process's peak resident set so far, in bytes (`VmHWM` of `/proc/self/status`).
    pub peak_bytes: u64,
    /// The samples the run read.
    pub samples: usize,
    /// `peak_bytes / samples`: an upper bound of the bytes each sample costs (the fixed part of the
    /// process, a few tens of MB, is counted in it).
    pub bytes_per_sample: u64,
}

impl MemoryUse {
    /// The peak so far, for a run on `samples` samples; `None` where the system does not say
    /// (not Linux, or `/proc` not mounted).
    pub fn now(samples: usize) -> Option<Self> {
        let peak_bytes = peak_resident_bytes()?;
        Some(Self::of(peak_bytes, samples))
    }

    /// The figure for a peak of `peak_bytes` over `samples` samples.
    pub fn of(peak_bytes: u64, samples: usize) -> Self {
        Self {
            peak_bytes,
            samples,
            bytes_per_sample: peak_bytes / samples.max(1) as u64,
        }
    }

    /// One line for a reader: `peak memory 1.23 GB (1 234 567 890 bytes), 109.7 kB per sample over 11256 samples`.
    pub fn line(&self) -> String {
        format!(
            "peak memory {} ({} bytes), {} per sample over {} samples",
            bytes_text(self.peak_bytes),
            self.peak_bytes,
            bytes_text(self.bytes_per_sample),
            self.samples
        )
    }
}

/// The process's peak resident set size in bytes (`VmHWM`), `None` where `/proc/self/status` does not
/// give it.
pub fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    vm_hwm_bytes(&status)
}

/// `VmHWM` of a `/proc/PID/status` text, in bytes (the kernel writes it in kB).
fn vm_hwm_bytes(status: &str) -> Option<u64> {
    let line = status.lines().find(|line| line.starts_with("VmHWM:"))?;
    let mut words = line["VmHWM:".len()..].split_whitespace();
    let value: u64 = words.next()?.parse().ok()?;
    match words.next() {
        Some("kB") | None => value.checked_mul(1024),
        Some(_) => None,
    }
}

/// Bytes in decimal units, three significant figures: `812 B`, `45.3 kB`, `1.23 GB`.
pub fn bytes_text(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["B", "kB", "MB", "GB", "TB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1000.0 && unit + 1 < UNITS.len() {
        value /= 1000.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else if value >= 100.0 {
        format!("{value:.0} {}", UNITS[unit])
    } else if value >= 10.0 {
        format!("{value:.1} {}", UNITS[unit])
    } else {
        format!("{value:.2} {}", UNITS[unit])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_peak_is_read_from_vm_hwm_in_kilobytes() {
        let status = "Name:\tpresrs\nVmPeak:\t  900 kB\nVmHWM:\t    1536 kB\nVmRSS:\t 1000 kB\n";
        assert_eq!(vm_hwm_bytes(status), Some(1536 * 1024));
        assert_eq!(vm_hwm_bytes("Name:\tx\n"), None);
        assert_eq!(vm_hwm_bytes("VmHWM:\tmany kB\n"), None);
    }

    #[test]
    fn this_process_has_a_peak_and_the_line_states_it_per_sample() {
        if cfg!(target_os = "linux") {
            let peak = peak_resident_bytes().unwrap();
            assert!(peak > 1 << 20, "{peak}");
        }
        let memory = MemoryUse::of(2_000_000_000, 10_000);
        assert_eq!(memory.bytes_per_sample, 200_000);
        assert_eq!(
            memory.line(),
            "peak memory 2.00 GB (2000000000 bytes), 200 kB per sample over 10000 samples"
        );
    }
}
