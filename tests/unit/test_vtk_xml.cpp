// Binary VTK XML output (hemo/io/output.hpp): every array read back from the appended block
// by the offsets and sizes the header names, bit for bit against what was written; the .pvd
// series, and a resumed run's kept frames.
#include "hemo/io/output.hpp"

#include "file_bytes.hpp"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <regex>
#include <sstream>
#include <string>

#include <unistd.h>

namespace hemo::test {
namespace {

namespace fs = std::filesystem;

fs::path freshDir(const std::string& name) { return freshTempDir("vtk_xml_" + name); }

// A VTK XML file as its reader sees it: each DataArray's attributes, and its bytes from the
// appended block (a UInt64 count, then the data).
struct XmlArray {
  std::string type;
  int components = 1;
  std::uint64_t tuples = 0;
  std::string bytes;
};
struct XmlFile {
  std::string header;  // the XML before the appended block
  std::map<std::string, XmlArray> arrays;
};

XmlFile parse(const fs::path& path) {
  const std::string text = readText(path);
  XmlFile f;
  const std::string marker = "<AppendedData encoding=\"raw\">";
  const std::size_t at = text.find(marker);
  EXPECT_NE(at, std::string::npos) << path;
  if (at == std::string::npos) return f;
  const std::size_t base = text.find('_', at + marker.size()) + 1;
  f.header = text.substr(0, at);
  EXPECT_NE(text.find("</AppendedData>\n</VTKFile>\n", base), std::string::npos) << "the file's end";
  const std::regex element(R"re(<DataArray type="(\w+)" Name="(\w+)"(?: NumberOfComponents="(\d+)")? NumberOfTuples="(\d+)" format="appended" offset="(\d+)"/>)re");
  for (auto it = std::sregex_iterator(f.header.begin(), f.header.end(), element); it != std::sregex_iterator(); ++it) {
    const std::smatch& m = *it;
    XmlArray a;
    a.type = m[1];
    a.components = m[3].matched ? std::stoi(m[3]) : 1;
    a.tuples = std::stoull(m[4]);
    const std::size_t offset = base + std::stoull(m[5]);
    std::uint64_t size = 0;
    EXPECT_LE(offset + 8, text.size()) << m[2];
    if (offset + 8 > text.size()) continue;
    std::memcpy(&size, text.data() + offset, 8);
    EXPECT_LE(offset + 8 + size, text.size()) << m[2];
    a.bytes = text.substr(offset + 8, size);
    EXPECT_TRUE(f.arrays.emplace(m[2], a).second) << "two arrays named " << m[2];
  }
  return f;
}

template <class T>
std::vector<T> values(const XmlFile& f, const std::string& name, const char* type, int components) {
  const auto it = f.arrays.find(name);
  EXPECT_NE(it, f.arrays.end()) << "no array " << name;
  if (it == f.arrays.end()) return {};
  EXPECT_EQ(it->second.type, type) << name;
  EXPECT_EQ(it->second.components, components) << name;
  EXPECT_EQ(it->second.bytes.size() % sizeof(T), 0u) << name;
  std::vector<T> v(it->second.bytes.size() / sizeof(T));
  std::memcpy(v.data(), it->second.bytes.data(), it->second.bytes.size());
  EXPECT_EQ(it->second.tuples * std::uint64_t(components), v.size()) << name << ": NumberOfTuples";
  return v;
}

struct Case {
  sim::Snapshot snap;
  std::vector<sim::GpuSpring> springs;
};

Case randomCase(std::uint32_t n, std::uint32_t m) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Case c;
  for (std::uint32_t i = 0; i < n; ++i) {
    c.snap.positions.emplace_back(0.01f * u(rng), 0.01f * u(rng), 0.01f * u(rng), 1e-7f * (2.0f + u(rng)));
    c.snap.velocities.emplace_back(u(rng), u(rng), u(rng), float(i % 3));
    c.snap.densityPressure.emplace_back(1000.0f + 30.0f * u(rng), 500.0f * u(rng));
    c.snap.ids.push_back(n - 1 - i);
  }
  for (std::uint32_t k = 0; k < m; ++k) {
    sim::GpuSpring s{};
    s.a = k % n;
    s.b = (7 * k + 3) % n;
    s.restLength = 0.004f + 0.001f * u(rng);
    s.stiffness = 5.0f;
    s.broken = k % 4 == 0 ? 1u : 0u;
    c.springs.push_back(s);
  }
  return c;
}

TEST(VtkXml, ParticleArraysReadBackBitForBit) {
  const fs::path dir = freshDir("particles");
  const Case c = randomCase(57, 40);
  const double time = 0.0123456789012345;
  const glm::vec3 period(0.015f, 0.0f, 0.0f);
  // The wall maps, per wall point id (ids below 40 here; kind 2 rows are wall points).
  std::vector<glm::vec3> wss(40);
  std::vector<float> tawss(40), osi(40);
  for (std::size_t k = 0; k < 40; ++k) wss[k] = glm::vec3(0.5f * k, -0.25f * k, 1.0f + k), tawss[k] = 0.1f * k, osi[k] = 0.01f * k;
  const io::WallShearFields maps{&wss, &tawss, &osi};
  // non-Newtonian blood: each particle's viscosity
  sim::Snapshot viscous = c.snap;
  for (std::size_t i = 0; i < viscous.positions.size(); ++i) viscous.viscosity.push_back(0.001f * float(i) + 0.0035f);
  for (const int variant : {0, 1, 2, 3}) {
    const bool withSprings = variant == 1 || variant == 2, withShear = variant == 2, withViscosity = variant == 3;
    SCOPED_TRACE(withShear ? "with springs and wall maps" : withSprings ? "with springs" : withViscosity ? "with viscosities" : "without springs");
    const fs::path path = dir / "p.vtu";
    io::writeParticlesVtu(path, withViscosity ? viscous : c.snap, time, withSprings ? &c.springs : nullptr, period,
                          withShear ? &maps : nullptr);
    const XmlFile f = parse(path);
    EXPECT_NE(f.header.find("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"),
              std::string::npos);
    EXPECT_NE(f.header.find("<Piece NumberOfPoints=\"57\" NumberOfCells=\"57\">"), std::string::npos);
    EXPECT_EQ(f.arrays.size(), withShear ? 16u : withSprings ? 13u : withViscosity ? 12u : 11u);
    if (withViscosity) {
      EXPECT_EQ(values<float>(f, "viscosity_Pa_s", "Float32", 1), viscous.viscosity);
    }
    EXPECT_EQ(values<double>(f, "TimeValue", "Float64", 1), std::vector<double>{time});
    const auto x = values<float>(f, "position_m", "Float32", 3);
    const auto v = values<float>(f, "velocity_m_s", "Float32", 3);
    const auto rho = values<float>(f, "density_kg_m3", "Float32", 1);
    const auto p = values<float>(f, "pressure_pa", "Float32", 1);
    const auto kind = values<std::uint8_t>(f, "kind", "UInt8", 1);
    const auto mass = values<float>(f, "mass_kg", "Float32", 1);
    const auto ids = values<std::uint32_t>(f, "id", "UInt32", 1);
    const auto conn = values<std::int32_t>(f, "connectivity", "Int32", 1);
    const auto offsets = values<std::int32_t>(f, "offsets", "Int32", 1);
    const auto types = values<std::uint8_t>(f, "types", "UInt8", 1);
    ASSERT_EQ(x.size(), 3u * 57u);
    ASSERT_EQ(v.size(), 3u * 57u);
    ASSERT_EQ(rho.size(), 57u);
    ASSERT_EQ(p.size(), 57u);
    ASSERT_EQ(kind.size(), 57u);
    ASSERT_EQ(mass.size(), 57u);
    ASSERT_EQ(ids.size(), 57u);
    ASSERT_EQ(conn.size(), 57u);
    ASSERT_EQ(offsets.size(), 57u);
    ASSERT_EQ(types.size(), 57u);
    for (std::size_t i = 0; i < 57; ++i) {
      for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(x[3 * i + a], c.snap.positions[i][a]);
        EXPECT_EQ(v[3 * i + a], c.snap.velocities[i][a]);
      }
      EXPECT_EQ(rho[i], c.snap.densityPressure[i].x);
      EXPECT_EQ(p[i], c.snap.densityPressure[i].y);
      EXPECT_EQ(kind[i], i % 3);
      EXPECT_EQ(mass[i], c.snap.positions[i].w);
      EXPECT_EQ(ids[i], c.snap.ids[i]);
      EXPECT_EQ(conn[i], std::int32_t(i));
      EXPECT_EQ(offsets[i], std::int32_t(i + 1));
      EXPECT_EQ(types[i], 1u);  // VTK_VERTEX
    }
    if (withSprings) {
      const io::WallPointStats w = io::wallPointStats(c.snap, c.springs, period);
      EXPECT_EQ(values<float>(f, "max_strain", "Float32", 1), w.maxStrain);
      EXPECT_EQ(values<float>(f, "broken_fraction", "Float32", 1), w.brokenFraction);
    }
    if (withShear) {
      const auto w = values<float>(f, "wss_Pa", "Float32", 3);
      const auto t = values<float>(f, "tawss_Pa", "Float32", 1);
      const auto o = values<float>(f, "osi", "Float32", 1);
      ASSERT_EQ(w.size(), 3u * 57u);
      std::size_t mapped = 0;
      for (std::size_t i = 0; i < 57; ++i) {
        const std::uint32_t id = c.snap.ids[i];
        const bool wall = c.snap.velocities[i].w == 2.0f && id < 40;
        mapped += wall;
        for (int a = 0; a < 3; ++a) EXPECT_EQ(w[3 * i + a], wall ? wss[id][a] : 0.0f);
        EXPECT_EQ(t[i], wall ? tawss[id] : 0.0f);
        EXPECT_EQ(o[i], wall ? osi[id] : 0.0f);
      }
      EXPECT_GT(mapped, 5u);
    }
  }
}

TEST(VtkXml, SpringLinesReadBackWithStrainTensionAndBroken) {
  const fs::path dir = freshDir("springs");
  const Case c = randomCase(31, 44);
  const glm::vec3 period(0.0f, 0.012f, 0.0f);
  const fs::path path = dir / "s.vtp";
  io::writeSpringsVtp(path, c.snap, c.springs, 0.5, period);
  const XmlFile f = parse(path);
  EXPECT_NE(f.header.find("<Piece NumberOfPoints=\"31\" NumberOfVerts=\"0\" NumberOfLines=\"44\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">"),
            std::string::npos);
  EXPECT_EQ(values<double>(f, "TimeValue", "Float64", 1), std::vector<double>{0.5});
  EXPECT_EQ(values<float>(f, "position_m", "Float32", 3).size(), 3u * 31u);
  const auto conn = values<std::int32_t>(f, "connectivity", "Int32", 1);
  const auto offsets = values<std::int32_t>(f, "offsets", "Int32", 1);
  const auto strain = values<float>(f, "strain", "Float32", 1);
  const auto tension = values<float>(f, "tension_N", "Float32", 1);
  const auto broken = values<std::uint8_t>(f, "broken", "UInt8", 1);
  ASSERT_EQ(conn.size(), 88u);
  ASSERT_EQ(offsets.size(), 44u);
  ASSERT_EQ(strain.size(), 44u);
  ASSERT_EQ(tension.size(), 44u);
  ASSERT_EQ(broken.size(), 44u);
  for (std::size_t k = 0; k < 44; ++k) {
    const sim::GpuSpring& s = c.springs[k];
    EXPECT_EQ(conn[2 * k], std::int32_t(s.a));
    EXPECT_EQ(conn[2 * k + 1], std::int32_t(s.b));
    EXPECT_EQ(offsets[k], std::int32_t(2 * k + 2));
    // the minimum image across the periodic y axis, in double
    glm::dvec3 d = glm::dvec3(c.snap.positions[s.b]) - glm::dvec3(c.snap.positions[s.a]);
    d.y -= 0.012 * std::round(d.y / double(0.012f));
    const double length = glm::length(d);
    EXPECT_NEAR(strain[k], length / s.restLength - 1.0, 1e-6 * (1.0 + std::abs(length / s.restLength)));
    EXPECT_NEAR(tension[k], s.broken ? 0.0 : s.stiffness * (length - s.restLength), 1e-6 * s.stiffness * (length + s.restLength));
    EXPECT_EQ(broken[k], s.broken);
  }
  // A spring naming a particle the snapshot does not have is refused.
  auto bad = c.springs;
  bad[3].b = 31;
  EXPECT_THROW(io::writeSpringsVtp(dir / "bad.vtp", c.snap, bad, 0.5, period), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir / "bad.vtp"));
}

std::vector<std::pair<double, std::string>> pvdEntries(const fs::path& path) {
  const std::string text = readText(path);
  const std::regex entry(R"re(<DataSet timestep="([^"]+)" part="0" file="([^"]+)"/>)re");
  std::vector<std::pair<double, std::string>> out;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), entry); it != std::sregex_iterator(); ++it) {
    out.emplace_back(std::strtod((*it)[1].str().c_str(), nullptr), (*it)[2]);
  }
  EXPECT_NE(text.find("<VTKFile type=\"Collection\""), std::string::npos);
  EXPECT_NE(text.find("</Collection>\n</VTKFile>\n"), std::string::npos);
  return out;
}

TEST(VtkXml, SeriesListsEveryFrameAndAResumedRunKeepsItsEarlierOnes) {
  const fs::path dir = freshDir("pvd");
  const fs::path pvd = dir / "particles.pvd";
  const double t1 = 0.1 / 3.0, t2 = 2.0 / 3.0;
  {
    io::PvdSeries series(pvd);
    series.add(0.0, "particles_00000000.vtu");
    series.add(t1, "particles_00000010.vtu");
    EXPECT_EQ(pvdEntries(pvd).size(), 2u) << "rewritten at every frame";
    series.add(t2, "particles_00000020.vtu");
  }
  const auto all = pvdEntries(pvd);
  ASSERT_EQ(all.size(), 3u);
  EXPECT_EQ(all[1].first, t1) << "times round-trip exactly";
  EXPECT_EQ(all[2].first, t2);
  EXPECT_EQ(all[2].second, "particles_00000020.vtu");
  // Resumed after step 10: the frames up to it stay, the later one goes, the new ones follow.
  io::PvdSeries resumed(pvd, [](const std::string& file) { return file <= "particles_00000010.vtu"; });
  EXPECT_EQ(resumed.size(), 2u);
  resumed.add(0.7, "particles_00000030.vtu");
  const auto after = pvdEntries(pvd);
  ASSERT_EQ(after.size(), 3u);
  EXPECT_EQ(after[1].second, "particles_00000010.vtu");
  EXPECT_EQ(after[2].second, "particles_00000030.vtu");
  // Without `keep`, an old .pvd is replaced.
  io::PvdSeries fresh(pvd);
  fresh.add(0.0, "particles_00000000.vtu");
  EXPECT_EQ(pvdEntries(pvd).size(), 1u);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace hemo::test
