#pragma once
// Checkpoint files: a simulation's whole state, for a run that resumes bit for bit where
// another stopped (hemo-run --checkpoint-every N, --resume FILE; sim::Simulation::
// writeCheckpoint and resume). The state is what the GPU holds, byte for byte: every buffer of
// the particles, the grid, the neighbour lists, the solver, the dispatch gate and the wall,
// with the host's few recording flags and the step count. Its layout depends on the device
// (list layout, SIMD-group partials, pages), which is why a checkpoint resumes on the device
// and driver that wrote it.
//
// Layout (little-endian):
//   "HEMOCKPT"  u32 version  u32 0x01020304  u64 file bytes
//   string scene name, u64 scene fingerprint
//   string device, string driver, u32 vendor id, u32 device id, u8[16] pipeline-cache UUID
//   u64 steps, f64 simulated time (s)
//   u32 n, u32[n] host state
//   u32 buffers, then per buffer: string name, u64 bytes, the bytes
//   u64 checksum (hemo/io/hash.hpp) of everything before it
// A string is a u32 length (at most kMaxText) and that many bytes.
#include "hemo/gpu/buffer.hpp"

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemo::io {

// A checkpoint that cannot be resumed: not a checkpoint, another format version, truncated,
// damaged, or from another scene, device or build. The message names the file and the
// problem. hemo-run exits with code 1 (bad input) on it.
class CheckpointError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct CheckpointHeader {
  static constexpr std::uint32_t kVersion = 1;
  static constexpr std::uint32_t kMaxText = 4096;
  static constexpr std::uint32_t kMaxHostWords = 256;
  static constexpr std::uint32_t kMaxBuffers = 1u << 20;
  std::string scene;
  std::uint64_t sceneFingerprint = 0;
  std::string device, driver;
  std::uint32_t vendorId = 0, deviceId = 0;
  std::array<std::uint8_t, 16> pipelineCacheUuid{};
  std::uint64_t steps = 0;
  double time = 0.0;  // s
  std::vector<std::uint32_t> host;
};

// One buffer's record in a file: its name, bytes and where they start.
struct CheckpointRecord {
  std::string name;
  std::uint64_t bytes = 0;
  std::uint64_t offset = 0;
};

struct CheckpointFile {
  CheckpointHeader header;
  std::vector<CheckpointRecord> buffers;
};

// A named run of bytes to write: `read` copies `bytes` from `offset` into `dst` (called in
// chunks of at most 64 MiB).
struct CheckpointPayload {
  std::string name;
  std::uint64_t bytes = 0;
  std::function<void(void* dst, std::uint64_t bytes, std::uint64_t offset)> read;
};
// A GPU buffer's payload: its name and all its bytes (allocatedSize(), read back).
CheckpointPayload payloadOf(const gpu::Buffer& buffer);

// Writes the header and the payloads to `path`, atomically (hemo/io/atomic_file.hpp). Throws
// WriteError naming the file.
void writeCheckpoint(const std::filesystem::path& path, const CheckpointHeader& header,
                     const std::vector<CheckpointPayload>& payloads);

// Reads a checkpoint's header and record table after checking that it is one, of this format
// version, whole (its declared size) and undamaged (its checksum). Throws CheckpointError.
CheckpointFile readCheckpoint(const std::filesystem::path& path);

// Uploads the records of `file` (readCheckpoint's) into `buffers`, which must match them in
// number, names and sizes (else CheckpointError, before anything is uploaded).
void loadCheckpointBuffers(const std::filesystem::path& path, const CheckpointFile& file,
                           const std::vector<gpu::Buffer*>& buffers);

}  // namespace hemo::io
