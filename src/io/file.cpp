// Whole-file reads and atomic writes (io/file.h), on POSIX calls so that every failure carries the
// operating system's reason.
//
// AtomicFile (and write_file_atomic, which is one) writes a temporary file next to the target (same
// directory, hence same file system, so rename() is atomic), fsyncs it, renames it over the target
// and fsyncs the directory.
// On any failure the temporary file is removed and the target is left as it was.
#include "subvec/io/file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <utility>

#include "subvec/core/error.h"

namespace subvec {
namespace {

std::string os_error(const std::filesystem::path& path, const char* action, int err) {
  return path.string() + ": cannot " + action + ": " + std::strerror(err);
}

// Closes a descriptor on scope exit unless released.
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }
  int release() { return std::exchange(fd_, -1); }

 private:
  int fd_;
};

}  // namespace

std::vector<uint8_t> read_file(const std::filesystem::path& path, int64_t max_bytes) {
  int raw = -1;
  do {
    raw = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  } while (raw < 0 && errno == EINTR);
  // A missing file reads the same from every reader: "PATH: no such file".
  if (raw < 0 && errno == ENOENT) throw Error(ErrorCode::kIo, path.string() + ": no such file");
  if (raw < 0) throw Error(ErrorCode::kIo, os_error(path, "open", errno));
  Fd fd(raw);
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0) throw Error(ErrorCode::kIo, os_error(path, "stat", errno));
  if (S_ISDIR(st.st_mode)) throw Error(ErrorCode::kIo, path.string() + ": is a directory");
  if (S_ISREG(st.st_mode) && st.st_size > max_bytes) {
    throw Error(ErrorCode::kLimit, path.string() + ": file is " + std::to_string(st.st_size) +
                                       " bytes, over the limit of " + std::to_string(max_bytes));
  }

  // Regular files: one allocation of the stat size. Pipes and devices: grow as data arrives.
  std::vector<uint8_t> bytes(S_ISREG(st.st_mode) ? size_t(st.st_size)
                                                 : size_t(std::min<int64_t>(max_bytes, 1 << 16)));
  size_t used = 0;
  for (;;) {
    if (used == bytes.size()) {
      if (static_cast<int64_t>(used) >= max_bytes) {
        // At the limit: one more byte means the file is too large.
        uint8_t probe;
        const ssize_t n = ::read(fd.get(), &probe, 1);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) throw Error(ErrorCode::kIo, os_error(path, "read", errno));
        if (n == 0) break;
        throw Error(ErrorCode::kLimit, path.string() + ": file is over the limit of " +
                                           std::to_string(max_bytes) + " bytes");
      }
      bytes.resize(std::min<size_t>(std::max<size_t>(used * 2, 4096), size_t(max_bytes)));
    }
    const ssize_t n = ::read(fd.get(), bytes.data() + used, bytes.size() - used);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw Error(ErrorCode::kIo, os_error(path, "read", errno));
    if (n == 0) break;
    used += size_t(n);
  }
  bytes.resize(used);
  return bytes;
}

struct AtomicFile::Impl {
  std::filesystem::path path, temp;
  int fd = -1;
  bool committed = false;

  [[noreturn]] void fail(const char* action, int err) {
    throw Error(ErrorCode::kIo, os_error(path, action, err));
  }
};

AtomicFile::AtomicFile(const std::filesystem::path& path) : impl_(std::make_unique<Impl>()) {
  static std::atomic<uint64_t> counter{0};
  Impl& m = *impl_;
  m.path = path;
  if (path.filename().empty()) throw Error(ErrorCode::kIo, path.string() + ": not a file name");
  const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : ".";

  // A unique name in the same directory: pid and a process-wide counter; O_EXCL guards the rest.
  for (int attempt = 0; m.fd < 0; ++attempt) {
    std::string name = ".";
    name.append(path.filename().string()).append(".tmp-").append(std::to_string(::getpid()));
    name.append("-").append(std::to_string(counter.fetch_add(1)));
    m.temp = dir / name;
    m.fd = ::open(m.temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (m.fd < 0 && !(errno == EEXIST && attempt < 100) && errno != EINTR) {
      const int err = errno;
      m.temp.clear();
      m.fail("create a temporary file", err);
    }
  }
}

AtomicFile::~AtomicFile() {
  Impl& m = *impl_;
  if (m.fd >= 0) ::close(m.fd);
  if (!m.committed && !m.temp.empty()) ::unlink(m.temp.c_str());
}

const std::filesystem::path& AtomicFile::path() const { return impl_->path; }

void AtomicFile::write(std::span<const uint8_t> bytes) {
  Impl& m = *impl_;
  if (m.fd < 0) throw Error(ErrorCode::kIo, m.path.string() + ": written after commit");
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(m.fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) m.fail("write", errno);
    done += size_t(n);
  }
}

void AtomicFile::commit() {
  Impl& m = *impl_;
  if (m.fd < 0) throw Error(ErrorCode::kIo, m.path.string() + ": committed twice");
  if (::fsync(m.fd) != 0) m.fail("flush", errno);
  if (::close(std::exchange(m.fd, -1)) != 0) m.fail("close", errno);
  if (::rename(m.temp.c_str(), m.path.c_str()) != 0) m.fail("rename the temporary file onto", errno);
  m.committed = true;

  // Make the rename itself durable; a failure here leaves a complete file, so it is not an error.
  const std::filesystem::path dir = m.path.has_parent_path() ? m.path.parent_path() : ".";
  const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
}

void write_file_atomic(const std::filesystem::path& path, std::span<const uint8_t> bytes) {
  AtomicFile file(path);
  file.write(bytes);
  file.commit();
}

}  // namespace subvec
