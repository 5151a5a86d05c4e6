// Recordings: the REC_DIR contract of issue 7, read and written exactly.
//
//   meta.json    {"field": name or path, "field_geometry": {...geometry file...} (optional; written
//   by
//                 every writer since issue 16, so that a recording replays without the field file),
//                 "camera": {...camera block...}, "robot": {...robot block...},
//                 "initial_pose": {"x_cm", "y_cm", "yaw_deg"} (optional)}
//   encoders.csv t_ms,seq,c1,c2,c3,c4,gyro_yaw_deg      one row per encoder window
//   camera.csv   t_ms,file                              file: image (JPEG or PNG) relative to
//   REC_DIR truth.csv    t_ms,x_cm,y_cm,yaw_deg                 optional poses.csv
//   t_ms,x_cm,y_cm,yaw_deg,source,match_error,search_range_cm   (output of replay)
//
// Every error (RecordingError) names the file and, for CSV files, the line (1-based, header = 1).
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "omniloc/camera.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/feature_db.hpp"
#include "omniloc/field.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/odometry.hpp"
#include "omniloc/robot_config.hpp"

namespace omniloc {

class RecordingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct RecordingMeta {
  std::string field = "fira-robosot";       ///< geometry name or path, as written in meta.json
  std::optional<FieldSpec> field_geometry;  ///< the geometry itself (replay uses it before `field`)
  CameraModel camera;
  RobotConfig robot;
  std::optional<Pose2> initial_pose;

  /// Throws ConfigError "<at>.<field>: <why> (got <value>)": an empty field name, a bad camera or
  /// robot block, a non-finite initial pose.
  void validate(const config::Origin& at) const;
};

struct FrameRef {
  double t_ms = 0.0;
  std::string file;  ///< relative to the recording directory
};

struct TruthSample {
  double t_ms = 0.0;
  Pose2 pose;
};

struct Recording {
  std::filesystem::path dir;
  RecordingMeta meta;
  std::vector<EncoderWindow> windows;
  std::vector<FrameRef> frames;
  std::vector<TruthSample> truth;  ///< empty without truth.csv
};

/// Reads meta.json (config layer: camera via camera_from_json, robot via parse_robot_config);
/// errors are RecordingError "<meta.json>:<field path>: <why> (got <value>)".
[[nodiscard]] RecordingMeta read_meta(const std::filesystem::path& meta_json);
[[nodiscard]] std::vector<EncoderWindow> read_encoders_csv(const std::filesystem::path& path);
[[nodiscard]] std::vector<FrameRef> read_camera_csv(const std::filesystem::path& path);
[[nodiscard]] std::vector<TruthSample> read_truth_csv(const std::filesystem::path& path);
/// Reads the poses.csv that replay writes.
[[nodiscard]] std::vector<LocalizedPose> read_poses_csv(const std::filesystem::path& path);

/// Reads meta.json, encoders.csv, camera.csv and truth.csv if present; checks that every listed
/// image exists (images are loaded on demand with load_frame).
[[nodiscard]] Recording load_recording(const std::filesystem::path& dir);
/// The recording's field: the embedded geometry, else the file `field` names (a name in
/// common/fields/, a path as given, or a relative path from the recording's directory: older
/// recordings stored --field as typed). The initial pose, if any, must lie on the carpet (or
/// within 100 cm of it); throws RecordingError / ConfigError naming meta.json otherwise.
[[nodiscard]] FieldGeometry recording_field(const Recording& recording);
/// Loads a frame's PNG as BGR; throws RecordingError naming the file (and camera.csv's line) if it
/// cannot be read or its size differs from the camera's.
[[nodiscard]] cv::Mat load_frame(const Recording& recording, std::size_t frame_index);

/// Truth pose at t_ms, linear between samples (yaw the short way); nullopt outside the samples.
[[nodiscard]] std::optional<Pose2> truth_at(const std::vector<TruthSample>& truth, double t_ms);

/// How frames are stored: JPEG (default; ~5x smaller than PNG, replayed poses within 0.5 cm of the
/// PNG recording's, docs/DAEMON.md "Recording") or PNG (lossless).
enum class FrameFormat { kJpeg, kPng };

struct RecordingOptions {
  /// false: a directory that exists and is not empty is refused (nothing of an old recording is
  /// replaced or mixed). true: an old recording there (a meta.json) is removed first, its frames
  /// included; a non-empty directory without meta.json is still refused.
  bool overwrite = false;
  FrameFormat frame_format = FrameFormat::kJpeg;
  int jpeg_quality = 95;  ///< 1..100
};

/// Streams CSV rows so that a crash loses at most the last second: each row goes to the kernel
/// in one write(2) (a SIGKILL leaves whole rows only), the file is fdatasync'ed at least once a
/// second (power loss), and a short write (disk full, file size limit) is cut back to the last
/// whole row and reported as RecordingError naming the file and the reason.
class CsvFile {
 public:
  CsvFile(const std::filesystem::path& path, const std::string& header);
  ~CsvFile();
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  void write_row(const std::string& row_with_newline);
  /// Syncs and closes; throws RecordingError if the data did not reach the file.
  void close();
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
  long long bytes_ = 0;  // whole rows written so far
  double last_sync_s_ = 0.0;
};

/// Streams truth.csv rows (t_ms,x_cm,y_cm,yaw_deg): the ground truth of a simulated run, written by
/// the simulator beside the daemon's recording (the robot never knows its truth).
class TruthCsvWriter {
 public:
  explicit TruthCsvWriter(const std::filesystem::path& path);
  ~TruthCsvWriter();
  TruthCsvWriter(const TruthCsvWriter&) = delete;
  TruthCsvWriter& operator=(const TruthCsvWriter&) = delete;
  void add(double t_ms, const Pose2& pose);
  /// Flushes and closes; throws RecordingError if the data did not reach the file.
  void close();

 private:
  CsvFile file_;
};

/// One clock.csv row (the daemon's board clock, board_clock.hpp): the window's board seq and board
/// time, when it arrived (daemon clock), the time it was given (encoders.csv t_ms), and the model's
/// offset, drift, uncertainty and epoch then. Replay does not read it (old recordings have none).
struct ClockRow {
  std::uint32_t seq = 0;
  double board_ms = 0.0, arrival_ms = 0.0, t_ms = 0.0, offset_ms = 0.0, drift_ppm = 0.0,
         uncertainty_ms = 0.0;
  std::uint32_t epoch = 0;
};

/// One frame_times.csv row: a frame's time (camera.csv t_ms), where it came from ("buffer": the
/// driver's buffer timestamp, "latency": hand-over minus the configured latency, "file": the video
/// file's own time, "sim": the simulator's exposure time) and when the daemon got it.
struct FrameTimeRow {
  double t_ms = 0.0;
  std::string source;
  double handover_ms = 0.0;
};

/// Writes a recording directory (created if needed; see RecordingOptions for an existing one).
/// Every write is checked: add_* throw RecordingError naming the file and the reason (a full disk:
/// "No space left on device"); after one, the writer refuses further rows (the daemon stops the
/// recording and goes on streaming poses). Rows reach the disk as CsvFile says; a frame's
/// camera.csv row is written only after its image is complete.
class RecordingWriter {
 public:
  RecordingWriter(const std::filesystem::path& dir, const RecordingMeta& meta, bool with_truth,
                  const RecordingOptions& options = {});
  ~RecordingWriter();
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  /// The encoders.csv row; and, from the first window whose heading_trust is not kAbsolute or that
  /// carries a board gyro, a heading.csv row (`t_ms,trust,gyro_sum_lsb,gyro_samples,gyro_flags`,
  /// samples -1: no gyro) for it and every later window.
  void add_window(const EncoderWindow& window);
  /// Writes frames/NNNNNN.jpg (or .png) and the camera.csv row.
  void add_frame(double t_ms, const cv::Mat& bgr);
  void add_truth(double t_ms, const Pose2& pose);
  /// clock.csv (`seq,board_ms,arrival_ms,t_ms,offset_ms,drift_ppm,uncertainty_ms,epoch`), created
  /// at the first row.
  void add_clock(const ClockRow& row);
  /// frame_times.csv (`t_ms,source,handover_ms`), created at the first row.
  void add_frame_time(const FrameTimeRow& row);
  /// Flushes and closes (also done by the destructor, which cannot report errors).
  void close();
  [[nodiscard]] std::uint64_t frame_bytes() const { return frame_bytes_; }

 private:
  void check_usable() const;
  std::filesystem::path dir_;
  RecordingOptions options_;
  std::unique_ptr<CsvFile> encoders_;
  std::unique_ptr<CsvFile> camera_;
  std::unique_ptr<TruthCsvWriter> truth_;
  std::unique_ptr<CsvFile> clock_, frame_times_, heading_;
  int frame_count_ = 0;
  std::uint64_t frame_bytes_ = 0;
  std::string failed_;  // the first write error; the writer is unusable after it
};

/// Writes meta.json with nlohmann-json (strings escaped, doubles exact): the camera block in the
/// camera-file format including the mask, the robot block's six contract keys, initial_pose if set.
void write_meta(const std::filesystem::path& meta_json, const RecordingMeta& meta);

/// Streams poses.csv rows.
class PosesCsvWriter {
 public:
  explicit PosesCsvWriter(const std::filesystem::path& path);
  ~PosesCsvWriter();
  PosesCsvWriter(const PosesCsvWriter&) = delete;
  PosesCsvWriter& operator=(const PosesCsvWriter&) = delete;
  void write(const LocalizedPose& pose);
  void close();

 private:
  CsvFile file_;
};

/// The database for a field and camera from `cache_path` if it holds the right one, else built
/// (10 cm grid) and saved there (the folder is created). `log` gets one line on what was done;
/// when saving fails (a full disk), that line is a warning naming the file and the error and the
/// database built is returned all the same. Something at `cache_path` that is not a feature
/// database is never overwritten (std::runtime_error, refuse_to_overwrite_foreign_file).
[[nodiscard]] FeatureDb load_or_build_feature_db(
    const FieldGeometry& field, const CameraModel& camera, const std::filesystem::path& cache_path,
    const std::function<void(const std::string&)>& log = {});
/// A cache file name for a field and camera: featuredb-<field fingerprint>-<camera
/// fingerprint>.bin.
[[nodiscard]] std::string feature_db_cache_name(const FieldGeometry& field,
                                                const CameraModel& camera);

/// Mean, median, 95th percentile (nearest rank) and maximum of a set of errors.
struct ErrorSummary {
  std::size_t count = 0;
  double mean = 0.0;
  double median = 0.0;
  double p95 = 0.0;
  double max = 0.0;
};
/// Throws std::invalid_argument for an empty set.
[[nodiscard]] ErrorSummary summarize_errors(std::vector<double> errors);

struct ReplayResult {
  std::vector<LocalizedPose> poses;  ///< one per encoder window
  LocalizerStats stats;
  std::size_t poses_without_fix = 0;              ///< source "none" (left out of the error figures)
  std::optional<ErrorSummary> position_error_cm;  ///< with truth.csv, over poses that have a fix
  std::optional<ErrorSummary> yaw_error_deg;
  /// Board time from the first window to the first pose with a fix (nullopt: never fixed; 0 with a
  /// known start pose).
  std::optional<double> time_to_first_fix_ms;
  /// Every frame's outcome in processing order (FrameReport::no_measurement set: the frame showed
  /// nothing usable and gave no measurement, odometry stood).
  std::vector<FrameReport> frames;
};

/// What a replay may change of the run it replays.
struct ReplaySettings {
  /// Every window's heading trust (else each window's own: heading.csv, absolute without one).
  std::optional<HeadingTrust> heading;
  /// The team's side (Localizer::set_side), as the daemon's `side` key.
  std::optional<GoalColour> side;
  /// Called with a warning for each window whose gyro yaw the localizer dropped (GyroYawGuard):
  /// "<dir>/encoders.csv: window seq 42: gyro_yaw_deg 1e+06 is outside ...: dropped, ... (1 so
  /// far)". Unset: the warnings are only counted (ReplayResult::stats.gyro_yaw_dropped).
  std::function<void(const std::string&)> warn;
};

/// Runs the localizer over a recording: windows and frames merged by time (a frame before the
/// window that covers it), one pose per window; errors against truth.csv when present.
/// `progress(done, total)` is called now and then with events processed. Throws
/// std::invalid_argument for a side the field and camera cannot place (Localizer::set_side).
[[nodiscard]] ReplayResult replay_recording(
    const Recording& recording, const LocalizerConfig& config, const FieldGeometry& field,
    const FeatureDb& db, const std::function<void(std::size_t, std::size_t)>& progress = {},
    const ReplaySettings& settings = {});

}  // namespace omniloc
