// libtorch's intra-op thread count. Our networks run in threads that libtorch starts at one
// intra-op thread, so each loader sets it; it follows the process's worker count (`latentpt
// --threads`, a tbb::global_control, as the tracer does) instead of every core of the machine.
// Torch-free header: the callers in vae/ and refiner/ include it.
#pragma once

namespace lpt {

/// The process's worker thread count: the tbb::global_control limit when one is set
/// (`latentpt --threads`), else TBB's default (the cores this process may run on).
int worker_threads();
/// Sets libtorch's intra-op threads to worker_threads().
void use_worker_threads_in_torch();

}  // namespace lpt
