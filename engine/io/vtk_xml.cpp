#include "hemo/io/atomic_file.hpp"
#include "hemo/io/output.hpp"

#include <bit>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace hemo::io {

namespace {

// A VTK XML file's data arrays, appended raw after the XML (format="appended", encoding
// "raw"): each array is a UInt64 byte count and then its bytes in the host's byte order, and
// its XML element names its offset from the block's start (the byte after the '_'). Readers
// map the block instead of parsing text, which is what makes these files fast to load.
class AppendedArrays {
 public:
  // The array's XML element, indented for its place in the document.
  template <class T>
  std::string add(const char* vtkType, const std::string& name, int components, const T* data, std::size_t count) {
    std::ostringstream e;
    e << "<DataArray type=\"" << vtkType << "\" Name=\"" << name << "\"";
    if (components > 1) e << " NumberOfComponents=\"" << components << "\"";
    e << " NumberOfTuples=\"" << count / std::size_t(components) << "\"";
    e << " format=\"appended\" offset=\"" << blob_.size() << "\"/>";
    const std::uint64_t bytes = count * sizeof(T);
    const auto* p = reinterpret_cast<const char*>(&bytes);
    blob_.insert(blob_.end(), p, p + sizeof bytes);
    const auto* d = reinterpret_cast<const char*>(data);
    blob_.insert(blob_.end(), d, d + bytes);
    return e.str();
  }
  template <class T>
  std::string add(const char* vtkType, const std::string& name, int components, const std::vector<T>& data) {
    return add(vtkType, name, components, data.data(), data.size());
  }
  void write(std::ostream& out) const {
    out << "  <AppendedData encoding=\"raw\">\n   _";
    out.write(blob_.data(), std::streamsize(blob_.size()));
    out << "\n  </AppendedData>\n";
  }

 private:
  std::vector<char> blob_;
};

const char* byteOrder() { return std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian"; }

std::ostream& xmlHeader(AtomicFile& file, const char* type) {
  std::ostream& out = file.stream();
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"" << type << "\" version=\"1.0\" byte_order=\"" << byteOrder()
      << "\" header_type=\"UInt64\">\n";
  return out;
}

std::vector<float> xyz(const std::vector<glm::vec4>& v) {
  std::vector<float> out;
  out.reserve(3 * v.size());
  for (const auto& p : v) out.insert(out.end(), {p.x, p.y, p.z});
  return out;
}

}  // namespace

void writeParticlesVtu(const std::filesystem::path& path, const sim::Snapshot& s, double time,
                       const std::vector<sim::GpuSpring>* springs, glm::vec3 period, const WallShearFields* shear) {
  const std::size_t n = s.positions.size();
  if (s.velocities.size() != n || s.densityPressure.size() != n || s.ids.size() != n) {
    throw std::runtime_error("the snapshot's arrays differ in length");
  }
  AppendedArrays arrays;
  const std::string timeValue = arrays.add("Float64", "TimeValue", 1, &time, 1);
  std::vector<std::string> pointData;
  pointData.push_back(arrays.add("Float32", "velocity_m_s", 3, xyz(s.velocities)));
  std::vector<float> density(n), pressure(n), mass(n);
  std::vector<std::uint8_t> kind(n);
  for (std::size_t i = 0; i < n; ++i) {
    density[i] = s.densityPressure[i].x;
    pressure[i] = s.densityPressure[i].y;
    mass[i] = s.positions[i].w;
    kind[i] = static_cast<std::uint8_t>(s.velocities[i].w);
  }
  pointData.push_back(arrays.add("Float32", "density_kg_m3", 1, density));
  pointData.push_back(arrays.add("Float32", "pressure_pa", 1, pressure));
  pointData.push_back(arrays.add("UInt8", "kind", 1, kind));
  pointData.push_back(arrays.add("Float32", "mass_kg", 1, mass));
  pointData.push_back(arrays.add("UInt32", "id", 1, s.ids));
  if (s.viscosity.size() == n) pointData.push_back(arrays.add("Float32", "viscosity_Pa_s", 1, s.viscosity));
  if (springs) {
    const WallPointStats w = wallPointStats(s, *springs, period);
    pointData.push_back(arrays.add("Float32", "max_strain", 1, w.maxStrain));
    pointData.push_back(arrays.add("Float32", "broken_fraction", 1, w.brokenFraction));
  }
  if (shear && shear->wss && shear->tawss && shear->osi) {
    const WallShearArrays a = wallShearArrays(s, *shear);
    pointData.push_back(arrays.add("Float32", "wss_Pa", 3, a.wss));
    pointData.push_back(arrays.add("Float32", "tawss_Pa", 1, a.tawss));
    pointData.push_back(arrays.add("Float32", "osi", 1, a.osi));
  }
  const std::string points = arrays.add("Float32", "position_m", 3, xyz(s.positions));
  // one vertex cell (VTK_VERTEX = 1) per particle
  std::vector<std::int32_t> connectivity(n), offsets(n);
  for (std::size_t i = 0; i < n; ++i) connectivity[i] = std::int32_t(i), offsets[i] = std::int32_t(i + 1);
  const std::string cells[3] = {arrays.add("Int32", "connectivity", 1, connectivity),
                                arrays.add("Int32", "offsets", 1, offsets),
                                arrays.add("UInt8", "types", 1, std::vector<std::uint8_t>(n, 1))};
  AtomicFile file(path);
  std::ostream& out = xmlHeader(file, "UnstructuredGrid");
  out << " <UnstructuredGrid>\n  <FieldData>\n   " << timeValue << "\n  </FieldData>\n";
  out << "  <Piece NumberOfPoints=\"" << n << "\" NumberOfCells=\"" << n << "\">\n";
  out << "   <PointData Scalars=\"pressure_pa\" Vectors=\"velocity_m_s\">\n";
  for (const auto& e : pointData) out << "    " << e << "\n";
  out << "   </PointData>\n   <Points>\n    " << points << "\n   </Points>\n   <Cells>\n";
  for (const auto& e : cells) out << "    " << e << "\n";
  out << "   </Cells>\n  </Piece>\n </UnstructuredGrid>\n";
  arrays.write(out);
  out << "</VTKFile>\n";
  file.commit();
}

void writeSpringsVtp(const std::filesystem::path& path, const sim::Snapshot& s, const std::vector<sim::GpuSpring>& springs,
                     double time, glm::vec3 period) {
  const std::size_t n = s.positions.size(), m = springs.size();
  const SpringStats stats = springStats(s, springs, period);
  std::vector<std::int32_t> connectivity, offsets;
  std::vector<std::uint8_t> broken;
  connectivity.reserve(2 * m);
  for (const auto& k : springs) {
    connectivity.insert(connectivity.end(), {std::int32_t(k.a), std::int32_t(k.b)});
    offsets.push_back(std::int32_t(connectivity.size()));
    broken.push_back(k.broken ? 1 : 0);
  }
  AppendedArrays arrays;
  const std::string timeValue = arrays.add("Float64", "TimeValue", 1, &time, 1);
  const std::string cellData[3] = {arrays.add("Float32", "strain", 1, stats.strain), arrays.add("Float32", "tension_N", 1, stats.tension),
                                   arrays.add("UInt8", "broken", 1, broken)};
  const std::string points = arrays.add("Float32", "position_m", 3, xyz(s.positions));
  const std::string lines[2] = {arrays.add("Int32", "connectivity", 1, connectivity), arrays.add("Int32", "offsets", 1, offsets)};
  AtomicFile file(path);
  std::ostream& out = xmlHeader(file, "PolyData");
  out << " <PolyData>\n  <FieldData>\n   " << timeValue << "\n  </FieldData>\n";
  out << "  <Piece NumberOfPoints=\"" << n << "\" NumberOfVerts=\"0\" NumberOfLines=\"" << m
      << "\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n";
  out << "   <CellData Scalars=\"strain\">\n";
  for (const auto& e : cellData) out << "    " << e << "\n";
  out << "   </CellData>\n   <Points>\n    " << points << "\n   </Points>\n   <Lines>\n";
  for (const auto& e : lines) out << "    " << e << "\n";
  out << "   </Lines>\n  </Piece>\n </PolyData>\n";
  arrays.write(out);
  out << "</VTKFile>\n";
  file.commit();
}

PvdSeries::PvdSeries(std::filesystem::path path, const std::function<bool(const std::string& file)>& keep)
    : path_(std::move(path)) {
  if (!keep) return;
  std::ifstream in(path_);
  std::string line;
  const std::regex entry(R"re(<DataSet timestep="([^"]+)" part="0" file="([^"]+)"/>)re");
  while (std::getline(in, line)) {
    std::smatch m;
    if (!std::regex_search(line, m, entry)) continue;
    char* end = nullptr;
    const double t = std::strtod(m[1].str().c_str(), &end);
    if (end == m[1].str().c_str() || !keep(m[2].str())) continue;
    entries_.push_back({t, m[2].str()});
  }
}

void PvdSeries::add(double time, const std::string& file) {
  entries_.push_back({time, file});
  AtomicFile out(path_);
  std::ostream& o = out.stream();
  o.precision(17);
  o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"" << byteOrder()
    << "\">\n <Collection>\n";
  for (const auto& e : entries_) o << "  <DataSet timestep=\"" << e.time << "\" part=\"0\" file=\"" << e.file << "\"/>\n";
  o << " </Collection>\n</VTKFile>\n";
  out.commit();
}

}  // namespace hemo::io
