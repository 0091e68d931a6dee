// PNG plots through gnuplot (Debian: gnuplot-nox). Data go to temporary files, a script is
// written next to them and gnuplot runs on it; the PNG is renamed into place only on success.
#pragma once
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace cohdem {

/// One curve. Non-finite points (NaN, inf) leave a gap in the line.
struct Series {
  std::string label;
  std::vector<double> x, y;
  std::string style = "lines";  // "lines", "points", "linespoints", "steps" or "impulses"
};

/// One panel: title, axis labels, curves and marked x positions (e.g. phase changes).
struct PlotSpec {
  std::string title, xlabel, ylabel;
  std::vector<Series> series;
  std::vector<std::pair<double, std::string>> vlines;  // dashed vertical lines with labels
  int width = 900, height = 600;                        // pixels
  bool equal_axes = false;                              // same scale on x and y (Mohr circles)
  bool logx = false, logy = false;
  std::optional<std::pair<double, double>> xrange, yrange;  // default: autoscale
};

/// Renders `spec` into `png`. Labels are printed literally (no gnuplot "enhanced" markup).
/// A panel without data is drawn empty. Uses the pngcairo terminal when gnuplot has it,
/// else png. The gnuplot executable is `gnuplot` on PATH, or $COHDEM_GNUPLOT if set.
/// Throws std::invalid_argument for x/y of different lengths or an unknown style, and
/// std::runtime_error if gnuplot is missing or fails (with its error output).
void plot_png(const std::filesystem::path& png, const PlotSpec& spec);

/// Several panels in one PNG (gnuplot multiplot), filled row by row in `columns` columns.
/// Each cell is panels[0].width x panels[0].height pixels.
void plot_png_panels(const std::filesystem::path& png, const std::vector<PlotSpec>& panels, int columns);

/// A circle of `radius` about (center_x, 0), sampled at `samples` points (closed), or only the
/// upper half (y >= 0) when `upper_half_only`: the usual drawing of a Mohr circle.
Series circle(double center_x, double radius, std::string label, bool upper_half_only = false,
              int samples = 181);

/// True if the gnuplot executable (see plot_png) runs. Spawns `gnuplot --version` each call.
bool gnuplot_available();

}  // namespace cohdem
