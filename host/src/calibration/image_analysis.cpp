// Image side of the calibration: the mirror rim, the carpet colour, line pixels, and the robot's
// body, masts and the end of the carpet, all measured from the frame itself.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <random>
#include <stdexcept>

#include <Eigen/Dense>
#include <opencv2/imgproc.hpp>

#include "omniloc/calibration.hpp"
#include "omniloc/conventions.hpp"
#include "step_pictures.hpp"

namespace omniloc {

namespace {

constexpr int kRimRays = 360;
constexpr int kPolarAngles = 720;  // 0.5 deg: a 3 px rod at 40 px spans 4 deg = 8 bins

float bilinear(const cv::Mat1f& img, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= img.cols || y0 + 1 >= img.rows) return 0.0f;
  const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
  const float* r0 = img.ptr<float>(y0);
  const float* r1 = img.ptr<float>(y0 + 1);
  return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) +
         fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

// Window of the rim's step test: wider than the widest line in the image (a 5 cm line is ~6 px
// at 480 px near the robot), so that a line's edge scores at most width/window of its contrast.
int rim_window_px(const cv::Mat& img) {
  return std::clamp(static_cast<int>(std::lround(std::min(img.cols, img.rows) / 60.0)), 4, 16);
}

struct EdgeCandidate {
  int ray;
  Eigen::Vector2d p;
  double contrast;
};

// Steps along 360 rays from `origin`: local maxima of polarity x (mean(inside window) -
// mean(outside window)) above `min_contrast`, sub-pixel by a parabola (polarity +1: bright to dark
// outwards, the usual rim against a dark housing; -1: dark to bright, a light housing).
std::vector<EdgeCandidate> rim_candidates(const cv::Mat1f& gray, const Eigen::Vector2d& origin,
                                          int w, double min_contrast, double polarity) {
  std::vector<EdgeCandidate> out;
  const double rmax = std::hypot(gray.cols, gray.rows);
  std::vector<double> prof, pre;
  for (int k = 0; k < kRimRays; ++k) {
    const double a = deg_to_rad(k), c = std::cos(a), s = std::sin(a);
    prof.clear();
    for (int r = 0; r < rmax; ++r) {
      const double x = origin.x() + r * c, y = origin.y() - r * s;
      if (x < 0 || y < 0 || x > gray.cols - 2 || y > gray.rows - 2) break;
      prof.push_back(bilinear(gray, x, y));
    }
    const int n = static_cast<int>(prof.size());
    if (n < 2 * w + 3) continue;
    pre.assign(static_cast<std::size_t>(n) + 1, 0.0);
    for (int i = 0; i < n; ++i)
      pre[static_cast<std::size_t>(i) + 1] =
          pre[static_cast<std::size_t>(i)] + prof[static_cast<std::size_t>(i)];
    auto contrast = [&](int r) {
      return polarity *
             ((pre[static_cast<std::size_t>(r)] - pre[static_cast<std::size_t>(r - w)]) / w -
              (pre[static_cast<std::size_t>(r + w + 1)] - pre[static_cast<std::size_t>(r + 1)]) /
                  w);
    };
    for (int r = w + 1; r + w + 2 < n; ++r) {
      const double c0 = contrast(r);
      if (c0 < min_contrast || c0 < contrast(r - 1) || c0 <= contrast(r + 1)) continue;
      const double cm = contrast(r - 1), cp = contrast(r + 1);
      const double den = cm - 2 * c0 + cp;
      const double dr = den < 0 ? std::clamp(0.5 * (cm - cp) / den, -0.5, 0.5) : 0.0;
      const double rr = r + dr;
      out.push_back({k, origin + rr * Eigen::Vector2d(c, -s), c0});
    }
  }
  return out;
}

bool circle_through(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                    Eigen::Vector2d& centre, double& radius) {
  const double d =
      2 * (a.x() * (b.y() - c.y()) + b.x() * (c.y() - a.y()) + c.x() * (a.y() - b.y()));
  if (std::abs(d) < 1e-9) return false;
  const double a2 = a.squaredNorm(), b2 = b.squaredNorm(), c2 = c.squaredNorm();
  centre = {(a2 * (b.y() - c.y()) + b2 * (c.y() - a.y()) + c2 * (a.y() - b.y())) / d,
            (a2 * (c.x() - b.x()) + b2 * (a.x() - c.x()) + c2 * (b.x() - a.x())) / d};
  radius = (a - centre).norm();
  return true;
}

// Least-squares (Kasa) circle through points.
bool fit_circle(const std::vector<Eigen::Vector2d>& pts, Eigen::Vector2d& centre, double& radius) {
  if (pts.size() < 3) return false;
  Eigen::MatrixXd A(static_cast<Eigen::Index>(pts.size()), 3);
  Eigen::VectorXd b(static_cast<Eigen::Index>(pts.size()));
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    A(r, 0) = 2 * pts[i].x();
    A(r, 1) = 2 * pts[i].y();
    A(r, 2) = 1;
    b(r) = pts[i].squaredNorm();
  }
  const Eigen::Vector3d x = A.colPivHouseholderQr().solve(b);
  centre = {x(0), x(1)};
  radius = std::sqrt(std::max(0.0, x(2) + centre.squaredNorm()));
  return std::isfinite(radius);
}

// Per ray, the strongest candidate within `tol` of the circle; their contrast sum and points.
double circle_support(const std::vector<std::vector<int>>& by_ray,
                      const std::vector<EdgeCandidate>& cand, const Eigen::Vector2d& centre,
                      double radius, double tol, std::vector<Eigen::Vector2d>* pts) {
  double score = 0.0;
  for (const auto& ray : by_ray) {
    double best = 0.0;
    const EdgeCandidate* bc = nullptr;
    for (int i : ray) {
      const auto& e = cand[static_cast<std::size_t>(i)];
      if (std::abs((e.p - centre).norm() - radius) <= tol && e.contrast > best) {
        best = e.contrast;
        bc = &e;
      }
    }
    score += best;
    if (pts != nullptr && bc != nullptr) pts->push_back(bc->p);
  }
  return score;
}

// Fraction of a circle's circumference inside the image. The rim is seen round much of its
// circumference (a frame may crop it, but keeps at least 40 % of it); a large circle centred near
// the image's edge that passes along one arc of the rim and through stray steps elsewhere is not
// (on rendered frames with dark walls at the rim such circles got half the rim's support and, being
// larger, were taken as the rim).
double inside_fraction(const Eigen::Vector2d& c, double r, const cv::Size& size) {
  int in = 0;
  constexpr int kSamples = 72;
  for (int k = 0; k < kSamples; ++k) {
    const double a = 2.0 * kPi * k / kSamples;
    const double x = c.x() + r * std::cos(a), y = c.y() + r * std::sin(a);
    in += x >= 0 && y >= 0 && x < size.width && y < size.height;
  }
  return static_cast<double>(in) / kSamples;
}

struct RimHypothesis {
  Eigen::Vector2d c;
  double r, score;
};

// Among circles supported by at least half the best support and enclosing the best-supported
// circle, the outermost: the rim is outside every line and the centre circle (which may also be
// concentric with the image), and a larger circle that crosses the best-supported one (along one
// arc of the rim and through steps beyond it) is not the rim.
const RimHypothesis& outermost_enclosing(const std::vector<RimHypothesis>& hyps) {
  const RimHypothesis* top = &hyps.front();
  for (const auto& h : hyps)
    if (h.score > top->score) top = &h;
  const RimHypothesis* chosen = top;
  for (const auto& h : hyps) {
    const bool encloses = (h.c - top->c).norm() + top->r <= h.r + 2.0;
    if (h.score >= 0.5 * top->score && encloses && h.r > chosen->r) chosen = &h;
  }
  return *chosen;
}

// One RANSAC pass: circles through random triples of steps, the rim chosen by outermost_enclosing.
bool ransac_rim(const std::vector<EdgeCandidate>& cand, const cv::Size& size,
                Eigen::Vector2d& centre, double& radius, int& rays) {
  if (cand.size() < 3) return false;
  std::vector<std::vector<int>> by_ray(kRimRays);
  for (std::size_t i = 0; i < cand.size(); ++i)
    by_ray[static_cast<std::size_t>(cand[i].ray)].push_back(static_cast<int>(i));
  std::mt19937 rng(1);  // fixed: the calibration is deterministic
  std::uniform_int_distribution<std::size_t> pick(0, cand.size() - 1);
  std::vector<RimHypothesis> hyps;
  const double min_r = 0.15 * std::min(size.width, size.height);
  for (int it = 0; it < 3000; ++it) {
    const auto& a = cand[pick(rng)];
    const auto& b = cand[pick(rng)];
    const auto& c = cand[pick(rng)];
    auto apart = [](int x, int y) { return std::abs(angle_diff_deg(x, y)) >= 40.0; };
    if (!apart(a.ray, b.ray) || !apart(b.ray, c.ray) || !apart(a.ray, c.ray)) continue;
    Eigen::Vector2d cc;
    double rr = 0;
    if (!circle_through(a.p, b.p, c.p, cc, rr) || rr < min_r) continue;
    if (cc.x() < 0 || cc.y() < 0 || cc.x() >= size.width || cc.y() >= size.height) continue;
    if (inside_fraction(cc, rr, size) < 0.4) continue;
    hyps.push_back({cc, rr, circle_support(by_ray, cand, cc, rr, 2.0, nullptr)});
  }
  if (hyps.empty()) return false;
  const RimHypothesis& chosen = outermost_enclosing(hyps);
  std::vector<Eigen::Vector2d> pts;
  (void)circle_support(by_ray, cand, chosen.c, chosen.r, 2.0, &pts);
  centre = chosen.c;
  radius = chosen.r;
  if (!fit_circle(pts, centre, radius)) return false;
  pts.clear();
  (void)circle_support(by_ray, cand, centre, radius, 1.5, &pts);
  rays = static_cast<int>(pts.size());
  return fit_circle(pts, centre, radius);
}

// The rim from steps of one polarity: RANSAC from the image centre, then again from the circle's
// centre (its rays cross the rim squarely). A quarter of the rays on which the circle lies inside
// the image must see it: the masts hide some, and where the rim leaves the image none are seen.
std::optional<RimCircle> rim_of_polarity(const cv::Mat1f& gray, const cv::Size& size, int w,
                                         double min_contrast, double polarity, std::string* why) {
  Eigen::Vector2d origin(0.5 * (size.width - 1), 0.5 * (size.height - 1));
  double radius = 0.0;
  int rays = 0;
  for (int pass = 0; pass < 2; ++pass) {
    const auto cand = rim_candidates(gray, origin, w, min_contrast, polarity);
    Eigen::Vector2d c;
    if (!ransac_rim(cand, size, c, radius, rays)) {
      if (why->empty()) *why = "no circle of bright-to-dark (or dark-to-bright) steps found";
      return std::nullopt;
    }
    origin = c;
  }
  const int inside =
      static_cast<int>(std::lround(kRimRays * inside_fraction(origin, radius, size)));
  if (rays < inside / 4 || rays < kRimRays / 8) {
    *why = "the best circle is seen on only " + std::to_string(rays) + " of the " +
           std::to_string(inside) + " rays on which it lies inside the image";
    return std::nullopt;
  }
  RimCircle rim;
  rim.centre_px = origin;
  rim.radius_px = radius;
  rim.rays_on_circle = rays;
  return rim;
}

}  // namespace

RimCircle find_mirror_rim(const cv::Mat& bgr, const std::string& ctx) {
  if (bgr.empty() || bgr.type() != CV_8UC3)
    throw std::runtime_error(ctx + ": expected a non-empty 8-bit colour image");
  if (std::min(bgr.cols, bgr.rows) < 64) {
    throw std::runtime_error(ctx + ": image " + std::to_string(bgr.cols) + " x " +
                             std::to_string(bgr.rows) +
                             " is too small for an omni frame (at least 64 px a side)");
  }
  cv::Mat gray8;
  cv::cvtColor(bgr, gray8, cv::COLOR_BGR2GRAY);
  cv::Mat1f gray;
  gray8.convertTo(gray, CV_32F);
  cv::GaussianBlur(gray, gray, cv::Size(3, 3), 0.8);
  std::vector<double> g;
  for (int v = 0; v < gray.rows; v += 2)
    for (int u = 0; u < gray.cols; u += 2) g.push_back(gray(v, u));
  const double range = percentile(g, 0.99) - percentile(g, 0.01);
  // The rim steps from the floor (dimmest: the renderer's outside floor, 25 % of the range after
  // dimming) to the black beyond the mirror: 15 % of the image's range keeps it and drops noise.
  const double min_contrast = 0.15 * range;
  if (range < 20.0) {
    throw std::runtime_error(ctx +
                             ": no mirror rim: the image has no contrast (1-99 % grey range " +
                             std::to_string(static_cast<int>(range)) + " levels)");
  }
  const int w = rim_window_px(bgr);
  Eigen::Vector2d origin(0.5 * (bgr.cols - 1), 0.5 * (bgr.rows - 1));
  // Bright-to-dark first (a dark housing round the mirror, the usual case); a light housing steps
  // the other way.
  std::string why;
  for (const double polarity : {1.0, -1.0}) {
    if (const auto rim = rim_of_polarity(gray, bgr.size(), w, min_contrast, polarity, &why))
      return *rim;
  }
  throw std::runtime_error(ctx + ": no mirror rim: " + why);
}

namespace {

// Carpet: the colour cluster that reaches out from the robot on most bearings (vision.hpp,
// estimate_carpet_colour), searched over the whole disc: no ring, hue or fraction of the rim is
// assumed, so a large body, a person next to the robot or a light floor beyond the carpet does not
// decide it.
CarpetColour carpet_colour(const cv::Mat& bgr, const RimCircle& rim, const AnalysisHints& hints,
                           const std::string& ctx) {
  CarpetSearch search;
  search.centre_px = {rim.centre_px.x(), rim.centre_px.y()};
  search.outer_px = rim.radius_px;
  if (hints.carpet_at_px)
    search.carpet_at = cv::Point2d(hints.carpet_at_px->x(), hints.carpet_at_px->y());
  std::string why;
  const auto c = estimate_carpet_colour(bgr, search, &why);
  if (!c) throw std::runtime_error(ctx + ": " + why);
  return *c;
}

cv::Mat1f normalised_box(const cv::Mat1f& value, const cv::Mat1f& weight, int k) {
  cv::Mat1f num, den;
  cv::boxFilter(value.mul(weight), num, CV_32F, cv::Size(k, k));
  cv::boxFilter(weight, den, CV_32F, cv::Size(k, k));
  return num / cv::max(den, 1e-3f);
}

}  // namespace

namespace {

// The rim from the team's hint when given (both --center and --rim-radius), else searched.
RimCircle rim_of(const cv::Mat& bgr, const AnalysisHints& hints, const std::string& ctx) {
  if (!hints.centre_px || !hints.rim_radius_px) return find_mirror_rim(bgr, ctx);
  const Eigen::Vector2d c = *hints.centre_px;
  const double r = *hints.rim_radius_px;
  if (c.x() < 0 || c.y() < 0 || c.x() >= bgr.cols || c.y() >= bgr.rows) {
    throw std::runtime_error(ctx + ": the centre given (" + std::to_string(c.x()) + ", " +
                             std::to_string(c.y()) + ") is outside the " +
                             std::to_string(bgr.cols) + " x " + std::to_string(bgr.rows) +
                             " image");
  }
  const double max_r = std::hypot(bgr.cols, bgr.rows);
  if (!(r >= 16.0 && r <= max_r)) {
    throw std::runtime_error(ctx + ": the rim radius given (" + std::to_string(r) +
                             " px) must be 16 to " + std::to_string(static_cast<int>(max_r)) +
                             " px");
  }
  RimCircle rim;
  rim.centre_px = c;
  rim.radius_px = r;
  rim.rays_on_circle = 0;  // not measured: given
  return rim;
}

}  // namespace

namespace {

// The frame's hue, saturation and value as float planes: the carpet and line tests compare them
// with the carpet colour and with local averages.
struct HsvPlanes {
  cv::Mat1f hue, sat, val;
};

HsvPlanes hsv_planes(const cv::Mat& bgr) {
  cv::Mat hsv;
  cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
  HsvPlanes p;
  std::vector<cv::Mat> ch;
  cv::split(hsv, ch);
  ch[0].convertTo(p.hue, CV_32F);
  ch[1].convertTo(p.sat, CV_32F);
  ch[2].convertTo(p.val, CV_32F);
  return p;
}

// Carpet pixels inside the rim: within the carpet colour's hue, saturation and value bounds. The
// float map weights the local averages below; the 8-bit mask is the analysis's output.
cv::Mat1f carpet_pixels(const HsvPlanes& p, const RimCircle& rim, const CarpetColour& cc,
                        cv::Mat& mask) {
  cv::Mat1f carpet(p.hue.size(), 0.0f);
  mask = cv::Mat::zeros(p.hue.size(), CV_8U);
  for (int v = 0; v < p.hue.rows; ++v) {
    for (int u = 0; u < p.hue.cols; ++u) {
      if (std::hypot(u - rim.centre_px.x(), v - rim.centre_px.y()) > rim.radius_px) continue;
      const double dh = std::abs(p.hue(v, u) - cc.hue);
      if (std::min(dh, 180 - dh) <= cc.hue_half_width && p.sat(v, u) >= cc.sat_min &&
          p.val(v, u) >= cc.val_min && p.val(v, u) <= cc.val_max) {
        carpet(v, u) = 1.0f;
        mask.at<std::uint8_t>(v, u) = 255;
      }
    }
  }
  return carpet;
}

// Local carpet brightness and saturation over a window four rim windows wide (several line
// widths: the line itself never dominates it), from carpet pixels only, and how much of the
// window is carpet.
struct CarpetBackground {
  cv::Mat1f val, sat, near_carpet;
};

CarpetBackground carpet_background(const HsvPlanes& p, const cv::Mat1f& carpet, int w) {
  const int kb = 4 * w + 1;
  CarpetBackground bg{normalised_box(p.val, carpet, kb), normalised_box(p.sat, carpet, kb), {}};
  cv::boxFilter(carpet, bg.near_carpet, CV_32F, cv::Size(kb, kb));
  return bg;
}

// The steps a line pixel stands out of the carpet by: from the carpet's own spread about its
// local background, so a noisy carpet needs a clearer line.
void set_line_steps(const HsvPlanes& p, const cv::Mat1f& carpet, const CarpetBackground& bg,
                    CarpetColour& cc) {
  std::vector<double> ev, es;
  for (int v = 0; v < carpet.rows; v += 2)
    for (int u = 0; u < carpet.cols; u += 2)
      if (carpet(v, u) > 0) {
        ev.push_back(p.val(v, u) - bg.val(v, u));
        es.push_back(p.sat(v, u) - bg.sat(v, u));
      }
  // Four robust sigmas of the carpet's own spread (at least 2 levels: 8-bit quantisation).
  cc.line_val_step = std::max(4.0 * robust_sigma(ev), 2.0);
  // A grey carpet's saturation is noise: its lines are told by brightness alone.
  cc.line_sat_step =
      is_grey_carpet(cc.hue_half_width) ? 0.0 : std::max(2.0 * robust_sigma(es), 2.0);
}

// Line pixels: not carpet but among it, brighter and less saturated than the carpet round them.
cv::Mat line_mask_of(const HsvPlanes& p, const cv::Mat1f& carpet, const CarpetBackground& bg,
                     const RimCircle& rim, const CarpetColour& cc) {
  cv::Mat mask = cv::Mat::zeros(carpet.size(), CV_8U);
  for (int v = 0; v < carpet.rows; ++v) {
    for (int u = 0; u < carpet.cols; ++u) {
      // A fifth of the window carpet: the pixel is on (or in a line across) the carpet.
      if (carpet(v, u) > 0 || bg.near_carpet(v, u) < 0.2f) continue;
      if (std::hypot(u - rim.centre_px.x(), v - rim.centre_px.y()) > rim.radius_px) continue;
      if (p.val(v, u) - bg.val(v, u) >= cc.line_val_step &&
          bg.sat(v, u) - p.sat(v, u) >= cc.line_sat_step)
        mask.at<std::uint8_t>(v, u) = 255;
    }
  }
  return mask;
}

// Polar statistics about the rim centre: class per (angle, radius): 0 other, 1 carpet, 2 line.
void classify_polar(detail::PolarClasses& polar, const RimCircle& rim, const cv::Mat& line_mask,
                    const cv::Mat1f& carpet) {
  const int nr = polar.radii_px;
  for (int k = 0; k < kPolarAngles; ++k) {
    const double a = deg_to_rad(k * 360.0 / kPolarAngles);
    for (int r = 0; r < nr; ++r) {
      const int u = static_cast<int>(std::lround(rim.centre_px.x() + r * std::cos(a)));
      const int v = static_cast<int>(std::lround(rim.centre_px.y() - r * std::sin(a)));
      if (u < 0 || v < 0 || u >= line_mask.cols || v >= line_mask.rows) continue;
      polar.cls[static_cast<std::size_t>(k) * static_cast<std::size_t>(nr) +
                static_cast<std::size_t>(r)] =
          line_mask.at<std::uint8_t>(v, u) ? 2 : (carpet(v, u) > 0 ? 1 : 0);
    }
  }
}

// Body: inside the first radius where the floor is seen on 80 % as many angles as anywhere.
// Returns the index of that radius; refuses a frame where no radius is a quarter floor.
int body_radius_index(const detail::PolarClasses& polar, const std::string& ctx) {
  const int nr = polar.radii_px;
  std::vector<double> floor_frac(static_cast<std::size_t>(nr), 0.0);
  for (int r = 0; r < nr; ++r) {
    int n = 0;
    for (int k = 0; k < kPolarAngles; ++k) n += polar.at(k, r) != 0;
    floor_frac[static_cast<std::size_t>(r)] = static_cast<double>(n) / kPolarAngles;
  }
  const double fmax = *std::max_element(floor_frac.begin(), floor_frac.end());
  if (fmax < 0.25)
    throw std::runtime_error(ctx +
                             ": no carpet: at no radius is a quarter of the circle carpet or line");
  int body = 0;
  while (body < nr && floor_frac[static_cast<std::size_t>(body)] < 0.8 * fmax) ++body;
  return body;
}

// End of the carpet per angle: the first run of more than a rim window of "other" pixels.
std::vector<double> carpet_ends(const detail::PolarClasses& polar, int body, int w) {
  const int nr = polar.radii_px;
  std::vector<double> end(kPolarAngles, nr);
  for (int k = 0; k < kPolarAngles; ++k) {
    int run = 0;
    for (int r = body; r < nr; ++r) {
      run = polar.at(k, r) == 0 ? run + 1 : 0;
      if (run > w) {
        end[static_cast<std::size_t>(k)] = r - run;
        break;
      }
    }
  }
  return end;
}

// Masts: angles where most of [body, view] is neither carpet nor line (rods, the mast), smoothed
// over three bins.
void mark_masts(const detail::PolarClasses& polar, int body, int w, double view0,
                std::vector<bool>& mast) {
  std::vector<double> other(kPolarAngles, 0.0);
  const int r0 = body + w / 2, r1 = std::max(r0 + 1, static_cast<int>(view0));
  for (int k = 0; k < kPolarAngles; ++k) {
    int n = 0;
    for (int r = r0; r < r1; ++r) n += polar.at(k, r) == 0;
    other[static_cast<std::size_t>(k)] = static_cast<double>(n) / (r1 - r0);
  }
  for (int k = 0; k < kPolarAngles; ++k) {
    const double s = (other[static_cast<std::size_t>((k + kPolarAngles - 1) % kPolarAngles)] +
                      other[static_cast<std::size_t>(k)] +
                      other[static_cast<std::size_t>((k + 1) % kPolarAngles)]) /
                     3.0;
    mast[static_cast<std::size_t>(k)] = s >= 0.6;
  }
}

// The mast bins as sectors (centre, half width) in image angle; the caller has checked that at
// least one bin is open.
std::vector<MastSector> mast_sectors(const std::vector<bool>& mast) {
  std::vector<MastSector> sectors;
  int start = 0;
  while (mast[static_cast<std::size_t>(start)]) ++start;  // begin the sweep outside a sector
  for (int i = 0; i < kPolarAngles; ++i) {
    const int k = (start + i) % kPolarAngles;
    if (!mast[static_cast<std::size_t>(k)] ||
        mast[static_cast<std::size_t>((k + kPolarAngles - 1) % kPolarAngles)])
      continue;
    int len = 0;
    while (mast[static_cast<std::size_t>((k + len) % kPolarAngles)]) ++len;
    const double step = 360.0 / kPolarAngles;
    // Half a bin each side for the sampling, one more bin of margin for the rod's soft edge.
    sectors.push_back({wrap_deg((k + 0.5 * (len - 1)) * step), 0.5 * len * step + step});
  }
  return sectors;
}

// Line pixels for the fit: outside the body, before the carpet ends on their ray, not on a mast.
std::vector<Eigen::Vector2d> fit_line_pixels(const FrameAnalysis& fa,
                                             const std::vector<double>& end,
                                             const std::vector<bool>& mast) {
  std::vector<Eigen::Vector2d> pixels;
  const RimCircle& rim = fa.rim;
  for (int v = 0; v < fa.line_mask.rows; ++v) {
    for (int u = 0; u < fa.line_mask.cols; ++u) {
      if (!fa.line_mask.at<std::uint8_t>(v, u)) continue;
      const double du = u - rim.centre_px.x(), dv = rim.centre_px.y() - v;
      const double r = std::hypot(du, dv);
      if (r < fa.body_radius_px + 1.0) continue;
      double a = rad_to_deg(std::atan2(dv, du));
      if (a < 0) a += 360.0;
      const auto k = static_cast<std::size_t>(
          std::min(kPolarAngles - 1, static_cast<int>(a * kPolarAngles / 360.0)));
      if (mast[k] || r > end[k]) continue;
      pixels.emplace_back(u, v);
    }
  }
  return pixels;
}

// The polar half of the analysis: body and view radii, masts and the line pixels for the fit.
// Fills fa (and mast) as it goes, so a refusal's picture shows what was measured before it.
void analyse_polar(FrameAnalysis& fa, const detail::PolarClasses& polar, int w,
                   std::vector<bool>& mast, const std::string& ctx) {
  const int body = body_radius_index(polar, ctx);
  fa.body_radius_px = body + 1.0;
  const std::vector<double> end = carpet_ends(polar, body, w);
  mark_masts(polar, body, w, percentile(end, 0.1), mast);
  if (std::all_of(mast.begin(), mast.end(), [](bool b) { return b; })) {
    throw std::runtime_error(
        ctx + ": no carpet: every direction is hidden between the body and the end of the carpet");
  }
  fa.masts_image = mast_sectors(mast);
  std::vector<double> open_end;
  for (int k = 0; k < kPolarAngles; ++k)
    if (!mast[static_cast<std::size_t>(k)]) open_end.push_back(end[static_cast<std::size_t>(k)]);
  // The 10th percentile: the ball or a robot on a few rays does not pull the view in.
  fa.view_radius_px = percentile(open_end, 0.1);
  if (fa.view_radius_px <= fa.body_radius_px + 2 * w) {
    throw std::runtime_error(ctx + ": no carpet ring: the carpet ends at " +
                             std::to_string(fa.view_radius_px) + " px, at the robot's body (" +
                             std::to_string(fa.body_radius_px) + " px)");
  }
  fa.line_pixels = fit_line_pixels(fa, end, mast);
  if (fa.line_pixels.size() < 50) {
    throw std::runtime_error(ctx + ": no lines: only " + std::to_string(fa.line_pixels.size()) +
                             " line pixels on the carpet");
  }
}

}  // namespace

FrameAnalysis analyse_frame(const cv::Mat& bgr, const std::string& ctx, const AnalysisHints& hints,
                            const StepPictureSink& pictures) {
  // Drawn only when someone looks: a run without --debug-dir pays nothing.
  const auto show = [&](const char* step, const auto& draw) {
    if (pictures) pictures(ctx, step, draw());
  };
  FrameAnalysis fa;
  fa.rim = rim_of(bgr, hints, ctx);
  show("1-disc", [&] { return detail::disc_picture(bgr, fa.rim); });
  const HsvPlanes planes = hsv_planes(bgr);
  fa.carpet = carpet_colour(bgr, fa.rim, hints, ctx);
  const int w = rim_window_px(bgr);
  const cv::Mat1f carpet = carpet_pixels(planes, fa.rim, fa.carpet, fa.carpet_mask);
  show("2-carpet", [&] { return fa.carpet_mask.clone(); });
  const CarpetBackground bg = carpet_background(planes, carpet, w);
  set_line_steps(planes, carpet, bg, fa.carpet);
  fa.line_mask = line_mask_of(planes, carpet, bg, fa.rim, fa.carpet);
  show("3-lines", [&] { return detail::lines_picture(bgr, fa.line_mask); });

  const int nr = static_cast<int>(fa.rim.radius_px);
  detail::PolarClasses polar{kPolarAngles, nr, {}};
  polar.cls.assign(static_cast<std::size_t>(kPolarAngles) * static_cast<std::size_t>(nr), 0);
  std::vector<bool> mast(kPolarAngles, false);
  // Picture 4 with what was measured: on a refusal below too (body, view or masts then 0 / none).
  const auto show_polar = [&] {
    show("4-polar",
         [&] { return detail::polar_picture(polar, fa.body_radius_px, fa.view_radius_px, mast); });
  };
  try {
    classify_polar(polar, fa.rim, fa.line_mask, carpet);
    analyse_polar(fa, polar, w, mast, ctx);
  } catch (const std::runtime_error&) {
    show_polar();
    throw;
  }
  show_polar();
  return fa;
}

}  // namespace omniloc
