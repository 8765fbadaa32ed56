#pragma once
// Scene files: JSON with named sections and SI units in the key names. One table
// (sceneSchema()) lists every parameter with its unit, range, default and description; it
// drives loading, validation and docs/scene-format.md.
#include "hemo/sim/sph.hpp"

#include <glm/vec3.hpp>
#include <glm/vector_relational.hpp>

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemo::scene {

class VesselMesh;

// Bad scene input (hemo-run exit code 1). The message names the file, the field and the problem.
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Box {
  glm::vec3 min{0.0f};  // m
  glm::vec3 max{0.0f};  // m
};

struct FluidBlock {
  // How the block is filled. Cubic: the dp lattice. Body-centred cubic: cells of edge
  // 2^(1/3) dp (two particles each, so the same number of particles per volume), stretched by
  // a few per cent per axis so a whole number of cells fills the box. Under pressure the
  // simple cubic arrangement is not a stable equilibrium of the SPH pressure force (it shears
  // into another packing; docs/physics.md), the body-centred one is.
  enum class Lattice { Cubic, BodyCentred };
  Box box;
  glm::vec3 velocity{0.0f};  // m/s
  Lattice lattice = Lattice::Cubic;
};

// A rigid container: `layers` layers of boundary particles just outside the box, on every
// face except the top (+z) when openTop and the faces across periodic axes.
struct Tank {
  Box box;
  std::uint32_t layers = 3;
  bool openTop = true;
  glm::bvec3 periodic{false};  // set from the domain: no walls across these axes
};

// A vessel built of wall particles and springs, its axis along +x from `start`; filled with
// fluid. Shapes: a straight tube, a tube with a saccular aneurysm (a spherical sac on its
// +z side, halfway along), with a fusiform aneurysm (a bulge all round, halfway along), or a
// bifurcation (two branches that split off at +-angle in the x-y plane and merge again, halfway
// along a periodic tube). Periodic along x when the domain is (the tube then spans it).
// A part of a mesh vessel's wall with other tissue: springs whose midpoint lies in the sphere
// take the scales.
struct MeshRegion {
  glm::vec3 centre{0.0f};  // m
  float radius = 0.0f;     // m
  float stiffnessScale = 1.0f;
  float strengthScale = 1.0f;
};

// A vessel can also come from a triangle surface of its lumen (Shape::Mesh, an STL or OBJ
// file; hemo/scene/mesh_vessel.hpp): start, length and radius then describe its ends (start:
// the domain's min x and the inlet's centre; radius: the inlet's equivalent radius).
struct Vessel {
  enum class Shape { Tube, SaccularAneurysm, FusiformAneurysm, Bifurcation, Mesh };
  Shape shape = Shape::Tube;
  glm::vec3 start{0.0f};       // m, where the axis starts
  float length = 0.0f;         // m
  float radius = 0.0f;         // m, inner radius (the fluid fills r < radius)
  std::uint32_t layers = 2;    // wall layers
  float pointMass = 0.0f;      // kg per wall point
  float stiffness = 0.0f;      // N/m per spring
  float damping = 0.0f;        // N s/m per spring
  float maxForce = 0.0f;       // N: a spring breaks above this tension
  bool anchorEnds = true;      // non-periodic tubes: end rings fixed
  bool periodic = false;       // set from the domain
  float sacRadius = 0.0f;      // m (saccular aneurysm)
  float neckWidth = 0.0f;      // m
  float sacStiffnessScale = 1.0f;
  float sacStrengthScale = 1.0f;
  float bulgeRadius = 0.0f;    // m (fusiform aneurysm): inner radius at the bulge's middle
  float bulgeLength = 0.0f;    // m: axial length of the bulge
  float branchAngle = 0.0f;    // rad (bifurcation): each branch's angle to the parent's axis
  float branchLength = 0.0f;   // m: each leg, split -> bend and bend -> merge
  float timeStepFactor = 0.1f;  // the wall's dt <= factor sqrt(m / sum k) (sim::SpringNetwork)
  std::uint32_t substeps = 1;    // the wall's substeps per fluid step (sim::SpringNetwork::substeps)
  // Tissue properties, when the scene gives them instead of stiffness / max force (0: not
  // given); the loader maps them onto the springs with scene::springsFromTissue.
  float youngsModulus = 0.0f;   // Pa
  float poissonRatio = 0.45f;
  float wallThickness = 0.0f;   // m
  float failureStress = 0.0f;   // Pa
  // Driven inflow at the start of a periodic tube (the outflow comes back through the seam);
  // none when the scene's vessel.inflow.profile is "none".
  std::optional<sim::Inflow> inflow;
  // Open ends (inflow->open, vessel.outlet): the free fluid slots beyond those the outlet frees
  // (0: automatic, scene::reserveParticles).
  std::uint32_t reserveParticles = 0;
  // Shape::Mesh: the checked surface in metres, and the role the scene gave each of its ends
  // (VesselMesh::ends order): "inlet" or "outlet".
  std::shared_ptr<const VesselMesh> mesh;
  std::vector<std::string> endRoles;
  std::vector<MeshRegion> meshRegions;
  // Shape::Mesh with open ends (vessel.outlet): the inlet's and the outlets' frames, from the
  // mesh's loops (their caps' centres, inward normals and equivalent radii; the outlets in the
  // order of the scene's vessel.mesh.ends; the buffers' lengths and reach are set with the rest of the
  // open ends).
  sim::OpenEnd meshInlet;
  std::vector<sim::OpenEnd> meshOutlets;
  std::vector<std::size_t> meshOutletEntries;  // each outlet's entry in vessel.mesh.ends
  std::map<std::size_t, float> meshEndPressures;  // entry -> its own pressure_Pa, where given
};

// The blood surface's grid (hemo/surface/marching_cubes.hpp).
struct SurfaceSpec {
  std::uint32_t resolution = 128;  // voxels along the longest side
  float iso = 0.5f;
  std::uint32_t maxTriangles = 0;  // 0: automatic
  float splatVoxelOverH = 0.5f;    // splat grid voxel in h (0: splat on the surface grid)
};

struct Scene {
  std::string name;
  std::string description;
  sim::SphSettings sph;
  float expectedMaxSpeed = 0.0f;  // m/s (c0 = 10x this unless given)
  std::vector<FluidBlock> blocks;
  std::vector<Tank> tanks;
  std::optional<Vessel> vessel;
  Box domain;
  double endTime = 1.0;             // s
  double minTimeStep = 0.0;         // s; the run stops when the step falls below it (0: automatic)
  std::uint32_t stepsPerBatch = 64;  // steps recorded per submit
  SurfaceSpec surface;
  // Surgical tools (hemo/sim/tools.hpp), with their keyframed paths; none: no tool stage runs.
  std::vector<sim::ToolSpec> tools;
};

// `baseDir`: where files the scene names by relative path (a vessel's mesh) are looked up;
// loadScene passes the scene file's directory.
Scene parseScene(const std::string& jsonText, const std::string& sourceName, const std::filesystem::path& baseDir = {});
Scene loadScene(const std::filesystem::path& path);
// The rules for periodic axes (a whole number of spacings, at least 2.5 neighbour-list
// radii, tanks spanning the period); throws SceneError naming `source` and the field. Run by
// the loader (every periodic axis), and again by anything that edits a loaded scene's
// geometry (`axis` 0-2: only that axis).
void checkPeriodicAxes(const Scene& scene, const std::string& source, int axis = -1);

// One row per parameter, for docs and tools.
struct FieldDoc {
  std::string path;  // e.g. "fluid.blocks[].min_m"
  std::string type;
  std::string unit;
  std::string range;
  std::string defaultValue;
  std::string description;
};
std::vector<FieldDoc> sceneSchema();
// docs/scene-format.md's table, generated from sceneSchema().
std::string schemaMarkdown();

}  // namespace hemo::scene
