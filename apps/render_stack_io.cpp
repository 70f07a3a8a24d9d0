// EXR stacks and emitter masks for render comparisons (apps/render_stack_io.h).
#include "apps/render_stack_io.h"
#include "core/image_io.h"
#include <tbb/parallel_for.h>
#include <stdexcept>

namespace lpt::app {

std::vector<float> load_rgb(const std::string& path, int factor, int& width, int& height) {
    Image img = read_image(path);
    if (img.channels != 3 && img.channels != 4)  // a 16-channel latent compared its first three
        throw std::runtime_error(path + ": expected an RGB image, found " + std::to_string(img.channels) +
                                 " channel(s)");
    require_finite_pixels(img, path);
    if (img.display)
        throw std::runtime_error(path +
                                 ": holds display values (a reference after fit's tone, or a decoded "
                                 "latent); comparing renders needs linear radiance");
    if (img.width % factor || img.height % factor)
        throw std::runtime_error(path + ": " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                                 " is not a multiple of the downsampling factor " + std::to_string(factor));
    width = img.width / factor;
    height = img.height / factor;
    std::vector<float> out(size_t(width) * size_t(height) * 3, 0.f);
    const float inv = 1.f / float(factor * factor);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (int c = 0; c < 3; ++c)
                out[(size_t(y / factor) * size_t(width) + size_t(x / factor)) * 3 + c] +=
                    img.data[(size_t(y) * size_t(img.width) + size_t(x)) * size_t(img.channels) + size_t(c)] * inv;
    return out;
}

RenderStack load_stack(const std::vector<std::string>& paths, int target_width) {
    RenderStack s;
    for (const auto& p : paths) {
        Image probe_dims = read_image(p);  // the factor follows from the first test image's width
        int factor = target_width > 0 ? probe_dims.width / target_width : 1;
        if (factor < 1 || (target_width > 0 && probe_dims.width != factor * target_width))
            throw std::runtime_error(p + ": width " + std::to_string(probe_dims.width) +
                                     " is not a multiple of the test width " + std::to_string(target_width));
        int w = 0, h = 0;
        s.renders.push_back(load_rgb(p, factor, w, h));
        if (s.renders.size() > 1 && (w != s.width || h != s.height))
            throw std::runtime_error(p + ": size differs from " + paths.front());
        s.width = w;
        s.height = h;
    }
    return s;
}

std::vector<uint8_t> emitter_mask(const Scene& scene, int width, int height) {
    Camera cam = scene.camera.with_resolution(width, height);
    const float reach = std::max(0.5f, cam.filter.radius);
    std::vector<uint8_t> mask(size_t(width) * size_t(height), 0);
    const bool env = scene.environment >= 0;
    tbb::parallel_for(0, height, [&](int y) {
        for (int x = 0; x < width; ++x) {
            for (int k = 0; k < 16 && !mask[size_t(y) * size_t(width) + size_t(x)]; ++k) {
                const float ox = -reach + 2.f * reach * (float(k % 4) + 0.5f) / 4.f;
                const float oy = -reach + 2.f * reach * (float(k / 4) + 0.5f) / 4.f;
                SurfaceInteraction si =
                    scene.intersect(cam.generate_ray(Vec2f(float(x) + 0.5f + ox, float(y) + 0.5f + oy)));
                const bool hit_emitter = si.valid() ? scene.shapes[size_t(si.shape)].emitter >= 0 : env;
                if (hit_emitter) mask[size_t(y) * size_t(width) + size_t(x)] = 1;
            }
        }
    });
    return mask;
}

}  // namespace lpt::app
