// The Vulkan layer itself: device choice, buffers, bindings, timestamps, bad input.
#include "gpu_test.hpp"
#include "hemo/gpu/commands.hpp"
#include "hemo/gpu/pipeline_cache.hpp"
#include "interface/bench.h"
#include "interface/scan.h"

#include <cmath>
#include <cstdlib>
#include <glm/glm.hpp>
#include <vector>

namespace hemo::test {
namespace {

class GpuLayerTest : public GpuTest {};

TEST_F(GpuLayerTest, ListsTheDeviceInUse) {
  const auto devices = gpu::listDevices();
  ASSERT_FALSE(devices.empty());
  bool found = false;
  for (const auto& d : devices) found = found || d.name == ctx().info().name;
  EXPECT_TRUE(found);
  EXPECT_GT(ctx().subgroupSize(), 0u);
}

TEST_F(GpuLayerTest, UnknownDeviceNameIsAClearError) {
  gpu::ContextOptions options;
  options.device = "no-such-gpu-xyz";
  try {
    gpu::Context other(options);
    FAIL() << "expected GpuError";
  } catch (const gpu::GpuError& e) {
    EXPECT_NE(std::string(e.what()).find("no-such-gpu-xyz"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(ctx().info().name), std::string::npos) << "lists the devices";
  }
  options.device = "97";
  EXPECT_THROW(gpu::Context{options}, gpu::GpuError);
}

TEST_F(GpuLayerTest, DeviceCanBeChosenByIndexAndByName) {
  gpu::ContextOptions byIndex;
  byIndex.device = std::to_string(ctx().info().index);
  EXPECT_EQ(gpu::Context(byIndex).info().name, ctx().info().name);
  gpu::ContextOptions byName;
  byName.device = ctx().info().name.substr(0, 4);
  EXPECT_NO_THROW(gpu::Context{byName});
}

TEST_F(GpuLayerTest, OversizedBufferNamesItselfAndTheLimit) {
  const VkDeviceSize tooBig = VkDeviceSize(ctx().limits().maxStorageBufferRange) + 64;
  try {
    gpu::Buffer b(ctx(), tooBig, gpu::MemoryUse::Device, "huge particle array");
    FAIL() << "expected GpuError";
  } catch (const gpu::GpuError& e) {
    EXPECT_NE(std::string(e.what()).find("huge particle array"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("maxStorageBufferRange"), std::string::npos) << e.what();
  }
}

TEST_F(GpuLayerTest, UploadReadbackRoundTripAndBounds) {
  gpu::Buffer b(ctx(), 1000 * 4, gpu::MemoryUse::Device, "roundtrip");
  std::vector<std::uint32_t> v(1000);
  for (std::uint32_t i = 0; i < v.size(); ++i) v[i] = i * 2654435761u;
  b.upload(v);
  EXPECT_EQ(b.readback<std::uint32_t>(1000), v);
  EXPECT_EQ(b.readback<std::uint32_t>(10, 40)[0], v[10]);
  EXPECT_THROW(b.readback<std::uint32_t>(1001), std::out_of_range);
  EXPECT_THROW(b.upload(std::vector<std::uint32_t>(1001)), std::out_of_range);
  gpu::Buffer moved = std::move(b);
  EXPECT_FALSE(b.valid());
  EXPECT_EQ(moved.readback<std::uint32_t>(1)[0], v[0]);
}

TEST_F(GpuLayerTest, FillAndCopyThroughTheRecorder) {
  gpu::Buffer a(ctx(), 256, gpu::MemoryUse::Device, "a");
  gpu::Buffer b(ctx(), 256, gpu::MemoryUse::Device, "b");
  gpu::CommandRecorder rec(ctx());
  rec.begin();
  rec.fill(a, 0xdeadbeefu);
  rec.transferToTransfer();
  rec.copy(a, b, 128, 0, 64);
  rec.end();
  rec.submitAndWait();
  const auto got = b.readback<std::uint32_t>(64);
  EXPECT_EQ(got[16], 0xdeadbeefu);
  EXPECT_EQ(got[47], 0xdeadbeefu);
}

// The recorder refuses a fill, copy or dispatch that touches bytes an earlier fill or copy
// wrote with no barrier since, on any device (synchronization validation reports the same
// hazards, but only where the layer runs).
TEST_F(GpuLayerTest, TransferWritesNeedABarrierBeforeTheirNextUse) {
  const auto& p = ctx().pipelines().get({"scan/scan_add", HEMO_SCAN_BINDING_COUNT, 16, 256, {}});
  gpu::Buffer a(ctx(), 256, gpu::MemoryUse::Device, "a");
  gpu::Buffer b(ctx(), 256, gpu::MemoryUse::Device, "b");
  gpu::Buffer sums(ctx(), 64, gpu::MemoryUse::Device, "sums");
  const auto set = p.makeSet({{HEMO_SCAN_BINDING_DATA, &b}, {HEMO_SCAN_BINDING_SUMS, &sums}, {HEMO_SCAN_BINDING_LENGTH, &sums}});
  const std::uint32_t push[4] = {64, HEMO_SCAN_NO_LENGTH, 0, 0};
  auto message = [](auto&& f) -> std::string {
    try {
      f();
    } catch (const std::logic_error& e) {
      return e.what();
    }
    return "(no error)";
  };
  gpu::CommandRecorder rec(ctx());
  rec.begin();
  rec.fill(a, 1u, 0, 64);
  EXPECT_NO_THROW(rec.fill(a, 2u, 64, 64));  // other bytes
  const std::string overFill = message([&] { rec.fill(a, 3u, 32, 64); });
  EXPECT_NE(overFill.find("a fill touches bytes 32 to 64 of buffer 'a'"), std::string::npos) << overFill;
  EXPECT_NE(overFill.find("transferToTransfer"), std::string::npos) << overFill;
  const std::string readFill = message([&] { rec.copy(a, b, 16); });
  EXPECT_NE(readFill.find("copy from buffer 'a'"), std::string::npos) << readFill;
  rec.transferToTransfer();
  EXPECT_NO_THROW(rec.copy(a, b, 256));
  EXPECT_NO_THROW(rec.fill(sums, 0u));
  const std::string dispatch = message([&] { rec.dispatch(p, set, push, sizeof(push), p.groupsFor(16)); });
  EXPECT_NE(dispatch.find("dispatch of 'scan/scan_add'"), std::string::npos) << dispatch;
  EXPECT_NE(dispatch.find("transferToCompute"), std::string::npos) << dispatch;
  rec.transferToCompute();
  EXPECT_NO_THROW(rec.dispatch(p, set, push, sizeof(push), p.groupsFor(16)));
  rec.end();
  rec.submitAndWait();
  const auto got = b.readback<std::uint32_t>(64);
  EXPECT_EQ(got[0], 1u);   // block 0 of the scan is left as it is
  EXPECT_EQ(got[16], 2u);
}

TEST_F(GpuLayerTest, BindingsAreCheckedBySlot) {
  const auto& p = ctx().pipelines().get({"scan/scan_add", HEMO_SCAN_BINDING_COUNT, 16, 256, {}});
  gpu::Buffer a(ctx(), 64, gpu::MemoryUse::Device, "a");
  gpu::Buffer staging(ctx(), 64, gpu::MemoryUse::Upload, "staging");
  EXPECT_THROW(p.makeSet({{HEMO_SCAN_BINDING_DATA, &a}, {2, &a}}), std::invalid_argument);  // slot 1 missing
  EXPECT_THROW(p.makeSet({{0, &a}, {0, &a}, {2, &a}}), std::invalid_argument);               // twice
  EXPECT_THROW(p.makeSet({{0, &a}, {1, &a}, {5, &a}}), std::invalid_argument);               // no such slot
  EXPECT_THROW(p.makeSet({{0, &a}, {1, &staging}, {2, &a}}), std::invalid_argument);         // not a device buffer
  EXPECT_NO_THROW(p.makeSet({{0, &a}, {1, &a}, {2, &a}}));
  // The same description returns the same pipeline object.
  EXPECT_EQ(&p, &ctx().pipelines().get({"scan/scan_add", HEMO_SCAN_BINDING_COUNT, 16, 256, {}}));
}

// Uniform-buffer slots: the same values read as a uniform buffer, a storage buffer and push
// constants (bench/param_read.comp) give the same results, and a uniform slot's offset must
// respect minUniformBufferOffsetAlignment.
TEST_F(GpuLayerTest, UniformSlotsReadTheBoundBuffer) {
  struct Push {
    glm::vec4 p[HEMO_BENCH_PARAM_VEC4S - 1];
    std::uint32_t n, reads;
  };
  const std::uint32_t n = 300, reads = 13;
  Push push{};
  std::vector<glm::vec4> values(HEMO_BENCH_PARAM_VEC4S);
  for (std::uint32_t k = 0; k < HEMO_BENCH_PARAM_VEC4S; ++k) {
    values[k] = glm::vec4(0.5f + 0.0625f * float(k), 0.125f * float(k), -0.25f, 1.0f + float(k));
    if (k + 1 < HEMO_BENCH_PARAM_VEC4S) push.p[k] = values[k];
  }
  push.n = n;
  push.reads = reads;
  gpu::Buffer params(ctx(), values.size() * 16, gpu::MemoryUse::Device, "params");
  params.upload(values);
  // CPU double reference of the loop in bench/param_read.comp.
  std::vector<glm::dvec4> expected(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    glm::dvec4 sum(double(float(i) * 1e-3f), 0.5, 0.25, 1.0);
    for (std::uint32_t k = 0; k < reads; ++k) {
      const glm::dvec4 q(values[k % (HEMO_BENCH_PARAM_VEC4S - 1)]);
      sum = sum * q.x + glm::dvec4(q.y, q.z, q.w, q.x);
    }
    expected[i] = sum;
  }
  for (std::uint32_t variant = 1; variant <= 3; ++variant) {
    SCOPED_TRACE("variant " + std::to_string(variant));
    const auto& p = ctx().pipelines().get({"bench/param_read", HEMO_BENCH_PARAM_BINDING_COUNT, sizeof(Push), 64,
                                           {variant}, 1u << HEMO_BENCH_PARAM_BINDING_UNIFORM});
    gpu::Buffer out(ctx(), std::uint64_t(n) * 16, gpu::MemoryUse::Device, "out");
    const auto set = p.makeSet({{HEMO_BENCH_PARAM_BINDING_STORAGE, &params},
                                {HEMO_BENCH_PARAM_BINDING_UNIFORM, &params},
                                {HEMO_BENCH_PARAM_BINDING_OUT, &out}});
    gpu::CommandRecorder rec(ctx());
    rec.begin();
    rec.dispatch(p, set, push, p.groupsFor(n));
    rec.end();
    rec.submitAndWait();
    const auto got = out.readback<glm::vec4>(n);
    for (std::uint32_t i = 0; i < n; ++i) {
      for (int c = 0; c < 4; ++c) {
        ASSERT_NEAR(got[i][c], expected[i][c], 1e-5 * (1.0 + std::abs(expected[i][c]))) << "invocation " << i;
      }
    }
  }
  // A uniform slot at an offset that breaks the device's alignment is refused, naming the slot.
  const auto& p = ctx().pipelines().get({"bench/param_read", HEMO_BENCH_PARAM_BINDING_COUNT, sizeof(Push), 64, {2u},
                                         1u << HEMO_BENCH_PARAM_BINDING_UNIFORM});
  const VkDeviceSize align = ctx().limits().minUniformBufferOffsetAlignment;
  gpu::Buffer big(ctx(), 4096, gpu::MemoryUse::Device, "big");
  if (align > 1) {
    try {
      p.makeSet({{HEMO_BENCH_PARAM_BINDING_STORAGE, &big},
                 {HEMO_BENCH_PARAM_BINDING_UNIFORM, &big, align / 2, 128},
                 {HEMO_BENCH_PARAM_BINDING_OUT, &big}});
      ADD_FAILURE() << "a misaligned uniform offset was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("minUniformBufferOffsetAlignment"), std::string::npos) << e.what();
    }
  }
  EXPECT_NO_THROW(p.makeSet({{HEMO_BENCH_PARAM_BINDING_STORAGE, &big},
                             {HEMO_BENCH_PARAM_BINDING_UNIFORM, &big, align, 128},
                             {HEMO_BENCH_PARAM_BINDING_OUT, &big}}));
  // A uniform mask naming a slot the pipeline does not have is an error.
  EXPECT_THROW(ctx().pipelines().get({"bench/param_read", HEMO_BENCH_PARAM_BINDING_COUNT, sizeof(Push), 64, {2u},
                                      1u << HEMO_BENCH_PARAM_BINDING_COUNT}),
               gpu::GpuError);
}

// Texel slots: the pair loop of bench/pair_gather_texel.comp reads a list (R32_UINT texels)
// and four vec4 arrays (R32G32B32A32_SFLOAT texels) through buffer views, in both list
// layouts; against a CPU double reference on random inputs. Then the checks of makeSet.
TEST_F(GpuLayerTest, TexelSlotsGatherTheBoundBuffers) {
  struct Push {
    std::uint32_t n, entries;
  };
  const std::uint32_t n = 300, entries = 9;
  std::srand(7);
  auto unit = [] { return float(std::rand() % 2001 - 1000) * 1e-3f; };
  std::vector<std::uint32_t> list(std::size_t(n) * entries);
  for (auto& j : list) j = std::uint32_t(std::rand()) % n;
  std::vector<std::vector<glm::vec4>> values(4, std::vector<glm::vec4>(n));
  for (auto& v : values)
    for (auto& x : v) x = glm::vec4(unit(), unit(), unit(), 0.25f + 0.5f * std::abs(unit()));
  gpu::Buffer listBuffer(ctx(), list.size() * 4, gpu::MemoryUse::Device, "list");
  listBuffer.upload(list);
  std::vector<gpu::Buffer> data;
  for (int b = 0; b < 4; ++b) {
    data.emplace_back(ctx(), std::uint64_t(n) * 16, gpu::MemoryUse::Device, "data");
    data.back().upload(values[b]);
  }
  gpu::Buffer out(ctx(), std::uint64_t(n) * 16, gpu::MemoryUse::Device, "out");
  const std::uint32_t texels = 0x1fu;  // LIST and A..D
  for (std::uint32_t contiguous = 0; contiguous <= 1; ++contiguous) {
    SCOPED_TRACE("contiguous " + std::to_string(contiguous));
    const auto& p = ctx().pipelines().get(
        {"bench/pair_gather_texel", HEMO_BENCH_BINDING_COUNT, sizeof(Push), 64, {4u, contiguous}, 0u, texels});
    const auto set = p.makeSet({gpu::texelBinding(HEMO_BENCH_BINDING_LIST, &listBuffer, VK_FORMAT_R32_UINT),
                                gpu::texelBinding(HEMO_BENCH_BINDING_A, &data[0], VK_FORMAT_R32G32B32A32_SFLOAT),
                                gpu::texelBinding(HEMO_BENCH_BINDING_B, &data[1], VK_FORMAT_R32G32B32A32_SFLOAT),
                                gpu::texelBinding(HEMO_BENCH_BINDING_C, &data[2], VK_FORMAT_R32G32B32A32_SFLOAT),
                                gpu::texelBinding(HEMO_BENCH_BINDING_D, &data[3], VK_FORMAT_R32G32B32A32_SFLOAT),
                                {HEMO_BENCH_BINDING_OUT, &out}});
    gpu::CommandRecorder rec(ctx());
    rec.begin();
    rec.dispatch(p, set, Push{n, entries}, p.groupsFor(n));
    rec.end();
    rec.submitAndWait();
    const auto got = out.readback<glm::vec4>(n);
    for (std::uint32_t i = 0; i < n; ++i) {
      glm::dvec4 sum(0.0);
      const glm::dvec3 self(double(float(i) * 1e-3f), 0.5, 0.25);
      for (std::uint32_t k = 0; k < entries; ++k) {
        const std::uint32_t j = list[contiguous ? std::size_t(i) * entries + k : std::size_t(k) * n + i];
        glm::dvec4 x(0.0);
        for (int b = 0; b < 4; ++b) x += glm::dvec4(values[b][j]);
        const glm::dvec3 r = self - glm::dvec3(x);
        const double r2 = glm::dot(r, r) + 1e-6;
        sum += glm::dvec4(r * (x.w / std::sqrt(r2)), r2);
      }
      for (int c = 0; c < 4; ++c) {
        ASSERT_NEAR(got[i][c], sum[c], 1e-4 * (1.0 + std::abs(sum[c]))) << "invocation " << i;
      }
    }
  }
  const auto& p = ctx().pipelines().get(
      {"bench/pair_gather_texel", HEMO_BENCH_BINDING_COUNT, sizeof(Push), 64, {4u, 0u}, 0u, texels});
  auto expectRefused = [&](std::initializer_list<gpu::Binding> bindings, const std::string& phrase) {
    try {
      p.makeSet(bindings);
      ADD_FAILURE() << "accepted; expected an error naming '" << phrase << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(phrase), std::string::npos) << e.what();
    }
  };
  const auto vec4s = VK_FORMAT_R32G32B32A32_SFLOAT;
  // A texel slot without a format.
  expectRefused({{HEMO_BENCH_BINDING_LIST, &listBuffer}, gpu::texelBinding(HEMO_BENCH_BINDING_A, &data[0], vec4s),
                 gpu::texelBinding(HEMO_BENCH_BINDING_B, &data[1], vec4s), gpu::texelBinding(HEMO_BENCH_BINDING_C, &data[2], vec4s),
                 gpu::texelBinding(HEMO_BENCH_BINDING_D, &data[3], vec4s), {HEMO_BENCH_BINDING_OUT, &out}},
                "slot 0 is a texel slot");
  // A storage slot given a format.
  expectRefused({gpu::texelBinding(HEMO_BENCH_BINDING_LIST, &listBuffer, VK_FORMAT_R32_UINT),
                 gpu::texelBinding(HEMO_BENCH_BINDING_A, &data[0], vec4s), gpu::texelBinding(HEMO_BENCH_BINDING_B, &data[1], vec4s),
                 gpu::texelBinding(HEMO_BENCH_BINDING_C, &data[2], vec4s), gpu::texelBinding(HEMO_BENCH_BINDING_D, &data[3], vec4s),
                 gpu::texelBinding(HEMO_BENCH_BINDING_OUT, &out, vec4s)},
                "slot 5 is not a texel slot");
  // A texel offset that breaks the device's alignment.
  const VkDeviceSize align = ctx().limits().minTexelBufferOffsetAlignment;
  if (align > 1) {
    expectRefused({gpu::texelBinding(HEMO_BENCH_BINDING_LIST, &listBuffer, VK_FORMAT_R32_UINT),
                   {HEMO_BENCH_BINDING_A, &data[0], align / 2, 256, vec4s}, gpu::texelBinding(HEMO_BENCH_BINDING_B, &data[1], vec4s),
                   gpu::texelBinding(HEMO_BENCH_BINDING_C, &data[2], vec4s), gpu::texelBinding(HEMO_BENCH_BINDING_D, &data[3], vec4s),
                   {HEMO_BENCH_BINDING_OUT, &out}},
                  "minTexelBufferOffsetAlignment");
  }
  // A texel range past the end of its buffer.
  expectRefused({gpu::texelBinding(HEMO_BENCH_BINDING_LIST, &listBuffer, VK_FORMAT_R32_UINT),
                 {HEMO_BENCH_BINDING_A, &data[0], 0, std::uint64_t(n) * 16 + 64, vec4s},
                 gpu::texelBinding(HEMO_BENCH_BINDING_B, &data[1], vec4s), gpu::texelBinding(HEMO_BENCH_BINDING_C, &data[2], vec4s),
                 gpu::texelBinding(HEMO_BENCH_BINDING_D, &data[3], vec4s), {HEMO_BENCH_BINDING_OUT, &out}},
                "lie beyond buffer");
  // A slot declared both uniform and texel.
  EXPECT_THROW(ctx().pipelines().get({"bench/pair_gather_texel", HEMO_BENCH_BINDING_COUNT, sizeof(Push), 64, {4u, 1u},
                                      1u << HEMO_BENCH_BINDING_A, texels}),
               gpu::GpuError);
}

// Storage texel slots: bench/store_scatter.comp writes one R32_UINT texel per iteration
// through imageStore (or, as the control, through a storage buffer), in both layouts, every
// store kept or the slot advancing under a data mask (later stores then overwrite earlier
// ones); against the same sequence on the CPU. Slots not written keep their old value.
TEST_F(GpuLayerTest, StorageTexelSlotsWriteTheBoundBuffer) {
  struct Push {
    std::uint32_t n, entries;
  };
  const std::uint32_t n = 300, entries = 7;
  const std::uint32_t untouched = 0xdeadbeefu;
  const std::vector<std::uint32_t> fill(std::size_t(n) * entries, untouched);
  gpu::Buffer out(ctx(), fill.size() * 4, gpu::MemoryUse::Device, "out");
  gpu::Buffer image(ctx(), fill.size() * 4, gpu::MemoryUse::Device, "image");
  for (std::uint32_t texel = 0; texel <= 1; ++texel)
  for (std::uint32_t contiguous = 0; contiguous <= 1; ++contiguous)
  for (std::uint32_t masked = 0; masked <= 1; ++masked) {
    SCOPED_TRACE("texel " + std::to_string(texel) + ", contiguous " + std::to_string(contiguous) + ", masked " +
                 std::to_string(masked));
    out.upload(fill);
    image.upload(fill);
    const auto& p = ctx().pipelines().get({"bench/store_scatter", HEMO_BENCH_STORE_BINDING_COUNT, sizeof(Push), 64,
                                           {contiguous, texel, masked}, 0u, 0u, 1u << HEMO_BENCH_STORE_BINDING_IMAGE});
    const auto set = p.makeSet({{HEMO_BENCH_STORE_BINDING_OUT, &out},
                                gpu::texelBinding(HEMO_BENCH_STORE_BINDING_IMAGE, &image, VK_FORMAT_R32_UINT)});
    gpu::CommandRecorder rec(ctx());
    rec.begin();
    rec.dispatch(p, set, Push{n, entries}, p.groupsFor(n));
    rec.end();
    rec.submitAndWait();
    std::vector<std::uint32_t> expected = fill;
    for (std::uint32_t i = 0; i < n; ++i) {
      std::uint32_t h = i * 2654435761u;
      std::uint32_t count = 0;
      for (std::uint32_t k = 0; k < entries; ++k) {
        h = h * 1664525u + 1013904223u;
        const std::uint32_t slot = masked ? count : k;
        expected[contiguous ? std::size_t(i) * entries + slot : std::size_t(slot) * n + i] = h;
        count += masked ? (h >> 31) : 1u;
      }
    }
    const auto written = (texel ? image : out).readback<std::uint32_t>(fill.size());
    const auto other = (texel ? out : image).readback<std::uint32_t>(fill.size());
    for (std::size_t e = 0; e < fill.size(); ++e) {
      ASSERT_EQ(written[e], expected[e]) << "texel " << e;
      ASSERT_EQ(other[e], untouched) << "the other binding, texel " << e;
    }
  }
  const auto& p = ctx().pipelines().get({"bench/store_scatter", HEMO_BENCH_STORE_BINDING_COUNT, sizeof(Push), 64,
                                         {0u, 1u, 0u}, 0u, 0u, 1u << HEMO_BENCH_STORE_BINDING_IMAGE});
  // A storage texel slot without a format.
  try {
    p.makeSet({{HEMO_BENCH_STORE_BINDING_OUT, &out}, {HEMO_BENCH_STORE_BINDING_IMAGE, &image}});
    ADD_FAILURE() << "a storage texel slot without a format was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("slot 1 is a texel slot"), std::string::npos) << e.what();
  }
  // A slot declared both a uniform texel and a storage texel slot.
  EXPECT_THROW(ctx().pipelines().get({"bench/store_scatter", HEMO_BENCH_STORE_BINDING_COUNT, sizeof(Push), 64, {0u, 1u, 0u}, 0u,
                                      1u << HEMO_BENCH_STORE_BINDING_IMAGE, 1u << HEMO_BENCH_STORE_BINDING_IMAGE}),
               gpu::GpuError);
}

TEST_F(GpuLayerTest, PushConstantSizeMismatchIsRejected) {
  const auto& p = ctx().pipelines().get({"scan/scan_add", HEMO_SCAN_BINDING_COUNT, 16, 256, {}});
  gpu::Buffer a(ctx(), 64, gpu::MemoryUse::Device, "a");
  auto set = p.makeSet({{0, &a}, {1, &a}, {2, &a}});
  gpu::CommandRecorder rec(ctx());
  rec.begin();
  const std::uint64_t wrong = 0;  // 8 bytes; the pipeline takes 16
  EXPECT_THROW(rec.dispatch(p, set, wrong, p.groupsFor(1)), std::invalid_argument);
  rec.end();
}

TEST_F(GpuLayerTest, GroupsFoldIntoTwoDimensionsPastTheLimit) {
  const auto& p = ctx().pipelines().get({"scan/scan_add", HEMO_SCAN_BINDING_COUNT, 16, 256, {}});
  const std::uint64_t maxX = ctx().limits().maxComputeWorkGroupCount[0];
  const auto small = p.groupsFor(1000);
  EXPECT_EQ(small.x, 4u);
  EXPECT_EQ(small.y, 1u);
  const auto big = p.groupsFor((maxX + 10) * 256);
  EXPECT_GE(big.total(), maxX + 10);
  EXPECT_LE(big.x, maxX);
  EXPECT_GT(big.y, 1u);
  EXPECT_EQ(p.groupsFor(0).total(), 0u);
}

// Fills `a` with 7 as the stage "fill", timed by `ts`, and waits.
void timeAFill(gpu::Context& context, gpu::Buffer& a, gpu::TimestampQueries& ts) {
  gpu::CommandRecorder rec(context);
  rec.begin();
  ts.reset(rec);
  ts.mark(rec, "start");
  rec.fill(a, 7);
  ts.mark(rec, "fill");
  rec.end();
  rec.submitAndWait();
}

// A queue without timestamps (forced): stages are recorded untimed, and the times are empty
// rather than made up.
TEST_F(GpuLayerTest, StagesRunUntimedWithoutTimestamps) {
  gpu::ContextOptions options;
  options.validation = true;
  options.limits.timestamps = false;
  gpu::Context untimed(options);
  ASSERT_FALSE(untimed.timestampsSupported());
  gpu::Buffer a(untimed, 1 << 16, gpu::MemoryUse::Device, "a");
  gpu::TimestampQueries ts(untimed, 4);
  EXPECT_FALSE(ts.supported());
  timeAFill(untimed, a, ts);
  EXPECT_TRUE(ts.stageMs().empty());
  EXPECT_EQ(ts.totalMs(), 0.0);
  EXPECT_EQ(a.readback<std::uint32_t>(1)[0], 7u);
  for (const auto& m : untimed.takeValidationMessages()) ADD_FAILURE() << m;
}

// A timestamp counter with few valid bits (forced to 12): stage times are differences modulo
// 2^12 ticks, never the garbage a wrapped counter gives when the high bits are kept.
TEST_F(GpuLayerTest, TimestampDifferencesWrapAtTheValidBits) {
  if (!ctx().timestampsSupported()) GTEST_SKIP() << "device has no timestamps";
  gpu::ContextOptions options;
  options.validation = true;
  options.limits.timestampValidBits = 12;
  gpu::Context narrow(options);
  ASSERT_EQ(narrow.timestampValidBits(), 12u);
  gpu::Buffer a(narrow, 1 << 20, gpu::MemoryUse::Device, "a");
  gpu::TimestampQueries ts(narrow, 4);
  for (int round = 0; round < 4; ++round) {
    timeAFill(narrow, a, ts);
    const auto stages = ts.stageMs();
    ASSERT_EQ(stages.size(), 1u);
    EXPECT_GE(stages[0].second, 0.0);
    EXPECT_LT(stages[0].second, 4096 * narrow.timestampPeriodNs() * 1e-6);
  }
  for (const auto& m : narrow.takeValidationMessages()) ADD_FAILURE() << m;
}

// A device with fewer storage-buffer descriptors per stage than a pass binds (forced; Vulkan
// guarantees only 4) refuses the pipeline with the count and the limit, not a driver crash.
TEST_F(GpuLayerTest, PipelineBeyondTheDescriptorLimitsIsAClearError) {
  gpu::ContextOptions options;
  options.validation = true;
  options.limits.maxPerStageDescriptorStorageBuffers = 2;
  gpu::Context small(options);
  EXPECT_NO_THROW(small.pipelines().get({"bench/dispatch_probe", HEMO_BENCH_PROBE_BINDING_COUNT, 4, 64, {}}));
  std::string message;
  try {
    small.pipelines().get({"scan/scan_add", HEMO_SCAN_BINDING_COUNT, 16, 256, {}});
  } catch (const gpu::GpuError& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("'scan/scan_add' binds 3 storage buffers (maxPerStageDescriptorStorageBuffers is 2"),
            std::string::npos)
      << "got: " << message;
  for (const auto& m : small.takeValidationMessages()) ADD_FAILURE() << m;
}

// hemo's account of device memory: each buffer adds what its allocation took (at least its
// size) and gives it back when destroyed; the peak stays until reset.
TEST_F(GpuLayerTest, DeviceMemoryIsCountedPerBuffer) {
  const std::uint64_t before = ctx().deviceMemoryBytes();
  ctx().resetPeakDeviceMemoryBytes();
  EXPECT_EQ(ctx().peakDeviceMemoryBytes(), before);
  EXPECT_GT(ctx().deviceMemoryCapacity(), 0u);
  {
    gpu::Buffer a(ctx(), 1 << 20, gpu::MemoryUse::Device, "a");
    const std::uint64_t withA = ctx().deviceMemoryBytes();
    EXPECT_GE(withA, before + (1u << 20));
    EXPECT_LT(withA, before + (1u << 20) + (1u << 16));  // alignment at most
    gpu::Buffer b(ctx(), 3 << 20, gpu::MemoryUse::Device, "b");
    EXPECT_GE(ctx().deviceMemoryBytes(), withA + (3u << 20));
    gpu::Buffer moved = std::move(b);  // the allocation moves with the buffer, counted once
    EXPECT_GE(ctx().deviceMemoryBytes(), withA + (3u << 20));
    EXPECT_LT(ctx().deviceMemoryBytes(), withA + (3u << 20) + (1u << 16));
  }
  EXPECT_EQ(ctx().deviceMemoryBytes(), before);
  EXPECT_GE(ctx().peakDeviceMemoryBytes(), before + (4u << 20));
  ctx().resetPeakDeviceMemoryBytes();
  EXPECT_EQ(ctx().peakDeviceMemoryBytes(), before);
}

// A device with little memory (capped at 4 MiB) refuses the buffer that does not fit before
// allocating it, naming the buffer and the figures, and keeps the buffers it holds.
TEST_F(GpuLayerTest, BufferBeyondTheDeviceMemoryIsRefusedWithTheFigures) {
  gpu::ContextOptions options;
  options.validation = true;
  options.limits.deviceMemoryBytes = 4u << 20;
  gpu::Context small(options);
  EXPECT_EQ(small.deviceMemoryCapacity() % (4u << 20), 0u);  // 4 MiB per device-local heap
  gpu::Buffer a(small, 3u << 20, gpu::MemoryUse::Device, "particle positions");
  const std::uint64_t held = small.deviceMemoryBytes();
  std::string message;
  std::uint64_t needed = 0;
  try {
    gpu::Buffer b(small, 2u << 20, gpu::MemoryUse::Device, "neighbour list");
  } catch (const gpu::OutOfDeviceMemory& e) {
    message = e.what();
    needed = e.needed;
    EXPECT_EQ(e.available, 4u << 20);
  }
  EXPECT_NE(message.find("cannot hold buffer 'neighbour list'"), std::string::npos) << message;
  EXPECT_NE(message.find("needs at least"), std::string::npos) << message;
  EXPECT_GE(needed, held + (2u << 20));
  EXPECT_EQ(small.deviceMemoryBytes(), held);  // nothing was taken for the refused buffer
  a.upload(std::vector<std::uint32_t>(4, 9u));
  EXPECT_EQ(a.readback<std::uint32_t>(4)[3], 9u);
  gpu::Buffer c(small, 512u << 10, gpu::MemoryUse::Device, "fits");  // what is left still serves
  for (const auto& m : small.takeValidationMessages()) ADD_FAILURE() << m;
}

TEST_F(GpuLayerTest, UnknownShaderNameThrows) {
  EXPECT_THROW(ctx().pipelines().get({"scan/nope", 1, 0, 64, {}}), std::invalid_argument);
}

TEST_F(GpuLayerTest, TimestampsMeasureStages) {
  if (!ctx().timestampsSupported()) GTEST_SKIP() << "device has no timestamps";
  gpu::Buffer a(ctx(), 1 << 20, gpu::MemoryUse::Device, "a");
  gpu::TimestampQueries ts(ctx(), 8);
  timeAFill(ctx(), a, ts);
  const auto stages = ts.stageMs();
  ASSERT_EQ(stages.size(), 1u);
  EXPECT_EQ(stages[0].first, "fill");
  EXPECT_GE(stages[0].second, 0.0);
}

}  // namespace
}  // namespace hemo::test

namespace hemo::test {
namespace {

// Guards the guard: the validation layer is really on and its messages are counted.
TEST_F(GpuLayerTest, ValidationLayerReportsMisuse) {
  ASSERT_TRUE(ctx().validationEnabled());
  const std::uint64_t before = ctx().validationMessageCount();
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = 0;  // invalid: VUID-VkBufferCreateInfo-size-00912
  info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  VkBuffer buffer = VK_NULL_HANDLE;
  vkCreateBuffer(ctx().device(), &info, nullptr, &buffer);
  if (buffer) vkDestroyBuffer(ctx().device(), buffer, nullptr);
  EXPECT_GT(ctx().validationMessageCount(), before);
  const auto messages = ctx().takeValidationMessages();  // expected here; not a failure
  ASSERT_FALSE(messages.empty());
  EXPECT_NE(messages[0].find("00912"), std::string::npos) << messages[0];
}

// Synchronization validation is on in the test suite (a missing barrier fails the test that
// records it): a fill over what a dispatch wrote, with no barrier between, is reported.
TEST_F(GpuLayerTest, SynchronizationValidationReportsAMissingBarrier) {
  if (ctx().validation() != gpu::Validation::Standard) {
    GTEST_SKIP() << "synchronization validation is off (" << gpu::validationName(ctx().validation()) << " validation)";
  }
  const auto& p = ctx().pipelines().get({"scan/scan_add", HEMO_SCAN_BINDING_COUNT, 16, 256, {}});
  gpu::Buffer data(ctx(), 4096, gpu::MemoryUse::Device, "data");
  gpu::Buffer sums(ctx(), 64, gpu::MemoryUse::Device, "sums");
  const auto set = p.makeSet({{HEMO_SCAN_BINDING_DATA, &data}, {HEMO_SCAN_BINDING_SUMS, &sums}, {HEMO_SCAN_BINDING_LENGTH, &sums}});
  const std::uint32_t push[4] = {1024, HEMO_SCAN_NO_LENGTH, 0, 0};
  const std::uint64_t before = ctx().validationMessageCount();
  gpu::CommandRecorder rec(ctx());
  rec.begin();
  rec.dispatch(p, set, push, sizeof(push), p.groupsFor(1024));
  vkCmdFillBuffer(rec.handle(), data.handle(), 0, 64, 0);  // no computeToTransfer before
  rec.end();
  rec.submitAndWait();
  EXPECT_GT(ctx().validationMessageCount(), before);
  const auto messages = ctx().takeValidationMessages();  // expected here; not a failure
  ASSERT_FALSE(messages.empty());
  EXPECT_NE(messages[0].find("SYNC-HAZARD-WRITE-AFTER-WRITE"), std::string::npos) << messages[0];
}

// The staging path of a discrete GPU, whose large memory the host cannot map, forced on
// lavapipe: device buffers are not mapped, and uploads, recorded work and readbacks still
// meet (with the staging copies' barriers checked by synchronization validation).
TEST_F(GpuLayerTest, StagingPathWhereDeviceMemoryIsNotMapped) {
  gpu::ContextOptions options;
  options.validation = true;
  options.stagingOnly = true;
  gpu::Context staged(options);
  gpu::Buffer device(staged, 1024 * 4, gpu::MemoryUse::Device, "device");
  gpu::Buffer upload(staged, 64, gpu::MemoryUse::Upload, "upload");
  EXPECT_FALSE(device.hostMapped());
  EXPECT_TRUE(upload.hostMapped());
  std::vector<std::uint32_t> v(1024);
  for (std::uint32_t i = 0; i < v.size(); ++i) v[i] = i * 2654435761u;
  device.upload(v);
  EXPECT_EQ(device.readback<std::uint32_t>(1024), v);
  gpu::CommandRecorder rec(staged);
  rec.begin();
  rec.fill(device, 7u, 64, 64);
  rec.end();
  rec.submitAndWait();
  const auto got = device.readback<std::uint32_t>(48);
  EXPECT_EQ(got[15], v[15]);
  EXPECT_EQ(got[16], 7u);
  EXPECT_EQ(got[31], 7u);
  EXPECT_EQ(got[32], v[32]);
  const auto messages = staged.takeValidationMessages();
  for (const auto& m : messages) ADD_FAILURE() << m;
}

}  // namespace
}  // namespace hemo::test

namespace hemo::test {
namespace {

// A requested validation layer that the loader cannot find is a clear error, not a crash.
TEST_F(GpuLayerTest, MissingValidationLayerIsAClearError) {
  const char* old = std::getenv("VK_LAYER_PATH");
  const std::string saved = old ? old : "";
  ::setenv("VK_LAYER_PATH", "/nonexistent-hemo-layer-dir", 1);
  gpu::ContextOptions options;
  options.validation = true;
  std::string message;
  try {
    gpu::Context other(options);
  } catch (const gpu::GpuError& e) {
    message = e.what();
  }
  if (old) {
    ::setenv("VK_LAYER_PATH", saved.c_str(), 1);
  } else {
    ::unsetenv("VK_LAYER_PATH");
  }
  EXPECT_NE(message.find("VK_LAYER_KHRONOS_validation"), std::string::npos) << "got: " << message;
}

}  // namespace
}  // namespace hemo::test
