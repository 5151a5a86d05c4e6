// Harness: the recording CSV readers (recording.hpp read_encoders_csv, read_camera_csv,
// read_truth_csv, read_poses_csv) on any file content. Input: byte 0 picks the reader, the rest is
// the file. RecordingError naming the file is the only expected error; what a reader returns must
// hold what the REC_DIR contract says: times finite and strictly increasing (encoders, camera,
// truth), poses and gyro finite, camera files non-empty, the row count no more than the lines.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "fuzz_common.hpp"
#include "omniloc/recording.hpp"

namespace {

using omniloc::fuzz::fuzz_check;

template <class Rows, class Time>
void check_times(const Rows& rows, Time t_of) {
  for (std::size_t i = 0; i < rows.size(); ++i) {
    fuzz_check(std::isfinite(t_of(rows[i])), "a row with a non-finite time was accepted");
    if (i > 0)
      fuzz_check(t_of(rows[i]) > t_of(rows[i - 1]), "times that do not increase were accepted");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const omniloc::fuzz::ScratchFile file("recording.csv");
  const std::string_view content(reinterpret_cast<const char*>(data + 1), size - 1);
  const auto& path = file.write(content);
  std::size_t lines = 0;
  for (const char ch : content) lines += ch == '\n';
  try {
    switch (data[0] % 4) {
      case 0: {
        const auto rows = omniloc::read_encoders_csv(path);
        fuzz_check(rows.size() <= lines, "more rows than lines");
        check_times(rows, [](const auto& w) { return w.t_end_ms; });
        for (const auto& w : rows)
          fuzz_check(std::isfinite(w.gyro_yaw_deg), "a non-finite gyro yaw was accepted");
        break;
      }
      case 1: {
        const auto rows = omniloc::read_camera_csv(path);
        fuzz_check(rows.size() <= lines, "more rows than lines");
        check_times(rows, [](const auto& r) { return r.t_ms; });
        for (const auto& r : rows) {
          fuzz_check(!r.file.empty(), "an empty frame file name was accepted");
          fuzz_check(
              r.file.find(',') == std::string::npos && r.file.find('\n') == std::string::npos,
              "a frame file name holds a separator");
        }
        break;
      }
      case 2: {
        const auto rows = omniloc::read_truth_csv(path);
        fuzz_check(rows.size() <= lines, "more rows than lines");
        check_times(rows, [](const auto& s) { return s.t_ms; });
        for (const auto& s : rows)
          fuzz_check(std::isfinite(s.pose.x_cm) && std::isfinite(s.pose.y_cm) &&
                         std::isfinite(s.pose.yaw_deg),
                     "a non-finite truth pose was accepted");
        break;
      }
      default: {
        const auto rows = omniloc::read_poses_csv(path);
        fuzz_check(rows.size() <= lines, "more rows than lines");
        break;
      }
    }
  } catch (const omniloc::RecordingError& e) {
    fuzz_check(std::string_view(e.what()).starts_with(path.string()),
               "a RecordingError that does not start with the file");
  }
  return 0;
}
