#include "hemo/io/output.hpp"

#include "hemo/io/atomic_file.hpp"

#include <bit>
#include <cstring>
#include <ostream>
#include <stdexcept>
#include <unordered_map>

namespace hemo::io {
namespace {

struct PositionBits {
  std::uint32_t x, y, z;
  bool operator==(const PositionBits&) const = default;
};
struct PositionHash {
  std::size_t operator()(const PositionBits& p) const {
    std::uint64_t h = p.x;
    h = h * 0x9E3779B97F4A7C15ull ^ p.y;
    h = h * 0x9E3779B97F4A7C15ull ^ p.z;
    return std::size_t(h ^ (h >> 29));
  }
};

template <class T>
void put(std::ostream& out, T value) {
  static_assert(std::endian::native == std::endian::little, "PLY output assumes a little-endian host");
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

}  // namespace

IndexedMesh weld(const std::vector<surface::McVertex>& vertices) {
  IndexedMesh mesh;
  std::unordered_map<PositionBits, std::uint32_t, PositionHash> ids;
  ids.reserve(vertices.size() / 2);
  mesh.indices.reserve(vertices.size());
  for (const surface::McVertex& v : vertices) {
    PositionBits key;
    std::memcpy(&key, &v.position, sizeof(key));
    const auto [it, added] = ids.emplace(key, std::uint32_t(mesh.positions.size()));
    if (added) {
      mesh.positions.emplace_back(v.position);
      mesh.normals.emplace_back(v.normal);
    }
    mesh.indices.push_back(it->second);
  }
  return mesh;
}

void writeSurfacePly(const std::filesystem::path& path, const surface::SurfaceMesh& surface, double time) {
  const IndexedMesh mesh = weld(surface.vertices);
  AtomicFile file(path);
  std::ostream& out = file.stream();
  char timeText[64];
  std::snprintf(timeText, sizeof timeText, "%.9g", time);
  out << "ply\nformat binary_little_endian 1.0\n"
      << "comment hemo blood surface (marching cubes), positions in m, normals unit outward\n"
      << "comment time_s " << timeText << "\n";
  if (surface.totals.overflow()) {
    out << "comment incomplete: " << surface.totals.written << " of " << surface.totals.triangles
        << " triangles (raise surface.max_triangles)\n";
  }
  out << "element vertex " << mesh.positions.size() << "\n"
      << "property float x\nproperty float y\nproperty float z\n"
      << "property float nx\nproperty float ny\nproperty float nz\n"
      << "element face " << mesh.indices.size() / 3 << "\n"
      << "property list uchar uint vertex_indices\nend_header\n";
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    for (int a = 0; a < 3; ++a) put(out, mesh.positions[v][a]);
    for (int a = 0; a < 3; ++a) put(out, mesh.normals[v][a]);
  }
  for (std::size_t t = 0; t < mesh.indices.size() / 3; ++t) {
    put(out, std::uint8_t(3));
    for (int k = 0; k < 3; ++k) put(out, mesh.indices[3 * t + k]);
  }
  file.commit();
}

}  // namespace hemo::io
