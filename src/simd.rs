//! The CPU's vector instructions, detected once for the whole program: the chaos game's lane
//! kernel (`chaos_game/x86.rs`), the splat (`splat/x86.rs`) and the ray tracer's wide traversal
//! (`raytrace/wide.rs`) all ask [`SimdLevel::detect`] instead of probing the CPU themselves, so
//! they agree on what the CPU runs and the probe (a `cpuid` each time) runs once.

use std::sync::OnceLock;

/// The widest vector instructions this CPU runs that nlifs has kernels for. Ordered: a level
/// includes every lower one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Default)]
pub enum SimdLevel {
    /// Only the baseline target (SSE2 on x86-64), or another architecture.
    #[default]
    Scalar,
    /// x86-64 with AVX2 and POPCNT (every AVX2 CPU has it; the baseline target has not, and a
    /// count of bits was a dozen instructions).
    Avx2,
    /// x86-64 with AVX2 and AVX-512 F, CD, VL, DQ and BW (every AVX-512 CPU since Skylake-SP
    /// and Zen 4 has the five; the splat's accumulating modes find a vector's repeated pixels
    /// with CD's conflict detection, the flame game's kernel is compiled for all five).
    Avx512,
}

impl SimdLevel {
    /// This CPU's level, detected on the first call; `NLIFS_SIMD` = `avx2` or `scalar` caps it
    /// (to measure the narrower kernels on a wider CPU).
    pub fn detect() -> Self {
        static LEVEL: OnceLock<SimdLevel> = OnceLock::new();
        *LEVEL.get_or_init(|| {
            let cap = match std::env::var("NLIFS_SIMD").as_deref() {
                Ok("avx2") => Self::Avx2,
                Ok("scalar") => Self::Scalar,
                _ => Self::Avx512,
            };
            Self::probe().min(cap)
        })
    }

    /// Whether AVX2 code may run at this level.
    pub fn avx2(self) -> bool {
        self >= Self::Avx2
    }

    /// Whether AVX-512 F, CD, VL, DQ and BW (and AVX2) code may run at this level.
    pub fn avx512(self) -> bool {
        self >= Self::Avx512
    }

    fn probe() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("popcnt") {
                let avx512 = std::arch::is_x86_feature_detected!("avx512f")
                    && std::arch::is_x86_feature_detected!("avx512cd")
                    && std::arch::is_x86_feature_detected!("avx512vl")
                    && std::arch::is_x86_feature_detected!("avx512dq")
                    && std::arch::is_x86_feature_detected!("avx512bw");
                return if avx512 { Self::Avx512 } else { Self::Avx2 };
            }
        }
        Self::Scalar
    }
}

/// How the 16-wide splat adds a vector's points to their pixels' sums (the accumulating modes).
/// Both give the same sums; which is faster depends on the CPU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SumUpdates {
    /// Gather the sums of a vector whose pixels are distinct, add, scatter them back: faster
    /// on Intel's AVX-512 cores, where a scatter of eight 64-bit words takes a few cycles.
    Scatter,
    /// Each lane's sum read, added and written with one 16-byte load and store, a vector
    /// behind its lines' prefetch: faster on AMD's (Zen 4), whose scatters are microcoded.
    Lanes,
}

impl SumUpdates {
    /// This CPU's choice, made on the first call: `NLIFS_SUM_UPDATES` = `scatter` or `lanes`
    /// where set (for measuring one against the other), else by the CPU's maker.
    pub fn detect() -> Self {
        static CHOICE: OnceLock<SumUpdates> = OnceLock::new();
        *CHOICE.get_or_init(|| match std::env::var("NLIFS_SUM_UPDATES").as_deref() {
            Ok("scatter") => Self::Scatter,
            Ok("lanes") => Self::Lanes,
            _ if cpu_is_amd() => Self::Lanes,
            _ => Self::Scatter,
        })
    }
}

/// Whether the CPU's vendor string is AMD's.
fn cpu_is_amd() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        let id = std::arch::x86_64::__cpuid(0);
        let vendor: Vec<u8> = [id.ebx, id.edx, id.ecx].iter().flat_map(|w| w.to_le_bytes()).collect();
        vendor == b"AuthenticAMD"
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detection_is_stable_and_ordered() {
        let level = SimdLevel::detect();
        assert_eq!(level, SimdLevel::detect());
        assert!(!level.avx512() || level.avx2());
        #[cfg(target_arch = "x86_64")]
        assert_eq!(level.avx2(), std::arch::is_x86_feature_detected!("avx2"));
    }
}
