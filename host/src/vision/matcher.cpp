#include "omniloc/matcher.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <utility>

#include <Eigen/LU>

#include "omniloc/conventions.hpp"
#include "omniloc/detail/vision_reference.hpp"

namespace omniloc {

namespace {

// The pattern searches of the refinements (refine_match_reference, refine_match_previous): each
// move lowers the error strictly and stays within the reach, so a walk ends; this cap only guards
// against options that would make it absurdly long (a min step of 1e-300).
constexpr int kMaxRefineSteps = 10'000;

struct Window {
  int i0, i1, j0, j1;  // inclusive
};

// Fills the errors of a window of cells, picks the best, the second distinct minimum and the
// ambiguity flag. `error_of(cell)` returns the normalised error (kNoError: nothing compared).
template <class ErrorOf>
MatchResult search_window(const FeatureDb& db, const Window& w, int rays_used,
                          const MatchOptions& opt, ErrorOf error_of) {
  MatchResult r;
  r.rays_used = rays_used;
  if (rays_used == 0) return r;  // nothing seen: error stays kNoError
  const int wi = w.i1 - w.i0 + 1, wj = w.j1 - w.j0 + 1;
  std::vector<double> err(static_cast<std::size_t>(wi * wj));
  double best = kNoError;
  int best_at = -1;
  for (int j = 0; j < wj; ++j) {
    const int row = (w.j0 + j) * db.grid.nx;
    for (int i = 0; i < wi; ++i) {
      const double e = error_of(row + w.i0 + i);
      err[static_cast<std::size_t>(j * wi + i)] = e;
      if (e < best) {
        best = e;
        best_at = j * wi + i;
      }
    }
  }
  r.cells_searched = wi * wj;
  if (best_at < 0) return r;  // no cell had anything to compare
  const int bi = best_at % wi, bj = best_at / wi;
  r.cell = (w.j0 + bj) * db.grid.nx + w.i0 + bi;
  r.grid_position_cm = db.grid.position(r.cell);
  r.position_cm = r.grid_position_cm;
  r.error = best;
  r.refined_error = r.error;
  // Second-best distinct minimum: a local minimum of the error surface far enough from the best.
  const double sep2 = opt.ambiguity_separation_cm * opt.ambiguity_separation_cm;
  double second = kNoError;
  for (int j = 0; j < wj; ++j) {
    for (int i = 0; i < wi; ++i) {
      const double e = err[static_cast<std::size_t>(j * wi + i)];
      if (e >= second) continue;
      const double dx = (i - bi) * db.grid.step_cm, dy = (j - bj) * db.grid.step_cm;
      if (dx * dx + dy * dy < sep2) continue;
      bool local_min = true;
      for (int dj = -1; dj <= 1 && local_min; ++dj) {
        for (int di = -1; di <= 1; ++di) {
          const int ni = i + di, nj = j + dj;
          if ((di == 0 && dj == 0) || ni < 0 || nj < 0 || ni >= wi || nj >= wj) continue;
          if (err[static_cast<std::size_t>(nj * wi + ni)] < e) {
            local_min = false;
            break;
          }
        }
      }
      if (local_min) {
        second = e;
        r.second_position_cm = db.grid.position((w.j0 + j) * db.grid.nx + w.i0 + i);
      }
    }
  }
  if (second < kNoError) {
    r.second_error = second;
    r.ambiguous = r.second_error <= opt.ambiguity_ratio * r.error;
  }
  return r;
}

Window full_window(const FeatureDb& db) {
  return {0, db.grid.nx - 1, 0, db.grid.ny - 1};
}

/// The grid index nearest to `v_cm`, clamped to [0, n - 1] before the conversion to int (a centre
/// of 1e300 cm is finite, and converting it unclamped is undefined behaviour).
int nearest_index(double v_cm, double origin_cm, double step_cm, int n) {
  const double k =
      std::clamp(std::round((v_cm - origin_cm) / step_cm), 0.0, static_cast<double>(n - 1));
  return static_cast<int>(k);
}

// load_feature_db checks a file's grid against the field; this guards a database made in memory:
// every search below indexes cells and converts positions with the grid, so it must be sane.
void check_db(const FeatureDb& db) {
  const GridSpec& g = db.grid;
  constexpr int kMaxSide = 100000;  // as the file format's limit
  const bool grid_ok =
      g.nx >= 1 && g.ny >= 1 && g.nx <= kMaxSide && g.ny <= kMaxSide && std::isfinite(g.x0_cm) &&
      std::isfinite(g.y0_cm) && std::isfinite(g.step_cm) && g.step_cm > 0.0 &&
      static_cast<std::int64_t>(g.nx) * g.ny <= std::numeric_limits<int>::max() / 2;
  if (!grid_ok || db.features.size() != static_cast<std::size_t>(g.nx) *
                                            static_cast<std::size_t>(g.ny) * kFeatureBytes) {
    throw std::invalid_argument(
        "matcher: feature database is empty, has a non-finite or non-positive grid, or does "
        "not match its grid");
  }
}

}  // namespace

FieldScan make_field_scan(const BearingScan& bearings, double yaw_deg) {
  FieldScan f = make_field_scan(rotate_to_field(bearings, yaw_deg));
  f.yaw_deg = yaw_deg;
  // Field ray 0 is robot ray j0 (rotate_to_field's choice), at field bearing j0 / rpd + yaw.
  const int rpd = std::max(1, bearings.rays_per_degree);
  const long j0 = std::lround(-yaw_deg * rpd);
  f.bearing_offset_deg = wrap_deg(static_cast<double>(j0) / rpd + yaw_deg);
  return f;
}

FieldScan make_field_scan(const Scan& field_frame_scan) {
  FieldScan f;
  f.scan = field_frame_scan;
  f.prepared = prepare_scan(field_frame_scan);
  return f;
}

MatchResult global_search(const FeatureDb& db, const FieldScan& scan, const MatchOptions& opt) {
  check_db(db);
  const PreparedScan& p = scan.prepared;
  return search_window(db, full_window(db), p.rays_used, opt,
                       [&](int c) { return match_error(db.cell_features(c), p, opt); });
}

MatchResult global_search(const FeatureDb& db, const Scan& scan, const MatchOptions& opt) {
  return global_search(db, make_field_scan(scan), opt);
}

MatchResult global_search_reference(const FeatureDb& db, const Scan& scan,
                                    const MatchOptions& opt) {
  check_db(db);
  const int rays = scan.rays_valid();
  return search_window(db, full_window(db), rays, opt, [&](int c) {
    if (opt.cost == MatchCost::kPaperSad)
      return static_cast<double>(sad_reference(db.cell_features(c), scan)) / rays;
    const CostTerms t = bounded_cost_reference(db.cell_features(c), scan, opt.crossing_cap_px);
    return t.crossings == 0 ? kNoError : static_cast<double>(t.sum) / t.crossings;
  });
}

int local_search_reach_cells(double range_cm, double grid_step_cm) {
  return static_cast<int>(std::floor(range_cm / grid_step_cm + 1e-9));
}

MatchResult local_search(const FeatureDb& db, const FieldScan& scan, const Eigen::Vector2d& centre,
                         double range_cm, const MatchOptions& opt) {
  check_db(db);
  if (!(range_cm >= 0.0) || !centre.allFinite()) {
    throw std::invalid_argument("local_search: range must be >= 0 cm and the centre finite");
  }
  const GridSpec& g = db.grid;
  const int ci = nearest_index(centre.x(), g.x0_cm, g.step_cm, g.nx);
  const int cj = nearest_index(centre.y(), g.y0_cm, g.step_cm, g.ny);
  // A range beyond the grid is the whole grid (and keeps ci + reach within int).
  const int reach = range_cm >= g.step_cm * std::max(g.nx, g.ny)
                        ? std::max(g.nx, g.ny)
                        : local_search_reach_cells(range_cm, g.step_cm);
  const Window w{std::max(0, ci - reach), std::min(g.nx - 1, ci + reach), std::max(0, cj - reach),
                 std::min(g.ny - 1, cj + reach)};
  const PreparedScan& p = scan.prepared;
  return search_window(db, w, p.rays_used, opt,
                       [&](int c) { return match_error(db.cell_features(c), p, opt); });
}

MatchResult local_search(const FeatureDb& db, const Scan& scan, const Eigen::Vector2d& centre,
                         double range_cm, const MatchOptions& opt) {
  return local_search(db, make_field_scan(scan), centre, range_cm, opt);
}

double error_at(const FieldGeometry& field, const CameraModel& camera, const PreparedScan& p,
                const Eigen::Vector2d& pos, const MatchOptions& opt, double bearing_offset_deg) {
  if (p.rays_used == 0) return kNoError;
  alignas(32) std::array<std::uint8_t, kFeatureBytes> expected{};
  std::vector<WhiteInterval> scratch;
  expected_features(field, camera, pos, expected.data(), scratch, ScanParams{}.min_gap_px,
                    bearing_offset_deg);
  return match_error(expected.data(), p, opt);
}

namespace {

/// Equiangular fit (the shape of a sum of absolute differences): E(x) = a |x - x0| + b through
/// (-1, em), (0, e0), (1, ep) with e0 the smallest; returns x0 in [-0.5, 0.5].
double equiangular_offset(double em, double e0, double ep) {
  double x0 = 0.0;
  if (em >= ep && em > e0) x0 = 0.5 * (em - ep) / (em - e0);
  if (ep > em && ep > e0) x0 = -0.5 * (ep - em) / (ep - e0);
  return std::clamp(x0, -0.5, 0.5);
}

}  // namespace

void interpolate_match(const FeatureDb& db, const FieldScan& scan, MatchResult& r,
                       const MatchOptions& opt) {
  if (r.cell < 0 || r.rays_used == 0) return;
  const PreparedScan& p = scan.prepared;
  const GridSpec& g = db.grid;
  const int i = r.cell % g.nx, j = r.cell / g.nx;
  const double e0 = match_error(db.cell_features(r.cell), p, opt);
  auto err = [&](int ii, int jj) -> double {
    if (ii < 0 || jj < 0 || ii >= g.nx || jj >= g.ny) return kNoError;
    return match_error(db.cell_features(jj * g.nx + ii), p, opt);
  };
  auto offset = [&](double em, double ep) {
    // At the grid's edge (or next to a cell with nothing to compare): stay on the grid point.
    if (!std::isfinite(em) || !std::isfinite(ep) || !std::isfinite(e0)) return 0.0;
    return equiangular_offset(em, e0, ep);
  };
  r.position_cm =
      r.grid_position_cm + g.step_cm * Eigen::Vector2d(offset(err(i - 1, j), err(i + 1, j)),
                                                       offset(err(i, j - 1), err(i, j + 1)));
}

void interpolate_match(const FeatureDb& db, const Scan& scan, MatchResult& r,
                       const MatchOptions& opt) {
  interpolate_match(db, make_field_scan(scan), r, opt);
}

void refine_match_reference(const FieldGeometry& field, const CameraModel& camera,
                            const FieldScan& scan, MatchResult& r, const MatchOptions& opt) {
  if (r.cell < 0 || r.rays_used == 0) return;
  // A non-finite start would never compare equal to itself and never stop (a corrupt grid origin
  // did that once); load_feature_db refuses such grids, and this keeps the loop finite regardless.
  if (!r.position_cm.allFinite() || !r.grid_position_cm.allFinite()) return;
  const PreparedScan& p = scan.prepared;
  Eigen::Vector2d pos = r.position_cm;
  int probes = pos == r.grid_position_cm ? 0 : 1;
  double best = pos == r.grid_position_cm
                    ? r.error
                    : error_at(field, camera, p, pos, opt, scan.bearing_offset_deg);
  const Eigen::Vector2d steps[] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  const double limit = opt.refine_reach_cm;
  int steps_taken = 0;
  for (double step = opt.refine_start_step_cm;
       step >= opt.refine_min_step_cm - 1e-9 && steps_taken < kMaxRefineSteps; ++steps_taken) {
    Eigen::Vector2d best_pos = pos;
    for (const auto& d : steps) {
      const Eigen::Vector2d q = pos + step * d;
      if ((q - r.grid_position_cm).cwiseAbs().maxCoeff() > limit) continue;
      const double e = error_at(field, camera, p, q, opt, scan.bearing_offset_deg);
      ++probes;
      if (e < best) {
        best = e;
        best_pos = q;
      }
    }
    if (best_pos == pos) {
      step /= 2.0;
    } else {
      pos = best_pos;
    }
  }
  r.position_cm = pos;
  r.refined_error = best;
  r.refine_probes = probes;
  r.refine_casts = probes;
}

namespace {

// Ray casting is most of the refinement's cost (~0.1 ms a point). Within a few cm of a point,
// every white run a ray crosses keeps its place on the ray to first order: where a ray from a
// shifted origin enters a straight line moves exactly linearly with the shift, an arc's nearly
// so, and the radius table is smooth. So the caster casts three points (the centre, and 1 cm
// along x and along y), keeps each run's radii in px and their gradients, and gives the expected
// scan at any point near the centre from that model. A ray whose runs differ between the three
// casts (a line's end or an arc's tangent lies in between) is cast exactly at every point. At the
// centre the model is the ray cast itself, bit for bit.
class LinearisedCaster {
 public:
  LinearisedCaster(const FieldGeometry& field, const CameraModel& camera,
                   const Eigen::Vector2d& centre_cm, double bearing_offset_deg)
      : caster_(field), camera_(camera), centre_(centre_cm) {
    k0_ = camera.first_scan_sample();
    k1_ = camera.last_scan_sample();
    step_px_ = camera.scan_step_px();
    t_lo_ = camera.ground_cm_at_radius(k0_ * step_px_);
    t_hi_ = camera.ground_cm_at_radius(k1_ * step_px_);
    std::vector<Run> at_x, at_y;
    for (int k = 0; k < kScanRays; ++k) {
      dirs_[static_cast<std::size_t>(k)] = {std::cos(deg_to_rad(k + bearing_offset_deg)),
                                            std::sin(deg_to_rad(k + bearing_offset_deg))};
      first_[static_cast<std::size_t>(k)] = static_cast<int>(runs_.size());
      cast(centre_, k, runs_);
      at_x.clear();
      at_y.clear();
      cast(centre_ + Eigen::Vector2d(kStepCm, 0.0), k, at_x);
      cast(centre_ + Eigen::Vector2d(0.0, kStepCm), k, at_y);
      const std::size_t n =
          runs_.size() - static_cast<std::size_t>(first_[static_cast<std::size_t>(k)]);
      exact_[static_cast<std::size_t>(k)] = at_x.size() != n || at_y.size() != n;
      if (exact_[static_cast<std::size_t>(k)]) continue;
      for (std::size_t i = 0; i < n; ++i) {
        Run& r = runs_[static_cast<std::size_t>(first_[static_cast<std::size_t>(k)]) + i];
        r.enter_g = {(at_x[i].enter_px - r.enter_px) / kStepCm,
                     (at_y[i].enter_px - r.enter_px) / kStepCm};
        r.exit_g = {(at_x[i].exit_px - r.exit_px) / kStepCm,
                    (at_y[i].exit_px - r.exit_px) / kStepCm};
      }
    }
    first_[kScanRays] = static_cast<int>(runs_.size());
  }

  [[nodiscard]] const Eigen::Vector2d& centre() const { return centre_; }

  /// One crossing's term of the covariance: its 10-degree sector, its residual (seen - model, px)
  /// and the model entry's gradient.
  struct Term {
    int sector;
    double r;
    Eigen::Vector2d g;
  };

  /// The model's entry on ray k nearest the crossing seen at `seen` px, from a point d from the
  /// centre: seen - entry (kNoError: no entry the scan could see), its gradient in g.
  [[nodiscard]] double nearest_entry(int k, int seen, const Eigen::Vector2d& d,
                                     Eigen::Vector2d& g) const {
    double nearest = kNoError;
    for (int i = first_[static_cast<std::size_t>(k)]; i < first_[static_cast<std::size_t>(k) + 1];
         ++i) {
      const Run& r = runs_[static_cast<std::size_t>(i)];
      const double at = r.enter_px + r.enter_g.dot(d);
      if (at < k0_ || at > k1_) continue;  // no entry the scan could see
      if (std::abs(seen - at) < std::abs(nearest)) {
        nearest = seen - at;
        g = r.enter_g;
      }
    }
    return nearest;
  }

  /// The sandwich H^-1 B H^-1 over the terms: each sector's score summed from residuals about
  /// their median, clipped at 3 robust spreads. nullopt with fewer than three sectors scoring.
  [[nodiscard]] static std::optional<Eigen::Matrix2d> robust_sandwich(
      const std::vector<Term>& terms, const Eigen::Matrix2d& h) {
    const auto median = [](std::vector<double> v) {
      const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
      std::nth_element(v.begin(), mid, v.end());
      return *mid;
    };
    std::vector<double> r;
    for (const Term& t : terms) r.push_back(t.r);
    const double centre = median(r);
    for (double& x : r) x = std::abs(x - centre);
    // Whole pixels against a continuous model: never less spread than rounding's 1/sqrt(12) px.
    const double clip = 3.0 * std::max(1.4826 * median(r), 1.0 / std::sqrt(12.0));
    std::array<Eigen::Vector2d, kScanRays / kSectorRays> score;
    score.fill(Eigen::Vector2d::Zero());
    for (const Term& t : terms)
      score[static_cast<std::size_t>(t.sector)] += t.g * std::clamp(t.r - centre, -clip, clip);
    Eigen::Matrix2d b = Eigen::Matrix2d::Zero();
    int sectors = 0;
    for (const Eigen::Vector2d& s : score) {
      b += s * s.transpose();
      sectors += s.isZero() ? 0 : 1;
    }
    if (sectors < 3) return std::nullopt;
    const Eigen::Matrix2d hi = h.inverse();
    return static_cast<double>(sectors) / (sectors - 1) * hi * b * hi;
  }

  /// The position's covariance at q from the error surface's curvature (Gauss-Newton) and the
  /// residuals themselves: every scan crossing within cap_px of a modelled run entry gives a
  /// residual r = d - entry(q) and the entry's gradient g (px per cm). H = sum g g^T is the
  /// surface's curvature. Neighbouring rays cross the same line and share its error (blur, width,
  /// the camera model), so the residuals are not independent: the covariance is the cluster-robust
  /// (sandwich) form H^-1 (sum over sectors s_c s_c^T) H^-1, s_c = sum of g r over a sector of
  /// kSectorRays rays, with r taken about the residuals' median (the integer rounding's constant
  /// offset) and clipped at 3 robust spreads (a spurious crossing within the cap is not noise).
  /// Rays the model does not hold (cast exactly) are left out. nullopt with fewer than
  /// kMinCrossings crossings or a singular H.
  [[nodiscard]] std::optional<Eigen::Matrix2d> covariance(const Eigen::Vector2d& q,
                                                          const PreparedScan& scan,
                                                          int cap_px) const {
    const Eigen::Vector2d d = q - centre_;
    std::vector<Term> terms;
    Eigen::Matrix2d h = Eigen::Matrix2d::Zero();
    for (int k = 0; k < kScanRays; ++k) {
      if (exact_[static_cast<std::size_t>(k)]) continue;
      for (int n = 0; n < kCrossingsPerRay; ++n) {
        const auto slot = static_cast<std::size_t>(k * kCrossingsPerRay + n);
        const int seen = scan.radii[slot];
        if (seen == kNoCrossing || seen >= scan.end[slot]) continue;
        Eigen::Vector2d g{0.0, 0.0};
        const double nearest = nearest_entry(k, seen, d, g);
        if (!(std::abs(nearest) <= cap_px)) continue;
        terms.push_back({k / kSectorRays, nearest, g});
        h += g * g.transpose();
      }
    }
    if (static_cast<int>(terms.size()) < kMinCrossings || std::abs(h.determinant()) < 1e-12)
      return std::nullopt;
    return robust_sandwich(terms, h);
  }

  /// The expected scan at q (kFeatureBytes radii).
  void features(const Eigen::Vector2d& q, std::uint8_t* out) {
    const Eigen::Vector2d d = q - centre_;
    const int min_gap = ScanParams{}.min_gap_px;  // as the database (expected_features' default)
    for (int k = 0; k < kScanRays; ++k) {
      std::uint8_t* o = out + k * kCrossingsPerRay;
      if (exact_[static_cast<std::size_t>(k)]) {
        scratch_runs_.clear();
        cast(q, k, scratch_runs_);
        px_.clear();
        for (const Run& r : scratch_runs_) px_.push_back({r.enter_px, r.exit_px});
      } else {
        px_.clear();
        for (int i = first_[static_cast<std::size_t>(k)];
             i < first_[static_cast<std::size_t>(k) + 1]; ++i) {
          const Run& r = runs_[static_cast<std::size_t>(i)];
          px_.push_back({r.enter_px + r.enter_g.dot(d), r.exit_px + r.exit_g.dot(d)});
        }
      }
      crossings_of_runs(
          k0_, k1_, min_gap, px_, [](const auto& r) { return r; }, o);
    }
  }

 private:
  static constexpr double kStepCm = 1.0;
  static constexpr int kMinCrossings = 8;
  static constexpr int kSectorRays = 10;  // the sandwich's clusters: 10 degrees of rays
  struct Run {
    double enter_px = 0.0, exit_px = 0.0;  // in samples (line_scan.hpp): px up to a 254 px view
    Eigen::Vector2d enter_g{0.0, 0.0}, exit_g{0.0, 0.0};  // samples per cm of the origin's shift
  };
  void cast(const Eigen::Vector2d& origin, int k, std::vector<Run>& out) {
    caster_.intervals(origin, dirs_[static_cast<std::size_t>(k)], t_lo_, t_hi_, iv_);
    for (const auto& w : iv_) {
      Run r;
      r.enter_px =
          camera_.radius_px_at_ground(w.enter_cm) / step_px_;  // in samples (line_scan.hpp)
      r.exit_px = camera_.radius_px_at_ground(w.exit_cm) / step_px_;
      out.push_back(r);
    }
  }

  RayCaster caster_;
  const CameraModel& camera_;
  Eigen::Vector2d centre_;
  int k0_ = 0, k1_ = 0;
  double step_px_ = 1.0;
  double t_lo_ = 0.0, t_hi_ = 0.0;
  std::array<Eigen::Vector2d, kScanRays> dirs_;
  std::vector<Run> runs_;
  std::array<int, kScanRays + 1> first_{};
  std::array<bool, kScanRays> exact_{};
  std::vector<WhiteInterval> iv_;
  std::vector<Run> scratch_runs_;
  std::vector<std::pair<double, double>> px_;
};

// The refinement's errors: from the linearised caster, re-centred when the walk leaves
// kRecentreCm of its centre, and remembered, since the walk comes back to points it has seen.
class ProbeErrors {
 public:
  ProbeErrors(const FieldGeometry& field, const CameraModel& camera, const FieldScan& scan,
              const MatchOptions& opt)
      : field_(field),
        camera_(camera),
        scan_(scan.prepared),
        offset_deg_(scan.bearing_offset_deg),
        opt_(opt) {}
  double operator()(const Eigen::Vector2d& q) {
    for (const auto& [at, e] : seen_) {
      if ((at - q).cwiseAbs().maxCoeff() < 1e-6) return e;
    }
    if (!caster_ || (q - caster_->centre()).cwiseAbs().maxCoeff() > kRecentreCm) {
      caster_.emplace(field_, camera_, q, offset_deg_);
      ++casts_;
    }
    alignas(32) std::array<std::uint8_t, kFeatureBytes> expected{};
    caster_->features(q, expected.data());
    const double e = match_error(expected.data(), scan_, opt_);
    seen_.push_back({q, e});
    return e;
  }
  [[nodiscard]] int probes() const { return static_cast<int>(seen_.size()); }
  /// The linearised caster nearest the walk's end (re-centred there when it is farther than the
  /// model holds), for the covariance at the end point.
  [[nodiscard]] const LinearisedCaster& caster_at(const Eigen::Vector2d& q) {
    if (!caster_ || (q - caster_->centre()).cwiseAbs().maxCoeff() > kRecentreCm) {
      caster_.emplace(field_, camera_, q, offset_deg_);
      ++casts_;
    }
    return *caster_;
  }
  [[nodiscard]] int linearisations() const { return casts_; }

 private:
  static constexpr double kRecentreCm = 3.0;
  const FieldGeometry& field_;
  const CameraModel& camera_;
  const PreparedScan& scan_;
  double offset_deg_ = 0.0;
  const MatchOptions& opt_;
  std::optional<LinearisedCaster> caster_;
  std::vector<std::pair<Eigen::Vector2d, double>> seen_;
  int casts_ = 0;
};

}  // namespace

namespace {
// The crossings' share (from the error surface) plus the walk's own resolution: it ends on a
// point within half its last step of the surface's minimum along each axis, uniformly as far as it
// knows (the V fit below the step does better, so this is the conservative side).
void set_covariance(MatchResult& r, const std::optional<Eigen::Matrix2d>& cov, double min_step_cm) {
  if (!cov || !cov->allFinite()) return;
  r.covariance_cm2 = *cov + (min_step_cm * min_step_cm / 12.0) * Eigen::Matrix2d::Identity();
  r.sigma_cm = std::sqrt(std::max(r.covariance_cm2.trace(), 0.0));
}
}  // namespace

namespace {
// One step of the pattern search at `step`: to the best of the four neighbours when one is lower
// (false: the step stays); else, the centre being the best of its neighbours, to the point the V
// fitted through them along each axis proposes below the step, if lower (true: the step halves).
template <class Within>
bool pattern_step(ProbeErrors& error_of, const Within& within, double step, Eigen::Vector2d& pos,
                  double& best) {
  double e[4];  // +x, -x, +y, -y
  const Eigen::Vector2d dirs[] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  int best_dir = -1;
  double best_e = best;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector2d q = pos + step * dirs[k];
    e[k] = within(q) ? error_of(q) : kNoError;
    if (e[k] < best_e) {
      best_e = e[k];
      best_dir = k;
    }
  }
  if (best_dir >= 0) {
    pos += step * dirs[best_dir];
    best = best_e;
    return false;
  }
  const auto offset = [&](double em, double ep) {
    return std::isfinite(em) && std::isfinite(ep) ? equiangular_offset(em, best, ep) : 0.0;
  };
  const Eigen::Vector2d q = pos + step * Eigen::Vector2d(offset(e[1], e[0]), offset(e[3], e[2]));
  if (q != pos && within(q)) {
    const double eq = error_of(q);
    if (eq < best) {
      best = eq;
      pos = q;
    }
  }
  return true;
}
}  // namespace

void refine_match_previous(const FieldGeometry& field, const CameraModel& camera,
                           const FieldScan& scan, MatchResult& r, const MatchOptions& opt) {
  if (r.cell < 0 || r.rays_used == 0) return;
  // A non-finite start would never compare equal to itself and never stop (a corrupt grid origin
  // did that once); load_feature_db refuses such grids, and this keeps the loop finite regardless.
  if (!r.position_cm.allFinite() || !r.grid_position_cm.allFinite()) return;
  ProbeErrors error_of(field, camera, scan, opt);
  Eigen::Vector2d pos = r.position_cm;
  const Eigen::Vector2d start = pos;
  double best = error_of(pos);  // the linearised caster is centred here: this one is exact
  const double start_error = best;
  const double limit = opt.refine_reach_cm;
  const auto within = [&](const Eigen::Vector2d& q) {
    return (q - r.grid_position_cm).cwiseAbs().maxCoeff() <= limit;
  };
  // A pattern search as refine_match_reference, except that once the centre is the best of its
  // four neighbours, the V fitted through them along each axis (the shape of the bounded cost
  // near its minimum, as interpolate_match) proposes a point below the step before it halves.
  int steps_taken = 0;
  for (double step = opt.refine_start_step_cm;
       step >= opt.refine_min_step_cm - 1e-9 && steps_taken < kMaxRefineSteps; ++steps_taken) {
    if (pattern_step(error_of, within, step, pos, best)) step /= 2.0;
  }
  // The walk ran on the model: the error at its end is cast exactly, and the start kept if that
  // is no better.
  const double exact =
      pos == start ? start_error
                   : error_at(field, camera, scan.prepared, pos, opt, scan.bearing_offset_deg);
  r.refine_probes = error_of.probes();
  r.refine_casts = 3 * error_of.linearisations() + (pos == start ? 0 : 1);
  if (exact < start_error) {
    r.position_cm = pos;
    r.refined_error = exact;
  } else {
    r.position_cm = start;
    r.refined_error = start_error;
  }
  set_covariance(r,
                 error_of.caster_at(r.position_cm)
                     .covariance(r.position_cm, scan.prepared, opt.crossing_cap_px),
                 opt.refine_min_step_cm);
}

void refine_match(const FieldGeometry& field, const CameraModel& camera, const FieldScan& scan,
                  MatchResult& r, const MatchOptions& opt) {
  refine_match_previous(field, camera, scan, r, opt);
}

void refine_match(const FieldGeometry& field, const CameraModel& camera, const Scan& scan,
                  MatchResult& r, const MatchOptions& opt) {
  refine_match(field, camera, make_field_scan(scan), r, opt);
}

void apply_refinement(const FeatureDb& db, const FieldGeometry& field, const CameraModel& camera,
                      const FieldScan& scan, MatchResult& r, const MatchOptions& opt) {
  if (opt.refinement != Refinement::kNone) interpolate_match(db, scan, r, opt);
  if (opt.refinement == Refinement::kRayCast) refine_match(field, camera, scan, r, opt);
}

YawEstimate estimate_yaw(const FieldGeometry& field, const CameraModel& camera,
                         const BearingScan& bearings, const Eigen::Vector2d& position_cm,
                         double yaw_hint_deg, double range_deg, const MatchOptions& opt) {
  if (!(range_deg >= 0.0) || range_deg > 180.0)
    throw std::invalid_argument("estimate_yaw: range must be 0..180 deg");
  alignas(32) std::array<std::uint8_t, kFeatureBytes> expected{};
  std::vector<WhiteInterval> scratch;
  expected_features(field, camera, position_cm, expected.data(), scratch);
  YawEstimate best;
  const int steps = static_cast<int>(std::floor(range_deg * bearings.rays_per_degree + 1e-9));
  std::vector<double> errors(static_cast<std::size_t>(2 * steps + 1), kNoError);
  int best_s = 0;
  for (int s = -steps; s <= steps; ++s) {
    const double yaw = yaw_hint_deg + static_cast<double>(s) / bearings.rays_per_degree;
    const double e =
        match_error(expected.data(), prepare_scan(rotate_to_field(bearings, yaw)), opt);
    if (!(e < kNoError)) continue;
    errors[static_cast<std::size_t>(s + steps)] = e;
    if (e < best.error) {
      best = {yaw, e};
      best_s = s;
    }
  }
  // Below the step: the equiangular fit through the best step and its two neighbours (not at
  // either end of the searched range, where the minimum may lie outside).
  if (best.error < kNoError && best_s > -steps && best_s < steps) {
    const double em = errors[static_cast<std::size_t>(best_s - 1 + steps)];
    const double ep = errors[static_cast<std::size_t>(best_s + 1 + steps)];
    if (em < kNoError && ep < kNoError)
      best.yaw_deg += equiangular_offset(em, best.error, ep) / bearings.rays_per_degree;
  }
  return best;
}

PoseMatch global_search_any_yaw(const FeatureDb& db, const FieldGeometry& field,
                                const CameraModel& camera, const BearingScan& bearings,
                                double yaw_step_deg, const MatchOptions& opt) {
  if (!(yaw_step_deg >= 0.25) || yaw_step_deg > 45.0) {
    throw std::invalid_argument("global_search_any_yaw: yaw step must be 0.25..45 deg");
  }
  struct Candidate {
    MatchResult m;
    double yaw;
  };
  std::vector<Candidate> per_yaw;
  for (double yaw = 0.0; yaw < 360.0 - 1e-9; yaw += yaw_step_deg) {
    per_yaw.push_back({global_search(db, make_field_scan(bearings, yaw), opt), yaw});
  }
  auto better = [](const Candidate& a, const Candidate& b) { return a.m.error < b.m.error; };
  const Candidate best = *std::min_element(per_yaw.begin(), per_yaw.end(), better);
  PoseMatch out;
  if (best.m.cell < 0) {
    out.match = best.m;
    return out;
  }
  // Finer yaw at the best grid point, then the position again at that yaw.
  const YawEstimate y =
      estimate_yaw(field, camera, bearings, best.m.grid_position_cm, best.yaw, yaw_step_deg, opt);
  const FieldScan scan = make_field_scan(bearings, y.yaw_deg);
  out.match = local_search(db, scan, best.m.grid_position_cm, db.grid.step_cm, opt);
  out.yaw_deg = wrap_deg(y.yaw_deg);
  apply_refinement(db, field, camera, scan, out.match, opt);
  // Second candidate: the best per-yaw result far enough from the chosen position.
  out.match.second_error = kNoError;
  out.match.ambiguous = false;
  for (const auto& c : per_yaw) {
    if (c.m.cell < 0 ||
        (c.m.grid_position_cm - out.match.grid_position_cm).norm() < opt.ambiguity_separation_cm)
      continue;
    if (c.m.error < out.match.second_error) {
      out.match.second_error = c.m.error;
      out.match.second_position_cm = c.m.grid_position_cm;
      out.second_yaw_deg = wrap_deg(c.yaw);
    }
  }
  out.match.ambiguous = out.match.second_error <= opt.ambiguity_ratio * best.m.error;
  out.match.cells_searched = db.grid.cells() * static_cast<int>(per_yaw.size());
  return out;
}

MatchResult image_to_position(const cv::Mat& bgr, const CameraModel& camera,
                              const FieldGeometry& field, const FeatureDb& db, double yaw_deg,
                              const Eigen::Vector2d* around_cm, double range_cm,
                              const MatchOptions& opt, const ScanParams& scan_params) {
  FieldScan scan = make_field_scan(scan_image(bgr, camera, yaw_deg, scan_params));
  scan.yaw_deg = yaw_deg;
  MatchResult r = around_cm != nullptr ? local_search(db, scan, *around_cm, range_cm, opt)
                                       : global_search(db, scan, opt);
  apply_refinement(db, field, camera, scan, r, opt);
  return r;
}

}  // namespace omniloc
