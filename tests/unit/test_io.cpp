// Output layer: VTU bytes decode to what was written, PVD order, atomic writes, CSV round
// trip and errors, gnuplot PNGs. The VTU is checked by parsing its header and appended
// blocks here, so the test does not need python's vtk module.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/csv.hpp"
#include "io/plot.hpp"
#include "io/vtk.hpp"

using namespace cohdem;
namespace fs = std::filesystem;

namespace {

/// A fresh directory per test, removed afterwards.
class IoDir : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir = fs::temp_directory_path() /
          (std::string("cohdem-test-io-") + std::to_string(::getpid()) + "-" + info->test_suite_name() + "-" + info->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }

  /// Names of the files in `dir` containing ".tmp." (leftover temp files).
  std::vector<std::string> temp_files() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().filename().string().find(".tmp.") != std::string::npos) out.push_back(e.path().filename());
    return out;
  }
  fs::path dir;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void spit(const fs::path& p, const std::string& s) {
  std::ofstream out(p, std::ios::binary);
  out << s;
}

/// A parsed .vtu: header attributes of each DataArray and its decoded appended block.
struct ParsedArray {
  std::string type;
  int components = 0;
  uint64_t offset = 0;
  std::string bytes;  // payload (after the UInt64 count)
};

struct ParsedVtu {
  std::string header;
  std::map<std::string, ParsedArray> arrays;
  std::vector<uint64_t> offsets_in_order;
  uint64_t appended_size = 0;  // bytes between '_' and the closing tag
};

ParsedVtu parse_vtu(const std::string& file) {
  ParsedVtu v;
  const std::string tag = "<AppendedData encoding=\"raw\">";
  const size_t at = file.find(tag);
  EXPECT_NE(at, std::string::npos);
  const size_t base = file.find('_', at) + 1;
  v.header = file.substr(0, at);
  const std::string end_tag = "\n  </AppendedData>";
  const size_t end = file.rfind(end_tag);
  EXPECT_NE(end, std::string::npos);
  v.appended_size = end - base;

  const std::regex re(
      R"re(<DataArray type="(\w+)" Name="([^"]+)" NumberOfComponents="(\d+)" format="appended" offset="(\d+)"/>)re");
  for (auto it = std::sregex_iterator(v.header.begin(), v.header.end(), re); it != std::sregex_iterator(); ++it) {
    ParsedArray a;
    a.type = (*it)[1];
    a.components = std::stoi((*it)[3]);
    a.offset = std::stoull((*it)[4]);
    uint64_t n = 0;
    std::memcpy(&n, file.data() + base + a.offset, sizeof n);
    a.bytes = file.substr(base + a.offset + 8, n);
    v.offsets_in_order.push_back(a.offset);
    v.arrays[(*it)[2]] = a;
  }
  return v;
}

template <class T>
std::vector<T> decode(const std::string& bytes) {
  std::vector<T> out(bytes.size() / sizeof(T));
  std::memcpy(out.data(), bytes.data(), out.size() * sizeof(T));
  return out;
}

Vec3 quad_normal(const VtuData& d, size_t cell) {
  const int64_t b = cell == 0 ? 0 : d.offsets[cell - 1];
  const Vec3 p0 = d.points[d.connectivity[b]], p1 = d.points[d.connectivity[b + 1]],
             p2 = d.points[d.connectivity[b + 2]];
  return normalized(cross(p1 - p0, p2 - p0));
}

}  // namespace

// ------------------------------------------------------------------------------- atomic

using IoAtomicFile = IoDir;

TEST_F(IoAtomicFile, WriteReplacesAndLeavesNoTemp) {
  const auto p = dir / "a.txt";
  write_file_atomic(p, "first");
  write_file_atomic(p, "second");
  EXPECT_EQ(slurp(p), "second");
  EXPECT_TRUE(temp_files().empty());
}

// Sync::durable adds fsyncs (of the file before the rename, of its directory after): what is
// on disk must be the same as without them. (Surviving a power cut cannot be tested here;
// tests/cli/resume_killed.sh covers the kill -9 side of checkpoints.)
TEST_F(IoAtomicFile, DurableWriteReplacesAndLeavesNoTemp) {
  const auto p = dir / "ck.bin";
  write_file_atomic(p, "first", Sync::durable);
  write_file_atomic(p, std::string(100000, 'x'), Sync::durable);
  EXPECT_EQ(slurp(p), std::string(100000, 'x'));
  EXPECT_TRUE(temp_files().empty());
}

TEST_F(IoAtomicFile, UncommittedWriterKeepsOldFile) {
  const auto p = dir / "a.txt";
  write_file_atomic(p, "old contents");
  {
    AtomicWriter w(p);
    w << "new " << 42;
    EXPECT_TRUE(fs::exists(w.temp_path()));
    EXPECT_EQ(slurp(p), "old contents");  // not visible before commit
  }
  EXPECT_EQ(slurp(p), "old contents");
  EXPECT_TRUE(temp_files().empty());

  AtomicWriter w(p);
  w << "new " << 42;
  w.commit();
  EXPECT_TRUE(w.committed());
  EXPECT_EQ(slurp(p), "new 42");
  EXPECT_TRUE(temp_files().empty());
}

TEST_F(IoAtomicFile, ErrorNamesPathAndErrno) {
  const auto p = dir / "no-such-dir" / "a.txt";
  try {
    write_file_atomic(p, "x");
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(std::strerror(ENOENT)), std::string::npos) << e.what();
  }
}

// ------------------------------------------------------------------------------- vtu

using VtkWriter = IoDir;

TEST_F(VtkWriter, HeaderAndAppendedBlocksDecode) {
  const std::vector<Vec3> pts = {{0, 0, 0}, {1.5, -2, 3}, {1e-3, 2e-3, -7.25}};
  VtuData d = particles_vtu(pts);
  d.add_point_scalar("radius", {0.1, 0.2, 0.3});
  d.add_point_vector("velocity", {{1, 2, 3}, {4, 5, 6}, {-1, -2, -3.5}});
  const auto p = dir / "p.vtu";
  write_vtu(p, d);
  EXPECT_TRUE(temp_files().empty());

  const std::string file = slurp(p);
  const ParsedVtu v = parse_vtu(file);
  EXPECT_NE(v.header.find("type=\"UnstructuredGrid\""), std::string::npos);
  EXPECT_NE(v.header.find("header_type=\"UInt64\""), std::string::npos);
  EXPECT_NE(v.header.find("byte_order=\"LittleEndian\""), std::string::npos);
  EXPECT_NE(v.header.find("NumberOfPoints=\"3\""), std::string::npos);
  EXPECT_NE(v.header.find("NumberOfCells=\"3\""), std::string::npos);

  // 2 point arrays + Points + connectivity/offsets/types.
  ASSERT_EQ(v.arrays.size(), 6u);
  for (const char* name : {"radius", "velocity", "Points", "connectivity", "offsets", "types"})
    ASSERT_TRUE(v.arrays.count(name)) << name;
  EXPECT_EQ(v.arrays.at("radius").type, "Float64");
  EXPECT_EQ(v.arrays.at("radius").components, 1);
  EXPECT_EQ(v.arrays.at("velocity").components, 3);
  EXPECT_EQ(v.arrays.at("types").type, "UInt8");

  // Blocks are contiguous: each is an 8-byte count plus its payload, the first at offset 0.
  std::vector<std::pair<uint64_t, uint64_t>> blocks;  // offset, payload size
  for (const auto& [name, a] : v.arrays) blocks.push_back({a.offset, a.bytes.size()});
  std::sort(blocks.begin(), blocks.end());
  EXPECT_EQ(blocks.front().first, 0u);
  for (size_t i = 1; i < blocks.size(); ++i)
    EXPECT_EQ(blocks[i].first, blocks[i - 1].first + 8 + blocks[i - 1].second);
  EXPECT_EQ(v.appended_size, blocks.back().first + 8 + blocks.back().second);
  EXPECT_EQ(v.offsets_in_order, [&] {
    std::vector<uint64_t> o;
    for (auto& b : blocks) o.push_back(b.first);
    return o;
  }());  // header lists blocks in file order

  EXPECT_EQ(decode<double>(v.arrays.at("radius").bytes), (std::vector<double>{0.1, 0.2, 0.3}));
  EXPECT_EQ(decode<double>(v.arrays.at("velocity").bytes),
            (std::vector<double>{1, 2, 3, 4, 5, 6, -1, -2, -3.5}));
  EXPECT_EQ(decode<double>(v.arrays.at("Points").bytes),
            (std::vector<double>{0, 0, 0, 1.5, -2, 3, 1e-3, 2e-3, -7.25}));
  EXPECT_EQ(decode<int64_t>(v.arrays.at("connectivity").bytes), (std::vector<int64_t>{0, 1, 2}));
  EXPECT_EQ(decode<int64_t>(v.arrays.at("offsets").bytes), (std::vector<int64_t>{1, 2, 3}));
  EXPECT_EQ(decode<uint8_t>(v.arrays.at("types").bytes), (std::vector<uint8_t>{1, 1, 1}));
}

TEST_F(VtkWriter, IntegerArraysAndEmptyGrid) {
  VtuData d = particles_vtu({{0, 0, 0}, {1, 1, 1}});
  d.add_point_id("id", {7, 1ull << 40});
  d.add_point_int("group", {-3, 4});
  d.add_cell_u8("flag", {0, 255});
  write_vtu(dir / "i.vtu", d);
  const ParsedVtu v = parse_vtu(slurp(dir / "i.vtu"));
  EXPECT_EQ(v.arrays.at("id").type, "UInt64");
  EXPECT_EQ(decode<uint64_t>(v.arrays.at("id").bytes), (std::vector<uint64_t>{7, 1ull << 40}));
  EXPECT_EQ(decode<int32_t>(v.arrays.at("group").bytes), (std::vector<int32_t>{-3, 4}));
  EXPECT_EQ(decode<uint8_t>(v.arrays.at("flag").bytes), (std::vector<uint8_t>{0, 255}));

  // No particles yet is a valid (empty) file.
  write_vtu(dir / "empty.vtu", particles_vtu({}));
  const ParsedVtu e = parse_vtu(slurp(dir / "empty.vtu"));
  EXPECT_NE(e.header.find("NumberOfPoints=\"0\""), std::string::npos);
  EXPECT_EQ(e.appended_size, 4u * 8u);  // Points + 3 cell arrays, all empty
}

TEST_F(VtkWriter, RejectsInconsistentData) {
  VtuData d = particles_vtu({{0, 0, 0}, {1, 1, 1}});
  d.add_point_scalar("r", {1.0});  // one value for two points
  EXPECT_THROW(write_vtu(dir / "bad.vtu", d), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir / "bad.vtu"));

  VtuData dup = particles_vtu({{0, 0, 0}});
  dup.add_point_scalar("r", {1.0});
  dup.add_point_scalar("r", {2.0});
  EXPECT_THROW(dup.validate(), std::invalid_argument);

  VtuData badcell;
  badcell.points = {{0, 0, 0}};
  badcell.add_cell(VtkCell::Line, {0, 1});  // point 1 does not exist
  EXPECT_THROW(badcell.validate(), std::invalid_argument);

  EXPECT_THROW(lines_vtu({{0, 0, 0}}, {{0, 1}}), std::invalid_argument);
}

TEST_F(VtkWriter, LinesForContactNetwork) {
  VtuData d = lines_vtu({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1}, {1, 2}});
  d.add_cell_scalar("force", {1.0, 2.0});
  d.add_cell_vector("normal", {{1, 0, 0}, {0, 1, 0}});
  EXPECT_EQ(d.num_cells(), 2u);
  EXPECT_EQ(d.connectivity, (std::vector<int64_t>{0, 1, 1, 2}));
  EXPECT_EQ(d.offsets, (std::vector<int64_t>{2, 4}));
  EXPECT_NO_THROW(write_vtu(dir / "net.vtu", d));
  const ParsedVtu v = parse_vtu(slurp(dir / "net.vtu"));
  EXPECT_EQ(decode<uint8_t>(v.arrays.at("types").bytes), (std::vector<uint8_t>{3, 3}));
}

TEST(VtkMesh, PlanePatchOrientation) {
  const Vec3 c{1, 2, 3}, n{0, 0, -1};
  const VtuData d = plane_patch(c, n, 0.5);
  ASSERT_EQ(d.num_cells(), 1u);
  EXPECT_EQ(d.types[0], static_cast<uint8_t>(VtkCell::Quad));
  EXPECT_NEAR(norm(quad_normal(d, 0) - n), 0, 1e-12);
  for (const Vec3& p : d.points) {
    EXPECT_NEAR(dot(p - c, n), 0, 1e-12);
    EXPECT_NEAR(norm(p - c), 0.5 * std::sqrt(2.0), 1e-12);
  }
  EXPECT_NO_THROW(d.validate());
  EXPECT_THROW(plane_patch(c, {0, 0, 0}, 1), std::invalid_argument);
}

TEST(VtkMesh, CylinderOutwardQuads) {
  const Vec3 a0{1, 0, 0}, axis{0, 1, 1};
  const Vec3 ua = normalized(axis);
  const VtuData d = cylinder_surface(a0, axis, 0.2, -1, 2, 16);
  EXPECT_EQ(d.num_points(), 32u);
  EXPECT_EQ(d.num_cells(), 16u);
  for (const Vec3& p : d.points) {
    const Vec3 r = (p - a0) - dot(p - a0, ua) * ua;
    EXPECT_NEAR(norm(r), 0.2, 1e-12);
    const double z = dot(p - a0, ua);
    EXPECT_TRUE(std::abs(z + 1) < 1e-12 || std::abs(z - 2) < 1e-12) << z;
  }
  for (size_t c = 0; c < d.num_cells(); ++c) {
    const int64_t b = c == 0 ? 0 : d.offsets[c - 1];
    Vec3 centroid;
    for (int k = 0; k < 4; ++k) centroid += d.points[d.connectivity[b + k]] / 4.0;
    const Vec3 radial = (centroid - a0) - dot(centroid - a0, ua) * ua;
    EXPECT_GT(dot(quad_normal(d, c), radial), 0) << "cell " << c;
  }
  EXPECT_NO_THROW(d.validate());
}

TEST(VtkMesh, AnnulusAndDisk) {
  const Vec3 c{0, 0, 1}, n{0, 1, 0};
  const VtuData ring = disk_annulus(c, n, 0.5, 1.0, 12);
  EXPECT_EQ(ring.num_cells(), 12u);
  EXPECT_EQ(ring.types[0], static_cast<uint8_t>(VtkCell::Quad));
  for (size_t k = 0; k < ring.num_cells(); ++k) EXPECT_NEAR(norm(quad_normal(ring, k) - n), 0, 1e-12);
  const VtuData disk = disk_annulus(c, n, 0.0, 1.0, 12);
  EXPECT_EQ(disk.num_points(), 13u);
  EXPECT_EQ(disk.types[0], static_cast<uint8_t>(VtkCell::Triangle));
  for (size_t k = 0; k < disk.num_cells(); ++k) EXPECT_NEAR(norm(quad_normal(disk, k) - n), 0, 1e-12);
  EXPECT_NO_THROW(ring.validate());
  EXPECT_NO_THROW(disk.validate());
  EXPECT_THROW(disk_annulus(c, n, 1.0, 0.5, 12), std::invalid_argument);
}

TEST(VtkMesh, MergeShiftsIndicesAndConcatenatesArrays) {
  VtuData a = plane_patch({0, 0, 0}, {0, 0, 1}, 1);
  a.fill_cell_int("wall_id", 0);
  VtuData b = cylinder_surface({0, 0, 0}, {0, 0, 1}, 1, 0, 1, 8);
  b.fill_cell_int("wall_id", 1);
  const VtuData m = merge({a, b});
  EXPECT_EQ(m.num_points(), 4u + 16u);
  EXPECT_EQ(m.num_cells(), 1u + 8u);
  EXPECT_NO_THROW(m.validate());
  EXPECT_EQ(m.connectivity[4], b.connectivity[0] + 4);
  EXPECT_EQ(m.offsets[1], b.offsets[0] + 4);
  const auto& ids = std::get<std::vector<int32_t>>(m.cell_data.at(0).values);
  EXPECT_EQ(ids, (std::vector<int32_t>{0, 1, 1, 1, 1, 1, 1, 1, 1}));

  VtuData c = plane_patch({0, 0, 0}, {1, 0, 0}, 1);
  c.fill_cell_int("other", 2);
  EXPECT_THROW(merge({a, c}), std::invalid_argument);
  VtuData e = plane_patch({0, 0, 0}, {1, 0, 0}, 1);
  e.add_cell_scalar("wall_id", {2.0});  // same name, different type
  EXPECT_THROW(merge({a, e}), std::invalid_argument);
  EXPECT_EQ(merge({}).num_points(), 0u);
}

using VtkPvd = IoDir;

TEST_F(VtkPvd, ListsEntriesInOrder) {
  PvdSeries s(dir / "particles.pvd");
  s.add(0.0, "particles_000000.vtu");
  s.add(1e-4, "particles_000100.vtu");
  s.add(2.5e-4, "particles_000250.vtu");
  EXPECT_TRUE(temp_files().empty());
  const std::string x = slurp(dir / "particles.pvd");
  EXPECT_NE(x.find("type=\"Collection\""), std::string::npos);
  const std::regex re(R"re(<DataSet timestep="([^"]+)" group="" part="0" file="([^"]+)"/>)re");
  std::vector<std::string> files;
  std::vector<double> times;
  for (auto it = std::sregex_iterator(x.begin(), x.end(), re); it != std::sregex_iterator(); ++it) {
    times.push_back(std::stod((*it)[1]));
    files.push_back((*it)[2]);
  }
  EXPECT_EQ(files, (std::vector<std::string>{"particles_000000.vtu", "particles_000100.vtu", "particles_000250.vtu"}));
  EXPECT_EQ(times, (std::vector<double>{0.0, 1e-4, 2.5e-4}));  // exact: shortest round-trip
}

// ------------------------------------------------------------------------------- csv

using CsvIo = IoDir;

TEST_F(CsvIo, RoundTrip) {
  const auto p = dir / "series.csv";
  const double third = 1.0 / 3.0;
  {
    CsvWriter w(p, {"t", "E_kin", "label, with comma"}, 2, 17);
    w.row({0.0, 1.5, -2});
    w.row(std::vector<double>{1e-7, third, 6.02214076e23});
    w.row({2e-7, NAN, INFINITY});
    EXPECT_EQ(w.rows_written(), 3u);
    EXPECT_THROW(w.row({1.0}), std::invalid_argument);
  }
  const CsvTable t = CsvTable::read(p);
  EXPECT_EQ(t.names(), (std::vector<std::string>{"t", "E_kin", "label, with comma"}));
  ASSERT_EQ(t.num_rows(), 3u);
  EXPECT_EQ(t.column("t"), (std::vector<double>{0.0, 1e-7, 2e-7}));
  EXPECT_EQ(t.column("E_kin")[1], third);  // exact with 17 digits
  EXPECT_TRUE(std::isnan(t.column("E_kin")[2]));
  EXPECT_TRUE(std::isinf(t.column(2)[2]));
  EXPECT_EQ(t.line_of_row(0), 2);
}

TEST_F(CsvIo, DefaultPrecisionIsTenDigits) {
  const auto p = dir / "p.csv";
  {
    CsvWriter w(p, {"x"});
    w.row({1.0 / 3.0});
  }
  EXPECT_EQ(slurp(p), "x\n0.3333333333\n");
}

// sync() puts every row written so far into the file (a checkpoint relies on it), while the
// writer stays open and its buffer would otherwise hold them (flush_every = 100).
TEST_F(CsvIo, SyncWritesBufferedRows) {
  const auto p = dir / "s.csv";
  CsvWriter w(p, {"step"}, 100);
  w.row({1.0});
  w.row({2.0});
  EXPECT_EQ(slurp(p), "step\n");  // still buffered
  w.sync();
  EXPECT_EQ(slurp(p), "step\n1\n2\n");
}

TEST_F(CsvIo, ReaderSkipsCommentsAndBlankLines) {
  const CsvTable t = CsvTable::parse("# a path for cohdem contact\n\n delta , xi\n1e-6, 0\r\n+2e-6 ,1.5\n\n", "path.csv");
  EXPECT_EQ(t.names(), (std::vector<std::string>{"delta", "xi"}));
  EXPECT_EQ(t.column("delta"), (std::vector<double>{1e-6, 2e-6}));
  EXPECT_EQ(t.column("xi"), (std::vector<double>{0, 1.5}));
  EXPECT_EQ(t.line_of_row(1), 5);
  EXPECT_TRUE(t.has("xi"));
  EXPECT_FALSE(t.has("theta"));
}

TEST_F(CsvIo, ErrorsNameLineAndColumn) {
  try {
    CsvTable::parse("delta,xi,theta\n0,0,0\n1,abc,0\n", "path.csv");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "path.csv");
    EXPECT_EQ(e.line(), 3);
    EXPECT_EQ(e.key(), "xi");
    const std::string w = e.what();
    EXPECT_NE(w.find("path.csv:3"), std::string::npos) << w;
    EXPECT_NE(w.find("'abc' is not a number (column 2)"), std::string::npos) << w;
  }
  try {
    CsvTable::parse("a,b\n1,2\n3\n", "f.csv");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_NE(std::string(e.what()).find("expected 2 fields"), std::string::npos) << e.what();
  }
  EXPECT_THROW(CsvTable::parse("a,b\n1,\n", "f.csv"), InputError);  // empty field
  EXPECT_THROW(CsvTable::parse("a,a\n1,2\n", "f.csv"), InputError);  // duplicate name
  EXPECT_THROW(CsvTable::parse("a,b\n1,2x\n", "f.csv"), InputError);  // trailing junk

  spit(dir / "empty.csv", "");
  try {
    CsvTable::read(dir / "empty.csv");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("empty file"), std::string::npos) << e.what();
  }
  EXPECT_THROW(CsvTable::read(dir / "missing.csv"), InputError);

  const CsvTable t = CsvTable::parse("a,b\n1,2\n", "f.csv");
  try {
    t.column("phi");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "phi");
    EXPECT_NE(std::string(e.what()).find("columns: a, b"), std::string::npos) << e.what();
  }
}

// ------------------------------------------------------------------------------- plot

using PlotPng = IoDir;

namespace {
bool is_png(const fs::path& p) {
  const std::string s = slurp(p);
  return s.size() > 8 && s.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0;
}
}  // namespace

TEST_F(PlotPng, SinglePanel) {
  if (!gnuplot_available()) GTEST_SKIP() << "gnuplot not installed";
  PlotSpec s;
  s.title = "force_n vs delta (it's literal: a_b^c)";
  s.xlabel = "delta [m]";
  s.ylabel = "F [N]";
  Series a{"loading", {0, 1, 2, 3}, {0, 1, 4, 9}};
  Series b{"with gap", {0, 1, 2, 3}, {1, NAN, 3, 2}, "linespoints"};
  s.series = {a, b};
  s.vlines = {{1.5, "yield"}, {2.5, "unload"}};
  const auto p = dir / "one.png";
  plot_png(p, s);
  EXPECT_TRUE(is_png(p));
  EXPECT_TRUE(temp_files().empty());
}

TEST_F(PlotPng, PanelsWithMohrCirclesAndEmptyPanel) {
  if (!gnuplot_available()) GTEST_SKIP() << "gnuplot not installed";
  PlotSpec mohr;
  mohr.title = "Mohr circles";
  mohr.equal_axes = true;
  mohr.series = {circle(2.0, 1.0, "sigma_3=1", true), circle(3.0, 2.0, "full", false, 91)};
  PlotSpec empty;
  empty.title = "contacts";
  PlotSpec logp;
  logp.logy = true;
  logp.series = {Series{"decay", {0, 1, 2}, {1, 0.1, 0.01}, "points"}};
  const auto p = dir / "panels.png";
  plot_png_panels(p, {mohr, empty, logp}, 2);
  EXPECT_TRUE(is_png(p));
  EXPECT_TRUE(temp_files().empty());

  const Series c = circle(2.0, 1.0, "", true, 5);
  EXPECT_NEAR(c.x.front(), 3.0, 1e-15);
  EXPECT_NEAR(c.x.back(), 1.0, 1e-15);
  EXPECT_NEAR(c.y[2], 1.0, 1e-15);
  for (double y : c.y) EXPECT_GE(y, -1e-15);
}

TEST_F(PlotPng, ClearErrors) {
  PlotSpec s;
  s.series = {Series{"bad", {0, 1}, {0}}};
  EXPECT_THROW(plot_png(dir / "x.png", s), std::invalid_argument);
  s.series = {Series{"bad", {0, 1}, {0, 1}, "bars"}};
  EXPECT_THROW(plot_png(dir / "x.png", s), std::invalid_argument);

  s.series = {Series{"ok", {0, 1}, {0, 1}}};
  const char* old = std::getenv("COHDEM_GNUPLOT");
  const std::string saved = old ? old : "";
  ::setenv("COHDEM_GNUPLOT", "/nonexistent/gnuplot", 1);
  try {
    plot_png(dir / "x.png", s);
    ADD_FAILURE() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot run gnuplot"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(gnuplot_available());
  ::setenv("COHDEM_GNUPLOT", "false", 1);  // runs, exits 1
  try {
    plot_png(dir / "x.png", s);
    ADD_FAILURE() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("gnuplot failed"), std::string::npos) << e.what();
  }
  if (old) ::setenv("COHDEM_GNUPLOT", saved.c_str(), 1);
  else ::unsetenv("COHDEM_GNUPLOT");
  EXPECT_FALSE(fs::exists(dir / "x.png"));
  EXPECT_TRUE(temp_files().empty());
}
