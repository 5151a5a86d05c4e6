// `omniloc calibrate`: estimates the camera (centre, radial model, yaw offset, mirroring, view
// radius, body and mast mask) and the venue's colours (carpet, lines, goals: the "vision" block)
// from frames taken at known positions, writes the camera file and an overlay of the field model
// at the fitted pose.
#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "commands.hpp"
#include "omniloc/calibration.hpp"
#include "omniloc/detail/strict_number.hpp"
#include "omniloc/field.hpp"
#include "omniloc/image_file.hpp"

namespace omniloc::cli {

namespace {
struct CalibrateArgs {
  std::string field_name = "fira-robosot", out, overlay, debug_dir;
  std::vector<std::string> images, poses;
  std::string carpet_at, centre, mirrored;
  double rim_radius_px = 0.0;
};

/// "X,Y" in image pixels, each part by the strict parser (NumberError naming the option).
Eigen::Vector2d parse_pixel(const std::string& text, const std::string& option) {
  const auto comma = text.find(',');
  if (comma == std::string::npos || text.find(',', comma + 1) != std::string::npos) {
    throw NumberError(option + ": '" + text + "' is not X,Y (pixels)");
  }
  return {parse_double(text.substr(0, comma), "X of " + option + " '" + text + "'", 0.0, 1e5),
          parse_double(text.substr(comma + 1), "Y of " + option + " '" + text + "'", 0.0, 1e5)};
}

/// The hints of --carpet-at, --center, --rim-radius, --mirrored; throws NumberError.
AnalysisHints hints_of(const CalibrateArgs& a) {
  AnalysisHints h;
  if (!a.carpet_at.empty()) h.carpet_at_px = parse_pixel(a.carpet_at, "--carpet-at");
  if (!a.centre.empty()) h.centre_px = parse_pixel(a.centre, "--center");
  if (a.rim_radius_px > 0.0) h.rim_radius_px = a.rim_radius_px;
  if (h.centre_px.has_value() != h.rim_radius_px.has_value()) {
    throw NumberError(
        "--center and --rim-radius come together (the mirror's disc replaces the rim search)");
  }
  if (!a.mirrored.empty()) h.mirrored = a.mirrored == "yes";
  return h;
}

/// "X,Y" or "X,Y,YAW" (cm, cm, deg), each part by the strict parser; throws NumberError naming the
/// part and quoting the text.
CalibrationFrame parse_pose(const std::string& text) {
  std::vector<std::string> parts(1);
  for (char ch : text) {
    if (ch == ',')
      parts.emplace_back();
    else
      parts.back() += ch;
  }
  if (parts.size() != 2 && parts.size() != 3)
    throw NumberError("'" + text + "' is not X,Y or X,Y,YAW");
  const char* names[] = {"X", "Y", "YAW"};
  const double limits[] = {1e6, 1e6, 360.0};  // cm, cm, deg
  std::vector<double> v;
  for (std::size_t i = 0; i < parts.size(); ++i)
    v.push_back(parse_double(parts[i], std::string(names[i]) + " of '" + text + "'", -limits[i],
                             limits[i]));
  CalibrationFrame f;
  f.position_cm = {v[0], v[1]};
  if (v.size() == 3) f.yaw_deg = v[2];
  return f;
}

/// The --pose check: "" or what is wrong (CLI11 puts "--pose: " before it).
std::string pose_problem(const std::string& text) {
  try {
    (void)parse_pose(text);
    return {};
  } catch (const NumberError& e) {
    return e.what();
  }
}

std::string numbered(const std::string& path, std::size_t i) {
  if (i == 0) return path;
  const std::size_t dot = path.rfind('.');
  std::string n = "-";
  n += std::to_string(i + 1);  // (not "-" + ...: GCC 12 warns -Wrestrict on it)
  return dot == std::string::npos ? path + n : path.substr(0, dot) + n + path.substr(dot);
}
/// `--debug-dir`: writes the step pictures as DIR/<image stem>-<step>.png and counts them. Two
/// images with one stem (a/f.png, b/f.png) get "-2", "-3" after the later ones' stems, so no
/// picture overwrites another.
class DebugPictures {
 public:
  explicit DebugPictures(std::filesystem::path dir) : dir_(std::move(dir)) {}

  /// Creates the directory; false (and says why, naming it) when it cannot.
  bool create() const {
    std::error_code ec;
    std::filesystem::create_directories(dir_, ec);
    if (ec || !std::filesystem::is_directory(dir_)) {
      std::fprintf(stderr, "omniloc calibrate: error: cannot create the debug directory '%s': %s\n",
                   dir_.string().c_str(), ec ? ec.message().c_str() : "not a directory");
      return false;
    }
    return true;
  }

  /// The sink: never throws (it runs while a refusal is on its way out; a picture it cannot
  /// write is reported and counted as failed, the calibration's own reason stays the error).
  void write(const std::string& frame_name, const std::string& step, const cv::Mat& picture) {
    const std::filesystem::path path = dir_ / (stem_of(frame_name) + "-" + step + ".png");
    bool ok = false;
    try {
      ok = cv::imwrite(path.string(), picture);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "omniloc calibrate: %s\n", e.what());
    }
    if (ok)
      ++written_;
    else {
      ++failed_;
      std::fprintf(stderr, "omniloc calibrate: error: cannot write debug picture '%s'\n",
                   path.string().c_str());
    }
  }

  /// "debug pictures: DIR (N files)", on stdout, at the end or before a failure's error.
  void report() const {
    std::printf("debug pictures: %s (%d files%s)\n", dir_.string().c_str(), written_,
                failed_ > 0 ? (", " + std::to_string(failed_) + " not written").c_str() : "");
    std::fflush(stdout);
  }
  [[nodiscard]] bool all_written() const { return failed_ == 0; }

 private:
  std::string stem_of(const std::string& frame_name) {
    if (const auto it = stems_.find(frame_name); it != stems_.end()) return it->second;
    const std::string stem = std::filesystem::path(frame_name).stem().string();
    std::string unique = stem;
    for (int n = 2; taken(unique); ++n) unique = stem + "-" + std::to_string(n);
    return stems_[frame_name] = unique;
  }
  [[nodiscard]] bool taken(const std::string& stem) const {
    for (const auto& [name, s] : stems_)
      if (s == stem) return true;
    return false;
  }
  std::filesystem::path dir_;
  std::map<std::string, std::string> stems_;  // frame name -> file stem
  int written_ = 0, failed_ = 0;
};

// The frames with their poses: one --pose per image, one for all, or none (the field's centre).
// Returns 0, or the exit status after saying what is wrong.
int read_frames(const CalibrateArgs& a, const std::vector<CalibrationFrame>& poses,
                const FieldGeometry& field, std::vector<CalibrationFrame>& frames) {
  const std::vector<std::string>& images = a.images;
  for (std::size_t i = 0; i < images.size(); ++i) {
    CalibrationFrame f;
    if (!poses.empty())
      f = poses[poses.size() == 1 ? 0 : i];
    else
      f.position_cm = field.centre_cm();
    f.name = images[i];
    try {
      f.image = read_image_file(images[i]);  // the size from the header first, refused above the
                                             // limits
    } catch (const ImageFileError& e) {
      std::fprintf(stderr, "omniloc calibrate: error: cannot read image: %s\n", e.what());
      return 1;
    }
    std::printf("%s: %d x %d, robot at (%.1f, %.1f) cm, heading %s\n", f.name.c_str(), f.image.cols,
                f.image.rows, f.position_cm.x(), f.position_cm.y(),
                f.yaw_deg ? std::to_string(*f.yaw_deg).c_str() : "unknown");
    frames.push_back(std::move(f));
  }
  return 0;
}

// The camera found: centre, radial model, yaw offset and handedness, view, body and masts.
void print_camera(const CalibrationResult& r) {
  const CameraModel& c = r.camera;
  std::printf("centre (%.2f, %.2f) px (rim (%.2f, %.2f) r %.1f px on %d/360 rays)\n",
              c.center_px.x(), c.center_px.y(), r.rim.centre_px.x(), r.rim.centre_px.y(),
              r.rim.radius_px, r.rim.rays_on_circle);
  const RadialModel& m = r.radial;
  if (m.rational()) {
    std::printf("radial model (rational) d(r) = %.6g x / (1 %+.6g x^2 %+.6g x^3 %+.6g x^4) cm",
                m.a[0], m.e[0], m.e[1], m.e[2]);
  } else {
    std::printf("radial model (quartic) d(r) = %.6g x %+.6g x^2 %+.6g x^3 %+.6g x^4 cm", m.a[0],
                m.a[1], m.a[2], m.a[3]);
  }
  std::printf(", x = r / %.1f px; d(50) %.1f, d(100) %.1f, d(view) %.1f cm\n", m.scale_px,
              m.ground_cm(50), m.ground_cm(100), m.ground_cm(r.view_radius_px));
  std::printf("yaw offset %.2f deg%s, mirrored %s (%s)%s\n", c.yaw_offset_deg,
              r.yaw_offset_ambiguous
                  ? " (or 180 deg more: the view is symmetric; add a frame off the centre to tell)"
                  : "",
              c.mirrored ? "yes" : "no", r.handedness_from.c_str(),
              r.mirrored_ambiguous ? " (ambiguous: the other handedness fits as well)" : "");
  std::printf("view radius %.1f px, body radius %.1f px, %zu mast(s):", r.view_radius_px,
              c.body_radius_px, c.masts.size());
  for (const auto& mast : c.masts)
    std::printf(" %.1f+-%.1f deg", mast.bearing_deg, mast.half_width_deg);
  std::printf("\n");
}

// The venue's goal colours, as measured.
void print_goals(const CalibrationResult& r) {
  for (const auto& [name, g] :
       {std::pair{"blue", &r.goals.blue}, std::pair{"yellow", &r.goals.yellow}}) {
    if (*g) {
      std::printf("%s goal: hue %.0f +- %.0f, S >= %.0f, V >= %.0f (%d px)\n", name,
                  (*g)->colour.hue, (*g)->colour.hue_half_width, (*g)->colour.sat_min,
                  (*g)->colour.val_min, (*g)->pixels);
    } else {
      std::printf("%s goal: not seen\n", name);
    }
  }
  std::printf("goal colour at x = max: %s\n", goal_colour_name(r.goal_colour_at_x_max));
}

// How well the camera fits each frame, the first frame's twin heading and the overall residual.
void print_fits(const CalibrationResult& r, const std::vector<CalibrationFrame>& frames,
                const std::string& out, double seconds) {
  for (std::size_t i = 0; i < r.fits.size(); ++i) {
    const auto& f = r.fits[i];
    std::printf(
        "%s: heading %.2f deg%s, %d line pixels, %d within %.0f px: rms %.2f px (%.2f cm), median "
        "%.2f px\n",
        frames[i].name.c_str(), f.yaw_deg,
        f.yaw_given ? " (given)" : " (found, yaw offset taken for heading 0)", f.line_pixels,
        f.inliers, r.inlier_threshold_px, f.rms_px, f.rms_cm, f.median_px);
    std::printf(
        "%s: self-check: %.0f %% of the %d line points the camera puts on the carpet are seen as "
        "lines\n",
        frames[i].name.c_str(), 100 * f.line_recall, f.recall_points);
  }
  const auto& f0 = r.fits.front();
  std::printf(
      "%s: coarse score %.2f px at heading %.1f deg; best distinct heading %.1f deg scores %.2f "
      "px%s\n",
      frames.front().name.c_str(), f0.score, f0.yaw_deg, f0.twin_yaw_deg, f0.twin_score,
      f0.twin_score < 1.1 * f0.score ? " (a twin: the heading is not told apart)" : "");
  std::printf(
      "residual rms %.2f px (%.2f cm) over %.0f %% of the line pixels; wrote %s in %.2f s\n",
      r.rms_px, r.rms_cm, 100 * r.inlier_fraction, out.c_str(), seconds);
}

// --overlay: each frame with the field's lines drawn through the camera. False when one cannot
// be written (said on stderr).
bool write_overlays(const CalibrateArgs& a, const std::vector<CalibrationFrame>& frames,
                    const CalibrationResult& r, const FieldGeometry& field) {
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const std::string p = numbered(a.overlay, i);
    if (!cv::imwrite(p, calibration_overlay(frames[i], r.analyses[i], r.fits[i], r, field))) {
      std::fprintf(stderr, "omniloc calibrate: error: cannot write overlay '%s'\n", p.c_str());
      return false;
    }
    std::printf("overlay %s\n", p.c_str());
  }
  return true;
}

// The calibration's options from the arguments: hints, progress on stderr timed from t0, and
// the step pictures when --debug-dir is given (debug set). Returns 0 or the exit status.
int calibration_options(const CalibrateArgs& a, std::chrono::steady_clock::time_point t0,
                        CalibrationOptions& opt, std::shared_ptr<DebugPictures>& debug) {
  try {
    opt.hints = hints_of(a);
  } catch (const NumberError& e) {
    std::fprintf(stderr, "omniloc calibrate: %s\n", e.what());
    return 2;
  }
  opt.progress = [t0](const std::string& m) {
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr, "[%6.2f s] %s\n", s, m.c_str());
  };
  if (!a.debug_dir.empty()) {
    debug = std::make_shared<DebugPictures>(a.debug_dir);
    if (!debug->create()) return 1;
    opt.step_pictures = [debug](const std::string& frame, const std::string& step,
                                const cv::Mat& picture) { debug->write(frame, step, picture); };
  }
  return 0;
}

int run_calibrate(const CalibrateArgs& a) {
  const std::string& out = a.out;
  std::vector<CalibrationFrame> poses;
  for (const auto& p : a.poses) poses.push_back(parse_pose(p));
  if (!poses.empty() && poses.size() != 1 && poses.size() != a.images.size()) {
    std::fprintf(
        stderr,
        "omniloc calibrate: %zu --pose for %zu images (give one per image, or one for all)\n",
        poses.size(), a.images.size());
    return 2;
  }
  const FieldGeometry field = load_field(a.field_name);
  std::vector<CalibrationFrame> frames;
  if (const int status = read_frames(a, poses, field, frames); status != 0) return status;
  const auto t0 = std::chrono::steady_clock::now();
  CalibrationOptions opt;
  std::shared_ptr<DebugPictures> debug;
  if (const int status = calibration_options(a, t0, opt, debug); status != 0) return status;
  CalibrationResult r;
  try {
    r = calibrate_camera(frames, field, opt);
  } catch (const std::exception&) {
    if (debug) debug->report();  // the pictures of the steps reached: where to look for the cause
    throw;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  {
    std::ofstream f(out);
    f << calibrated_camera_json(r, frames);
    if (!f) {
      std::fprintf(stderr, "omniloc calibrate: error: cannot write '%s'\n", out.c_str());
      return 1;
    }
  }
  (void)load_camera(out);  // read back with the project's reader
  print_camera(r);
  print_goals(r);
  print_fits(r, frames, out, seconds);
  if (!a.overlay.empty() && !write_overlays(a, frames, r, field)) return 1;
  if (!debug) return 0;
  debug->report();
  return debug->all_written() ? 0 : 1;
}

}  // namespace

Subcommand add_calibrate(CLI::App& program) {
  CLI::App* app = program.add_subcommand(
      "calibrate", "estimate the camera (centre, mapping, yaw, mask) from frames at known poses");
  auto a = std::make_shared<CalibrateArgs>();
  app->add_option("IMAGE", a->images, "the frames (PNG, JPEG)")->required();
  app->add_option("--out", a->out, "the camera file to write (CAMERA.json)")->required();
  app->add_option(
         "--pose", a->poses,
         "where the robot stood (field frame, cm; YAW deg if known), one per image in order,\n"
         "or one for all")
      ->allow_extra_args(false)
      ->type_name("X,Y[,YAW]")
      ->check(CLI::Validator(pose_problem, ""))
      ->default_str("the field centre, heading unknown (searched, twins included)");
  app->add_option("--field", a->field_name, "geometry file or name in common/fields/")
      ->capture_default_str();
  app->add_option(
      "--overlay", a->overlay,
      "PNG of the frame with the detected line pixels and the field model at the fitted pose\n"
      "(frames after the first: OUT-2.png, OUT-3.png, ...)");
  app->add_option(
         "--debug-dir", a->debug_dir,
         "directory (created) for each step's picture per frame, STEM = the image's name without\n"
         "extension: STEM-1-disc.png, -2-carpet, -3-lines, -4-polar, -5-coarse (first frame),\n"
         "-6-residuals; written up to a failed step too")
      ->type_name("DIR");
  app->add_option("--carpet-at", a->carpet_at,
                  "a pixel that is carpet: its colour is the carpet's (when the carpet step fails)")
      ->type_name("X,Y");
  app->add_option("--center", a->centre,
                  "the mirror's centre in px (with --rim-radius: replaces the rim search)")
      ->type_name("X,Y");
  app->add_option("--rim-radius", a->rim_radius_px, "the mirror's rim radius in px (with --center)")
      ->type_name("PX")
      ->check(CLI::Range(16.0, 1e5));
  app->add_option("--mirrored", a->mirrored,
                  "the camera's handedness, when the frames do not tell it")
      ->check(CLI::IsMember({"yes", "no"}));
  return {app, [a] { return run_calibrate(*a); }};
}

}  // namespace omniloc::cli
