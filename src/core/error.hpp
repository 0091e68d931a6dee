// Errors that a user can act on: each names the file, the line and the key at fault.
#pragma once
#include <stdexcept>
#include <string>

namespace cohdem {

/// Thrown for bad input (case file, command line, CSV path). The CLI prints what() and
/// exits with status 2 before any output is written.
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& file, int line, const std::string& key, const std::string& what)
      : std::runtime_error(format(file, line, key, what)), file_(file), line_(line), key_(key) {}
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& key() const { return key_; }

 private:
  static std::string format(const std::string& file, int line, const std::string& key,
                            const std::string& what) {
    std::string s = file.empty() ? std::string("<input>") : file;
    if (line > 0) {
      s += ':';
      s += std::to_string(line);
    }
    if (!key.empty()) {
      s += ": key '";
      s += key;
      s += '\'';
    }
    s += ": ";
    s += what;
    return s;
  }
  std::string file_;
  int line_;
  std::string key_;
};

/// Thrown when a run cannot continue (particles cannot be inserted, a NaN appears,
/// the time step is past its hard bound). Exit status 3.
class RunError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace cohdem
