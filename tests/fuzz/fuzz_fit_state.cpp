// What a fit leaves on disk and a later command reads back: fit.json + params.json (the fit
// folder, pipeline/fit_folder.cpp) and a checkpoint (state.json, params-<tag>.json and the Adam
// blob, autodiff/fit.cpp). The input is up to five parts separated by "\n=====\n":
// fit.json, params.json, state.json, params-t.json, adam-t.bin.
#include "autodiff/fit.h"
#include "core/scene_loader.h"
#include "fuzz_util.h"
#include "latent/latent_model.h"
#include "pipeline/fit_folder.h"
#include <filesystem>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    namespace fz = lpt::fuzz;
    static const lpt::Scene scene = [] {
        std::filesystem::copy_file(fz::bundled_scene(), fz::work_dir() + "/scene.json",
                                   std::filesystem::copy_options::overwrite_existing);
        return lpt::load_scene(fz::bundled_scene());
    }();
    const std::vector<std::string> parts = fz::split_parts(data, size, 5);
    fz::write_input("fit.json", fz::with_dir(parts[0]));
    fz::write_input("params.json", parts[1]);
    LPT_FUZZ_EXPECT_CLEAN("", lpt::pipeline::load_fit_folder(fz::work_dir()));

    const std::string checkpoint = fz::work_dir() + "/checkpoint";
    std::filesystem::create_directories(checkpoint);
    fz::write_input("checkpoint/state.json", parts[2]);
    fz::write_input("checkpoint/params-t.json", parts[3]);
    fz::write_input("checkpoint/adam-t.bin", parts[4]);
    lpt::LatentModel model(scene, lpt::Parameterisation::Code, 0);
    LPT_FUZZ_EXPECT_CLEAN("", lpt::load_checkpoint(checkpoint, model));
    return 0;
}
