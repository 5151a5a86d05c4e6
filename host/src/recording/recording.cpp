// Recording directories (issue 7 contract): CSV and meta.json reading and writing.
#include "omniloc/recording.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "omniloc/detail/config_reader.hpp"
#include "omniloc/detail/file_read.hpp"
#include "omniloc/detail/strict_number.hpp"
#include "omniloc/gyro_heading.hpp"
#include "omniloc/image_file.hpp"

namespace omniloc {

namespace fs = std::filesystem;

namespace {

[[noreturn]] void fail_at(const fs::path& file, int line, const std::string& why) {
  throw RecordingError(file.string() + ":" + std::to_string(line) + ": " + why);
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::string cur;
  for (char ch : s) {
    if (ch == ',') {
      out.push_back(cur);
      cur.clear();
    } else {
      cur.push_back(ch);
    }
  }
  out.push_back(cur);
  return out;
}

// Numbers go through the shared strict parser (strict_number.hpp): the whole cell, finite, in
// range; its message is kept after the file and line. poses.csv spells "no value" as nan/inf.
double parse_double(const std::string& s, const fs::path& file, int line,
                    const std::string& column) {
  if (s == "nan") return std::numeric_limits<double>::quiet_NaN();
  if (s == "inf") return std::numeric_limits<double>::infinity();
  try {
    return omniloc::parse_double(s, "column '" + column + "'");
  } catch (const NumberError& e) {
    fail_at(file, line, e.what());
  }
}

long long parse_int(const std::string& s, const fs::path& file, int line, const std::string& column,
                    long long min, long long max) {
  try {
    return omniloc::parse_int(s, "column '" + column + "'", min, max);
  } catch (const NumberError& e) {
    fail_at(file, line, e.what());
  }
}

/// Reads a CSV with exactly the given header; calls row(fields, line) for each data line.
template <typename RowFn>
void read_csv(const fs::path& file, const std::vector<std::string>& header, RowFn row) {
  std::string content;
  try {
    content = read_file_bounded(file, kMaxCsvFileBytes, "CSV file");
  } catch (const FileReadError& e) {
    throw RecordingError(e.what());
  }
  std::istringstream in(content);
  std::string text;
  int line = 0;
  bool seen_header = false;
  while (std::getline(in, text)) {
    ++line;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (!seen_header) {
      std::string want;
      for (std::size_t i = 0; i < header.size(); ++i) want += (i ? "," : "") + header[i];
      if (text != want) fail_at(file, line, "header must be '" + want + "' (got '" + text + "')");
      seen_header = true;
      continue;
    }
    if (text.empty()) continue;
    const auto f = split(text);
    if (f.size() != header.size())
      fail_at(file, line,
              "expected " + std::to_string(header.size()) + " columns, got " +
                  std::to_string(f.size()));
    row(f, line);
  }
  if (!seen_header) fail_at(file, 1, "empty file (no header)");
}

void check_time(double t, double prev, bool have_prev, const fs::path& file, int line) {
  if (!std::isfinite(t)) fail_at(file, line, "column 't_ms': not finite");
  if (have_prev && !(t > prev)) {
    std::ostringstream os;
    os << "column 't_ms': times must increase (" << t << " after " << prev << ")";
    fail_at(file, line, os.str());
  }
}

double finite(double v, const fs::path& file, int line, const std::string& column) {
  if (!std::isfinite(v)) fail_at(file, line, "column '" + column + "': not finite");
  return v;
}

}  // namespace

std::vector<EncoderWindow> read_encoders_csv(const fs::path& path) {
  std::vector<EncoderWindow> out;
  read_csv(
      path, {"t_ms", "seq", "c1", "c2", "c3", "c4", "gyro_yaw_deg"}, [&](const auto& f, int line) {
        EncoderWindow w;
        w.t_end_ms = parse_double(f[0], path, line, "t_ms");
        check_time(w.t_end_ms, out.empty() ? 0.0 : out.back().t_end_ms, !out.empty(), path, line);
        const long long seq = parse_int(f[1], path, line, "seq", 0, 0xFFFFFFFFLL);
        if (seq < 0 || seq > 0xFFFFFFFFLL) fail_at(path, line, "column 'seq': out of range");
        w.seq = static_cast<std::uint32_t>(seq);
        for (int i = 0; i < 4; ++i) {
          static const char* const kColumns[4] = {"c1", "c2", "c3", "c4"};
          const std::string col = kColumns[i];
          const long long c =
              parse_int(f[2 + i], path, line, col, std::numeric_limits<std::int32_t>::min(),
                        std::numeric_limits<std::int32_t>::max());
          if (c < std::numeric_limits<std::int32_t>::min() ||
              c > std::numeric_limits<std::int32_t>::max())
            fail_at(path, line, "column '" + col + "': out of range");
          w.counts[i] = static_cast<std::int32_t>(c);
        }
        w.gyro_yaw_deg =
            finite(parse_double(f[6], path, line, "gyro_yaw_deg"), path, line, "gyro_yaw_deg");
        out.push_back(w);
      });
  return out;
}

std::vector<FrameRef> read_camera_csv(const fs::path& path) {
  std::vector<FrameRef> out;
  read_csv(path, {"t_ms", "file"}, [&](const auto& f, int line) {
    FrameRef r;
    r.t_ms = parse_double(f[0], path, line, "t_ms");
    check_time(r.t_ms, out.empty() ? 0.0 : out.back().t_ms, !out.empty(), path, line);
    if (f[1].empty()) fail_at(path, line, "column 'file': empty");
    r.file = f[1];
    out.push_back(r);
  });
  return out;
}

std::vector<TruthSample> read_truth_csv(const fs::path& path) {
  std::vector<TruthSample> out;
  read_csv(path, {"t_ms", "x_cm", "y_cm", "yaw_deg"}, [&](const auto& f, int line) {
    TruthSample s;
    s.t_ms = parse_double(f[0], path, line, "t_ms");
    check_time(s.t_ms, out.empty() ? 0.0 : out.back().t_ms, !out.empty(), path, line);
    s.pose.x_cm = finite(parse_double(f[1], path, line, "x_cm"), path, line, "x_cm");
    s.pose.y_cm = finite(parse_double(f[2], path, line, "y_cm"), path, line, "y_cm");
    s.pose.yaw_deg = finite(parse_double(f[3], path, line, "yaw_deg"), path, line, "yaw_deg");
    out.push_back(s);
  });
  return out;
}

std::vector<LocalizedPose> read_poses_csv(const fs::path& path) {
  std::vector<LocalizedPose> out;
  read_csv(path, {"t_ms", "x_cm", "y_cm", "yaw_deg", "source", "match_error", "search_range_cm"},
           [&](const auto& f, int line) {
             LocalizedPose p;
             p.t_ms = parse_double(f[0], path, line, "t_ms");
             p.pose.x_cm = parse_double(f[1], path, line, "x_cm");
             p.pose.y_cm = parse_double(f[2], path, line, "y_cm");
             p.pose.yaw_deg = parse_double(f[3], path, line, "yaw_deg");
             const auto s = parse_pose_source(f[4]);
             if (!s) fail_at(path, line, "column 'source': unknown source '" + f[4] + "'");
             p.source = *s;
             // No image result yet: "inf"; a global search's range: -1 (PosesCsvWriter).
             if (const double e = parse_double(f[5], path, line, "match_error"); std::isfinite(e))
               p.match_error = e;
             if (const double r = parse_double(f[6], path, line, "search_range_cm");
                 p.match_error && r >= 0.0)
               p.search_range_cm = r;
             out.push_back(p);
           });
  return out;
}

namespace {

const config::KeyTable<Pose2>& pose_keys() {
  using config::Need;
  static const config::KeyTable<Pose2> table = {
      config::key("x_cm", &Pose2::x_cm, Need::kRequired),
      config::key("y_cm", &Pose2::y_cm, Need::kRequired),
      config::key("yaw_deg", &Pose2::yaw_deg, Need::kRequired),
  };
  return table;
}

// meta.json's keys. The camera and robot blocks are read (and validated) by their components; the
// robot block is written with the contract's six keys only, as it always was.
const config::KeyTable<RecordingMeta>& meta_keys() {
  using config::Need;
  using M = RecordingMeta;
  static const config::KeyTable<RecordingMeta> table = {
      config::key("field", &M::field, Need::kRequired),
      config::Key<M>{"field_geometry",
                     Need::kOptional,
                     config::Kind::kOther,
                     [](const config::Node& n, M& m) { m.field_geometry = parse_field_spec(n); },
                     [](const M& m) -> std::optional<config::Json> {
                       if (!m.field_geometry) return std::nullopt;
                       return config::write_keys(*m.field_geometry, field_spec_keys());
                     },
                     {}},
      config::custom<M>(
          "camera", Need::kRequired,
          [](const config::Node& n, M& m) { m.camera = camera_from_json(n); },
          [](const M& m) { return config::write_keys(m.camera, camera_keys()); }),
      config::custom<M>(
          "robot", Need::kRequired,
          [](const config::Node& n, M& m) { m.robot = parse_robot_config(n); },
          [](const M& m) {
            return config::write_keys(m.robot, robot_config_keys(), Need::kRequired);
          }),
      config::Key<M>{"initial_pose",
                     Need::kOptional,
                     config::Kind::kOther,
                     [](const config::Node& n, M& m) {
                       Pose2 p;
                       config::read_keys(n, pose_keys(), p);
                       m.initial_pose = p;
                     },
                     [](const M& m) -> std::optional<config::Json> {
                       if (!m.initial_pose) return std::nullopt;
                       return config::write_keys(*m.initial_pose, pose_keys());
                     },
                     {}},
  };
  return table;
}

}  // namespace

namespace {
void check_initial_pose(const Pose2& pose, const FieldGeometry& field, const config::Origin& at);
}  // namespace

void RecordingMeta::validate(const config::Origin& at) const {
  config::require(!field.empty(), at / "field", "must name a geometry (a name or a path)",
                  config::show(field));
  camera.validate(at / "camera");
  robot.validate(at / "robot");
  if (initial_pose) {
    config::require(std::isfinite(initial_pose->x_cm), at / "initial_pose" / "x_cm",
                    "must be finite", initial_pose->x_cm);
    config::require(std::isfinite(initial_pose->y_cm), at / "initial_pose" / "y_cm",
                    "must be finite", initial_pose->y_cm);
    config::require(std::isfinite(initial_pose->yaw_deg), at / "initial_pose" / "yaw_deg",
                    "must be finite", initial_pose->yaw_deg);
    if (field_geometry) check_initial_pose(*initial_pose, build_field(*field_geometry, ""), at);
  }
}

namespace {
void check_initial_pose(const Pose2& pose, const FieldGeometry& field, const config::Origin& at) {
  // On the carpet or near it (a robot put down just outside): 1e9 cm was accepted once.
  const auto inside = [&](double v, double total) {
    return v >= -kPlacementMarginCm && v <= total + kPlacementMarginCm;
  };
  config::require(inside(pose.x_cm, field.total_x_cm()), at / "initial_pose" / "x_cm",
                  "must lie on the carpet of field '" + field.name + "' (0 .. " +
                      config::show(field.total_x_cm()) + " cm, 100 cm margin)",
                  pose.x_cm);
  config::require(inside(pose.y_cm, field.total_y_cm()), at / "initial_pose" / "y_cm",
                  "must lie on the carpet of field '" + field.name + "' (0 .. " +
                      config::show(field.total_y_cm()) + " cm, 100 cm margin)",
                  pose.y_cm);
  config::require(std::abs(pose.yaw_deg) <= 3600.0, at / "initial_pose" / "yaw_deg",
                  "must be within +-3600 degrees", pose.yaw_deg);
}
}  // namespace

FieldGeometry recording_field(const Recording& rec) {
  const fs::path meta = rec.dir / "meta.json";
  try {
    FieldGeometry field;
    if (rec.meta.field_geometry) {
      field = build_field(*rec.meta.field_geometry, meta.string() + ":field_geometry");
    } else {
      // Older recordings name the geometry; a relative path was stored as typed, so it is also
      // looked for from the recording's directory.
      const fs::path as_given(rec.meta.field);
      std::error_code ec;
      const bool beside = as_given.is_relative() && !fs::exists(as_given, ec) &&
                          fs::is_regular_file(rec.dir / as_given, ec);
      field = load_field(beside ? (rec.dir / as_given).string() : rec.meta.field);
    }
    if (rec.meta.initial_pose) check_initial_pose(*rec.meta.initial_pose, field, meta.string());
    return field;
  } catch (const ConfigError& e) {
    throw RecordingError(e.what());
  }
}

RecordingMeta read_meta(const fs::path& meta_json) {
  try {
    const config::Document doc = config::parse_json_file(meta_json);
    RecordingMeta m;
    config::read_keys(doc.root(), meta_keys(), m);
    m.validate(doc.source);
    return m;
  } catch (const ConfigError& e) {
    throw RecordingError(e.what());
  }
}

namespace {

/// heading.csv (RecordingWriter::add_window) into the windows it belongs to.
void read_heading_csv(const fs::path& path, std::vector<EncoderWindow>& windows) {
  std::vector<std::pair<int, EncoderWindow>> rows;  // (line, window with the heading fields)
  read_csv(path, {"t_ms", "trust", "gyro_sum_lsb", "gyro_samples", "gyro_flags"},
           [&](const auto& f, int line) {
             EncoderWindow w;
             w.t_end_ms = parse_double(f[0], path, line, "t_ms");
             const std::optional<HeadingTrust> trust = parse_heading_trust(f[1]);
             if (!trust)
               fail_at(path, line,
                       "column 'trust': must be absolute, relative or none (got '" + f[1] + "')");
             w.heading_trust = *trust;
             w.gyro.sum_lsb = parse_int(f[2], path, line, "gyro_sum_lsb",
                                        std::numeric_limits<std::int64_t>::min(),
                                        std::numeric_limits<std::int64_t>::max());
             const long long samples =
                 parse_int(f[3], path, line, "gyro_samples", -1, 0xFFFFFFFFLL);  // -1: no gyro
             w.gyro.present = samples >= 0;
             w.gyro.samples = w.gyro.present ? static_cast<std::uint32_t>(samples) : 0U;
             w.gyro.flags =
                 static_cast<std::uint8_t>(parse_int(f[4], path, line, "gyro_flags", 0, 255));
             rows.emplace_back(line, w);
           });
  // The file starts at the first window whose heading was not the default and then has a row for
  // every window: it lines up with the end of encoders.csv.
  if (rows.size() > windows.size())
    fail_at(path, static_cast<int>(windows.size()) + 2,
            "more rows (" + std::to_string(rows.size()) + ") than encoders.csv has windows (" +
                std::to_string(windows.size()) + ")");
  const std::size_t first = windows.size() - rows.size();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EncoderWindow& w = windows[first + i];
    const auto& [line, h] = rows[i];
    if (std::abs(h.t_end_ms - w.t_end_ms) > 1e-3)
      fail_at(path, line,
              "column 't_ms': " + std::to_string(h.t_end_ms) +
                  " is not the time of encoders.csv's window " + std::to_string(first + i + 1) +
                  " (" + std::to_string(w.t_end_ms) + ")");
    w.heading_trust = h.heading_trust;
    w.gyro = h.gyro;
  }
}

}  // namespace

Recording load_recording(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw RecordingError(dir.string() + ": not a recording directory");
  Recording r;
  r.dir = dir;
  r.meta = read_meta(dir / "meta.json");
  r.windows = read_encoders_csv(dir / "encoders.csv");
  if (fs::exists(dir / "heading.csv")) read_heading_csv(dir / "heading.csv", r.windows);
  r.frames = read_camera_csv(dir / "camera.csv");
  for (std::size_t i = 0; i < r.frames.size(); ++i)
    if (!fs::is_regular_file(dir / r.frames[i].file))  // a device there would be read without end
      fail_at(dir / "camera.csv", static_cast<int>(i) + 2,
              "image '" + r.frames[i].file + "' does not exist or is not a regular file");
  if (fs::exists(dir / "truth.csv")) r.truth = read_truth_csv(dir / "truth.csv");
  return r;
}

cv::Mat load_frame(const Recording& rec, std::size_t i) {
  const FrameRef& f = rec.frames.at(i);
  const fs::path p = rec.dir / f.file;
  const std::string where = (rec.dir / "camera.csv").string() + ":" + std::to_string(i + 2) + ": ";
  cv::Mat img;
  try {
    img = read_image_file(p);  // the size from the header first, refused above the limits
  } catch (const ImageFileError& e) {
    throw RecordingError(where + "cannot read image: " + e.what());
  }
  if (img.cols != rec.meta.camera.width_px || img.rows != rec.meta.camera.height_px) {
    std::ostringstream os;
    os << where << "image '" << p.string() << "' is " << img.cols << " x " << img.rows
       << ", the camera is " << rec.meta.camera.width_px << " x " << rec.meta.camera.height_px;
    throw RecordingError(os.str());
  }
  return img;
}

std::optional<Pose2> truth_at(const std::vector<TruthSample>& truth, double t_ms) {
  if (truth.empty() || t_ms < truth.front().t_ms || t_ms > truth.back().t_ms) return std::nullopt;
  auto hi = std::lower_bound(truth.begin(), truth.end(), t_ms,
                             [](const TruthSample& s, double t) { return s.t_ms < t; });
  if (hi->t_ms == t_ms || hi == truth.begin()) return hi->pose;
  const auto lo = std::prev(hi);
  const double f = (t_ms - lo->t_ms) / (hi->t_ms - lo->t_ms);
  return interpolate(lo->pose, hi->pose, f);
}

// ---------------------------------------------------------------------------------------------
// Writing.

namespace {

std::string errno_text() {
  return std::strerror(errno);
}

double steady_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// All of `data` to `fd`, or false with errno set (a short write is retried until it fails).
bool write_all(int fd, const char* data, std::size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd, data, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    if (w == 0) {
      errno = ENOSPC;
      return false;
    }
    data += w;
    n -= static_cast<std::size_t>(w);
  }
  return true;
}

/// A whole file written and closed, or RecordingError naming it (the partial file is removed).
void write_file(const fs::path& p, const char* data, std::size_t n) {
  const int fd = ::open(p.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw RecordingError(p.string() + ": cannot create (" + errno_text() + ")");
  const bool ok = write_all(fd, data, n);
  const std::string why = ok ? "" : errno_text();
  if (::close(fd) != 0 && ok)
    throw RecordingError(p.string() + ": write failed (" + errno_text() + ")");
  if (!ok) {
    std::error_code ec;
    fs::remove(p, ec);
    throw RecordingError(p.string() + ": write failed (" + why + ")");
  }
}

// The files a recording consists of: what `overwrite` removes, and nothing else.
const char* const kRecordingFiles[] = {"meta.json", "encoders.csv", "camera.csv", "truth.csv",
                                       "poses.csv"};

/// A new recording directory: created, or existing and empty, or (overwrite) holding an old
/// recording, which is removed first (its frames too, so none is left to mix with the new ones).
void prepare_directory(const fs::path& dir, bool overwrite) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw RecordingError(dir.string() + ": exists and is not a directory");
  if (fs::is_directory(dir, ec) && !fs::is_empty(dir, ec)) {
    if (!overwrite) {
      throw RecordingError(
          dir.string() +
          ": exists and is not empty (an earlier recording?): not overwriting it; "
          "record to a new directory, or set record_overwrite (--record-overwrite) to replace it");
    }
    if (!fs::exists(dir / "meta.json", ec))
      throw RecordingError(dir.string() +
                           ": not empty and holds no recording (no meta.json): not overwriting it");
    for (const char* f : kRecordingFiles) fs::remove(dir / f, ec);
    fs::remove_all(dir / "frames", ec);
    if (ec)
      throw RecordingError(dir.string() + ": cannot remove the old recording (" + ec.message() +
                           ")");
  }
  fs::create_directories(dir / "frames", ec);
  if (ec) throw RecordingError(dir.string() + ": cannot create (" + ec.message() + ")");
}

}  // namespace

CsvFile::CsvFile(const fs::path& path, const std::string& header) : path_(path) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw RecordingError(path.string() + ": cannot create (" + errno_text() + ")");
  last_sync_s_ = steady_s();
  write_row(header);
}

CsvFile::~CsvFile() {
  if (fd_ >= 0) ::close(fd_);
}

void CsvFile::write_row(const std::string& row) {
  if (fd_ < 0) throw RecordingError(path_.string() + ": closed");
  if (!write_all(fd_, row.data(), row.size())) {
    const std::string why = errno_text();
    // Whole rows only: cut back what part of this row got in, so the file still reads.
    if (::ftruncate(fd_, bytes_) != 0) { /* the error below is the one that matters */
    }
    throw RecordingError(path_.string() + ": write failed (" + why + ")");
  }
  bytes_ += static_cast<long long>(row.size());
  // Once a second to the disk itself, so that a power loss costs at most the last second.
  const double now = steady_s();
  if (now - last_sync_s_ >= 1.0) {
    last_sync_s_ = now;
    if (::fdatasync(fd_) != 0)
      throw RecordingError(path_.string() + ": sync failed (" + errno_text() + ")");
  }
}

void CsvFile::close() {
  if (fd_ < 0) return;
  const bool synced = ::fdatasync(fd_) == 0;
  const std::string why = synced ? "" : errno_text();
  const bool closed = ::close(fd_) == 0;
  fd_ = -1;
  if (!synced || !closed)
    throw RecordingError(path_.string() + ": write failed (" + (synced ? errno_text() : why) + ")");
}

void write_meta(const fs::path& meta_json, const RecordingMeta& m) {
  // nlohmann escapes the strings (a field path with '\' or '"') and writes every double so that it
  // reads back to the same value.
  const std::string s = config::write_keys(m, meta_keys()).dump(2) + "\n";
  write_file(meta_json, s.data(), s.size());
}

RecordingWriter::RecordingWriter(const fs::path& dir, const RecordingMeta& meta, bool with_truth,
                                 const RecordingOptions& options)
    : dir_(dir), options_(options) {
  if (options.jpeg_quality < 1 || options.jpeg_quality > 100)
    throw RecordingError(dir.string() + ": JPEG quality must be 1..100 (got " +
                         std::to_string(options.jpeg_quality) + ")");
  prepare_directory(dir, options.overwrite);
  write_meta(dir / "meta.json", meta);
  encoders_ =
      std::make_unique<CsvFile>(dir / "encoders.csv", "t_ms,seq,c1,c2,c3,c4,gyro_yaw_deg\n");
  camera_ = std::make_unique<CsvFile>(dir / "camera.csv", "t_ms,file\n");
  if (with_truth) truth_ = std::make_unique<TruthCsvWriter>(dir / "truth.csv");
}

RecordingWriter::~RecordingWriter() = default;

void RecordingWriter::check_usable() const {
  if (!failed_.empty()) throw RecordingError("recording stopped after an error: " + failed_);
  if (!encoders_) throw RecordingError(dir_.string() + ": recording closed");
}

void RecordingWriter::add_window(const EncoderWindow& w) {
  check_usable();
  char row[160];
  std::snprintf(row, sizeof row, "%.6f,%u,%d,%d,%d,%d,%.6f\n", w.t_end_ms, w.seq, w.counts[0],
                w.counts[1], w.counts[2], w.counts[3], w.gyro_yaw_deg);
  try {
    encoders_->write_row(row);
    // heading.csv from the first window whose heading is not the simulator's aligned gyro, then
    // for every window (the reader lines it up with the end of encoders.csv).
    if (!heading_ && (w.heading_trust != HeadingTrust::kAbsolute || w.gyro.present))
      heading_ = std::make_unique<CsvFile>(dir_ / "heading.csv",
                                           "t_ms,trust,gyro_sum_lsb,gyro_samples,gyro_flags\n");
    if (heading_) {
      std::snprintf(row, sizeof row, "%.6f,%s,%lld,%lld,%u\n", w.t_end_ms,
                    heading_trust_name(w.heading_trust), static_cast<long long>(w.gyro.sum_lsb),
                    w.gyro.present ? static_cast<long long>(w.gyro.samples) : -1LL,
                    static_cast<unsigned>(w.gyro.flags));
      heading_->write_row(row);
    }
  } catch (const RecordingError& e) {
    failed_ = e.what();
    throw;
  }
}

void RecordingWriter::add_frame(double t_ms, const cv::Mat& bgr) {
  check_usable();
  const bool jpeg = options_.frame_format == FrameFormat::kJpeg;
  char name[32];
  std::snprintf(name, sizeof name, "frames/%06d.%s", frame_count_, jpeg ? "jpg" : "png");
  const fs::path p = dir_ / name;
  try {
    std::vector<std::uint8_t> bytes;
    const std::vector<int> params =
        jpeg ? std::vector<int>{cv::IMWRITE_JPEG_QUALITY, options_.jpeg_quality}
             : std::vector<int>{};
    if (!cv::imencode(jpeg ? ".jpg" : ".png", bgr, bytes, params))
      throw RecordingError(p.string() + ": cannot encode image");
    // The image is complete before camera.csv names it: after a crash every listed frame reads.
    write_file(p, reinterpret_cast<const char*>(bytes.data()), bytes.size());
    frame_bytes_ += bytes.size();
    ++frame_count_;
    char row[64];
    std::snprintf(row, sizeof row, "%.6f,%s\n", t_ms, name);
    camera_->write_row(row);
  } catch (const RecordingError& e) {
    failed_ = e.what();
    throw;
  }
}

void RecordingWriter::add_truth(double t_ms, const Pose2& pose) {
  if (!truth_) throw RecordingError(dir_.string() + ": recording opened without truth");
  truth_->add(t_ms, pose);
}

void RecordingWriter::add_clock(const ClockRow& c) {
  check_usable();
  char row[256];
  std::snprintf(row, sizeof row, "%u,%.6f,%.6f,%.6f,%.6f,%.4f,%.4f,%u\n", c.seq, c.board_ms,
                c.arrival_ms, c.t_ms, c.offset_ms, c.drift_ppm, c.uncertainty_ms, c.epoch);
  try {
    if (!clock_)
      clock_ = std::make_unique<CsvFile>(
          dir_ / "clock.csv",
          "seq,board_ms,arrival_ms,t_ms,offset_ms,drift_ppm,uncertainty_ms,epoch\n");
    clock_->write_row(row);
  } catch (const RecordingError& e) {
    failed_ = e.what();
    throw;
  }
}

void RecordingWriter::add_frame_time(const FrameTimeRow& f) {
  check_usable();
  char row[128];
  std::snprintf(row, sizeof row, "%.6f,%s,%.6f\n", f.t_ms, f.source.c_str(), f.handover_ms);
  try {
    if (!frame_times_)
      frame_times_ =
          std::make_unique<CsvFile>(dir_ / "frame_times.csv", "t_ms,source,handover_ms\n");
    frame_times_->write_row(row);
  } catch (const RecordingError& e) {
    failed_ = e.what();
    throw;
  }
}

void RecordingWriter::close() {
  if (!encoders_) return;
  encoders_->close();
  camera_->close();
  if (clock_) clock_->close();
  if (heading_) heading_->close();
  if (frame_times_) frame_times_->close();
  if (truth_) truth_->close();
}

TruthCsvWriter::TruthCsvWriter(const fs::path& path) : file_(path, "t_ms,x_cm,y_cm,yaw_deg\n") {}

TruthCsvWriter::~TruthCsvWriter() = default;

void TruthCsvWriter::add(double t_ms, const Pose2& pose) {
  char row[160];
  std::snprintf(row, sizeof row, "%.6f,%.6f,%.6f,%.6f\n", t_ms, pose.x_cm, pose.y_cm, pose.yaw_deg);
  file_.write_row(row);
}

void TruthCsvWriter::close() {
  file_.close();
}

PosesCsvWriter::PosesCsvWriter(const fs::path& path)
    : file_(path, "t_ms,x_cm,y_cm,yaw_deg,source,match_error,search_range_cm\n") {}

PosesCsvWriter::~PosesCsvWriter() = default;

void PosesCsvWriter::write(const LocalizedPose& p) {
  // No image result yet is spelled "inf" (read_poses_csv accepts it); the range of a global search
  // -1, as before the columns were optional.
  auto num = [](std::optional<double> v, const char* none, char* buf, std::size_t n) {
    if (v)
      std::snprintf(buf, n, "%.3f", *v);
    else
      std::snprintf(buf, n, "%s", none);
  };
  char e[32], r[32], row[256];
  num(p.match_error, "inf", e, sizeof e);
  num(p.search_range_cm, p.match_error ? "-1.000" : "0.000", r, sizeof r);
  std::snprintf(row, sizeof row, "%.3f,%.3f,%.3f,%.3f,%s,%s,%s\n", p.t_ms, p.pose.x_cm, p.pose.y_cm,
                p.pose.yaw_deg, pose_source_name(p.source), e, r);
  file_.write_row(row);
}

void PosesCsvWriter::close() {
  file_.close();
}

}  // namespace omniloc
