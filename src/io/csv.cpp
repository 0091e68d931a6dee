#include "io/csv.hpp"

#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "core/error.hpp"

namespace cohdem {

namespace {

std::runtime_error io_error(const std::string& what, const std::filesystem::path& p, int err) {
  return std::runtime_error(what + " '" + p.string() + "': " + std::strerror(err));
}

/// Quotes a header name only when it needs it (comma, quote, leading/trailing space).
std::string csv_field(const std::string& s) {
  const bool plain = s.find_first_of(",\"\n\r") == std::string::npos &&
                     (s.empty() || (s.front() != ' ' && s.back() != ' '));
  if (plain) return s;
  std::string q = "\"";
  for (char c : s) q += (c == '"') ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string_view trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

/// Splits one line into fields; a field may be double-quoted ("" is a literal quote).
/// Returns false for an unterminated quote.
bool split_fields(std::string_view line, std::vector<std::string>& out) {
  out.clear();
  size_t i = 0;
  while (true) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    std::string field;
    if (i < line.size() && line[i] == '"') {
      ++i;
      bool closed = false;
      while (i < line.size()) {
        if (line[i] == '"') {
          if (i + 1 < line.size() && line[i + 1] == '"') {
            field += '"';
            i += 2;
            continue;
          }
          ++i;
          closed = true;
          break;
        }
        field += line[i++];
      }
      if (!closed) return false;
      const auto comma = line.find(',', i);
      // Anything other than spaces between the closing quote and the comma is kept as text,
      // so it fails number parsing with a clear message rather than vanishing.
      field += std::string(trim(line.substr(i, comma == std::string_view::npos ? std::string_view::npos : comma - i)));
      out.push_back(std::move(field));
      if (comma == std::string_view::npos) return true;
      i = comma + 1;
    } else {
      const auto comma = line.find(',', i);
      const auto f = line.substr(i, comma == std::string_view::npos ? std::string_view::npos : comma - i);
      out.emplace_back(trim(f));
      if (comma == std::string_view::npos) return true;
      i = comma + 1;
    }
  }
}

}  // namespace

// ---------------------------------------------------------------- CsvWriter

CsvWriter::CsvWriter(const std::filesystem::path& path, std::vector<std::string> columns,
                     size_t flush_every, int precision)
    : path_(path), columns_(std::move(columns)), flush_every_(flush_every == 0 ? 1 : flush_every),
      precision_(precision) {
  if (columns_.empty()) throw std::invalid_argument("CsvWriter: no columns for " + path_.string());
  file_.reset(std::fopen(path_.c_str(), "w"));
  if (!file_) throw io_error("cannot open CSV file", path_, errno);
  std::string header;
  for (size_t c = 0; c < columns_.size(); ++c) header += (c ? "," : "") + csv_field(columns_[c]);
  header += '\n';
  if (std::fputs(header.c_str(), file_.get()) < 0) throw io_error("cannot write", path_, errno);
  flush();  // the header is on disk even if no row ever follows
}

CsvWriter::~CsvWriter() = default;  // fclose flushes; errors cannot be reported from here
CsvWriter::CsvWriter(CsvWriter&&) noexcept = default;
CsvWriter& CsvWriter::operator=(CsvWriter&&) noexcept = default;

void CsvWriter::row(std::span<const double> values) {
  if (values.size() != columns_.size())
    throw std::invalid_argument(fmt::format("CsvWriter '{}': row of {} values, {} columns", path_.string(),
                                            values.size(), columns_.size()));
  line_.clear();
  for (size_t c = 0; c < values.size(); ++c) {
    if (c) line_ += ',';
    fmt::format_to(std::back_inserter(line_), "{:.{}g}", values[c], precision_);
  }
  line_ += '\n';
  if (std::fwrite(line_.data(), 1, line_.size(), file_.get()) != line_.size())
    throw io_error("cannot write", path_, errno);
  ++rows_;
  if (++since_flush_ >= flush_every_) flush();
}

void CsvWriter::flush() {
  since_flush_ = 0;
  if (std::fflush(file_.get()) != 0) throw io_error("cannot write", path_, errno);
}

void CsvWriter::sync() {
  flush();
  if (::fsync(::fileno(file_.get())) != 0) throw io_error("cannot sync", path_, errno);
}

// ---------------------------------------------------------------- CsvTable

CsvTable CsvTable::read(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string(), 0, "", std::string("cannot open: ") + std::strerror(errno));
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path.string(), 0, "", "read error");
  return parse(ss.str(), path.string());
}

CsvTable CsvTable::parse(std::string_view text, const std::string& source) {
  CsvTable t;
  t.source_ = source;
  std::vector<std::string> fields;
  bool have_header = false;
  int line_no = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    auto nl = text.find('\n', pos);
    if (nl == std::string_view::npos) nl = text.size();
    const std::string_view line = trim(text.substr(pos, nl - pos));
    pos = nl + 1;
    ++line_no;
    if (line.empty() || line.front() == '#') continue;
    if (!split_fields(line, fields)) throw InputError(source, line_no, "", "unterminated quoted field");

    if (!have_header) {
      for (size_t c = 0; c < fields.size(); ++c) {
        if (fields[c].empty())
          throw InputError(source, line_no, "", fmt::format("header field {} is empty", c + 1));
        for (size_t k = 0; k < c; ++k)
          if (fields[k] == fields[c]) throw InputError(source, line_no, fields[c], "column name given twice");
      }
      t.names_ = fields;
      t.cols_.assign(fields.size(), {});
      have_header = true;
      continue;
    }

    if (fields.size() != t.names_.size())
      throw InputError(source, line_no, "",
                       fmt::format("expected {} fields (as in the header), found {}", t.names_.size(), fields.size()));
    for (size_t c = 0; c < fields.size(); ++c) {
      const std::string& f = fields[c];
      double v = 0;
      // from_chars rejects a leading '+', which people do write; skip it (only it: "+-1" is
      // not a number).
      const char* b = f.data();
      const char* e = f.data() + f.size();
      if (e - b > 1 && *b == '+' && b[1] != '+' && b[1] != '-') ++b;
      const auto [ptr, ec] = std::from_chars(b, e, v);
      if (f.empty() || ec == std::errc::invalid_argument || ptr != e)
        throw InputError(source, line_no, t.names_[c],
                         fmt::format("'{}' is not a number (column {})", f, c + 1));
      if (ec == std::errc::result_out_of_range)
        throw InputError(source, line_no, t.names_[c], fmt::format("'{}' is out of range (column {})", f, c + 1));
      t.cols_[c].push_back(v);
    }
    t.row_lines_.push_back(line_no);
  }
  if (!have_header) throw InputError(source, 0, "", "empty file: expected a header row of column names");
  return t;
}

std::optional<size_t> CsvTable::index_of(std::string_view name) const {
  for (size_t c = 0; c < names_.size(); ++c)
    if (names_[c] == name) return c;
  return std::nullopt;
}

const std::vector<double>& CsvTable::column(std::string_view name) const {
  if (auto i = index_of(name)) return cols_[*i];
  std::string list;
  for (const auto& n : names_) list += (list.empty() ? "" : ", ") + n;
  throw InputError(source_, 0, std::string(name), "no such column (columns: " + list + ")");
}

}  // namespace cohdem
