// The image analysis (analyse_frame's carpet mask and line pixels, measure_goal_colours' regions)
// on the two RoboCup Junior frames against masks drawn by hand for them (issue 38, item 5):
// tests/data/rcj-omicam-*.masks.json, polygons and polylines in image pixels read off zoomed,
// gridded crops of the frames by eye (never from the analysis). Every figure is printed; each is
// bounded by a floor a little below what was measured, so a regression of the analysis fails here.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omniloc/calibration.hpp"
#include "test_data_path.hpp"

namespace omniloc {
namespace {

using nlohmann::json;
using test::test_data;

// A detected line pixel and a hand line match when they are this close (px): the hand polylines
// are read to a pixel or two, JPEG blurs a line's edges by about as much.
constexpr double kLineTolerancePx = 3.0;

std::vector<cv::Point> points_of(const json& pts) {
  std::vector<cv::Point> out;
  for (const auto& p : pts) out.emplace_back(p.at(0).get<int>(), p.at(1).get<int>());
  return out;
}

cv::Mat fill_polygons(const json& polys, const cv::Size& size) {
  cv::Mat m = cv::Mat::zeros(size, CV_8U);
  for (const auto& p : polys) {
    const std::vector<std::vector<cv::Point>> one{points_of(p)};
    cv::fillPoly(m, one, cv::Scalar(255), cv::LINE_8);
  }
  return m;
}

// Polylines {"width_px": w, "points": [...]} drawn w px wide (width 1: the centre lines).
cv::Mat draw_polylines(const json& lines, const cv::Size& size, bool centre_only) {
  cv::Mat m = cv::Mat::zeros(size, CV_8U);
  for (const auto& l : lines) {
    const std::vector<std::vector<cv::Point>> one{points_of(l.at("points"))};
    cv::polylines(m, one, false, cv::Scalar(255), centre_only ? 1 : l.at("width_px").get<int>(),
                  cv::LINE_8);
  }
  return m;
}

struct HandMasks {
  cv::Mat carpet_region;  // the carpet as the hand drew it, lines included
  cv::Mat carpet;         // ... without the line bands: the pixels of carpet colour
  cv::Mat line_band;      // the lines at their drawn width
  cv::Mat line_centre;    // the lines' centre lines (1 px)
  cv::Mat blue, yellow;
};

HandMasks load_masks(const std::string& name, const cv::Size& size) {
  const auto path = test_data(name);
  EXPECT_FALSE(path.empty()) << name;
  std::ifstream in(path);
  const json j = json::parse(in);
  EXPECT_EQ(j.at("size").at(0).get<int>(), size.width) << name;
  EXPECT_EQ(j.at("size").at(1).get<int>(), size.height) << name;
  HandMasks h;
  const json& c = j.at("carpet");
  h.carpet_region = fill_polygons(c.at("include"), size);
  h.carpet_region.setTo(0, fill_polygons(c.at("exclude"), size));
  h.carpet_region.setTo(0, draw_polylines(c.at("exclude_lines"), size, false));
  h.line_band = draw_polylines(j.at("lines"), size, false);
  h.line_centre = draw_polylines(j.at("lines"), size, true);
  h.carpet = h.carpet_region.clone();
  h.carpet.setTo(0, h.line_band);
  h.blue = fill_polygons(j.at("blue_goal"), size);
  h.yellow = fill_polygons(j.at("yellow_goal"), size);
  return h;
}

// Distance (px) of every pixel to the nearest non-zero pixel of `mask`.
cv::Mat distance_to(const cv::Mat& mask) {
  cv::Mat inverted = mask == 0, dist;
  cv::distanceTransform(inverted, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  return dist;
}

double ratio(int num, int den) {
  return den > 0 ? static_cast<double>(num) / den : 0.0;
}

struct Figures {
  double carpet_precision, carpet_recall, line_precision, line_recall;
  double blue_iou, yellow_iou;
};

struct Case {
  const char* label;
  const char* image;
  const char* masks;
  // Floors: what was measured when the masks were drawn (docs/CALIBRATION.md), less 0.05 and
  // rounded down: room for another OpenCV's JPEG decoding and rounding; a drop of the analysis
  // by more than 0.05 on any figure fails.
  Figures floor;
};

// The case's name for GoogleTest's and CTest's listings (instead of its bytes).
void PrintTo(const Case& c, std::ostream* os) {
  *os << c.label;
}

class RcjHandMasks : public ::testing::TestWithParam<Case> {};

TEST_P(RcjHandMasks, AnalysisAgreesWithHandDrawnMasks) {
  const Case& k = GetParam();
  const auto path = test_data(k.image);
  ASSERT_FALSE(path.empty()) << k.image;
  const cv::Mat img = cv::imread(path.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty()) << k.image;
  const HandMasks h = load_masks(k.masks, img.size());
  const FrameAnalysis a = analyse_frame(img, k.image);
  const GoalColours g = measure_goal_colours(img, a);
  ASSERT_EQ(a.carpet_mask.size(), img.size());
  ASSERT_EQ(a.line_mask.size(), img.size());

  // Carpet, pixelwise. The line bands are left out of the detected side (their drawn width is
  // read to a pixel or two: a carpet pixel at a band's edge is neither right nor wrong).
  const cv::Mat detected_carpet = a.carpet_mask & ~h.line_band;
  const int carpet_both = cv::countNonZero(detected_carpet & h.carpet);
  Figures f{};
  f.carpet_precision = ratio(carpet_both, cv::countNonZero(detected_carpet));
  f.carpet_recall = ratio(carpet_both, cv::countNonZero(h.carpet));

  // Lines: recall over the hand centre lines on the carpet (a detected line pixel within
  // kLineTolerancePx), precision over the detected line pixels inside the hand carpet region (a
  // hand line band within kLineTolerancePx).
  const cv::Mat to_detected = distance_to(a.line_mask), to_hand = distance_to(h.line_band);
  const cv::Mat centre_on_carpet = h.line_centre & h.carpet_region;
  const cv::Mat detected_on_carpet = a.line_mask & h.carpet_region;
  const cv::Mat near_detected = to_detected <= kLineTolerancePx,
                near_hand = to_hand <= kLineTolerancePx;
  f.line_recall =
      ratio(cv::countNonZero(centre_on_carpet & near_detected), cv::countNonZero(centre_on_carpet));
  f.line_precision =
      ratio(cv::countNonZero(detected_on_carpet & near_hand), cv::countNonZero(detected_on_carpet));

  // Goals: the measured region's pixels against the hand polygon.
  const auto goal = [&](const std::optional<GoalRegion>& r, const cv::Mat& hand, const char* name) {
    if (!r || r->mask.empty()) {
      ADD_FAILURE() << k.label << ": no " << name << " goal region";
      return 0.0;
    }
    const int both = cv::countNonZero(r->mask & hand);
    const int either = cv::countNonZero(r->mask | hand);
    const double precision = ratio(both, cv::countNonZero(r->mask)),
                 recall = ratio(both, cv::countNonZero(hand));
    std::printf(
        "rcj %s %s goal precision %.3f recall %.3f iou %.3f (%d px measured, %d px drawn)\n",
        k.label, name, precision, recall, ratio(both, either), r->pixels, cv::countNonZero(hand));
    RecordProperty(std::string(name) + "_goal_precision", std::to_string(precision));
    RecordProperty(std::string(name) + "_goal_recall", std::to_string(recall));
    return ratio(both, either);
  };
  f.blue_iou = goal(g.blue, h.blue, "blue");
  f.yellow_iou = goal(g.yellow, h.yellow, "yellow");

  std::printf("rcj %s carpet precision %.3f recall %.3f (%d px detected, %d px drawn)\n", k.label,
              f.carpet_precision, f.carpet_recall, cv::countNonZero(detected_carpet),
              cv::countNonZero(h.carpet));
  std::printf(
      "rcj %s lines precision %.3f recall %.3f (within %.0f px; %d detected line px on the carpet, "
      "%d hand centre-line px)\n",
      k.label, f.line_precision, f.line_recall, kLineTolerancePx,
      cv::countNonZero(detected_on_carpet), cv::countNonZero(centre_on_carpet));
  RecordProperty("carpet_precision", std::to_string(f.carpet_precision));
  RecordProperty("carpet_recall", std::to_string(f.carpet_recall));
  RecordProperty("line_precision", std::to_string(f.line_precision));
  RecordProperty("line_recall", std::to_string(f.line_recall));
  RecordProperty("blue_goal_iou", std::to_string(f.blue_iou));
  RecordProperty("yellow_goal_iou", std::to_string(f.yellow_iou));

  EXPECT_GE(f.carpet_precision, k.floor.carpet_precision);
  EXPECT_GE(f.carpet_recall, k.floor.carpet_recall);
  EXPECT_GE(f.line_precision, k.floor.line_precision);
  EXPECT_GE(f.line_recall, k.floor.line_recall);
  EXPECT_GE(f.blue_iou, k.floor.blue_iou);
  EXPECT_GE(f.yellow_iou, k.floor.yellow_iou);
}

// Floors: {carpet precision, carpet recall, line precision, line recall, blue IoU, yellow IoU},
// each the measured figure (the comment above it) less 0.05, rounded down. What the figures say
// today: the carpet recall misses the pale haze of carpet beyond the boundary line near the
// mirror's edge (drawn as carpet: it is); the line recall misses the faint, blurred stretches of
// line there; the blue goal of goals_frame9 is cut in pieces by the other robot's parts in front of
// it, and the analysis keeps the largest piece only (a third of what is drawn). The floors hold
// what is, so a change that improves a figure should raise its floor.
INSTANTIATE_TEST_SUITE_P(Rcj, RcjHandMasks,
                         ::testing::Values(Case{"frame6",
                                                "rcj-omicam-frame6.jpg",
                                                "rcj-omicam-frame6.masks.json",
                                                // measured 0.991 0.800 0.839 0.667 0.657 0.770
                                                {0.94, 0.75, 0.78, 0.61, 0.60, 0.72}},
                                           Case{"goals_frame9",
                                                "rcj-omicam-goals-frame9.jpg",
                                                "rcj-omicam-goals-frame9.masks.json",
                                                // measured 0.941 0.766 0.815 0.654 0.286 0.756
                                                {0.89, 0.71, 0.76, 0.60, 0.23, 0.70}}),
                         [](const auto& info) { return std::string(info.param.label); });

}  // namespace
}  // namespace omniloc
