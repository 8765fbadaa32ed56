#include "hemo/io/atomic_file.hpp"

#include <cerrno>
#include <cstring>
#include <system_error>

#include <unistd.h>

namespace hemo::io {

namespace {

std::FILE* openTemporary(const std::filesystem::path& temporary, const std::filesystem::path& path) {
  std::FILE* file = std::fopen(temporary.c_str(), "wb");
  if (!file) {
    const int error = errno;
    throw WriteError("cannot write '" + path.string() + "': " + std::strerror(error));
  }
  return file;
}

}  // namespace

AtomicFile::AtomicFile(std::filesystem::path path)
    : path_(std::move(path)),
      temporary_(path_.parent_path() / (path_.filename().string() + ".part-" + std::to_string(::getpid()))),
      file_(openTemporary(temporary_, path_)),
      buffer_(file_),
      stream_(&buffer_) {}

AtomicFile::~AtomicFile() {
  if (committed_) return;
  if (file_) std::fclose(file_);
  std::error_code ignored;
  std::filesystem::remove(temporary_, ignored);
}

AtomicFile::Buffer::int_type AtomicFile::Buffer::overflow(int_type c) {
  if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
  if (std::fputc(traits_type::to_char_type(c), file_) == EOF) {
    if (error_ == 0) error_ = errno ? errno : EIO;
    return traits_type::eof();
  }
  return c;
}

std::streamsize AtomicFile::Buffer::xsputn(const char* s, std::streamsize n) {
  const std::size_t written = std::fwrite(s, 1, static_cast<std::size_t>(n), file_);
  if (written != static_cast<std::size_t>(n) && error_ == 0) error_ = errno ? errno : EIO;
  return static_cast<std::streamsize>(written);
}

void AtomicFile::fail(const std::string& what, int error) {
  std::string reason = std::strerror(error);
  if (error == ENOSPC) reason += " (the disk is full)";
  throw WriteError(what + " '" + path_.string() + "': " + reason);
}

void AtomicFile::commit() {
  if (committed_) return;
  // A failed write sets the stream's badbit or the C stream's error flag; the buffer kept the
  // reason of the first (a C stream writer's is in errno, if nothing has changed it since).
  if (!stream_ || std::ferror(file_)) fail("failed while writing", buffer_.error() ? buffer_.error() : errno ? errno : EIO);
  if (std::fflush(file_) != 0) fail("failed while writing", errno);
  if (::fsync(::fileno(file_)) != 0) fail("failed while syncing", errno);
  const int closed = std::fclose(file_);
  file_ = nullptr;
  if (closed != 0) fail("failed while closing", errno);
  if (std::rename(temporary_.c_str(), path_.c_str()) != 0) fail("cannot rename the finished file to", errno);
  committed_ = true;
}

}  // namespace hemo::io
