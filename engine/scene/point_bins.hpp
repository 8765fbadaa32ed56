#pragma once
// Shared by the vessel builders (engine/scene/): wall and fluid points binned for the
// builders' neighbourhood queries, periodic along x or not.
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace hemo::scene {

// Points binned in cubes of `cell` (periodic along x with the given period; a period many
// times the scene's size makes it not periodic) for the neighbourhood queries of the
// builders (all within one cell).
class Bins {
 public:
  Bins(double x0, double period, double cell) : x0_(x0), period_(period), cell_(cell) {
    nx_ = std::max<long>(1, static_cast<long>(std::floor(period / cell)));
    cellX_ = period / nx_;
  }
  void add(glm::dvec3 p, std::uint32_t id) {
    points_.push_back(p);
    ids_.push_back(id);
    bins_[key(ix(p.x), long(std::floor(p.y / cell_)), long(std::floor(p.z / cell_)))].push_back(std::uint32_t(points_.size() - 1));
  }
  glm::dvec3 separation(glm::dvec3 p, glm::dvec3 q) const {
    glm::dvec3 d = q - p;
    d.x -= period_ * std::round(d.x / period_);
    return d;
  }
  // Calls f(id, separation) for every binned point nearer than `radius` (<= cell) to p.
  template <class F>
  void near(glm::dvec3 p, double radius, F&& f) const {
    const long cx = ix(p.x), cy = long(std::floor(p.y / cell_)), cz = long(std::floor(p.z / cell_));
    long xs[3];
    int nxs = 0;
    for (long o = -1; o <= 1; ++o) {
      const long x = ((cx + o) % nx_ + nx_) % nx_;
      if (std::find(xs, xs + nxs, x) == xs + nxs) xs[nxs++] = x;
    }
    for (int a = 0; a < nxs; ++a)
      for (long y = cy - 1; y <= cy + 1; ++y)
        for (long z = cz - 1; z <= cz + 1; ++z) {
          const auto it = bins_.find(key(xs[a], y, z));
          if (it == bins_.end()) continue;
          for (std::uint32_t k : it->second) {
            const glm::dvec3 d = separation(p, points_[k]);
            if (glm::length(d) < radius) f(ids_[k], d);
          }
        }
  }

 private:
  long ix(double x) const {
    const long i = static_cast<long>(std::floor((x - x0_) / cellX_));
    return ((i % nx_) + nx_) % nx_;
  }
  static std::int64_t key(long x, long y, long z) {
    return (std::int64_t(x) * 2000003 + std::int64_t(y)) * 2000003 + std::int64_t(z);
  }
  double x0_, period_, cell_, cellX_;
  long nx_;
  std::vector<glm::dvec3> points_;
  std::vector<std::uint32_t> ids_;
  std::unordered_map<std::int64_t, std::vector<std::uint32_t>> bins_;
};

}  // namespace hemo::scene
