//! A process's CPU time and memory, from Linux's /proc.

use anyhow::Context;

/// Clock ticks per second in /proc/PID/stat: `sysconf(_SC_CLK_TCK)`, which is 100 on
/// every Linux architecture this runs on (the kernel's USER_HZ).
const CLOCK_TICKS_PER_S: f64 = 100.0;

/// CPU time in user space and in the kernel, seconds.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Cpu {
    pub user_s: f64,
    pub system_s: f64,
}

impl std::ops::Sub for Cpu {
    type Output = Cpu;
    fn sub(self, earlier: Cpu) -> Cpu {
        Cpu {
            user_s: self.user_s - earlier.user_s,
            system_s: self.system_s - earlier.system_s,
        }
    }
}

impl Cpu {
    pub(crate) fn total_s(&self) -> f64 {
        self.user_s + self.system_s
    }
}

/// A process's CPU time so far (utime and stime).
pub(crate) fn cpu(pid: u32) -> anyhow::Result<Cpu> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat"))
        .with_context(|| format!("reading /proc/{pid}/stat"))?;
    // The command name may hold spaces and parentheses: fields count from the last ')'.
    let after = stat.rsplit_once(')').map_or("", |(_, rest)| rest);
    let fields: Vec<&str> = after.split_whitespace().collect();
    // After the name: state (3rd field of the line) is fields[0], utime (14th) is
    // fields[11], stime (15th) fields[12].
    let ticks = |i: usize| -> anyhow::Result<f64> {
        Ok(fields
            .get(i)
            .context("a short /proc stat line")?
            .parse::<f64>()?)
    };
    Ok(Cpu {
        user_s: ticks(11)? / CLOCK_TICKS_PER_S,
        system_s: ticks(12)? / CLOCK_TICKS_PER_S,
    })
}

#[derive(Debug, Clone, Copy)]
pub(crate) struct Memory {
    pub rss_mb: f64,
    pub peak_rss_mb: f64,
}

/// Resident memory now and at its peak (VmRSS, VmHWM).
pub(crate) fn memory(pid: u32) -> anyhow::Result<Memory> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status"))
        .with_context(|| format!("reading /proc/{pid}/status"))?;
    let kb = |name: &str| -> f64 {
        status
            .lines()
            .find_map(|l| l.strip_prefix(name))
            .and_then(|v| v.split_whitespace().next())
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(f64::NAN)
    };
    Ok(Memory {
        rss_mb: kb("VmRSS:") / 1024.0,
        peak_rss_mb: kb("VmHWM:") / 1024.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_process_has_cpu_time_and_memory() {
        let pid = std::process::id();
        // Burn CPU until the kernel's 10 ms accounting shows some (within a bound).
        let start = std::time::Instant::now();
        let mut spin = 0u64;
        while cpu(pid).unwrap().total_s() == 0.0 && start.elapsed().as_secs() < 5 {
            spin = (0..1_000_000u64).fold(spin, |a, i| a.wrapping_add(i ^ (a >> 3)));
        }
        assert!(cpu(pid).unwrap().total_s() > 0.0, "{spin}");
        let m = memory(pid).unwrap();
        assert!(m.rss_mb > 1.0 && m.peak_rss_mb >= m.rss_mb, "{m:?}");
    }
}
