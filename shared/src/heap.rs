//! The C allocator's settings for the processes that evaluate designs.
//!
//! An evaluation at 12×40×12 allocates and frees tens of megabytes of matrices (the stiffness,
//! the multigrid hierarchy, their single-precision copies). glibc's defaults adapt: blocks above a
//! moving threshold are mapped and unmapped one by one, and free memory at the top of a heap is
//! handed back to the kernel, so every evaluation faults the same pages in again, zeroed. On the
//! quickstart that was 9.2 million page faults and 29 s of system time in a 229 s run (2-core AMD
//! EPYC, 2026-12-07). Fixed thresholds keep freed memory in the process for the next evaluation:
//! a worker's resident memory then stays at the peak of its largest evaluation, which the memory
//! check (`task::memory`) already budgets for.

/// Blocks up to this size come from the heap (glibc's largest accepted value on 64-bit targets).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const MMAP_THRESHOLD: libc::c_int = 32 << 20;

/// Free memory kept at the top of a heap before any is returned. Above glibc's 64 MiB per-thread
/// heaps, so those are never trimmed; the main heap keeps up to this much.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const TRIM_THRESHOLD: libc::c_int = 256 << 20;

/// Sets the allocator to keep freed memory for reuse. Call it first in `main`, before the
/// evaluations start. Returns whether the allocator took both settings (false where it has no such
/// settings: other C libraries keep their own policy, and results are the same bits either way).
#[allow(unsafe_code)] // the project's one foreign call: no crate wraps mallopt
pub fn keep_freed_memory() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: mallopt takes plain integers and only sets allocator parameters; glibc takes its
        // arena locks itself, so even a call beside other threads is sound.
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD) == 1
                && libc::mallopt(libc::M_TRIM_THRESHOLD, TRIM_THRESHOLD) == 1
        }
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        false
    }
}

#[cfg(test)]
mod tests {
    #[test]
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    fn glibc_takes_both_settings() {
        assert!(super::keep_freed_memory());
    }
}
