// Whole-file atomic writes: readers (ParaView, a plotting script, a restart) see either the
// old file or the complete new one, never a half-written file, even if the run is killed.
#pragma once
#include <filesystem>
#include <memory>
#include <ostream>
#include <string_view>

namespace cohdem {

/// How far a committed file must have reached when commit() returns.
///  - Sync::none: the rename is done; a killed process cannot leave a half-written file, but
///    after a power cut or kernel crash the file system may still hold the old file or (on
///    some file systems) an empty new one. Enough for frames, series and summaries, which a
///    rerun rewrites.
///  - Sync::durable: the data are fsync'ed before the rename and the directory after it, so
///    once commit() returns the new file survives a power cut. For checkpoints: a resume must
///    find either the previous checkpoint or the complete new one.
enum class Sync { none, durable };

/// Writes `bytes` to `path.tmp.<pid>` in the same directory, then renames it over `path`
/// (rename within one file system is atomic on POSIX). Throws std::runtime_error naming the
/// path and the errno text; on failure `path` is left as it was and the temp file is removed.
void write_file_atomic(const std::filesystem::path& path, std::string_view bytes, Sync sync = Sync::none);

/// Streams a file into `path.tmp.<pid>`; `commit()` renames it over the target. If the writer
/// is destroyed without a commit (exception, early return) the temp file is removed and the
/// old file is untouched. Two writers of the same path in one process at once are not
/// supported (they would share the temp name).
class AtomicWriter {
 public:
  /// Opens the temp file. Throws std::runtime_error if it cannot be created.
  explicit AtomicWriter(std::filesystem::path path, Sync sync = Sync::none);
  ~AtomicWriter();
  AtomicWriter(const AtomicWriter&) = delete;
  AtomicWriter& operator=(const AtomicWriter&) = delete;

  /// The stream to write to (binary: no newline translation).
  std::ostream& stream() { return *os_; }
  void write(std::string_view bytes) { os_->write(bytes.data(), static_cast<std::streamsize>(bytes.size())); }
  template <class T>
  AtomicWriter& operator<<(const T& v) {
    *os_ << v;
    return *this;
  }

  /// Flushes, closes and renames over the target. Throws std::runtime_error (naming the path
  /// and errno text) if any write failed; the temp file is then removed. Call once.
  void commit();
  bool committed() const { return committed_; }

  const std::filesystem::path& path() const { return path_; }
  const std::filesystem::path& temp_path() const { return tmp_; }

 private:
  class FdBuf;
  void discard() noexcept;

  std::filesystem::path path_, tmp_;
  std::unique_ptr<FdBuf> buf_;
  std::unique_ptr<std::ostream> os_;
  Sync sync_;
  bool committed_ = false;
};

}  // namespace cohdem
