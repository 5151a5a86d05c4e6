// Image files: the size from the header before any decoding (image_file.hpp).
#include "omniloc/image_file.hpp"

#include <cstring>
#include <optional>

#include <opencv2/imgcodecs.hpp>

namespace omniloc {

namespace fs = std::filesystem;

namespace {

[[noreturn]] void refuse(const fs::path& path, const std::string& why) {
  throw ImageFileError(path.string() + ": " + why);
}

std::uint32_t be16(std::string_view b, std::size_t at) {
  return (static_cast<std::uint32_t>(static_cast<unsigned char>(b[at])) << 8) |
         static_cast<unsigned char>(b[at + 1]);
}

std::uint32_t be32(std::string_view b, std::size_t at) {
  return (be16(b, at) << 16) | be16(b, at + 2);
}

std::int64_t le32s(std::string_view b, std::size_t at) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(b[at + i]);
  return static_cast<std::int32_t>(v);
}

std::string size_text(std::int64_t w, std::int64_t h) {
  return std::to_string(w) + " x " + std::to_string(h) + " px";
}

// PNG: the 8-byte signature, then the IHDR chunk (length 13, "IHDR", width, height: big-endian);
// the file ends with the IEND chunk.
ImageHeader png_header(std::string_view b, const fs::path& path) {
  if (b.size() < 33 || b.substr(12, 4) != "IHDR")
    refuse(path, "truncated or malformed PNG: no IHDR chunk in its first 33 bytes (the file has " +
                     std::to_string(b.size()) + " bytes)");
  const std::uint32_t w = be32(b, 16), h = be32(b, 20);
  if (w == 0 || h == 0 || w > 0x7fffffffu || h > 0x7fffffffu)
    refuse(path, "malformed PNG: its header gives a size of " + std::to_string(w) + " x " +
                     std::to_string(h) + " px");
  return {"PNG", static_cast<int>(w), static_cast<int>(h)};
}

bool png_complete(std::string_view b) {
  return b.size() >= 12 && b.substr(b.size() - 8, 4) == "IEND";
}

// JPEG: markers FF xx from SOI (FF D8); the first SOFn segment (C0-CF but C4 DHT, C8 JPG, CC DAC)
// holds precision, height, width (big-endian). Standalone markers (01, D0-D7) have no length.
std::optional<ImageHeader> jpeg_frame(std::string_view b) {
  std::size_t i = 2;
  while (i + 4 <= b.size()) {
    if (static_cast<unsigned char>(b[i]) != 0xFF) return std::nullopt;
    const auto m = static_cast<unsigned char>(b[i + 1]);
    if (m == 0xFF) {  // fill byte
      ++i;
      continue;
    }
    if (m == 0x01 || (m >= 0xD0 && m <= 0xD7)) {
      i += 2;
      continue;
    }
    if (m == 0xDA || m == 0xD9) return std::nullopt;  // scan data or the end before any frame
    const std::uint32_t len = be16(b, i + 2);
    const bool sof = m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC;
    if (sof) {
      if (len < 7 || i + 9 > b.size()) return std::nullopt;
      return ImageHeader{"JPEG", static_cast<int>(be16(b, i + 7)),
                         static_cast<int>(be16(b, i + 5))};
    }
    if (len < 2) return std::nullopt;
    i += 2 + len;
  }
  return std::nullopt;
}

ImageHeader jpeg_header(std::string_view b, const fs::path& path) {
  const std::optional<ImageHeader> h = jpeg_frame(b);
  if (!h)
    refuse(path,
           "truncated or malformed JPEG: no frame header (SOFn) before its image data (the "
           "file has " +
               std::to_string(b.size()) + " bytes)");
  if (h->width_px == 0 || h->height_px == 0)
    refuse(path, "malformed JPEG: its frame header gives a size of " +
                     size_text(h->width_px, h->height_px));
  return *h;
}

// JPEG ends with EOI (FF D9); some writers append padding, so it is looked for near the end.
bool jpeg_complete(std::string_view b) {
  const std::size_t from = b.size() > 1024 ? b.size() - 1024 : 2;
  for (std::size_t i = b.size(); i >= from + 2; --i)
    if (static_cast<unsigned char>(b[i - 2]) == 0xFF &&
        static_cast<unsigned char>(b[i - 1]) == 0xD9)
      return true;
  return false;
}

// BMP: "BM", the info header's width and height (signed little-endian; a negative height is a
// top-down image).
ImageHeader bmp_header(std::string_view b, const fs::path& path) {
  if (b.size() < 26)
    refuse(path, "truncated BMP: " + std::to_string(b.size()) + " bytes, less than its header");
  const std::int64_t w = le32s(b, 18), h = le32s(b, 22);
  const std::int64_t ah = h < 0 ? -h : h;
  if (w <= 0 || ah == 0)
    refuse(path, "malformed BMP: its header gives a size of " + size_text(w, h));
  return {"BMP", static_cast<int>(w), static_cast<int>(ah)};
}

}  // namespace

ImageHeader read_image_header(std::string_view b, const fs::path& path) {
  static constexpr unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (b.size() >= 8 && std::memcmp(b.data(), kPng, 8) == 0) {
    const ImageHeader h = png_header(b, path);
    if (!png_complete(b)) refuse(path, "truncated PNG: the file ends before its IEND chunk");
    return h;
  }
  if (b.size() >= 3 && static_cast<unsigned char>(b[0]) == 0xFF &&
      static_cast<unsigned char>(b[1]) == 0xD8 && static_cast<unsigned char>(b[2]) == 0xFF) {
    const ImageHeader h = jpeg_header(b, path);
    if (!jpeg_complete(b))
      refuse(path, "truncated JPEG: the file ends before its end-of-image marker");
    return h;
  }
  if (b.size() >= 2 && b[0] == 'B' && b[1] == 'M') return bmp_header(b, path);
  if (b.empty()) refuse(path, "empty file, not an image");
  refuse(path, "unsupported image format (omniloc reads PNG, JPEG and BMP files)");
}

cv::Mat read_image_file(const fs::path& path, const ImageLimits& limits) {
  std::string bytes;
  try {
    bytes = read_file_bounded(path, limits.max_file_bytes, "image file");
  } catch (const ImageFileError&) {
    throw;
  } catch (const FileReadError& e) {
    throw ImageFileError(e.what());
  }
  const ImageHeader h = read_image_header(bytes, path);
  if (h.width_px > limits.max_width_px || h.height_px > limits.max_height_px)
    refuse(path, h.format + " image of " + size_text(h.width_px, h.height_px) + ", more than the " +
                     size_text(limits.max_width_px, limits.max_height_px) +
                     " an image may have (not decoded)");
  const cv::Mat encoded(1, static_cast<int>(bytes.size()), CV_8U, bytes.data());  // no copy
  cv::Mat img;
  try {
    img = cv::imdecode(encoded, cv::IMREAD_COLOR);
  } catch (const cv::Exception& e) {
    refuse(path, "cannot decode the " + h.format + " image (" + size_text(h.width_px, h.height_px) +
                     "): " + e.what());
  }
  if (img.empty())
    refuse(path,
           "cannot decode the " + h.format + " image (" + size_text(h.width_px, h.height_px) + ")");
  return img;
}

}  // namespace omniloc
