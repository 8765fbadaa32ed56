// hemo-neighbours [--particles N] [--device SEL] [--seed S]
// The neighbour-search demo (the main job until the SPH and aneurysm stages land): builds the
// cell-linked list of N particles on the GPU, lists every particle's neighbours within the
// support radius, and checks a sample of them against an O(N^2) double-precision search.
// Exit codes: 0 success, 1 bad arguments, 2 the GPU result disagrees with the reference,
// 3 no usable Vulkan device or a device error.
#include "cli.hpp"
#include "hemo/reference/neighbours.hpp"
#include "hemo/sim/neighbour_grid.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <random>

int main(int argc, char** argv) {
  const char* usage = "usage: hemo-neighbours [--particles N] [--device SEL] [--seed S] [--help]\n";
  if (hemo::cli::printUsageIfAsked(argc, argv, usage)) return 0;
  try {
    const auto args = hemo::cli::parse(argc, argv, {"--particles", "--device", "--seed"});
    if (!args.positional.empty()) throw hemo::cli::UsageError("unexpected argument '" + args.positional[0] + "'");
    const auto n = static_cast<std::uint32_t>(args.count("--particles", 100000, 1, 8000000));
    const std::uint64_t seed = args.count("--seed", 1, 0, ~0ull);

    hemo::gpu::ContextOptions options;
    options.device = args.text("--device");
    hemo::gpu::Context ctx(options);
    std::printf("device        %s (%s)\n", ctx.info().name.c_str(), ctx.info().typeName().c_str());

    // A block of blood-like particles: spacing dp, support radius 2 dp, slightly jittered,
    // in random order (as if nothing had been sorted yet).
    const float dp = 1.0e-4f;  // m (0.1 mm)
    const float radius = 2.0f * dp;
    const auto side = static_cast<std::uint32_t>(std::ceil(std::cbrt(double(n))));
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> jitter(-0.3f * dp, 0.3f * dp);
    std::vector<glm::vec4> pos(n), vel(n);
    for (std::uint32_t i = 0; i < n; ++i) {
      const glm::vec3 lattice(float(i % side), float((i / side) % side), float(i / (side * side)));
      pos[i] = glm::vec4((lattice + 0.5f) * dp + glm::vec3(jitter(rng), jitter(rng), jitter(rng)), 1.0f);
      vel[i] = glm::vec4(0.0f);
    }
    std::shuffle(pos.begin(), pos.end(), rng);

    hemo::sim::ParticleStore store(ctx, n);
    const auto spec = hemo::sim::GridSpec::covering({0, 0, 0}, glm::vec3(float(side) * dp), radius);
    hemo::sim::NeighbourGrid grid(ctx, spec, store);
    const std::uint32_t capacity = 64;
    hemo::sim::NeighbourList nlist(ctx, grid, store, radius, capacity);

    hemo::gpu::CommandRecorder rec(ctx);
    hemo::gpu::TimestampQueries ts(ctx, 16);
    double wallMs = 0.0;
    // Twice from the same shuffled input: the first run pays for compiling the shaders on
    // drivers that compile at first use (lavapipe); the second is the one reported.
    for (int run = 0; run < 2; ++run) {
      store.upload(pos, vel);
      rec.begin();
      ts.reset(rec);
      ts.mark(rec, "start");
      grid.resetCounters(rec);
      grid.record(rec, n, &ts);
      nlist.record(rec, n);
      ts.mark(rec, "neighbour list");
      rec.end();
      const auto t0 = std::chrono::steady_clock::now();
      rec.submitAndWait();
      wallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    }

    const auto counts = nlist.counts().readback<std::uint32_t>(n);
    const auto list = nlist.list().readback<std::uint32_t>(std::uint64_t(n) * capacity);
    const auto sorted = store.readPositions();
    const auto counters = grid.readCounters();

    std::uint64_t total = 0;
    std::uint32_t maxCount = 0;
    for (auto c : counts) {
      total += c;
      maxCount = std::max(maxCount, c);
    }
    std::printf("particles     %u (spacing %.3g m, support radius %.3g m)\n", n, double(dp), double(radius));
    std::printf("grid          %ux%ux%u cells of %.3g m\n", spec.dims.x, spec.dims.y, spec.dims.z, double(spec.cellSize));
    for (const auto& [stage, ms] : ts.stageMs()) std::printf("%-13s %.3f ms (GPU)\n", stage.c_str(), ms);
    std::printf("submit+wait   %.3f ms (host clock)\n", wallMs);
    std::printf("neighbours    %.2f per particle on average, %u at most\n", double(total) / n, maxCount);
    std::printf("outside grid  %u, non-finite %u\n", counters.outside, counters.nonFinite);

    // Check a sample of particles against brute force over all particles (double precision).
    std::vector<glm::dvec3> all(n);
    for (std::uint32_t i = 0; i < n; ++i) all[i] = glm::dvec3(sorted[i]);
    const std::uint32_t samples = std::min<std::uint32_t>(n, 500);
    std::uint32_t bad = 0;
    for (std::uint32_t s = 0; s < samples; ++s) {
      const std::uint32_t i = static_cast<std::uint32_t>((std::uint64_t(s) * 2654435761u) % n);
      std::vector<std::uint32_t> want;
      for (std::uint32_t j = 0; j < n; ++j) {
        if (j != i && glm::dot(all[i] - all[j], all[i] - all[j]) < double(radius) * radius) want.push_back(j);
      }
      std::vector<std::uint32_t> got(list.begin() + std::uint64_t(i) * capacity,
                                     list.begin() + std::uint64_t(i) * capacity + std::min(counts[i], capacity));
      if (counts[i] > capacity || got != want) ++bad;
    }
    std::printf("check         %u of %u sampled particles match brute force\n", samples - bad, samples);
    if (hemo::cli::validationProblems(ctx, "hemo-neighbours")) return 3;
    return bad == 0 ? 0 : 2;
  } catch (const hemo::cli::UsageError& e) {
    std::cerr << "hemo-neighbours: " << e.what() << "\n" << usage;
    return 1;
  } catch (const hemo::gpu::GpuError& e) {
    std::cerr << "hemo-neighbours: GPU error: " << e.what() << "\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "hemo-neighbours: " << e.what() << "\n";
    return 1;
  }
}
