// liblatentpt_oiio.so: image reading through OpenImageIO, opened on demand by
// core/image_reader.cpp. It depends on nothing of latentpt but the interface in image_reader.h (and the
// handshake of plugin_interface.h).
#include "core/error.h"
#include "core/image_reader.h"
#include "core/plugin_interface.h"
#include "latentpt_interface_fingerprint.h"
#include <OpenImageIO/imageio.h>
#include <stdexcept>

namespace lpt {
namespace {

class OiioReader final : public ImageFileReader {
public:
    OiioReader(std::unique_ptr<OIIO::ImageInput> in, std::string path) : m_in(std::move(in)), m_path(std::move(path)) {
        const OIIO::ImageSpec& spec = m_in->spec();
        m_info.width = spec.width;
        m_info.height = spec.height;
        m_info.depth = spec.depth;
        m_info.channels = spec.nchannels;
        m_info.channel_names = spec.channelnames;
        const auto base = OIIO::TypeDesc::BASETYPE(spec.format.basetype);
        m_info.is_float =
            base == OIIO::TypeDesc::FLOAT || base == OIIO::TypeDesc::HALF || base == OIIO::TypeDesc::DOUBLE;
        m_info.is_uint8 = base == OIIO::TypeDesc::UINT8;
        m_info.display_values = spec.get_string_attribute(kDisplayValuesAttribute) == kDisplayValues;
        m_info.source = spec.get_string_attribute(kSourceAttribute);
    }
    const ImageFileInfo& info() const override { return m_info; }
    void read_float(float* out) override { read(OIIO::TypeDesc::FLOAT, out); }
    void read_uint8(uint8_t* out) override { read(OIIO::TypeDesc::UINT8, out); }

private:
    void read(OIIO::TypeDesc type, void* out) {
        if (!m_in->read_image(0, 0, 0, m_info.channels, type, out))
            throw std::runtime_error(m_path +
                                     ": cannot decode image (truncated or corrupt?): " + one_line(m_in->geterror()));
    }
    std::unique_ptr<OIIO::ImageInput> m_in;
    std::string m_path;
    ImageFileInfo m_info;
};

}  // namespace
}  // namespace lpt

LPT_DEFINE_PLUGIN_INTERFACE(LPT_INTERFACE_FINGERPRINT)

extern "C" lpt::ImageFileReader* latentpt_open_image_file(const char* path, bool unassociated_alpha,
                                                          std::string* error) {
    OIIO::ImageSpec config;
    // PNG/TIFF alpha is premultiplied into the colour by default in OIIO.
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, unassociated_alpha ? &config : nullptr);
    if (!in) {
        *error = lpt::one_line(OIIO::geterror());
        return nullptr;
    }
    return new lpt::OiioReader(std::move(in), path);
}
