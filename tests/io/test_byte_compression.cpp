// The cache entries' compression: pieces of 16 MiB that come back whole, and damage named.
#include "core/byte_codec.hpp"
#include "io/byte_compression.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string>

using namespace phantasm;

namespace {

/// 40 MiB (three pieces, the last one short): runs of one byte, then noise, as the cache holds.
std::string sample_bytes() {
  std::string bytes(40u << 20, '\0');
  std::mt19937 random(7);
  for (std::size_t at = 0; at < bytes.size(); ++at)
    bytes[at] = at < (12u << 20) ? static_cast<char>(at >> 20) : static_cast<char>(random() & 0xff);
  return bytes;
}

} // namespace

TEST(ByteCompression, BytesOfSeveralPiecesComeBackWhole) {
  const std::string bytes = sample_bytes();
  for (const int level : {0, 1}) {
    const std::string compressed = compress_bytes(bytes, level);
    if (level == 1) {
      EXPECT_LT(compressed.size(), bytes.size() * 4 / 5); // the runs compress
    }
    EXPECT_EQ(decompress_bytes(compressed), bytes) << "level " << level;
  }
  EXPECT_EQ(decompress_bytes(compress_bytes("")), "");
}

TEST(ByteCompression, DamageInAnyPieceIsNamed) {
  const std::string compressed = compress_bytes(sample_bytes(), 1);
  const auto message = [](const std::string& damaged) {
    try {
      decompress_bytes(damaged);
    } catch (const DamagedBytes& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  // A byte flipped in the last piece's stream, near the end (its check no longer holds).
  std::string flipped = compressed;
  flipped[flipped.size() - 100] = static_cast<char>(flipped[flipped.size() - 100] ^ 0x5a);
  EXPECT_EQ(message(flipped), "compressed bytes: a piece that does not decompress");
  EXPECT_NE(message(compressed.substr(0, compressed.size() - 10)).find("compressed bytes: "),
            std::string::npos);
  EXPECT_EQ(message(compressed + "x"), "compressed bytes: bytes after the last piece");
}
