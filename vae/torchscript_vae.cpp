// Any VAE exported as two TorchScript modules (tools/export_vae.py for the SD3.5 VAE,
// tools/export_taesd3.py for TAESD3) plus vae.json describing its conventions:
//   {"channels": 16, "downsample": 8, "scale": 1.5305, "shift": 0.0609,
//    "image_range": [-1, 1], "latent": "raw" | "model"}
// Images cross this interface in [0, 1] and latents in the diffusion model's space; the affine
// maps to and from the modules' own ranges happen here, so the modules stay plain exports.
#include "vae/vae_config.h"
#include "vae/torch_threads.h"
#include "vae/vae_torch.h"
#include <torch/script.h>
#include <algorithm>
#include <filesystem>
#include <stdexcept>

namespace lpt {

namespace {

torch::jit::Module load_module(const std::string& path, const char* role) {
    if (!std::filesystem::exists(path)) throw std::runtime_error(path + ": " + role + " module not found");
    try {
        torch::jit::Module m = torch::jit::load(path);
        m.eval();
        return m;
    } catch (const c10::Error& e) {
        throw std::runtime_error(path + ": cannot load TorchScript " + role + ": " + e.what_without_backtrace());
    }
}

std::string shape_of(const torch::Tensor& t) {
    std::string s = "[";
    for (int64_t i = 0; i < t.dim(); ++i) s += (i ? ", " : "") + std::to_string(t.size(i));
    return s + "]";
}

class TorchScriptVae final : public NchwVae {
public:
    TorchScriptVae(const std::string& encoder, const std::string& decoder, const std::string& config) {
        const VaeConfig c = read_vae_config(config);
        m_conv = c.convention;
        m_lo = c.image_lo;
        m_hi = c.image_hi;
        m_raw = c.raw_latent;
        m_encoder_path = encoder;
        m_decoder_path = decoder;
        m_enc = load_module(encoder, "encoder");
        m_dec = load_module(decoder, "decoder");
        use_worker_threads_in_torch();
    }

    torch::Tensor encode_nchw(const torch::Tensor& rgb) const override {
        torch::Tensor z = run(m_enc, m_encoder_path, rgb * (m_hi - m_lo) + m_lo);
        const int f = m_conv.downsample;
        if (z.dim() != 4 || z.size(1) != m_conv.channels || z.size(2) * f != rgb.size(2) ||
            z.size(3) * f != rgb.size(3))
            throw std::runtime_error(m_encoder_path + ": encoder returned " + shape_of(z) + " for an image " +
                                     shape_of(rgb) + "; the config says " + std::to_string(m_conv.channels) +
                                     " channels at 1/" + std::to_string(f));
        return m_raw ? (z - m_conv.shift) * m_conv.scale : z;
    }

    torch::Tensor decode_nchw(const torch::Tensor& latent) const override {
        torch::Tensor x = run(m_dec, m_decoder_path, m_raw ? latent / m_conv.scale + m_conv.shift : latent);
        const int f = m_conv.downsample;
        if (x.dim() != 4 || x.size(1) != 3 || x.size(2) != latent.size(2) * f || x.size(3) != latent.size(3) * f)
            throw std::runtime_error(m_decoder_path + ": decoder returned " + shape_of(x) + " for a latent " +
                                     shape_of(latent));
        return (x - m_lo) / (m_hi - m_lo);
    }

    const LatentConvention& convention() const override { return m_conv; }

private:
    static torch::Tensor run(torch::jit::Module& m, const std::string& path, const torch::Tensor& x) {
        try {
            c10::IValue out = m.forward({x});
            if (!out.isTensor()) throw std::runtime_error(path + ": forward() must return one tensor");
            return out.toTensor().to(torch::kFloat32);
        } catch (const c10::Error& e) {
            throw std::runtime_error(path + ": forward failed: " + e.what_without_backtrace());
        }
    }
    LatentConvention m_conv;
    float m_lo = 0.f, m_hi = 1.f;
    bool m_raw = false;
    std::string m_encoder_path, m_decoder_path;
    // forward() is not const in libtorch; running a module does not change what it computes.
    mutable torch::jit::Module m_enc, m_dec;
};

}  // namespace

std::unique_ptr<Vae> load_torchscript_vae(const std::string& encoder, const std::string& decoder,
                                          const std::string& config) {
    return std::make_unique<TorchScriptVae>(encoder, decoder, config);
}

}  // namespace lpt
