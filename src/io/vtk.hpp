// VTK XML UnstructuredGrid (.vtu) output for ParaView, plus .pvd time series and simple wall
// meshes. Binary "appended raw" encoding: each array is a UInt64 byte count followed by the
// raw little-endian values, so files are compact and need no base64 or zlib.
#pragma once
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <variant>
#include <vector>

#include "core/vec3.hpp"

namespace cohdem {

/// VTK cell type codes (vtkCellType.h).
enum class VtkCell : uint8_t { Vertex = 1, Line = 3, Triangle = 5, Polygon = 7, Quad = 9 };

/// The values of one data array, flattened (a 3-vector array stores x0 y0 z0 x1 ...).
using VtuValues = std::variant<std::vector<double>, std::vector<int32_t>, std::vector<int64_t>,
                               std::vector<uint64_t>, std::vector<uint8_t>>;

/// One named point-data or cell-data array.
struct VtuArray {
  std::string name;
  int components = 1;  // 1 (scalar) or 3 (vector)
  VtuValues values;

  size_t size() const;  // number of values (tuples * components)
  size_t tuples() const { return size() / static_cast<size_t>(components); }
  /// VTK type name: Float64, Int32, Int64, UInt64 or UInt8.
  const char* vtk_type() const;
};

/// A generic unstructured grid: points, cells (VTK's connectivity/offsets/types triple) and
/// named point and cell arrays. Array lengths are checked by validate() and write_vtu().
struct VtuData {
  std::vector<Vec3> points;
  std::vector<int64_t> connectivity;  // point indices of all cells, concatenated
  std::vector<int64_t> offsets;       // end of each cell in `connectivity` (VTK convention)
  std::vector<uint8_t> types;         // VtkCell code of each cell
  std::vector<VtuArray> point_data;
  std::vector<VtuArray> cell_data;

  size_t num_points() const { return points.size(); }
  size_t num_cells() const { return types.size(); }

  /// Appends one cell over existing point indices.
  void add_cell(VtkCell type, std::initializer_list<int64_t> ids);
  void add_cell(VtkCell type, const std::vector<int64_t>& ids);

  // Point data: one value (or Vec3) per point.
  void add_point_scalar(std::string name, std::vector<double> v);
  void add_point_vector(std::string name, const std::vector<Vec3>& v);
  void add_point_int(std::string name, std::vector<int32_t> v);
  void add_point_id(std::string name, std::vector<uint64_t> v);
  void add_point_u8(std::string name, std::vector<uint8_t> v);
  // Cell data: one value (or Vec3) per cell.
  void add_cell_scalar(std::string name, std::vector<double> v);
  void add_cell_vector(std::string name, const std::vector<Vec3>& v);
  void add_cell_int(std::string name, std::vector<int32_t> v);
  void add_cell_id(std::string name, std::vector<uint64_t> v);
  void add_cell_u8(std::string name, std::vector<uint8_t> v);
  /// Int32 cell array with the same value on every current cell (e.g. "wall_id").
  void fill_cell_int(std::string name, int32_t value);

  /// Throws std::invalid_argument if sizes disagree (offsets vs types, connectivity range,
  /// array lengths vs points/cells, duplicate array names, components not 1 or 3).
  void validate() const;
};

/// Writes `d` as a .vtu file, atomically (see atomic_file.hpp). Validates first.
/// Throws std::invalid_argument for inconsistent data, std::runtime_error for I/O errors.
void write_vtu(const std::filesystem::path& path, const VtuData& d);

/// One vertex cell per point, so the points show in every ParaView representation (Point
/// Gaussian works on points alone; Surface/Points need cells).
VtuData particles_vtu(std::vector<Vec3> points);

/// Line cells between point pairs (contact network); the caller adds cell data such as
/// force or conductance. Throws std::invalid_argument for an index past the points.
VtuData lines_vtu(std::vector<Vec3> points, const std::vector<std::array<uint32_t, 2>>& pairs);

// --- Wall meshes: pure geometry, one mesh per wall; tag with fill_cell_int("wall_id", k).

/// A square of side 2*half_size centred on `center`, perpendicular to `normal`; one quad
/// wound counter-clockwise about `normal`.
VtuData plane_patch(const Vec3& center, const Vec3& normal, double half_size);

/// The lateral surface of a cylinder: axis through `axis_point` along `axis_dir`, axial
/// coordinate (from axis_point) in [z_min, z_max]; `segments` quads with outward normals.
VtuData cylinder_surface(const Vec3& axis_point, const Vec3& axis_dir, double radius,
                         double z_min, double z_max, int segments = 48);

/// A flat ring r_in <= r <= r_out in the plane through `center` perpendicular to `normal`;
/// quads, or a triangle fan when r_in == 0. Normals along `normal`.
VtuData disk_annulus(const Vec3& center, const Vec3& normal, double r_in, double r_out,
                     int segments = 48);

/// Concatenates meshes (points, cells, and arrays matched by name). Every mesh must carry the
/// same point-data and cell-data names with the same type and components; otherwise throws
/// std::invalid_argument.
VtuData merge(const std::vector<VtuData>& parts);

/// A ParaView .pvd collection: one (time, file) entry per output step. The collection file is
/// rewritten atomically on every add(), so a killed run still leaves a valid series.
class PvdSeries {
 public:
  struct Entry {
    double time;
    std::string file;  // relative to the .pvd's directory
    int part;
  };

  explicit PvdSeries(std::filesystem::path pvd_path) : path_(std::move(pvd_path)) {}

  /// Records a dataset and rewrites the .pvd. `file` should be relative to the .pvd's
  /// directory so the output folder can be moved. `part` distinguishes several datasets at
  /// the same time step (ParaView shows them as blocks).
  void add(double time, const std::string& file, int part = 0);

  /// Writes the .pvd with the current entries (also valid with none).
  void write() const;

  const std::vector<Entry>& entries() const { return entries_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::vector<Entry> entries_;
};

}  // namespace cohdem
