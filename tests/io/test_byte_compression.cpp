// The cache entries' compression: pieces of 16 MiB that come back whole, and damage named.
#include "core/byte_codec.hpp"
#include "io/byte_compression.hpp"

#include <gtest/gtest.h>

#include <omp.h>

#include <cstdint>
#include <cstring>
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

/// What decompress_bytes() says of damaged bytes ("no error" when it reads them).
std::string message(const std::string& damaged) {
  try {
    decompress_bytes(damaged);
  } catch (const DamagedBytes& error) {
    return error.what();
  }
  return "no error";
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
  // A byte flipped in the last piece's stream, near the end (its check no longer holds).
  std::string flipped = compressed;
  flipped[flipped.size() - 100] = static_cast<char>(flipped[flipped.size() - 100] ^ 0x5a);
  EXPECT_EQ(message(flipped), "compressed bytes: a piece that does not decompress");
  EXPECT_NE(message(compressed.substr(0, compressed.size() - 10)).find("compressed bytes: "),
            std::string::npos);
  EXPECT_EQ(message(compressed + "x"), "compressed bytes: bytes after the last piece");
}

// The pieces are compressed and inflated side by side (io/byte_compression.cpp): the same bytes on
// one thread as on several, and a damaged entry named by the first damage in order, whichever
// piece a thread reached first.
TEST(ByteCompression, TheBytesAndTheMessagesAreTheSameOnAnyNumberOfThreads) {
  const std::string bytes = sample_bytes();
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::string one = compress_bytes(bytes, 1);
  omp_set_num_threads(3);
  const std::string three = compress_bytes(bytes, 1);
  EXPECT_EQ(one, three);
  EXPECT_EQ(decompress_bytes(one), bytes);
  // The first piece's stream damaged, and the third's size: the first is named.
  std::string damaged = one;
  damaged[8 + 8 + 8 + 1000] = static_cast<char>(damaged[8 + 8 + 8 + 1000] ^ 0x5a);
  EXPECT_EQ(message(damaged), "compressed bytes: a piece that does not decompress");
  std::uint64_t first_length = 0;
  std::memcpy(&first_length, one.data() + 16, sizeof first_length);
  std::uint64_t second_length = 0;
  const std::size_t second = 24 + first_length;
  std::memcpy(&second_length, one.data() + second + 8, sizeof second_length);
  const std::size_t third = second + 16 + second_length;
  const std::uint64_t wrong_size = bytes.size(); // more than remains after two pieces
  std::memcpy(damaged.data() + third, &wrong_size, sizeof wrong_size);
  EXPECT_EQ(message(damaged), "compressed bytes: a piece that does not decompress");
  std::string only_third = one;
  std::memcpy(only_third.data() + third, &wrong_size, sizeof wrong_size);
  EXPECT_EQ(message(only_third), "compressed bytes: a piece of another size");
  omp_set_num_threads(threads);
}
