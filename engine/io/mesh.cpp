#include "hemo/io/mesh.hpp"

#include "hemo/io/atomic_file.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

namespace hemo::io {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

std::string readAll(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MeshError(path.string() + ": cannot open the mesh file");
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw MeshError(path.string() + ": cannot read the mesh file");
  return s.str();
}

// Joins corners with bit-identical coordinates into one vertex.
class Welder {
 public:
  explicit Welder(TriangleMesh& mesh) : mesh_(mesh) {}
  std::uint32_t vertex(float x, float y, float z) {
    const auto key = std::array<std::uint32_t, 3>{bits(x), bits(y), bits(z)};
    const auto [it, added] = index_.try_emplace(key, std::uint32_t(mesh_.vertices.size()));
    if (added) mesh_.vertices.emplace_back(x, y, z);
    return it->second;
  }

 private:
  static std::uint32_t bits(float v) {
    if (v == 0.0f) v = 0.0f;  // -0 and +0 are the same place
    std::uint32_t u;
    std::memcpy(&u, &v, sizeof u);
    return u;
  }
  TriangleMesh& mesh_;
  std::map<std::array<std::uint32_t, 3>, std::uint32_t> index_;
};

// `where` names the place (built only for the message).
template <class Where>
void checkFinite(const std::filesystem::path& path, const glm::dvec3& p, Where where) {
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
    throw MeshError(path.string() + ": " + where() + " has a coordinate that is not a finite number");
  }
}

TriangleMesh readBinaryStl(const std::filesystem::path& path, const std::string& bytes, std::uint32_t count) {
  TriangleMesh mesh;
  Welder weld(mesh);
  mesh.triangles.reserve(count);
  for (std::uint32_t t = 0; t < count; ++t) {
    const char* rec = bytes.data() + 84 + 50 * std::size_t(t);
    float c[9];
    std::memcpy(c, rec + 12, sizeof c);  // after the facet normal, which is recomputed from the corners
    std::array<std::uint32_t, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      checkFinite(path, glm::dvec3(c[3 * k], c[3 * k + 1], c[3 * k + 2]), [&] { return "triangle " + std::to_string(t); });
      tri[k] = weld.vertex(c[3 * k], c[3 * k + 1], c[3 * k + 2]);
    }
    mesh.triangles.push_back(tri);
  }
  return mesh;
}

TriangleMesh readAsciiStl(const std::filesystem::path& path, const std::string& text) {
  TriangleMesh mesh;
  Welder weld(mesh);
  std::istringstream in(text);
  std::string line;
  std::size_t lineNo = 0;
  std::vector<std::uint32_t> corners;
  bool inFacet = false, sawSolid = false;
  auto fail = [&](const std::string& what) { throw MeshError(path.string() + ":" + std::to_string(lineNo) + ": " + what); };
  while (std::getline(in, line)) {
    ++lineNo;
    std::istringstream words(line);
    std::string word;
    if (!(words >> word)) continue;
    word = lower(word);
    if (word == "solid") {
      sawSolid = true;
    } else if (word == "facet") {
      if (inFacet) fail("'facet' inside another facet");
      inFacet = true;
      corners.clear();
    } else if (word == "vertex") {
      if (!inFacet) fail("'vertex' outside a facet");
      double x, y, z;
      if (!(words >> x >> y >> z)) fail("expected three numbers after 'vertex'");
      checkFinite(path, {x, y, z}, [&] { return "line " + std::to_string(lineNo); });
      corners.push_back(weld.vertex(float(x), float(y), float(z)));
    } else if (word == "endfacet") {
      if (!inFacet) fail("'endfacet' without 'facet'");
      if (corners.size() != 3) fail("a facet needs exactly 3 vertices, this one has " + std::to_string(corners.size()));
      mesh.triangles.push_back({corners[0], corners[1], corners[2]});
      inFacet = false;
    } else if (word != "outer" && word != "endloop" && word != "endsolid") {
      fail("unexpected '" + word + "' (neither ASCII STL nor a binary STL of consistent size)");
    }
  }
  if (!sawSolid) throw MeshError(path.string() + ": not an STL file (no 'solid' line, and not the size of a binary STL)");
  if (inFacet) throw MeshError(path.string() + ": ends inside a facet (truncated?)");
  return mesh;
}

// An OBJ face corner "v", "v/t", "v//n" or "v/t/n"; 1-based, negative counts from the end.
std::uint32_t objIndex(const std::string& corner, std::size_t vertices, const std::function<void(const std::string&)>& fail) {
  const std::string v = corner.substr(0, corner.find('/'));
  long long k = 0;
  try {
    std::size_t used = 0;
    k = std::stoll(v, &used);
    if (used != v.size()) fail("face corner '" + corner + "' is not an index");
  } catch (const std::logic_error&) {
    fail("face corner '" + corner + "' is not an index");
  }
  if (k < 0) k += static_cast<long long>(vertices) + 1;
  if (k < 1 || k > static_cast<long long>(vertices)) {
    fail("face corner '" + corner + "' refers to vertex " + std::to_string(k) + ", but " + std::to_string(vertices) + " are defined so far");
  }
  return static_cast<std::uint32_t>(k - 1);
}

}  // namespace

TriangleMesh readStl(const std::filesystem::path& path) {
  const std::string bytes = readAll(path);
  if (bytes.size() >= 84) {
    std::uint32_t count;
    std::memcpy(&count, bytes.data() + 80, sizeof count);
    if (bytes.size() == 84 + 50 * std::uint64_t(count)) return readBinaryStl(path, bytes, count);
  }
  return readAsciiStl(path, bytes);
}

TriangleMesh readObj(const std::filesystem::path& path) {
  const std::string text = readAll(path);
  TriangleMesh mesh;
  std::istringstream in(text);
  std::string line;
  std::size_t lineNo = 0;
  const std::function<void(const std::string&)> fail = [&](const std::string& what) {
    throw MeshError(path.string() + ":" + std::to_string(lineNo) + ": " + what);
  };
  while (std::getline(in, line)) {
    ++lineNo;
    std::istringstream words(line);
    std::string word;
    if (!(words >> word)) continue;
    if (word == "v") {
      double x, y, z;
      if (!(words >> x >> y >> z)) fail("expected three numbers after 'v'");
      checkFinite(path, {x, y, z}, [&] { return "line " + std::to_string(lineNo); });
      mesh.vertices.emplace_back(x, y, z);
    } else if (word == "f") {
      std::vector<std::uint32_t> poly;
      std::string corner;
      while (words >> corner) poly.push_back(objIndex(corner, mesh.vertices.size(), fail));
      if (poly.size() < 3) fail("a face needs at least 3 corners, this one has " + std::to_string(poly.size()));
      for (std::size_t k = 1; k + 1 < poly.size(); ++k) mesh.triangles.push_back({poly[0], poly[k], poly[k + 1]});
    }
  }
  if (mesh.triangles.empty()) throw MeshError(path.string() + ": no faces ('f' records)");
  return mesh;
}

TriangleMesh readMesh(const std::filesystem::path& path) {
  const std::string ext = lower(path.extension().string());
  if (ext == ".stl") return readStl(path);
  if (ext == ".obj") return readObj(path);
  throw MeshError(path.string() + ": unknown mesh format '" + path.extension().string() + "' (expected .stl or .obj)");
}

void writeStl(const std::filesystem::path& path, const TriangleMesh& mesh, const std::string& header) {
  AtomicFile file(path);
  std::ostream& out = file.stream();
  char head[80] = {};
  std::memcpy(head, header.data(), std::min<std::size_t>(header.size(), sizeof head));
  out.write(head, sizeof head);
  const auto count = static_cast<std::uint32_t>(mesh.triangles.size());
  out.write(reinterpret_cast<const char*>(&count), sizeof count);
  for (const auto& t : mesh.triangles) {
    const glm::dvec3 a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
    glm::dvec3 n = glm::cross(b - a, c - a);
    const double len = glm::length(n);
    n = len > 0.0 ? n / len : glm::dvec3(0.0);
    float rec[12];
    for (int k = 0; k < 3; ++k) {
      rec[k] = float(n[k]);
      rec[3 + k] = float(a[k]);
      rec[6 + k] = float(b[k]);
      rec[9 + k] = float(c[k]);
    }
    out.write(reinterpret_cast<const char*>(rec), sizeof rec);
    const std::uint16_t attributes = 0;
    out.write(reinterpret_cast<const char*>(&attributes), sizeof attributes);
  }
  file.commit();
}

}  // namespace hemo::io
