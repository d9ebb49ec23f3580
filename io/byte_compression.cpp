#include "io/byte_compression.hpp"

#include "core/byte_codec.hpp"
#include "core/cancellation.hpp"

#include <libdeflate.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <stdexcept>

namespace phantasm {
namespace {

// A piece of input per libdeflate call: a fraction of a second, so a cancelled run stops soon.
constexpr std::size_t k_piece_bytes = std::size_t{1} << 24;

} // namespace

std::string compress_bytes(std::string_view bytes, int level) {
  const std::unique_ptr<libdeflate_compressor, void (*)(libdeflate_compressor*)> compressor(
      libdeflate_alloc_compressor(level), libdeflate_free_compressor);
  if (!compressor) throw std::runtime_error("libdeflate: cannot allocate a compressor");
  ByteWriter out;
  out.value(static_cast<std::uint64_t>(bytes.size()));
  std::string piece;
  for (std::size_t at = 0; at < bytes.size(); at += k_piece_bytes) {
    throw_if_cancelled();
    const std::size_t size = std::min(k_piece_bytes, bytes.size() - at);
    piece.resize(libdeflate_zlib_compress_bound(compressor.get(), size));
    const std::size_t compressed =
        libdeflate_zlib_compress(compressor.get(), bytes.data() + at, size, piece.data(), piece.size());
    if (compressed == 0) throw std::runtime_error("libdeflate: zlib compression failed");
    out.value(static_cast<std::uint64_t>(size));
    out.text(std::string_view(piece).substr(0, compressed));
  }
  return out.take();
}

std::string decompress_bytes(std::string_view compressed) {
  const std::unique_ptr<libdeflate_decompressor, void (*)(libdeflate_decompressor*)> decompressor(
      libdeflate_alloc_decompressor(), libdeflate_free_decompressor);
  if (!decompressor) throw std::runtime_error("libdeflate: cannot allocate a decompressor");
  ByteReader in(compressed, "compressed bytes");
  const auto total = in.value<std::uint64_t>();
  // No more than the input could hold at deflate's best ratio (about 1032:1): a damaged size
  // must not allocate without bound.
  if (total / 1032 > compressed.size()) in.damaged("a size larger than the bytes can hold");
  std::string out(total, '\0');
  for (std::size_t at = 0; at < total;) {
    throw_if_cancelled();
    const auto size = in.value<std::uint64_t>();
    const std::string_view piece = in.view();
    if (size == 0 || size > total - at) in.damaged("a piece of another size");
    std::size_t got = 0;
    if (libdeflate_zlib_decompress(decompressor.get(), piece.data(), piece.size(), out.data() + at, size,
                                   &got) != LIBDEFLATE_SUCCESS ||
        got != size)
      in.damaged("a piece that does not decompress");
    at += size;
  }
  if (!in.done()) in.damaged("bytes after the last piece");
  return out;
}

} // namespace phantasm
