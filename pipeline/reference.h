// The paper's target: the scene path traced in RGB, display-mapped, encoded by the VAE.
#pragma once
#include "pipeline/progress.h"
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace lpt {
class Scene;
class Vae;
struct Image;
}  // namespace lpt

namespace lpt::pipeline {

/// The paper's display mapping for references: clip to [0, 1] (or |x|/(1+|x|) for "reinhard"),
/// then x^(1/2.2).
float display_value(float v, const std::string& tone);

/// Whether `path` names a float image format by its extension, any case (.exr, .hdr).
bool float_image_path(const std::string& path);
/// How an RGB file's values are read as display values (metrics, encode): PNG/JPEG as read; an
/// EXR/HDR marked as display values (Image::display: references, decoded latents) clipped to
/// [0, 1], as the edit scores clip decoded RGB; other EXR/HDR taken for linear radiance and mapped
/// with display_value(v, "clip"), as fit maps its references.
enum class RgbValues { Display, MarkedDisplay, Linear };
RgbValues rgb_values_of(const Image& img, const std::string& path);
/// The first three channels of `img` (at least three) as display values, read as rgb_values_of says.
std::vector<float> display_rgb(const Image& img, const std::string& path);

/// The seed of every reference unless told otherwise: fits, edit sequences and the bench share it.
constexpr uint64_t kReferenceSeed = 0x5eed;

/// Path-traced RGB of `scene` at width x height and `spp` with `seed`, display-mapped with
/// `tone`, encoded by `vae`. `save_png` (if not empty) receives the display image, `display_rgb`
/// (if given) its values. Throws if the size is not a multiple of the VAE's downsampling.
/// Another seed gives an independent reference of the same view (same sampler): two of them
/// measure a reference's own noise (docs/metrics.md "Reference noise").
/// `linear_rgb` (if given) receives the traced values before the display mapping.
std::vector<float> encoded_reference_of(const Scene& scene, int width, int height, int spp, uint64_t seed,
                                        const std::string& tone, const Vae& vae, const std::string& save_png,
                                        std::vector<float>* display_rgb = nullptr, const Reporter& report = {},
                                        std::vector<float>* linear_rgb = nullptr);
/// The path-traced RGB of encoded_reference_of before its display mapping.
std::vector<float> linear_reference_of(const Scene& scene, int width, int height, int spp, uint64_t seed,
                                       const Reporter& report = {});

/// The cache name of a view's training reference ("training_<W>x<H>_<spp>spp_<tone>"): fits
/// and the unedited frames of edit sequences share it.
std::string training_reference_key(int width, int height, int spp, const std::string& tone);
/// The cache name of an edited frame's reference ("<edits stem>_<W>x<H>_<spp>spp_<tone>_<frame
/// name>_own_seed"): the suffix marks references traced with edited_frame_seed, so a cache
/// written when every frame shared one seed is not read as theirs.
std::string edited_frame_reference_key(const std::string& edits_stem, int width, int height, int spp,
                                       const std::string& tone, const std::string& frame_name);
/// The tag edited_frame_reference_key ends with.
inline constexpr const char* kEditedFrameSeedTag = "_own_seed";
/// The seed of edited frame `frame`'s reference under `ref_seed`: each frame its own stream, so the
/// references of one sequence do not share their noise (with one seed for all, a frame's noise
/// repeats in the next wherever the view changes little, and the sequence mean keeps it).
uint64_t edited_frame_seed(uint64_t ref_seed, int frame);
/// What a cache key gains for a reference of another seed ("_seed<N>"; nothing for
/// kReferenceSeed, so caches written before the option keep their names).
std::string reference_seed_suffix(uint64_t seed);

/// What a traced reference shows, as a fingerprint: the text of `scene`'s file (not of the
/// meshes and textures it names), the -D `defines` it was loaded with, and for an edited frame
/// the edit file's text and the frame's index (`edits` empty: the training view). A reference
/// cache's names say how a frame was traced, not what of: this tells a cached frame of another
/// scene or sequence from this one's. The sampler is left out: another one's trace is as good.
std::string reference_source(const Scene& scene, const std::map<std::string, std::string>& defines,
                             const std::string& edits = {}, int frame = -1);

/// encoded_reference_of through a cache: `cache_stem`.exr holds the display RGB and
/// `cache_stem`_latent.exr its encoding. A cached reference is read (and re-encoded only when its
/// latent file is missing); a missing one is traced and both files written, latent first, each
/// atomically, so several jobs (an experiment's fits and edit sequences) trace a reference once
/// and encode it once. An empty `cache_stem` caches nothing. `display_rgb` receives the display
/// image and `save_png` (if not empty) a picture of it. The RGB file records `source`
/// (reference_source) in its header; a cached one that records another throws, naming the file
/// (two scenes or sequences of one name sharing a cache folder). The latent file records `source`
/// and `encoder` (vae_encoder_fingerprint); one another VAE encoded is encoded again. A cached EXR
/// without the display mark or the records (written before EXRs had them) is rewritten with them,
/// its pixels unchanged. `linear_rgb` (if given) receives the values before the display mapping,
/// kept in `cache_stem`_linear.exr: traced again where the cache lacks them, refused where they do
/// not map to the cached display values.
std::vector<float> cached_encoded_reference(const Scene& scene, int width, int height, int spp, uint64_t seed,
                                            const std::string& tone, const Vae& vae, const std::string& cache_stem,
                                            const std::string& source, const std::string& encoder,
                                            const std::string& save_png, std::vector<float>& display_rgb,
                                            const Reporter& report = {}, std::vector<float>* linear_rgb = nullptr);

}  // namespace lpt::pipeline
