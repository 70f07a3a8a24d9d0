// Scene files → Scene. `.json` is our format (docs/scene-format.md); Mitsuba 3 `.xml` arrives
// with its loader. Every error is a SceneError naming the file and the field.
#pragma once
#include "core/sampler.h"
#include "core/scene.h"
#include <map>
#include <optional>
#include <string>

namespace lpt {

/// Loads and build()s a scene. `defines` override scene parameters by name (for XML: <default>;
/// for JSON: "integrator.spp", "camera.width", ... see docs/scene-format.md). `sampler`, when given,
/// replaces the file's (the CLI's `--sampler`, Python's `sampler=`; docs/sampling.md).
Scene load_scene(const std::string& path, const std::map<std::string, std::string>& defines = {},
                 std::optional<SamplerKind> sampler = std::nullopt);
Scene load_scene_json(const std::string& path, const std::map<std::string, std::string>& defines = {});
/// Mitsuba 3 XML (docs/scene-format.md, "Mitsuba 3 XML"); `defines` override <default> values like
/// Mitsuba's -D name=value.
Scene load_scene_mitsuba_xml(const std::string& path, const std::map<std::string, std::string>& defines = {});

}  // namespace lpt
