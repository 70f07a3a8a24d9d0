// LPIPS v0.1 (Zhang et al. 2018) with the SqueezeNet-1.1 backbone, torch-free interface: images
// are interleaved RGB float buffers in [0, 1] (row-major from the top-left, like vae.h). The
// computation follows ../shared/models/lpips/FACTS.md exactly (docs/metrics.md): 2x-1, the
// scaling layer, 7 ReLU taps, channel unit-normalisation, squared difference, the linear heads,
// spatial mean, sum over layers. The differentiable libtorch core is in vae/lpips_torch.h.
#pragma once
#include <memory>
#include <string>
#include <vector>

namespace lpt {

struct LpipsNet;  ///< weights (libtorch tensors); defined in vae/lpips_torch.h

class Lpips {
public:
    static constexpr int kLayers = 7;
    /// Smallest width and height the backbone accepts (its pools need at least a 3x3 input).
    static constexpr int kMinSize = 17;

    /// `<dir>/lpips_squeeze_v0.1.safetensors` (dir: e.g. ../shared/models/lpips). Throws
    /// std::runtime_error naming the file on a missing file, a missing tensor or a bad shape.
    static std::unique_ptr<Lpips> load(const std::string& dir);
    ~Lpips();

    /// LPIPS distance between two width x height RGB images in [0, 1]: 0 for identical images,
    /// symmetric. Throws std::invalid_argument on wrong buffer sizes or images under kMinSize.
    double distance(const std::vector<float>& rgb_a, const std::vector<float>& rgb_b, int width, int height) const;
    /// The 7 per-layer terms whose sum is distance().
    std::vector<double> layer_distances(const std::vector<float>& rgb_a, const std::vector<float>& rgb_b, int width,
                                        int height) const;

    /// The network, for code that includes vae/lpips_torch.h (e.g. a training loss).
    const LpipsNet& net() const { return *m_net; }
    const std::string& path() const;

private:
    explicit Lpips(std::unique_ptr<LpipsNet> net);
    std::unique_ptr<LpipsNet> m_net;
};

}  // namespace lpt
