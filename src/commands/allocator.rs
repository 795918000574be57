//! How the C allocator gives freed memory back. Mesa's software rasterisers allocate their
//! binned scenes, vertex buffers and texture storage through `malloc`, so a run measuring one
//! configuration after another holds what glibc keeps of the earlier ones.

/// The size from which every `malloc` block gets a mapping of its own.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const OWN_MAPPING_BYTES: libc::c_int = 1024 * 1024;

/// Fixes glibc's mmap threshold at 1 MiB, so that every block of that size or more is mapped
/// on its own and unmapped when freed. By default glibc raises the threshold to the largest
/// block freed so far (up to 32 MiB); blocks under it then come from its heap, which it can
/// shrink only from the top, so the pages of an earlier configuration's frames stay resident
/// under a later one's. A 12-candidate `tune` of oa_dm3 peaked at 2.07 GB with the threshold
/// at 32 MiB, 1.92 GB at 1 MiB and 1.86 GB at 128 KiB (glibc's starting value); 128 KiB made a
/// paper's frame of volumes there 10% slower (blocks of a few hundred KiB mapped and faulted
/// in every frame), 1 MiB no slower (docs/reproduce.md, "Memory"). A threshold set in the
/// environment (`MALLOC_MMAP_THRESHOLD_`) is left as it is. Elsewhere than glibc this does
/// nothing.
pub fn return_large_blocks() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    if std::env::var_os("MALLOC_MMAP_THRESHOLD_").is_none() {
        // SAFETY: mallopt only changes a tunable of the allocator; called before any thread
        // other than main exists.
        let set = unsafe { libc::mallopt(libc::M_MMAP_THRESHOLD, OWN_MAPPING_BYTES) };
        if set != 1 {
            log::warn!("could not fix malloc's mmap threshold: freed memory may stay resident");
        }
    }
}
