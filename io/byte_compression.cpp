#include "io/byte_compression.hpp"

#include "core/byte_codec.hpp"
#include "core/cancellation.hpp"
#include "core/parallel_tasks.hpp"

#include <libdeflate.h>
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

namespace phantasm {
namespace {

// A piece of input per libdeflate call: a fraction of a second, so a cancelled run stops soon.
constexpr std::size_t k_piece_bytes = std::size_t{1} << 24;

/// Threads for `pieces` pieces: the run's (OpenMP's limit), no more than there are pieces.
std::size_t threads_for(std::size_t pieces) {
  return std::max<std::size_t>(1, std::min(pieces, static_cast<std::size_t>(omp_get_max_threads())));
}

} // namespace

std::string compress_bytes(std::string_view bytes, int level) {
  // The pieces side by side, each by a compressor of its own: the same bytes on any number of
  // threads.
  const std::size_t pieces = (bytes.size() + k_piece_bytes - 1) / k_piece_bytes;
  std::vector<std::string> compressed(pieces);
  run_tasks_in_parallel(pieces, threads_for(pieces), [&](std::size_t p) {
    throw_if_cancelled();
    const std::unique_ptr<libdeflate_compressor, void (*)(libdeflate_compressor*)> compressor(
        libdeflate_alloc_compressor(level), libdeflate_free_compressor);
    if (!compressor) throw std::runtime_error("libdeflate: cannot allocate a compressor");
    const std::size_t at = p * k_piece_bytes, size = std::min(k_piece_bytes, bytes.size() - at);
    std::string& piece = compressed[p];
    piece.resize(libdeflate_zlib_compress_bound(compressor.get(), size));
    const std::size_t length =
        libdeflate_zlib_compress(compressor.get(), bytes.data() + at, size, piece.data(), piece.size());
    if (length == 0) throw std::runtime_error("libdeflate: zlib compression failed");
    piece.resize(length);
  });
  ByteWriter out;
  out.value(static_cast<std::uint64_t>(bytes.size()));
  for (std::size_t p = 0; p < pieces; ++p) {
    out.value(static_cast<std::uint64_t>(std::min(k_piece_bytes, bytes.size() - p * k_piece_bytes)));
    out.text(compressed[p]);
  }
  return out.take();
}

namespace {

/// decompress_bytes() a piece after another, each checked before the next is read: what a
/// damaged entry is reported by.
std::string decompress_in_order(std::string_view compressed) {
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

} // namespace

std::string decompress_bytes(std::string_view compressed) {
  // The pieces found first, then inflated side by side. Bytes that are not pieces in order, or a
  // piece that does not inflate, are read again in order, which says what is wrong as it meets it.
  struct Piece {
    std::size_t at = 0, size = 0;
    std::string_view bytes;
  };
  std::vector<Piece> pieces;
  std::uint64_t total = 0;
  try {
    ByteReader in(compressed, "compressed bytes");
    total = in.value<std::uint64_t>();
    if (total / 1032 > compressed.size()) return decompress_in_order(compressed);
    for (std::size_t at = 0; at < total;) {
      const auto size = in.value<std::uint64_t>();
      const std::string_view bytes = in.view();
      if (size == 0 || size > total - at) return decompress_in_order(compressed);
      pieces.push_back({at, size, bytes});
      at += size;
    }
    if (!in.done()) return decompress_in_order(compressed);
  } catch (const DamagedBytes&) {
    return decompress_in_order(compressed);
  }
  std::string out(total, '\0');
  std::atomic<bool> failed{false};
  run_tasks_in_parallel(pieces.size(), threads_for(pieces.size()), [&](std::size_t p) {
    throw_if_cancelled();
    const std::unique_ptr<libdeflate_decompressor, void (*)(libdeflate_decompressor*)> decompressor(
        libdeflate_alloc_decompressor(), libdeflate_free_decompressor);
    if (!decompressor) throw std::runtime_error("libdeflate: cannot allocate a decompressor");
    std::size_t got = 0;
    const Piece& piece = pieces[p];
    if (libdeflate_zlib_decompress(decompressor.get(), piece.bytes.data(), piece.bytes.size(),
                                   out.data() + piece.at, piece.size, &got) != LIBDEFLATE_SUCCESS ||
        got != piece.size)
      failed = true;
  });
  return failed ? decompress_in_order(compressed) : out;
}

} // namespace phantasm
