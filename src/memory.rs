//! Process memory: the peak the summary line reports, and what is still available, so that work
//! too large for the machine is refused before it starts instead of failing half way.

/// Keep freed memory in the process for reuse (glibc: every block from the heap, never from a
/// fresh mapping, and the heap never trimmed), for a command-line run that ends when its work
/// does. glibc maps blocks of more than 32 MB afresh at every allocation and unmaps them when
/// freed, so each frame's buffers at a million triangles and more (right-hand sides, solve
/// blocks, positions: 48-192 MB each at 4M) came back as new pages the kernel zeroes one
/// fault at a time. Measured on the bench tubes (`perf stat inbetween tween`, 3 keys,
/// `--tweens 10`): 4M triangles 20.1 -> 16.3 s, 3.94M -> 2.06M page faults, system time 11.7 ->
/// 5.7 s, peak 4107 -> 4048 MiB; 1M 3.64-3.88 -> 3.49-3.60 s. Elsewhere (other systems and
/// C libraries) it does nothing.
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets the allocator's parameters; called first thing in main, before
    // any other thread exists.
    unsafe {
        libc::mallopt(libc::M_MMAP_MAX, 0);
        // -1: never trim (mallopt(3)).
        libc::mallopt(libc::M_TRIM_THRESHOLD, -1);
    }
}

/// Hand back to the system the freed memory every thread's arena holds (glibc: `malloc_trim`),
/// between the big steps of a run (a segment's set-up, its frames). glibc gives each thread an
/// arena of its own, and with [`keep_freed_memory`] a block one worker thread freed serves only
/// that thread: on 16 threads the resident memory never fell between segments. Trimmed after
/// each large segment's set-up and after its frames, on a 16-core machine (`bench --end-to-end
/// 4000000 --e2e-arg=--threads=16`): peak 5056-5105 -> 4372-4447 MiB, 11.3-11.6 s -> 11.6-12.7
/// s; 1M 1358-1399 -> 1184-1259 MiB, 2.91-2.94 -> 2.67-2.75 s. On this 2-core VM, the 4M tube
/// on 2 threads 4147 -> 4054 MiB, the time the same within the noise. Elsewhere it does
/// nothing.
pub fn release_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only returns free memory to the system; it takes the arenas' locks.
    unsafe {
        libc::malloc_trim(0);
    }
}

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
