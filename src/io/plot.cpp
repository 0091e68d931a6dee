#include "io/plot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>

extern char** environ;

namespace cohdem {

namespace {

std::string gnuplot_exe() {
  const char* e = std::getenv("COHDEM_GNUPLOT");
  return (e && *e) ? std::string(e) : std::string("gnuplot");
}

/// A temporary directory removed with everything in it on scope exit.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "cohdem-plot-XXXXXX").string();
    if (!::mkdtemp(tmpl.data()))
      throw std::runtime_error(fmt::format("cannot create temporary directory '{}': {}", tmpl, std::strerror(errno)));
    path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

struct RunResult {
  int spawn_error = 0;  // errno from posix_spawnp, 0 if the process started
  int status = -1;      // exit status, or -1 if it did not exit normally
};

/// Runs `exe args...` without a shell (no quoting issues), stdout and stderr to `log`.
RunResult run(const std::string& exe, const std::vector<std::string>& args, const std::filesystem::path& log) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(exe.c_str()));
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  RunResult r;
  r.spawn_error = posix_spawnp(&pid, exe.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (r.spawn_error != 0) return r;
  int st = 0;
  while (::waitpid(pid, &st, 0) < 0) {
    if (errno != EINTR) {
      r.status = -1;
      return r;
    }
  }
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

/// A gnuplot single-quoted string: only ' needs escaping (doubled); newlines become spaces.
std::string quote(std::string_view s) {
  std::string q = "'";
  for (char c : s) {
    if (c == '\'') q += "''";
    else if (c == '\n' || c == '\r') q += ' ';
    else q += c;
  }
  return q + "'";
}

std::string style_clause(const std::string& style) {
  if (style == "lines") return "with lines lw 1.5";
  if (style == "points") return "with points pt 7 ps 0.6";
  if (style == "linespoints") return "with linespoints lw 1.5 pt 7 ps 0.6";
  if (style == "steps") return "with steps lw 1.5";
  if (style == "impulses") return "with impulses lw 1.5";
  throw std::invalid_argument(
      fmt::format("plot: unknown series style '{}' (lines, points, linespoints, steps, impulses)", style));
}

std::string range(const std::pair<double, double>& r, const char* axis) {
  if (!std::isfinite(r.first) || !std::isfinite(r.second) || !(r.first < r.second))
    throw std::invalid_argument(fmt::format("plot: bad {} range [{}, {}]", axis, r.first, r.second));
  return fmt::format("set {} [{}:{}]\n", axis, r.first, r.second);
}

/// Writes the data files of one panel into `dir` and returns its gnuplot commands.
std::string panel_script(const PlotSpec& p, size_t panel, const std::filesystem::path& dir) {
  std::string s;
  // Reset what a previous multiplot panel may have set.
  s += "unset arrow\nunset label\nunset logscale\nset size noratio\nset autoscale xy\n";
  s += "set grid\nset key top right opaque\n";  // opaque: curves do not run through the legend

  s += fmt::format("set title {}\nset xlabel {}\nset ylabel {}\n", quote(p.title), quote(p.xlabel), quote(p.ylabel));
  if (p.equal_axes) s += "set size ratio -1\n";
  if (p.logx) s += "set logscale x\n";
  if (p.logy) s += "set logscale y\n";
  if (p.xrange) s += range(*p.xrange, "xrange");
  if (p.yrange) s += range(*p.yrange, "yrange");
  for (const auto& [x, text] : p.vlines) {
    if (!std::isfinite(x)) continue;
    s += fmt::format("set arrow from {0}, graph 0 to {0}, graph 1 nohead dt 2 lw 1 lc rgb 'gray40'\n", x);
    if (!text.empty())
      s += fmt::format("set label {} at {}, graph 0.98 rotate by 90 right front offset character -1.0,0 "
                       "font ',8' tc rgb 'gray30'\n",
                       quote(text), x);
  }

  std::vector<std::string> items;
  for (size_t k = 0; k < p.series.size(); ++k) {
    const Series& sr = p.series[k];
    if (sr.x.size() != sr.y.size())
      throw std::invalid_argument(fmt::format("plot '{}': series '{}' has {} x and {} y values", p.title, sr.label,
                                              sr.x.size(), sr.y.size()));
    const std::string with = style_clause(sr.style);
    const auto file = dir / fmt::format("p{}_s{}.dat", panel, k);
    std::ofstream out(file);
    size_t finite = 0;
    bool gap = true;  // no blank line first or twice in a row (two mean a new data block)
    for (size_t i = 0; i < sr.x.size(); ++i) {
      if (std::isfinite(sr.x[i]) && std::isfinite(sr.y[i])) {
        out << fmt::format("{:.17g} {:.17g}\n", sr.x[i], sr.y[i]);
        ++finite;
        gap = false;
      } else if (!gap) {
        out << '\n';
        gap = true;
      }
    }
    out.close();
    if (!out) throw std::runtime_error(fmt::format("plot: cannot write data file '{}'", file.string()));
    if (finite == 0) continue;  // gnuplot fails on a file without points
    items.push_back(fmt::format("{} using 1:2 {} {}", quote(file.string()), with,
                                sr.label.empty() ? std::string("notitle") : "title " + quote(sr.label)));
  }
  if (items.empty()) {
    // An empty panel (e.g. no contacts yet): draw the frame with a note instead of failing.
    s += "unset logscale\n";
    if (!p.xrange) s += "set xrange [0:1]\n";
    if (!p.yrange) s += "set yrange [0:1]\n";
    s += "set label 'no data' at graph 0.5, graph 0.5 center\nplot NaN notitle\n";
    return s;
  }
  s += "plot ";
  for (size_t i = 0; i < items.size(); ++i) s += (i ? ", \\\n     " : "") + items[i];
  s += '\n';
  return s;
}

std::string tail(const std::filesystem::path& log, size_t max_chars = 2000) {
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string t = ss.str();
  if (t.size() > max_chars) t = "..." + t.substr(t.size() - max_chars);
  while (!t.empty() && (t.back() == '\n' || t.back() == ' ')) t.pop_back();
  return t;
}

void render(const std::filesystem::path& png, const std::vector<PlotSpec>& panels, int columns) {
  if (panels.empty()) throw std::invalid_argument("plot: no panels for " + png.string());
  if (columns < 1) throw std::invalid_argument("plot: columns must be >= 1");
  const int cols = std::min<int>(columns, static_cast<int>(panels.size()));
  const int rows = (static_cast<int>(panels.size()) + cols - 1) / cols;
  const int w = panels[0].width * cols, h = panels[0].height * rows;
  if (panels[0].width <= 0 || panels[0].height <= 0) throw std::invalid_argument("plot: width and height must be > 0");

  TempDir dir;
  // gnuplot writes next to the target, then we rename: no half-written PNG on failure.
  std::filesystem::path tmp_png = png;
  tmp_png += ".tmp." + std::to_string(::getpid());

  std::string s;
  s += fmt::format(
      "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {{\n"
      "  set terminal pngcairo size {0},{1} noenhanced font 'sans,10'\n"
      "}} else {{\n"
      "  set terminal png size {0},{1} noenhanced\n"
      "}}\n",
      w, h);
  s += fmt::format("set output {}\n", quote(tmp_png.string()));
  if (panels.size() > 1) s += fmt::format("set multiplot layout {},{}\n", rows, cols);
  for (size_t i = 0; i < panels.size(); ++i) s += panel_script(panels[i], i, dir.path());
  if (panels.size() > 1) s += "unset multiplot\n";
  s += "set output\n";  // closes the PNG

  const auto script = dir.path() / "plot.gp";
  {
    std::ofstream out(script);
    out << s;
    if (!out) throw std::runtime_error(fmt::format("plot: cannot write script '{}'", script.string()));
  }
  const auto log = dir.path() / "gnuplot.log";
  const std::string exe = gnuplot_exe();
  const RunResult r = run(exe, {script.string()}, log);
  std::error_code ec;
  if (r.spawn_error != 0)
    throw std::runtime_error(fmt::format(
        "cannot run gnuplot ('{}': {}) to draw '{}': install gnuplot (Debian: gnuplot-nox) or set COHDEM_GNUPLOT",
        exe, std::strerror(r.spawn_error), png.string()));
  if (r.status != 0 || !std::filesystem::exists(tmp_png)) {
    std::filesystem::remove(tmp_png, ec);
    throw std::runtime_error(
        fmt::format("gnuplot failed (exit status {}) drawing '{}':\n{}", r.status, png.string(), tail(log)));
  }
  if (std::rename(tmp_png.c_str(), png.c_str()) != 0) {
    const int err = errno;
    std::filesystem::remove(tmp_png, ec);
    throw std::runtime_error(fmt::format("cannot rename plot onto '{}': {}", png.string(), std::strerror(err)));
  }
}

}  // namespace

void plot_png(const std::filesystem::path& png, const PlotSpec& spec) { render(png, {spec}, 1); }

void plot_png_panels(const std::filesystem::path& png, const std::vector<PlotSpec>& panels, int columns) {
  render(png, panels, columns);
}

Series circle(double center_x, double radius, std::string label, bool upper_half_only, int samples) {
  if (samples < 2) throw std::invalid_argument("circle: need at least 2 samples");
  Series s;
  s.label = std::move(label);
  s.x.resize(static_cast<size_t>(samples));
  s.y.resize(static_cast<size_t>(samples));
  const double span = upper_half_only ? std::numbers::pi : 2 * std::numbers::pi;
  for (int i = 0; i < samples; ++i) {
    // Last sample lands exactly on the start angle + span, so the full circle closes.
    const double t = span * static_cast<double>(i) / static_cast<double>(samples - 1);
    s.x[static_cast<size_t>(i)] = center_x + radius * std::cos(t);
    s.y[static_cast<size_t>(i)] = radius * std::sin(t);
  }
  return s;
}

bool gnuplot_available() {
  TempDir dir;
  const RunResult r = run(gnuplot_exe(), {"--version"}, dir.path() / "version.log");
  return r.spawn_error == 0 && r.status == 0;
}

}  // namespace cohdem
