#include "hemo/render/renderer.hpp"

#include "hemo/io/atomic_file.hpp"

#include <png.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>

namespace hemo::render {

void writePng(const std::filesystem::path& path, std::uint32_t width, std::uint32_t height,
              const std::vector<std::uint8_t>& rgba) {
  if (rgba.size() != std::size_t(width) * height * 4) {
    throw std::invalid_argument("PNG '" + path.string() + "': " + std::to_string(rgba.size()) + " bytes for " +
                                std::to_string(width) + "x" + std::to_string(height) + " RGBA pixels");
  }
  io::AtomicFile file(path);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(&png, &info);
    throw std::runtime_error("libpng could not start writing '" + path.string() + "'");
  }
  // libpng reports errors by longjmp; nothing with a destructor lives between here and the end.
  if (setjmp(png_jmpbuf(png))) {
    const int error = errno;  // (a failed fwrite's, where that is what stopped libpng)
    png_destroy_write_struct(&png, &info);
    throw io::WriteError("failed while writing PNG file '" + path.string() + "'" +
                         (error ? std::string(": ") + std::strerror(error) : std::string()));
  }
  png_init_io(png, file.file());
  png_set_IHDR(png, info, width, height, 8, PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (std::uint32_t y = 0; y < height; ++y) {
    png_write_row(png, const_cast<png_bytep>(rgba.data() + std::size_t(y) * width * 4));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  file.commit();
}

}  // namespace hemo::render
