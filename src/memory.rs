//! Process memory: the peak the summary line reports, and what is still available, so that work
//! too large for the machine is refused before it starts instead of failing half way.

/// Peak resident set size of this process (VmHWM), in MiB; 0 where the system does not say.
pub fn peak_rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| {
                l.split_whitespace()
                    .nth(1)
                    .and_then(|k| k.parse::<f64>().ok())
            })
        })
        .map_or(0.0, |kib| kib / 1024.0)
}

/// Bytes this process can still allocate: the system's available memory, or what is left
/// under an address-space limit (`ulimit -v`) when that is less; `None` where the system does
/// not say.
pub fn memory_available() -> Option<u64> {
    let field = |text: &str, key: &str| -> Option<u64> {
        text.lines()
            .find(|l| l.starts_with(key))?
            .split_whitespace()
            .nth(1)?
            .parse::<u64>()
            .ok()
    };
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
    let mut available = field(&meminfo, "MemAvailable:")? * 1024;
    let limits = std::fs::read_to_string("/proc/self/limits").unwrap_or_default();
    let limit = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))
        .and_then(|l| l.split_whitespace().nth(3))
        .and_then(|v| v.parse::<u64>().ok());
    if let Some(limit) = limit {
        let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
        let used = field(&status, "VmSize:").unwrap_or(0) * 1024;
        available = available.min(limit.saturating_sub(used));
    }
    Some(available)
}
