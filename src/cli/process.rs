//! This process's CPU time and resident memory, read from Linux's /proc
//! (the procfs crate: clock ticks per second from sysconf, not assumed), for
//! `render --stats` and `bench tree`. None where /proc is unavailable. And
//! the USD stage read once in a child process first, where an abort of the
//! reader cannot take the command with it.

use std::path::Path;

use procfs::process::{ClearRefs, Process};

use crate::scene::{Scene, SceneError};

/// Set in the child that reads a stage for [`read_usd_in_a_child`], which
/// must not spawn another.
const CHILD: &str = "LIGHTCUTS_USD_CHILD";

/// Reads the USD stage `scene` names (if any) in a child process first
/// (`lightcuts inspect` with the same `flags`): the USD reader (openusd
/// 0.6) allocates what a crate file's counts say before checking them, and
/// a corrupt file's absurd count makes the allocation fail, which aborts a
/// process; so does a stack overflow. A child that dies by a signal is this
/// scene's error, naming the stage, and nothing is written. A child that
/// fails otherwise has met an error the load in this process reports
/// itself. Costs one more read of the stage.
pub fn read_usd_in_a_child(scene: &Path, flags: &[String]) -> Result<(), SceneError> {
    use std::os::unix::process::ExitStatusExt;
    if std::env::var_os(CHILD).is_some() {
        return Ok(());
    }
    let Some(stage) = Scene::usd_stage(scene) else { return Ok(()) };
    let Ok(exe) = std::env::current_exe() else { return Ok(()) };
    let status = std::process::Command::new(exe)
        .arg("inspect")
        .arg(scene)
        .args(flags)
        .env(CHILD, "1")
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status();
    match status {
        Ok(status) => match status.signal() {
            Some(signal) => Err(SceneError::new(
                &stage,
                "file",
                format!(
                    "the USD reader aborted on this file (signal {signal}: a corrupt or hostile file, whose counts ask \
                     for more memory than there is, or whose nesting overflows the stack)"
                ),
            )),
            None => Ok(()),
        },
        // Without a child (no process table), the load goes on in this process.
        Err(_) => Ok(()),
    }
}

/// User plus system CPU time of this process so far, seconds.
#[must_use]
pub fn cpu_seconds() -> Option<f64> {
    let stat = Process::myself().ok()?.stat().ok()?;
    Some((stat.utime + stat.stime) as f64 / procfs::ticks_per_second() as f64)
}

/// Resident memory now and at its peak, from one read of
/// /proc/self/status.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Memory {
    /// VmRSS, MiB.
    pub resident_mib: f64,
    /// VmHWM (the largest resident memory so far, or since the last
    /// [`reset_peak_resident`]), MiB. The kernel computes it as the larger
    /// of its recorded peak and the VmRSS of the same read, so within one
    /// read it is never below VmRSS. Across two reads it can be: the
    /// kernel records the peak only at certain events (unmapping memory),
    /// and the VmRSS of an earlier read may exceed both that record and a
    /// later VmRSS; a test that compared two reads failed about one run in six.
    pub peak_resident_mib: f64,
}

/// This process's memory now, None where /proc is unavailable.
#[must_use]
pub fn memory() -> Option<Memory> {
    let status = Process::myself().ok()?.status().ok()?;
    Some(Memory { resident_mib: status.vmrss? as f64 / 1024.0, peak_resident_mib: status.vmhwm? as f64 / 1024.0 })
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
        // orderings that always hold are checked: within one read.
        let block = vec![1u8; 64 << 20];
        std::hint::black_box(&block);
        let now = memory().unwrap();
        assert!(now.resident_mib >= 64.0, "a touched 64 MiB block is resident: {now:?}");
        assert!(now.peak_resident_mib >= now.resident_mib, "{now:?}");
        assert!(now.peak_resident_mib >= 64.0, "{now:?}");
    }
}
