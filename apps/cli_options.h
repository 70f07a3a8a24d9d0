// Option builders shared by latentpt's subcommands: range checks that print their range plainly,
// the VAE source and the refiner's stage-2 options. Included by main.cpp alone, which stays the
// only translation unit that compiles CLI11 (apps/CMakeLists.txt).
#pragma once
#include "apps/commands.h"
#include <CLI/CLI.hpp>
#include <cmath>
#include <string>
#include <vector>

namespace lpt::app {

/// A number > 0 (strict) or >= 0; CLI11's own validators print their range as "0 to 1.8e308".
inline CLI::Validator bounded_below(bool strict) {
    return CLI::Validator(
        [strict](std::string& text) -> std::string {
            double v = 0;
            try {
                size_t used = 0;
                v = std::stod(text, &used);
                if (used != text.size()) return "expected a number, got '" + text + "'";
            } catch (const std::exception&) {
                return "expected a number, got '" + text + "'";
            }
            if (strict ? v > 0 : v >= 0) return "";
            return std::string("must be ") + (strict ? "> 0" : ">= 0") + ", got " + text;
        },
        strict ? "> 0" : ">= 0");
}
inline CLI::Validator positive() { return bounded_below(true); }
inline CLI::Validator non_negative() { return bounded_below(false); }

/// A finite number: --exposure nan wrote an all-black preview.
inline CLI::Validator finite() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            try {
                size_t used = 0;
                const double v = std::stod(text, &used);
                if (used == text.size() && std::isfinite(v)) return "";
            } catch (const std::exception&) {}
            return "expected a finite number, got '" + text + "'";
        },
        "finite");
}

/// A seed: digits only, within 64 bits (-1, 2^64 and 1e23 all became 2^64 - 1).
inline CLI::Validator seed_value() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            const bool digits = !text.empty() && text.find_first_not_of("0123456789") == std::string::npos;
            try {
                if (digits) return std::stoull(text), "";
            } catch (const std::exception&) {}
            return "expected an integer in [0, 2^64 - 1], got '" + text + "'";
        },
        "0 ... 2^64-1");
}

/// The autoencoder: native TAESD3 weights, or any VAE exported to TorchScript (tools/export_vae.py).
inline void add_vae_options(CLI::App* sc, VaeSource& vs) {
    auto* dir = sc->add_option("--vae-dir", vs.dir,
                               "TAESD3 weights folder holding taesd3_encoder.safetensors and "
                               "taesd3_decoder.safetensors (default: ../shared/models/taesd3); other VAEs (TAEF1, "
                               "SD3.5's) through --vae-encoder, --vae-decoder, --vae-config");
    // --vae-dir beside a TorchScript VAE was ignored
    for (auto* ts :
         {sc->add_option("--vae-encoder", vs.encoder,
                         "TorchScript encoder module (with --vae-decoder, --vae-config; e.g. the SD3.5 VAE)")
              ->check(CLI::ExistingFile),
          sc->add_option("--vae-decoder", vs.decoder, "TorchScript decoder module")->check(CLI::ExistingFile),
          sc->add_option("--vae-config", vs.config,
                         "vae.json of the TorchScript VAE: channels, downsample, scale, shift, image_range, latent")
              ->check(CLI::ExistingFile)})
        ts->excludes(dir);
}

/// A number option that shows its default and checks its range.
template <class T>
inline void add_number(CLI::App* sc, const std::string& name, T& value, const std::string& help,
                       const CLI::Validator& check) {
    sc->add_option(name, value, help)->capture_default_str()->check(check);
}

/// A choice of two words kept as a bool: true when given `yes`; --help lists them in the order given.
inline void add_choice(CLI::App* sc, const std::string& name, bool& flag, const std::string& yes, const std::string& no,
                       const std::string& help, bool yes_first = false) {
    sc->add_option_function<std::string>(
          name, [&flag, yes](const std::string& v) { flag = v == yes; }, help)
        ->check(CLI::IsMember(yes_first ? std::vector<std::string>{yes, no} : std::vector<std::string>{no, yes}))
        ->default_str(flag ? yes : no);
}

/// Stage-2 options: `--refiner-<name>` on fit, `--<name>` on refine.
inline void add_refine_options(CLI::App* sc, pipeline::RefineJob& ra, const std::string& pre) {
    add_number(sc, "--" + pre + "iterations", ra.train.iterations, "refiner training steps", positive());
    add_number(sc, "--" + pre + "expansion", ra.net.expansion, "refiner width = expansion x 16 channels", positive());
    add_number(sc, "--" + pre + "crop", ra.train.crop, "latent crop side per refiner step (0 = the whole view)",
               non_negative());
    add_number(sc, "--" + pre + "lpips-crop", ra.train.lpips_crop,
               "latent side of the sub-crop decoded for LPIPS (0 = no LPIPS)", non_negative());
    add_number(sc, "--" + pre + "lr", ra.train.lr, "refiner Adam learning rate", positive());
    add_choice(sc, "--" + pre + "lr-decay", ra.train.cosine_decay, "cosine", "none",
               "refiner learning rate over the steps: none (constant) or cosine (one half cosine down to 0)");
    add_number(sc, "--" + pre + "patience", ra.train.patience, "refiner early stopping on the smoothed loss; 0 = off",
               non_negative());
    add_number(sc, "--" + pre + "w-mse", ra.train.w_mse, "weight of latent MSE", non_negative());
    add_number(sc, "--" + pre + "w-ssim", ra.train.w_ssim, "weight of latent 1 - SSIM", non_negative());
    add_number(sc, "--" + pre + "w-lpips", ra.train.w_lpips, "weight of LPIPS on decoded crops", non_negative());
    add_number(sc, "--" + pre + "squash", ra.net.squash, "inputs enter as tanh(x / squash)", positive());
    add_choice(sc, "--" + pre + "norm", ra.net.instance_norm, "instance", "none",
               "normalisation after each convolution: instance (ours) or none (the paper's network)", true);
    sc->add_option_function<std::string>(
          "--" + pre + "arch",
          [&ra, pre](const std::string& v) { ra.net.arch = parse_refiner_arch(v, "--" + pre + "arch"); },
          "network body: conv (three convolutions at full resolution, the paper's blocks) or unet (a two-level "
          "U-Net with skip connections, a wider view at a fifth of the cost per pixel)")
        ->check(CLI::IsMember({"conv", "unet"}))
        ->default_str(to_string(ra.net.arch));
    add_choice(sc, "--" + pre + "inputs", ra.net.terms, "terms", "latent",
               "what the refiner reads besides the AOVs: latent (the toned render) or terms (also its transport terms "
               "Ie, Ia, Ic before the tone curve; edits then render them too)");
    add_choice(sc, "--" + pre + "inference", ra.windowed_inference, "windows", "whole",
               "how the trained refiner is applied: windows (the training crop's size, overlapping, averaged; "
               "InstanceNorm sees what it saw in training) or whole (the view at once)",
               true);
    add_number(sc, "--" + pre + "window-stride", ra.window_stride, "latent pixels between windows", positive());
    add_number(sc, "--" + pre + "dropout", ra.net.dropout, "dropout after each block", CLI::Range(0.0, 0.99));
    add_number(sc, "--" + pre + "emitter-cells", ra.net.emitter_cells,
               "also read each latent pixel's emitter coverage in N x N sub-cells (0 = no)", CLI::Range(0, 8));
    add_number(sc, "--" + pre + "input-noise", ra.train.input_noise,
               "std of Gaussian noise added, fresh each step, to the latent the refiner's body reads in training "
               "(not to the latent its output is added to); 0 = none",
               non_negative());
    add_number(sc, "--" + pre + "noise-views", ra.noise_views,
               "renders of the training view (independent samples) the refiner trains on; 1 = the fit's alone",
               positive());
    sc->add_option_function<std::string>(
          "--" + pre + "augment", [&ra](const std::string& v) { ra.augment = pipeline::parse_refiner_augment(v); },
          "extra training views made from the training view alone: none, mirror (its mirror image), dihedral (also "
          "the camera rolled by quarter turns) or shift (the film moved by half a latent pixel); each against its "
          "reference moved the same way and encoded")
        ->check(CLI::IsMember({"none", "mirror", "dihedral", "shift"}))
        ->default_str(pipeline::to_string(ra.augment));
    add_choice(sc, "--" + pre + "latent-target", ra.compensated_target, "compensated", "encoded",
               "the refiner's target: encoded (target.exr, the paper's) or compensated (the reference encoded with "
               "the decoder's bias per latent cell added back: decodes closer to it)");
    add_number(sc, "--" + pre + "latent-target-block", ra.latent_target_block,
               "with the compensated target: pixels of the square blocks the decoder's bias is averaged over "
               "(0 = one latent cell; coarser keeps only a broader colour cast)",
               non_negative());
    add_number(sc, "--" + pre + "checkpoint-every", ra.train.checkpoint_every, "refiner steps between checkpoints",
               non_negative());
    sc->add_option("--lpips-dir", ra.lpips_dir, "LPIPS weights folder (default: ../shared/models/lpips)");
}

}  // namespace lpt::app
