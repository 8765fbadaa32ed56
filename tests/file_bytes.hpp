#pragma once
// Files as bytes, for tests that write, damage or edit them (checkpoints, output files).
#include "hemo/io/hash.hpp"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <unistd.h>

namespace hemo::test {

// An empty folder of its own under the system's temporary folder: hemo_<name>_<pid>.
inline std::filesystem::path freshTempDir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("hemo_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::string readText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

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
