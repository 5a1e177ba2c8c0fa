//! The C allocator's settings for the driver's per-frame memory.
//!
//! Lavapipe (the software Vulkan driver the harness runs on without a GPU) allocates and frees
//! megabytes per frame through the C allocator: llvmpipe's binned scene data and the draw
//! module's vertex buffers. glibc hands such memory back to the kernel on every free (its
//! trim and mmap thresholds adapt only upwards from 128 KiB), so each frame faults the same
//! pages in again, zeroed: 2,967 minor faults per GATOR frame, 3,842 per fragment-PT frame and
//! 768 per HAVS frame on box:20k at 512² (`/usr/bin/time`'s minor fault count over 10 extra
//! frames; docs/profile.md). Keeping up to [`TRIM_THRESHOLD`] of freed memory, and serving
//! blocks below [`MMAP_THRESHOLD`] from the heap, removes them (0, 65 and 0 per frame).
//!
//! This is what any long-running renderer would do with its allocator; it changes no image. It
//! does make a row's `host_peak_bytes` include up to [`TRIM_THRESHOLD`] of memory freed by
//! earlier rows and kept for reuse.

/// Freed memory at the top of a heap that glibc keeps instead of returning it (bytes).
pub const TRIM_THRESHOLD: usize = 256 << 20;
/// Blocks from this size up are mapped and unmapped on their own (bytes; glibc's largest
/// allowed value on 64-bit targets).
pub const MMAP_THRESHOLD: usize = 32 << 20;

/// Sets the thresholds (process-wide, every thread's arena). Call once, first thing in `main`;
/// a no-op off glibc. Returns whether both settings were taken.
pub fn keep_freed_driver_memory() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: mallopt only sets allocator parameters; it is safe to call at any time.
        unsafe {
            libc::mallopt(libc::M_TRIM_THRESHOLD, TRIM_THRESHOLD as libc::c_int) == 1
                && libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD as libc::c_int) == 1
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
    fn glibc_takes_both_thresholds() {
        assert!(super::keep_freed_driver_memory());
    }
}
