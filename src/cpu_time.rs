//! The process's CPU time, for the benchmarks (`nlifs bench`).

/// User + system CPU seconds of this process (all its threads) and of its waited-for children,
/// from `getrusage` (microseconds on Linux, where a render of 0.08 s read from /proc's 10 ms
/// ticks was ±12 %); zeros where there is none (the browser). CPU time is what comparisons on a
/// shared machine use: wall-clock time depends on what else runs.
pub fn cpu_secs() -> (f64, f64) {
    #[cfg(unix)]
    {
        let used = |who: libc::c_int| {
            #[expect(unsafe_code, reason = "the libc call that reports CPU time")]
            // SAFETY: `getrusage` fills the zeroed `rusage` it is given and reads nothing else.
            let usage = unsafe {
                let mut usage: libc::rusage = std::mem::zeroed();
                if libc::getrusage(who, &mut usage) != 0 {
                    return 0.0;
                }
                usage
            };
            let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
            secs(usage.ru_utime) + secs(usage.ru_stime)
        };
        (used(libc::RUSAGE_SELF), used(libc::RUSAGE_CHILDREN))
    }
    #[cfg(not(unix))]
    {
        (0.0, 0.0)
    }
}
