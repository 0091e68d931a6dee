#include "io/vtk.hpp"

#include <fmt/format.h>

#include <bit>
#include <cmath>
#include <numbers>
#include <set>
#include <stdexcept>

#include "io/atomic_file.hpp"

namespace cohdem {

static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");

namespace {

constexpr const char* kByteOrder =
    std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian";

std::string xml_escape(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

std::vector<double> flatten(const std::vector<Vec3>& v) {
  std::vector<double> out(3 * v.size());
  for (size_t i = 0; i < v.size(); ++i) {
    out[3 * i] = v[i].x;
    out[3 * i + 1] = v[i].y;
    out[3 * i + 2] = v[i].z;
  }
  return out;
}

/// An orthonormal pair (u, v) with u x v = n (n must be unit).
void basis(const Vec3& n, Vec3& u, Vec3& v) {
  // Cross with the coordinate axis least aligned with n, for a well-conditioned u.
  const double ax = std::abs(n.x), ay = std::abs(n.y), az = std::abs(n.z);
  const Vec3 a = (ax <= ay && ax <= az) ? Vec3{1, 0, 0} : (ay <= az ? Vec3{0, 1, 0} : Vec3{0, 0, 1});
  u = normalized(cross(a, n));
  v = cross(n, u);
}

Vec3 unit_or_throw(const Vec3& d, const char* what) {
  const double l = norm(d);
  if (!(l > 0) || !std::isfinite(l)) throw std::invalid_argument(fmt::format("{}: zero or non-finite direction", what));
  return d / l;
}

void add_array(std::vector<VtuArray>& list, std::string name, int components, VtuValues values) {
  list.push_back(VtuArray{std::move(name), components, std::move(values)});
}

void check_arrays(const std::vector<VtuArray>& list, size_t n, const char* where) {
  std::set<std::string> names;
  for (const auto& a : list) {
    if (a.name.empty()) throw std::invalid_argument(fmt::format("VTU {} array with an empty name", where));
    if (!names.insert(a.name).second)
      throw std::invalid_argument(fmt::format("VTU {} array '{}' given twice", where, a.name));
    if (a.components != 1 && a.components != 3)
      throw std::invalid_argument(
          fmt::format("VTU {} array '{}': {} components (1 or 3 expected)", where, a.name, a.components));
    if (a.size() != n * static_cast<size_t>(a.components))
      throw std::invalid_argument(fmt::format("VTU {} array '{}': {} values, expected {} x {}", where,
                                              a.name, a.size(), n, a.components));
  }
}

/// The raw bytes of an array's values.
std::string_view raw_bytes(const VtuValues& v) {
  return std::visit(
      [](const auto& vec) {
        return std::string_view(reinterpret_cast<const char*>(vec.data()),
                                vec.size() * sizeof(typename std::decay_t<decltype(vec)>::value_type));
      },
      v);
}

}  // namespace

size_t VtuArray::size() const {
  return std::visit([](const auto& vec) { return vec.size(); }, values);
}

const char* VtuArray::vtk_type() const {
  static constexpr const char* names[] = {"Float64", "Int32", "Int64", "UInt64", "UInt8"};
  return names[values.index()];
}

void VtuData::add_cell(VtkCell type, std::initializer_list<int64_t> ids) {
  connectivity.insert(connectivity.end(), ids.begin(), ids.end());
  offsets.push_back(static_cast<int64_t>(connectivity.size()));
  types.push_back(static_cast<uint8_t>(type));
}

void VtuData::add_cell(VtkCell type, const std::vector<int64_t>& ids) {
  connectivity.insert(connectivity.end(), ids.begin(), ids.end());
  offsets.push_back(static_cast<int64_t>(connectivity.size()));
  types.push_back(static_cast<uint8_t>(type));
}

void VtuData::add_point_scalar(std::string name, std::vector<double> v) { add_array(point_data, std::move(name), 1, std::move(v)); }
void VtuData::add_point_vector(std::string name, const std::vector<Vec3>& v) { add_array(point_data, std::move(name), 3, flatten(v)); }
void VtuData::add_point_int(std::string name, std::vector<int32_t> v) { add_array(point_data, std::move(name), 1, std::move(v)); }
void VtuData::add_point_id(std::string name, std::vector<uint64_t> v) { add_array(point_data, std::move(name), 1, std::move(v)); }
void VtuData::add_point_u8(std::string name, std::vector<uint8_t> v) { add_array(point_data, std::move(name), 1, std::move(v)); }
void VtuData::add_cell_scalar(std::string name, std::vector<double> v) { add_array(cell_data, std::move(name), 1, std::move(v)); }
void VtuData::add_cell_vector(std::string name, const std::vector<Vec3>& v) { add_array(cell_data, std::move(name), 3, flatten(v)); }
void VtuData::add_cell_int(std::string name, std::vector<int32_t> v) { add_array(cell_data, std::move(name), 1, std::move(v)); }
void VtuData::add_cell_id(std::string name, std::vector<uint64_t> v) { add_array(cell_data, std::move(name), 1, std::move(v)); }
void VtuData::add_cell_u8(std::string name, std::vector<uint8_t> v) { add_array(cell_data, std::move(name), 1, std::move(v)); }

void VtuData::fill_cell_int(std::string name, int32_t value) {
  add_cell_int(std::move(name), std::vector<int32_t>(num_cells(), value));
}

void VtuData::validate() const {
  if (offsets.size() != types.size())
    throw std::invalid_argument(fmt::format("VTU: {} cell offsets but {} cell types", offsets.size(), types.size()));
  int64_t prev = 0;
  for (size_t c = 0; c < offsets.size(); ++c) {
    const int64_t n = offsets[c] - prev;
    if (n <= 0) throw std::invalid_argument(fmt::format("VTU: cell {} has no points (offsets must increase)", c));
    // Check the node count for the cell types written here; other codes pass unchecked.
    bool ok = true;
    switch (static_cast<VtkCell>(types[c])) {
      case VtkCell::Vertex: ok = n == 1; break;
      case VtkCell::Line: ok = n == 2; break;
      case VtkCell::Triangle: ok = n == 3; break;
      case VtkCell::Quad: ok = n == 4; break;
      case VtkCell::Polygon: ok = n >= 3; break;
    }
    if (!ok) throw std::invalid_argument(fmt::format("VTU: cell {} of type {} has {} points", c, types[c], n));
    prev = offsets[c];
  }
  if (static_cast<size_t>(prev) != connectivity.size())
    throw std::invalid_argument(
        fmt::format("VTU: last offset {} but connectivity has {} entries", prev, connectivity.size()));
  for (int64_t id : connectivity)
    if (id < 0 || static_cast<size_t>(id) >= points.size())
      throw std::invalid_argument(fmt::format("VTU: point index {} out of range ({} points)", id, points.size()));
  check_arrays(point_data, num_points(), "point");
  check_arrays(cell_data, num_cells(), "cell");
}

void write_vtu(const std::filesystem::path& path, const VtuData& d) {
  d.validate();

  // Blocks in file order; the XML header refers to them by byte offset into the appended
  // section, each block being a UInt64 byte count followed by the payload.
  std::vector<std::string_view> blocks;
  uint64_t offset = 0;
  auto entry = [&](std::string_view bytes) {
    const uint64_t at = offset;
    blocks.push_back(bytes);
    offset += sizeof(uint64_t) + bytes.size();
    return at;
  };
  auto data_array = [&](const char* type, std::string_view name, int comps, std::string_view bytes) {
    return fmt::format(
        "        <DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"appended\" "
        "offset=\"{}\"/>\n",
        type, xml_escape(name), comps, entry(bytes));
  };

  std::string xml;
  xml += "<?xml version=\"1.0\"?>\n";
  xml += fmt::format(
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"{}\" header_type=\"UInt64\">\n",
      kByteOrder);
  xml += "  <UnstructuredGrid>\n";
  xml += fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", d.num_points(), d.num_cells());
  xml += "      <PointData>\n";
  for (const auto& a : d.point_data) xml += data_array(a.vtk_type(), a.name, a.components, raw_bytes(a.values));
  xml += "      </PointData>\n      <CellData>\n";
  for (const auto& a : d.cell_data) xml += data_array(a.vtk_type(), a.name, a.components, raw_bytes(a.values));
  xml += "      </CellData>\n      <Points>\n";
  xml += data_array("Float64", "Points", 3,
                    {reinterpret_cast<const char*>(d.points.data()), d.points.size() * sizeof(Vec3)});
  xml += "      </Points>\n      <Cells>\n";
  auto bytes_of = [](const auto& vec) {
    return std::string_view(reinterpret_cast<const char*>(vec.data()), vec.size() * sizeof(vec[0]));
  };
  xml += data_array("Int64", "connectivity", 1, bytes_of(d.connectivity));
  xml += data_array("Int64", "offsets", 1, bytes_of(d.offsets));
  xml += data_array("UInt8", "types", 1, bytes_of(d.types));
  xml += "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n";
  xml += "  <AppendedData encoding=\"raw\">\n   _";

  AtomicWriter w(path);
  w.write(xml);
  for (std::string_view b : blocks) {
    const uint64_t n = b.size();
    w.write({reinterpret_cast<const char*>(&n), sizeof n});
    w.write(b);
  }
  w.write("\n  </AppendedData>\n</VTKFile>\n");
  w.commit();
}

VtuData particles_vtu(std::vector<Vec3> points) {
  VtuData d;
  const size_t n = points.size();
  d.points = std::move(points);
  d.connectivity.resize(n);
  d.offsets.resize(n);
  d.types.assign(n, static_cast<uint8_t>(VtkCell::Vertex));
  for (size_t i = 0; i < n; ++i) {
    d.connectivity[i] = static_cast<int64_t>(i);
    d.offsets[i] = static_cast<int64_t>(i + 1);
  }
  return d;
}

VtuData lines_vtu(std::vector<Vec3> points, const std::vector<std::array<uint32_t, 2>>& pairs) {
  VtuData d;
  d.points = std::move(points);
  d.connectivity.reserve(2 * pairs.size());
  d.offsets.reserve(pairs.size());
  d.types.assign(pairs.size(), static_cast<uint8_t>(VtkCell::Line));
  for (const auto& p : pairs) {
    if (p[0] >= d.points.size() || p[1] >= d.points.size())
      throw std::invalid_argument(
          fmt::format("lines_vtu: pair ({}, {}) past the {} points", p[0], p[1], d.points.size()));
    d.connectivity.push_back(p[0]);
    d.connectivity.push_back(p[1]);
    d.offsets.push_back(static_cast<int64_t>(d.connectivity.size()));
  }
  return d;
}

VtuData plane_patch(const Vec3& center, const Vec3& normal, double half_size) {
  if (!(half_size > 0)) throw std::invalid_argument("plane_patch: half_size must be > 0");
  const Vec3 n = unit_or_throw(normal, "plane_patch normal");
  Vec3 u, v;
  basis(n, u, v);
  u *= half_size;
  v *= half_size;
  VtuData d;
  d.points = {center - u - v, center + u - v, center + u + v, center - u + v};
  d.add_cell(VtkCell::Quad, {0, 1, 2, 3});
  return d;
}

VtuData cylinder_surface(const Vec3& axis_point, const Vec3& axis_dir, double radius, double z_min,
                         double z_max, int segments) {
  if (!(radius > 0)) throw std::invalid_argument("cylinder_surface: radius must be > 0");
  if (!(z_max > z_min)) throw std::invalid_argument("cylinder_surface: z_max must exceed z_min");
  if (segments < 3) throw std::invalid_argument("cylinder_surface: at least 3 segments");
  const Vec3 a = unit_or_throw(axis_dir, "cylinder_surface axis");
  Vec3 u, v;
  basis(a, u, v);
  VtuData d;
  const int64_t m = segments;
  d.points.resize(2 * static_cast<size_t>(m));
  for (int64_t i = 0; i < m; ++i) {
    const double t = 2 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(m);
    const Vec3 r = radius * (std::cos(t) * u + std::sin(t) * v);
    d.points[i] = axis_point + z_min * a + r;      // bottom ring
    d.points[m + i] = axis_point + z_max * a + r;  // top ring
  }
  // (bottom i, bottom i+1, top i+1, top i): tangent x axis points outward.
  for (int64_t i = 0; i < m; ++i) {
    const int64_t j = (i + 1) % m;
    d.add_cell(VtkCell::Quad, {i, j, m + j, m + i});
  }
  return d;
}

VtuData disk_annulus(const Vec3& center, const Vec3& normal, double r_in, double r_out, int segments) {
  if (!(r_in >= 0) || !(r_out > r_in)) throw std::invalid_argument("disk_annulus: need 0 <= r_in < r_out");
  if (segments < 3) throw std::invalid_argument("disk_annulus: at least 3 segments");
  const Vec3 n = unit_or_throw(normal, "disk_annulus normal");
  Vec3 u, v;
  basis(n, u, v);
  VtuData d;
  const int64_t m = segments;
  auto ring = [&](double r) {
    for (int64_t i = 0; i < m; ++i) {
      const double t = 2 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(m);
      d.points.push_back(center + r * (std::cos(t) * u + std::sin(t) * v));
    }
  };
  if (r_in == 0) {
    // Triangle fan about the centre (point 0); radial x tangential = normal.
    d.points.push_back(center);
    ring(r_out);
    for (int64_t i = 0; i < m; ++i) d.add_cell(VtkCell::Triangle, {0, 1 + i, 1 + (i + 1) % m});
  } else {
    ring(r_in);   // 0 .. m-1
    ring(r_out);  // m .. 2m-1
    for (int64_t i = 0; i < m; ++i) {
      const int64_t j = (i + 1) % m;
      d.add_cell(VtkCell::Quad, {i, m + i, m + j, j});
    }
  }
  return d;
}

namespace {

/// Appends `part`'s arrays onto `out`'s, matching by name; all must be present and alike.
void merge_arrays(std::vector<VtuArray>& out, const std::vector<VtuArray>& part, size_t index, const char* where) {
  if (part.size() != out.size())
    throw std::invalid_argument(
        fmt::format("merge: mesh {} has {} {} arrays, mesh 0 has {}", index, part.size(), where, out.size()));
  for (auto& o : out) {
    const VtuArray* p = nullptr;
    for (const auto& a : part)
      if (a.name == o.name) p = &a;
    if (!p) throw std::invalid_argument(fmt::format("merge: mesh {} lacks {} array '{}'", index, where, o.name));
    if (p->values.index() != o.values.index() || p->components != o.components)
      throw std::invalid_argument(
          fmt::format("merge: {} array '{}' differs in type or components in mesh {}", where, o.name, index));
    std::visit(
        [&](auto& dst) {
          const auto& src = std::get<std::decay_t<decltype(dst)>>(p->values);
          dst.insert(dst.end(), src.begin(), src.end());
        },
        o.values);
  }
}

}  // namespace

VtuData merge(const std::vector<VtuData>& parts) {
  VtuData out;
  if (parts.empty()) return out;
  // Start from mesh 0's array names and types, with no values.
  auto empty_like = [](const std::vector<VtuArray>& src) {
    std::vector<VtuArray> r = src;
    for (auto& a : r) std::visit([](auto& vec) { vec.clear(); }, a.values);
    return r;
  };
  out.point_data = empty_like(parts[0].point_data);
  out.cell_data = empty_like(parts[0].cell_data);
  for (size_t k = 0; k < parts.size(); ++k) {
    const VtuData& p = parts[k];
    const auto point_base = static_cast<int64_t>(out.points.size());
    const auto conn_base = static_cast<int64_t>(out.connectivity.size());
    out.points.insert(out.points.end(), p.points.begin(), p.points.end());
    for (int64_t id : p.connectivity) out.connectivity.push_back(id + point_base);
    for (int64_t o : p.offsets) out.offsets.push_back(o + conn_base);
    out.types.insert(out.types.end(), p.types.begin(), p.types.end());
    merge_arrays(out.point_data, p.point_data, k, "point");
    merge_arrays(out.cell_data, p.cell_data, k, "cell");
  }
  return out;
}

void PvdSeries::add(double time, const std::string& file, int part) {
  entries_.push_back({time, file, part});
  write();
}

void PvdSeries::write() const {
  std::string s = "<?xml version=\"1.0\"?>\n";
  s += fmt::format("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"{}\">\n  <Collection>\n", kByteOrder);
  // "{}" prints the shortest decimal that reads back to the same double.
  for (const auto& e : entries_)
    s += fmt::format("    <DataSet timestep=\"{}\" group=\"\" part=\"{}\" file=\"{}\"/>\n", e.time, e.part,
                     xml_escape(e.file));
  s += "  </Collection>\n</VTKFile>\n";
  write_file_atomic(path_, s);
}

}  // namespace cohdem
