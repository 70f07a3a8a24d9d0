// libtorch's intra-op threads follow the process's worker count (vae/torch_threads.h): before,
// every network set them to all cores whatever `latentpt --threads` said.
#include "vae/torch_threads.h"
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <torch/torch.h>
#include <algorithm>

using namespace lpt;

TEST(TorchThreads, FollowTheWorkerLimit) {
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        EXPECT_EQ(worker_threads(), 1);
        use_worker_threads_in_torch();
        EXPECT_EQ(at::get_num_threads(), 1);
    }
    const int unlimited = int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
    EXPECT_EQ(worker_threads(), std::max(1, unlimited));
    use_worker_threads_in_torch();
    EXPECT_EQ(at::get_num_threads(), worker_threads());
}
