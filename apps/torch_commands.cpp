#include "apps/torch_commands.h"
#include "core/plugin_loader.h"

namespace lpt::app {

const TorchCommands& torch_commands() {
    static const TorchCommands* table =
        reinterpret_cast<TorchCommandsFn>(plugin_symbol(kTorchPluginFile, kTorchPluginSymbol))();
    return *table;
}

}  // namespace lpt::app
