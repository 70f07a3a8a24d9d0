// The subcommands that need libtorch (a VAE, LPIPS or the refiner) are built into the plugin
// liblatentpt_torch.so (apps/torch_plugin.cpp) and reached through this table, opened on their
// first use: `latentpt --help`, a render or a comparison never load libtorch (~0.5 s of start-up).
// The plugin resolves everything else (core .. pipeline_io, the terminal's progress) from the
// executable, which exports those symbols, so both share one copy of every global.
#pragma once
#include "apps/commands.h"

namespace lpt::app {

struct TorchCommands {
    int (*fit)(const FitArgs&);
    int (*refine)(const RefineArgs&);
    int (*render_edit)(const RenderArgs&);
    int (*encode)(const VaeArgs&);
    int (*decode)(const VaeArgs&);
    int (*metrics)(const MetricsArgs&);
    int (*bench_equal_error)(const BenchArgs&);
};

/// Loads the plugin on the first call; throws std::runtime_error saying where it looked.
const TorchCommands& torch_commands();

inline constexpr const char* kTorchPluginFile = "liblatentpt_torch.so";
inline constexpr const char* kTorchPluginSymbol = "latentpt_torch_commands";
using TorchCommandsFn = const TorchCommands* (*)();

}  // namespace lpt::app
