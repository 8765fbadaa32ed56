// hemo-bench SUITE [--json FILE] [--device SEL] [--repeat N] [--case NAME] [--scene FILE] [--until S]
// Benchmarks (not tests): GPU times from timestamp queries, medians over repeated runs after a
// warm-up. Suites: primitives, accuracy, table1, render (surface field, extraction and draw),
// speed (a whole scene, the dam break by default, run from start to end), scale (a 3D dam
// break from 0.1M to 64M particles), device (what hemo reads from the device).
#include "cli.hpp"
#include "hemo/io/atomic_file.hpp"
#include "hemo/gpu/pipeline_cache.hpp"
#include "hemo/gpu/primitives.hpp"
#include "hemo/reference/marching_cubes.hpp"
#include "hemo/render/renderer.hpp"
#include "hemo/reference/published.hpp"
#include "hemo/scene/builders.hpp"
#include "hemo/scene/scene.hpp"
#include "hemo/sim/neighbour_grid.hpp"
#include "hemo/sim/probes.hpp"
#include "hemo/sim/simulation.hpp"
#include "hemo/surface/marching_cubes.hpp"

#include "interface/bench.h"
#include "interface/scan.h"

#include <nlohmann/json.hpp>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <numbers>
#include <random>

#include <malloc.h>
#include <sys/resource.h>
#include <unistd.h>

namespace {

using hemo::gpu::CommandRecorder;
using hemo::gpu::Context;
using hemo::gpu::TimestampQueries;
using Json = nlohmann::json;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

// Runs `record` (one measured region between two timestamps) repeat times after one warm-up;
// returns the median GPU milliseconds. `prepare` runs on the host before every repetition.
template <class Prepare, class Record>
double timeGpu(Context& ctx, int repeat, Prepare prepare, Record record) {
  CommandRecorder rec(ctx);
  TimestampQueries ts(ctx, 2);
  std::vector<double> ms;
  for (int r = 0; r <= repeat; ++r) {
    prepare();
    rec.begin();
    ts.reset(rec);
    ts.mark(rec, "start");
    record(rec);
    ts.mark(rec, "end");
    rec.end();
    rec.submitAndWait();
    if (r > 0) ms.push_back(ts.totalMs());
  }
  return median(ms);
}

Json primitives(Context& ctx, int repeat) {
  Json rows = Json::array();
  std::mt19937_64 rng(12345);
  auto row = [&](const std::string& op, std::uint64_t n, double ms, Json extra = Json::object()) {
    Json r = {{"op", op}, {"n", n}, {"ms", ms}};
    r.update(extra);
    std::printf("%-16s %10llu %10.3f ms  %8.2f ns/item  %s\n", op.c_str(), static_cast<unsigned long long>(n), ms,
                n ? ms * 1e6 / double(n) : 0.0, extra.empty() ? "" : extra.dump().c_str());
    std::fflush(stdout);
    rows.push_back(r);
  };
  std::printf("%-16s %10s %13s\n", "op", "n", "median GPU");

  // Empty submit + fence wait: a host round trip, measured on the host clock.
  {
    CommandRecorder rec(ctx);
    std::vector<double> ms;
    for (int r = 0; r <= 50; ++r) {
      rec.begin();
      rec.end();
      const auto t0 = std::chrono::steady_clock::now();
      rec.submitAndWait();
      const auto t1 = std::chrono::steady_clock::now();
      if (r > 0) ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    }
    row("empty_submit", 0, median(ms), {{"clock", "host"}});
  }
  // The fixed cost of one dispatch plus a barrier: 1000 one-workgroup dispatches of a shader
  // that reads 64 values and writes nothing (bench/dispatch_probe.comp) in one command buffer.
  {
    hemo::gpu::Buffer data(ctx, 64 * 4, hemo::gpu::MemoryUse::Device, "dispatch probe");
    data.upload(std::vector<std::uint32_t>(64, 0u));
    const std::uint32_t n = 64;
    const auto& probe = ctx.pipelines().get({"bench/dispatch_probe", HEMO_BENCH_PROBE_BINDING_COUNT, sizeof(n), 64, {}});
    const auto set = probe.makeSet({{HEMO_BENCH_PROBE_BINDING_IN, &data}});
    const int k = 1000;
    const double ms = timeGpu(ctx, repeat, [] {}, [&](CommandRecorder& rec) {
      for (int i = 0; i < k; ++i) {
        rec.dispatch(probe, set, n, probe.groupsFor(n));
        rec.computeToCompute();
      }
    });
    row("dispatch", 1, ms / k, {{"clock", "gpu"}, {"dispatches_timed", k}});
    // The same dispatches without the barrier between them, and indirect dispatches of zero
    // workgroups (a closed dispatch gate, engine/gpu/gate.cpp) with their barriers: what a
    // step pays for each dispatch it records, and for each one a gate skips.
    const double loose = timeGpu(ctx, repeat, [] {}, [&](CommandRecorder& rec) {
      for (int i = 0; i < k; ++i) rec.dispatch(probe, set, n, probe.groupsFor(n));
      rec.computeToCompute();
    });
    row("dispatch_nobar", 1, loose / k, {{"clock", "gpu"}, {"dispatches_timed", k}});
    hemo::gpu::Buffer zero(ctx, 16, hemo::gpu::MemoryUse::Device, "zero dispatch arguments");
    zero.upload(std::vector<std::uint32_t>{0, 1, 1, 0});
    const double closed = timeGpu(ctx, repeat, [] {}, [&](CommandRecorder& rec) {
      for (int i = 0; i < k; ++i) {
        rec.dispatchIndirect(probe, set, n, zero, 0);
        rec.computeToCompute();
      }
    });
    row("dispatch_closed", 0, closed / k, {{"clock", "gpu"}, {"dispatches_timed", k}});
  }

  // What an SPH pair loop's memory accesses cost (bench/pair_gather.comp): a periodic cubic
  // lattice of 22^3 particles in lattice order, each listing the lattice points within
  // 2.86 spacings (the list radius at h/dp = 1.3 with a skin of 0.1: 92 entries; a disordered
  // fluid lists ~100) in both layouts (interface/sph.h), and loading 0..4 vec4 per
  // neighbour. The step from one row to the next is the price of one more per-pair gather.
  {
    const int side = 22;
    const auto n = static_cast<std::uint32_t>(side * side * side);
    std::vector<glm::ivec3> offsets;
    for (int z = -3; z <= 3; ++z)
      for (int y = -3; y <= 3; ++y)
        for (int x = -3; x <= 3; ++x)
          if ((x || y || z) && x * x + y * y + z * z < 2.86 * 2.86) offsets.emplace_back(x, y, z);
    const auto entries = static_cast<std::uint32_t>(offsets.size());
    std::vector<std::uint32_t> list(std::size_t(n) * entries);
    auto wrap = [&](int v) { return (v % side + side) % side; };
    for (std::uint32_t i = 0; i < n; ++i) {
      const glm::ivec3 p(int(i) % side, (int(i) / side) % side, int(i) / (side * side));
      for (std::uint32_t k = 0; k < entries; ++k) {
        const glm::ivec3 q = p + offsets[k];
        list[std::size_t(k) * n + i] = static_cast<std::uint32_t>(wrap(q.x) + side * (wrap(q.y) + side * wrap(q.z)));
      }
    }
    std::vector<glm::vec4> values(n);
    for (auto& v : values) v = glm::vec4(float(rng() % 1000) * 1e-3f, 0.1f, 0.2f, 1.0f);
    hemo::gpu::Buffer listBuffer(ctx, list.size() * 4, hemo::gpu::MemoryUse::Device, "pair_gather list");
    listBuffer.upload(list);
    std::vector<hemo::gpu::Buffer> data;
    for (int b = 0; b < 5; ++b) {
      data.emplace_back(ctx, std::uint64_t(n) * 16, hemo::gpu::MemoryUse::Device, "pair_gather data");
      data.back().upload(values);
    }
    struct Push {
      std::uint32_t n, entries;
    };
    std::vector<std::uint32_t> contiguous(list.size());
    for (std::uint32_t i = 0; i < n; ++i)
      for (std::uint32_t k = 0; k < entries; ++k) contiguous[std::size_t(i) * entries + k] = list[std::size_t(k) * n + i];
    hemo::gpu::Buffer contiguousBuffer(ctx, list.size() * 4, hemo::gpu::MemoryUse::Device, "pair_gather list");
    contiguousBuffer.upload(contiguous);
    // Rows: both layouts with vec4 gathers, then the interleaved layout with narrow gathers
    // and with a workgroup-uniform index (variants of bench/pair_gather.comp).
    const std::uint32_t runs[4][2] = {{0, 0}, {1, 0}, {0, 1}, {0, 2}};  // layout, variant
    const char* variantNames[3] = {"vec4", "narrow (2nd float, 3rd vec2)", "uniform index"};
    for (const auto& run : runs)
    for (std::uint32_t loads = 0; loads <= 4; ++loads) {
      const std::uint32_t layout = run[0], variant = run[1];
      const auto& probe =
          ctx.pipelines().get({"bench/pair_gather", HEMO_BENCH_BINDING_COUNT, sizeof(Push), 64, {loads, layout, variant}});
      const auto set = probe.makeSet({{HEMO_BENCH_BINDING_LIST, layout ? &contiguousBuffer : &listBuffer}, {HEMO_BENCH_BINDING_A, &data[0]},
                                      {HEMO_BENCH_BINDING_B, &data[1]}, {HEMO_BENCH_BINDING_C, &data[2]},
                                      {HEMO_BENCH_BINDING_D, &data[3]}, {HEMO_BENCH_BINDING_OUT, &data[4]}});
      const Push push{n, entries};
      const double ms = timeGpu(ctx, repeat, [] {}, [&](CommandRecorder& rec) {
        rec.dispatch(probe, set, push, probe.groupsFor(n));
      });
      row("pair_gather", std::uint64_t(n) * entries, ms,
          {{"vec4_loads_per_pair", loads}, {"list_layout", layout ? "contiguous" : "interleaved"},
           {"gathers", variantNames[variant]}, {"particles", n}, {"entries_per_particle", entries}});
    }
    // The same loop reading the list and the data as uniform texel buffers
    // (bench/pair_gather_texel.comp), both layouts.
    for (std::uint32_t layout = 0; layout <= 2; ++layout)
    for (std::uint32_t loads = 0; loads <= 4; ++loads) {
      const std::uint32_t texels = 0x1fu;  // slots LIST and A..D
      const auto& probe = ctx.pipelines().get(
          {"bench/pair_gather_texel", HEMO_BENCH_BINDING_COUNT, sizeof(Push), 64, {loads, layout & 1u, layout >> 1}, 0u, texels});
      using hemo::gpu::texelBinding;
      const auto set = probe.makeSet({texelBinding(HEMO_BENCH_BINDING_LIST, layout ? &contiguousBuffer : &listBuffer, VK_FORMAT_R32_UINT),
                                      texelBinding(HEMO_BENCH_BINDING_A, &data[0], VK_FORMAT_R32G32B32A32_SFLOAT),
                                      texelBinding(HEMO_BENCH_BINDING_B, &data[1], VK_FORMAT_R32G32B32A32_SFLOAT),
                                      texelBinding(HEMO_BENCH_BINDING_C, &data[2], VK_FORMAT_R32G32B32A32_SFLOAT),
                                      texelBinding(HEMO_BENCH_BINDING_D, &data[3], VK_FORMAT_R32G32B32A32_SFLOAT),
                                      {HEMO_BENCH_BINDING_OUT, &data[4]}});
      const Push push{n, entries};
      const double ms = timeGpu(ctx, repeat, [] {}, [&](CommandRecorder& rec) {
        rec.dispatch(probe, set, push, probe.groupsFor(n));
      });
      row("pair_gather", std::uint64_t(n) * entries, ms,
          {{"vec4_loads_per_pair", loads}, {"list_layout", layout ? "contiguous" : "interleaved"},
           {"gathers", layout == 2 ? "texel buffer, uniform index" : "texel buffer"}, {"particles", n}, {"entries_per_particle", entries}});
    }
    // Clusters (bench/pair_gather_cluster.comp): an invocation owns 1, 2, 4 or 8 particles and
    // evaluates each fetched entry against all of them, over lists as long as one particle's.
    // The cost per pair evaluated, against the fetches it saves; a real cluster list is the
    // union of its particles' (1.27, 1.59 and 1.98 times one list for 2, a 2 x 2 square and a
    // 2 x 2 x 2 cube of lattice points).
    const char* bodyNames[3] = {"few flops", "density", "forces"};
    for (const std::uint32_t body : {0u, 1u, 2u})
    for (const std::uint32_t cluster : {1u, 2u, 4u, 8u}) {
      const std::uint32_t loads = body == 2u ? 2u : 1u;
      const std::uint32_t texels = 0x1fu;
      const auto& probe = ctx.pipelines().get(
          {"bench/pair_gather_cluster", HEMO_BENCH_BINDING_COUNT, sizeof(Push), 64, {loads, cluster, body}, 0u, texels});
      using hemo::gpu::texelBinding;
      const auto set = probe.makeSet({texelBinding(HEMO_BENCH_BINDING_LIST, &contiguousBuffer, VK_FORMAT_R32_UINT),
                                      texelBinding(HEMO_BENCH_BINDING_A, &data[0], VK_FORMAT_R32G32B32A32_SFLOAT),
                                      texelBinding(HEMO_BENCH_BINDING_B, &data[1], VK_FORMAT_R32G32B32A32_SFLOAT),
                                      texelBinding(HEMO_BENCH_BINDING_C, &data[2], VK_FORMAT_R32G32B32A32_SFLOAT),
                                      texelBinding(HEMO_BENCH_BINDING_D, &data[3], VK_FORMAT_R32G32B32A32_SFLOAT),
                                      {HEMO_BENCH_BINDING_OUT, &data[4]}});
      const Push push{n / cluster, entries};
      const double ms = timeGpu(ctx, repeat, [] {}, [&](CommandRecorder& rec) {
        rec.dispatch(probe, set, push, probe.groupsFor(n / cluster));
      });
      row("pair_gather", std::uint64_t(n / cluster) * cluster * entries, ms,
          {{"vec4_loads_per_pair", loads}, {"list_layout", "contiguous"}, {"gathers", "texel buffer"},
           {"cluster", cluster}, {"pair_body", bodyNames[body]}, {"particles", n / cluster * cluster}, {"entries_per_particle", entries}});
    }
  }

  // What a per-lane store costs (bench/store_scatter.comp): 10,648 invocations (the
  // pair_gather lattice's count) x 92 stores, through a storage buffer or a storage texel
  // buffer, both list layouts, every store kept or a candidate's advance under a data mask.
  {
    const std::uint32_t n = 10648, entries = 92;
    hemo::gpu::Buffer out(ctx, std::uint64_t(n) * entries * 4, hemo::gpu::MemoryUse::Device, "store_scatter out");
    struct Push {
      std::uint32_t n, entries;
    };
    for (std::uint32_t texel = 0; texel <= 1; ++texel)
    for (std::uint32_t layout = 0; layout <= 1; ++layout)
    for (std::uint32_t masked = 0; masked <= 1; ++masked) {
      const auto& probe = ctx.pipelines().get({"bench/store_scatter", HEMO_BENCH_STORE_BINDING_COUNT, sizeof(Push), 64,
                                               {layout, texel, masked}, 0u, 0u, 1u << HEMO_BENCH_STORE_BINDING_IMAGE});
      const auto set = probe.makeSet({{HEMO_BENCH_STORE_BINDING_OUT, &out},
                                      hemo::gpu::texelBinding(HEMO_BENCH_STORE_BINDING_IMAGE, &out, hemo::gpu::texel::kUint)});
      const Push push{n, entries};
      const double ms = timeGpu(ctx, repeat, [] {}, [&](CommandRecorder& rec) {
        rec.dispatch(probe, set, push, probe.groupsFor(n));
      });
      row("store_scatter", std::uint64_t(n) * entries, ms,
          {{"through", texel ? "storage texel buffer" : "storage buffer"}, {"list_layout", layout ? "contiguous" : "interleaved"},
           {"slot", masked ? "advances under a data mask" : "every store kept"}, {"particles", n}, {"entries_per_particle", entries}});
    }
  }

  // What a parameter read costs (bench/param_read.comp): one vec4 per loop iteration at an
  // address that is the same for the whole dispatch, from a storage buffer, a uniform buffer
  // or push constants, against the loop without reads. 20,000 invocations (a scene's
  // particle count) x 64 reads.
  {
    const std::uint32_t n = 20000, reads = 64;
    struct Push {
      glm::vec4 p[HEMO_BENCH_PARAM_VEC4S - 1];
      std::uint32_t n, reads;
    };
    static_assert(sizeof(Push) == 120);
    Push push{};
    std::vector<glm::vec4> values(HEMO_BENCH_PARAM_VEC4S);
    for (std::uint32_t k = 0; k < HEMO_BENCH_PARAM_VEC4S; ++k) {
      values[k] = glm::vec4(0.999f, 1e-3f * float(k), 0.5f, 0.25f);
      if (k + 1 < HEMO_BENCH_PARAM_VEC4S) push.p[k] = values[k];
    }
    push.n = n;
    push.reads = reads;
    hemo::gpu::Buffer params(ctx, values.size() * 16, hemo::gpu::MemoryUse::Device, "param_read params");
    params.upload(values);
    hemo::gpu::Buffer out(ctx, std::uint64_t(n) * 16, hemo::gpu::MemoryUse::Device, "param_read out");
    const char* sources[4] = {"none", "storage buffer", "uniform buffer", "push constants"};
    for (std::uint32_t variant = 0; variant < 4; ++variant) {
      const auto& probe = ctx.pipelines().get({"bench/param_read", HEMO_BENCH_PARAM_BINDING_COUNT, sizeof(Push), 64,
                                               {variant}, 1u << HEMO_BENCH_PARAM_BINDING_UNIFORM});
      const auto set = probe.makeSet({{HEMO_BENCH_PARAM_BINDING_STORAGE, &params},
                                      {HEMO_BENCH_PARAM_BINDING_UNIFORM, &params},
                                      {HEMO_BENCH_PARAM_BINDING_OUT, &out}});
      const double ms = timeGpu(ctx, repeat, [] {}, [&](CommandRecorder& rec) {
        rec.dispatch(probe, set, push, probe.groupsFor(n));
      });
      row("param_read", std::uint64_t(n) * reads, ms,
          {{"source", sources[variant]}, {"invocations", n}, {"reads_per_invocation", reads}});
    }
  }

  for (std::uint64_t n : {10000ull, 100000ull, 1000000ull, 16000000ull}) {
    std::vector<std::uint32_t> v(n);
    for (auto& x : v) x = static_cast<std::uint32_t>(rng() & 0xff);
    hemo::gpu::Buffer data(ctx, n * 4, hemo::gpu::MemoryUse::Device, "scan data");
    hemo::gpu::PrefixScan scan(ctx, data, n);
    data.upload(v);
    const double ms = timeGpu(ctx, repeat, [] {}, [&](CommandRecorder& rec) { scan.record(rec, n); });
    row("scan", n, ms);
  }

  for (std::uint32_t keyBits : {16u, 32u}) {
    for (std::uint64_t n : {10000ull, 100000ull, 1000000ull}) {
      std::vector<glm::uvec2> v(n);
      for (std::uint64_t i = 0; i < n; ++i) {
        v[i] = {static_cast<std::uint32_t>(rng()) & static_cast<std::uint32_t>((1ull << keyBits) - 1),
                static_cast<std::uint32_t>(i)};
      }
      hemo::gpu::Buffer pairs(ctx, n * 8, hemo::gpu::MemoryUse::Device, "sort pairs");
      hemo::gpu::RadixSort sort(ctx, pairs, n);
      const double ms = timeGpu(ctx, repeat, [&] { pairs.upload(v); },
                                [&](CommandRecorder& rec) { sort.record(rec, n, keyBits); });
      row("sort", n, ms, {{"key_bits", keyBits}});
    }
  }

  // Full neighbour structure (hash, scan of cell counts, sort, reorder) for a jittered
  // lattice of spacing dp with cells of 2 dp (8 particles per cell on average), as SPH uses it.
  for (std::uint64_t n : {10000ull, 100000ull, 1000000ull}) {
    const float dp = 0.01f;
    const auto side = static_cast<std::uint32_t>(std::ceil(std::cbrt(double(n))));
    std::vector<glm::vec4> pos(n), vel(n, glm::vec4(0.0f));
    std::uniform_real_distribution<float> jitter(-0.25f * dp, 0.25f * dp);
    for (std::uint64_t i = 0; i < n; ++i) {
      const float x = float(i % side), y = float((i / side) % side), z = float(i / (side * side));
      // shuffle-free but not cell-ordered: z-major lattice order, jittered
      pos[i] = glm::vec4((x + 0.5f) * dp + jitter(rng), (y + 0.5f) * dp + jitter(rng), (z + 0.5f) * dp + jitter(rng), 1.0f);
    }
    std::shuffle(pos.begin(), pos.end(), rng);  // worst case: no locality from the last step
    hemo::sim::ParticleStore store(ctx, static_cast<std::uint32_t>(n));
    const auto spec = hemo::sim::GridSpec::covering({0, 0, 0}, glm::vec3(float(side) * dp), 2.0f * dp);
    hemo::sim::NeighbourGrid grid(ctx, spec, store);
    for (const bool presorted : {false, true}) {
      // Shuffled input is the worst case; "previous_step" is the steady state of a simulation,
      // where the particles are still in the cell order of the last step.
      CommandRecorder rec(ctx);
      TimestampQueries ts(ctx, 8);
      std::vector<double> total;
      std::map<std::string, std::vector<double>> stages;
      for (int r = 0; r <= repeat; ++r) {
        if (!presorted || r == 0) store.upload(pos, vel);
        rec.begin();
        ts.reset(rec);
        ts.mark(rec, "start");
        grid.record(rec, static_cast<std::uint32_t>(n), &ts);
        rec.end();
        rec.submitAndWait();
        if (r == 0) continue;  // warm-up (first use compiles the shaders on some drivers)
        total.push_back(ts.totalMs());
        for (const auto& [stage, ms] : ts.stageMs()) stages[stage].push_back(ms);
      }
      Json stageMs = Json::object();
      for (const auto& [stage, ms] : stages) stageMs[stage] = median(ms);
      row("neighbour_build", n, median(total),
          {{"cells", spec.cellCount()}, {"order", presorted ? "previous_step" : "shuffled"}, {"stage_ms", stageMs}});
    }
  }
  return rows;
}

// ---- accuracy: error against analytic / published results, next to what it cost -----------

// Runs `sim` to `until` (s) and returns the wall seconds spent.
double runTo(hemo::sim::Simulation& sim, double until) {
  hemo::sim::RunOptions opt;
  opt.until = until;
  return sim.run(opt).wallSeconds;
}

// Median GPU ms of one step (sum of the stages), measured after the run.
double gpuStepMs(hemo::sim::Simulation& sim) {
  double ms = 0.0;
  for (const auto& [stage, t] : sim.profileStep(5)) ms += t;
  return ms;
}

Json accuracy(Context& ctx, const std::string& only, const std::string& solverOnly) {
  // (--solver: only the runs of that pressure solver)
  auto skip = [&](bool dfsph) { return !solverOnly.empty() && solverOnly != (dfsph ? "dfsph" : "wcsph"); };
  using hemo::sim::Integrator;
  Json rows = Json::array();
  std::printf("%-12s %-6s %10s %5s %-17s %-11s %10s %-28s %10s %8s %12s %11s\n", "case", "solver", "spacing_m", "h/dp", "integrator",
              "density", "error", "metric", "ms/step", "steps", "wall s/sim s", "x real time");
  // One row per run; the scene supplies spacing, smoothing ratio and integrator.
  auto row = [&](const std::string& name, const hemo::scene::Scene& scene, double error, const std::string& metric,
                 hemo::sim::Simulation& sim, double wall) {
    const char* integ = scene.sph.integrator == Integrator::Rk2Midpoint ? "rk2_midpoint" : "symplectic_euler";
    const char* density = scene.sph.densityMethod == hemo::sim::DensityMethod::Continuity ? "continuity" : "summation";
    const std::uint64_t steps = sim.steps();
    const double wallPerSim = wall / sim.time();
    const double msPerStep = gpuStepMs(sim);
    const char* solver = scene.sph.pressureSolver == hemo::sim::PressureSolver::Dfsph ? "dfsph" : "wcsph";
    std::printf("%-12s %-6s %10.6f %5.2f %-17s %-11s %10.4f %-28s %10.2f %8llu %12.1f %11.4f\n", name.c_str(), solver,
                scene.sph.spacing, scene.sph.smoothingRatio, integ, density, error, metric.c_str(), msPerStep,
                static_cast<unsigned long long>(steps), wallPerSim, 1.0 / wallPerSim);
    std::fflush(stdout);
    rows.push_back({{"case", name}, {"spacing_m", scene.sph.spacing}, {"smoothing_ratio", scene.sph.smoothingRatio},
                    {"integrator", integ}, {"density", density}, {"error", error}, {"error_metric", metric}, {"ms_per_step", msPerStep},
                    {"steps", steps}, {"wall_s_per_sim_s", wallPerSim},
                    // the fluid's pressure solver (wcsph or dfsph), and simulated seconds per
                    // wall-clock second (1: keeps up with the clock)
                    {"solver", solver}, {"real_time_factor", 1.0 / wallPerSim}});
    if (scene.sph.pressureSolver == hemo::sim::PressureSolver::Dfsph) {
      const hemo::sim::PressureSolveStats st = sim.solver().readPressureSolveStats();
      rows.back()["solver_iterations_mean"] = st.meanIterations();
      rows.back()["solver_iterations_max"] = st.maxIterations;
      rows.back()["solver_cap_hits"] = st.capHits;
    }
  };
  const Integrator integrators[] = {Integrator::SymplecticEuler, Integrator::Rk2Midpoint};

  if (only.empty() || only == "hydrostatic") {
    // A 0.12 m column on a 0.08 m square floor, filled body-centred, damped settling to 0.8 s,
    // then the floor load averaged over 0.9 and 1.0 s against rho g H (the test's measurement);
    // also the largest drift from 0.8 to 1.0 s, of all particles and of those more than 2h
    // below the free surface.
    for (double dp : {0.02, 0.01, 0.008}) {
      struct Variant {
        Integrator integrator;
        hemo::sim::DensityMethod density;
        bool dfsph = false;
      };
      for (const Variant v : {Variant{Integrator::SymplecticEuler, hemo::sim::DensityMethod::Summation},
                              Variant{Integrator::Rk2Midpoint, hemo::sim::DensityMethod::Summation},
                              Variant{Integrator::SymplecticEuler, hemo::sim::DensityMethod::Continuity},
                              Variant{Integrator::Rk2Midpoint, hemo::sim::DensityMethod::Continuity},
                              Variant{Integrator::SymplecticEuler, hemo::sim::DensityMethod::Summation, true}}) {
        if (skip(v.dfsph)) continue;
        const Integrator integrator = v.integrator;
        const std::string text = R"({"scene": "hydrostatic_bench", "particles": {"spacing_m": )" + std::to_string(dp) +
                                 R"(}, "fluid": {"viscosity_pa_s": 0.5, "expected_max_speed_m_s": 1.5,
          "blocks": [{"min_m": [0, 0, 0], "max_m": [0.08, 0.08, 0.12], "lattice": "bcc"}]},
          "boundary": {"tanks": [{"min_m": [0, 0, 0], "max_m": [0.08, 0.08, 0.13], "layers": 3}]},
          "time": {"steps_per_batch": 128, "settle_damping_1_s": 30, "settle_until_s": 0.8},
          "domain": {"min_m": [-0.06, -0.06, -0.06], "max_m": [0.14, 0.14, 0.2]}})";
        hemo::scene::Scene scene = hemo::scene::parseScene(text, "hydrostatic_bench");
        scene.sph.integrator = integrator;
        scene.sph.densityMethod = v.density;
        if (v.dfsph) {
          scene.sph.pressureSolver = hemo::sim::PressureSolver::Dfsph;
          scene.sph.maxTimeStep = 0.004f;
        }
        hemo::sim::Simulation sim(ctx, scene);
        double wall = runTo(sim, 0.8), load = 0.0;
        const hemo::sim::Snapshot settled = sim.snapshot();
        double top = -1e30;
        for (std::uint32_t i = 0; i < sim.fluidParticles(); ++i) top = std::max(top, double(settled.positions[i].z));
        if (v.dfsph) {
          // DFSPH's pressure is each step's impulse over its dt: the load on the whole tank
          // (the side walls' mirrored pressure pushes the floor's corners down), averaged over
          // every step from 0.9 to 1.0 s weighted by its dt (DfsphTest.ColumnLoadsTheFloorWithRhoGH)
          wall += runTo(sim, 0.9);
          double span = 0.0;
          while (sim.time() < 1.0) {
            const double before = sim.time();
            hemo::sim::RunOptions one;
            one.steps = 1;
            wall += sim.run(one).wallSeconds;
            const double dt = sim.time() - before;
            load += hemo::sim::floorLoad(sim.snapshot(), sim.fluidParticles(), scene.sph.h(), 1.0e9f) / (0.08 * 0.08) * dt;
            span += dt;
          }
          load /= span;
        } else {
          for (double t : {0.9, 1.0}) {
            wall += runTo(sim, t);
            load += hemo::sim::floorLoad(sim.snapshot(), sim.fluidParticles(), scene.sph.h()) / (0.08 * 0.08) / 2.0;
          }
        }
        const double expect = 1000.0 * 9.81 * 0.12;
        row("hydrostatic", scene, std::abs(load - expect) / expect,
            v.dfsph ? "rel_error_tank_load_step_mean" : "rel_error_floor_pressure", sim, wall);
        const hemo::sim::Snapshot last = sim.snapshot();
        rows.back()["drift_dp"] = hemo::sim::largestDisplacement(settled, last) / dp;
        rows.back()["deep_drift_dp"] = hemo::sim::largestDisplacement(settled, last, top - 2.0 * scene.sph.h()) / dp;
        std::printf("    drift 0.8-1.0 s: %.3f dp (all), %.3f dp (deeper than 2h)\n", double(rows.back()["drift_dp"]),
                    double(rows.back()["deep_drift_dp"]));
      }
    }
  }
  if (only.empty() || only == "poiseuille") {
    // scenes/poiseuille.json at 10, 20 and 40 particles across; RMS error of the layer-mean
    // velocity against the start-up series at t = 1 s (steady), relative to the peak.
    const double L = 1e-3, F = 2e-4, nu = 1e-6, t = 1.0;
    for (int across : {10, 20, 40}) {
      for (int variant = 0; variant < 3; ++variant) {  // symplectic Euler, RK2, DFSPH (symplectic Euler)
        if (skip(variant == 2)) continue;
        hemo::scene::Scene scene = hemo::scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/scenes/poiseuille.json");
        scene.sph.spacing = float(L / across);
        scene = hemo::scene::withSlabThickness(scene, 0, 9);  // periodic extents of 9 dp (three list radii)
        scene = hemo::scene::withSlabThickness(scene, 1, 9);
        scene.sph.integrator = integrators[variant == 1 ? 1 : 0];
        if (variant == 2) scene.sph.pressureSolver = hemo::sim::PressureSolver::Dfsph;
        hemo::sim::Simulation sim(ctx, scene);
        const double wall = runTo(sim, t);
        const double error = hemo::sim::poiseuilleProfileError(sim.snapshot(), sim.fluidParticles(), scene.sph.spacing, L,
                                                               F, nu, t);
        row("poiseuille", scene, error, "rms_over_peak_at_1s", sim, wall);
      }
    }
  }
  if (only.empty() || only == "carreau_tube") {
    // Non-Newtonian blood (NonNewtonianFlowTest): a periodic tube of R = 2 mm driven by a body
    // force of 10 m/s^2, Carreau-Yasuda viscosity from 0.2 Pa s at rest to 0.05 (lambda 0.05 s,
    // n = 0.3, a = 2), at 4 and 8 particles across the radius (6 and 3 mm long: the least
    // period is 2.5 list radii). The error is the RMS over four radial bins of the mean axial
    // velocity (averaged over snapshots every 2 ms from 0.102 to 0.11 s) against the law's
    // steady profile (sim::carreauTubeProfile), over its peak. WCSPH only (the force pass is
    // the solvers' common part).
    const double R = 0.002, G = 10.0;
    constexpr int kBins = 4;
    for (int across : {4, 8}) {
      if (skip(false)) continue;
      const double dp = R / across, length = across == 4 ? 0.006 : 0.003;
      const std::string text = R"({"scene": "carreau_tube_bench", "particles": {"spacing_m": )" + std::to_string(dp) +
                               R"(}, "fluid": {"expected_max_speed_m_s": 0.2, "rheology": {"model": "carreau_yasuda",
          "zero_shear_viscosity_pa_s": 0.2, "infinite_shear_viscosity_pa_s": 0.05, "relaxation_time_s": 0.05,
          "power_index": 0.3, "yasuda_exponent": 2.0}},
        "vessel": {"shape": "tube", "length_m": )" + std::to_string(length) +
                               R"(, "radius_m": 0.002, "point_mass_kg": 1e-3, "stiffness_N_m": 50.0, "damping_N_s_m": 0.005},
        "forces": {"gravity_m_s2": [0, 0, 0], "body_force_m_s2": [10.0, 0, 0]},
        "time": {"steps_per_batch": 64},
        "domain": {"min_m": [0.0, -0.004, -0.004], "max_m": [)" + std::to_string(length) +
                               R"(, 0.004, 0.004], "periodic": ["x"]}})";
      const hemo::scene::Scene scene = hemo::scene::parseScene(text, "carreau_tube_bench");
      hemo::sim::Simulation sim(ctx, scene);
      double wall = runTo(sim, 0.1);
      std::vector<double> profile(kBins, 0.0);
      for (int k = 1; k <= 5; ++k) {
        wall += runTo(sim, 0.1 + 0.002 * k);
        const std::vector<double> p = hemo::sim::radialProfile(sim.snapshot(), R, kBins);
        for (int b = 0; b < kBins; ++b) profile[std::size_t(b)] += p[std::size_t(b)] / 5.0;
      }
      const std::vector<double> exact = hemo::sim::carreauTubeProfile(scene.sph.carreau, scene.sph.restDensity, G, R, kBins);
      double sq = 0.0;
      for (int b = 0; b < kBins; ++b) sq += std::pow(profile[std::size_t(b)] - exact[std::size_t(b)], 2.0) / kBins;
      row("carreau_tube", scene, std::sqrt(sq) / exact[0], "rms_over_peak_steady", sim, wall);
    }
  }
  if (only.empty() || only == "open_tube") {
    // Open ends (OpenEndsTest.PressureDropDrivesPoiseuilleFlow): a tube of R = 2 mm, 18 mm long
    // with 3 mm buffers at both ends, its flow driven by a pressure inlet 300 Pa above a
    // pressure outlet through blood of 0.1 Pa s, at 4 and 8 particles across the radius. The
    // error is |mean speed / Poiseuille's - 1| in the lumen's middle (more than 4 dp from
    // either plane), the mean speed over the particles against dp R^2 (1 - r^2 / R^2) / (4 mu L)
    // at their radii, averaged over snapshots every 0.5 ms from 0.0305 to 0.035 s. WCSPH only.
    const double R = 0.002, mu = 0.1, drop = 300.0;
    for (int across : {4, 8}) {
      if (skip(false)) continue;
      const double dp = R / across;
      const std::string text = R"({"scene": "open_tube_bench", "particles": {"spacing_m": )" + std::to_string(dp) +
                               R"(, "list_skin": 0.25, "neighbour_capacity": 176},
        "fluid": {"expected_max_speed_m_s": 0.5, "density_kg_m3": 1060.0, "viscosity_pa_s": 0.1, "background_pressure_Pa": 200.0},
        "vessel": {"shape": "tube", "length_m": 0.018, "radius_m": 0.002, "point_mass_kg": 2e-4, "stiffness_N_m": 200.0,
                   "damping_N_s_m": 0.01,
                   "inflow": {"profile": "parabolic", "driven_by": "pressure", "pressure_Pa": 300.0, "zone_length_m": 0.003,
                              "ramp_s": 0.005},
                   "outlet": {"condition": "pressure"}},
        "forces": {"gravity_m_s2": [0, 0, 0]},
        "time": {"steps_per_batch": 64},
        "domain": {"min_m": [0.0, -0.004, -0.004], "max_m": [0.018, 0.004, 0.004]}})";
      const hemo::scene::Scene scene = hemo::scene::parseScene(text, "open_tube_bench");
      const hemo::sim::Inflow& in = *scene.vessel->inflow;
      const double outletPlane = double(in.open->outlets[0].origin.x) - in.open->outlets[0].length;
      const double lo = in.zoneEnd + 4.0 * dp, hi = outletPlane - 4.0 * dp;
      const double G = drop / (outletPlane - in.zoneEnd);
      hemo::sim::Simulation sim(ctx, scene);
      double wall = runTo(sim, 0.03);
      double speed = 0.0, want = 0.0;
      for (int k = 1; k <= 10; ++k) {
        wall += runTo(sim, 0.03 + 0.0005 * k);
        const hemo::sim::Snapshot snap = sim.snapshot();
        for (std::size_t i = 0; i < snap.positions.size(); ++i) {
          const glm::vec4 p = snap.positions[i];
          if (snap.velocities[i].w != 0.0f || p.x < lo || p.x >= hi) continue;
          const double r2 = std::pow(p.y - in.centreY, 2.0) + std::pow(p.z - in.centreZ, 2.0);
          if (r2 >= R * R) continue;
          speed += snap.velocities[i].x;
          want += G * (R * R - r2) / (4.0 * mu);
        }
      }
      row("open_tube", scene, std::abs(speed / want - 1.0), "mean_speed_over_poiseuille", sim, wall);
    }
  }
  if (only.empty() || only == "dam_break") {
    // scenes/dam_break.json geometry; mean |dZ| against Martin & Moyce (1952) over T in
    // [0, 3] with the gate-release offset dT = 0.15 of docs/physics.md. Both integrators at
    // the scene's h/dp = 1.3; symplectic Euler also at 1.0 and 1.15 (fewer neighbours); both
    // integrators with continuity density at 1.3.
    const double a = 0.05715, g = 9.81, offset = 0.15;
    struct Variant {
      Integrator integrator;
      float smoothingRatio;
      hemo::sim::DensityMethod density = hemo::sim::DensityMethod::Summation;
      bool dfsph = false;
    };
    const Variant variants[] = {{Integrator::SymplecticEuler, 1.3f}, {Integrator::Rk2Midpoint, 1.3f},
                                {Integrator::SymplecticEuler, 1.15f}, {Integrator::SymplecticEuler, 1.0f},
                                {Integrator::SymplecticEuler, 1.3f, hemo::sim::DensityMethod::Continuity},
                                {Integrator::Rk2Midpoint, 1.3f, hemo::sim::DensityMethod::Continuity},
                                {Integrator::SymplecticEuler, 1.3f, hemo::sim::DensityMethod::Summation, true}};
    for (double fraction : {8.0, 10.0, 16.0}) {
      for (const Variant& v : variants) {
        if (skip(v.dfsph)) continue;
        hemo::scene::Scene scene = hemo::scene::loadScene(std::string(HEMO_SOURCE_DIR) + "/scenes/dam_break.json");
        scene.sph.spacing = float(a / fraction);
        scene.sph.smoothingRatio = v.smoothingRatio;
        // the periodic slab: 0.6 a thick as in the scene, at least 9 dp (three list radii)
        scene = hemo::scene::withSlabThickness(scene, 1, std::max(9, int(std::lround(0.6 * fraction))));
        scene.sph.integrator = v.integrator;
        scene.sph.densityMethod = v.density;
        if (v.dfsph) {
          scene.sph.pressureSolver = hemo::sim::PressureSolver::Dfsph;
          scene.sph.maxTimeStep = 0.002f;
        }
        hemo::sim::Simulation sim(ctx, scene);
        const auto& table = hemo::reference::martinMoyceN2();
        double sum = 0.0, wall = 0.0;
        int samples = 0;
        for (double T = 0.25; T <= 3.0 - offset + 1e-9; T += 0.25) {
          wall += runTo(sim, T * std::sqrt(a / (2 * g)));
          const double front = hemo::sim::surgeFront(sim.snapshot(), sim.fluidParticles(), 2.0f * scene.sph.spacing);
          sum += std::abs(front / a - hemo::reference::interpolateTable(table, T + offset));
          ++samples;
        }
        row("dam_break", scene, sum / samples, "mean_abs_dZ_martin_moyce", sim, wall);
      }
    }
  }
  if (only.empty() || only == "laplace") {
    // Laplace's law (LaplaceTest): a closed periodic tube (R = 5 mm, two layers, dp = 1 mm,
    // 10 mm long) whose hoop springs break at 5% strain; the lumen pressure rises to 1.3 P* in
    // 0.39 s, P* the static estimate of the spring layout (scene::ruptureEstimate). The error
    // is |p / P* - 1|, p the lumen pressure at the first broken spring (from the step rows of
    // every step; the dynamic break comes somewhat below P*: the wall overshoots). WCSPH with
    // the wall's own step, DFSPH with the wall in 8 substeps.
    const double dp = 0.001, radius = 0.005;
    const double around = std::round(2.0 * std::numbers::pi * radius / dp);
    const double hoop = 2.0 * (radius + 0.5 * dp) * std::sin(std::numbers::pi / around);
    const double maxForce = 100.0 * 0.05 * hoop;
    for (const bool dfsph : {false, true}) {
      if (skip(dfsph)) continue;
      const std::string text = R"({"scene": "laplace_bench", "particles": {"spacing_m": 0.001},
        "fluid": {"density_kg_m3": 1060, "viscosity_pa_s": 0.0035, "expected_max_speed_m_s": 0.2},
        "vessel": {"shape": "tube", "start_m": [0, 0, 0], "length_m": 0.01, "radius_m": 0.005, "layers": 2,
                   "point_mass_kg": 0.001, "stiffness_N_m": 100, "damping_N_s_m": 0.02, "max_force_N": )" +
                               std::to_string(maxForce) + R"(},
        "forces": {"gravity_m_s2": [0, 0, 0]},
        "time": {"end_time_s": 0.39, "steps_per_batch": 64},
        "domain": {"min_m": [0, -0.013, -0.013], "max_m": [0.01, 0.013, 0.013], "periodic": ["x"]}})";
      hemo::scene::Scene scene = hemo::scene::parseScene(text, "laplace_bench");
      const std::optional<hemo::scene::RuptureEstimate> estimate = hemo::scene::ruptureEstimate(scene);
      if (!estimate) throw std::runtime_error("accuracy: the Laplace tube has no rupture estimate");
      const double pStar = estimate->pressure;
      scene.sph.backgroundPressure = float(1.3 * pStar);
      scene.sph.backgroundPressureRamp = 0.39f;
      if (dfsph) {
        scene.sph.pressureSolver = hemo::sim::PressureSolver::Dfsph;
        scene.vessel->substeps = 8;
      }
      hemo::sim::Simulation sim(ctx, scene);
      sim.enableStepStats(1);
      double breakTime = -1.0;
      hemo::sim::RunOptions opt;
      opt.until = 0.39;
      opt.onStepStats = [&](const std::vector<hemo::sim::StepStatsRow>& stepRows) {
        for (const auto& r : stepRows) {
          if (breakTime < 0.0 && r.brokenSprings > 0) breakTime = r.time;
        }
      };
      // in pieces of 0.01 s, stopping at the first break
      double wall = 0.0;
      for (double t = 0.01; breakTime < 0.0 && t <= 0.39 + 1e-9; t += 0.01) {
        opt.until = t;
        wall += sim.run(opt).wallSeconds;
      }
      // (no break up to 1.3 P*: the error is at least 0.3)
      const double lumen = breakTime < 0.0 ? 1.3 * pStar : 1.3 * pStar * breakTime / 0.39;
      row("laplace", scene, std::abs(lumen / pStar - 1.0), "rel_error_rupture_pressure", sim, wall);
      rows.back()["rupture_pressure_Pa"] = lumen;
      rows.back()["rupture_estimate_Pa"] = pStar;
      rows.back()["wall_substeps"] = scene.vessel->substeps;
      std::printf("    first break at t = %.4f s, lumen pressure %.0f Pa = %.3f of the static estimate %.0f Pa\n", breakTime,
                  lumen, lumen / pStar, pStar);
    }
  }
  return rows;
}

// The seed paper's Table 1: a vessel of N_f fluid and N_b boundary (wall) particles, fluid and
// wall solved every step. Each row here is a periodic tube (one wall layer at the fluid's
// spacing dp = 0.35 mm, 9 slices along the axis: the shortest periodic length the neighbour
// grid allows) whose radius gives N_f fluid particles; its wall count follows from the radius
// (the paper's walls were sparser than one layer at the fluid's spacing, so small rows carry
// more wall particles than the paper's). The full coupled step runs: SPH, springs (aneurysm
// scene's soft preset), rupture check, parabolic inflow at 0.3 m/s with the lumen supply,
// lumen pressure 500 Pa, and the vessel scenes' neighbour-list skin of 0.25. Steps per second
// are the median of 2 * repeat + 1 wall-clock windows of 200 steps each (repeat = --repeat / 3,
// so 7 windows by default), one after another after a warm-up of 100 steps; the stage times
// are GPU medians of 5 profiled steps. Paper frame rates: the issue quotes 5.7 fps at
// 10,000 / 1,000 and 18.2 fps at 5,000 / 600; the other rows' figures are not available here
// (null).
Json table1(Context& ctx, int repeat) {
  struct PaperRow {
    int fluid, boundary;
    double fps;  // <= 0: not available
  };
  // The seed paper's eleven rows (fluid / boundary particles); its frame rates are known here
  // for two of them (18.2 fps at 5,000 / 600 and 5.7 at 10,000 / 1,000), the others are null.
  const PaperRow paper[] = {{500, 80, 0.0},   {1000, 80, 0.0},  {1500, 80, 0.0},   {2000, 200, 0.0},
                            {2500, 200, 0.0}, {3000, 300, 0.0}, {3500, 300, 0.0},  {4000, 600, 0.0},
                            {5000, 600, 18.2}, {8000, 1000, 0.0}, {10000, 1000, 5.7}};
  Json rows = Json::array();
  std::printf("%8s %8s %9s %9s %10s %10s %10s %14s\n", "fluid", "wall", "p.fluid", "p.bound", "steps/s", "paper fps",
              "x paper", "Mparticle-st/s");
  for (const PaperRow& pr : paper) {
    const double dp = 3.5e-4;
    const int slices = 9;
    const double length = slices * dp;
    // Fluid per slice of a tube of radius a dp is about pi a^2 (tubeFluidPoints).
    const double radius = std::max(2.0, std::round(std::sqrt(pr.fluid / (slices * std::numbers::pi)))) * dp;
    const double half = radius + 3 * dp;
    Json j = Json::parse(R"({
      "scene": "table1",
      "particles": { "spacing_m": 3.5e-4, "list_skin": 0.25, "neighbour_capacity": 176 },
      "fluid": { "density_kg_m3": 1060.0, "viscosity_pa_s": 0.0035, "expected_max_speed_m_s": 0.5,
                 "background_pressure_Pa": 500.0, "background_pressure_ramp_s": 0.005 },
      "vessel": { "shape": "tube", "layers": 1, "point_mass_kg": 5e-6, "stiffness_N_m": 5.0, "damping_N_s_m": 0.002,
                  "max_force_N": 1.65e-4 },
      "forces": { "gravity_m_s2": [0, 0, 0] },
      "time": { "steps_per_batch": 128 },
      "domain": { "periodic": ["x"] }
    })");
    j["vessel"]["length_m"] = length;
    j["vessel"]["radius_m"] = radius;
    j["vessel"]["inflow"] = {{"profile", "parabolic"}, {"mean_speed_m_s", 0.3}, {"zone_length_m", 3 * dp},
                             {"hold_lumen_pressure", true}};
    j["domain"]["min_m"] = {0.0, -half, -half};
    j["domain"]["max_m"] = {length, half, half};
    const hemo::scene::Scene scene = hemo::scene::parseScene(j.dump(), "table1");
    hemo::sim::Simulation sim(ctx, scene);
    hemo::sim::RunOptions opt;
    opt.steps = 100;
    sim.run(opt);  // warm-up: pipelines, first list builds, the inflow's start
    // Timed windows of 200 steps, one after another; the row reports their median (the
    // machine's speed drifts by tens of percent within a minute, ../shared/LAVAPIPE.md).
    const int windows = 2 * repeat + 1;
    opt.steps = 200;
    const std::uint32_t rebuildsBefore = sim.solver().readRebuilds();
    std::vector<double> windowRates;
    std::uint64_t timedSteps = 0;
    for (int w = 0; w < windows; ++w) {
      const hemo::sim::RunResult r = sim.run(opt);
      windowRates.push_back(double(r.steps) / r.wallSeconds);
      timedSteps += r.steps;
    }
    const std::uint32_t rebuilds = sim.solver().readRebuilds() - rebuildsBefore;
    std::vector<double> sorted = windowRates;
    std::sort(sorted.begin(), sorted.end());
    const double stepsPerS = sorted[sorted.size() / 2];
    Json stageMs = Json::object();
    for (const auto& [stage, ms] : sim.profileStep(5)) stageMs[stage] = ms;
    Json rebuildMs = Json::object();  // steps forced to rebuild the grid and the list
    for (const auto& [stage, ms] : sim.profileStep(5, true)) rebuildMs[stage] = ms;
    const std::uint32_t total = sim.fluidParticles() + sim.wallParticles();
    std::printf("%8u %8u %9d %9d %10.1f %10s %10s %14.2f\n", sim.fluidParticles(), sim.wallParticles(), pr.fluid, pr.boundary,
                stepsPerS, pr.fps > 0 ? std::to_string(pr.fps).substr(0, 4).c_str() : "-",
                pr.fps > 0 ? std::to_string(stepsPerS / pr.fps).substr(0, 5).c_str() : "-", stepsPerS * total / 1e6);
    std::fflush(stdout);
    rows.push_back({{"fluid", sim.fluidParticles()},
                    {"boundary", sim.wallParticles()},
                    {"paper_fluid", pr.fluid},
                    {"paper_boundary", pr.boundary},
                    {"springs", sim.springs()},
                    {"steps", timedSteps},
                    {"steps_per_s", stepsPerS},
                    {"steps_per_s_windows", windowRates},
                    {"particle_steps_per_s", stepsPerS * total},
                    {"paper_fps", pr.fps > 0 ? Json(pr.fps) : Json(nullptr)},
                    {"ratio_to_paper", pr.fps > 0 ? Json(stepsPerS / pr.fps) : Json(nullptr)},
                    {"stage_ms", stageMs},
                    {"neighbour_rebuilds", rebuilds},
                    {"rebuild_stage_ms", rebuildMs}});
  }
  return rows;
}

// CPU seconds (user + system) this process has used so far, lavapipe's threads included.
double processCpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// A whole scene, start to end (`until` seconds of simulated time; <= 0: the scene's end time),
// `runs` times, each from a fresh Simulation whose pipelines are built before the clock
// starts. Per run: steps, neighbour-list rebuilds, wall seconds, steps/s, fluid particle-steps
// per second and the CPU seconds the process spent (on lavapipe the host's speed decides the
// rate: the same work has taken 34 s of CPU on one host and 114 s on another); then the GPU
// milliseconds of each stage, median of 20 steps after the run, both as the steps come (most
// reuse the neighbour list) and forced to rebuild it. Printed last: the runs' median steps/s
// and the last run's stage times.
Json speed(Context& ctx, const hemo::scene::Scene& scene, const std::string& scenePath, double until, int runs) {
  Json rows = Json::array();
  std::vector<double> rates;
  std::vector<std::pair<std::string, double>> calm, rebuild;  // the last run's stage times
  std::pair<double, double> perStep;  // the last run's dispatches and barriers per step
  for (int r = 0; r < runs; ++r) {
    hemo::sim::Simulation sim(ctx, scene);
    if (r == 0) {
      std::printf("scene %s (%s): %u fluid, %u boundary, %u wall particles, %u springs\n", scene.name.c_str(),
                  scenePath.c_str(), sim.fluidParticles(), sim.boundaryParticles(), sim.wallParticles(), sim.springs());
      std::printf("%4s %8s %9s %10s %8s %9s %18s %8s\n", "run", "steps", "sim s", "rebuilds", "wall s", "steps/s",
                  "fluid part-steps/s", "CPU s");
    }
    hemo::sim::RunOptions opt;
    if (until > 0) opt.until = until;
    const double cpuBefore = processCpuSeconds();
    const hemo::sim::RunResult result = sim.run(opt);
    const double cpu = processCpuSeconds() - cpuBefore;
    const std::uint32_t rebuilds = sim.solver().readRebuilds();
    const double rate = result.wallSeconds > 0 ? double(result.steps) / result.wallSeconds : 0.0;
    rates.push_back(rate);
    perStep = {sim.dispatchesPerStep(), sim.barriersPerStep()};
    calm = sim.profileStep(20);
    rebuild = sim.profileStep(20, true);
    Json stageMs = Json::object(), rebuildMs = Json::object();
    for (const auto& [stage, ms] : calm) stageMs[stage] = ms;
    for (const auto& [stage, ms] : rebuild) rebuildMs[stage] = ms;
    std::printf("%4d %8llu %9.4f %10u %8.2f %9.1f %18.3e %8.2f\n", r + 1, static_cast<unsigned long long>(result.steps),
                result.simTime, rebuilds, result.wallSeconds, rate, rate * sim.fluidParticles(), cpu);
    std::fflush(stdout);
    rows.push_back({{"scene", scene.name},
                    {"run", r + 1},
                    {"fluid_particles", sim.fluidParticles()},
                    {"boundary_particles", sim.boundaryParticles()},
                    {"wall_particles", sim.wallParticles()},
                    {"steps", result.steps},
                    {"sim_time_s", result.simTime},
                    {"neighbour_rebuilds", rebuilds},
                    {"wall_time_s", result.wallSeconds},
                    {"steps_per_s", rate},
                    {"fluid_particle_steps_per_s", rate * sim.fluidParticles()},
                    {"cpu_s", cpu},
                    {"dispatches_per_step", sim.dispatchesPerStep()},
                    {"barriers_per_step", sim.barriersPerStep()},
                    {"stage_ms", stageMs},
                    {"rebuild_stage_ms", rebuildMs}});
  }
  const double mid = median(rates);
  std::printf("median %.1f steps/s over %d run%s\n", mid, runs, runs == 1 ? "" : "s");
  std::printf("recorded per step: %.2f dispatches, %.2f barriers\n", perStep.first, perStep.second);
  for (const auto* stages : {&calm, &rebuild}) {
    std::printf("%s (run %d, GPU ms, median of 20 steps%s):", stages == &calm ? "stage_ms" : "rebuild_stage_ms", runs,
                stages == &calm ? "" : " forced to rebuild");
    double total = 0.0;
    for (const auto& [stage, ms] : *stages) {
      std::printf("  %s %.3f", stage.c_str(), ms);
      total += ms;
    }
    std::printf("  (sum %.3f)\n", total);
  }
  return rows;
}

// The process's resident host memory (bytes), from /proc/self/statm.
std::uint64_t residentBytes() {
  std::ifstream statm("/proc/self/statm");
  std::uint64_t size = 0, resident = 0;
  statm >> size >> resident;
  return resident * static_cast<std::uint64_t>(sysconf(_SC_PAGESIZE));
}

// Soak: `steps` steps of a scene (default the aneurysm) in 20 windows. After each window: the
// host's resident memory, the device memory hemo's buffers hold, the particles lost (no
// longer finite) and escaped, broken springs, the simulated time and the window's steps/s.
// From the second window on (the first holds the pipelines' and the driver's one-off
// allocations) the memory must stay flat: hemo's device memory exactly, the host's within 1%
// or 4 MiB, whichever is larger; and no particle may be lost. `flat` reports the verdict.
Json soak(Context& ctx, const hemo::scene::Scene& scene, const std::string& scenePath, std::uint64_t steps, bool& flat) {
  Json rows = Json::array();
  hemo::sim::Simulation sim(ctx, scene);
  std::printf("scene %s (%s): %u fluid, %u boundary, %u wall particles, %u springs; %llu steps\n", scene.name.c_str(),
              scenePath.c_str(), sim.fluidParticles(), sim.boundaryParticles(), sim.wallParticles(), sim.springs(),
              static_cast<unsigned long long>(steps));
  std::printf("%6s %10s %10s %9s %12s %12s %6s %8s %8s\n", "window", "steps", "sim s", "steps/s", "host MiB",
              "device MiB", "lost", "escaped", "broken");
  constexpr int kWindows = 20;
  const std::uint64_t window = std::max<std::uint64_t>(steps / kWindows, 1);
  std::uint64_t hostFirst = 0, deviceFirst = 0, hostMax = 0, deviceMax = 0;
  std::uint32_t lost = 0;
  for (int w = 0; w < kWindows && sim.steps() < steps; ++w) {
    hemo::sim::RunOptions opt;
    opt.steps = std::min(window, steps - sim.steps());
    const hemo::sim::RunResult r = sim.run(opt);
    const std::uint64_t host = residentBytes();
    const std::uint64_t device = ctx.deviceMemoryBytes();
    lost = sim.lostParticles();
    const std::uint32_t broken = sim.solver().wall() ? sim.solver().wall()->readBrokenCount() : 0u;
    const double rate = r.wallSeconds > 0 ? double(r.steps) / r.wallSeconds : 0.0;
    if (w == 1) hostFirst = host, deviceFirst = device;
    if (w >= 1) hostMax = std::max(hostMax, host), deviceMax = std::max(deviceMax, device);
    std::printf("%6d %10llu %10.5f %9.1f %12.1f %12.1f %6u %8u %8u\n", w + 1, static_cast<unsigned long long>(sim.steps()),
                sim.time(), rate, double(host) / (1 << 20), double(device) / (1 << 20), lost, sim.escapedParticles(),
                broken);
    std::fflush(stdout);
    rows.push_back({{"window", w + 1},
                    {"steps", sim.steps()},
                    {"sim_time_s", sim.time()},
                    {"steps_per_s", rate},
                    {"host_resident_bytes", host},
                    {"gpu_memory_bytes", device},
                    {"lost_particles", lost},
                    {"escaped_particles", sim.escapedParticles()},
                    {"broken_springs", broken}});
  }
  const std::uint64_t hostAllowed = std::max<std::uint64_t>(hostFirst / 100, 4ull << 20);
  const bool hostFlat = hostMax <= hostFirst + hostAllowed;
  const bool deviceFlat = deviceMax == deviceFirst;
  flat = hostFlat && deviceFlat && lost == 0;
  std::printf("from window 2 on: host memory %.1f -> at most %.1f MiB (%s), device memory %.1f -> at most %.1f MiB (%s), "
              "%u lost: %s\n",
              double(hostFirst) / (1 << 20), double(hostMax) / (1 << 20), hostFlat ? "flat" : "grew",
              double(deviceFirst) / (1 << 20), double(deviceMax) / (1 << 20), deviceFlat ? "flat" : "grew", lost,
              flat ? "memory flat, nothing lost" : "FAILED");
  return rows;
}

// The scale suite's scene: a 3D dam break in the geometry of SPHERIC's benchmark 2 (a column
// of water 1.228 x 1 x 0.55 m at one end of a tank 3.22 x 1 m, here without the obstacle and
// with walls 0.6 m high), at the spacing that gives about `target` particles in all (fluid
// and tank). Per unit spacing the fluid holds 0.675 m^3 / dp^3 particles and the tank's
// walls (bottom, ends and sides, `layers` deep) about 8.28 m^2 layers / dp^2.
hemo::scene::Scene scaleScene(double target, double ratio, const std::string& search) {
  const int layers = static_cast<int>(std::ceil(2.0 * ratio - 1e-6));  // the kernel support, 2h, in spacings
  double dp = std::cbrt(0.675 / target);
  for (int it = 0; it < 60; ++it) {  // fluid + wall particles = target
    const double f = 0.675 / (dp * dp * dp) + 8.28 * layers / (dp * dp);
    const double df = -3.0 * 0.675 / (dp * dp * dp * dp) - 2.0 * 8.28 * layers / (dp * dp * dp);
    dp -= (f - target) / df;
  }
  // List entries: the particles within the list radius 2h (1 + skin) of a particle inside the
  // fluid, with a third to spare for compression, in whole texels of four.
  const double skin = 0.1;
  const double reach = 2.0 * ratio * (1.0 + skin);
  const auto capacity = static_cast<std::uint32_t>(
      std::min(1024.0, std::ceil(1.35 * 4.0 / 3.0 * std::numbers::pi * reach * reach * reach / 4.0) * 4.0));
  Json j = Json::parse(R"({
    "scene": "dam_break_3d",
    "description": "3D dam break (SPHERIC benchmark 2's column and tank, no obstacle), sized by hemo-bench scale",
    "fluid": { "density_kg_m3": 1000.0, "viscosity_pa_s": 0.001, "expected_max_speed_m_s": 3.5,
               "blocks": [ { "min_m": [0.0, 0.0, 0.0], "max_m": [1.228, 1.0, 0.55] } ] },
    "boundary": { "tanks": [ { "min_m": [0.0, 0.0, 0.0], "max_m": [3.22, 1.0, 0.6], "open_top": true } ] },
    "forces": { "gravity_m_s2": [0.0, 0.0, -9.81] },
    "time": { "integrator": "symplectic_euler", "cfl_acoustic": 0.3, "max_dt_s": 0.0005, "steps_per_batch": 32 },
    "domain": { "min_m": [-0.1, -0.1, -0.1], "max_m": [3.32, 1.1, 1.0] }
  })");
  j["particles"] = {{"spacing_m", dp}, {"smoothing_ratio", ratio}, {"list_skin", skin}, {"neighbour_capacity", capacity},
                    {"neighbour_search", search}};
  j["boundary"]["tanks"][0]["layers"] = layers;
  return hemo::scene::parseScene(j.dump(), "hemo-bench scale");
}

// Throughput against size: the 3D dam break (scaleScene) at about 0.1M, 1M, 4M, 16M and 64M
// particles, up to `maxParticles` or the largest the device holds. Per size, after 10 steps of
// warm-up, timed windows of steps (about 2 s each, median of `repeat`): steps/s, fluid and
// total particle-steps/s, the device memory hemo's buffers held (bytes per particle), the
// neighbour search the solver took (`search`: auto, list or cells; a list's pages), and the GPU
// ms of each stage (median of 5 steps as they come, and of 5 steps forced to rebuild the
// neighbour list). A size the device refuses (memory or a binding limit) is reported with the
// reason, and ends the suite.
Json scale(Context& ctx, int repeat, std::uint64_t maxParticles, double ratio, const std::string& search) {
  Json rows = Json::array();
  std::printf("%10s %10s %5s %10s %10s %14s %14s %10s %9s %6s\n", "particles", "fluid", "h/dp", "spacing m", "steps/s",
              "part-steps/s", "fluid p-st/s", "B/particle", "step ms", "pages");  // (pages: "cells" without a list)
  for (const double target : {1.0e5, 1.0e6, 4.0e6, 1.6e7, 6.4e7}) {
    if (target > 1.05 * double(maxParticles)) break;
    const hemo::scene::Scene scene = scaleScene(target, ratio, search);
    Json row = {{"target_particles", target}, {"smoothing_ratio", ratio}, {"spacing_m", scene.sph.spacing},
                {"neighbour_capacity", scene.sph.neighbourCapacity}};
    ctx.resetPeakDeviceMemoryBytes();
    try {
      hemo::sim::Simulation sim(ctx, scene);
      const std::uint64_t total = std::uint64_t(sim.fluidParticles()) + sim.boundaryParticles() + sim.wallParticles();
      hemo::sim::RunOptions opt;
      opt.steps = 10;
      const hemo::sim::RunResult warm = sim.run(opt);  // pipelines, the first list build
      const double guess = warm.wallSeconds > 0 ? double(warm.steps) / warm.wallSeconds : 100.0;
      const auto window = static_cast<std::uint64_t>(std::clamp(2.0 * guess, 10.0, 4000.0));
      opt.steps = window;
      std::vector<double> rates;
      for (int w = 0; w < repeat; ++w) {
        const hemo::sim::RunResult r = sim.run(opt);
        rates.push_back(r.wallSeconds > 0 ? double(r.steps) / r.wallSeconds : 0.0);
      }
      const double rate = median(rates);
      Json stageMs = Json::object(), rebuildMs = Json::object();
      double stepMs = 0.0;
      for (const auto& [stage, ms] : sim.profileStep(5)) {
        stageMs[stage] = ms;
        stepMs += ms;
      }
      for (const auto& [stage, ms] : sim.profileStep(5, true)) rebuildMs[stage] = ms;
      const std::uint64_t bytes = ctx.peakDeviceMemoryBytes();
      const bool cells = sim.solver().walksCells();
      const double perParticle = double(bytes) / double(std::max<std::uint64_t>(total, 1));
      const Json measured = {{"particles", total},
                  {"fluid", sim.fluidParticles()},
                  {"boundary", sim.boundaryParticles()},
                  {"steps", window * std::uint64_t(repeat)},
                  {"steps_per_s", rate},
                  {"steps_per_s_windows", rates},
                  {"particle_steps_per_s", rate * double(total)},
                  {"fluid_particle_steps_per_s", rate * sim.fluidParticles()},
                  {"gpu_memory_bytes", bytes},
                  {"neighbour_search", cells ? "cells" : "list"},
                  {"list_pages", cells ? 0u : sim.solver().listPages()},  // the neighbour list's pages (1: one buffer)
                  {"bytes_per_particle", perParticle},
                  {"stage_ms", stageMs},
                  {"rebuild_stage_ms", rebuildMs},
                  {"finite", true}};
      row.update(measured);
      const std::string pages = cells ? "cells" : std::to_string(sim.solver().listPages());
      std::printf("%10llu %10u %5.2f %10.3e %10.1f %14.3e %14.3e %10.0f %9.3f %6s\n", static_cast<unsigned long long>(total),
                  sim.fluidParticles(), ratio, double(scene.sph.spacing), rate, rate * double(total),
                  rate * sim.fluidParticles(), perParticle, stepMs, pages.c_str());
      std::fflush(stdout);
      rows.push_back(row);
    } catch (const std::exception& e) {
      // The device's memory or a binding limit (hemo::gpu::OutOfDeviceMemory, GpuError, or
      // the simulation's own fit check, a SceneError); a blow-up (SimulationError) is a failure.
      if (dynamic_cast<const hemo::sim::SimulationError*>(&e)) throw;
      row["refused"] = e.what();
      std::printf("%10s about %.0f particles at h/dp %.2f refused: %s\n", "-", target, ratio, e.what());
      std::fflush(stdout);
      rows.push_back(row);
      break;
    }
  }
  return rows;
}

// Marching-cubes rendering benchmark: for the dam break and the aneurysm (after a few hundred
// steps, so the surface has moved), the GPU field (bounds + splat) and extraction (classify,
// scans, compact, generate) at grids of 64^3, 128^3 and 256^3 voxels over the fluid's box, the
// surface draw (960x540, offscreen, with the copy to host memory), the CPU reference
// extracting the same field (double precision, one thread) in the same run, and the cost of a
// frame with the surface (one step + field + extraction + draw) over one without (one step +
// the particles drawn).
Json render(Context& ctx, int repeat, const std::filesystem::path& scenes) {
  // The CPU reference allocates its mesh and work arrays on every call. By default glibc maps
  // large blocks afresh and returns them on free, so each call would also pay the kernel's
  // page faults (up to 3x its time on the dam break at 64^3), which the GPU
  // side, whose buffers are made once, does not. Keeping freed memory in the heap times the
  // reference in its steady state, as an application that runs it every frame would see it.
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  Json rows = Json::array();
  std::printf("%-10s %5s %10s %10s %12s %12s %9s %10s %12s %8s %9s\n", "scene", "grid", "particles", "field_ms",
              "extract_ms", "cpu_mc_ms", "speed-up", "triangles", "Mtri/s", "draw_ms", "frame_x");
  for (const char* name : {"dam_break", "aneurysm"}) {
    const hemo::scene::Scene scene = hemo::scene::loadScene(scenes / (std::string(name) + ".json"));
    hemo::sim::Simulation sim(ctx, scene);
    hemo::sim::RunOptions opt;
    opt.steps = 300;
    sim.run(opt);
    // A frame without the surface: one simulation step and the particles drawn (fluid by
    // speed, the wall by strain); the draws are timed in a 960x540 offscreen image.
    double stepMs = 0.0;
    for (const auto& [stage, ms] : sim.profileStep(5)) stepMs += ms;
    hemo::render::OffscreenRenderer renderer(ctx, 960, 540);
    const hemo::render::Camera camera =
        hemo::render::defaultCamera(sim.store().readPositions(), 960.0f / 540.0f, sim.wallParticles() > 0);
    hemo::render::FrameOptions frame;
    frame.particleRadius = 0.5f * scene.sph.spacing;
    const hemo::render::ParticleView view{&sim.store().live().positions, &sim.store().live().velocities,
                                          sim.store().count(), nullptr};
    const double particlesDrawMs = timeGpu(ctx, repeat, [] {}, [&](CommandRecorder& rec) {
      renderer.record(rec, camera, frame, view, nullptr);
    });
    frame.fluid = false;  // with the surface, the surface shows the blood
    for (std::uint32_t grid : {64u, 128u, 256u}) {
      hemo::surface::MarchingCubes mc(ctx, grid);
      hemo::surface::FieldSettings fs;
      fs.resolution = grid;
      fs.iso = scene.surface.iso;
      fs.h = sim.solver().settings().h();
      fs.restDensity = sim.solver().settings().restDensity;
      fs.splatVoxelOverH = scene.surface.splatVoxelOverH;
      // The exact field (splat on the surface grid itself) for comparison, timed alone.
      hemo::surface::FieldSettings exact = fs;
      exact.splatVoxelOverH = 0.0f;
      double exactFieldMs = 0.0;
      {
        hemo::surface::ParticleField direct(ctx, mc, sim.store(), sim.solver().state(), exact);
        exactFieldMs = timeGpu(ctx, repeat, [] {}, [&](CommandRecorder& r) { direct.record(r, sim.store().count()); });
      }
      hemo::surface::ParticleField field(ctx, mc, sim.store(), sim.solver().state(), fs);
      CommandRecorder rec(ctx);
      TimestampQueries ts(ctx, 16);
      std::map<std::string, std::vector<double>> stages;
      for (int r = 0; r <= repeat; ++r) {
        rec.begin();
        ts.reset(rec);
        ts.mark(rec, "start");
        field.record(rec, sim.store().count(), &ts);
        mc.record(rec, &ts);
        rec.end();
        rec.submitAndWait();
        if (r == 0) continue;
        for (const auto& [stage, ms] : ts.stageMs()) stages[stage].push_back(ms);
      }
      Json stageMs = Json::object();
      double fieldMs = 0.0, extractMs = 0.0;
      for (auto& [stage, ms] : stages) {
        const double m = median(ms);
        stageMs[stage] = m;
        (stage == "field" ? fieldMs : extractMs) += m;
      }
      const hemo::surface::McTotals totals = mc.readTotals();
      const double surfaceDrawMs = timeGpu(ctx, repeat, [] {}, [&](CommandRecorder& r) {
        renderer.record(r, camera, frame, view, &mc);
      });
      const double frameWithout = stepMs + particlesDrawMs;
      const double frameWith = stepMs + fieldMs + extractMs + surfaceDrawMs;
      // The CPU reference on the same field.
      const hemo::surface::McGrid g = mc.readGrid();
      const auto fixed = mc.readField();
      hemo::reference::ScalarGrid ref;
      ref.origin = glm::dvec3(g.origin[0], g.origin[1], g.origin[2]);
      ref.spacing = g.origin[3];
      ref.points = glm::uvec3(g.points[0], g.points[1], g.points[2]);
      ref.values.resize(fixed.size());
      for (std::size_t k = 0; k < fixed.size(); ++k) ref.values[k] = hemo::surface::fromFixed(fixed[k]);
      const auto table = hemo::surface::buildCaseTable();
      std::vector<double> cpu;
      std::size_t cpuTriangles = 0;
      for (int r = 0; r <= 3; ++r) {  // a warm-up call, then the median of 3
        const auto t0 = std::chrono::steady_clock::now();
        cpuTriangles = hemo::reference::marchingCubes(ref, g.level[0], table).triangleCount();
        if (r > 0) cpu.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      }
      const double cpuMs = median(cpu);
      std::printf("%-10s %5u %10u %10.2f %12.2f %12.1f %9.1f %10u %12.2f %8.2f %9.2f%s\n", name, grid, sim.fluidParticles(),
                  fieldMs, extractMs, cpuMs, cpuMs / extractMs, totals.triangles,
                  totals.triangles / (fieldMs + extractMs) / 1e3, surfaceDrawMs, frameWith / frameWithout,
                  cpuTriangles == totals.triangles ? "" : "  (CPU triangle count differs!)");
      std::fflush(stdout);
      rows.push_back({{"scene", name},
                      {"grid", grid},
                      {"fluid_particles", sim.fluidParticles()},
                      {"grid_points", {g.points[0], g.points[1], g.points[2]}},
                      {"gpu_ms", fieldMs + extractMs},
                      {"gpu_field_ms", fieldMs},
                      {"splat_voxel_h", fs.splatVoxelOverH},
                      {"gpu_field_exact_ms", exactFieldMs},
                      {"gpu_extract_ms", extractMs},
                      {"draw_ms", surfaceDrawMs},
                      {"step_ms", stepMs},
                      {"particles_draw_ms", particlesDrawMs},
                      {"frame_ms", frameWith},
                      {"frame_without_surface_ms", frameWithout},
                      {"frame_cost_ratio", frameWith / frameWithout},
                      {"cpu_ms", cpuMs},
                      {"speedup_extract", cpuMs / extractMs},
                      {"triangles", totals.triangles},
                      {"cpu_triangles", cpuTriangles},
                      {"triangles_per_s", totals.triangles / ((fieldMs + extractMs) / 1e3)},
                      {"overflow", totals.overflow()},
                      {"stage_ms", stageMs}});
    }
  }
  return rows;
}

// What the engine reads from the device instead of assuming it (a GPU check's first record):
// the sizes and limits the shaders and buffers are sized by, timestamps, and the memory types
// (a discrete GPU's large device-local heap is not host-visible: buffers there go through
// staging copies).
Json deviceFacts(Context& ctx) {
  const VkPhysicalDeviceLimits& l = ctx.limits();
  const VkPhysicalDeviceMemoryProperties& m = ctx.memoryProperties();
  Json heaps = Json::array(), types = Json::array();
  for (std::uint32_t i = 0; i < m.memoryHeapCount; ++i) {
    heaps.push_back({{"bytes", m.memoryHeaps[i].size},
                     {"device_local", (m.memoryHeaps[i].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT) != 0}});
  }
  for (std::uint32_t i = 0; i < m.memoryTypeCount; ++i) {
    const VkMemoryPropertyFlags f = m.memoryTypes[i].propertyFlags;
    types.push_back({{"heap", m.memoryTypes[i].heapIndex},
                     {"device_local", (f & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) != 0},
                     {"host_visible", (f & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT) != 0},
                     {"host_coherent", (f & VK_MEMORY_PROPERTY_HOST_COHERENT_BIT) != 0},
                     {"host_cached", (f & VK_MEMORY_PROPERTY_HOST_CACHED_BIT) != 0}});
  }
  hemo::gpu::Buffer probe(ctx, 16, hemo::gpu::MemoryUse::Device, "device memory probe");
  const std::uint32_t api = ctx.info().apiVersion;
  Json row = {{"device", ctx.info().name},
              {"type", ctx.info().typeName()},
              {"api_version", std::to_string(VK_API_VERSION_MAJOR(api)) + "." + std::to_string(VK_API_VERSION_MINOR(api)) +
                                  "." + std::to_string(VK_API_VERSION_PATCH(api))},
              {"driver", ctx.driver()},
              {"vendor_id", ctx.vendorId()},
              {"subgroup_size", ctx.subgroupSize()},
              {"max_compute_workgroup_invocations", l.maxComputeWorkGroupInvocations},
              {"max_compute_workgroup_size_x", l.maxComputeWorkGroupSize[0]},
              {"max_compute_workgroup_count", {l.maxComputeWorkGroupCount[0], l.maxComputeWorkGroupCount[1],
                                               l.maxComputeWorkGroupCount[2]}},
              {"max_compute_shared_memory_bytes", l.maxComputeSharedMemorySize},
              {"max_texel_buffer_elements", l.maxTexelBufferElements},
              {"max_storage_buffer_range_bytes", l.maxStorageBufferRange},
              {"max_uniform_buffer_range_bytes", l.maxUniformBufferRange},
              {"max_per_stage_storage_buffers", l.maxPerStageDescriptorStorageBuffers},
              {"max_per_stage_uniform_buffers", l.maxPerStageDescriptorUniformBuffers},
              {"max_per_stage_texel_buffers", l.maxPerStageDescriptorSampledImages},
              {"max_per_stage_resources", l.maxPerStageResources},
              {"max_allocation_bytes", ctx.maxAllocationSize()},
              {"timestamps", ctx.timestampsSupported()},
              {"timestamp_period_ns", ctx.timestampPeriodNs()},
              {"timestamp_valid_bits", ctx.timestampValidBits()},
              {"device_buffers_mapped", probe.hostMapped()},
              {"memory_heaps", heaps},
              {"memory_types", types}};
  for (const auto& [key, value] : row.items()) {
    if (key == "memory_heaps" || key == "memory_types") continue;
    std::printf("%-36s %s\n", key.c_str(), value.is_string() ? value.get<std::string>().c_str() : value.dump().c_str());
  }
  for (std::size_t i = 0; i < heaps.size(); ++i) {
    std::printf("memory heap %zu: %.2f GiB%s\n", i, heaps[i]["bytes"].get<double>() / (1024.0 * 1024 * 1024),
                heaps[i]["device_local"].get<bool>() ? ", device-local" : "");
  }
  for (std::size_t i = 0; i < types.size(); ++i) {
    std::printf("memory type %zu: heap %u%s%s%s%s\n", i, types[i]["heap"].get<unsigned>(),
                types[i]["device_local"].get<bool>() ? " device-local" : "",
                types[i]["host_visible"].get<bool>() ? " host-visible" : "",
                types[i]["host_coherent"].get<bool>() ? " host-coherent" : "",
                types[i]["host_cached"].get<bool>() ? " host-cached" : "");
  }
  return Json::array({row});
}

}  // namespace

int main(int argc, char** argv) {
  const char* usage =
      "usage: hemo-bench SUITE [--json FILE] [--device SEL] [--repeat N] [--case NAME] [--scene FILE] [--until S]\n"
      "                  [--max-particles N] [--smoothing-ratio R] [--neighbour-search MODE]\n"
      "  SUITE: primitives | accuracy | table1 | render | speed | scale | soak | device\n"
      "         (soak: a long run of --scene, default the aneurysm; exit 5 if memory grew or particles were lost)\n"
      "         (device: what hemo reads from the device: sizes, limits, timestamps, memory types)\n"
      "  --repeat N    timed repetitions (default 9; table1 takes N/3 windows either side of the median;\n"
      "                speed: whole runs, default 3)\n"
      "  --case NAME   accuracy: only this case (hydrostatic, poiseuille, carreau_tube, open_tube, dam_break, laplace)\n"
      "  --solver NAME accuracy: only the runs of this pressure solver (wcsph, dfsph)\n"
      "  --scene FILE  speed, soak: the scene to run (default scenes/dam_break.json; soak: scenes/aneurysm.json)\n"
      "  --until S     speed: simulated seconds per run (default: the scene's time.end_time_s)\n"
      "  --steps N     soak: steps to run (default 100000), in 20 windows\n"
      "  --max-particles N    scale: the largest size to run (sizes of about 0.1M, 1M, 4M, 16M, 64M;\n"
      "                       default: up to what the device holds)\n"
      "  --smoothing-ratio R  scale: h/dp of the 3D dam break (default 1.3)\n"
      "  --neighbour-search MODE  scale: auto (default: a neighbour list where the device's memory\n"
      "                       holds it, else cells), list or cells (no list: the passes walk cells)\n"
      "  --help        prints this text\n";
  if (hemo::cli::printUsageIfAsked(argc, argv, usage)) return 0;
  hemo::cli::Args args;
  try {
    args = hemo::cli::parse(argc, argv, {"--json", "--device", "--repeat", "--case", "--solver", "--scene", "--until", "--max-particles",
                                          "--smoothing-ratio", "--neighbour-search", "--steps"});
    if (args.positional.size() != 1) throw hemo::cli::UsageError("expected exactly one SUITE");
  } catch (const hemo::cli::UsageError& e) {
    std::cerr << "hemo-bench: " << e.what() << "\n" << usage;
    return 1;
  }
  const std::string suite = args.positional[0];
  try {
    if (suite != "primitives" && suite != "accuracy" && suite != "table1" && suite != "render" && suite != "speed" &&
        suite != "scale" && suite != "soak" && suite != "device") {
      std::cerr << "hemo-bench: unknown suite '" << suite << "'\n" << usage;
      return 1;
    }
    const int repeat = static_cast<int>(args.count("--repeat", suite == "speed" || suite == "scale" ? 3 : 9, 1, 1000));
    const std::string only = args.text("--case");
    if (args.has("--case") && suite != "accuracy") throw hemo::cli::UsageError("--case applies to the accuracy suite only");
    const std::string solverOnly = args.text("--solver");
    if (args.has("--solver") && suite != "accuracy") throw hemo::cli::UsageError("--solver applies to the accuracy suite only");
    if (args.has("--solver") && solverOnly != "wcsph" && solverOnly != "dfsph") {
      throw hemo::cli::UsageError("unknown --solver '" + solverOnly + "' (expected wcsph or dfsph)");
    }
    if (!only.empty() && only != "hydrostatic" && only != "poiseuille" && only != "carreau_tube" && only != "open_tube" &&
        only != "dam_break" && only != "laplace") {
      throw hemo::cli::UsageError("unknown --case '" + only +
                                  "' (expected hydrostatic, poiseuille, carreau_tube, open_tube, dam_break or laplace)");
    }
    if (args.has("--until") && suite != "speed") throw hemo::cli::UsageError("--until applies to the speed suite only");
    if (args.has("--scene") && suite != "speed" && suite != "soak") {
      throw hemo::cli::UsageError("--scene applies to the speed and soak suites only");
    }
    if (args.has("--steps") && suite != "soak") throw hemo::cli::UsageError("--steps applies to the soak suite only");
    const std::uint64_t soakSteps = args.count("--steps", 100000, 20, 100000000);
    for (const char* option : {"--max-particles", "--smoothing-ratio", "--neighbour-search"}) {
      if (args.has(option) && suite != "scale") {
        throw hemo::cli::UsageError(std::string(option) + " applies to the scale suite only");
      }
    }
    const std::uint64_t maxParticles = args.count("--max-particles", 100000000, 1000, 1000000000);
    const double ratio = args.number("--smoothing-ratio", 1.3, 1.0, 3.0);
    const std::string search = args.text("--neighbour-search", "auto");
    if (search != "auto" && search != "list" && search != "cells") {
      throw hemo::cli::UsageError("unknown --neighbour-search '" + search + "' (expected auto, list or cells)");
    }
    const double until = args.seconds("--until", 0.0);
    if (args.has("--until") && until <= 0) throw hemo::cli::UsageError("--until must be above 0 s");
    // The scene is read before any device is opened: a bad file fails at once.
    const std::string scenePath =
        args.text("--scene", std::string(HEMO_SOURCE_DIR) + (suite == "soak" ? "/scenes/aneurysm.json" : "/scenes/dam_break.json"));
    hemo::scene::Scene scene;
    if (suite == "speed" || suite == "soak") scene = hemo::scene::loadScene(scenePath);
    // The JSON file is opened before the benchmark runs (a suite takes minutes): a path that
    // cannot be written fails at once.
    // (under a temporary name until the suite ends: hemo/io/atomic_file.hpp)
    std::unique_ptr<hemo::io::AtomicFile> json;
    if (args.has("--json")) {
      try {
        json = std::make_unique<hemo::io::AtomicFile>(args.text("--json"));
      } catch (const hemo::io::WriteError& e) {
        throw std::runtime_error("cannot write --json file '" + args.text("--json") + "'");
      }
    }
    hemo::gpu::ContextOptions options;
    options.device = args.text("--device");
    Context ctx(options);
    const std::string host = hemo::cli::hostCpu();
    std::printf("device: %s (%s), host: %s\n", ctx.info().name.c_str(), ctx.info().typeName().c_str(), host.c_str());
    if (suite != "device" && !ctx.timestampsSupported()) {
      std::cerr << "hemo-bench: the device has no timestamp queries; GPU times are unavailable\n";
      return 3;
    }
    bool soakFlat = true;
    const Json rows = suite == "device"     ? deviceFacts(ctx)
                      : suite == "primitives" ? primitives(ctx, repeat)
                      : suite == "table1"     ? table1(ctx, std::max(1, repeat / 3))
                      : suite == "render"     ? render(ctx, repeat, std::filesystem::path(HEMO_SOURCE_DIR) / "scenes")
                      : suite == "speed"      ? speed(ctx, scene, scenePath, until, repeat)
                      : suite == "scale"      ? scale(ctx, repeat, maxParticles, ratio, search)
                      : suite == "soak"       ? soak(ctx, scene, scenePath, soakSteps, soakFlat)
                                              : accuracy(ctx, only, solverOnly);
    if (json) {
      json->stream() << Json{{"suite", suite}, {"device", ctx.info().name}, {"driver", ctx.driver()}, {"host_cpu", host}, {"rows", rows}}.dump(2) << "\n";
      json->commit();
    }
    if (hemo::cli::validationProblems(ctx, "hemo-bench")) return 3;
    if (!soakFlat) return 5;
  } catch (const hemo::cli::UsageError& e) {
    std::cerr << "hemo-bench: " << e.what() << "\n" << usage;
    return 1;
  } catch (const hemo::gpu::GpuError& e) {
    std::cerr << "hemo-bench: GPU error: " << e.what() << "\n";
    return 3;
  } catch (const hemo::sim::SimulationError& e) {
    std::cerr << "hemo-bench: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "hemo-bench: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
