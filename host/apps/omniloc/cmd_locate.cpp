// `omniloc locate IMAGE --camera CAMERA.json`: one frame to a pose by exactly the localizer's
// global search and acceptance rule (locate_frame, shared with Localizer), with the goal colours
// telling a pose from its twin; prints the result (or one JSON object) and draws an overlay.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "commands.hpp"
#include "omniloc/feature_db.hpp"
#include "omniloc/field.hpp"
#include "omniloc/goals.hpp"
#include "omniloc/image_file.hpp"
#include "omniloc/locate.hpp"
#include "omniloc/recording.hpp"
#include "omniloc/vision.hpp"

namespace omniloc::cli {

namespace {

struct LocateArgs {
  std::string image, camera, field = "fira-robosot", db, config = "default", overlay;
  std::optional<double> yaw_deg;
  bool json = false;
};

FeatureDb feature_db_for(const LocateArgs& a, const FieldGeometry& field,
                         const CameraModel& camera) {
  auto log = [](const std::string& s) { std::fprintf(stderr, "%s\n", s.c_str()); };
  if (!a.db.empty()) return load_or_build_feature_db(field, camera, a.db, log);
  const GridSpec grid =
      GridSpec::covering(field, 10.0);  // the grid load_or_build_feature_db builds
  return build_feature_db(field, camera, grid, [](int done, int total) {
    std::fprintf(stderr, "\rbuilding the feature database: %5d / %d grid points (%3d %%)", done,
                 total, 100 * done / total);
    if (done == total) std::fprintf(stderr, "\n");
  });
}

nlohmann::ordered_json number_or_null(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

nlohmann::ordered_json result_json(const SingleFrameResult& r, double time_ms) {
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  const bool found = r.match.cell >= 0;
  out["x_cm"] = found ? nlohmann::ordered_json(r.pose.x_cm) : nlohmann::ordered_json(nullptr);
  out["y_cm"] = found ? nlohmann::ordered_json(r.pose.y_cm) : nlohmann::ordered_json(nullptr);
  out["yaw_deg"] = found ? nlohmann::ordered_json(r.pose.yaw_deg) : nlohmann::ordered_json(nullptr);
  out["match_error"] = number_or_null(r.match.error);
  out["accepted"] = r.accepted;
  out["ambiguous"] = r.ambiguous;
  out["heading_ambiguous"] = r.heading_ambiguous;
  out["twin"] = r.twin ? nlohmann::ordered_json{{"x_cm", r.twin->x_cm},
                                                {"y_cm", r.twin->y_cm},
                                                {"yaw_deg", r.twin->yaw_deg}}
                       : nlohmann::ordered_json(nullptr);
  out["rays_used"] = r.match.rays_used;
  out["time_ms"] = time_ms;
  out["goal_cue"] = r.goal_choice.reason;
  return out;
}

void print_text(const SingleFrameResult& r, double e_th, double time_ms) {
  if (r.match.cell < 0) {
    std::printf("no match (no ray seen anything)\n");
    return;
  }
  std::printf("pose (%.1f, %.1f) cm, yaw %.1f deg%s; match error %.2f (E_TH %.2f) on %d rays: %s\n",
              r.pose.x_cm, r.pose.y_cm, r.pose.yaw_deg, r.yaw_searched ? " (found)" : " (given)",
              r.match.error, e_th, r.match.rays_used,
              r.accepted                            ? "accepted"
              : r.ambiguous && r.match.error < e_th ? "refused (ambiguous)"
                                                    : "not accepted");
  if (r.twin)
    std::printf("twin (%.1f, %.1f) cm, yaw %.1f deg, error %.2f: %s\n", r.twin->x_cm, r.twin->y_cm,
                r.twin->yaw_deg, r.twin_error,
                r.ambiguous ? "not told apart" : "ruled out by the goal colours");
  std::printf("goal colours: %s\n", r.goal_choice.reason.c_str());
  std::printf("located in %.1f ms\n", time_ms);
}

int run_locate(const LocateArgs& a) {
  cv::Mat bgr;
  try {
    bgr = read_image_file(a.image);  // the size from the header first, refused above the limits
  } catch (const ImageFileError& e) {
    std::fprintf(stderr, "omniloc locate: error: cannot read image: %s\n", e.what());
    return 1;
  }
  struct {
    CameraModel camera;
    GoalColourModels goals;
  } cam{load_camera(a.camera), {}};
  cam.goals = goal_colour_models(cam.camera.vision);
  if (bgr.cols != cam.camera.width_px || bgr.rows != cam.camera.height_px) {
    std::fprintf(
        stderr,
        "omniloc locate: error: image '%s' is %d x %d px but camera '%s' is for %d x %d px\n",
        a.image.c_str(), bgr.cols, bgr.rows, a.camera.c_str(), cam.camera.width_px,
        cam.camera.height_px);
    return 1;
  }
  const FieldGeometry field = load_field(a.field);
  const LocalizerConfig config = load_localizer_config(a.config);
  const FeatureDb db = feature_db_for(a, field, cam.camera);

  const auto t0 = std::chrono::steady_clock::now();
  // The frame as Localizer::on_image takes it: the line extraction (a frame with nothing usable is
  // "no measurement", never a pose), the goal observation, then the shared global search.
  LineExtractor extractor(cam.camera);
  ExtractionReport extraction;
  const BearingScan bearings = extractor.extract(bgr, config.scan_rays_per_degree, &extraction);
  const GoalObservation goals = observe_goals(bgr, cam.camera, field, cam.goals);
  SingleFrameResult r;
  if (extraction.usable)
    r = locate_frame(config, field, cam.camera, db, bearings, a.yaw_deg, &goals);
  const double time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  if (a.json) {
    nlohmann::ordered_json j = result_json(r, time_ms);
    if (!extraction.usable) j["no_measurement"] = extraction.reason;
    std::printf("%s\n", j.dump().c_str());
  } else if (!extraction.usable) {
    std::printf("no measurement: %s\n", extraction.reason.c_str());
  } else {
    print_text(r, config.e_th, time_ms);
  }
  if (!a.overlay.empty()) {
    const cv::Mat ov = locate_overlay(bgr, cam.camera, field, {&bearings, &r, &goals});
    if (!cv::imwrite(a.overlay, ov)) {
      std::fprintf(stderr, "omniloc locate: error: cannot write overlay '%s'\n", a.overlay.c_str());
      return 1;
    }
    if (!a.json) std::printf("overlay %s\n", a.overlay.c_str());
  }
  return 0;
}

}  // namespace

Subcommand add_locate(CLI::App& program) {
  CLI::App* app = program.add_subcommand(
      "locate",
      "one frame to a pose: the localizer's global search and acceptance, JSON and overlay");
  auto a = std::make_shared<LocateArgs>();
  app->add_option("IMAGE", a->image, "the frame (PNG, JPEG)")->required();
  app->add_option(
         "--camera", a->camera,
         "camera file or name in common/cameras/ (its size must be the image's); its optional\n"
         "\"vision\" block's goal colours tell a pose from its twin")
      ->required();
  app->add_option("--field", a->field, "geometry file or name in common/fields/")
      ->capture_default_str();
  add_number_callback<double>(
      *app, "--yaw-deg", [a](double v) { a->yaw_deg = v; },
      "the robot's heading if known (field frame, deg)", -360.0, 360.0)
      ->default_str("unknown: every heading searched");
  app->add_option("--db", a->db,
                  "feature database file: used if it matches the field and camera, else built and "
                  "written there")
      ->default_str("built in memory, progress on stderr");
  app->add_option("--config", a->config,
                  "localizer config (E_TH, refinement, ambiguity refusal), name in "
                  "common/localizer/ or path")
      ->capture_default_str();
  app->add_option(
      "--overlay", a->overlay,
      "PNG of the frame with the rays, crossings, ray ends and the field model at the pose");
  app->add_flag(
      "--json", a->json,
      "print one JSON object: x_cm, y_cm, yaw_deg, match_error, accepted, ambiguous, twin,\n"
      "rays_used, time_ms (and goal_cue: the goal colours' verdict)");
  app->footer(
      "Exit 0 with a pose (accepted or not), 1 for an unreadable image or a camera of another "
      "size, 2 usage.");
  return {app, [a] { return run_locate(*a); }};
}

}  // namespace omniloc::cli
