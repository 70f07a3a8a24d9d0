// reuse_freed_memory: a block far above glibc's mmap threshold comes from the heap, and the heap
// keeps it after free. Without the call every check fails (glibc maps such a block and unmaps it).
// The checks count the heap's bytes in use, not its growth: earlier tests in the same process
// may have left free memory at the heap's top, which the block then partly reuses.
#include "core/process_memory.h"
#include <gtest/gtest.h>
#include <cstdlib>
#include <cstring>
#include <malloc.h>

#if defined(__SANITIZE_ADDRESS__)
#define LPT_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LPT_UNDER_ASAN 1
#endif
#endif

namespace {

char* volatile g_block = nullptr;  // volatile: the allocation cannot be optimised away

TEST(ProcessMemory, LargeBlocksComeFromTheHeapAndStay) {
#ifdef LPT_UNDER_ASAN
    GTEST_SKIP() << "AddressSanitizer's allocator ignores mallopt";
#endif
    lpt::reuse_freed_memory();
    constexpr size_t kBytes = size_t(256) << 20;  // 8x glibc's largest dynamic mmap threshold
    const struct mallinfo2 before = mallinfo2();
    g_block = static_cast<char*>(std::malloc(kBytes));
    ASSERT_NE(g_block, nullptr);
    std::memset(g_block, 1, kBytes);
    const struct mallinfo2 held = mallinfo2();
    EXPECT_LT(held.hblkhd, before.hblkhd + kBytes) << "the block was mapped with mmap";
    EXPECT_GE(held.uordblks, before.uordblks + kBytes) << "the block is not in use in the heap";
    std::free(g_block);
    g_block = nullptr;
    const struct mallinfo2 after = mallinfo2();
    EXPECT_GE(after.arena, before.uordblks + kBytes) << "the freed block went back to the kernel";
    EXPECT_GE(after.fordblks, kBytes) << "the freed block is not free in the heap";
}

}  // namespace
