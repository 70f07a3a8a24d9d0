// How the process takes memory from the system.
#pragma once

namespace lpt {

/// Keeps freed memory in the process for the next allocation of its size. By default glibc maps
/// every block above ~32 MB fresh from the kernel and unmaps it on free; TAESD3's and LPIPS's
/// activations (hundreds of MB each, allocated and freed per layer) then spend a third of an edit
/// frame in page faults and zeroing (docs/performance.md "Memory the networks reuse"). After this
/// call the main heap serves those blocks and keeps them: same results, a higher peak RSS. Call it
/// first in main(), before any thread starts. Blocks that worker threads allocate above 64 MB still
/// come from mmap (their arenas cannot grow that far).
void reuse_freed_memory();

}  // namespace lpt
