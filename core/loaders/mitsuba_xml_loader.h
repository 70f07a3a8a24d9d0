// The Mitsuba 3 XML loader's reader of one document: it walks <scene>'s elements into a Scene,
// keeping ids for <ref>s. Internal to core/loaders/: mitsuba_xml.cpp holds the scene content
// (ids, textures, BSDFs, emitters, shapes) and load_scene_mitsuba_xml, mitsuba_xml_sensor.cpp
// the camera and render settings (sensor, film, sampler, integrator).
#pragma once
#include "core/loaders/mitsuba_xml_detail.h"
#include "core/loaders/mitsuba_xml_plugin.h"
#include "core/scene.h"
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace lpt::mitsuba_xml {

namespace fs = std::filesystem;

/// What an id names, for <ref> and duplicate-id errors.
struct IdEntry {
    std::string tag;
    int line = -1;
    std::shared_ptr<Props> props;  ///< for <bsdf> and <texture>
    int material = -1;             ///< index in Scene::materials once a shape uses it
};

class Loader : private PluginReader {
public:
    Loader(const Source& src, Scene& scene)
        : PluginReader(src), scene(scene), dir(fs::path(src.path()).parent_path()) {}

    /// Every top-level element of <scene> into the Scene, in document order.
    void load(const pugi::xml_node& root);

private:
    Scene& scene;
    fs::path dir;  ///< the XML's folder: relative filenames resolve against it, as in Mitsuba
    std::map<std::string, IdEntry> ids;
    bool have_sensor = false, have_integrator = false;
    int default_material = -1;
    std::vector<int> unnamed_shapes;

    void register_id(const std::string& id, const std::string& tag, int line, std::shared_ptr<Props> props = nullptr);

    IdEntry& resolve_ref(const pugi::xml_node& ref);

    void skip_medium(const pugi::xml_node& n);

    /// A <texture> as Props (type "bitmap"; filename made absolute, relative to the XML's folder
    /// as Mitsuba resolves it). The image is loaded here, so a missing or unreadable file is
    /// reported at this element's line; the BSDF later gets it from the cache.
    std::shared_ptr<Props> read_texture(const pugi::xml_node& n, const std::string& what);

    /// Top-level <texture id>, for <ref name="reflectance" id="..."/> inside BSDFs (Mitsuba's
    /// named textures).
    void read_top_texture(const pugi::xml_node& n);

    /// Puts a texture under `name` in a BSDF's props; a name given twice is an error, as for
    /// properties.
    void add_texture(const Plugin& p, Props& props, const pugi::xml_node& c, std::shared_ptr<Props> tex);

    Props to_props(const Plugin& p) const;

    /// A <bsdf> (nested BSDFs included) as Props, validated by building it for N = 3 so errors
    /// point at the file before rendering starts.
    std::shared_ptr<Props> read_bsdf(const pugi::xml_node& n, const std::string& what);

    int add_material(const Props& m);

    // The camera and how it is rendered (mitsuba_xml_sensor.cpp).
    /// A plugin element a scene may hold once (<integrator>, <sensor>), of the one `type` we read.
    Plugin read_single(const pugi::xml_node& n, const std::string& tag, bool& seen, const std::string& type);
    void read_integrator(const pugi::xml_node& n);
    void read_sensor(const pugi::xml_node& n);  ///< with its <film> and <sampler>
    void read_film(const pugi::xml_node& n);
    void read_sampler(const pugi::xml_node& n);

    void read_top_emitter(const pugi::xml_node& n);

    /// Mitsuba 3 envmap: filename (relative to the XML), scale, to_world. The image is loaded
    /// now, so a missing file is an error at the emitter's line naming the file.
    Emitter read_envmap(const Plugin& p);

    Emitter read_emitter_props(const Plugin& p, EmitterKind kind, int shape);

    /// A shape's properties checked against what its type takes, each of its XML kind (a wrong
    /// kind is an error at its line), as the Props make_shape reads; the filename relative to
    /// the XML's folder, as Mitsuba resolves it.
    Props shape_props(const Plugin& p) const;

    void read_shape(const pugi::xml_node& n);

    /// Unnamed shapes get "shape_<index>", suffixed until unique: our ids must be unique, while
    /// Mitsuba lets shapes go without one.
    void name_unnamed_shapes();
};

}  // namespace lpt::mitsuba_xml
