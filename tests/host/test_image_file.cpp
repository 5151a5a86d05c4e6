// Issue (hostile input): `omniloc calibrate` on a 388 KB PNG of 20000 x 20000 px took 10 s and
// 5.5 GB before std::bad_alloc, `locate` decoded 1.2 GB before checking the size, a 50000 x 50000
// header ended in OpenCV's own assertion naming no file. read_image_file (image_file.hpp) takes
// the size from the header and refuses, naming the file and the size, before decoding anything.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "omniloc/image_file.hpp"

namespace omniloc {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir() {
  const auto* info = testing::UnitTest::GetInstance()->current_test_info();
  const fs::path d = fs::temp_directory_path() /
                     ("omniloc_image_" + std::to_string(::getpid()) + "_" + info->name());
  fs::create_directories(d);
  return d;
}

fs::path write_bytes(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary) << bytes;
  return p;
}

void put_be32(std::string& s, std::uint32_t v) {
  for (int i = 3; i >= 0; --i) s.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}

// A PNG whose IHDR says w x h (8-bit RGB), a tiny IDAT (not a valid stream: nothing may decode it)
// and IEND. CRCs are not checked before the size is.
std::string png_claiming(std::uint32_t w, std::uint32_t h) {
  std::string s = "\x89PNG\r\n\x1a\n";
  put_be32(s, 13);
  s += "IHDR";
  put_be32(s, w);
  put_be32(s, h);
  s += std::string("\x08\x02\x00\x00\x00", 5);
  put_be32(s, 0);  // CRC (unchecked here)
  put_be32(s, 4);
  s += "IDAT";
  s += std::string("\x78\x9c\x03\x00", 4);
  put_be32(s, 0);
  put_be32(s, 0);
  s += "IEND";
  s += "\xae\x42\x60\x82";
  return s;
}

// A JPEG: SOI, an APP0 (JFIF), SOF0 saying w x h, EOI.
std::string jpeg_claiming(std::uint16_t w, std::uint16_t h) {
  std::string s("\xff\xd8", 2);
  s += std::string("\xff\xe0\x00\x10JFIF\x00\x01\x01\x00\x00\x01\x00\x01\x00\x00", 18);
  s += std::string("\xff\xc0\x00\x11\x08", 5);
  s.push_back(static_cast<char>(h >> 8));
  s.push_back(static_cast<char>(h & 0xFF));
  s.push_back(static_cast<char>(w >> 8));
  s.push_back(static_cast<char>(w & 0xFF));
  s += std::string("\x03\x01\x22\x00\x02\x11\x01\x03\x11\x01", 10);
  s += std::string("\xff\xd9", 2);
  return s;
}

std::string encoded(const cv::Mat& img, const char* ext) {
  std::vector<std::uint8_t> buf;
  EXPECT_TRUE(cv::imencode(ext, img, buf));
  return {buf.begin(), buf.end()};
}

cv::Mat test_picture(int w, int h) {
  cv::Mat img(h, w, CV_8UC3);
  cv::randu(img, cv::Scalar::all(0), cv::Scalar::all(255));
  return img;
}

/// The message read_image_file throws for `path` (and that it threw within `max_ms`).
std::string refusal(const fs::path& path, double max_ms = 200.0) {
  const auto t0 = std::chrono::steady_clock::now();
  std::string what = "(no error)";
  try {
    (void)read_image_file(path);
  } catch (const ImageFileError& e) {
    what = e.what();
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(ms, max_ms) << path << " took " << ms << " ms: decoded?";
  EXPECT_EQ(what.rfind(path.string() + ": ", 0), 0u)
      << "the message must start with the file: " << what;
  return what;
}

TEST(ImageFile, HugeHeadersAreRefusedBeforeDecodingNamingTheFileAndSize) {
  const fs::path d = temp_dir();
  const fs::path png = write_bytes(d / "huge.png", png_claiming(20000, 20000));
  const fs::path jpg = write_bytes(d / "huge.jpg", jpeg_claiming(50000, 50000));
  const fs::path wide = write_bytes(d / "wide.png", png_claiming(4097, 10));
  const fs::path png2g = write_bytes(d / "4g.png", png_claiming(0x7fffffffu, 0x7fffffffu));
  const std::vector<std::pair<fs::path, std::string>> cases = {
      {png,
       "PNG image of 20000 x 20000 px, more than the 4096 x 4096 px an image may have (not "
       "decoded)"},
      {jpg, "JPEG image of 50000 x 50000 px, more than the 4096 x 4096 px"},
      {wide, "PNG image of 4097 x 10 px"},
      {png2g, "PNG image of 2147483647 x 2147483647 px"},
  };
  for (const auto& [path, why] : cases) {
    const std::string e = refusal(path);
    EXPECT_NE(e.find(why), std::string::npos) << "want '" << why << "' in: " << e;
    std::printf("%s\n", e.c_str());
  }
  const ImageHeader h = read_image_header(jpeg_claiming(50000, 40000), jpg);
  EXPECT_EQ(h.format, "JPEG");
  EXPECT_EQ(h.width_px, 50000);
  EXPECT_EQ(h.height_px, 40000);
  fs::remove_all(d);
}

TEST(ImageFile, TruncatedMalformedAndUnsupportedFilesAreNamed) {
  const fs::path d = temp_dir();
  const cv::Mat img = test_picture(64, 48);
  const std::string png = encoded(img, ".png"), jpg = encoded(img, ".jpg");
  struct Case {
    std::string name, bytes, why;
  };
  const std::vector<Case> cases = {
      {"half.png", png.substr(0, png.size() / 2), "truncated PNG: the file ends before its IEND"},
      {"head.png", png.substr(0, 20), "truncated or malformed PNG: no IHDR chunk"},
      {"half.jpg", jpg.substr(0, jpg.size() / 2),
       "truncated JPEG: the file ends before its end-of-image marker"},
      {"head.jpg", jpg.substr(0, 3), "truncated or malformed JPEG: no frame header"},
      {"zero.png", png_claiming(0, 10), "malformed PNG: its header gives a size of 0 x 10 px"},
      {"anim.gif", "GIF89a\x01\x00\x01\x00", "unsupported image format"},
      {"text.png", "not an image", "unsupported image format"},
      {"empty.png", "", "empty file"},
  };
  for (const Case& c : cases) {
    const std::string e = refusal(write_bytes(d / c.name, c.bytes));
    EXPECT_NE(e.find(c.why), std::string::npos) << c.name << ": want '" << c.why << "' in: " << e;
  }
  EXPECT_NE(refusal(d / "missing.png").find("no such file"), std::string::npos);
  EXPECT_NE(refusal(d).find("is a directory"), std::string::npos);
  // A header that passes but data that do not decode: the file is still named.
  std::string broken = png;
  for (std::size_t i = 60; i < broken.size() - 20; ++i) broken[i] = '\x55';
  const std::string e = refusal(write_bytes(d / "broken.png", broken), 2000.0);
  EXPECT_NE(e.find("cannot decode the PNG image (64 x 48 px)"), std::string::npos) << e;
  fs::remove_all(d);
}

TEST(ImageFile, ReadsWhatImreadReadsWithinTheLimits) {
  const fs::path d = temp_dir();
  const cv::Mat img = test_picture(640, 480);
  for (const char* ext : {".png", ".jpg", ".bmp"}) {
    const fs::path p = write_bytes(d / (std::string("frame") + ext), encoded(img, ext));
    const cv::Mat got = read_image_file(p);
    const cv::Mat want = cv::imread(p.string(), cv::IMREAD_COLOR);
    ASSERT_EQ(got.size(), want.size()) << ext;
    EXPECT_EQ(cv::norm(got, want, cv::NORM_INF), 0.0) << ext;
  }
  // The limit is inclusive and its own: a 4096-wide strip passes, a smaller limit refuses it.
  const fs::path strip = write_bytes(d / "strip.png", encoded(test_picture(4096, 2), ".png"));
  EXPECT_EQ(read_image_file(strip).cols, 4096);
  ImageLimits small;
  small.max_width_px = 640;
  try {
    (void)read_image_file(strip, small);
    ADD_FAILURE() << "accepted";
  } catch (const ImageFileError& e) {
    EXPECT_NE(std::string(e.what()).find("PNG image of 4096 x 2 px, more than the 640 x 4096 px"),
              std::string::npos)
        << e.what();
  }
  fs::remove_all(d);
}

}  // namespace
}  // namespace omniloc
