// [[particles]] files (docs/case-file.md): particles listed in a CSV file rather than as one
// TOML table each. What they must give is known without the code: the same particles, bit for
// bit, as the same numbers written as [[particle]] tables (both are read correctly rounded);
// and every malformed file must be an InputError naming the CSV file, its line and column.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.hpp"
#include "io/case_file.hpp"

using namespace cohdem;
namespace fs = std::filesystem;

namespace {

// A case with one material and no particles of its own: `extra` adds them.
std::string case_text(const std::string& extra) {
  return R"(
[simulation]
dt = 1e-5
duration = 1e-4
[[material]]
name = "glass"
density = 2500
[[material]]
name = "steel"
density = 7800
[contact]
model = "linear"
kn = 1e4
e = 0.5
mu = 0.5
)" + extra;
}

struct TempDir {
  fs::path p;
  TempDir() {
    p = fs::temp_directory_path() / ("cohdem_pf_" + std::to_string(::getpid()) + "_" +
                                     ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(p);
  }
  ~TempDir() { fs::remove_all(p); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(p / name) << text;
    return (p / name).string();
  }
};

// Loads a case whose [[particles]] file holds `csv`; returns the InputError's message ("" if none).
std::string error_of(const TempDir& d, const std::string& csv, int* line = nullptr, std::string* file = nullptr) {
  d.write("p.csv", csv);
  const std::string c = d.write("case.toml", case_text("[[particles]]\nfile = \"p.csv\"\nmaterial = \"glass\"\n"));
  try {
    load_case_file(c);
  } catch (const InputError& e) {
    if (line) *line = e.line();
    if (file) *file = e.file();
    return e.what();
  }
  return "";
}

}  // namespace

// The same numbers as TOML tables and as CSV rows give the same particles, bit for bit
// (numbers chosen to need correct rounding: 0.1, 1/3 to 17 digits, a denormal-free 1e-300,
// a leading '+'); missing velocity columns are zero; material and frozen apply to every row.
TEST(ParticleFile, SameParticlesAsTomlTables) {
  TempDir d;
  const char* rows[3][7] = {{"0.1", "0.2", "0.3", "0.05", "1.5", "-0.25", "0"},
                            {"0.33333333333333331", "-7.0000000000000009", "1e-300", "2.5e-4", "+0.1", "0", "3"},
                            {"123456.789", "0", "-0.0", "0.001", "0", "0", "-1e3"}};
  std::string toml, csv = "# id column ignored\nid, x, y, z, radius, vx, vy, vz\n";
  for (int r = 0; r < 3; ++r) {
    toml += std::string("[[particle]]\nmaterial = \"steel\"\nfrozen = true\nposition = [") + rows[r][0] + ", " +
            rows[r][1] + ", " + rows[r][2] + "]\nradius = " + rows[r][3] + "\nvelocity = [" + rows[r][4] + ", " +
            rows[r][5] + ", " + rows[r][6] + "]\n";
    csv += std::to_string(r) + ", " + rows[r][0] + ", " + rows[r][1] + ", " + rows[r][2] + ", " + rows[r][3] + ", " +
           rows[r][4] + ", " + rows[r][5] + ", " + rows[r][6] + "\n";
  }
  d.write("bed.csv", csv);
  const Case a = load_case_text(case_text(toml), "tables");
  const Case b =
      load_case_file(d.write("case.toml", case_text("[[particles]]\nfile = \"bed.csv\"\nmaterial = \"steel\"\nfrozen = true\n")));
  ASSERT_EQ(a.particles.size(), 3u);
  ASSERT_EQ(b.particles.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const ExplicitParticle &p = a.particles[i], &q = b.particles[i];
    EXPECT_EQ(p.material, q.material);
    EXPECT_EQ(p.material, 1);
    EXPECT_TRUE(q.frozen);
    EXPECT_EQ(p.radius, q.radius);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(std::signbit(p.x[k]), std::signbit(q.x[k])) << "particle " << i << " x[" << k << "]";
      EXPECT_EQ(p.x[k], q.x[k]) << "particle " << i << " x[" << k << "]";
      EXPECT_EQ(p.v[k], q.v[k]) << "particle " << i << " v[" << k << "]";
      EXPECT_EQ(q.omega[k], 0.0);
    }
  }
}

// The file is found beside the case file, not in the working folder; [[particle]] tables
// come first, then each [[particles]] file in order.
TEST(ParticleFile, PathIsRelativeToTheCaseFile) {
  TempDir d;
  fs::create_directories(d.p / "beds");
  d.write("beds/a.csv", "x,y,z,radius,wz\n1,2,3,0.5,7\n");
  d.write("beds/b.csv", "radius,z,y,x\n0.25,6,5,4\n0.25,9,8,7\n");
  const std::string c = d.write("case.toml", case_text(R"(
[[particles]]
file = "beds/a.csv"
material = "glass"
[[particle]]
material = "glass"
radius = 1
position = [0, 0, 0]
[[particles]]
file = "beds/b.csv"
material = "steel"
)"));
  const Case k = load_case_file(c);
  ASSERT_EQ(k.particles.size(), 4u);
  EXPECT_EQ(k.particles[0].radius, 1.0);
  EXPECT_EQ(k.particles[1].x[0], 1.0);
  EXPECT_EQ(k.particles[1].omega[2], 7.0);
  EXPECT_EQ(k.particles[2].x[0], 4.0);  // columns in any order
  EXPECT_EQ(k.particles[2].x[2], 6.0);
  EXPECT_EQ(k.particles[3].material, 1);
}

TEST(ParticleFile, MalformedFilesNameTheFileLineAndColumn) {
  TempDir d;
  int line = -1;
  std::string file, m;
  m = error_of(d, "x,y,radius\n1,2,3\n", &line, &file);
  EXPECT_NE(m.find("key 'z': missing column in the header"), std::string::npos) << m;
  EXPECT_EQ(line, 1);
  EXPECT_EQ(fs::path(file).filename(), "p.csv");
  m = error_of(d, "x,y,z,radius\n1,2,3,1\n4,5,abc,1\n", &line, &file);
  EXPECT_NE(m.find("key 'z': 'abc' is not a number"), std::string::npos) << m;
  EXPECT_EQ(line, 3);
  EXPECT_EQ(fs::path(file).filename(), "p.csv");
  // Malformed first rows: each error names its column (where there is one) and line 2.
  const struct { const char* row; const char* says; } bad_rows[] = {
      {"+-1,2,3,1", "key 'x': '+-1' is not a number"},
      {"1,2,3,0", "key 'radius': expected a number > 0 m"},
      {"1,2,3,1e999", "key 'radius': '1e999' is out of range"},
      {"1,2,inf,1", "key 'z': expected a finite number"},
      {"1,2,3", "expected 4 fields (as in the header), found 3"},
  };
  for (const auto& b : bad_rows) {
    m = error_of(d, std::string("x,y,z,radius\n") + b.row + "\n", &line);
    EXPECT_NE(m.find(b.says), std::string::npos) << b.row << ": " << m;
    EXPECT_EQ(line, 2) << b.row;
  }
  m = error_of(d, "x,y,z,radius\n");
  EXPECT_NE(m.find("key 'particles[0].file': particle file"), std::string::npos) << m;
  EXPECT_NE(m.find("has no particle rows"), std::string::npos) << m;
  // A file that is not there: the case file's key is named.
  const std::string c = d.write("nofile.toml", case_text("[[particles]]\nfile = \"nope.csv\"\nmaterial = \"glass\"\n"));
  try {
    load_case_file(c);
    ADD_FAILURE() << "no error for a missing particle file";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "particles[0].file");
    EXPECT_NE(std::string(e.what()).find("cannot open particle file"), std::string::npos) << e.what();
  }
  // Unknown keys of the table are errors too (as everywhere in a case file).
  try {
    load_case_text(case_text("[[particles]]\nfile = \"x.csv\"\nmaterial = \"glass\"\nradius = 1\n"), "t");
    ADD_FAILURE() << "no error for an unknown key";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "particles[0].radius");
  }
}
