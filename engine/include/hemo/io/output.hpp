#pragma once
// Output files: VTK particle files for ParaView and the run summary.
#include "hemo/sim/simulation.hpp"

#include <filesystem>
#include <string>

namespace hemo::io {

// Legacy VTK polydata (ASCII) of all particles: velocity (m/s), density (kg/m^3),
// pressure (Pa), kind (0 fluid, 1 boundary) and id. Throws std::runtime_error naming the file
// if it cannot be written.
void writeParticlesVtk(const std::filesystem::path& path, const sim::Snapshot& snapshot, double time);

}  // namespace hemo::io
