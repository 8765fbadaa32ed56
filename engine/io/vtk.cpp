#include "hemo/io/output.hpp"

#include "hemo/io/atomic_file.hpp"
#include "interface/sph.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hemo::io {

namespace {

glm::dvec3 minImage(glm::dvec3 d, glm::vec3 period) {
  for (int a = 0; a < 3; ++a) {
    if (period[a] > 0.0f) d[a] -= double(period[a]) * std::round(d[a] / double(period[a]));
  }
  return d;
}

double springLength(const sim::Snapshot& s, const sim::GpuSpring& k, glm::vec3 period) {
  return glm::length(minImage(glm::dvec3(s.positions[k.b]) - glm::dvec3(s.positions[k.a]), period));
}

std::ostream& vtkHeader(AtomicFile& file, const std::string& title, double time) {
  std::ostream& out = file.stream();
  out.precision(9);
  out << "# vtk DataFile Version 3.0\n" << title << ", t = " << time << " s\nASCII\nDATASET POLYDATA\n";
  out << "FIELD FieldData 1\nTIME 1 1 double\n" << time << "\n";
  return out;
}

void checkSprings(const sim::Snapshot& s, const std::vector<sim::GpuSpring>& springs) {
  for (const auto& k : springs) {
    if (k.a >= s.positions.size() || k.b >= s.positions.size()) {
      throw std::runtime_error("a spring refers to particle ids beyond the snapshot");
    }
  }
}

}  // namespace

SpringStats springStats(const sim::Snapshot& s, const std::vector<sim::GpuSpring>& springs, glm::vec3 period) {
  checkSprings(s, springs);
  SpringStats out;
  out.strain.reserve(springs.size());
  out.tension.reserve(springs.size());
  for (const auto& k : springs) {
    const double length = springLength(s, k, period);
    out.strain.push_back(float(length / k.restLength - 1.0));
    out.tension.push_back(k.broken ? 0.0f : float(k.stiffness * (length - k.restLength)));
  }
  return out;
}

WallPointStats wallPointStats(const sim::Snapshot& s, const std::vector<sim::GpuSpring>& springs, glm::vec3 period) {
  checkSprings(s, springs);
  const std::size_t n = s.positions.size();
  WallPointStats w;
  w.maxStrain.assign(n, 0.0f);
  w.brokenFraction.assign(n, 0.0f);
  std::vector<std::uint32_t> total(n, 0), broken(n, 0);
  for (const auto& k : springs) {
    ++total[k.a];
    ++total[k.b];
    if (k.broken) {
      ++broken[k.a];
      ++broken[k.b];
      continue;
    }
    const float strain = float(springLength(s, k, period) / k.restLength - 1.0);
    w.maxStrain[k.a] = std::max(w.maxStrain[k.a], strain);
    w.maxStrain[k.b] = std::max(w.maxStrain[k.b], strain);
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (total[i]) w.brokenFraction[i] = float(broken[i]) / float(total[i]);
  }
  return w;
}

WallShearArrays wallShearArrays(const sim::Snapshot& s, const WallShearFields& shear) {
  const std::size_t n = s.positions.size();
  WallShearArrays a{std::vector<float>(3 * n, 0.0f), std::vector<float>(n, 0.0f), std::vector<float>(n, 0.0f)};
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t id = s.ids[i];
    if (id >= shear.wss->size() || std::uint32_t(s.velocities[i].w) != HEMO_KIND_WALL) continue;
    for (int c = 0; c < 3; ++c) a.wss[3 * i + std::size_t(c)] = (*shear.wss)[id][c];
    a.tawss[i] = (*shear.tawss)[id];
    a.osi[i] = (*shear.osi)[id];
  }
  return a;
}

void writeParticlesVtk(const std::filesystem::path& path, const sim::Snapshot& s, double time,
                       const std::vector<sim::GpuSpring>* springs, glm::vec3 period, const WallShearFields* shear) {
  AtomicFile file(path);
  std::ostream& out = vtkHeader(file, "hemo particles", time);
  const std::size_t n = s.positions.size();
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
  out << "SCALARS mass_kg float 1\nLOOKUP_TABLE default\n";
  for (const auto& p : s.positions) out << p.w << '\n';
  out << "SCALARS id unsigned_int 1\nLOOKUP_TABLE default\n";
  for (auto id : s.ids) out << id << '\n';
  if (s.viscosity.size() == n) {
    out << "SCALARS viscosity_Pa_s float 1\nLOOKUP_TABLE default\n";
    for (float x : s.viscosity) out << x << '\n';
  }
  if (springs) {
    const WallPointStats w = wallPointStats(s, *springs, period);
    out << "SCALARS max_strain float 1\nLOOKUP_TABLE default\n";
    for (float x : w.maxStrain) out << x << '\n';
    out << "SCALARS broken_fraction float 1\nLOOKUP_TABLE default\n";
    for (float x : w.brokenFraction) out << x << '\n';
  }
  if (shear && shear->wss && shear->tawss && shear->osi) {
    const WallShearArrays a = wallShearArrays(s, *shear);
    out << "VECTORS wss_Pa float\n";
    for (std::size_t i = 0; i < n; ++i) out << a.wss[3 * i] << ' ' << a.wss[3 * i + 1] << ' ' << a.wss[3 * i + 2] << '\n';
    out << "SCALARS tawss_Pa float 1\nLOOKUP_TABLE default\n";
    for (float x : a.tawss) out << x << '\n';
    out << "SCALARS osi float 1\nLOOKUP_TABLE default\n";
    for (float x : a.osi) out << x << '\n';
  }
  file.commit();
}

void writeSpringsVtk(const std::filesystem::path& path, const sim::Snapshot& s, const std::vector<sim::GpuSpring>& springs,
                     double time, glm::vec3 period) {
  const SpringStats stats = springStats(s, springs, period);
  AtomicFile file(path);
  std::ostream& out = vtkHeader(file, "hemo springs", time);
  const std::size_t n = s.positions.size(), m = springs.size();
  out << "POINTS " << n << " float\n";
  for (const auto& p : s.positions) out << p.x << ' ' << p.y << ' ' << p.z << '\n';
  out << "LINES " << m << ' ' << 3 * m << '\n';
  for (const auto& k : springs) out << "2 " << k.a << ' ' << k.b << '\n';
  out << "CELL_DATA " << m << "\nSCALARS strain float 1\nLOOKUP_TABLE default\n";
  for (float x : stats.strain) out << x << '\n';
  out << "SCALARS tension_N float 1\nLOOKUP_TABLE default\n";
  for (float x : stats.tension) out << x << '\n';
  out << "SCALARS broken int 1\nLOOKUP_TABLE default\n";
  for (const auto& k : springs) out << (k.broken ? 1 : 0) << '\n';
  file.commit();
}

}  // namespace hemo::io
