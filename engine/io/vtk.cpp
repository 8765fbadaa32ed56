#include "hemo/io/output.hpp"

#include <fstream>
#include <stdexcept>

namespace hemo::io {

void writeParticlesVtk(const std::filesystem::path& path, const sim::Snapshot& s, double time) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write VTK file '" + path.string() + "'");
  const std::size_t n = s.positions.size();
  out.precision(9);
  out << "# vtk DataFile Version 3.0\nhemo particles, t = " << time << " s\nASCII\nDATASET POLYDATA\n";
  out << "FIELD FieldData 1\nTIME 1 1 double\n" << time << "\n";
  out << "POINTS " << n << " float\n";
  for (const auto& p : s.positions) out << p.x << ' ' << p.y << ' ' << p.z << '\n';
  out << "VERTICES " << n << ' ' << 2 * n << '\n';
  for (std::size_t i = 0; i < n; ++i) out << "1 " << i << '\n';
  out << "POINT_DATA " << n << "\nVECTORS velocity_m_s float\n";
  for (const auto& v : s.velocities) out << v.x << ' ' << v.y << ' ' << v.z << '\n';
  out << "SCALARS density_kg_m3 float 1\nLOOKUP_TABLE default\n";
  for (const auto& d : s.densityPressure) out << d.x << '\n';
  out << "SCALARS pressure_pa float 1\nLOOKUP_TABLE default\n";
  for (const auto& d : s.densityPressure) out << d.y << '\n';
  out << "SCALARS kind int 1\nLOOKUP_TABLE default\n";
  for (const auto& v : s.velocities) out << int(v.w) << '\n';
  out << "SCALARS id unsigned_int 1\nLOOKUP_TABLE default\n";
  for (auto id : s.ids) out << id << '\n';
  if (!out) throw std::runtime_error("failed while writing VTK file '" + path.string() + "'");
}

}  // namespace hemo::io
