// Field model: geometry files, white-line membership and ray intervals against hand-computed
// values.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "config_test_util.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/detail/config_reader.hpp"
#include "omniloc/field.hpp"

namespace omniloc {
namespace {

TEST(Field, FiraGeometryFileBuildsTheDocumentedLines) {
  const FieldGeometry f = load_field("fira-robosot");
  EXPECT_EQ(f.name, "fira-robosot");
  EXPECT_DOUBLE_EQ(f.total_x_cm(), 750.0);
  EXPECT_DOUBLE_EQ(f.total_y_cm(), 550.0);
  EXPECT_EQ(f.centre_cm(), Eigen::Vector2d(375.0, 275.0));
  // 4 boundary + centre line + 2 x (goal area 3 + penalty area 3).
  EXPECT_EQ(f.segments.size(), 17u);
  // 2 penalty arcs + centre circle + 4 corner arcs.
  EXPECT_EQ(f.arcs.size(), 7u);
  EXPECT_EQ(f.discs.size(), 4u);
}

TEST(Field, WhitePointsByHand) {
  const FieldGeometry f = load_field("fira-robosot");
  auto white = [&](double x, double y) { return is_white(f, Eigen::Vector2d(x, y)); };
  EXPECT_TRUE(white(375, 100));     // centre line
  EXPECT_TRUE(white(435, 275));     // centre circle, r 60
  EXPECT_TRUE(white(437.4, 275));   // inside the 5 cm line
  EXPECT_FALSE(white(437.6, 275));  // just outside it
  EXPECT_FALSE(white(300, 300));
  EXPECT_TRUE(white(75, 200));  // left boundary
  EXPECT_TRUE(white(72.6, 200));
  EXPECT_FALSE(white(72.4, 200));
  EXPECT_TRUE(white(115, 275));  // left goal area front (75 + 40)
  EXPECT_TRUE(white(150, 180));  // left penalty area side line at y = 275 - 100 = 175 (+- 2.5)
  EXPECT_TRUE(white(210, 275));  // left penalty arc: centre (150, 275), r 60, front half only
  EXPECT_FALSE(white(150 - 42.43, 275 + 42.43));             // the arc's back half is not drawn
  EXPECT_TRUE(white(75 + 25 * 0.70711, 75 + 25 * 0.70711));  // corner arc r 25
  EXPECT_TRUE(white(300, 175));                              // mark at centre + (-75, -100), r 5
  EXPECT_FALSE(white(305.5, 175));
  EXPECT_TRUE(on_carpet(f, {0, 0}));
  EXPECT_TRUE(on_carpet(f, {750, 550}));
  EXPECT_FALSE(on_carpet(f, {750.1, 300}));
}

TEST(Field, RayIntervalsByHand) {
  const FieldGeometry f = load_field("fira-robosot");
  std::vector<WhiteInterval> iv;
  // From (200, 275) along +x: left penalty arc at x 210, centre circle at 315 and 435, centre line
  // at 375, right penalty arc at 540 (centre 600, r 60), right penalty area front at 600, right
  // goal area front at 635.
  white_intervals(f, {200, 275}, {1, 0}, 0.0, 450.0, iv);
  const double expected[][2] = {{7.5, 12.5},    {112.5, 117.5}, {172.5, 177.5}, {232.5, 237.5},
                                {337.5, 342.5}, {397.5, 402.5}, {432.5, 437.5}};
  ASSERT_EQ(iv.size(), 7u);
  for (std::size_t i = 0; i < iv.size(); ++i) {
    EXPECT_NEAR(iv[i].enter_cm, expected[i][0], 1e-9) << i;
    EXPECT_NEAR(iv[i].exit_cm, expected[i][1], 1e-9) << i;
  }
  // Standing on the centre line, looking along it (+y): white from t_min, the boundary is the
  // same white region, so one merged interval from 0 to the far edge of the top boundary line.
  white_intervals(f, {375, 300}, {0, 1}, 0.0, 400.0, iv);
  ASSERT_EQ(iv.size(), 1u);
  EXPECT_DOUBLE_EQ(iv[0].enter_cm, 0.0);
  EXPECT_NEAR(iv[0].exit_cm, 177.5, 1e-9);
}

TEST(Field, RayIntervalsAgreeWithPointSamplingEverywhere) {
  // Independent check of the analytic ray casting: sample is_white every 0.05 cm along rays.
  const FieldGeometry f = load_field("fira-robosot");
  std::vector<WhiteInterval> iv;
  int checked = 0;
  for (double x = 30; x < 750; x += 97.3) {
    for (double y = 20; y < 550; y += 83.1) {
      for (int k = 0; k < 360; k += 23) {
        const Eigen::Vector2d o(x, y),
            u(std::cos(k * 3.14159265358979 / 180), std::sin(k * 3.14159265358979 / 180));
        white_intervals(f, o, u, 10.0, 300.0, iv);
        for (double t = 10.0; t <= 300.0; t += 0.05) {
          bool in = false, near_edge = false;
          for (const auto& w : iv) {
            in = in || (t >= w.enter_cm && t <= w.exit_cm);
            near_edge =
                near_edge || std::abs(t - w.enter_cm) < 1e-6 || std::abs(t - w.exit_cm) < 1e-6;
          }
          if (near_edge) continue;
          ASSERT_EQ(in, is_white(f, o + t * u))
              << "ray from (" << x << ", " << y << ") at " << k << " deg, t " << t;
          ++checked;
        }
      }
    }
  }
  EXPECT_GT(checked, 500000);
}

// The line walk that the overlays and calibrate's self-check share: every point lies on a white
// line, consecutive points of one line are at most the step apart, and the count is the lines'
// length over the step (centre circle, arcs and segments, hand-summed for the FIRA field).
TEST(Field, LinePointsLieOnTheLinesAtTheStep) {
  const FieldGeometry field = load_field("fira-robosot");
  double length_cm = 0.0;
  for (const auto& s : field.segments) length_cm += (s.b_cm - s.a_cm).norm();
  for (const auto& a : field.arcs) length_cm += deg_to_rad(a.end_deg - a.start_deg) * a.radius_cm;
  const std::size_t pieces = field.segments.size() + field.arcs.size();
  for (const double step : {0.5, 2.0}) {
    std::vector<Eigen::Vector2d> pts;
    for_each_line_point(field, step, [&](const Eigen::Vector2d& q) { pts.push_back(q); });
    int off = 0;
    for (const auto& q : pts) off += !is_white(field, q);
    EXPECT_EQ(off, 0) << step;
    // n = ceil(len / step) + 1 per piece: between len / step + 1 and len / step + 2 per piece.
    EXPECT_GE(static_cast<double>(pts.size()), length_cm / step + static_cast<double>(pieces))
        << step;
    EXPECT_LE(static_cast<double>(pts.size()), length_cm / step + 2.0 * static_cast<double>(pieces))
        << step;
    std::printf("step %.1f cm: %zu points over %.0f cm of lines in %zu pieces\n", step, pts.size(),
                length_cm, pieces);
  }
}

TEST(Field, WhiteLineIndexAgreesWithIsWhite) {
  for (const char* name : {"fira-robosot", "robocup-msl"}) {
    const FieldGeometry f = load_field(name);
    const WhiteLineIndex index(f);
    int white = 0;
    for (double x = -20.0; x < f.total_x_cm() + 20.0; x += 0.37) {
      for (double y = -20.0; y < f.total_y_cm() + 20.0; y += 1.13) {
        const bool expected = is_white(f, {x, y});
        ASSERT_EQ(index.is_white({x, y}), expected) << name << " (" << x << ", " << y << ")";
        white += expected;
      }
    }
    EXPECT_GT(white, 1000) << name;
  }
}

TEST(Field, RoboCupMslIsASecondGeometry) {
  const FieldGeometry m = load_field("robocup-msl");
  EXPECT_DOUBLE_EQ(m.total_x_cm(), 2400.0);
  EXPECT_DOUBLE_EQ(m.total_y_cm(), 1600.0);
  EXPECT_EQ(m.arcs.size(), 5u);  // no penalty arcs: centre circle + 4 corners
  EXPECT_EQ(m.discs.size(), 3u);
  EXPECT_TRUE(is_white(m, {1200 + 200, 800}));  // centre circle r 200
  EXPECT_TRUE(is_white(m, {100 + 225, 800}));   // penalty area front
  EXPECT_TRUE(is_white(m, {100 + 6.0, 500}));   // 12.5 cm boundary line
  EXPECT_FALSE(is_white(m, {100 + 6.5, 500}));
  EXPECT_NE(m.fingerprint(), load_field("fira-robosot").fingerprint());
}

// --- geometry files
// ---------------------------------------------------------------------------------

using test::error_of;
using test::replaced;

const std::vector<std::string> kEveryKey = {"name",
                                            "description",
                                            "units",
                                            "field_length_cm",
                                            "field_width_cm",
                                            "border_cm",
                                            "line_width_cm",
                                            "centre_circle_radius_cm",
                                            "goal",
                                            "goal_area",
                                            "penalty_area",
                                            "penalty_arc",
                                            "corner_arc_radius_cm",
                                            "marks"};

std::string fira_text() {
  std::ifstream in(resolve_data_file("fields", "fira-robosot"));
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

TEST(FieldFile, ShippedFilesHaveEveryKey) {
  for (const char* name : {"fira-robosot", "robocup-msl"}) {
    const auto json = test::read_json(resolve_data_file("fields", name));
    EXPECT_EQ(test::keys_of(json), kEveryKey) << name;
  }
}

TEST(FieldFile, EveryKeyReachesItsMember) {
  const std::string file =
      test::write_file("f.json", R"({"name": "test-field", "description": "d", "units": "cm",
      "field_length_cm": 900, "field_width_cm": 600, "border_cm": 50, "line_width_cm": 8,
      "centre_circle_radius_cm": 75, "goal": {"width_cm": 120, "depth_cm": 40, "colour_at_x_max": "yellow"},
      "goal_area": {"depth_cm": 50, "width_cm": 250},
      "penalty_area": {"depth_cm": 150, "width_cm": 400}, "penalty_arc": {"radius_cm": 40, "centre_from_goal_line_cm": 120},
      "corner_arc_radius_cm": 30, "marks": {"radius_cm": 6, "from_centre_cm": [[200, 50], [-200, -50]]}})")
          .string();
  const FieldSpec s = parse_field_spec(config::parse_json_file(file).root());
  EXPECT_EQ(s.name, "test-field");
  EXPECT_EQ(s.field_length_cm, 900.0);
  EXPECT_EQ(s.field_width_cm, 600.0);
  EXPECT_EQ(s.border_cm, 50.0);
  EXPECT_EQ(s.line_width_cm, 8.0);
  EXPECT_EQ(s.centre_circle_radius_cm, 75.0);
  EXPECT_EQ(s.goal.width_cm, 120.0);
  EXPECT_EQ(s.goal.depth_cm, 40.0);
  EXPECT_EQ(s.goal.colour_at_x_max, GoalColour::kYellow);
  EXPECT_EQ(s.goal_area.depth_cm, 50.0);
  EXPECT_EQ(s.goal_area.width_cm, 250.0);
  EXPECT_EQ(s.penalty_area.depth_cm, 150.0);
  EXPECT_EQ(s.penalty_area.width_cm, 400.0);
  EXPECT_EQ(s.penalty_arc.radius_cm, 40.0);
  EXPECT_EQ(s.penalty_arc.centre_from_goal_line_cm, 120.0);
  EXPECT_EQ(s.corner_arc_radius_cm, 30.0);
  EXPECT_EQ(s.mark_radius_cm, 6.0);
  ASSERT_EQ(s.marks_from_centre_cm.size(), 2u);
  EXPECT_EQ(s.marks_from_centre_cm[0], Eigen::Vector2d(200, 50));
  EXPECT_EQ(s.marks_from_centre_cm[1], Eigen::Vector2d(-200, -50));
  // And the lines built from them, by hand: centre (50 + 450, 50 + 300); marks at +-(200, 50).
  const FieldGeometry f = load_field(file);
  EXPECT_EQ(f.name, "test-field");
  EXPECT_EQ(f.goal, s.goal);
  EXPECT_EQ(f.source, file);
  EXPECT_DOUBLE_EQ(f.total_x_cm(), 1000.0);
  EXPECT_DOUBLE_EQ(f.total_y_cm(), 700.0);
  EXPECT_EQ(f.segments.size(), 17u);
  EXPECT_EQ(f.arcs.size(), 7u);
  ASSERT_EQ(f.discs.size(), 2u);
  EXPECT_EQ(f.discs[0].centre_cm, Eigen::Vector2d(700, 400));
  EXPECT_EQ(f.discs[1].radius_cm, 6.0);
  EXPECT_TRUE(is_white(f, {500 + 75, 350}));  // centre circle r 75
  EXPECT_TRUE(is_white(f, {50 + 50, 350}));   // left goal area front at x 50 + 50
  EXPECT_TRUE(is_white(f, {50 + 160, 350}));  // left penalty arc: centre 50 + 120, r 40
}

TEST(FieldFile, ErrorsNameFileAndFieldPath) {
  const std::string v = fira_text();
  test::expect_errors(
      [](const std::string& f) { (void)load_field(f); },
      {
          {replaced(v, "\"line_width_cm\": 5", "\"line_width_cm\": -5"), "line_width_cm",
           "must be > 0 (got -5)"},
          // Issue 16 item 6: a line 10 m wide was accepted; a length of 1e7 cm ended in
          // std::bad_alloc (with no file named) when the database was laid over it.
          {replaced(v, "\"line_width_cm\": 5", "\"line_width_cm\": 1000"), "line_width_cm",
           "must be at most 50 cm (got 1000)"},
          {replaced(v, "\"field_length_cm\": 600", "\"field_length_cm\": 1e7"), "field_length_cm",
           "must be at most 5000 cm (50 m) (got 10000000)"},
          {replaced(v, "\"field_width_cm\": 400", "\"field_width_cm\": 1e7"), "field_width_cm",
           "must be at most 5000 cm (50 m)"},
          {replaced(v, "\"border_cm\": 75", "\"border_cm\": 1e6"), "border_cm",
           "must be at most 1000 cm"},
          {replaced(v, "\"field_length_cm\": 600,", ""), "field_length_cm", "missing (required)"},
          {replaced(v, "\"centre_circle_radius_cm\": 60", "\"centre_circle_radius_cm\": \"big\""),
           "centre_circle_radius_cm", "must be a number, not a string (got \"big\")"},
          {replaced(v, "\"depth_cm\": 75", "\"depth_cm\": 400"), "penalty_area.depth_cm",
           "must be < field_length_cm / 2 (got 400)"},
          {replaced(v, "\"depth_cm\": 75", "\"depth_cm\": 75, \"depth\": 1"), "penalty_area.depth",
           "unknown key"},
          {replaced(v, "[75, 100]", "[75]"), "marks.from_centre_cm[0]",
           "must be an array of 2 elements"},
          {replaced(v, "[75, 100]", "[375, 100]"), "marks.from_centre_cm[0]",
           "outside the playing area (got [375, 100])"},
          {replaced(v, "\"units\": \"cm\"", "\"units\": \"mm\""), "units",
           "the only unit is \"cm\""},
          {replaced(v, "\"border_cm\": 75", "\"border_cm\": true"), "border_cm", "not a boolean"},
          {replaced(v, "\"border_cm\": 75", "\"border_cm\": NaN"), "border_cm", "not valid JSON"},
          {replaced(v, "\"border_cm\": 75", "\"border_cm\": 1e400"), "border_cm",
           "number out of range"},
          {replaced(v, "\"border_cm\": 75", "\"border_cm\": 75, \"border_cm\": 76"), "border_cm",
           "duplicate key"},
          {replaced(v, "\"border_cm\": 75", "\"border_cm\": 75, \"border\": 76"), "border",
           "unknown key"},
          {replaced(v, "\"width_cm\": 100", "\"width_cm\": 0"), "goal.width_cm",
           "must be > 0 (got 0)"},
          {replaced(v, "\"depth_cm\": 30", "\"depth_cm\": 80"), "goal.depth_cm",
           "must be <= border_cm (got 80)"},
          {replaced(v, "\"depth_cm\": 30", "\"depth_cm\": 30, \"colour_at_x_max\": \"red\""),
           "goal.colour_at_x_max", "must be one of \"blue\", \"yellow\""},
          {replaced(v, "\"goal\": { \"width_cm\": 100, \"depth_cm\": 30 },", ""), "goal",
           "missing (required)"},
          {"{ \"name\": \"x\", ", "", "not valid JSON"},
      });
  EXPECT_THROW((void)load_field("no-such-field"), ConfigError);
  EXPECT_NE(error_of([] { (void)load_field("no-such-field"); }).find("no-such-field"),
            std::string::npos);
}

TEST(FieldFile, ShippedGoalsAndTheirColourAreKnownOrAbsent) {
  const FieldGeometry f = load_field("fira-robosot");
  EXPECT_EQ(f.goal.width_cm, 100.0);
  EXPECT_EQ(f.goal.depth_cm, 30.0);
  EXPECT_EQ(f.goal.colour_at_x_max, GoalColour::kUnknown);  // learnt at calibration
  const std::string blue =
      test::write_file("g.json", replaced(fira_text(), "\"depth_cm\": 30",
                                          "\"depth_cm\": 30, \"colour_at_x_max\": \"blue\""))
          .string();
  EXPECT_EQ(load_field(blue).goal.colour_at_x_max, GoalColour::kBlue);
  EXPECT_EQ(load_field(blue).fingerprint(), f.fingerprint());  // goals are not lines
}

TEST(FieldFile, MissingFileAndDirectoryAreNamed) {
  EXPECT_EQ(error_of([] { (void)load_field("/nonexistent/f.json"); }),
            "/nonexistent/f.json: no such file");
  const std::string dir = test::temp_dir().string();
  EXPECT_EQ(error_of([&] { (void)load_field(dir); }), dir + ": is a directory, not a JSON file");
}

}  // namespace
}  // namespace omniloc
