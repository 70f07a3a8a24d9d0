#include "vae/torch_threads.h"
#include <tbb/global_control.h>
#include <torch/torch.h>
#include <algorithm>

namespace lpt {

int worker_threads() {
    return std::max(1, int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism)));
}

void use_worker_threads_in_torch() { at::set_num_threads(worker_threads()); }

}  // namespace lpt
