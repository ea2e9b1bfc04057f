//! This process's CPU time and resident memory, read from Linux's /proc
//! (the procfs crate: clock ticks per second from sysconf, not assumed), for
//! `render --stats` and `bench tree`. None where /proc is unavailable.

use procfs::process::{ClearRefs, Process};

/// User plus system CPU time of this process so far, seconds.
#[must_use]
pub fn cpu_seconds() -> Option<f64> {
    let stat = Process::myself().ok()?.stat().ok()?;
    Some((stat.utime + stat.stime) as f64 / procfs::ticks_per_second() as f64)
}

/// Resident memory now (VmRSS), MiB.
#[must_use]
pub fn resident_mib() -> Option<f64> {
    Some(Process::myself().ok()?.status().ok()?.vmrss? as f64 / 1024.0)
}

/// The largest resident memory so far (VmHWM, or since the last
/// [`reset_peak_resident`]), MiB.
#[must_use]
pub fn peak_resident_mib() -> Option<f64> {
    Some(Process::myself().ok()?.status().ok()?.vmhwm? as f64 / 1024.0)
}

/// Resets the peak to the current resident memory (Linux 4.0 and later);
/// false when the kernel does not allow it.
pub fn reset_peak_resident() -> bool {
    Process::myself().and_then(|p| p.clear_refs(ClearRefs::PeakRSS)).is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_time_grows_and_the_peak_is_never_below_the_current_memory() {
        let before = cpu_seconds().unwrap();
        let mut x = 0u64;
        let start = std::time::Instant::now();
        while start.elapsed().as_millis() < 100 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
        }
        std::hint::black_box(x);
        assert!(cpu_seconds().unwrap() > before, "100 ms of spinning shows as CPU time");
        assert!(reset_peak_resident());
        // Other tests allocate and free in this process meanwhile, so only
        // orderings that always hold are checked.
        let block = vec![1u8; 64 << 20];
        std::hint::black_box(&block);
        let now = resident_mib().unwrap();
        assert!(now >= 64.0, "a touched 64 MiB block is resident: {now} MiB");
        assert!(peak_resident_mib().unwrap() >= now);
    }
}
