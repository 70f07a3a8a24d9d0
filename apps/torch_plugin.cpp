// liblatentpt_torch.so's entry point: the table of the subcommands built into it.
#include "apps/torch_commands.h"
#include "core/plugin_interface.h"
#include "latentpt_interface_fingerprint.h"

LPT_DEFINE_PLUGIN_INTERFACE(LPT_INTERFACE_FINGERPRINT)

extern "C" const lpt::app::TorchCommands* latentpt_torch_commands() {
    using namespace lpt::app;
    static const TorchCommands table{&run_fit,    &run_refine,  &run_render_edit,      &run_encode,
                                     &run_decode, &run_metrics, &run_bench_equal_error};
    return &table;
}
