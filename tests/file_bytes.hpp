#pragma once
// Files as bytes, for tests that damage or edit them (checkpoints).
#include "hemo/io/hash.hpp"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

namespace hemo::test {

inline std::vector<char> readAll(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(in), {});
}

inline void writeAll(const std::filesystem::path& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// A checkpoint's checksum (its last 8 bytes) made to match the bytes before it again, as a
// deliberate edit would leave it.
inline void reseal(std::vector<char>& bytes) {
  if (bytes.size() < 8) return;
  io::Hash64 h;
  h.add(bytes.data(), bytes.size() - 8);
  const std::uint64_t sum = h.value();
  std::memcpy(bytes.data() + bytes.size() - 8, &sum, 8);
}

}  // namespace hemo::test
