#include "hemo/io/checkpoint.hpp"

#include "hemo/io/atomic_file.hpp"
#include "hemo/io/hash.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <system_error>

namespace hemo::io {

namespace {

constexpr char kMagic[8] = {'H', 'E', 'M', 'O', 'C', 'K', 'P', 'T'};
constexpr std::uint32_t kByteOrder = 0x01020304u;
constexpr std::uint64_t kChunk = 64ull << 20;  // bytes per readback or upload of a large buffer

std::string quoted(const std::filesystem::path& path) { return "checkpoint '" + path.string() + "'"; }

// The header's bytes (up to the buffer records), and its size.
class Encoder {
 public:
  template <class T>
  void value(const T& v) {
    const auto* p = reinterpret_cast<const unsigned char*>(&v);
    bytes_.insert(bytes_.end(), p, p + sizeof v);
  }
  void text(const std::string& s) {
    value(static_cast<std::uint32_t>(s.size()));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
  }
  const std::vector<unsigned char>& bytes() const { return bytes_; }

 private:
  std::vector<unsigned char> bytes_;
};

std::vector<unsigned char> encodeHeader(const CheckpointHeader& h, std::uint64_t fileBytes) {
  Encoder e;
  for (char c : kMagic) e.value(c);
  e.value(CheckpointHeader::kVersion);
  e.value(kByteOrder);
  e.value(fileBytes);
  e.text(h.scene);
  e.value(h.sceneFingerprint);
  e.text(h.device);
  e.text(h.driver);
  e.value(h.vendorId);
  e.value(h.deviceId);
  e.value(h.pipelineCacheUuid);
  e.value(h.steps);
  e.value(h.time);
  e.value(static_cast<std::uint32_t>(h.host.size()));
  for (std::uint32_t w : h.host) e.value(w);
  return e.bytes();
}

// Reads the file's bytes in order, hashing them, with every read checked against the end of
// the records (the file's size less the checksum): a length that runs past it is damage.
class Decoder {
 public:
  Decoder(const std::filesystem::path& path, std::ifstream& in, std::uint64_t end) : path_(path), in_(in), end_(end) {}
  void read(void* dst, std::uint64_t bytes, const char* what) {
    if (bytes > end_ - pos_) {
      throw CheckpointError(quoted(path_) + " is damaged: its " + what + " runs past the end of the file");
    }
    in_.read(static_cast<char*>(dst), static_cast<std::streamsize>(bytes));
    if (!in_) throw CheckpointError(quoted(path_) + ": reading failed at byte " + std::to_string(pos_));
    hash_.add(dst, bytes);
    pos_ += bytes;
  }
  template <class T>
  T value(const char* what) {
    T v{};
    read(&v, sizeof v, what);
    return v;
  }
  std::string text(const char* what) {
    const auto n = value<std::uint32_t>(what);
    if (n > CheckpointHeader::kMaxText) {
      throw CheckpointError(quoted(path_) + " is damaged: its " + what + " claims " + std::to_string(n) +
                            " bytes, more than the " + std::to_string(CheckpointHeader::kMaxText) + " a name may have");
    }
    std::string s(n, '\0');
    read(s.data(), n, what);
    return s;
  }
  // Hashes the next `bytes` without keeping them (a buffer's payload).
  void skip(std::uint64_t bytes, const char* what) {
    if (bytes > end_ - pos_) {
      throw CheckpointError(quoted(path_) + " is damaged: its " + what + " runs past the end of the file");
    }
    std::vector<char> chunk(static_cast<std::size_t>(std::min<std::uint64_t>(bytes, kChunk)));
    for (std::uint64_t done = 0; done < bytes;) {
      const std::uint64_t n = std::min<std::uint64_t>(bytes - done, chunk.size());
      read(chunk.data(), n, what);
      done += n;
    }
  }
  std::uint64_t position() const { return pos_; }
  std::uint64_t hash() const { return hash_.value(); }

 private:
  const std::filesystem::path& path_;
  std::ifstream& in_;
  std::uint64_t end_;
  std::uint64_t pos_ = 0;
  Hash64 hash_;
};

std::uint64_t fileSize(const std::filesystem::path& path) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found) {
    throw CheckpointError("cannot open " + quoted(path) + ": no such file");
  }
  if (ec) throw CheckpointError("cannot open " + quoted(path) + ": " + ec.message());
  if (status.type() != std::filesystem::file_type::regular) {
    throw CheckpointError("cannot open " + quoted(path) + ": not a regular file");
  }
  const std::uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) throw CheckpointError("cannot open " + quoted(path) + ": " + ec.message());
  return size;
}

std::ifstream openInput(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw CheckpointError("cannot open " + quoted(path) + ": " + std::strerror(errno));
  return in;
}

}  // namespace

CheckpointPayload payloadOf(const gpu::Buffer& buffer) {
  return CheckpointPayload{buffer.name(), buffer.allocatedSize(),
                           [&buffer](void* dst, std::uint64_t bytes, std::uint64_t offset) {
                             buffer.readbackBytes(dst, bytes, offset);
                           }};
}

void writeCheckpoint(const std::filesystem::path& path, const CheckpointHeader& header,
                     const std::vector<CheckpointPayload>& payloads) {
  for (const std::string* s : {&header.scene, &header.device, &header.driver}) {
    if (s->size() > CheckpointHeader::kMaxText) throw std::invalid_argument("checkpoint: a name of over 4096 bytes");
  }
  // The whole size first: the header declares it, so a reader tells a truncated copy at once.
  std::uint64_t total = encodeHeader(header, 0).size() + sizeof(std::uint32_t);
  for (const CheckpointPayload& b : payloads) {
    if (b.name.size() > CheckpointHeader::kMaxText) throw std::invalid_argument("checkpoint: a name of over 4096 bytes");
    total += sizeof(std::uint32_t) + b.name.size() + 8 + b.bytes;
  }
  total += 8;  // the checksum

  AtomicFile file(path);
  Hash64 hash;
  auto put = [&](const void* data, std::uint64_t bytes) {
    hash.add(data, bytes);
    file.stream().write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
  };
  const std::vector<unsigned char> head = encodeHeader(header, total);
  put(head.data(), head.size());
  const auto count = static_cast<std::uint32_t>(payloads.size());
  put(&count, sizeof count);
  std::vector<char> chunk;
  for (const CheckpointPayload& b : payloads) {
    const auto nameBytes = static_cast<std::uint32_t>(b.name.size());
    const std::uint64_t bytes = b.bytes;
    put(&nameBytes, sizeof nameBytes);
    put(b.name.data(), nameBytes);
    put(&bytes, sizeof bytes);
    chunk.resize(static_cast<std::size_t>(std::min<std::uint64_t>(bytes, kChunk)));
    for (std::uint64_t done = 0; done < bytes;) {
      const std::uint64_t n = std::min<std::uint64_t>(bytes - done, chunk.size());
      b.read(chunk.data(), n, done);
      put(chunk.data(), n);
      done += n;
    }
  }
  const std::uint64_t sum = hash.value();
  file.stream().write(reinterpret_cast<const char*>(&sum), sizeof sum);
  file.commit();
}

CheckpointFile readCheckpoint(const std::filesystem::path& path) {
  const std::uint64_t size = fileSize(path);
  std::ifstream in = openInput(path);
  const std::string notOne = quoted(path) + " is not a hemo checkpoint";
  char magic[8] = {};
  constexpr std::uint64_t kFixed = 8 + 4 + 4 + 8;
  if (size < kFixed + 8) throw CheckpointError(notOne + " (" + std::to_string(size) + " bytes)");
  Decoder d(path, in, size - 8);
  d.read(magic, sizeof magic, "signature");
  if (std::memcmp(magic, kMagic, sizeof magic) != 0) throw CheckpointError(notOne + " (no HEMOCKPT signature)");
  const auto version = d.value<std::uint32_t>("version");
  const auto order = d.value<std::uint32_t>("byte-order mark");
  if (order != kByteOrder) {
    throw CheckpointError(quoted(path) + " was written with another byte order, or is damaged");
  }
  if (version != CheckpointHeader::kVersion) {
    throw CheckpointError(quoted(path) + " has format version " + std::to_string(version) +
                          "; this build of hemo reads version " + std::to_string(CheckpointHeader::kVersion));
  }
  const auto declared = d.value<std::uint64_t>("size");
  if (declared != size) {
    throw CheckpointError(quoted(path) + (size < declared ? " is truncated" : " is damaged") + ": it holds " +
                          std::to_string(size) + " bytes of the " + std::to_string(declared) + " it declares");
  }
  CheckpointFile f;
  CheckpointHeader& h = f.header;
  h.scene = d.text("scene name");
  h.sceneFingerprint = d.value<std::uint64_t>("scene fingerprint");
  h.device = d.text("device name");
  h.driver = d.text("driver");
  h.vendorId = d.value<std::uint32_t>("vendor id");
  h.deviceId = d.value<std::uint32_t>("device id");
  h.pipelineCacheUuid = d.value<std::array<std::uint8_t, 16>>("pipeline-cache UUID");
  h.steps = d.value<std::uint64_t>("step count");
  h.time = d.value<double>("time");
  const auto hostWords = d.value<std::uint32_t>("host state");
  if (hostWords > CheckpointHeader::kMaxHostWords) {
    throw CheckpointError(quoted(path) + " is damaged: " + std::to_string(hostWords) + " words of host state");
  }
  h.host.resize(hostWords);
  for (auto& w : h.host) w = d.value<std::uint32_t>("host state");
  const auto count = d.value<std::uint32_t>("buffer count");
  if (count > CheckpointHeader::kMaxBuffers) {
    throw CheckpointError(quoted(path) + " is damaged: it claims " + std::to_string(count) + " buffers");
  }
  for (std::uint32_t k = 0; k < count; ++k) {
    CheckpointRecord r;
    r.name = d.text("buffer name");
    r.bytes = d.value<std::uint64_t>("buffer size");
    r.offset = d.position();
    d.skip(r.bytes, "buffer");
    f.buffers.push_back(std::move(r));
  }
  if (d.position() != size - 8) {
    throw CheckpointError(quoted(path) + " is damaged: " + std::to_string(size - 8 - d.position()) +
                          " bytes follow its last buffer");
  }
  std::uint64_t sum = 0;
  in.read(reinterpret_cast<char*>(&sum), sizeof sum);
  if (!in) throw CheckpointError(quoted(path) + ": reading its checksum failed");
  if (sum != d.hash()) throw CheckpointError(quoted(path) + " is damaged: its checksum does not match its contents");
  return f;
}

void loadCheckpointBuffers(const std::filesystem::path& path, const CheckpointFile& file,
                           const std::vector<gpu::Buffer*>& buffers) {
  const std::string other = quoted(path) + " does not fit this simulation's buffers (written by another build of "
                                           "hemo, or with other device limits): ";
  if (file.buffers.size() != buffers.size()) {
    throw CheckpointError(other + "it holds " + std::to_string(file.buffers.size()) + " buffers, the simulation has " +
                          std::to_string(buffers.size()));
  }
  for (std::size_t k = 0; k < buffers.size(); ++k) {
    const CheckpointRecord& r = file.buffers[k];
    if (r.name != buffers[k]->name() || r.bytes != buffers[k]->allocatedSize()) {
      throw CheckpointError(other + "its buffer " + std::to_string(k) + " is '" + r.name + "' of " +
                            std::to_string(r.bytes) + " bytes, the simulation's '" + buffers[k]->name() + "' of " +
                            std::to_string(buffers[k]->allocatedSize()));
    }
  }
  std::ifstream in = openInput(path);
  std::vector<char> chunk;
  for (std::size_t k = 0; k < buffers.size(); ++k) {
    const CheckpointRecord& r = file.buffers[k];
    in.seekg(static_cast<std::streamoff>(r.offset));
    chunk.resize(static_cast<std::size_t>(std::min<std::uint64_t>(r.bytes, kChunk)));
    for (std::uint64_t done = 0; done < r.bytes;) {
      const std::uint64_t n = std::min<std::uint64_t>(r.bytes - done, chunk.size());
      in.read(chunk.data(), static_cast<std::streamsize>(n));
      if (!in) throw CheckpointError(quoted(path) + ": reading buffer '" + r.name + "' failed");
      buffers[k]->uploadBytes(chunk.data(), n, done);
      done += n;
    }
  }
}

}  // namespace hemo::io
