#include "core/process_memory.h"
#include <climits>
#include <malloc.h>

namespace lpt {

void reuse_freed_memory() {
    mallopt(M_MMAP_MAX, 0);              // no block from mmap: the heap grows instead
    mallopt(M_TRIM_THRESHOLD, INT_MAX);  // and is not given back to the kernel on free
}

}  // namespace lpt
