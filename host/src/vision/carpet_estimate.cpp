// The carpet's colour estimated from the frame's structure, not from where a venue happens to put
// it (docs/VISION.md, "The carpet from the frame"):
//  1. colours of the disc about the optical centre clustered by k-means in CIELAB (a perceptual
//     space: a green carpet under warm light and a teal one under cold light are both one compact
//     cluster, and so is a grey one);
//  2. along every bearing, the pixels classified to the nearest cluster and cut into runs (a gap as
//     wide as a line is bridged, so the lines crossing the carpet do not cut it); the run that
//     touches the centre is the robot; the bearing votes for the cluster of its first run beyond
//     the body when the body is known (the search starts beyond it), else, by length, of its
//     longest other run: the carpet is what the robot stands on, on most bearings;
//  3. the winner must be seen on enough bearings (the carpet surrounds the robot; a person, a box
//     or a rod hides it on a few only), else "no carpet" with the reason;
//  4. its colour window from its own pixels (carpet_colour_from_samples on them), grey carpets
//     included: for them the window is of brightness alone.
// A pixel the team knows is carpet (`--carpet-at`) chooses the cluster directly.
#include <algorithm>
#include <cmath>
#include <numeric>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "omniloc/conventions.hpp"
#include "omniloc/vision.hpp"

namespace omniloc {

namespace {

// Enough colours for what a disc shows: the carpet, the lines, the robot (lens and body), the
// floor beyond the carpet, walls and clutter. Fewer merge the carpet with its surroundings under a
// colour cast; more split one carpet by its light (the vote then still picks its largest part).
constexpr int kClusters = 6;
constexpr int kBearings = 180;             // 2 deg: a person or a rod takes a few
constexpr int kMaxClusterSamples = 12000;  // k-means on a subsample; every pixel is then classified
// The carpet must be seen on this fraction of the bearings: it surrounds the robot, which struts
// and obstacles hide on some bearings only (four 15 px rods at 60 px hide about 60 deg of 360).
constexpr double kMinBearingCoverage = 0.4;

cv::Vec3f lab_of(const cv::Vec3b& lab8) {
  // OpenCV's 8-bit Lab: L scaled to 0..255, a and b offset by 128. Back to CIELAB units so that
  // distances are perceptual (Delta E 1976).
  return {static_cast<float>(lab8[0] * (100.0 / 255.0)), static_cast<float>(lab8[1] - 128.0),
          static_cast<float>(lab8[2] - 128.0)};
}

struct Clusters {
  std::vector<cv::Vec3f> centres;
  [[nodiscard]] int nearest(const cv::Vec3f& c) const {
    int best = 0;
    double bd = 1e300;
    for (int k = 0; k < static_cast<int>(centres.size()); ++k) {
      const double d = cv::norm(c - centres[static_cast<std::size_t>(k)], cv::NORM_L2SQR);
      if (d < bd) {
        bd = d;
        best = k;
      }
    }
    return best;
  }
};

bool in_search(const CarpetSearch& s, double u, double v) {
  const double r = std::hypot(u - s.centre_px.x, v - s.centre_px.y);
  return r >= s.inner_px && r <= s.outer_px;
}

// k-means on a regular grid of the searched ring (deterministic: OpenCV's RNG seeded and restored).
std::optional<Clusters> cluster_colours(const cv::Mat& lab8, const CarpetSearch& s) {
  const double area = kPi * (s.outer_px * s.outer_px - s.inner_px * s.inner_px);
  const int step = std::max(1, static_cast<int>(std::ceil(std::sqrt(area / kMaxClusterSamples))));
  std::vector<cv::Vec3f> pts;
  for (int v = 0; v < lab8.rows; v += step)
    for (int u = 0; u < lab8.cols; u += step)
      if (in_search(s, u, v)) pts.push_back(lab_of(lab8.at<cv::Vec3b>(v, u)));
  if (static_cast<int>(pts.size()) < 4 * kClusters) return std::nullopt;
  cv::Mat data(static_cast<int>(pts.size()), 3, CV_32F, pts.data());
  cv::Mat labels, centres;
  const std::uint64_t saved = cv::theRNG().state;
  cv::theRNG().state = 0x0A11C0DEull;
  cv::kmeans(data, kClusters, labels,
             cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.1), 3,
             cv::KMEANS_PP_CENTERS, centres);
  cv::theRNG().state = saved;
  Clusters c;
  for (int k = 0; k < centres.rows; ++k)
    c.centres.emplace_back(centres.at<float>(k, 0), centres.at<float>(k, 1),
                           centres.at<float>(k, 2));
  return c;
}

struct Run {
  int label, begin, end;  // radii [begin, end)
};

// Runs of one cluster along a bearing; a gap of at most `bridge` px of other labels between two
// runs of the same label is bridged (a line across the carpet).
std::vector<Run> runs_along(const std::vector<int>& labels, int first_r, int bridge) {
  std::vector<Run> raw;
  for (int i = 0; i < static_cast<int>(labels.size()); ++i) {
    const int l = labels[static_cast<std::size_t>(i)];
    if (l < 0) continue;
    if (!raw.empty() && raw.back().label == l && raw.back().end == first_r + i) {
      ++raw.back().end;
    } else {
      raw.push_back({l, first_r + i, first_r + i + 1});
    }
  }
  std::vector<Run> out;
  for (const Run& r : raw) {
    // Merge into the latest run of the same label when only short runs lie between.
    bool merged = false;
    for (auto it = out.rbegin(); it != out.rend(); ++it) {
      if (r.begin - it->end > bridge) break;
      if (it->label == r.label) {
        it->end = r.end;
        out.erase(it.base(), out.end());
        merged = true;
        break;
      }
    }
    if (!merged) out.push_back(r);
  }
  return out;
}

struct Votes {
  std::vector<double> length;      // per cluster: sum of the winning runs' lengths
  std::vector<int> bearings_seen;  // per cluster: bearings with a run of at least `bridge` px
  std::vector<Run> winners;        // per bearing: the run that voted (label -1: none)
};

Votes vote(const cv::Mat& lab8, const CarpetSearch& s, const Clusters& c) {
  Votes v{std::vector<double>(c.centres.size(), 0.0), std::vector<int>(c.centres.size(), 0), {}};
  // Gaps up to a fortieth of the view are bridged: a 12.5 cm line next to the robot is a few px
  // wide in any omni view; the carpet runs between lines are many times that.
  const int bridge = std::max(2, static_cast<int>(std::lround(s.outer_px / 40.0)));
  const int r0 = static_cast<int>(std::floor(s.inner_px)),
            r1 = static_cast<int>(std::ceil(s.outer_px));
  std::vector<int> labels;
  for (int b = 0; b < kBearings; ++b) {
    const double a = 2.0 * kPi * b / kBearings;
    labels.assign(static_cast<std::size_t>(std::max(0, r1 - r0)), -1);
    for (int r = r0; r < r1; ++r) {
      const int u = static_cast<int>(std::lround(s.centre_px.x + r * std::cos(a)));
      const int vv = static_cast<int>(std::lround(s.centre_px.y - r * std::sin(a)));
      if (u < 0 || vv < 0 || u >= lab8.cols || vv >= lab8.rows) continue;
      if (!s.mask.empty() && s.mask.at<std::uint8_t>(vv, u) == 0) continue;
      labels[static_cast<std::size_t>(r - r0)] = c.nearest(lab_of(lab8.at<cv::Vec3b>(vv, u)));
    }
    const auto runs = runs_along(labels, r0, bridge);
    // Without a known body, the run from the centre is the robot's (lens, body): not the floor.
    const std::size_t skip =
        s.inner_px <= 0.0 && !runs.empty() && runs.front().begin <= bridge ? 1 : 0;
    // With the body known (the search starts beyond it), the floor next to it is what the robot
    // stands on: the first run as wide as a bridge (not a line) votes, so that near the carpet's
    // edge the floor beyond it, longer in the image, does not outvote it. Without, the body may
    // show as more than one run (lens, housing): the longest run votes.
    const Run* best = nullptr;
    const Run* first = nullptr;
    std::vector<bool> seen(c.centres.size(), false);
    for (std::size_t i = skip; i < runs.size(); ++i) {
      const Run& r = runs[i];
      if (r.end - r.begin >= bridge) {
        seen[static_cast<std::size_t>(r.label)] = true;
        if (first == nullptr) first = &r;
      }
      if (best == nullptr || r.end - r.begin > best->end - best->begin) best = &r;
    }
    if (s.inner_px > 0.0 && first != nullptr) best = first;
    v.winners.push_back(best != nullptr ? *best : Run{-1, 0, 0});
    if (best != nullptr) v.length[static_cast<std::size_t>(best->label)] += best->end - best->begin;
    for (std::size_t k = 0; k < seen.size(); ++k) v.bearings_seen[k] += seen[k];
  }
  return v;
}

std::vector<cv::Vec3b> to_hsv(std::vector<cv::Vec3b> bgr) {
  if (bgr.empty()) return bgr;
  cv::Mat in(1, static_cast<int>(bgr.size()), CV_8UC3, bgr.data()), hsv;
  cv::cvtColor(in, hsv, cv::COLOR_BGR2HSV);
  return {hsv.begin<cv::Vec3b>(), hsv.end<cv::Vec3b>()};
}

// The carpet's own pixels: those of the cluster on the bearings' winning runs (the floor that
// reaches out from the robot), not the same colour elsewhere (a wall of its hue, the floor behind
// an obstacle), every pixel along each run.
std::vector<cv::Vec3b> samples_on_runs(const cv::Mat& bgr, const cv::Mat& lab8,
                                       const CarpetSearch& s, const Clusters& c, const Votes& v,
                                       int label) {
  std::vector<cv::Vec3b> px;
  for (int b = 0; b < kBearings; ++b) {
    const Run& run = v.winners[static_cast<std::size_t>(b)];
    if (run.label != label) continue;
    const double a = 2.0 * kPi * b / kBearings;
    for (int r = run.begin; r < run.end; ++r) {
      const int u = static_cast<int>(std::lround(s.centre_px.x + r * std::cos(a)));
      const int vv = static_cast<int>(std::lround(s.centre_px.y - r * std::sin(a)));
      if (u < 0 || vv < 0 || u >= bgr.cols || vv >= bgr.rows) continue;
      if (c.nearest(lab_of(lab8.at<cv::Vec3b>(vv, u))) == label)
        px.push_back(bgr.at<cv::Vec3b>(vv, u));
    }
  }
  return to_hsv(std::move(px));
}

// With a pixel named as carpet: every pixel of its cluster in the searched ring.
std::vector<cv::Vec3b> samples_of_cluster(const cv::Mat& bgr, const cv::Mat& lab8,
                                          const CarpetSearch& s, const Clusters& c, int label) {
  const double area = kPi * (s.outer_px * s.outer_px - s.inner_px * s.inner_px);
  const int step =
      std::max(1, static_cast<int>(std::floor(std::sqrt(area / (4.0 * kMaxClusterSamples)))));
  std::vector<cv::Vec3b> px;
  for (int v = 0; v < bgr.rows; v += step)
    for (int u = 0; u < bgr.cols; u += step)
      if (in_search(s, u, v) && (s.mask.empty() || s.mask.at<std::uint8_t>(v, u) != 0) &&
          c.nearest(lab_of(lab8.at<cv::Vec3b>(v, u))) == label)
        px.push_back(bgr.at<cv::Vec3b>(v, u));
  return to_hsv(std::move(px));
}

std::string fmt0(double x) {
  return std::to_string(static_cast<long>(std::lround(x)));
}

}  // namespace

std::optional<CarpetColour> estimate_carpet_colour(const cv::Mat& bgr, const CarpetSearch& s,
                                                   std::string* why) {
  auto fail = [&](const std::string& reason) -> std::optional<CarpetColour> {
    if (why != nullptr) *why = "no carpet: " + reason;
    return std::nullopt;
  };
  if (bgr.empty() || bgr.type() != CV_8UC3) return fail("the image is not 8-bit colour");
  if (!(s.outer_px > s.inner_px) || !std::isfinite(s.outer_px)) return fail("no ring to search");
  cv::Mat lab8;
  cv::cvtColor(bgr, lab8, cv::COLOR_BGR2Lab);
  const auto clusters = cluster_colours(lab8, s);
  if (!clusters)
    return fail("too few pixels in the view (" + fmt0(s.inner_px) + " to " + fmt0(s.outer_px) +
                " px)");
  std::vector<cv::Vec3b> hsv;
  if (s.carpet_at) {
    const cv::Point p(static_cast<int>(std::lround(s.carpet_at->x)),
                      static_cast<int>(std::lround(s.carpet_at->y)));
    if (p.x < 0 || p.y < 0 || p.x >= bgr.cols || p.y >= bgr.rows) {
      return fail("the carpet pixel given (" + fmt0(s.carpet_at->x) + ", " + fmt0(s.carpet_at->y) +
                  ") is outside the image");
    }
    hsv = samples_of_cluster(bgr, lab8, s, *clusters,
                             clusters->nearest(lab_of(lab8.at<cv::Vec3b>(p))));
  } else {
    const Votes v = vote(lab8, s, *clusters);
    const int label =
        static_cast<int>(std::max_element(v.length.begin(), v.length.end()) - v.length.begin());
    const double coverage =
        static_cast<double>(v.bearings_seen[static_cast<std::size_t>(label)]) / kBearings;
    if (v.length[static_cast<std::size_t>(label)] <= 0.0)
      return fail("no colour reaches out from the robot on any bearing");
    if (coverage < kMinBearingCoverage) {
      return fail("the colour reaching farthest from the robot surrounds it on only " +
                  fmt0(100 * coverage) + " % of the bearings (at least " +
                  fmt0(100 * kMinBearingCoverage) + " % needed)");
    }
    hsv = samples_on_runs(bgr, lab8, s, *clusters, v, label);
  }
  std::string inner_why;
  auto colour = carpet_colour_from_samples(hsv, &inner_why, /*allow_grey=*/true);
  if (!colour)
    return fail(
        inner_why.substr(inner_why.find(": ") == std::string::npos ? 0 : inner_why.find(": ") + 2));
  return colour;
}

}  // namespace omniloc
