// Recording directories (issue 7 contract): CSV and meta.json reading and writing.
#include "omniloc/recording.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "omniloc/config_reader.hpp"
#include "omniloc/file_read.hpp"

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

double parse_double(const std::string& s, const fs::path& file, int line, const std::string& column) {
  double v = 0.0;
  const char* b = s.data();
  const char* e = s.data() + s.size();
  if (s == "nan") return std::numeric_limits<double>::quiet_NaN();
  if (s == "inf") return std::numeric_limits<double>::infinity();
  auto [p, ec] = std::from_chars(b, e, v);
  if (s.empty() || ec != std::errc() || p != e)
    fail_at(file, line, "column '" + column + "': not a number ('" + s + "')");
  return v;
}

long long parse_int(const std::string& s, const fs::path& file, int line, const std::string& column) {
  long long v = 0;
  const char* b = s.data();
  const char* e = s.data() + s.size();
  auto [p, ec] = std::from_chars(b, e, v);
  if (s.empty() || ec != std::errc() || p != e)
    fail_at(file, line, "column '" + column + "': not an integer ('" + s + "')");
  return v;
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
      fail_at(file, line, "expected " + std::to_string(header.size()) + " columns, got " + std::to_string(f.size()));
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
  read_csv(path, {"t_ms", "seq", "c1", "c2", "c3", "c4", "gyro_yaw_deg"}, [&](const auto& f, int line) {
    EncoderWindow w;
    w.t_end_ms = parse_double(f[0], path, line, "t_ms");
    check_time(w.t_end_ms, out.empty() ? 0.0 : out.back().t_end_ms, !out.empty(), path, line);
    const long long seq = parse_int(f[1], path, line, "seq");
    if (seq < 0 || seq > 0xFFFFFFFFLL) fail_at(path, line, "column 'seq': out of range");
    w.seq = static_cast<std::uint32_t>(seq);
    for (int i = 0; i < 4; ++i) {
      static const char* const kColumns[4] = {"c1", "c2", "c3", "c4"};
      const std::string col = kColumns[i];
      const long long c = parse_int(f[2 + i], path, line, col);
      if (c < std::numeric_limits<std::int32_t>::min() || c > std::numeric_limits<std::int32_t>::max())
        fail_at(path, line, "column '" + col + "': out of range");
      w.counts[i] = static_cast<std::int32_t>(c);
    }
    w.gyro_yaw_deg = finite(parse_double(f[6], path, line, "gyro_yaw_deg"), path, line, "gyro_yaw_deg");
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
             p.match_error = parse_double(f[5], path, line, "match_error");
             p.search_range_cm = parse_double(f[6], path, line, "search_range_cm");
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
      config::custom<M>(
          "camera", Need::kRequired, [](const config::Node& n, M& m) { m.camera = camera_from_json(n); },
          [](const M& m) { return config::write_keys(m.camera, camera_keys()); }),
      config::custom<M>(
          "robot", Need::kRequired, [](const config::Node& n, M& m) { m.robot = parse_robot_config(n); },
          [](const M& m) { return config::write_keys(m.robot, robot_config_keys(), Need::kRequired); }),
      config::Key<M>{"initial_pose", Need::kOptional, config::Kind::kOther,
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

void RecordingMeta::validate(const config::Origin& at) const {
  config::require(!field.empty(), at / "field", "must name a geometry (a name or a path)", config::show(field));
  camera.validate(at / "camera");
  robot.validate(at / "robot");
  if (initial_pose) {
    config::require(std::isfinite(initial_pose->x_cm), at / "initial_pose" / "x_cm", "must be finite", initial_pose->x_cm);
    config::require(std::isfinite(initial_pose->y_cm), at / "initial_pose" / "y_cm", "must be finite", initial_pose->y_cm);
    config::require(std::isfinite(initial_pose->yaw_deg), at / "initial_pose" / "yaw_deg", "must be finite",
                    initial_pose->yaw_deg);
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

Recording load_recording(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw RecordingError(dir.string() + ": not a recording directory");
  Recording r;
  r.dir = dir;
  r.meta = read_meta(dir / "meta.json");
  r.windows = read_encoders_csv(dir / "encoders.csv");
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
  cv::Mat img = cv::imread(p.string(), cv::IMREAD_COLOR);
  if (img.empty()) throw RecordingError(where + "cannot read image '" + p.string() + "'");
  if (img.cols != rec.meta.camera.width_px || img.rows != rec.meta.camera.height_px) {
    std::ostringstream os;
    os << where << "image '" << p.string() << "' is " << img.cols << " x " << img.rows << ", the camera is "
       << rec.meta.camera.width_px << " x " << rec.meta.camera.height_px;
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

std::FILE* open_write(const fs::path& p) {
  std::FILE* f = std::fopen(p.string().c_str(), "w");
  if (!f) throw RecordingError(p.string() + ": cannot create");
  return f;
}

void close_file(std::FILE*& f, const fs::path& p) {
  if (!f) return;
  const bool bad = std::ferror(f) != 0;
  const int rc = std::fclose(f);
  f = nullptr;
  if (bad || rc != 0) throw RecordingError(p.string() + ": write failed");
}

}  // namespace

void write_meta(const fs::path& meta_json, const RecordingMeta& m) {
  // nlohmann escapes the strings (a field path with '\' or '"') and writes every double so that it
  // reads back to the same value.
  const std::string s = config::write_keys(m, meta_keys()).dump(2) + "\n";
  std::FILE* f = open_write(meta_json);
  std::fwrite(s.data(), 1, s.size(), f);
  close_file(f, meta_json);
}

RecordingWriter::RecordingWriter(const fs::path& dir, const RecordingMeta& meta, bool with_truth) : dir_(dir) {
  std::error_code ec;
  fs::create_directories(dir / "frames", ec);
  if (ec) throw RecordingError(dir.string() + ": cannot create (" + ec.message() + ")");
  write_meta(dir / "meta.json", meta);
  encoders_ = open_write(dir / "encoders.csv");
  std::fputs("t_ms,seq,c1,c2,c3,c4,gyro_yaw_deg\n", encoders_);
  camera_ = open_write(dir / "camera.csv");
  std::fputs("t_ms,file\n", camera_);
  if (with_truth) {
    truth_ = std::make_unique<TruthCsvWriter>(dir / "truth.csv");
  } else {
    fs::remove(dir / "truth.csv", ec);
  }
}

RecordingWriter::~RecordingWriter() {
  for (std::FILE* f : {encoders_, camera_})
    if (f) std::fclose(f);
}

void RecordingWriter::add_window(const EncoderWindow& w) {
  std::fprintf(encoders_, "%.6f,%u,%d,%d,%d,%d,%.6f\n", w.t_end_ms, w.seq, w.counts[0], w.counts[1], w.counts[2],
               w.counts[3], w.gyro_yaw_deg);
}

void RecordingWriter::add_frame(double t_ms, const cv::Mat& bgr) {
  char name[32];
  std::snprintf(name, sizeof name, "frames/%06d.png", frame_count_++);
  const fs::path p = dir_ / name;
  if (!cv::imwrite(p.string(), bgr)) throw RecordingError(p.string() + ": cannot write image");
  std::fprintf(camera_, "%.6f,%s\n", t_ms, name);
}

void RecordingWriter::add_truth(double t_ms, const Pose2& pose) {
  if (!truth_) throw RecordingError(dir_.string() + ": recording opened without truth");
  truth_->add(t_ms, pose);
}

void RecordingWriter::close() {
  close_file(encoders_, dir_ / "encoders.csv");
  close_file(camera_, dir_ / "camera.csv");
  if (truth_) truth_->close();
}

TruthCsvWriter::TruthCsvWriter(const fs::path& path) : path_(path), file_(open_write(path)) {
  std::fputs("t_ms,x_cm,y_cm,yaw_deg\n", file_);
}

TruthCsvWriter::~TruthCsvWriter() {
  if (file_) std::fclose(file_);
}

void TruthCsvWriter::add(double t_ms, const Pose2& pose) {
  std::fprintf(file_, "%.6f,%.6f,%.6f,%.6f\n", t_ms, pose.x_cm, pose.y_cm, pose.yaw_deg);
}

void TruthCsvWriter::close() { close_file(file_, path_); }

PosesCsvWriter::PosesCsvWriter(const fs::path& path) : path_(path), file_(open_write(path)) {
  std::fputs("t_ms,x_cm,y_cm,yaw_deg,source,match_error,search_range_cm\n", file_);
}

PosesCsvWriter::~PosesCsvWriter() {
  if (file_) std::fclose(file_);
}

void PosesCsvWriter::write(const LocalizedPose& p) {
  // inf/nan are spelled "inf"/"nan" (read_poses_csv accepts them): no image result yet.
  auto num = [](double v, char* buf, std::size_t n) {
    if (std::isnan(v)) std::snprintf(buf, n, "nan");
    else if (std::isinf(v)) std::snprintf(buf, n, "inf");
    else std::snprintf(buf, n, "%.3f", v);
  };
  char e[32], r[32];
  num(p.match_error, e, sizeof e);
  num(p.search_range_cm, r, sizeof r);
  std::fprintf(file_, "%.3f,%.3f,%.3f,%.3f,%s,%s,%s\n", p.t_ms, p.pose.x_cm, p.pose.y_cm, p.pose.yaw_deg,
               pose_source_name(p.source), e, r);
}

void PosesCsvWriter::close() { close_file(file_, path_); }

}  // namespace omniloc
