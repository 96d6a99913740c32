// Whole-file reads and atomic writes.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace subvec {

// Reads a whole file; throws Error(kIo) naming the path, Error(kLimit) past `max_bytes`.
std::vector<uint8_t> read_file(const std::filesystem::path& path, int64_t max_bytes = int64_t{1} << 31);

// Writes to a temporary file in the same directory, flushes, then renames over `path`, so that a
// failure never leaves a partial file and never clobbers an existing one. Throws Error(kIo).
void write_file_atomic(const std::filesystem::path& path, std::span<const uint8_t> bytes);

// The same, in pieces: a temporary file next to `path` that write() appends to and commit()
// flushes and renames over `path`. Destroyed uncommitted (an error, an exception on the way), it
// removes the temporary file and leaves `path` as it was. Throws Error(kIo) naming `path`.
class AtomicFile {
 public:
  explicit AtomicFile(const std::filesystem::path& path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::filesystem::path& path() const;
  void write(std::span<const uint8_t> bytes);
  void commit();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace subvec
