// Bytes compressed in memory (deflate, zlib format, libdeflate at level 1) for the entries a run
// keeps across runs: the reference cache's volumes are mostly runs of 0 and 1.
#pragma once

#include <string>
#include <string_view>

namespace phantasm {

/// The bytes compressed in pieces of 16 MiB (each with its Adler-32 check), with a cancellation
/// poll between the pieces.
std::string compress_bytes(std::string_view bytes);

/// The bytes compress_bytes() was given.
/// @throws DamagedBytes (core/byte_codec.hpp) when the bytes are cut short or do not decompress
///         with their checks
std::string decompress_bytes(std::string_view compressed);

} // namespace phantasm
