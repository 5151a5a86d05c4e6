// `omniloc calibrate`: estimates the camera (centre, radial model, yaw offset, mirroring, view
// radius, body and mast mask) and the venue's colours (carpet, lines, goals: the "vision" block)
// from frames taken at known positions, writes the camera file and an overlay of the field model
// at the fitted pose.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "commands.hpp"
#include "omniloc/calibration.hpp"
#include "omniloc/field.hpp"

namespace omniloc::cli {

namespace {
void calibrate_usage(std::FILE* out) {
  std::fprintf(out,
               "usage: omniloc calibrate IMAGE... --out CAMERA.json [--pose X,Y[,YAW]]... [--field NAME|PATH]\n"
               "                         [--overlay OUT.png]\n"
               "  --pose     where the robot stood (field frame, cm; YAW deg if known), one per image in order,\n"
               "             or one for all; default: the field centre, heading unknown (searched, twins included)\n"
               "  --field    geometry file or name in common/fields/ (default fira-robosot)\n"
               "  --overlay  PNG of the frame with the detected line pixels and the field model at the fitted\n"
               "             pose (frames after the first: OUT-2.png, OUT-3.png, ...)\n");
}

bool parse_pose(std::string_view text, CalibrationFrame& f) {
  std::vector<double> v;
  std::string s(text);
  std::size_t start = 0;
  while (start <= s.size()) {
    const std::size_t comma = s.find(',', start);
    const std::string part = s.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    char* end = nullptr;
    const double x = std::strtod(part.c_str(), &end);
    if (part.empty() || end != part.c_str() + part.size()) return false;
    v.push_back(x);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (v.size() != 2 && v.size() != 3) return false;
  f.position_cm = {v[0], v[1]};
  if (v.size() == 3) f.yaw_deg = v[2];
  return true;
}

std::string numbered(const std::string& path, std::size_t i) {
  if (i == 0) return path;
  const std::size_t dot = path.rfind('.');
  std::string n = "-";
  n += std::to_string(i + 1);  // (not "-" + ...: GCC 12 warns -Wrestrict on it)
  return dot == std::string::npos ? path + n : path.substr(0, dot) + n + path.substr(dot);
}
}  // namespace

int cmd_calibrate(std::span<const std::string_view> args) {
  std::string field_name = "fira-robosot", out, overlay;
  std::vector<std::string> images;
  std::vector<CalibrationFrame> poses;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string_view a = args[i];
    if (a == "-h" || a == "--help") {
      calibrate_usage(stdout);
      return 0;
    }
    if (!a.starts_with("--")) {
      images.emplace_back(a);
      continue;
    }
    if (i + 1 >= args.size()) {
      std::fprintf(stderr, "omniloc calibrate: '%.*s' needs a value\n", static_cast<int>(a.size()), a.data());
      calibrate_usage(stderr);
      return 2;
    }
    const std::string_view v = args[++i];
    if (a == "--field") {
      field_name = v;
    } else if (a == "--out") {
      out = v;
    } else if (a == "--overlay") {
      overlay = v;
    } else if (a == "--pose") {
      CalibrationFrame f;
      if (!parse_pose(v, f)) {
        std::fprintf(stderr, "omniloc calibrate: bad --pose '%.*s' (expected X,Y or X,Y,YAW)\n", static_cast<int>(v.size()),
                     v.data());
        return 2;
      }
      poses.push_back(f);
    } else {
      std::fprintf(stderr, "omniloc calibrate: unknown option '%.*s'\n", static_cast<int>(a.size()), a.data());
      calibrate_usage(stderr);
      return 2;
    }
  }
  if (images.empty() || out.empty()) {
    std::fprintf(stderr, "omniloc calibrate: at least one IMAGE and --out CAMERA.json are required\n");
    calibrate_usage(stderr);
    return 2;
  }
  if (!poses.empty() && poses.size() != 1 && poses.size() != images.size()) {
    std::fprintf(stderr, "omniloc calibrate: %zu --pose for %zu images (give one per image, or one for all)\n", poses.size(),
                 images.size());
    return 2;
  }
  const FieldGeometry field = load_field(field_name);
  std::vector<CalibrationFrame> frames;
  for (std::size_t i = 0; i < images.size(); ++i) {
    CalibrationFrame f;
    if (!poses.empty()) f = poses[poses.size() == 1 ? 0 : i];
    else f.position_cm = field.centre_cm();
    f.name = images[i];
    f.image = cv::imread(images[i], cv::IMREAD_COLOR);
    if (f.image.empty()) {
      std::fprintf(stderr, "omniloc calibrate: error: cannot read image '%s'\n", images[i].c_str());
      return 1;
    }
    std::printf("%s: %d x %d, robot at (%.1f, %.1f) cm, heading %s\n", f.name.c_str(), f.image.cols, f.image.rows,
                f.position_cm.x(), f.position_cm.y(), f.yaw_deg ? std::to_string(*f.yaw_deg).c_str() : "unknown");
    frames.push_back(std::move(f));
  }
  const auto t0 = std::chrono::steady_clock::now();
  CalibrationOptions opt;
  opt.progress = [t0](const std::string& m) {
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr, "[%6.2f s] %s\n", s, m.c_str());
  };
  const CalibrationResult r = calibrate_camera(frames, field, opt);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  {
    std::ofstream f(out);
    f << calibrated_camera_json(r, frames);
    if (!f) {
      std::fprintf(stderr, "omniloc calibrate: error: cannot write '%s'\n", out.c_str());
      return 1;
    }
  }
  (void)load_camera(out);  // read back with the project's reader
  const CameraModel& c = r.camera;
  std::printf("centre (%.2f, %.2f) px (rim (%.2f, %.2f) r %.1f px on %d/360 rays)\n", c.center_px.x(), c.center_px.y(),
              r.rim.centre_px.x(), r.rim.centre_px.y(), r.rim.radius_px, r.rim.rays_on_circle);
  std::printf("radial model d(r) = %.6g r + %.6g r^2 + %.6g r^3 + %.6g r^4 cm; d(50) %.1f, d(100) %.1f, d(view) %.1f cm\n",
              r.radial.a[0], r.radial.a[1], r.radial.a[2], r.radial.a[3], r.radial.ground_cm(50), r.radial.ground_cm(100),
              r.radial.ground_cm(r.view_radius_px));
  std::printf("yaw offset %.2f deg%s, mirrored %s%s\n", c.yaw_offset_deg,
              r.yaw_offset_ambiguous ? " (or 180 deg more: the view is symmetric; add a frame off the centre to tell)" : "",
              c.mirrored ? "yes" : "no", r.mirrored_ambiguous ? " (ambiguous: the other handedness fits as well)" : "");
  std::printf("view radius %.1f px, body radius %.1f px, %zu mast(s):", r.view_radius_px, c.body_radius_px, c.masts.size());
  for (const auto& m : c.masts) std::printf(" %.1f+-%.1f deg", m.bearing_deg, m.half_width_deg);
  std::printf("\n");
  for (const auto& [name, g] : {std::pair{"blue", &r.goals.blue}, std::pair{"yellow", &r.goals.yellow}}) {
    if (*g) {
      std::printf("%s goal: hue %.0f +- %.0f, S >= %.0f, V >= %.0f (%d px)\n", name, (*g)->colour.hue,
                  (*g)->colour.hue_half_width, (*g)->colour.sat_min, (*g)->colour.val_min, (*g)->pixels);
    } else {
      std::printf("%s goal: not seen\n", name);
    }
  }
  std::printf("goal colour at x = max: %s\n", goal_colour_name(r.goal_colour_at_x_max));
  for (std::size_t i = 0; i < r.fits.size(); ++i) {
    const auto& f = r.fits[i];
    std::printf("%s: heading %.2f deg%s, %d line pixels, %d within %.0f px: rms %.2f px (%.2f cm), median %.2f px\n",
                frames[i].name.c_str(), f.yaw_deg, f.yaw_given ? " (given)" : " (found, yaw offset taken for heading 0)",
                f.line_pixels, f.inliers, r.inlier_threshold_px, f.rms_px, f.rms_cm, f.median_px);
  }
  const auto& f0 = r.fits.front();
  std::printf("%s: coarse score %.2f px at heading %.1f deg; best distinct heading %.1f deg scores %.2f px%s\n",
              frames.front().name.c_str(), f0.score, f0.yaw_deg, f0.twin_yaw_deg, f0.twin_score,
              f0.twin_score < 1.1 * f0.score ? " (a twin: the heading is not told apart)" : "");
  std::printf("residual rms %.2f px (%.2f cm) over %.0f %% of the line pixels; wrote %s in %.2f s\n", r.rms_px, r.rms_cm,
              100 * r.inlier_fraction, out.c_str(), seconds);
  if (!overlay.empty()) {
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const std::string p = numbered(overlay, i);
      if (!cv::imwrite(p, calibration_overlay(frames[i], r.analyses[i], r.fits[i], r, field))) {
        std::fprintf(stderr, "omniloc calibrate: error: cannot write overlay '%s'\n", p.c_str());
        return 1;
      }
      std::printf("overlay %s\n", p.c_str());
    }
  }
  return 0;
}

}  // namespace omniloc::cli
