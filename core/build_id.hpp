// The build id of the running code, so that what one build wrote for itself (the anatomy cache)
// is never read by another.
#pragma once

#include <string>

namespace phantasm {

/// The GNU build id (the linker's hash of the linked program) of the executable or shared
/// library that holds this code, as lower-case hex; empty when it has none (linked without
/// --build-id): callers then keep nothing across runs.
std::string code_build_id();

} // namespace phantasm
