// Every setting of a scene, defaults filled in, as JSON for provenance.json and the Python
// module.
#pragma once

#include "scene/scene.hpp"

#include <nlohmann/json.hpp>

namespace phantasm {

/// Every setting of a scene, defaults filled in, as recorded in provenance.json.
nlohmann::json scene_settings_json(const Scene& scene);

} // namespace phantasm
