// Path records: the part of a traced latent path that does not depend on the learned spectral
// coefficients (event kinds, shapes, local directions, pdfs, MIS weights, Russian-roulette
// probabilities, shadow-ray outcomes), 56 bytes per event. With the current coefficients, a
// record's forward sweep gives the path's Ĩe, Ĩa, Ĩc contributions and its backward sweep the
// path-replay gradient (docs/path-replay.md (1)–(6)).
// The retracing adjoint (latent_path_adjoint.cpp) sweeps each wavefront's records as soon as the
// tracer completes them and then forgets them: memory stays one wavefront. `fit --reuse-paths K`
// keeps a whole frame's records and replays them for K iterations without tracing a ray.
#pragma once
#include "latent/latent_model.h"
#include "integrators/path.h"
#include <cstdint>
#include <memory>
#include <vector>

namespace lpt {

struct PathEvent {
    enum Type : uint8_t { Emission, Ambient, Light, Bounce };
    static constexpr uint8_t kNee = 1, kFirst = 2, kVisible = 4;
    uint8_t type = Emission;
    uint8_t flags = 0;   ///< Light: kNee (NEE sample), kFirst (Ĩc gate here), kVisible (shadow ray unblocked)
    uint8_t lobe = 0;    ///< Bounce: the sampled BSDFFlags bit
    uint8_t depth = 0;   ///< Bounce: path depth, to regenerate a delta sample's random numbers
    int32_t shape = -1;  ///< Ambient -1: the background
    int32_t emitter = -1;
    /// One float per event, named by what it means for the event's type (each reads its own).
    union {
        float mis = 0.f;   ///< Emission: MIS weight (× the envmap's relative luminance where one applies)
        float w_over_pdf;  ///< Light: w_mis / p_light (× the same factor)
        float survival;    ///< Bounce: Russian-roulette survival probability q (1 before rr_depth)
    };
    float pdf = 0.f, eta = 1.f;  ///< Bounce: the BSDF sample's pdf and relative IOR
    Vec2f uv = Vec2f::Zero();
    Vec3f wi = Vec3f::Zero(), wo = Vec3f::Zero();  ///< local shading frame
};

static_assert(sizeof(PathEvent) == 56, "docs/path-replay.md and the memory estimates quote 56 bytes per event");

/// One wavefront: path k is events[begin[k] .. begin[k + 1]), seen by pixel[k] as its sample[k].
struct PathBlock {
    std::vector<uint32_t> pixel, sample, begin;
    std::vector<PathEvent> events;
    size_t paths() const { return pixel.size(); }
};

/// Every path of one primal render (a fit iteration's seed, spp and resolution).
struct PathRecords {
    SamplerId sampler;  ///< the primal's seed and sampler kind
    int width = 0, height = 0, spp = 0;
    std::vector<std::vector<PathBlock>> tiles;  ///< per image tile, wavefronts in trace order
    size_t events() const;
    size_t bytes() const;
};

/// Renders Ĩe, Ĩa, Ĩc with `options` and keeps every path's record. `image` (optional) receives
/// the primal Ĩ of the same pass (N floats per pixel).
PathRecords record_latent_paths(const LatentModel& model, const RenderOptions& options,
                                std::vector<float>* image = nullptr, RenderStats* stats = nullptr);

/// Ĩ of the recorded paths with the model's current values; equals the primal of the same
/// options (up to float rounding) while the coefficients are those of the recording.
std::vector<float> replay_forward(const LatentModel& model, const PathRecords& records);

/// Adds ∂loss/∂value into the model's ParamStore grad_values() for d_image = ∂loss/∂Ĩ, with
/// the recorded directions, pdfs, MIS weights and q held fixed. Deterministic (tile order).
void replay_backward(LatentModel& model, const PathRecords& records, const std::vector<float>& d_image);

namespace detail {

/// Records wavefronts as the tracer emits events; complete(tile, block) receives each finished
/// wavefront (default: appended to records()). Hooks may run on several threads, one tile each.
class PathRecorder : public PathObserver<kLatentChannels> {
public:
    explicit PathRecorder(int n_tiles);
    ~PathRecorder() override;
    void begin(int tile, size_t n) override;
    void emission(uint32_t slot, int emitter, float mis) override;
    void ambient(uint32_t slot, int shape) override;
    void light_sample(uint32_t slot, int shadow_id, int shape, int emitter, float w_over_pdf, const BSDFContext& ctx,
                      const Vec3f& wi, const Vec3f& wo, bool nee, bool first) override;
    void shadow(int shadow_id, bool blocked) override;
    void bounce(uint32_t slot, int shape, const BSDFContext& ctx, const Vec3f& wi,
                const BSDFSample<kLatentChannels>& bs, float q, int depth) override;
    void end(const uint32_t* pixel, const uint32_t* sample, size_t n) override;
    std::vector<std::vector<PathBlock>>& records() { return m_records; }

protected:
    virtual void complete(int tile, PathBlock& block) { m_records[tile].push_back(std::move(block)); }

private:
    struct Scratch;            ///< one thread's wavefront under construction
    struct Threads;            ///< every thread's Scratch
    Scratch& scratch() const;  ///< this thread's, for this recorder
    std::unique_ptr<Threads> m_threads;
    std::vector<std::vector<PathBlock>> m_records;
};

/// Gradient sweep of one block: adds into `grad` (the ParamStore's value layout).
void backward_block(const LatentModel& model, SamplerId sampler, const PathBlock& block, const float* d_image,
                    float inv_spp, float* grad);

}  // namespace detail

}  // namespace lpt
