// SHA-256 of a byte string as hex, for the scene hashes of provenance records and of a batch's
// complete subjects.
#pragma once

#include <string>
#include <string_view>

namespace phantasm {

/// SHA-256 (FIPS 180-4) of a byte string, as 64 lower-case hex digits. Used for scene hashes
/// in provenance records, so that a dataset names exactly the scene that made it.
std::string sha256_hex(std::string_view bytes);

} // namespace phantasm
