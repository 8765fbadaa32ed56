#pragma once
// Output files: VTK particle files for ParaView, PLY surfaces, and the run summary.
#include "hemo/sim/simulation.hpp"

#include <filesystem>
#include <functional>
#include <string>

namespace hemo::io {

// Per wall particle (by id): the largest strain (|x_a - x_b| / rest - 1, minimum image on
// periodic axes) of its unbroken springs and the fraction of its springs that broke; both 0 for
// particles without springs.
struct WallPointStats {
  std::vector<float> maxStrain;
  std::vector<float> brokenFraction;
};
WallPointStats wallPointStats(const sim::Snapshot& snapshot, const std::vector<sim::GpuSpring>& springs,
                              glm::vec3 period);

// Per spring: its strain |x_b - x_a| / rest - 1 (minimum image on periodic axes) and its
// tension (N, the elastic part k (|d| - rest); 0 once broken). Throws std::runtime_error if a
// spring names a particle the snapshot does not have.
struct SpringStats {
  std::vector<float> strain;
  std::vector<float> tension;
};
SpringStats springStats(const sim::Snapshot& snapshot, const std::vector<sim::GpuSpring>& springs, glm::vec3 period);

// Legacy VTK polydata (ASCII) of all particles: velocity (m/s), density (kg/m^3),
// pressure (Pa), kind (0 fluid, 1 boundary, 2 wall) and id; with springs also the wall's
// max_strain and broken_fraction (wallPointStats). Throws std::runtime_error naming the file
// if it cannot be written.
// With `shear` (per wall point id; hemo/sim/simulation.hpp, Simulation::readWallShear) also
// the wall maps: wss_Pa (the last step's wall shear stress), tawss_Pa and osi (0 for
// particles that are not wall points).
struct WallShearFields {
  const std::vector<glm::vec3>* wss = nullptr;
  const std::vector<float>* tawss = nullptr;
  const std::vector<float>* osi = nullptr;
};
// The wall maps per row of the snapshot, as both particle writers store them: wss xyz (3 per
// row), tawss and osi, the wall point's values for wall rows, 0 for the rest.
struct WallShearArrays {
  std::vector<float> wss, tawss, osi;
};
WallShearArrays wallShearArrays(const sim::Snapshot& snapshot, const WallShearFields& shear);
void writeParticlesVtk(const std::filesystem::path& path, const sim::Snapshot& snapshot, double time,
                       const std::vector<sim::GpuSpring>* springs = nullptr, glm::vec3 period = glm::vec3(0.0f),
                       const WallShearFields* shear = nullptr);

// The spring network as VTK lines between particle positions, with per-spring strain,
// tension (N, the elastic part k (|d| - rest)) and broken flag (0/1). A spring across a
// periodic seam is drawn between the wrapped positions; its strain uses the minimum image.
void writeSpringsVtk(const std::filesystem::path& path, const sim::Snapshot& snapshot,
                     const std::vector<sim::GpuSpring>& springs, double time, glm::vec3 period);

// The same particles and springs as binary VTK XML, which ParaView loads without parsing text
// (about 50 B per particle against the legacy files' 100): particles as an UnstructuredGrid
// (.vtu) of vertex cells with the same point arrays (kind as UInt8) and positions named
// position_m; springs as PolyData (.vtp) lines with the same cell arrays (broken as UInt8).
// Every array is appended raw (UInt64 byte counts, the host's byte order, named in the
// header), and the time (s) is the field TimeValue. Throws std::runtime_error naming the file
// if it cannot be written.
void writeParticlesVtu(const std::filesystem::path& path, const sim::Snapshot& snapshot, double time,
                       const std::vector<sim::GpuSpring>* springs = nullptr, glm::vec3 period = glm::vec3(0.0f),
                       const WallShearFields* shear = nullptr);
void writeSpringsVtp(const std::filesystem::path& path, const sim::Snapshot& snapshot,
                     const std::vector<sim::GpuSpring>& springs, double time, glm::vec3 period);

// A ParaView time series (.pvd): the files written so far, each with its time, named relative
// to the .pvd's folder. add() rewrites the whole .pvd (atomically), so it lists every frame
// written even if the run stops. With `keep`, the entries of an existing .pvd for which it
// returns true are kept first (a resumed run keeps the frames before its checkpoint).
class PvdSeries {
 public:
  explicit PvdSeries(std::filesystem::path path, const std::function<bool(const std::string& file)>& keep = {});
  void add(double time, const std::string& file);
  std::size_t size() const { return entries_.size(); }

 private:
  struct Entry {
    double time;
    std::string file;
  };
  std::filesystem::path path_;
  std::vector<Entry> entries_;
};

}  // namespace hemo::io

namespace hemo::io {

// A surface mesh with shared vertices: the GPU's per-triangle vertices welded where their
// positions are bit-identical (marching cubes computes a shared edge's vertex identically in
// both voxels), in first-use order.
struct IndexedMesh {
  std::vector<glm::vec3> positions;  // m
  std::vector<glm::vec3> normals;    // unit, outward
  std::vector<std::uint32_t> indices;  // 3 per triangle
};
IndexedMesh weld(const std::vector<surface::McVertex>& vertices);

// Binary little-endian PLY (float x y z nx ny nz per vertex, faces as uchar count + uint
// indices), positions in m; comments give the units, the time (s) and, if the triangle
// buffer overflowed, how many triangles are missing. Throws std::runtime_error naming the
// file if it cannot be written.
void writeSurfacePly(const std::filesystem::path& path, const surface::SurfaceMesh& mesh, double time);

}  // namespace hemo::io
