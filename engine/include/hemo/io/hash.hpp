#pragma once
// A 64-bit hash of a byte stream, for checkpoints: their checksum (a damaged file is refused)
// and the fingerprint of the scene they belong to. Not cryptographic: it detects accidents
// (a flipped bit, a truncated copy, another scene), not forgery. The result depends only on
// the bytes, not on how they are split across add() calls. Words of 8 bytes (little-endian)
// go through FNV-1a's step (xor, multiply by the FNV prime), which is fast, and a final
// avalanche mixes the length in.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>

namespace hemo::io {

class Hash64 {
 public:
  void add(const void* data, std::size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    length_ += bytes;
    while (bytes > 0 && pending_ > 0) {  // complete the word started by an earlier call
      word_ |= std::uint64_t(*p++) << (8 * pending_);
      --bytes;
      if (++pending_ == 8) mix(), pending_ = 0;
    }
    while (bytes >= 8) {
      std::uint64_t w = 0;
      for (int k = 0; k < 8; ++k) w |= std::uint64_t(p[k]) << (8 * k);
      word_ = w;
      mix();
      p += 8;
      bytes -= 8;
    }
    for (; bytes > 0; --bytes) {
      if (pending_ == 0) word_ = 0;
      word_ |= std::uint64_t(*p++) << (8 * pending_);
      ++pending_;
    }
  }
  // A value's bytes (integers, floats and arrays of them: no padding).
  template <class T>
  void addValue(const T& value) {
    static_assert(std::has_unique_object_representations_v<T> || std::is_floating_point_v<T>,
                  "hash values without padding");
    add(&value, sizeof value);
  }
  void addString(const std::string& text) {
    addValue(std::uint64_t(text.size()));
    add(text.data(), text.size());
  }
  std::uint64_t value() const {
    std::uint64_t h = state_;
    if (pending_ > 0) h = (h ^ word_) * kPrime;
    h ^= length_;
    // splitmix64's finaliser: every input bit reaches every output bit
    h ^= h >> 30;
    h *= 0xbf58476d1ce4e5b9ull;
    h ^= h >> 27;
    h *= 0x94d049bb133111ebull;
    h ^= h >> 31;
    return h;
  }

 private:
  static constexpr std::uint64_t kPrime = 0x100000001b3ull;
  void mix() { state_ = (state_ ^ word_) * kPrime; }
  std::uint64_t state_ = 0xcbf29ce484222325ull;  // FNV-1a's offset basis
  std::uint64_t word_ = 0;
  std::uint64_t length_ = 0;
  unsigned pending_ = 0;  // bytes of word_ filled by an unfinished word
};

}  // namespace hemo::io
