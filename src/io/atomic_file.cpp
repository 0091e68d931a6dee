#include "io/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <streambuf>
#include <string>
#include <vector>

namespace cohdem {

namespace {

std::runtime_error io_error(const std::string& what, const std::filesystem::path& p, int err) {
  return std::runtime_error(what + " '" + p.string() + "': " + std::strerror(err));
}

}  // namespace

/// A streambuf over a POSIX file descriptor. Used instead of std::ofstream so that a failed
/// write keeps its exact errno for the error message (ofstream only reports "failbit").
class AtomicWriter::FdBuf : public std::streambuf {
 public:
  explicit FdBuf(int fd) : fd_(fd), buf_(1 << 16) { setp(buf_.data(), buf_.data() + buf_.size()); }
  ~FdBuf() override { close_fd(); }

  int error() const { return err_; }

  /// Flushes (and with `durable`, fsyncs) and closes; returns 0 or the first errno seen.
  int finish(bool durable) {
    flush_buffer();
    if (durable && err_ == 0 && fd_ >= 0 && ::fsync(fd_) != 0) err_ = errno;
    if (fd_ >= 0 && ::close(fd_) != 0 && err_ == 0) err_ = errno;
    fd_ = -1;
    return err_;
  }
  void close_fd() noexcept {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 protected:
  int_type overflow(int_type ch) override {
    if (!flush_buffer()) return traits_type::eof();
    if (!traits_type::eq_int_type(ch, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(ch);
      pbump(1);
    }
    return traits_type::not_eof(ch);
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    // Large blocks (VTU payloads) bypass the buffer.
    if (n >= static_cast<std::streamsize>(buf_.size())) {
      if (!flush_buffer() || !write_all(s, static_cast<size_t>(n))) return 0;
      return n;
    }
    return std::streambuf::xsputn(s, n);
  }
  int sync() override { return flush_buffer() ? 0 : -1; }

 private:
  bool flush_buffer() {
    const size_t n = static_cast<size_t>(pptr() - pbase());
    const bool ok = write_all(pbase(), n);
    setp(buf_.data(), buf_.data() + buf_.size());
    return ok;
  }
  bool write_all(const char* s, size_t n) {
    if (err_ != 0) return false;
    while (n > 0) {
      const ssize_t w = ::write(fd_, s, n);
      if (w < 0) {
        if (errno == EINTR) continue;
        err_ = errno;
        return false;
      }
      s += w;
      n -= static_cast<size_t>(w);
    }
    return true;
  }

  int fd_;
  std::vector<char> buf_;
  int err_ = 0;
};

/// fsync of the directory holding `p`, so that a rename into it is on disk.
int sync_directory(const std::filesystem::path& p) {
  std::filesystem::path dir = p.parent_path();
  if (dir.empty()) dir = ".";
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return errno;
  const int err = ::fsync(fd) != 0 ? errno : 0;
  ::close(fd);
  return err;
}

AtomicWriter::AtomicWriter(std::filesystem::path path, Sync sync) : path_(std::move(path)), sync_(sync) {
  // Same directory as the target so that rename() never crosses a file system.
  tmp_ = path_;
  tmp_ += ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw io_error("cannot create temporary file for", path_, errno);
  buf_ = std::make_unique<FdBuf>(fd);
  os_ = std::make_unique<std::ostream>(buf_.get());
}

AtomicWriter::~AtomicWriter() {
  if (!committed_) discard();
}

void AtomicWriter::discard() noexcept {
  if (buf_) buf_->close_fd();
  std::error_code ec;
  std::filesystem::remove(tmp_, ec);
}

void AtomicWriter::commit() {
  if (committed_) throw std::logic_error("AtomicWriter::commit called twice for " + path_.string());
  os_->flush();
  if (const int err = buf_->finish(sync_ == Sync::durable); err != 0) {
    discard();
    throw io_error("cannot write", path_, err);
  }
  if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
    const int err = errno;
    discard();
    throw io_error("cannot rename temporary file onto", path_, err);
  }
  committed_ = true;
  // The new file is in place (the old one is gone): a failure here only means the rename may
  // not survive a power cut, which the caller is told about.
  if (sync_ == Sync::durable)
    if (const int err = sync_directory(path_); err != 0) throw io_error("cannot sync the directory of", path_, err);
}

void write_file_atomic(const std::filesystem::path& path, std::string_view bytes, Sync sync) {
  AtomicWriter w(path, sync);
  w.write(bytes);
  w.commit();
}

}  // namespace cohdem
