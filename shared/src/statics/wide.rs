//! Runs the solver's inner loops with the widest vector instructions the CPU offers.
//!
//! Release binaries target baseline x86-64 (SSE2), so one binary runs on every worker. The
//! solver's loops are plain Rust that the compiler vectorizes; compiled a second time for AVX2
//! (pulp's dispatch, as in the dynamics) a beam run is about 7 % faster (physics.md). Rust never
//! reassociates, contracts or reorders floating-point operations, so both versions compute every
//! value by the same operations in the same order, and a solution is the same bits on every CPU:
//! `solver_bits_do_not_depend_on_the_instruction_set` checks it. `mul_add`, the one fused
//! operation the solver asks for, is correctly rounded in hardware and in software alike.

use std::cell::Cell;

thread_local! {
    /// Set by [`baseline_only`]: this thread's solves take the baseline loops.
    static BASELINE_ONLY: Cell<bool> = const { Cell::new(false) };
}

/// Runs `kernel`, compiled for AVX2 where the CPU has it. Pass a closure marked
/// `#[inline(always)]` whose body calls only `#[inline(always)]` code: whatever the compiler does
/// not inline into the dispatched function keeps its baseline compilation.
#[inline(always)]
pub(crate) fn with_wide_vectors<R>(kernel: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if !BASELINE_ONLY.get()
        && let Some(avx2) = pulp::x86::V3::try_new()
    {
        return pulp::Simd::vectorize(avx2, kernel);
    }
    kernel()
}

/// Runs `f` with this thread's solves on the baseline loops, as on a CPU without AVX2: for the
/// test that compares the two.
pub fn baseline_only<R>(f: impl FnOnce() -> R) -> R {
    let before = BASELINE_ONLY.replace(true);
    let result = f();
    BASELINE_ONLY.set(before);
    result
}
