// Every setting of a scene, defaults filled in, as JSON for provenance.json and the Python
// module.
#pragma once

#include "mri/sequence_type.hpp"
#include "scene/scene.hpp"

#include <nlohmann/json.hpp>

namespace phantasm {

/// Every setting of a scene, defaults filled in, as recorded in provenance.json.
nlohmann::json scene_settings_json(const Scene& scene);

/// A value of a sequence's provenance or sidecar field (mri/sequence_type.hpp) as JSON.
nlohmann::json sequence_value_json(const SequenceValue& value);

} // namespace phantasm
