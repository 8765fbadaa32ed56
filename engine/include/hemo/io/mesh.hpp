#pragma once
// Triangle surface meshes: STL (binary or ASCII) and Wavefront OBJ, the formats 3D Slicer,
// vmtk, the Vascular Model Repository and AneuriskWeb export vessel lumens in.
//
// The readers are the project's own (a few hundred lines): a vessel needs only positions and
// triangles, and the scene loader checks the topology itself with errors that name the
// triangle or edge at fault (hemo/scene/mesh_vessel.hpp), which a general importer that
// repairs, merges or triangulates silently would hide. STL stores each triangle's corners
// separately; corners with bit-identical coordinates are joined into one vertex (what every
// exporter writes for a shared corner), so a mesh's edges are shared by index.
#include <array>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace hemo::io {

// A mesh file that cannot be read: the message names the file and, where it can, the line or
// the triangle.
class MeshError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct TriangleMesh {
  std::vector<glm::dvec3> vertices;                   // in the file's units until scaled
  std::vector<std::array<std::uint32_t, 3>> triangles;  // counter-clockwise seen from outside
};

// Reads `path` by its extension (.stl or .obj, any case). A binary STL is recognised by its
// size (84 + 50 n bytes for the n triangles its header counts); anything else must be ASCII
// STL. OBJ: 'v' and 'f' records (polygons are fanned into triangles; 'v/t/n' references and
// negative indices are understood), everything else is skipped. Throws MeshError.
TriangleMesh readMesh(const std::filesystem::path& path);
TriangleMesh readStl(const std::filesystem::path& path);
TriangleMesh readObj(const std::filesystem::path& path);

// Writes a binary STL (facet normals from the corners; float coordinates), through a temporary
// file renamed when complete (hemo/io/atomic_file.hpp). Throws std::runtime_error naming the
// file when it cannot be written.
void writeStl(const std::filesystem::path& path, const TriangleMesh& mesh, const std::string& header = "hemo");

}  // namespace hemo::io
