// The one random generator of nlifs, bit for bit the twin of `src/rng.rs`: a 32-bit PCG
// (RXS-M-XS output) with streams derived by hashing (seed, frame, chain). Keep the constants and
// the operations in sync with the Rust side; `tests/gpu_vs_cpu.rs` checks the streams agree.

const PCG_MUL: u32 = 747796405u;
const PCG_INC: u32 = 2891336453u;

// One PCG-RXS-M-XS round: used both as the generator's output function and as a hash.
fn pcg_hash(input: u32) -> u32 {
    let state = input * PCG_MUL + PCG_INC;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The generator state of chain `chain` in frame `frame` of a run seeded with `seed`.
fn pcg_for_stream(seed: u32, frame: u32, chain: u32) -> u32 {
    return pcg_hash(seed ^ pcg_hash(frame ^ pcg_hash(chain)));
}

fn pcg_next_u32(state: ptr<function, u32>) -> u32 {
    let old = *state;
    *state = old * PCG_MUL + PCG_INC;
    let word = ((old >> ((old >> 28u) + 4u)) ^ old) * 277803737u;
    return (word >> 22u) ^ word;
}

// Uniform in [0, 1) with 24 bits of resolution (exact in f32).
fn pcg_next_f32(state: ptr<function, u32>) -> f32 {
    return f32(pcg_next_u32(state) >> 8u) * (1.0 / 16777216.0);
}
