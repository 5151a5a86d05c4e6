// Bounded image reads: every image file omniloc reads (a recording's frames, `omniloc locate`'s
// and `omniloc calibrate`'s images) goes through read_image_file, which reads the file with
// read_file_bounded (file_read.hpp), takes the width and height from the format's own header
// (PNG IHDR, JPEG SOFn, BMP info header) and refuses an image above the limits, or a truncated or
// unsupported file, naming the file, before anything is decoded. OpenCV 4.6 (Debian 12) has no
// header-only API: cv::imread on a 388 KB PNG whose IHDR says 20000 x 20000 px allocated 5.5 GB
// before failing, and a 50000 x 50000 header ended in OpenCV's own assertion naming no file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include <opencv2/core.hpp>

#include "omniloc/detail/file_read.hpp"

namespace omniloc {

/// An image file that cannot be read as asked; what() starts with the path.
class ImageFileError : public FileReadError {
 public:
  using FileReadError::FileReadError;
};

/// What the project needs, with room: its cameras are 640 x 480 (common/cameras) and the real
/// frames of the tests up to 1280 x 960; an omni camera of 4096 x 4096 px (16.8 Mpx, 50 MB as
/// 8-bit BGR) is beyond any the localizer would run at frame rate, and far below the memory of
/// the robot's computer. A raw BMP of that size is 50 MB, hence the file cap.
struct ImageLimits {
  int max_width_px = 4096;
  int max_height_px = 4096;
  std::uintmax_t max_file_bytes = 64u << 20;
};

/// The size an image file's header announces.
struct ImageHeader {
  std::string format;  ///< "PNG", "JPEG" or "BMP"
  int width_px = 0;
  int height_px = 0;
};

/// Parses the header of an image held in `bytes` (the whole file, or at least its header); throws
/// ImageFileError "<path>: <why>" for an unsupported format, a truncated or malformed header, a
/// size of zero, or a PNG/JPEG missing its end (IEND chunk, EOI marker). Nothing is decoded.
[[nodiscard]] ImageHeader read_image_header(std::string_view bytes,
                                            const std::filesystem::path& path);

/// The image as 8-bit BGR (cv::IMREAD_COLOR). Throws ImageFileError naming the file: not a
/// regular file or too large (file_read.hpp), unsupported format, truncated, above `limits` ("is
/// 20000 x 20000 px, more than the 4096 x 4096 px an image may have"), or not decodable.
[[nodiscard]] cv::Mat read_image_file(const std::filesystem::path& path,
                                      const ImageLimits& limits = {});

}  // namespace omniloc
