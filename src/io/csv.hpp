// CSV time series: a streaming writer (header once, one row per sample) and a small reader
// for numeric tables with a header row (e.g. the path file of `cohdem contact`).
#pragma once
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace cohdem {

/// Writes a CSV file row by row. The file is truncated and the header written on
/// construction; rows are buffered and flushed every `flush_every` rows and on destruction, so
/// a running simulation's series can be plotted while it grows.
class CsvWriter {
 public:
  /// `precision` is the number of significant digits (printf %.<precision>g); 17 makes every
  /// double read back exactly. Throws std::runtime_error (path and errno text) if the file
  /// cannot be opened, std::invalid_argument for no columns.
  CsvWriter(const std::filesystem::path& path, std::vector<std::string> columns,
            size_t flush_every = 100, int precision = 10);
  ~CsvWriter();
  CsvWriter(CsvWriter&&) noexcept;
  CsvWriter& operator=(CsvWriter&&) noexcept;

  /// Writes one row. Throws std::invalid_argument if values.size() != columns().size(),
  /// std::runtime_error on a write error.
  void row(std::span<const double> values);
  void row(std::initializer_list<double> values) { row(std::span<const double>(values.begin(), values.size())); }

  /// Pushes buffered rows to the OS. Throws std::runtime_error on a write error.
  void flush();
  /// flush(), then fsync: every row written so far survives a power cut (called before a
  /// checkpoint, so that a resume finds every row up to it). Throws std::runtime_error.
  void sync();

  const std::vector<std::string>& columns() const { return columns_; }
  size_t rows_written() const { return rows_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  struct Closer {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::filesystem::path path_;
  std::vector<std::string> columns_;
  std::unique_ptr<std::FILE, Closer> file_;
  std::string line_;  // reused row buffer
  size_t flush_every_, rows_ = 0, since_flush_ = 0;
  int precision_;
};

/// A numeric table read from CSV: named double columns of equal length.
/// Format: a header row of names, then rows of numbers; fields separated by commas, spaces
/// around fields ignored, double-quoted fields allowed; blank lines and lines starting with
/// '#' are skipped; "nan" and "inf" are accepted.
class CsvTable {
 public:
  /// Reads `path`. Throws cohdem::InputError(file, line, column, what) for an unreadable or
  /// empty file, a malformed header, a wrong field count or a field that is not a number.
  static CsvTable read(const std::filesystem::path& path);
  /// Parses `text`; `source` names it in error messages.
  static CsvTable parse(std::string_view text, const std::string& source = "<string>");

  const std::vector<std::string>& names() const { return names_; }
  size_t num_columns() const { return names_.size(); }
  size_t num_rows() const { return cols_.empty() ? 0 : cols_[0].size(); }
  bool has(std::string_view name) const { return index_of(name).has_value(); }
  std::optional<size_t> index_of(std::string_view name) const;

  /// The column called `name`; throws cohdem::InputError naming the file and listing the
  /// columns if there is none.
  const std::vector<double>& column(std::string_view name) const;
  const std::vector<double>& column(size_t i) const { return cols_.at(i); }
  /// The source line number (1-based) of data row `r`, for error messages downstream.
  int line_of_row(size_t r) const { return row_lines_.at(r); }
  const std::string& source() const { return source_; }

 private:
  std::string source_;
  std::vector<std::string> names_;
  std::vector<std::vector<double>> cols_;
  std::vector<int> row_lines_;
};

}  // namespace cohdem
