// Fitting side of the calibration: a field-frame distance transform of the white lines, a coarse
// brute-force search of yaw and mapping, and a robust Ceres fit of centre, radial model and
// yaw with nearest-line-point re-association; the camera it writes and the overlay it draws.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <stdexcept>

#include <ceres/ceres.h>
#include <Eigen/Dense>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "handedness.hpp"
#include "omniloc/calibration.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/line_scan.hpp"
#include "omniloc/matcher.hpp"
#include "self_check.hpp"
#include "step_pictures.hpp"

namespace omniloc {

namespace detail {
// RadialModel's numerator n(x) = a1 x + a2 x^2 + a3 x^3 + a4 x^4 and denominator q(x) = 1 + e2 x^2
// + e3 x^3 + e4 x^4 with their derivatives, for doubles and Ceres jets alike (p = {a1..a4,
// e2..e4}).
template <class T>
T radial_n(const T* p, const T& x) {
  return x * (p[0] + x * (p[1] + x * (p[2] + x * p[3])));
}
template <class T>
T radial_dn(const T* p, const T& x) {
  return p[0] + x * (T(2) * p[1] + x * (T(3) * p[2] + x * T(4) * p[3]));
}
template <class T>
T radial_q(const T* p, const T& x) {
  return T(1) + x * x * (p[4] + x * (p[5] + x * p[6]));
}
template <class T>
T radial_dq(const T* p, const T& x) {
  return x * (T(2) * p[4] + x * (T(3) * p[5] + x * T(4) * p[6]));
}
}  // namespace detail

namespace {
std::array<double, 7> params_of(const RadialModel& m) {
  return {m.a[0], m.a[1], m.a[2], m.a[3], m.e[0], m.e[1], m.e[2]};
}
}  // namespace

double RadialModel::ground_cm(double r) const {
  const auto p = params_of(*this);
  const double x = r / scale_px;
  return detail::radial_n(p.data(), x) / detail::radial_q(p.data(), x);
}
double RadialModel::slope_cm_per_px(double r) const {
  const auto p = params_of(*this);
  const double x = r / scale_px, q = detail::radial_q(p.data(), x);
  return (detail::radial_dn(p.data(), x) * q -
          detail::radial_n(p.data(), x) * detail::radial_dq(p.data(), x)) /
         (q * q) / scale_px;
}
bool RadialModel::monotonic_up_to(double r_max) const {
  const auto p = params_of(*this);
  for (double r = 0.0; r <= r_max; r += 0.5)
    if (!(detail::radial_q(p.data(), r / scale_px) > 0.0) || !(slope_cm_per_px(r) > 0.0))
      return false;
  return true;
}

namespace {

// Field lines rasterised at 1 cm with a margin around the carpet, and their distance transform
// with, per cell, the nearest white cell (for the re-association).
class FieldDistance {
 public:
  explicit FieldDistance(const FieldGeometry& field) {
    const WhiteLineIndex lines(field);
    nx_ = static_cast<int>(std::ceil(field.total_x_cm() + 2 * kMarginCm));
    ny_ = static_cast<int>(std::ceil(field.total_y_cm() + 2 * kMarginCm));
    cv::Mat1b src(ny_, nx_, std::uint8_t{255});
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i)
        if (lines.is_white(cell_centre(i, j))) src(j, i) = 0;
    cv::Mat labels;
    cv::distanceTransform(src, dist_, labels, cv::DIST_L2, 5, cv::DIST_LABEL_PIXEL);
    label_xy_.assign(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_) + 1,
                     Eigen::Vector2f::Zero());
    nearest_.create(ny_, nx_);
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i)
        if (src(j, i) == 0)
          label_xy_[static_cast<std::size_t>(labels.at<int>(j, i))] =
              cell_centre(i, j).cast<float>();
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i) nearest_(j, i) = labels.at<int>(j, i);
    // The coarse search's copy: 2 cm cells, whole cm, 255 = far (a quarter of the memory, so
    // that the 10^8 look-ups of the brute force stay in the cache).
    coarse_.create((ny_ + 1) / 2, (nx_ + 1) / 2);
    for (int j = 0; j < coarse_.rows; ++j)
      for (int i = 0; i < coarse_.cols; ++i)
        coarse_(j, i) = static_cast<std::uint8_t>(std::min(
            255.0f, std::round(dist_(std::min(2 * j, ny_ - 1), std::min(2 * i, nx_ - 1)))));
  }
  [[nodiscard]] double coarse_distance_cm(double x, double y) const {
    const double fx = (x + kMarginCm) * 0.5,
                 fy = (y + kMarginCm) * 0.5;  // NaN (beyond a horizon) is far too
    if (!(fx >= 0.0 && fy >= 0.0 && fx < coarse_.cols && fy < coarse_.rows)) return 1e4;
    return coarse_(static_cast<int>(fy), static_cast<int>(fx));
  }
  /// Distance (cm) from p to the nearest white line (0 on a line); far beyond the raster, large.
  [[nodiscard]] float distance_cm(const Eigen::Vector2d& p) const {
    const double fx = p.x() + kMarginCm, fy = p.y() + kMarginCm;
    if (!(fx >= 0.0 && fy >= 0.0 && fx < nx_ && fy < ny_)) return 1e4f;
    return dist_(static_cast<int>(fy), static_cast<int>(fx));
  }
  /// Nearest white point to p (p itself on a line).
  [[nodiscard]] Eigen::Vector2d nearest(const Eigen::Vector2d& p) const {
    if (!std::isfinite(p.x()) || !std::isfinite(p.y())) return {0.0, 0.0};
    const int i = static_cast<int>(std::clamp(std::floor(p.x() + kMarginCm), 0.0, nx_ - 1.0));
    const int j = static_cast<int>(std::clamp(std::floor(p.y() + kMarginCm), 0.0, ny_ - 1.0));
    if (dist_(j, i) == 0.0f) return p;
    return label_xy_[static_cast<std::size_t>(nearest_(j, i))].cast<double>();
  }

 private:
  static constexpr double kMarginCm = 150.0;
  [[nodiscard]] static Eigen::Vector2d cell_centre(int i, int j) {
    return {i - kMarginCm + 0.5, j - kMarginCm + 0.5};
  }
  int nx_ = 0, ny_ = 0;
  cv::Mat1f dist_;
  cv::Mat1i nearest_;
  cv::Mat1b coarse_;
  std::vector<Eigen::Vector2f> label_xy_;
};

// A line pixel in polar form about the image centre (image angle, mirrored already applied).
struct PolarPixel {
  double r, phi;  // px, rad
};

std::vector<PolarPixel> to_polar(const std::vector<Eigen::Vector2d>& px, const Eigen::Vector2d& c,
                                 bool mirrored, std::size_t max_count) {
  std::vector<PolarPixel> out;
  const std::size_t stride =
      std::max<std::size_t>(1, px.size() / std::max<std::size_t>(1, max_count));
  for (std::size_t i = 0; i < px.size(); i += stride) {
    const double du = (px[i].x() - c.x()) * (mirrored ? -1.0 : 1.0), dv = c.y() - px[i].y();
    out.push_back({std::hypot(du, dv), std::atan2(dv, du)});
  }
  return out;
}

// Image residual (px) of one line pixel against the nearest line point q, as the fit measures it:
// the ground error split radially (through 1 / d') and tangentially (through r / d). b =
// RadialModel's {a1..a4, e2..e4}. False beyond the model's horizon or where it turns over (no
// distance there): Ceres then takes a shorter step.
template <class T>
bool pixel_residual(const T* c, const T* b, const T* alpha, double u, double v, double sign,
                    double inv_scale, const Eigen::Vector2d& pos, const Eigen::Vector2d& q,
                    T* res) {
  const T du = sign * (T(u) - c[0]), dv = c[1] - T(v);
  const T r = ceres::sqrt(du * du + dv * dv);
  const T x = r * inv_scale;
  const T n = detail::radial_n(b, x), qx = detail::radial_q(b, x);
  const T slope = detail::radial_dn(b, x) * qx - n * detail::radial_dq(b, x);
  if (!(qx > T(0)) || !(slope > T(0))) return false;
  const T d = n / qx;
  const T dd = slope / (qx * qx) * inv_scale;
  const T th = ceres::atan2(dv, du) - alpha[0];
  const T ct = ceres::cos(th), st = ceres::sin(th);
  const T ex = T(pos.x()) + d * ct - T(q.x()), ey = T(pos.y()) + d * st - T(q.y());
  res[0] = (ex * ct + ey * st) / dd;
  res[1] = (-ex * st + ey * ct) * r / d;
  return true;
}

struct PixelCost {
  double u, v, sign, inv_scale, yaw_rad;
  Eigen::Vector2d pos, q;
  template <class T>
  bool operator()(const T* c, const T* b, const T* angle, T* res) const {
    const T alpha = angle[0] - T(yaw_rad);
    return pixel_residual(c, b, &alpha, u, v, sign, inv_scale, pos, q, res);
  }
};

// The camera being fitted: centre, the radial model's {a1..a4, e2..e4} in r / scale, which of
// them are free, and per frame the image angle of the field's x axis.
enum class RadialForm { kQuartic, kRational };

struct FitState {
  double c[2];
  double b[7];
  double scale;  // px: r is normalised by it (the view radius)
  bool mirrored;
  RadialForm form = RadialForm::kQuartic;
  RadialModel model() const { return {scale, {b[0], b[1], b[2], b[3]}, {b[4], b[5], b[6]}}; }
};

struct FrameState {
  const CalibrationFrame* frame;
  const FrameAnalysis* analysis;
  double angle_rad = 0.0;  // yaw known: yaw_offset (shared); unknown: alpha of this frame
  double yaw_rad = 0.0;    // known heading (0 when unknown)
};

double residual_px(const FitState& s, double alpha, const Eigen::Vector2d& pos,
                   const Eigen::Vector2d& px, const FieldDistance& fd,
                   Eigen::Vector2d* ground_err_cm) {
  const double sign = s.mirrored ? -1.0 : 1.0;
  const double du = sign * (px.x() - s.c[0]), dv = s.c[1] - px.y();
  const double r = std::hypot(du, dv), th = std::atan2(dv, du) - alpha;
  const double d = s.model().ground_cm(r);
  const Eigen::Vector2d g = pos + d * Eigen::Vector2d(std::cos(th), std::sin(th));
  const Eigen::Vector2d q = fd.nearest(g);
  if (ground_err_cm != nullptr) *ground_err_cm = g - q;
  double res[2];
  if (!std::isfinite(d) ||
      !pixel_residual(s.c, s.b, &alpha, px.x(), px.y(), sign, 1.0 / s.scale, pos, q, res))
    return 1e9;
  const double e = std::hypot(res[0], res[1]);
  return std::isfinite(e) ? e : 1e9;
}

// Coarse mapping family: d(r) = -D ln(1 - x r / rv) with d(rv) = dv (x = 0.01 is nearly linear,
// x -> 1 a horizon just beyond rv, as mirrors compress the far floor).
struct CoarseMap {
  double dv_cm, x;
};
double coarse_d(const CoarseMap& m, double r, double rv) {
  const double dd = m.dv_cm / -std::log(1.0 - m.x);
  return -dd * std::log(1.0 - m.x * r / rv);
}

struct CoarseHit {
  double score = 1e18;
  CoarseMap map{};
  double alpha = 0.0;
};

// Truncated mean image distance of the pixels to the lines for a mapping and every heading.
// Fills scores[a] for alpha = a * step.
void score_yaws(const std::vector<PolarPixel>& pp, const CoarseMap& m, double rv,
                const Eigen::Vector2d& pos, const FieldDistance& fd, double step_rad,
                double trunc_px, std::vector<double>& scores) {
  const std::size_t n = pp.size();
  std::vector<double> d(n), k(n);
  for (std::size_t i = 0; i < n; ++i) {
    d[i] = coarse_d(m, pp[i].r, rv);
    const double eps = 0.5;
    const double slope =
        (coarse_d(m, pp[i].r + eps, rv) - coarse_d(m, pp[i].r - eps, rv)) / (2 * eps);
    k[i] = std::sqrt((1.0 / slope) * (pp[i].r / d[i]));
  }
  std::vector<double> cp(n), sp(n);
  for (std::size_t i = 0; i < n; ++i) {
    cp[i] = std::cos(pp[i].phi);
    sp[i] = std::sin(pp[i].phi);
  }
  for (std::size_t a = 0; a < scores.size(); ++a) {
    const double alpha = static_cast<double>(a) * step_rad, ca = std::cos(alpha),
                 sa = std::sin(alpha);
    double s = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      // cos / sin of (phi - alpha) by the angle-difference formulas: no trigonometry per pixel.
      const double gx = pos.x() + d[i] * (cp[i] * ca + sp[i] * sa),
                   gy = pos.y() + d[i] * (sp[i] * ca - cp[i] * sa);
      s += std::min(fd.coarse_distance_cm(gx, gy) * k[i], trunc_px);
    }
    scores[a] = s / static_cast<double>(n);
  }
}

void check_frames(const std::vector<CalibrationFrame>& frames, const FieldGeometry& field) {
  if (frames.empty()) throw std::runtime_error("calibrate: no frames");
  const cv::Size size = frames.front().image.size();
  for (const auto& f : frames) {
    if (f.image.empty()) throw std::runtime_error(f.name + ": empty image");
    if (f.image.size() != size) {
      throw std::runtime_error(f.name + ": image is " + std::to_string(f.image.cols) + " x " +
                               std::to_string(f.image.rows) + ", but " + frames.front().name +
                               " is " + std::to_string(size.width) + " x " +
                               std::to_string(size.height) +
                               ": all frames of one camera have one size");
    }
    if (!on_carpet(field, f.position_cm)) {
      throw std::runtime_error(f.name + ": pose (" + std::to_string(f.position_cm.x()) + ", " +
                               std::to_string(f.position_cm.y()) + ") cm is not on the carpet of " +
                               field.name);
    }
  }
}

constexpr double kCoarseTruncPx = 8.0;  // about the basin of the 3-degree heading step at 150 px
constexpr int kCoarseHeadings = 120;

// Best coarse camera per handedness, and the heading scores of its mapping (for the twin).
struct CoarseResult {
  CoarseHit best[2];
  std::vector<double> heading_scores[2];
  detail::CoarseGrid grid;  // the brute force's scores, for picture 5
};

// Brute force on one frame (centre = rim centre): 7 shapes x 51 scales x 120 headings per
// handedness, then 0.5 deg, 1 % scale and +-0.1 shape around the best.
CoarseResult coarse_search(const FrameAnalysis& a, const CalibrationFrame& f,
                           const FieldDistance& fd,
                           const std::function<void(const std::string&)>& say) {
  const double rv = a.view_radius_px;
  const std::vector<double> shapes{0.01, 0.3, 0.5, 0.65, 0.8, 0.9, 0.95};
  CoarseResult out;
  out.grid.heading_step_deg = 360.0 / kCoarseHeadings;
  std::vector<double> scores(static_cast<std::size_t>(kCoarseHeadings));
  for (int mir = 0; mir < 2; ++mir) {
    cv::Mat1f& grid = out.grid.score_px[mir];
    grid.create(detail::CoarseGrid::kScales, kCoarseHeadings);
    grid.setTo(1e9f);
    say(std::string("coarse search (") + (mir ? "mirrored" : "not mirrored") +
        "): 7 shapes x 51 scales x 120 headings");
    CoarseHit& best = out.best[mir];
    const auto pp = to_polar(a.line_pixels, a.rim.centre_px, mir == 1, 1000);
    for (double x : shapes) {
      for (int si = 0; si < detail::CoarseGrid::kScales; ++si) {
        const CoarseMap m{detail::CoarseGrid::view_cm(si), x};
        score_yaws(pp, m, rv, f.position_cm, fd, 2 * kPi / kCoarseHeadings, kCoarseTruncPx, scores);
        for (int k = 0; k < kCoarseHeadings; ++k) {
          grid(si, k) = std::min(
              grid(si, k), static_cast<float>(scores[static_cast<std::size_t>(k)]));  // best shape
          if (scores[static_cast<std::size_t>(k)] < best.score) {
            best = {scores[static_cast<std::size_t>(k)], m, k * 2 * kPi / kCoarseHeadings};
            out.heading_scores[mir] = scores;
          }
        }
      }
    }
    const auto pp2 = to_polar(a.line_pixels, a.rim.centre_px, mir == 1, 3000);
    const CoarseHit c = best;
    best.score = 1e18;
    std::vector<double> s1(1);
    for (double dx = -0.1; dx <= 0.1001; dx += 0.05) {
      const double x = std::clamp(c.map.x + dx, 0.01, 0.97);
      for (int si = -8; si <= 8; ++si) {
        const CoarseMap m{c.map.dv_cm * std::pow(1.01, si), x};
        for (int k = -6; k <= 6; ++k) {
          const double alpha = c.alpha + deg_to_rad(0.5 * k);
          std::vector<PolarPixel> rot = pp2;
          for (auto& p : rot) p.phi -= alpha;
          score_yaws(rot, m, rv, f.position_cm, fd, 0.0, kCoarseTruncPx, s1);
          if (s1[0] < best.score) best = {s1[0], m, alpha};
        }
      }
    }
  }
  return out;
}

// The radial model through the coarse curve, least squares over 0..1.1 view radii (short of the
// coarse curve's horizon). Quartic: d = sum a_k x^k. Rational (a2..a4 = 0): d q(x) = a1 x is linear
// in (a1, e2, e3, e4).
void initial_model(const CoarseHit& hit, FitState& st) {
  Eigen::MatrixXd A(100, 4);
  Eigen::VectorXd y(100);
  const bool rational = st.form == RadialForm::kRational;
  for (int i = 0; i < 100; ++i) {
    const double x = std::min((i + 1) / 100.0 * 1.1, 0.999 / hit.map.x);
    const double d = coarse_d(hit.map, x * st.scale, st.scale);
    if (rational)
      A.row(i) << x, -d * x * x, -d * x * x * x, -d * x * x * x * x;
    else
      A.row(i) << x, x * x, x * x * x, x * x * x * x;
    y(i) = d;
  }
  const Eigen::Vector4d b = A.colPivHouseholderQr().solve(y);
  std::fill(std::begin(st.b), std::end(st.b), 0.0);
  st.b[0] = b(0);
  for (int k = 1; k < 4; ++k) st.b[rational ? 3 + k : k] = b(k);
}

// Every 10 px ring of radii weighs alike (square root of the inverse pixel count, 1/3..3): the
// few lines near the body otherwise count for nothing against the many far ones.
struct RingWeights {
  const FitState& st;
  std::vector<int> ring = std::vector<int>(64, 0);
  int rings = 0, ring_total = 0;
  [[nodiscard]] std::size_t ring_of(const Eigen::Vector2d& p) const {
    return static_cast<std::size_t>(
        std::min(63.0, std::hypot(p.x() - st.c[0], p.y() - st.c[1]) / 10.0));
  }
  [[nodiscard]] double weight(const Eigen::Vector2d& p) const {
    return std::clamp(std::sqrt(static_cast<double>(ring_total) / std::max(1, rings) /
                                std::max(1, ring[ring_of(p)])),
                      1.0 / 3.0, 3.0);
  }
};

RingWeights ring_weights(const FitState& st, const std::vector<FrameState>& fs) {
  RingWeights rw{st};
  for (const auto& s : fs)
    for (const auto& p : s.analysis->line_pixels) ++rw.ring[rw.ring_of(p)];
  for (int n : rw.ring) {
    rw.rings += n > 0;
    rw.ring_total += n;
  }
  return rw;
}

// One refinement's problem: a Huber-robust, ring-weighted cost per line pixel within `trunc` px
// of the field model, against its nearest line point now. Returns how many pixels it holds.
int add_pixel_costs(ceres::Problem& problem, FitState& st, std::vector<FrameState>& fs,
                    double& shared_angle, const FieldDistance& fd, const RingWeights& rw,
                    double trunc) {
  int used = 0;
  for (auto& s : fs) {
    double* angle = s.frame->yaw_deg ? &shared_angle : &s.angle_rad;
    const double alpha = *angle - s.yaw_rad;
    const auto& lp = s.analysis->line_pixels;
    const std::size_t stride = std::max<std::size_t>(1, lp.size() / 6000);
    const double sign = st.mirrored ? -1.0 : 1.0;
    for (std::size_t j = 0; j < lp.size(); j += stride) {
      if (residual_px(st, alpha, s.frame->position_cm, lp[j], fd, nullptr) > trunc) continue;
      const double du = sign * (lp[j].x() - st.c[0]), dv = st.c[1] - lp[j].y();
      const double d = st.model().ground_cm(std::hypot(du, dv));
      const double th = std::atan2(dv, du) - alpha;
      const Eigen::Vector2d g =
          s.frame->position_cm + d * Eigen::Vector2d(std::cos(th), std::sin(th));
      auto* cost = new ceres::AutoDiffCostFunction<PixelCost, 2, 2, 7, 1>(
          new PixelCost{lp[j].x(), lp[j].y(), sign, 1.0 / st.scale, s.yaw_rad, s.frame->position_cm,
                        fd.nearest(g)});
      const double w = rw.weight(lp[j]);
      problem.AddResidualBlock(
          cost, new ceres::ScaledLoss(new ceres::HuberLoss(1.0), w * w, ceres::TAKE_OWNERSHIP),
          st.c, st.b, angle);
      ++used;
    }
  }
  return used;
}

// Solves one refinement's problem with the form's fixed terms held (the quartic's denominator,
// the rational form's a2..a4); returns the final cost.
double solve_refinement(ceres::Problem& problem, FitState& st) {
  problem.SetManifold(st.b, new ceres::SubsetManifold(7, st.form == RadialForm::kQuartic
                                                             ? std::vector<int>{4, 5, 6}
                                                             : std::vector<int>{1, 2, 3}));
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = 50;
  // Quiet: a step past the rational form's horizon fails to evaluate by design (PixelCost says
  // so) and Ceres would warn about each on stderr; the progress callback reports the refinement.
  so.logging_type = ceres::SILENT;
  so.num_threads = 1;
  ceres::Solver::Summary sum;
  ceres::Solve(so, &problem, &sum);
  return sum.final_cost;
}

// Robust refinement: Huber (1 px) on the image residual, pixels beyond a shrinking truncation
// dropped, nearest line points re-associated between solves. Frames with a known heading share
// one yaw offset (`shared_angle`); the others have their own heading term.
void refine(FitState& st, std::vector<FrameState>& fs, double& shared_angle,
            const FieldDistance& fd, const std::function<void(const std::string&)>& say) {
  const double trunc_schedule[] = {8.0, 6.0, 4.0, 3.0, 3.0, 3.0, 3.0, 3.0, 3.0, 3.0, 3.0, 3.0};
  for (std::size_t it = 0; it < std::size(trunc_schedule); ++it) {
    const RingWeights rw = ring_weights(st, fs);
    ceres::Problem problem;
    const int used = add_pixel_costs(problem, st, fs, shared_angle, fd, rw, trunc_schedule[it]);
    if (used < 50) {
      throw std::runtime_error(fs.front().frame->name + ": nothing fits: only " +
                               std::to_string(used) +
                               " line pixels lie near the field model at the best coarse camera");
    }
    const double final_cost = solve_refinement(problem, st);
    say("refinement " + std::to_string(it + 1) + "/" + std::to_string(std::size(trunc_schedule)) +
        ": " + std::to_string(used) + " pixels within " + std::to_string(trunc_schedule[it]) +
        " px, centre (" + std::to_string(st.c[0]) + ", " + std::to_string(st.c[1]) + "), cost " +
        std::to_string(final_cost));
  }
  for (auto& s : fs)
    if (s.frame->yaw_deg) s.angle_rad = shared_angle;
}

// Picture 6 per frame: every line pixel's residual at the refined camera.
void show_residuals(const FitState& st, const std::vector<FrameState>& fs, const FieldDistance& fd,
                    double inlier_threshold_px, const StepPictureSink& pictures) {
  for (const auto& s : fs) {
    const double alpha = s.angle_rad - s.yaw_rad;
    std::vector<double> e_px;
    for (const auto& p : s.analysis->line_pixels)
      e_px.push_back(residual_px(st, alpha, s.frame->position_cm, p, fd, nullptr));
    pictures(s.frame->name, "6-residuals",
             detail::residuals_picture(s.frame->image, s.analysis->line_pixels, e_px,
                                       inlier_threshold_px));
  }
}

// Residuals per frame over every line pixel, and the totals.
void measure_residuals(const FitState& st, const std::vector<FrameState>& fs,
                       const FieldDistance& fd, CalibrationResult& res) {
  std::vector<double> all_px;
  double sum_px2 = 0.0, sum_cm2 = 0.0;
  int inl_total = 0;
  for (const auto& s : fs) {
    FrameFit ff;
    ff.yaw_given = s.frame->yaw_deg.has_value();
    const double alpha = s.angle_rad - s.yaw_rad;
    ff.image_angle_of_field_x_deg = wrap_deg(rad_to_deg(alpha));
    std::vector<double> e_px;
    double s2 = 0.0, c2 = 0.0;
    for (const auto& p : s.analysis->line_pixels) {
      Eigen::Vector2d err;
      const double e = residual_px(st, alpha, s.frame->position_cm, p, fd, &err);
      e_px.push_back(e);
      if (e <= res.inlier_threshold_px) {
        s2 += e * e;
        c2 += err.squaredNorm();
        ++ff.inliers;
      }
    }
    all_px.insert(all_px.end(), e_px.begin(), e_px.end());
    ff.line_pixels = static_cast<int>(e_px.size());
    ff.rms_px = std::sqrt(s2 / std::max(1, ff.inliers));
    ff.rms_cm = std::sqrt(c2 / std::max(1, ff.inliers));
    std::nth_element(e_px.begin(), e_px.begin() + static_cast<std::ptrdiff_t>(e_px.size() / 2),
                     e_px.end());
    ff.median_px = e_px[e_px.size() / 2];
    sum_px2 += s2;
    sum_cm2 += c2;
    inl_total += ff.inliers;
    res.fits.push_back(ff);
  }
  res.inlier_fraction =
      static_cast<double>(inl_total) / std::max<double>(1.0, static_cast<double>(all_px.size()));
  res.rms_px = std::sqrt(sum_px2 / std::max(1, inl_total));
  res.rms_cm = std::sqrt(sum_cm2 / std::max(1, inl_total));
  std::nth_element(all_px.begin(), all_px.begin() + static_cast<std::ptrdiff_t>(all_px.size() / 2),
                   all_px.end());
  res.median_px = all_px[all_px.size() / 2];
}

// Radii where the mapping is measured: inlier pixels on lines that cross their ray (shorter
// along the ray than across it); a line running along the ray says nothing about distance.
void measured_radii(const FitState& st, const std::vector<FrameState>& fs, const FieldDistance& fd,
                    CalibrationResult& res) {
  std::vector<double> crossing_r;
  const Eigen::Vector2d c(st.c[0], st.c[1]);
  for (const auto& s : fs) {
    const double alpha = s.angle_rad - s.yaw_rad;
    const cv::Mat& lm = s.analysis->line_mask;
    auto run = [&](const Eigen::Vector2d& p, const Eigen::Vector2d& dir) {
      int n = 0;
      for (double sgn : {-1.0, 1.0}) {
        for (int k = 1; k <= 20; ++k) {
          const Eigen::Vector2d q = p + sgn * k * dir;
          const int u = static_cast<int>(std::lround(q.x())),
                    v = static_cast<int>(std::lround(q.y()));
          if (u < 0 || v < 0 || u >= lm.cols || v >= lm.rows || !lm.at<std::uint8_t>(v, u)) break;
          ++n;
        }
      }
      return n;
    };
    for (const auto& p : s.analysis->line_pixels) {
      if (residual_px(st, alpha, s.frame->position_cm, p, fd, nullptr) > res.inlier_threshold_px)
        continue;
      const Eigen::Vector2d radial = (p - c).normalized(), tangential(-radial.y(), radial.x());
      if (run(p, radial) < run(p, tangential)) crossing_r.push_back((p - c).norm());
    }
  }
  if (crossing_r.size() < 20) {
    throw std::runtime_error(
        fs.front().frame->name +
        ": nothing fits: no line seen crossing the rays, the mapping is not measured");
  }
  std::sort(crossing_r.begin(), crossing_r.end());
  res.measured_min_px = crossing_r[crossing_r.size() / 20];
  res.measured_max_px = crossing_r[crossing_r.size() - 1 - crossing_r.size() / 20];
}

// The camera in the project's model. Unknown headings: the offset is the image angle of the
// robot's x axis with the robot facing field x (heading 0); the twin (180 deg away) fits the
// symmetric field equally.
void build_camera(const FitState& st, const std::vector<FrameState>& fs, double yaw_offset_rad,
                  const cv::Size& size, CalibrationResult& res) {
  const FrameAnalysis& a0 = res.analyses.front();
  CameraModel& cam = res.camera;
  cam.width_px = size.width;
  cam.height_px = size.height;
  cam.center_px = {st.c[0], st.c[1]};
  cam.mirrored = st.mirrored;
  cam.yaw_offset_deg = wrap_deg(rad_to_deg(yaw_offset_rad));
  for (std::size_t i = 0; i < fs.size(); ++i) {
    FrameFit& ff = res.fits[i];
    ff.yaw_deg = fs[i].frame->yaw_deg
                     ? *fs[i].frame->yaw_deg
                     : wrap_deg(cam.yaw_offset_deg - ff.image_angle_of_field_x_deg);
  }
  // The table reaches as far as the lines measured the mapping, not only to where the carpet ends
  // all round: the line extraction ends each ray at the carpet's edge or an obstacle frame by
  // frame, so a robot or a goal near the calibration spot no longer shrinks the view of every later
  // frame. (Any length: the scan samples a long view more coarsely, CameraModel::scan_step_px.)
  const double lut_end =
      std::max(res.view_radius_px,
               res.radial.monotonic_up_to(res.measured_max_px) ? res.measured_max_px : 0.0);
  for (double r = 0.0; r < lut_end; r += 4.0)
    cam.radius_lut.push_back({r, res.radial.ground_cm(r)});
  cam.radius_lut.push_back({lut_end, res.radial.ground_cm(lut_end)});
  cam.body_radius_px = a0.body_radius_px;
  for (const auto& m : a0.masts_image) {
    const double image_angle = st.mirrored ? 180.0 - m.bearing_deg : m.bearing_deg;
    cam.masts.push_back({wrap_deg(image_angle - cam.yaw_offset_deg), m.half_width_deg});
  }
}

}  // namespace

namespace {
// The goals of every frame: each colour from the frame where its region is largest; the colour at
// x = max from the frames whose heading was given (the fitted heading of a symmetric view may be a
// twin, 180 deg off, so a found heading does not tell the ends apart).
void measure_venue_goals(const std::vector<CalibrationFrame>& frames, const FieldGeometry& field,
                         const GoalColourOptions& options, CalibrationResult& res) {
  GoalColour at_max = GoalColour::kUnknown;
  bool conflict =
      res.yaw_offset_ambiguous;  // the offset may be the twin's: the ends cannot be told
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const GoalColours g = measure_goal_colours(frames[i].image, res.analyses[i], options);
    for (const auto& [mine, best] :
         {std::pair{&g.blue, &res.goals.blue}, std::pair{&g.yellow, &res.goals.yellow}})
      if (*mine && (!*best || (*mine)->pixels > (*best)->pixels)) *best = *mine;
    if (!frames[i].yaw_deg) continue;
    const GoalColour c =
        goal_colour_at_x_max(g, res.camera, frames[i].position_cm, *frames[i].yaw_deg, field);
    if (c == GoalColour::kUnknown) continue;
    conflict = conflict || (at_max != GoalColour::kUnknown && at_max != c);
    at_max = c;
  }
  res.goal_colour_at_x_max = conflict ? GoalColour::kUnknown : at_max;
}
}  // namespace

namespace {
// The camera against each frame: how much of the field's lines it puts on the carpet is seen
// there as line (docs/CALIBRATION.md, step 8). A camera that puts most of the lines where the frame
// shows none is refused: the same 40 % as the inlier check, from the other side (that check asks
// how much of what the frame shows the camera explains; this one how much of what the camera
// predicts the frame shows). It judges only from 100 points on (the fraction known to about 5 %):
// a camera that puts fewer line points on the carpet (a short table, a small view) is not judged.
constexpr double kMinLineRecall = 0.4;
constexpr int kMinRecallPoints = 100;

void self_check(const std::vector<CalibrationFrame>& frames, const FieldGeometry& field,
                CalibrationResult& res) {
  for (std::size_t i = 0; i < frames.size(); ++i) {
    FrameFit& ff = res.fits[i];
    const Pose2 pose{frames[i].position_cm.x(), frames[i].position_cm.y(), ff.yaw_deg};
    const detail::LineRecall lr =
        detail::model_line_recall(res.camera, res.analyses[i], pose, field);
    ff.line_recall = lr.fraction();
    ff.recall_points = lr.expected;
  }
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const FrameFit& ff = res.fits[i];
    if (ff.recall_points < kMinRecallPoints || ff.line_recall >= kMinLineRecall) continue;
    throw std::runtime_error(
        frames[i].name + ": self-check failed: only " +
        std::to_string(static_cast<int>(100 * ff.line_recall)) + " % of the " +
        std::to_string(ff.recall_points) +
        " line points the fitted camera puts on the carpet are seen as lines (at least " +
        std::to_string(static_cast<int>(100 * kMinLineRecall)) +
        " %): the camera is wrong (see --debug-dir's residuals; check the pose and field, give "
        "--center with --rim-radius, "
        "or add a frame at another spot)");
  }
}

// What decides the handedness: the team's --mirrored, or frames that can tell it (then the lines'
// scores decide); with neither, the handedness is unknown and no camera is written, since the
// lines' choice would be a guess (wrong in 13 of 19 centre-spot trials of issue [1/4]).
std::string decide_handedness(const std::vector<CalibrationFrame>& frames,
                              const FieldGeometry& field, const std::optional<bool>& given) {
  if (given) return "given (--mirrored)";
  const double separation_cm = MatchOptions{}.ambiguity_separation_cm;
  if (auto evidence = detail::handedness_evidence(frames, field, separation_cm))
    return "the lines: " + *evidence;
  throw std::runtime_error(
      frames.front().name + ": handedness unknown: every frame stands on a mirror axis of " +
      field.name + "'s lines (within " + std::to_string(static_cast<int>(separation_cm / 2)) +
      " cm), where a mirrored camera sees what an unmirrored one sees: give --mirrored yes|no, or "
      "add a frame at a "
      "known spot off the axes (or two frames whose known headings differ)");
}
}  // namespace

namespace {

using Say = std::function<void(const std::string&)>;

// Steps 1-4 of every frame: rim, carpet, lines, body and masts.
void analyse_frames(const std::vector<CalibrationFrame>& frames, const CalibrationOptions& options,
                    const Say& say, CalibrationResult& res) {
  for (const auto& f : frames) {
    say(f.name + ": finding the mirror rim, carpet, lines, body and masts");
    res.analyses.push_back(analyse_frame(f.image, f.name, options.hints, options.step_pictures));
    const auto& a = res.analyses.back();
    say(f.name + ": rim (" + std::to_string(a.rim.centre_px.x()) + ", " +
        std::to_string(a.rim.centre_px.y()) + ") r " + std::to_string(a.rim.radius_px) + " px, " +
        std::to_string(a.line_pixels.size()) + " line pixels");
  }
}

// The coarse search's handedness: 1 mirrored, 0 not. Within 3 %: the lines seen do not tell the
// handedness (a view symmetric about the robot); the team's --mirrored then decides (and
// overrides the lines when given).
int coarse_handedness(const CoarseResult& coarse, const CalibrationOptions& options, double rv,
                      const Say& say, CalibrationResult& res) {
  res.unmirrored_score = coarse.best[0].score;
  res.mirrored_score = coarse.best[1].score;
  res.mirrored_ambiguous = std::abs(res.mirrored_score - res.unmirrored_score) <
                           0.03 * std::min(res.mirrored_score, res.unmirrored_score);
  const int mir = options.hints.mirrored ? (*options.hints.mirrored ? 1 : 0)
                                         : (res.mirrored_score < res.unmirrored_score ? 1 : 0);
  if (options.hints.mirrored) res.mirrored_ambiguous = false;
  const CoarseHit& hit = coarse.best[mir];
  say("coarse best: " + std::string(mir ? "mirrored" : "not mirrored") + ", heading term " +
      std::to_string(rad_to_deg(hit.alpha)) + " deg, d(" + std::to_string(rv) +
      " px) = " + std::to_string(hit.map.dv_cm) + " cm, shape " + std::to_string(hit.map.x) +
      ", truncated mean " + std::to_string(hit.score) + " px" +
      (res.mirrored_ambiguous ? " (handedness ambiguous)" : ""));
  return mir;
}

// Each frame's starting heading term: the coarse hit's for the first, the other frames' searched
// with the first frame's mapping. Frames with a known heading share one yaw offset
// (shared_angle, any_known set).
std::vector<FrameState> initial_frames(const std::vector<CalibrationFrame>& frames,
                                       const CalibrationResult& res, const CoarseHit& hit,
                                       const FitState& st, const FieldDistance& fd,
                                       double& shared_angle, bool& any_known) {
  const FrameAnalysis& a0 = res.analyses.front();
  const double rv = a0.view_radius_px;
  std::vector<FrameState> fs;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    FrameState s{&frames[i], &res.analyses[i]};
    if (frames[i].yaw_deg) s.yaw_rad = deg_to_rad(*frames[i].yaw_deg);
    if (i == 0) {
      s.angle_rad = hit.alpha + s.yaw_rad;
    } else {  // the other frames' headings: searched with the first frame's mapping
      const auto pp = to_polar(s.analysis->line_pixels, a0.rim.centre_px, st.mirrored, 1500);
      std::vector<double> sc(720);
      score_yaws(pp, hit.map, rv, s.frame->position_cm, fd, 2 * kPi / 720, kCoarseTruncPx, sc);
      const auto k = std::min_element(sc.begin(), sc.end()) - sc.begin();
      s.angle_rad = static_cast<double>(k) * 2 * kPi / 720 + s.yaw_rad;
    }
    if (frames[i].yaw_deg) {
      any_known = true;
      shared_angle = s.angle_rad;
    }
    fs.push_back(s);
  }
  return fs;
}

// Whether the model is monotonic over the lines' reach (and the view), with the line pixels'
// radii from the centre, sorted, in line_r (the refusal below quotes them).
bool monotonic_over_lines(const CalibrationResult& res, const FitState& st,
                          std::vector<double>& line_r) {
  line_r.clear();
  for (const auto& a : res.analyses)
    for (const auto& p : a.line_pixels)
      line_r.push_back(std::hypot(p.x() - st.c[0], p.y() - st.c[1]));
  std::sort(line_r.begin(), line_r.end());
  const RadialModel m = st.model();
  return m.monotonic_up_to(std::max(line_r.empty() ? 0.0 : line_r.back(), res.view_radius_px)) &&
         m.ground_cm(res.view_radius_px) > 0;
}

// The quartic first; where it turns over within the lines' reach (a mirror whose floor distance
// climbs towards its horizon, which no polynomial follows), the rational form from the same
// start.
void fit_radial(FitState& st, std::vector<FrameState>& fs, double& shared_angle,
                const CoarseHit& hit, const FieldDistance& fd, const CalibrationResult& res,
                const Say& say) {
  const FitState start = st;
  const std::vector<FrameState> fs_start = fs;
  const double shared_start = shared_angle;
  refine(st, fs, shared_angle, fd, say);
  std::vector<double> line_r;
  if (!monotonic_over_lines(res, st, line_r)) {
    say("the quartic turns over within the lines' reach: fitting the rational form (the mirror's "
        "horizon)");
    st = start;
    st.form = RadialForm::kRational;
    fs = fs_start;
    shared_angle = shared_start;
    initial_model(hit, st);
    refine(st, fs, shared_angle, fd, say);
  }
}

// Neither form monotonic: say where the lines were, since a band of radii measures the mapping
// only there.
[[noreturn]] void refuse_non_monotonic(const std::vector<CalibrationFrame>& frames,
                                       const std::vector<double>& line_r) {
  const double r_used = line_r.empty() ? 0.0 : line_r.back();
  const auto pct = [&](double q) {
    return static_cast<int>(
        line_r[static_cast<std::size_t>(q * static_cast<double>(line_r.size() - 1))]);
  };
  throw std::runtime_error(
      frames.front().name +
      ": nothing fits: neither the quartic nor the rational radial model is monotonic over the " +
      std::to_string(static_cast<int>(r_used)) +
      " px the lines span (90 % of the line pixels lie between " + std::to_string(pct(0.05)) +
      " and " + std::to_string(pct(0.95)) +
      " px from the centre: add a frame where lines cross the view at other distances)");
}

// The fit's start: the rim's centre, the first frame's view radius as the scale, the coarse
// hit's mapping and handedness.
FitState starting_state(const FrameAnalysis& a0, int mir, const CoarseHit& hit) {
  FitState st{};
  st.c[0] = a0.rim.centre_px.x();
  st.c[1] = a0.rim.centre_px.y();
  st.scale = a0.view_radius_px;
  st.mirrored = mir == 1;
  initial_model(hit, st);
  return st;
}

// Most line pixels must lie on the model: otherwise the pose, the field or the frame is wrong.
void refuse_few_inliers(const std::vector<CalibrationFrame>& frames, const CalibrationResult& res) {
  if (res.inlier_fraction < 0.4) {
    throw std::runtime_error(frames.front().name + ": nothing fits: only " +
                             std::to_string(static_cast<int>(100 * res.inlier_fraction)) +
                             " % of the line pixels lie within " +
                             std::to_string(res.inlier_threshold_px) +
                             " px of the field model at the best camera (wrong pose or field?)");
  }
}

// Twin of the first frame: its best coarse heading term at least 30 deg from the fitted one.
void find_twin(const CoarseResult& coarse, int mir, CalibrationResult& res) {
  const CoarseHit& hit = coarse.best[mir];
  FrameFit& f0 = res.fits.front();
  f0.score = hit.score;
  f0.twin_score = 1e18;
  const auto& sc = coarse.heading_scores[mir];
  for (int k = 0; k < kCoarseHeadings; ++k) {
    const double a_deg = k * 360.0 / kCoarseHeadings;
    if (std::abs(angle_diff_deg(a_deg, rad_to_deg(hit.alpha))) < 30.0 ||
        !(sc[static_cast<std::size_t>(k)] < f0.twin_score))
      continue;
    f0.twin_score = sc[static_cast<std::size_t>(k)];
    f0.twin_yaw_deg = wrap_deg(f0.yaw_deg + f0.image_angle_of_field_x_deg - a_deg);
  }
}

}  // namespace

CalibrationResult calibrate_camera(const std::vector<CalibrationFrame>& frames,
                                   const FieldGeometry& field, const CalibrationOptions& options) {
  const Say say = [&](const std::string& m) {
    if (options.progress) options.progress(m);
  };
  check_frames(frames, field);
  CalibrationResult res;
  analyse_frames(frames, options, say, res);
  res.handedness_from = decide_handedness(frames, field, options.hints.mirrored);
  say("building the field's distance transform");
  const FieldDistance fd(field);
  const FrameAnalysis& a0 = res.analyses.front();
  const double rv = a0.view_radius_px;

  const CoarseResult coarse = coarse_search(a0, frames.front(), fd, say);
  if (options.step_pictures)
    options.step_pictures(frames.front().name, "5-coarse",
                          detail::coarse_picture(coarse.grid, kCoarseTruncPx));
  const int mir = coarse_handedness(coarse, options, rv, say, res);
  const CoarseHit& hit = coarse.best[mir];

  FitState st = starting_state(a0, mir, hit);
  double shared_angle = 0.0;
  bool any_known = false;
  std::vector<FrameState> fs = initial_frames(frames, res, hit, st, fd, shared_angle, any_known);
  res.inlier_threshold_px = 3.0;  // a 5 cm line far away is 1-2 px: 3 px is one line width off
  // The view: where the carpet ends all round in every frame.
  res.view_radius_px = rv;
  for (const auto& a : res.analyses)
    res.view_radius_px = std::min(res.view_radius_px, a.view_radius_px);
  fit_radial(st, fs, shared_angle, hit, fd, res, say);
  // Before the refusals below (non-monotonic model, too few inliers): their cause is in this
  // picture.
  if (options.step_pictures)
    show_residuals(st, fs, fd, res.inlier_threshold_px, options.step_pictures);
  res.radial = st.model();
  if (std::vector<double> line_r; !monotonic_over_lines(res, st, line_r))
    refuse_non_monotonic(frames, line_r);
  measure_residuals(st, fs, fd, res);
  refuse_few_inliers(frames, res);
  measured_radii(st, fs, fd, res);
  build_camera(st, fs, any_known ? shared_angle : fs.front().angle_rad, frames.front().image.size(),
               res);
  self_check(frames, field, res);
  find_twin(coarse, mir, res);
  // The field is point-symmetric about its centre: from there (within the localizer's ambiguity
  // separation) the lines look the same at the offset 180 deg away, whatever the scores say. One
  // frame elsewhere tells them apart (the offset is shared).
  res.yaw_offset_ambiguous =
      std::all_of(frames.begin(), frames.end(), [&](const CalibrationFrame& f) {
        return (f.position_cm - field.centre_cm()).norm() < MatchOptions{}.ambiguity_separation_cm;
      });
  res.rim = a0.rim;
  res.carpet = a0.carpet;
  measure_venue_goals(frames, field, options.goal_colours, res);
  return res;
}

namespace {
// The venue's colour model (schema in docs/CALIBRATION.md; read by the vision configuration).
nlohmann::ordered_json vision_json(const CalibrationResult& r) {
  nlohmann::ordered_json v;
  v["carpet_hsv"] = {{"hue", r.carpet.hue},
                     {"hue_half_width", r.carpet.hue_half_width},
                     {"sat_min", r.carpet.sat_min},
                     {"val_min", r.carpet.val_min},
                     {"val_max", r.carpet.val_max}};
  v["line_contrast"] = {{"val_step", r.carpet.line_val_step}, {"sat_step", r.carpet.line_sat_step}};
  nlohmann::ordered_json goals = nlohmann::ordered_json::object();
  for (const auto& [name, g] :
       {std::pair{"blue", &r.goals.blue}, std::pair{"yellow", &r.goals.yellow}}) {
    if (!*g) continue;
    const HsvClass& c = (*g)->colour;
    goals[name] = {{"hue", c.hue},
                   {"hue_half_width", c.hue_half_width},
                   {"sat_min", c.sat_min},
                   {"val_min", c.val_min}};
  }
  v["goals"] = goals;
  if (r.goal_colour_at_x_max != GoalColour::kUnknown)
    v["goal_colour_at_x_max"] = goal_colour_name(r.goal_colour_at_x_max);
  return v;
}
}  // namespace

namespace {
// Per frame: where it was taken, the heading found and how well the camera fits it.
nlohmann::ordered_json frames_json(const CalibrationResult& r,
                                   const std::vector<CalibrationFrame>& frames) {
  nlohmann::ordered_json fr = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < frames.size() && i < r.fits.size(); ++i) {
    const auto& f = r.fits[i];
    fr.push_back({{"image", frames[i].name},
                  {"position_cm", {frames[i].position_cm.x(), frames[i].position_cm.y()}},
                  {"yaw_deg", f.yaw_deg},
                  {"yaw_given", f.yaw_given},
                  {"rms_px", f.rms_px},
                  {"line_pixels", f.line_pixels},
                  {"inliers", f.inliers},
                  {"line_recall", f.line_recall},
                  {"recall_points", f.recall_points}});
  }
  return fr;
}

// The "calibration" block: how the camera was found (the camera reader ignores it).
nlohmann::ordered_json calibration_json(const CalibrationResult& r,
                                        const std::vector<CalibrationFrame>& frames) {
  nlohmann::ordered_json cal;
  cal["radial_model"] = {
      {"form", r.radial.rational() ? "rational: ground_cm = a1 x / (1 + e2 x^2 + e3 x^3 + e4 x^4)"
                                   : "quartic: ground_cm = a1 x + a2 x^2 + a3 x^3 + a4 x^4"},
      {"x", "r / scale_px, r in px from center_px"},
      {"scale_px", r.radial.scale_px},
      {"a", r.radial.a},
      {"e", r.radial.e},
      {"note",
       "measured between measured_radii_px (5-95 % of the inlier pixels on lines crossing "
       "their ray); extrapolated outside"}};
  cal["view_radius_px"] = r.view_radius_px;
  cal["measured_radii_px"] = {r.measured_min_px, r.measured_max_px};
  cal["rim"] = {{"center_px", {r.rim.centre_px.x(), r.rim.centre_px.y()}},
                {"radius_px", r.rim.radius_px},
                {"rays_on_circle", r.rim.rays_on_circle}};
  cal["carpet_hsv"] = {{"hue", r.carpet.hue},
                       {"hue_half_width", r.carpet.hue_half_width},
                       {"sat_min", r.carpet.sat_min},
                       {"val_min", r.carpet.val_min},
                       {"val_max", r.carpet.val_max},
                       {"median_sat", r.carpet.median_sat},
                       {"median_val", r.carpet.median_val},
                       {"line_val_step", r.carpet.line_val_step},
                       {"line_sat_step", r.carpet.line_sat_step}};
  cal["mirrored_ambiguous"] = r.mirrored_ambiguous;
  cal["handedness_from"] = r.handedness_from;
  cal["yaw_offset_ambiguous"] = r.yaw_offset_ambiguous;
  cal["residual"] = {{"rms_px", r.rms_px},
                     {"rms_cm", r.rms_cm},
                     {"median_px", r.median_px},
                     {"inlier_fraction", r.inlier_fraction},
                     {"inlier_threshold_px", r.inlier_threshold_px}};
  cal["frames"] = frames_json(r, frames);
  return cal;
}
}  // namespace

std::string calibrated_camera_json(const CalibrationResult& r,
                                   const std::vector<CalibrationFrame>& frames) {
  nlohmann::ordered_json j;
  const CameraModel& c = r.camera;
  j["description"] = "Calibrated by `omniloc calibrate` from " + std::to_string(frames.size()) +
                     " frame(s); radius_lut samples the fitted radial model every 4 px and ends at "
                     "the view radius "
                     "(where the carpet ends all round). The \"calibration\" block records how; "
                     "the camera reader ignores it.";
  j["width"] = c.width_px;
  j["height"] = c.height_px;
  j["center_px"] = {c.center_px.x(), c.center_px.y()};
  nlohmann::ordered_json lut = nlohmann::ordered_json::array();
  for (const auto& m : c.radius_lut)
    lut.push_back({std::round(m.radius_px * 1000) / 1000, std::round(m.ground_cm * 1000) / 1000});
  j["radius_lut"] = lut;
  j["yaw_offset_deg"] = c.yaw_offset_deg;
  j["mirrored"] = c.mirrored;
  nlohmann::ordered_json masts = nlohmann::ordered_json::array();
  for (const auto& m : c.masts)
    masts.push_back({{"bearing_deg", m.bearing_deg}, {"half_width_deg", m.half_width_deg}});
  j["mask"] = {{"body_radius_px", c.body_radius_px}, {"masts", masts}};
  j["calibration"] = calibration_json(r, frames);
  j["vision"] = vision_json(r);
  return j.dump(2) + "\n";
}

cv::Mat calibration_overlay(const CalibrationFrame& frame, const FrameAnalysis& a,
                            const FrameFit& fit, const CalibrationResult& r,
                            const FieldGeometry& field) {
  cv::Mat out = frame.image.clone();
  const CameraModel& cam = r.camera;
  for (const auto& p : a.line_pixels)
    out.at<cv::Vec3b>(static_cast<int>(p.y()), static_cast<int>(p.x())) = {255, 0, 255};
  // Field model: ground distance -> radius by bisection in the fitted model (beyond the LUT's
  // view radius too, up to the rim, so the whole seen field is drawn).
  const double r_max = r.rim.radius_px;
  const bool monotonic_to_rim = r.radial.monotonic_up_to(r_max);  // once, not per line point
  auto radius_of = [&](double d) {
    double lo = 0.0, hi = r_max;
    if (!monotonic_to_rim || !(r.radial.ground_cm(hi) >= d)) hi = r.view_radius_px;
    if (r.radial.ground_cm(hi) < d) return -1.0;
    for (int i = 0; i < 40; ++i)
      ((r.radial.ground_cm(0.5 * (lo + hi)) < d) ? lo : hi) = 0.5 * (lo + hi);
    return 0.5 * (lo + hi);
  };
  const Eigen::Vector2d pos = frame.position_cm;
  auto draw = [&](const Eigen::Vector2d& q) {
    const Eigen::Vector2d rel = field_to_robot(q - pos, fit.yaw_deg);
    const double rr = radius_of(rel.norm());
    if (rr < cam.body_radius_px) return;
    const double phi = deg_to_rad(rad_to_deg(std::atan2(rel.y(), rel.x())) + cam.yaw_offset_deg);
    const double du = rr * std::cos(phi);
    const int u = static_cast<int>(std::lround(cam.center_px.x() + (cam.mirrored ? -du : du)));
    const int v = static_cast<int>(std::lround(cam.center_px.y() - rr * std::sin(phi)));
    if (u >= 0 && v >= 0 && u < out.cols && v < out.rows) out.at<cv::Vec3b>(v, u) = {0, 255, 255};
  };
  for_each_line_point(field, 0.5, draw);
  for (const auto& d : field.discs) draw(d.centre_cm);
  const cv::Point c(static_cast<int>(std::lround(cam.center_px.x())),
                    static_cast<int>(std::lround(cam.center_px.y())));
  cv::circle(out, c, static_cast<int>(std::lround(r.rim.radius_px)), {255, 128, 0}, 1, cv::LINE_AA);
  cv::circle(out, c, static_cast<int>(std::lround(cam.body_radius_px)), {0, 0, 255}, 1,
             cv::LINE_AA);
  cv::circle(out, c, static_cast<int>(std::lround(r.view_radius_px)), {0, 255, 0}, 1, cv::LINE_AA);
  for (const auto& m : cam.masts) {
    for (double sgn : {-1.0, 1.0}) {
      const double phi = deg_to_rad(m.bearing_deg + sgn * m.half_width_deg + cam.yaw_offset_deg);
      const double ux = std::cos(phi) * (cam.mirrored ? -1.0 : 1.0), vy = -std::sin(phi);
      cv::line(out,
               c + cv::Point(static_cast<int>(cam.body_radius_px * ux),
                             static_cast<int>(cam.body_radius_px * vy)),
               c + cv::Point(static_cast<int>(r.view_radius_px * ux),
                             static_cast<int>(r.view_radius_px * vy)),
               {0, 0, 255}, 1);
    }
  }
  return out;
}

}  // namespace omniloc
