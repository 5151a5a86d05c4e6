// The venue sampler (omniloc_sim/venue.hpp) and `omniloc-sim venues`: a seed is a venue (same
// frames and truth byte for byte), the sampled parameters cover their ranges and stay in them,
// every mirror profile's mapping inverts and puts the field's lines where the rendered frame is
// bright, and the default look is today's realistic frame. Randomised tests print their seeds.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omniloc/conventions.hpp"
#include "omniloc/field.hpp"
#include "omniloc_sim/renderer.hpp"
#include "omniloc_sim/venue.hpp"
#include "run_command.hpp"
#include "temp_dir.hpp"

namespace omniloc {
namespace {

namespace fs = std::filesystem;
using sim::MirrorProfile;

constexpr MirrorProfile kProfiles[] = {MirrorProfile::kHyperbolic, MirrorProfile::kTangent,
                                       MirrorProfile::kSpherical, MirrorProfile::kConical};

// The first venue (seeds after `after`) with the profile: printed, so a failure can be rerun.
sim::Venue first_venue_with(MirrorProfile p, std::uint64_t after = 0) {
  for (std::uint64_t seed = after + 1;; ++seed) {
    sim::Venue v = sim::sample_venue(seed);
    if (v.optics.profile != p) continue;
    std::printf("%s: venue seed %llu (%dx%d, %s)\n", sim::mirror_profile_name(p),
                static_cast<unsigned long long>(seed), v.optics.width_px, v.optics.height_px,
                v.field_name.c_str());
    return v;
  }
}

double hue_deg(const cv::Vec3f& bgr) {
  cv::Mat3f px(1, 1, bgr / 255.0f), hsv;
  cv::cvtColor(px, hsv, cv::COLOR_BGR2HSV);
  return hsv(0, 0)[0];
}

TEST(Venues, TheDefaultLookIsTodaysColours) {
  // Today's constants written out: the defaults must be them, so the default frames do not change
  // (checked when the look became a struct: two frames' hashes before and after were equal).
  sim::SceneLook today;
  today.carpet = {70, 140, 35};
  today.line = {245, 232, 216};
  today.floor_beyond = {34, 32, 36};
  today.goal_blue = {190, 80, 20};
  today.goal_yellow = {30, 200, 230};
  today.ball = {20, 110, 250};
  today.robot_dark = {26, 25, 30};
  today.body = {52, 48, 48};
  today.lens = {14, 14, 16};
  today.rod = {24, 24, 27};
  today.ring = {9, 9, 10};
  today.housing = {58, 56, 62};
  today.ceiling = {190, 190, 196};
  today.walls = {{205, 208, 212}, {140, 132, 122}, {70, 64, 60}, {120, 150, 170}};
  const FieldGeometry field = load_field("fira-robosot");
  const sim::RealisticRenderer rr(field, sim::TrueOptics{});
  sim::RenderOptions def = sim::realistic(7), explicit_look = def;
  explicit_look.realism.look = today;
  const Pose2 pose{200.0, 300.0, 70.0};
  EXPECT_EQ(cv::norm(rr.render(pose, def), rr.render(pose, explicit_look), cv::NORM_INF), 0.0);
  EXPECT_EQ(sim::TrueOptics{}.profile, MirrorProfile::kHyperbolic);
  EXPECT_DOUBLE_EQ(sim::TrueOptics{}.lens_fraction, 0.35);
}

TEST(Venues, ASeedIsAVenueByteForByte) {
  for (const std::uint64_t seed : {sim::venue_seed(11, 0), sim::venue_seed(11, 1)}) {
    std::printf("venue seed %llu\n", static_cast<unsigned long long>(seed));
    const sim::Venue a = sim::sample_venue(seed), b = sim::sample_venue(seed);
    const sim::VenueShots sa = sim::render_venue(a), sb = sim::render_venue(b);
    ASSERT_EQ(sa.calib.size(), sb.calib.size());
    EXPECT_EQ(sa.calib.size(), cv::Size(a.optics.width_px, a.optics.height_px));
    EXPECT_EQ(cv::norm(sa.calib, sb.calib, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(sa.frame, sb.frame, cv::NORM_INF), 0.0);
    EXPECT_EQ(sim::venue_truth_json(a, sa, "f"), sim::venue_truth_json(b, sb, "f"));
    EXPECT_GT(cv::norm(sa.calib, sa.frame, cv::NORM_L1), 0.0);  // two poses, two frames
  }
  EXPECT_NE(sim::venue_seed(11, 0), sim::venue_seed(11, 1));
  EXPECT_NE(sim::venue_seed(11, 0), sim::venue_seed(12, 0));
}

TEST(Venues, MslEighteenByTwelveIsTheMslLayoutScaled) {
  const FieldSpec s = sim::msl_18x12_spec();
  const FieldSpec msl = load_field("robocup-msl").spec;
  EXPECT_EQ(s.field_length_cm, 1800.0);
  EXPECT_EQ(s.field_width_cm, 1200.0);
  EXPECT_EQ(s.line_width_cm, msl.line_width_cm);
  EXPECT_EQ(s.border_cm, msl.border_cm);
  EXPECT_EQ(s.goal, msl.goal);
  EXPECT_LT(s.penalty_area.width_cm, msl.penalty_area.width_cm);
  EXPECT_LT(s.centre_circle_radius_cm, msl.centre_circle_radius_cm);
  EXPECT_EQ(s.marks_from_centre_cm.size(), msl.marks_from_centre_cm.size());
  EXPECT_NO_THROW(build_field(s, "test"));
}

// What one venue must satisfy (venue.hpp's ranges).
void expect_in_ranges(const sim::Venue& v) {
  const sim::TrueOptics& o = v.optics;
  const sim::SceneLook& lk = v.render.realism.look;
  EXPECT_GE(o.width_px, 400);
  EXPECT_LE(o.width_px, 1280);
  EXPECT_GE(o.height_px, 400);
  EXPECT_LE(o.height_px, 1024);
  EXPECT_LE(std::abs(o.centre_px.x() - 0.5 * o.width_px), 0.1 * o.width_px + 1e-9);
  EXPECT_LE(std::abs(o.centre_px.y() - 0.5 * o.height_px), 0.1 * o.height_px + 1e-9);
  EXPECT_GE(o.tilt_deg, 0.0);
  EXPECT_LE(o.tilt_deg, 3.0);
  EXPECT_GE(v.body_fraction, 0.05);
  EXPECT_LE(v.body_fraction, 0.35);
  EXPECT_NEAR(o.radius_px_at_ground(o.body_radius_cm), v.body_fraction * o.mirror_radius_px,
              1e-6 * o.mirror_radius_px);
  EXPECT_LE(o.rods.size(), 4u);
  for (const auto& r : o.rods) {
    EXPECT_GE(r.width_px, 2.0);
    EXPECT_LE(r.width_px, 15.0);
  }
  EXPECT_GE(v.field.line_width_cm, 5.0);
  EXPECT_LE(v.field.line_width_cm, 12.5);
  const double hue = hue_deg(lk.carpet);  // green (120) .. teal .. blue-green (185)
  EXPECT_GE(hue, 105.0 - 1e-3);
  EXPECT_LE(hue, 185.0 + 1e-3);
  EXPECT_GT(lk.line[0], 200.0f);  // white, tinted
  const double rim_theta_deg = rad_to_deg(o.theta_rad_at_radius(o.mirror_radius_px));
  EXPECT_GE(rim_theta_deg, 80.0 - 1e-6);
  EXPECT_LE(rim_theta_deg, 105.0 + 1e-6);
  const sim::VenueShots s = sim::venue_poses(v);  // a known spot and a pose, both on the carpet
  EXPECT_TRUE(sim::on_look_carpet(v.field, lk, s.spot.position_cm));
  EXPECT_TRUE(sim::on_look_carpet(v.field, lk, {s.frame_pose.x_cm, s.frame_pose.y_cm}));
}

TEST(Venues, ThreeHundredSeedsCoverTheRangesAndStayInThem) {
  std::printf("venue seeds venue_seed(2026, 0..299)\n");
  std::set<MirrorProfile> profiles;
  std::set<bool> mirrored, lab, goals, textured, worn, light_floor, rim_out, jpeg;
  std::set<sim::VenueField> fields;
  std::set<std::size_t> rods;
  std::set<std::string> spots;
  double body_min = 1.0, body_max = 0.0, w_min = 1e9, w_max = 0.0, line_min = 1e9, line_max = 0.0,
         hue_min = 360, hue_max = 0;
  std::set<bool> square;
  for (std::uint64_t i = 0; i < 300; ++i) {
    const sim::Venue v = sim::sample_venue(sim::venue_seed(2026, i));
    SCOPED_TRACE("venue seed " + std::to_string(v.seed));
    expect_in_ranges(v);
    const sim::TrueOptics& o = v.optics;
    const sim::SceneLook& lk = v.render.realism.look;
    profiles.insert(o.profile);
    mirrored.insert(o.mirrored);
    fields.insert(v.field_kind);
    lab.insert(v.lab);
    goals.insert(lk.goals);
    rods.insert(o.rods.size());
    textured.insert(lk.carpet_patch_contrast > 0.0);
    worn.insert(lk.line_wear > 0.0);
    light_floor.insert(lk.floor_beyond[1] > 100.0f);
    jpeg.insert(v.render.realism.jpeg_quality > 0);
    square.insert(o.width_px == o.height_px);
    rim_out.insert(o.centre_px.x() - o.mirror_radius_px < 0 ||
                   o.centre_px.x() + o.mirror_radius_px > o.width_px ||
                   o.centre_px.y() - o.mirror_radius_px < 0 ||
                   o.centre_px.y() + o.mirror_radius_px > o.height_px);
    spots.insert(sim::venue_poses(v).spot.name);
    body_min = std::min(body_min, v.body_fraction);
    body_max = std::max(body_max, v.body_fraction);
    w_min = std::min<double>(w_min, o.width_px);
    w_max = std::max<double>(w_max, o.width_px);
    line_min = std::min(line_min, v.field.line_width_cm);
    line_max = std::max(line_max, v.field.line_width_cm);
    hue_min = std::min(hue_min, hue_deg(lk.carpet));
    hue_max = std::max(hue_max, hue_deg(lk.carpet));
  }
  std::printf(
      "body %.3f..%.3f, width %.0f..%.0f px, lines %.1f..%.1f cm, carpet hue %.0f..%.0f deg, spots "
      "%zu\n",
      body_min, body_max, w_min, w_max, line_min, line_max, hue_min, hue_max, spots.size());
  EXPECT_EQ(profiles.size(), 4u);
  EXPECT_EQ(fields.size(), 3u);
  EXPECT_EQ(rods.size(), 5u);  // 0, 1, 2, 3, 4
  for (const auto* s :
       {&mirrored, &lab, &goals, &textured, &worn, &light_floor, &rim_out, &jpeg, &square})
    EXPECT_EQ(s->size(), 2u);
  EXPECT_EQ(spots.size(), 3u);  // the centre spot and both penalty marks
  EXPECT_LT(body_min, 0.08);
  EXPECT_GT(body_max, 0.32);
  EXPECT_EQ(w_min, 400.0);
  EXPECT_EQ(w_max, 1280.0);
  EXPECT_LT(line_min, 6.0);
  EXPECT_GT(line_max, 11.5);
  EXPECT_LT(hue_min, 120.0);
  EXPECT_GT(hue_max, 170.0);
}

TEST(Venues, EveryProfileInvertsAndProjectsConsistently) {
  for (const MirrorProfile p : kProfiles) {
    const sim::TrueOptics o = first_venue_with(p).optics;
    SCOPED_TRACE(sim::mirror_profile_name(p));
    // ground_cm_at_radius inverts radius_px_at_ground, the radius grows with the distance.
    double last_r = 0.0;
    for (double d = 5.0; d < 2000.0; d *= 1.15) {
      const double r = o.radius_px_at_ground(d);
      EXPECT_GT(r, last_r);
      last_r = r;
      EXPECT_NEAR(o.ground_cm_at_radius(r), d, 1e-7 * d) << d;
      EXPECT_NEAR(o.theta_rad_at_radius(o.radius_px_at_theta(std::atan2(d, o.viewpoint_height_cm))),
                  std::atan2(d, o.viewpoint_height_cm), 1e-10);
    }
    // The tilted mapping: pixel_of_robot_point and ray_of_pixel are each other's inverse, on the
    // floor and up the walls.
    for (int b = 0; b < 360; b += 30) {
      for (const Eigen::Vector3d& q :
           {Eigen::Vector3d(150, 0, 0), Eigen::Vector3d(400, 0, 0), Eigen::Vector3d(300, 0, 120)}) {
        const double c = std::cos(deg_to_rad(b)), s = std::sin(deg_to_rad(b));
        const Eigen::Vector3d pt(c * q.x(), s * q.x(), q.z());
        const auto px = o.pixel_of_robot_point(pt);
        ASSERT_TRUE(px.has_value());
        EXPECT_NEAR((o.ray_of_pixel(*px) -
                     Eigen::Vector3d(pt.x(), pt.y(), o.viewpoint_height_cm - pt.z()).normalized())
                        .norm(),
                    0.0, 1e-9);
      }
    }
    // Untilted, a floor point lies at the radial mapping's radius.
    sim::TrueOptics flat = o;
    flat.tilt_deg = 0.0;
    EXPECT_NEAR((*flat.pixel_of_robot_point({0.0, 250.0, 0.0}) - flat.centre_px).norm(),
                flat.radius_px_at_ground(250.0), 1e-7);
  }
  // The tangent model's own formula, by hand: a = 80 cm, b = 0.004 / px: d(200 px) = 80 tan(0.8) =
  // 80 x 1.029639 = 82.371 cm.
  sim::TrueOptics t;
  t.profile = MirrorProfile::kTangent;
  t.tan_a_cm = 80.0;
  t.tan_b_per_px = 0.004;
  EXPECT_NEAR(t.ground_cm_at_radius(200.0), 82.371, 1e-3);
  EXPECT_TRUE(std::isnan(t.ground_cm_at_radius(400.0)));  // b r = 1.6 > pi / 2: above the horizon
}

// Line points of one venue, cleaned of what would hide the floor (robots, the ball, goals, worn
// lines, noise), at its two poses: how many were checked and how many were bright.
std::pair<int, int> line_points_bright(sim::Venue v) {
  sim::RenderOptions& r = v.render;
  r.noise_sigma = 0.0;
  r.realism.jpeg_quality = 0;
  r.realism.robots = 0;
  r.realism.ball = false;
  r.realism.look.goals = false;
  r.realism.look.line_wear = 0.0;
  const sim::TrueOptics& o = v.optics;
  const sim::RealisticRenderer rr(v.field, o);
  const sim::VenueShots shots = sim::venue_poses(v);
  int checked = 0, bright = 0;
  for (const Pose2& pose : {shots.calib_pose, shots.frame_pose}) {
    cv::Mat gray;
    cv::cvtColor(rr.render(pose, r), gray, cv::COLOR_BGR2GRAY);
    const auto pixel = [&](const Eigen::Vector2d& q) -> std::optional<Eigen::Vector2d> {
      const Eigen::Vector2d rel(q.x() - pose.x_cm, q.y() - pose.y_cm);
      const double c = std::cos(deg_to_rad(-pose.yaw_deg)), s = std::sin(deg_to_rad(-pose.yaw_deg));
      const double d = rel.norm();
      if (d < o.body_radius_cm + 30.0 || !sim::on_look_carpet(v.field, r.realism.look, q))
        return std::nullopt;
      const auto px =
          o.pixel_of_robot_point({c * rel.x() - s * rel.y(), s * rel.x() + c * rel.y(), 0.0});
      if (!px || px->x() < 3 || px->y() < 3 || px->x() > o.width_px - 4 ||
          px->y() > o.height_px - 4)
        return std::nullopt;
      const Eigen::Vector2d rc = *px - o.centre_px;
      if (rc.norm() > 0.9 * o.mirror_radius_px) return std::nullopt;
      for (const auto& rod : o.rods) {
        const Eigen::Vector2d e(std::cos(deg_to_rad(rod.image_angle_deg)),
                                -std::sin(deg_to_rad(rod.image_angle_deg)));
        if (rc.dot(e) > 0.0 && std::abs(e.x() * rc.y() - e.y() * rc.x()) < rod.width_px / 2.0 + 4.0)
          return std::nullopt;
      }
      // The line must cover three pixels radially, so blur and lateral colour leave its middle
      // white.
      const double rr_px = rc.norm();
      const double cm_per_px =
          o.ground_cm_at_radius(rr_px + 0.5) - o.ground_cm_at_radius(rr_px - 0.5);
      if (!(cm_per_px * 3.0 < v.field.line_width_cm * 0.7)) return std::nullopt;
      return px;
    };
    const auto level = [&](const Eigen::Vector2d& px) {
      return static_cast<int>(gray.at<std::uint8_t>(static_cast<int>(std::lround(px.y())),
                                                    static_cast<int>(std::lround(px.x()))));
    };
    for (const auto& seg : v.field.segments) {
      const Eigen::Vector2d ab = seg.b_cm - seg.a_cm, e = ab.normalized(), n(-e.y(), e.x());
      for (double t = 20.0; t < ab.norm() - 20.0; t += 15.0) {
        const Eigen::Vector2d q = seg.a_cm + t * e;
        const Eigen::Vector2d side = q + n * (2.5 * v.field.line_width_cm + 12.0);
        const auto pl = pixel(q), ps = pixel(side);
        if (!pl || !ps || is_white(v.field, side)) continue;
        ++checked;
        if (level(*pl) > level(*ps) + 20) ++bright;
      }
    }
  }
  return {checked, bright};
}

// For venues of each profile (until 40 points, at most 8 venues: a big field seen at a penalty mark
// shows few lines near enough to be wide in the image): points along the field's straight lines
// are brighter in the frame than the carpet a little to the side.
TEST(Venues, FieldLinesLandWhereEveryProfileProjectsThem) {
  for (const MirrorProfile p : kProfiles) {
    int checked = 0, bright = 0;
    std::uint64_t seed = 0;
    for (int k = 0; k < 8 && checked < 40; ++k) {
      const sim::Venue v = first_venue_with(p, seed);
      seed = v.seed;
      const auto [c, b] = line_points_bright(v);
      checked += c;
      bright += b;
    }
    std::printf("%s: %d of %d line points brighter than the carpet beside them\n",
                sim::mirror_profile_name(p), bright, checked);
    EXPECT_GE(checked, 30) << sim::mirror_profile_name(p);
    EXPECT_GE(bright, checked * 9 / 10) << sim::mirror_profile_name(p);
  }
}

int run(const std::string& cmd, const fs::path& log, std::string& output) {
  return omniloc::test::run_command(cmd, log, output);
}

TEST(VenuesCommand, WritesEachVenuesFramesAndTruth) {
  const test::TempDir tmp("venues_cmd");
  const fs::path out = tmp.path / "out";
  std::string text;
  ASSERT_EQ(run(std::string(OMNILOC_SIM_PATH) + " venues --count 3 --seed 5 --out " + out.string(),
                tmp.path / "log", text),
            0)
      << text;
  std::printf("%s", text.c_str());
  for (std::uint64_t i = 0; i < 3; ++i) {
    const std::uint64_t seed = sim::venue_seed(5, i);
    EXPECT_NE(text.find("venue " + std::to_string(i + 1) + "/3 seed " + std::to_string(seed)),
              std::string::npos);
    const fs::path dir = out / ("venue-" + std::to_string(seed));
    std::ifstream in(dir / "truth.json");
    ASSERT_TRUE(in.good()) << dir;
    const nlohmann::json truth = nlohmann::json::parse(in);
    const sim::Venue v = sim::sample_venue(seed);
    EXPECT_EQ(truth["seed"].get<std::uint64_t>(), seed);
    EXPECT_EQ(truth["field"]["name"], v.field_name);
    EXPECT_EQ(truth["optics"]["profile"], sim::mirror_profile_name(v.optics.profile));
    EXPECT_TRUE(truth["nominal_camera"]["camera"].contains("radius_lut"));
    EXPECT_TRUE(truth["known_spot"].contains("name"));
    EXPECT_TRUE(truth["frame_pose"].contains("yaw_deg"));
    const std::string field_file = truth["field"]["file"];
    if (!v.field_shipped) {
      EXPECT_TRUE(fs::exists(out / field_file)) << field_file;
    }
    for (const char* png : {"calib.png", "frame.png"}) {
      const cv::Mat img = cv::imread((dir / png).string());
      EXPECT_EQ(img.size(), cv::Size(v.optics.width_px, v.optics.height_px)) << png;
    }
  }
}

TEST(VenuesCommand, RefusesNoVenuesAndAnOutThatIsAFile) {
  const test::TempDir tmp("venues_bad");
  std::string text;
  EXPECT_EQ(
      run(std::string(OMNILOC_SIM_PATH) + " venues --count 0 --out " + (tmp.path / "o").string(),
          tmp.path / "log", text),
      2);
  EXPECT_NE(text.find("--count"), std::string::npos) << text;
  std::ofstream(tmp.path / "file") << "x";
  EXPECT_EQ(
      run(std::string(OMNILOC_SIM_PATH) + " venues --count 1 --out " + (tmp.path / "file").string(),
          tmp.path / "log", text),
      1);
  EXPECT_NE(text.find("not a directory"), std::string::npos) << text;
  EXPECT_EQ(run(std::string(OMNILOC_SIM_PATH) + " venues --count 1", tmp.path / "log", text), 2);
  EXPECT_NE(text.find("--out"), std::string::npos) << text;
  EXPECT_FALSE(fs::exists(tmp.path / "o"));
}

}  // namespace
}  // namespace omniloc
