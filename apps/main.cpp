// latentpt command line: `latentpt <subcommand> --help` describes each subcommand. This is the
// only translation unit that includes CLI11 (with apps/cli_options.h, its option builders); each
// subcommand's options fill a plain struct.
#include "apps/cli_options.h"
#include "apps/commands.h"
#include "apps/torch_commands.h"
#include "core/process_memory.h"
#include "core/temp_file.h"
#include "integrators/path.h"
#include <CLI/CLI.hpp>
#include <tbb/global_control.h>
#include <filesystem>
#include <iostream>
#include <memory>

namespace lpt::app {
namespace {

/// Every subcommand's options, bound to the structs its run_* function receives.
struct Cli {
    int threads = 0;
    std::string sampler;
    RenderArgs r;
    std::vector<std::string> defines, fit_defines, cmp_defines;
    BenchArgs b;
    FitArgs f;
    std::string fit_tone = to_string(f.job.options.tone);  // the library's default, shown by --help
    RefineArgs rf;
    VaeArgs v;
    MetricsArgs m;
    CompareArgs cmp;
    CLI::App *render = nullptr, *bench = nullptr, *fit = nullptr, *refine = nullptr, *encode = nullptr,
             *decode = nullptr, *viz = nullptr, *metrics = nullptr, *compare = nullptr;

    void add_render(CLI::App& app) {
        render = app.add_subcommand("render", "path trace a scene (.json) to a float EXR plus an sRGB PNG preview");
        render->add_option("scene", r.scene, "scene file (.json or Mitsuba 3 .xml), or a fit folder with --edit")
            ->required()
            ->check(CLI::ExistingPath);
        auto* edit =
            render
                ->add_option(
                    "--edit", r.edit,
                    "edits.json: render the fitted latent scene edited (camera, shapes), frame by frame, and decode")
                ->check(CLI::ExistingFile);
        // The "with --X" options are refused without --X: alone they would change nothing.
        auto* reference =
            render
                ->add_flag("--reference", r.reference,
                           "with --edit: also path trace each frame in RGB, encode it, and write metrics.csv")
                ->needs(edit);
        render->add_option("--ref-spp", r.ref_spp, "with --reference: RGB samples per pixel")
            ->capture_default_str()
            ->check(positive())
            ->needs(reference);
        render
            ->add_option("--ref-seed", r.ref_seed,
                         "with --reference: the references' seed (each edited frame's is made from it and the frame's "
                         "index); another traces independent references (cached apart), e.g. to measure their noise")
            ->capture_default_str()
            ->check(seed_value())
            ->needs(reference);
        render
            ->add_option("--reference-cache", r.reference_cache,
                         "with --reference: keep path-traced frames here and reuse them (keyed by settings, frame)")
            ->needs(reference);
        render
            ->add_option("--frame-cache", r.frame_cache,
                         "with --edit: keep frames that show the training view (frame 0) here, for other sequences")
            ->needs(edit);
        render
            ->add_option("--frames", r.frames,
                         "with --edit: only frames A:B (inclusive, from 0), or every S-th of them with A:B:S; split "
                         "jobs give the same frame files as one, and write metrics_A-B.csv")
            ->needs(edit);
        render
            ->add_flag("--resume", r.resume,
                       "with --edit: skip frames an earlier, interrupted run finished (frame_NNNN.done)")
            ->needs(edit);
        render->add_option("-o,--out", r.out, "output EXR path; the PNG preview goes beside it")->capture_default_str();
        render->add_option("--spp", r.spp, "samples per pixel (default and 0: the scene's; with --edit 64)")
            ->check(non_negative());
        render->add_option("--res", r.res, "resolution WxH (default: the scene's camera)");
        render->add_option("--seed", r.seed, "random seed: same seed, same image, at any thread count")
            ->capture_default_str()
            ->check(seed_value());
        render
            ->add_option("--max-depth", r.max_depth, "longest path in segments, -1 = unbounded (default: the scene's)")
            ->check(CLI::Range(-1, 1 << 20))
            ->excludes(edit);  // the RGB renderer's options: an edit renders the fit's latents
        render->add_option("--strategy", r.strategy, "light estimator: mis (NEE + BSDF sampling), nee, bsdf")
            ->check(CLI::IsMember({"mis", "nee", "bsdf"}))
            ->capture_default_str()
            ->excludes(edit);
        auto* aov =
            render->add_flag("--aov", r.aov, "also write <out>.normal.exr, <out>.distance.exr, <out>.albedo.exr")
                ->excludes(edit);
        render->add_option("--aov-res", r.aov_res, "with --aov: AOV resolution WxH (default: the image's)")->needs(aov);
        render->add_option("--exposure", r.exposure, "PNG preview exposure in stops")
            ->capture_default_str()
            ->check(finite())
            ->excludes(edit);
        render->add_option(
            "-D,--define", defines,
            "override a scene value: a key path of a .json scene (-D integrator.max_depth=4), a "
            "$parameter of a Mitsuba .xml scene (-D spp=16); a key or name the scene does not have is an error");
        render->add_flag("-q,--quiet", r.quiet, "no progress line");
    }

    void add_bench(CLI::App& app) {
        bench = app.add_subcommand("bench",
                                   "rays/s of the path tracer next to raw Embree throughput on the same ray counts");
        bench->add_option("--scene", b.scene, "scene (default: scenes/cornell-box/scene.json)");
        bench->add_option("--spp", b.spp, "samples per pixel")->capture_default_str()->check(positive());
        bench->add_option("--res", b.res, "square resolution")->capture_default_str()->check(positive());
        bench
            ->add_option("--sphere-triangles", b.sphere_triangles,
                         "triangles of the sphere added for the heavy-scene run")
            ->capture_default_str()
            ->check(CLI::Range(1, 20000000));  // ~2 GB of mesh and BVH at the top
        bench->add_option("--json", b.out_json, "also write the results as JSON");
        auto* fit_flag =
            bench->add_flag("--fit", b.fit, "time fit iterations (forward and adjoint) at latent resolution instead");
        bench
            ->add_option("--fit-scene", b.fit_scene,
                         "scene for --fit (default: ../shared cbox_specular.xml, else the bundled Cornell box)")
            ->needs(fit_flag);
        bench->add_option("--fit-res", b.fit_res, "latent resolution for --fit")
            ->capture_default_str()
            ->check(positive())
            ->needs(fit_flag);
        bench->add_option("--fit-spp", b.fit_spp, "samples per pixel per iteration for --fit")
            ->capture_default_str()
            ->check(positive())
            ->needs(fit_flag);
        auto* equal_error =
            bench
                ->add_option("--equal-error", b.equal_error,
                             "fit folder: time for the latent renderer vs RGB path tracing (+ encode) to reach "
                             "the same latent error, and latent + decode vs RGB for the same image error")
                ->check(CLI::ExistingDirectory);
        bench->add_option("--max-spp", b.max_spp, "with --equal-error: highest RGB spp (latent side: a quarter)")
            ->capture_default_str()
            ->check(positive())
            ->needs(equal_error);
        auto* equal_noise = bench->add_flag(
            "--equal-noise", b.equal_noise,
            "spp and render seconds to one noise level, Sobol vs independent sampler, against a converged "
            "reference (default scene: ../shared cornell-box scene_v3.xml; docs/sampling.md)");
        bench
            ->add_option("--reference", b.reference,
                         "with --equal-noise: converged reference EXR (default: TungstenRender.exr beside the scene)")
            ->check(CLI::ExistingFile)
            ->needs(equal_noise);
        bench
            ->add_option("--target-spp", b.target_spp,
                         "with --equal-noise: target = the independent sampler's noise at this spp (4 ... 256)")
            ->capture_default_str()
            ->check(CLI::Range(4, 256))
            ->needs(equal_noise);
        auto* startup =
            bench->add_flag("--startup", b.startup,
                            "seconds from exec to exit of --help, a 1-spp 16x16 render and commands that open the "
                            "torch or image plugin (median and minimum of 10 runs each)");
        // one mode a run: --fit --startup ran the start-up alone
        const std::vector<CLI::Option*> modes = {fit_flag, equal_error, equal_noise, startup};
        for (CLI::Option* a : modes)
            for (CLI::Option* other : modes)
                if (a != other) a->excludes(other);
        bench->add_option("--seeds", b.seeds, "with --equal-noise: renders per ladder point")
            ->capture_default_str()
            ->check(positive())
            ->needs(equal_noise);
    }

    /// The latent model and its objective: what is fitted, and the penalty on it.
    void add_fit_model() {
        fit->add_option("--tone", fit_tone,
                        "signed tone curve: clip or reinhard; logit for the baseline (with --param classic --terms e)")
            ->check(CLI::IsMember({"clip", "reinhard", "logit"}))
            ->capture_default_str();
        fit->add_option(
               "--param", f.job.param,
               "parameterisation: code (public code), paper (paper text), classic (the baseline: non-negative), "
               "gain (code with a learnable gain on each emitter's Le)")
            ->check(CLI::IsMember({"code", "paper", "classic", "gain"}))
            ->capture_default_str();
        fit->add_option("--gate", f.job.gate, "Ic gate: shadowed (1 - V) or visible (V)")
            ->check(CLI::IsMember({"shadowed", "visible"}))
            ->capture_default_str();
        fit->add_option("--terms", f.job.terms, "latent terms to render: any of e, a, c (ablation)")
            ->capture_default_str();
        fit->add_option("--emission-decay", f.job.options.emission_decay,
                        "lambda of the L2 penalty lambda * sum Le^2 on every emitter's latent radiance; 0 = off "
                        "(docs/fitting.md (17))")
            ->capture_default_str()
            ->check(non_negative());
        fit->add_option(
               "--emitter-response-decay", f.job.options.emitter_response_decay,
               "mu of the L2 penalty mu * sum (La^2 + Lc^2) on the flat and occlusion responses of every emitting "
               "shape; 0 = off (docs/fitting.md (18))")
            ->capture_default_str()
            ->check(non_negative());
        fit->add_option("--exposures", f.job.options.exposures,
                        "light exposures the iterations cycle through, e.g. 1,0.5,1,2: an iteration with k fits the "
                        "render with every light's Le times k to the reference with every light k times as bright "
                        "(docs/fitting.md \"Exposure cycle\"); default: 1 only")
            ->delimiter(',')
            ->check(CLI::PositiveNumber);
    }

    /// The optimiser, the target's RGB reference, the VAE, stage 2: the rest of fit's options.
    void add_fit_optimisation() {
        fit->add_option("--iterations", f.job.options.iterations, "optimiser steps")
            ->capture_default_str()
            ->check(positive());
        fit->add_option("--spp", f.job.options.spp, "samples per pixel per iteration")
            ->capture_default_str()
            ->check(positive());
        fit->add_option("--final-spp", f.job.final_spp, "samples per pixel of the final render")
            ->capture_default_str()
            ->check(positive());
        fit->add_option("--seed", f.job.options.seed, "seed of the initial parameters and of every iteration's paths")
            ->capture_default_str()
            ->check(seed_value());
        fit->add_option("--lr", f.job.options.lr, "Adam learning rate (cosine annealing with warm restarts)")
            ->capture_default_str()
            ->check(positive());
        fit->add_option("--lr-min", f.job.options.lr_min, "minimum learning rate of the schedule")
            ->capture_default_str()
            ->check(non_negative());
        fit->add_option("--lr-period", f.job.options.lr_period, "iterations per restart period")
            ->capture_default_str()
            ->check(positive());
        fit->add_option("--patience", f.job.options.patience,
                        "early stopping: iterations without improvement of the smoothed loss; 0 = off")
            ->capture_default_str()
            ->check(non_negative());
        fit->add_option("--min-delta", f.job.options.min_delta, "early stopping: smallest improvement that counts")
            ->capture_default_str()
            ->check(non_negative());
        fit->add_option("--checkpoint-every", f.job.options.checkpoint_every,
                        "iterations between checkpoints; 0 = only at the end")
            ->capture_default_str()
            ->check(non_negative());
        fit->add_option("--reuse-paths", f.job.options.reuse_paths,
                        "K: trace and store one frame of paths every K iterations and replay them in between (no rays; "
                        "~56 bytes per path event, "
                        "~140 MB at 128x128 latents x 16 spp); 0: fresh paths every iteration, re-traced for the "
                        "gradient (least memory). "
                        "Equal final loss for K = 0, 1, 8, 32 on the CBox (docs/fitting.md)")
            ->capture_default_str()
            ->check(non_negative());
        auto* resume = fit->add_flag("--resume", f.job.resume,
                                     "continue from <out>/checkpoint; one made with other settings is an error");
        fit->add_flag("--restart-if-changed", f.job.restart_if_changed,
                      "with --resume: a checkpoint of other settings is removed and the fit starts again (workflows)")
            ->needs(resume);
        auto* encode = fit->add_flag("--encode", f.job.encode,
                                     "target = VAE encoding of the scene path traced in RGB (the paper's pipeline)");
        fit->add_option("--encode-res", f.job.encode_res, "image resolution WxH for --encode (latents are 1/8 of it)")
            ->capture_default_str()
            ->needs(encode);
        fit->add_option("--ref-spp", f.job.ref_spp, "samples per pixel of the RGB reference for --encode")
            ->capture_default_str()
            ->check(positive())
            ->needs(encode);
        fit->add_option("--reference-cache", f.job.reference_cache,
                        "with --encode: keep the encoded reference here and reuse it (fits of one scene share it)")
            ->needs(encode);
        fit->add_option("--ref-tone", f.job.ref_tone, "reference tone map: clip or reinhard (then gamma 1/2.2)")
            ->check(CLI::IsMember({"clip", "reinhard"}))
            ->capture_default_str();
        add_vae_options(fit, f.job.vae);
        fit->add_option("-D,--define", fit_defines, "override a scene value (as for render)");
        fit->add_flag("!--no-refiner", f.job.refiner, "stop after stage 1 (no refiner training)");
        fit->add_flag("-q,--quiet", f.quiet, "no progress line");

        add_refine_options(fit, f.job.refine, "refiner-");
    }

    void add_fit(CLI::App& app) {
        fit = app.add_subcommand("fit", "fit per-shape latent parameters to a target latent map (stage 1)");
        fit->add_option("scene", f.job.scene, "scene file (.json or Mitsuba 3 .xml)")
            ->required()
            ->check(CLI::ExistingFile);
        auto* target =
            fit->add_option(
                   "--target", f.job.target,
                   "16-channel float EXR at latent resolution (channels C00..C15; C0..C15 also read in order); "
                   "without it, a synthetic target rendered from random parameters")
                ->check(CLI::ExistingFile);
        fit->add_option("-o,--out", f.job.out, "output folder")->capture_default_str();
        auto* synthetic_res =
            fit->add_option("--synthetic-res", f.job.synthetic_res, "latent resolution WxH of the synthetic target")
                ->capture_default_str();
        auto* synthetic_seed =
            fit->add_option("--synthetic-seed", f.job.synthetic_seed, "seed of the synthetic target's parameters")
                ->capture_default_str()
                ->check(seed_value());
        add_fit_model();
        add_fit_optimisation();
        // Three targets, one taken: the others' options would be ignored without a word.
        CLI::Option* encode = fit->get_option("--encode");
        for (CLI::Option* synthetic : {synthetic_res, synthetic_seed}) synthetic->excludes(target)->excludes(encode);
        target->excludes(encode);
    }

    void add_refine(CLI::App& app) {
        refine = app.add_subcommand(
            "refine", "train the per-scene refiner on a fit folder (stage 2; fit runs it unless --no-refiner)");
        refine->add_option("fitdir", rf.job.fitdir, "folder written by latentpt fit")
            ->required()
            ->check(CLI::ExistingDirectory);
        add_refine_options(refine, rf.job, "");
        refine->add_option("--seed", rf.job.train.seed, "seed of the initial weights, crops and dropout")
            ->capture_default_str()
            ->check(seed_value());
        auto* resume = refine->add_flag(
            "--resume", rf.job.resume,
            "continue from <fitdir>/refiner_checkpoint.pt; one trained with other settings is an error");
        refine
            ->add_flag("--restart-if-changed", rf.job.restart_if_changed,
                       "with --resume: a checkpoint of other settings is removed and training starts again")
            ->needs(resume);
        refine->add_flag("--emitters", rf.job.emitters,
                         "train refiner_emitters.pt for where edits move emitters (--augment shift; docs/refiner.md)");
        refine->add_flag("-q,--quiet", rf.quiet, "no progress line");
    }

    void add_vae_commands(CLI::App& app) {
        encode =
            app.add_subcommand("encode",
                               "RGB image (PNG/JPEG display values, linear EXR, or an EXR marked as display values) "
                               "-> 16-channel latent EXR (TAESD3 or a TorchScript VAE)");
        decode = app.add_subcommand("decode", "latent EXR -> RGB image (PNG, or EXR unclamped)");
        viz = app.add_subcommand("viz", "latent EXR -> PNG of its channels (green positive, red negative)");
        for (auto* sc : {encode, decode, viz}) {
            sc->add_option("input", v.input, "input file")->required()->check(CLI::ExistingFile);
            sc->add_option("-o,--out", v.out, "output file")->required();
            sc->add_flag("-q,--quiet", v.quiet, "no messages");
        }
        for (auto* sc : {encode, decode}) add_vae_options(sc, v.vae);
    }

    void add_metrics(CLI::App& app) {
        metrics = app.add_subcommand(
            "metrics",
            "MSE, PSNR, SSIM and LPIPS between two images (PNG display values, linear EXR, or an "
            "EXR marked as display values), or MSE, PSNR and SSIM between two 16-channel latent EXRs");
        auto* a = metrics->add_option("a", m.a, "first image or latent EXR")->check(CLI::ExistingFile);
        auto* b =
            metrics->add_option("b", m.b, "second image or latent EXR, same size and kind")->check(CLI::ExistingFile);
        metrics
            ->add_option("--pairs", m.pairs,
                         "instead of a b: a file of pairs, one per line with the two paths separated by a tab "
                         "('-': stdin); prints one JSON object per pair, in order, loading LPIPS once")
            ->excludes(a, b);
        metrics->add_option("--lpips-dir", m.vae_dir, "LPIPS weights folder (default: ../shared/models/lpips)");
        metrics->add_flag("--json", m.json, "print one JSON object instead of text");
    }

    void add_compare(CLI::App& app) {
        compare = app.add_subcommand("compare",
                                     "bias of a render against an independent reference, beyond both renders' noise: "
                                     "channel mean ratios, block ratios with per-block noise, emitter-masked relMSE, "
                                     "pictures (docs/validation.md)");
        compare
            ->add_option("--test", cmp.test,
                         "render(s) under test: give >= 2 with independent seeds to estimate their noise")
            ->required()
            ->check(CLI::ExistingFile);
        compare
            ->add_option("--ref", cmp.ref, "reference render(s), same size or an integer multiple (box-averaged down)")
            ->required()
            ->check(CLI::ExistingFile);
        auto* scene = compare
                          ->add_option("--scene", cmp.scene,
                                       "scene of the renders: pixels that see an emitter directly are left out")
                          ->check(CLI::ExistingFile);
        compare->add_option("-D,--define", cmp_defines, "with --scene: scene override, as for render")->needs(scene);
        add_number(compare, "--block", cmp.block, "block side in pixels", positive());
        add_number(compare, "--sigma", cmp.sigma,
                   "flag blocks whose ratio is this many standard deviations of its noise from 1", positive());
        add_number(compare, "--mean-tolerance", cmp.mean_tolerance,
                   "verdict: channel means within this relative difference", non_negative());
        add_number(compare, "--ratio-range", cmp.ratio_range, "ratio map colour saturates at 1 +- this", positive());
        compare->add_option("--exposure", cmp.exposure, "exposure of the side-by-side previews in stops")
            ->capture_default_str()
            ->check(finite());
        compare->add_option("-o,--out-dir", cmp.out_dir,
                            "write comparison.txt/.json, ratio_map.png, side_by_side.png here");
        compare->add_flag("--strict", cmp.strict, "exit with code 3 when the verdict is FAIL");
    }

    /// --sampler for every subcommand that renders (none: each scene's own, or each fit's).
    void set_sampler(std::optional<SamplerKind> s) { r.sampler = b.sampler = f.job.sampler = rf.job.sampler = s; }

    /// Runs the chosen subcommand (after parsing).
    int run() {
        if (*render) {
            r.defines = parse_defines(defines);
            return r.edit.empty() ? run_render(r) : torch_commands().render_edit(r);
        }
        if (*bench)
            return !b.equal_error.empty() ? torch_commands().bench_equal_error(b)
                   : b.equal_noise        ? run_bench_equal_noise(b)
                   : b.startup            ? run_bench_startup(b)
                   : b.fit                ? run_bench_fit(b)
                                          : run_bench(b);
        if (*encode || *decode || *viz) refuse_output_over_input(v);
        if (*encode) return torch_commands().encode(v);
        if (*decode) return torch_commands().decode(v);
        if (*viz) return run_viz(v);
        if (*metrics) return torch_commands().metrics(m);
        if (*compare) {
            cmp.defines = parse_defines(cmp_defines);
            return run_compare(cmp);
        }
        if (*refine) return torch_commands().refine(rf);
        if (*fit) {
            f.job.defines = parse_defines(fit_defines);
            f.job.options.tone = parse_tone_curve(fit_tone);
            return torch_commands().fit(f);
        }
        return 0;
    }

    /// decode l.exr --out l.exr replaced the latent by its picture.
    static void refuse_output_over_input(const VaeArgs& v) {
        std::error_code ec;
        if (std::filesystem::equivalent(v.input, v.out, ec))
            throw std::invalid_argument(v.out + ": --out is the input file; name another");
    }

    /// -D key=value pairs.
    static std::map<std::string, std::string> parse_defines(const std::vector<std::string>& pairs) {
        std::map<std::string, std::string> out;
        for (const auto& d : pairs) {
            const auto eq = d.find('=');
            if (eq == std::string::npos) throw std::invalid_argument("-D expects key=value, got '" + d + "'");
            out[d.substr(0, eq)] = d.substr(eq + 1);
        }
        return out;
    }
};

}  // namespace
}  // namespace lpt::app

int main(int argc, char** argv) {
    lpt::reuse_freed_memory();               // before any thread: the networks' large blocks stay on the heap
    lpt::remove_temporaries_on_interrupt();  // Ctrl-C while an output is written leaves no temporary
    lpt::app::Cli cli;
    CLI::App app{"latentpt: a differentiable path tracer that renders into the latent space of an image autoencoder"};
    app.require_subcommand(1);
    app.fallthrough();  // `render ... --threads 1` as well as `--threads 1 render ...`
    // 10^7 threads took 1.3 GB before the first pixel; 4096 is past any machine's cores
    app.add_option("--threads", cli.threads, "worker threads (default: all cores)")->check(CLI::Range(1, 4096));
    app.add_option("--sampler", cli.sampler,
                   "random numbers of every render: sobol (Owen-scrambled, low discrepancy) or independent "
                   "(default: the scene's; a fit keeps the one it was given; docs/sampling.md)")
        ->check(CLI::IsMember({"sobol", "independent"}));
    cli.add_render(app);
    cli.add_bench(app);
    cli.add_fit(app);
    cli.add_refine(app);
    cli.add_vae_commands(app);
    cli.add_metrics(app);
    cli.add_compare(app);
    CLI11_PARSE(app, argc, argv);
    std::unique_ptr<tbb::global_control> limit;
    if (cli.threads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, cli.threads);
    try {
        cli.set_sampler(lpt::sampler_choice(cli.sampler, "--sampler"));  // empty: the scenes decide
        return cli.run();
    } catch (const std::exception& e) {
        std::cerr << "latentpt: error: " << e.what() << "\n";
        return 1;
    }
}
