// The checkpoint file format (hemo/io/checkpoint.hpp) without a GPU: a written file reads back
// with its header and its payloads where the record table says; every kind of damage is
// refused with a CheckpointError that names the file and the problem; and a seeded mutation
// test, thousands of damaged copies of a checkpoint (flipped, overwritten, inserted and cut
// bytes, half of them with the checksum and the declared size made to match again, as a
// deliberate edit would), each either reads or is refused with a CheckpointError, never another
// exception, a crash, a hang or a huge allocation. Under the asan preset every mutant also
// runs without a memory or undefined-behaviour error. The seed is fixed.
#include "file_bytes.hpp"

#include "hemo/io/checkpoint.hpp"
#include "hemo/io/hash.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace hemo::test {
namespace {

namespace fs = std::filesystem;

fs::path tempDir() {
  const fs::path dir = fs::temp_directory_path() / ("hemo-checkpoint-test-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  fs::create_directories(dir);
  return dir;
}


// A checkpoint with three payloads of known bytes (one empty).
struct Sample {
  io::CheckpointHeader header;
  std::vector<std::vector<unsigned char>> data;
  std::vector<std::string> names;
};

Sample sample() {
  Sample s;
  s.header.scene = "tiny_tank";
  s.header.sceneFingerprint = 0x1234567890abcdefull;
  s.header.device = "test device";
  s.header.driver = "test driver 1.0";
  s.header.vendorId = 0x10de;
  s.header.deviceId = 0x2335;
  for (int k = 0; k < 16; ++k) s.header.pipelineCacheUuid[k] = static_cast<std::uint8_t>(k * 7);
  s.header.steps = 1234;
  s.header.time = 0.0125;
  s.header.host = {1234, 0, 1, 0xffffffffu, 1, 3, 1, 0, 1, 1};
  std::mt19937 rng(7);
  for (std::size_t n : {std::size_t(4000), std::size_t(0), std::size_t(157)}) {
    std::vector<unsigned char> d(n);
    for (auto& b : d) b = static_cast<unsigned char>(rng());
    s.data.push_back(std::move(d));
  }
  s.names = {"positions", "empty", "clock"};
  return s;
}

void write(const fs::path& path, const Sample& s) {
  std::vector<io::CheckpointPayload> payloads;
  for (std::size_t k = 0; k < s.data.size(); ++k) {
    const auto* data = &s.data[k];
    payloads.push_back({s.names[k], data->size(), [data](void* dst, std::uint64_t bytes, std::uint64_t offset) {
                          std::memcpy(dst, data->data() + offset, bytes);
                        }});
  }
  io::writeCheckpoint(path, s.header, payloads);
}

// The declared size (bytes 16-23) made to match the file's.
void redeclare(std::vector<char>& bytes) {
  if (bytes.size() < 24) return;
  const std::uint64_t size = bytes.size();
  std::memcpy(bytes.data() + 16, &size, 8);
}

std::string refusal(const fs::path& path) {
  try {
    io::readCheckpoint(path);
  } catch (const io::CheckpointError& e) {
    return e.what();
  }
  return "(read without an error)";
}

// The checksum depends on the bytes only, however they are split across calls, and any one
// flipped bit or a changed length changes it.
TEST(CheckpointFile, HashDependsOnTheBytesNotOnTheirSplit) {
  std::mt19937 rng(3);
  std::vector<unsigned char> bytes(1001);
  for (auto& b : bytes) b = static_cast<unsigned char>(rng());
  io::Hash64 whole;
  whole.add(bytes.data(), bytes.size());
  for (int trial = 0; trial < 50; ++trial) {
    io::Hash64 split;
    for (std::size_t at = 0; at < bytes.size();) {
      const std::size_t n = std::min<std::size_t>(bytes.size() - at, std::uniform_int_distribution<std::size_t>(0, 19)(rng));
      split.add(bytes.data() + at, n);
      at += n;
    }
    ASSERT_EQ(split.value(), whole.value());
  }
  for (std::size_t bit = 0; bit < bytes.size() * 8; bit += 37) {
    std::vector<unsigned char> flipped = bytes;
    flipped[bit / 8] ^= static_cast<unsigned char>(1u << (bit % 8));
    io::Hash64 h;
    h.add(flipped.data(), flipped.size());
    EXPECT_NE(h.value(), whole.value()) << "bit " << bit;
  }
  io::Hash64 shorter, longer;
  shorter.add(bytes.data(), bytes.size() - 1);
  std::vector<unsigned char> zeroMore = bytes;
  zeroMore.push_back(0);
  longer.add(zeroMore.data(), zeroMore.size());
  EXPECT_NE(shorter.value(), whole.value());
  EXPECT_NE(longer.value(), whole.value());
}

TEST(CheckpointFile, WrittenFileReadsBackWithItsHeaderAndPayloads) {
  const fs::path path = tempDir() / "sample.hemo";
  const Sample s = sample();
  write(path, s);
  const io::CheckpointFile f = io::readCheckpoint(path);
  EXPECT_EQ(f.header.scene, s.header.scene);
  EXPECT_EQ(f.header.sceneFingerprint, s.header.sceneFingerprint);
  EXPECT_EQ(f.header.device, s.header.device);
  EXPECT_EQ(f.header.driver, s.header.driver);
  EXPECT_EQ(f.header.vendorId, s.header.vendorId);
  EXPECT_EQ(f.header.deviceId, s.header.deviceId);
  EXPECT_EQ(f.header.pipelineCacheUuid, s.header.pipelineCacheUuid);
  EXPECT_EQ(f.header.steps, s.header.steps);
  EXPECT_EQ(f.header.time, s.header.time);
  EXPECT_EQ(f.header.host, s.header.host);
  ASSERT_EQ(f.buffers.size(), s.data.size());
  const std::vector<char> bytes = readAll(path);
  for (std::size_t k = 0; k < s.data.size(); ++k) {
    EXPECT_EQ(f.buffers[k].name, s.names[k]);
    ASSERT_EQ(f.buffers[k].bytes, s.data[k].size());
    ASSERT_LE(f.buffers[k].offset + f.buffers[k].bytes, bytes.size());
    EXPECT_TRUE(std::equal(s.data[k].begin(), s.data[k].end(), bytes.begin() + std::ptrdiff_t(f.buffers[k].offset),
                           [](unsigned char a, char b) { return a == static_cast<unsigned char>(b); }))
        << s.names[k];
  }
  // No temporary left beside it (written under a temporary name and renamed).
  int files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(path.parent_path())) ++files;
  EXPECT_EQ(files, 1);
  fs::remove_all(path.parent_path());
}

TEST(CheckpointFile, DamageIsRefusedNamingTheFileAndTheProblem) {
  const fs::path dir = tempDir();
  const fs::path good = dir / "good.hemo", bad = dir / "bad.hemo";
  write(good, sample());
  const std::vector<char> original = readAll(good);
  auto expectRefused = [&](const std::vector<char>& bytes, const std::string& words) {
    writeAll(bad, bytes);
    const std::string message = refusal(bad);
    EXPECT_NE(message.find("checkpoint '" + bad.string() + "'"), std::string::npos) << message;
    EXPECT_NE(message.find(words), std::string::npos) << "expected '" << words << "' in: " << message;
  };
  EXPECT_NE(refusal(dir / "missing.hemo").find("no such file"), std::string::npos);
  EXPECT_NE(refusal(dir).find("not a regular file"), std::string::npos);
  expectRefused({}, "is not a hemo checkpoint (0 bytes)");
  expectRefused(std::vector<char>(original.begin(), original.begin() + 20), "is not a hemo checkpoint");
  {
    const std::string text = "{\"name\": \"a scene, not a checkpoint\", \"particles\": {}}\n";
    expectRefused(std::vector<char>(text.begin(), text.end()), "no HEMOCKPT signature");
  }
  for (std::size_t keep : {std::size_t(40), original.size() / 2, original.size() - 1}) {
    SCOPED_TRACE(keep);
    expectRefused(std::vector<char>(original.begin(), original.begin() + std::ptrdiff_t(keep)),
                  "is truncated: it holds " + std::to_string(keep) + " bytes of the " + std::to_string(original.size()));
  }
  {
    std::vector<char> longer = original;
    longer.push_back('x');
    expectRefused(longer, "is damaged: it holds");
  }
  {  // a flipped bit in a payload, in the header, in the checksum
    for (std::size_t at : {original.size() / 2, std::size_t(30), original.size() - 3}) {
      std::vector<char> flipped = original;
      flipped[at] ^= 0x10;
      expectRefused(flipped, "is damaged: its checksum does not match its contents");
    }
  }
  {  // another format version (a deliberate edit: the checksum matches)
    std::vector<char> v2 = original;
    const std::uint32_t version = 2;
    std::memcpy(v2.data() + 8, &version, 4);
    reseal(v2);
    expectRefused(v2, "has format version 2; this build of hemo reads version 1");
  }
  {  // a name's length that runs past the end, checksum and size matching
    std::vector<char> longName = original;
    const std::uint32_t n = 4000;  // (takes in the records that follow: what comes after them is garbage)
    std::memcpy(longName.data() + 24, &n, 4);
    reseal(longName);
    expectRefused(longName, "is damaged: its ");
    const std::uint32_t huge = 0xfffffff0u;
    std::memcpy(longName.data() + 24, &huge, 4);
    reseal(longName);
    expectRefused(longName, "claims 4294967280 bytes, more than the 4096 a name may have");
  }
  fs::remove_all(dir);
}

TEST(CheckpointFile, MutatedCheckpointsReadOrAreRefusedWithACheckpointError) {
  const fs::path dir = tempDir();
  const fs::path good = dir / "good.hemo", mutant = dir / "mutant.hemo";
  write(good, sample());
  const std::vector<char> original = readAll(good);
  std::mt19937 rng(20261128);
  int read = 0, refused = 0;
  // HEMO_FUZZ_MUTANTS sets a shorter budget (the sanitizer run in `make test`).
  const int kMutants = std::getenv("HEMO_FUZZ_MUTANTS") ? std::max(50, std::atoi(std::getenv("HEMO_FUZZ_MUTANTS"))) : 3000;
  for (int m = 0; m < kMutants; ++m) {
    std::vector<char> bytes = original;
    const int edits = std::uniform_int_distribution<int>(1, 4)(rng);
    for (int e = 0; e < edits && !bytes.empty(); ++e) {
      // Mostly in the header and the record table, where the parser's decisions are.
      const std::size_t limit = std::uniform_int_distribution<int>(0, 3)(rng) == 0 ? bytes.size() : std::min<std::size_t>(bytes.size(), 200);
      const std::size_t at = std::uniform_int_distribution<std::size_t>(0, limit - 1)(rng);
      switch (std::uniform_int_distribution<int>(0, 5)(rng)) {
        case 0: bytes[at] = static_cast<char>(bytes[at] ^ (1 << std::uniform_int_distribution<int>(0, 7)(rng))); break;
        case 1: bytes[at] = static_cast<char>(rng()); break;
        case 2: {  // a 32-bit word from the edges a length check must catch
          const std::uint32_t words[] = {0u, 1u, 0xffffffffu, 0x7fffffffu, 4096u, 4097u, 1u << 20, (1u << 20) + 1, 10u};
          const std::uint32_t w = words[std::uniform_int_distribution<std::size_t>(0, std::size(words) - 1)(rng)];
          if (at + 4 <= bytes.size()) std::memcpy(bytes.data() + at, &w, 4);
          break;
        }
        case 3: bytes.resize(at); break;
        case 4: bytes.insert(bytes.begin() + std::ptrdiff_t(at), std::uniform_int_distribution<int>(1, 16)(rng), 'A'); break;
        case 5: bytes.erase(bytes.begin() + std::ptrdiff_t(at), bytes.begin() + std::ptrdiff_t(std::min(bytes.size(), at + 9))); break;
      }
    }
    if (rng() & 1) {  // as a deliberate edit would leave it: size and checksum matching
      redeclare(bytes);
      reseal(bytes);
    }
    writeAll(mutant, bytes);
    try {
      const io::CheckpointFile f = io::readCheckpoint(mutant);
      // What it read stays within the file.
      for (const auto& r : f.buffers) ASSERT_LE(r.offset + r.bytes, bytes.size()) << "mutant " << m;
      ++read;
    } catch (const io::CheckpointError& e) {
      ASSERT_NE(std::string(e.what()).find(mutant.string()), std::string::npos) << "mutant " << m << ": " << e.what();
      ++refused;
    } catch (const std::exception& e) {
      FAIL() << "mutant " << m << " threw something other than a CheckpointError: " << e.what();
    }
  }
  EXPECT_EQ(read + refused, kMutants);
  EXPECT_GT(refused, kMutants / 2);
  EXPECT_GT(read, 0) << "some mutants only changed payload bytes and were resealed";
  std::printf("%d mutants: %d read, %d refused\n", kMutants, read, refused);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace hemo::test
