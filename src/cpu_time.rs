//! The process's CPU time, for the benchmarks (`nlifs bench`).

/// User + system CPU seconds of this process (all its threads) and of its waited-for children,
/// from /proc/self/stat (Linux; zeros elsewhere). The clock ticks at 10 ms. CPU time is what
/// comparisons on a shared machine use: wall-clock time depends on what else runs.
pub fn cpu_secs() -> (f64, f64) {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the parenthesised command name: utime, stime, cutime, cstime are 14–17.
    let fields: Vec<&str> = stat.rsplit(')').next().unwrap_or("").split_whitespace().collect();
    let ticks = |i: usize| fields.get(i).and_then(|f| f.parse::<f64>().ok()).unwrap_or(0.0);
    let tick = 100.0; // USER_HZ on Linux
    ((ticks(11) + ticks(12)) / tick, (ticks(13) + ticks(14)) / tick)
}
