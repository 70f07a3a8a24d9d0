// TAESD3 (Ollin Boer Bohan's tiny autoencoder for the SD3 latent space) in libtorch, built from
// ../shared/models/taesd3/ARCHITECTURE.md: 3x3 convolutions (padding 1), ReLU, residual blocks
// y = ReLU(conv(ReLU(conv(ReLU(conv(x))))) + x), stride-2 downsampling convs without bias,
// nearest 2x upsampling, and a 3·tanh(x/3) soft clamp at the decoder input. Weights are BF16
// safetensors converted to float32 by our reader (vae/safetensors.h).
#include "vae/safetensors.h"
#include "vae/torch_threads.h"
#include "vae/vae_torch.h"
#include <torch/torch.h>
#include <algorithm>
#include <stdexcept>

namespace lpt {

namespace {

struct Weights {
    std::map<std::string, torch::Tensor> t;
    const torch::Tensor& operator[](const std::string& k) const { return t.at(k); }
};

Weights load_weights(const std::string& path,
                     const std::vector<std::pair<std::string, std::vector<int64_t>>>& expected) {
    SafeTensors st = SafeTensors::load(path);
    Weights w;
    for (const auto& [key, shape] : expected) {
        if (!st.has(key)) throw std::runtime_error(path + ": missing tensor '" + key + "'");
        std::vector<float> v = st.to_float(key, shape);
        w.t[key] = torch::from_blob(v.data(), shape, torch::kFloat32).clone();
    }
    if (st.tensors().size() != expected.size())
        throw std::runtime_error(path + ": " + std::to_string(st.tensors().size()) + " tensors, expected " +
                                 std::to_string(expected.size()) + " (not a TAESD file?)");
    return w;
}

constexpr int64_t kC = 64;  // every internal width

void expect_conv(std::vector<std::pair<std::string, std::vector<int64_t>>>& e, const std::string& name, int64_t out,
                 int64_t in, bool bias) {
    e.push_back({name + ".weight", {out, in, 3, 3}});
    if (bias) e.push_back({name + ".bias", {out}});
}
void expect_block(std::vector<std::pair<std::string, std::vector<int64_t>>>& e, int i) {
    for (int k : {0, 2, 4}) expect_conv(e, std::to_string(i) + ".conv." + std::to_string(k), kC, kC, true);
}

torch::Tensor conv(const Weights& w, const std::string& name, const torch::Tensor& x, int64_t stride = 1) {
    auto it = w.t.find(name + ".bias");
    return torch::conv2d(x, w[name + ".weight"], it == w.t.end() ? torch::Tensor() : it->second, stride, 1);
}

torch::Tensor block(const Weights& w, int i, const torch::Tensor& x) {
    const std::string p = std::to_string(i) + ".conv.";
    torch::Tensor y = torch::relu(conv(w, p + "0", x));
    y = torch::relu(conv(w, p + "2", y));
    return torch::relu(conv(w, p + "4", y) + x);
}

class Taesd final : public NchwVae {
public:
    Taesd(const std::string& dir, const std::string& prefix, const LatentConvention& conv) : m_conv(conv) {
        std::vector<std::pair<std::string, std::vector<int64_t>>> enc, dec;
        expect_conv(enc, "0", kC, 3, true);
        expect_block(enc, 1);
        for (int i : {2, 6, 10}) {
            expect_conv(enc, std::to_string(i), kC, kC, false);
            for (int b = i + 1; b <= i + 3; ++b) expect_block(enc, b);
        }
        expect_conv(enc, "14", conv.channels, kC, true);
        expect_conv(dec, "1", kC, conv.channels, true);
        for (int b : {3, 4, 5, 8, 9, 10, 13, 14, 15, 18}) expect_block(dec, b);
        for (int i : {7, 12, 17}) expect_conv(dec, std::to_string(i), kC, kC, false);
        expect_conv(dec, "19", 3, kC, true);
        m_enc = load_weights(dir + "/" + prefix + "_encoder.safetensors", enc);
        m_dec = load_weights(dir + "/" + prefix + "_decoder.safetensors", dec);
        // Intra-op threads default to 1 here; convolutions dominate, so use the worker threads.
        use_worker_threads_in_torch();
    }

    torch::Tensor encode_nchw(const torch::Tensor& rgb) const override {
        torch::Tensor x = conv(m_enc, "0", rgb);
        x = block(m_enc, 1, x);
        for (int i : {2, 6, 10}) {
            x = conv(m_enc, std::to_string(i), x, 2);
            for (int b = i + 1; b <= i + 3; ++b) x = block(m_enc, b, x);
        }
        return conv(m_enc, "14", x);
    }

    torch::Tensor decode_nchw(const torch::Tensor& latent) const override {
        torch::Tensor x = torch::tanh(latent / 3.0) * 3.0;
        x = torch::relu(conv(m_dec, "1", x));
        for (int b : {3, 4, 5}) x = block(m_dec, b, x);
        for (int i : {7, 12, 17}) {
            x = torch::upsample_nearest2d(x, {}, std::vector<double>{2.0, 2.0});
            x = conv(m_dec, std::to_string(i), x);
            if (i == 17) x = block(m_dec, 18, x);
            else
                for (int b = i + 1; b <= i + 3; ++b) x = block(m_dec, b, x);
        }
        return conv(m_dec, "19", x);
    }

    const LatentConvention& convention() const override { return m_conv; }

private:
    LatentConvention m_conv;
    Weights m_enc, m_dec;
};

}  // namespace

std::unique_ptr<Vae> load_taesd(const std::string& dir, const std::string& prefix, const LatentConvention& convention) {
    return std::make_unique<Taesd>(dir, prefix, convention);
}

}  // namespace lpt
