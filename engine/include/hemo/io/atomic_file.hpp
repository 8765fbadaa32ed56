#pragma once
// Output files that are either whole or absent: written under a temporary name in their own
// directory, flushed to the disk (fsync) and renamed over the real name only once complete.
// A crash, a full disk or a failed write never leaves a partial file under the real name
// (rename within one file system replaces the name in one step, POSIX rename(2)).
#include <cstdio>
#include <filesystem>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <streambuf>
#include <string>

namespace hemo::io {

// An output that could not be written: names the file and the reason the system gave (for
// a full disk "No space left on device"). hemo-run exits with code 4 on it.
class WriteError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class AtomicFile {
 public:
  // Opens `path`'s temporary (`<name>.part-<pid>` beside it). Throws WriteError if it cannot.
  explicit AtomicFile(std::filesystem::path path);
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  // Without commit() (an error, an exception on the way) the temporary is removed and the
  // real name is left as it was.
  ~AtomicFile();

  // The file as a C stream (libpng) or a C++ stream; write through one of them only.
  std::FILE* file() { return file_; }
  std::ostream& stream() { return stream_; }

  // Flushes, syncs and closes the temporary and renames it to the real name. Throws WriteError
  // naming the file if any write failed, or the flush, sync or rename does.
  void commit();

  const std::filesystem::path& path() const { return path_; }

 private:
  class Buffer : public std::streambuf {
   public:
    explicit Buffer(std::FILE* file) : file_(file) {}
    int error() const { return error_; }  // errno of the first failed write, 0 if none
   protected:
    int_type overflow(int_type c) override;
    std::streamsize xsputn(const char* s, std::streamsize n) override;
   private:
    std::FILE* file_;
    int error_ = 0;
  };
  [[noreturn]] void fail(const std::string& what, int error);

  std::filesystem::path path_;
  std::filesystem::path temporary_;
  std::FILE* file_ = nullptr;
  Buffer buffer_;
  std::ostream stream_;
  bool committed_ = false;
};

}  // namespace hemo::io
