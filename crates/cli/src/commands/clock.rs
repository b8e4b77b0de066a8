//! The clocks `hystcomp bench` times with (`--clock`): the wall clock, or the CPU time of the
//! timing thread alone, which on a machine shared with other work counts only the cycles the
//! benchmark itself ran (not the time it waited for a core).

use std::time::Instant;

use crate::CliError;

/// What a timed run is measured in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Clock {
    /// Elapsed real time (`std::time::Instant`).
    #[default]
    Wall,
    /// CPU time of the timing thread (Linux `CLOCK_THREAD_CPUTIME_ID`): unaffected by waiting
    /// for a core on a loaded machine, though still by the caches other work shares. Not
    /// available on other systems.
    ThreadCpu,
}

impl Clock {
    /// The word `--clock` takes.
    pub fn name(self) -> &'static str {
        match self {
            Clock::Wall => "wall",
            Clock::ThreadCpu => "thread-cpu",
        }
    }

    /// Refuses a clock this system cannot read (before any timing starts).
    pub fn check(self) -> Result<(), CliError> {
        match self {
            Clock::Wall => Ok(()),
            Clock::ThreadCpu => thread_cpu_seconds().map(|_| ()).ok_or_else(|| {
                CliError::input(
                    "--clock thread-cpu: this system has no per-thread CPU clock \
                     (Linux only); use --clock wall",
                )
            }),
        }
    }

    /// Starts a measurement.
    pub fn start(self) -> Stopwatch {
        Stopwatch {
            clock: self,
            wall: Instant::now(),
            cpu: match self {
                Clock::Wall => 0.0,
                Clock::ThreadCpu => thread_cpu_seconds().unwrap_or(0.0),
            },
        }
    }
}

/// A measurement started by [`Clock::start`].
#[derive(Debug, Clone, Copy)]
pub struct Stopwatch {
    clock: Clock,
    wall: Instant,
    cpu: f64,
}

impl Stopwatch {
    /// Seconds since the start, on the stopwatch's clock.
    pub fn seconds(&self) -> f64 {
        match self.clock {
            Clock::Wall => self.wall.elapsed().as_secs_f64(),
            Clock::ThreadCpu => thread_cpu_seconds().unwrap_or(self.cpu) - self.cpu,
        }
    }
}

/// The CPU time the calling thread has used, seconds (`None` where the system has no such
/// clock).
#[cfg(target_os = "linux")]
fn thread_cpu_seconds() -> Option<f64> {
    let mut now = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `now` is a valid, writable timespec; clock_gettime writes only into it.
    let status = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut now) };
    (status == 0).then_some(now.tv_sec as f64 + now.tv_nsec as f64 * 1e-9)
}

#[cfg(not(target_os = "linux"))]
fn thread_cpu_seconds() -> Option<f64> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thread_cpu_time_counts_work_not_sleep() {
        if Clock::ThreadCpu.check().is_err() {
            hystcomp_testkit::skip("no per-thread CPU clock on this system (Linux only)");
            return;
        }
        let sleep = Clock::ThreadCpu.start();
        std::thread::sleep(std::time::Duration::from_millis(50));
        let slept = sleep.seconds();
        assert!(
            (0.0..0.02).contains(&slept),
            "{slept} s of CPU while asleep"
        );
        let work = Clock::ThreadCpu.start();
        let mut x = 0u64;
        let wall = Instant::now();
        while wall.elapsed().as_secs_f64() < 0.05 {
            x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
        }
        let worked = work.seconds();
        assert!(
            worked > 0.0 && worked <= 0.06,
            "{worked} s of CPU for 50 ms of work"
        );
    }
}
