// Mamdani min-max inference with centroid defuzzification (paper section 2.5).
#include "omniloc/fuzzy.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <opencv2/core/persistence.hpp>

#include "omniloc/robot_config.hpp"

namespace omniloc {

double Trapezoid::degree(double x) const {
  if (x < a || x > d) return 0.0;
  if (x >= b && x <= c) return 1.0;
  // Strictly inside a sloped edge here, so the divisor is non-zero.
  if (x < b) return (x - a) / (b - a);
  return (d - x) / (d - c);
}

const char* fuzzy_term_name(FuzzyTerm term) {
  switch (term) {
    case FuzzyTerm::kVeryLow: return "VL";
    case FuzzyTerm::kLow: return "L";
    case FuzzyTerm::kHigh: return "H";
    case FuzzyTerm::kVeryHigh: return "VH";
  }
  return "?";
}

FuzzyConfig FuzzyConfig::defaults() {
  FuzzyConfig c;
  // Speed (cm/s): the robot's top speed is ~300 cm/s; most play happens below 150 cm/s.
  c.speed_terms = {Trapezoid{0, 0, 20, 50}, Trapezoid{20, 50, 80, 120}, Trapezoid{80, 120, 150, 200},
                   Trapezoid{150, 200, 300, 300}};
  // Search range (cm): each term's core sits on (or against) one database range 0/10/20/30.
  c.range_terms = {Trapezoid{0, 0, 3, 8}, Trapezoid{3, 8, 12, 17}, Trapezoid{12, 17, 22, 27},
                   Trapezoid{22, 27, 30, 30}};
  return c;
}

double snap_to_ranges(double value_cm, const std::vector<double>& ranges_cm) {
  if (ranges_cm.empty()) throw std::invalid_argument("snap_to_ranges: no ranges");
  double best = ranges_cm.front();
  for (double r : ranges_cm) {
    const double d = std::abs(r - value_cm), db = std::abs(best - value_cm);
    // Ties within 1e-9 cm go up: the centroid of a symmetric set is only exact to rounding.
    if (d < db - 1e-9 || (std::abs(d - db) <= 1e-9 && r > best)) best = r;
  }
  return best;
}

FuzzyResult fuzzy_search_range(const FuzzyConfig& config, double speed_cm_per_s) {
  if (std::isnan(speed_cm_per_s)) throw std::invalid_argument("fuzzy_search_range: speed is NaN");
  const double v = std::clamp(speed_cm_per_s, 0.0, config.speed_max_cm_per_s);
  FuzzyResult r;
  for (int i = 0; i < kFuzzyTerms; ++i) r.speed_degrees[i] = config.speed_terms[i].degree(v);
  // Rule i: IF speed is term i THEN range is rules[i]; several rules may share an output term (max).
  for (int i = 0; i < kFuzzyTerms; ++i) {
    const int out = static_cast<int>(config.rules[i]);
    r.output_clip[out] = std::max(r.output_clip[out], r.speed_degrees[i]);
  }
  const int n = std::max(1, static_cast<int>(std::ceil(config.range_max_cm / config.resolution_cm)));
  const double h = config.range_max_cm / n;
  double area = 0.0, moment = 0.0;
  for (int k = 0; k < n; ++k) {
    const double x = (k + 0.5) * h;  // midpoint rule
    double mu = 0.0;
    for (int t = 0; t < kFuzzyTerms; ++t) mu = std::max(mu, std::min(r.output_clip[t], config.range_terms[t].degree(x)));
    area += mu;
    moment += mu * x;
  }
  if (area <= 0.0) {
    r.crisp_cm = config.range_max_cm;
    r.snapped_cm = *std::max_element(config.snap_ranges_cm.begin(), config.snap_ranges_cm.end());
    return r;
  }
  r.crisp_cm = moment / area;
  r.snapped_cm = snap_to_ranges(r.crisp_cm, config.snap_ranges_cm);
  return r;
}

namespace {

[[noreturn]] void fail(const std::string& source, const std::string& field, const std::string& why) {
  throw ConfigError(source + ": field '" + field + "': " + why);
}

void check_terms(const std::array<Trapezoid, kFuzzyTerms>& terms, double max, const std::string& source,
                 const std::string& prefix, bool must_cover) {
  for (int i = 0; i < kFuzzyTerms; ++i) {
    const Trapezoid& t = terms[i];
    const std::string f = prefix + "." + fuzzy_term_name(static_cast<FuzzyTerm>(i));
    if (!std::isfinite(t.a) || !std::isfinite(t.b) || !std::isfinite(t.c) || !std::isfinite(t.d))
      fail(source, f, "breakpoints must be finite");
    if (!(t.a <= t.b && t.b <= t.c && t.c <= t.d)) fail(source, f, "breakpoints must satisfy a <= b <= c <= d");
    if (t.a < 0.0 || t.d > max) {
      std::ostringstream os;
      os << "breakpoints must lie in [0, " << max << "] (got " << t.a << " .. " << t.d << ")";
      fail(source, f, os.str());
    }
  }
  if (!must_cover) return;
  // Every input must fire some rule: sample the universe finely (including each breakpoint).
  std::vector<double> xs;
  for (const auto& t : terms) xs.insert(xs.end(), {t.a, t.b, t.c, t.d});
  for (int k = 0; k <= 1000; ++k) xs.push_back(max * k / 1000.0);
  for (int i = 0; i + 1 < static_cast<int>(xs.size()); ++i) {
    const double x = xs[i];
    if (x < 0.0 || x > max) continue;
    double mu = 0.0;
    for (const auto& t : terms) mu = std::max(mu, t.degree(x));
    if (mu <= 0.0) {
      std::ostringstream os;
      os << "the terms leave the input " << x << " uncovered (no rule would fire)";
      fail(source, prefix, os.str());
    }
  }
}

}  // namespace

void validate_fuzzy_config(const FuzzyConfig& c, const std::string& source) {
  if (!(c.speed_max_cm_per_s > 0.0) || !std::isfinite(c.speed_max_cm_per_s))
    fail(source, "speed_max_cm_per_s", "must be a positive number");
  if (!(c.range_max_cm > 0.0) || !std::isfinite(c.range_max_cm)) fail(source, "range_max_cm", "must be a positive number");
  check_terms(c.speed_terms, c.speed_max_cm_per_s, source, "speed_terms", true);
  check_terms(c.range_terms, c.range_max_cm, source, "range_terms", false);
  for (int i = 0; i < kFuzzyTerms; ++i) {
    const int o = static_cast<int>(c.rules[i]);
    if (o < 0 || o >= kFuzzyTerms)
      fail(source, std::string("rules.") + fuzzy_term_name(static_cast<FuzzyTerm>(i)), "output term out of range");
  }
  for (int i = 0; i < kFuzzyTerms; ++i) {
    const Trapezoid& t = c.range_terms[i];
    if (!(t.d > t.a))
      fail(source, std::string("range_terms.") + fuzzy_term_name(static_cast<FuzzyTerm>(i)),
           "has zero width (its centroid would be undefined)");
  }
  if (!(c.resolution_cm > 0.0) || c.resolution_cm > c.range_max_cm / 10.0)
    fail(source, "resolution_cm", "must be > 0 and at most a tenth of range_max_cm");
  if (c.snap_ranges_cm.empty()) fail(source, "snap_ranges_cm", "must list at least one range");
  for (std::size_t i = 0; i < c.snap_ranges_cm.size(); ++i) {
    const double r = c.snap_ranges_cm[i];
    if (!std::isfinite(r) || r < 0.0) fail(source, "snap_ranges_cm", "ranges must be finite and >= 0");
    if (i > 0 && !(r > c.snap_ranges_cm[i - 1])) fail(source, "snap_ranges_cm", "must be strictly increasing");
  }
}

namespace {

double read_number(const cv::FileNode& n, const std::string& source, const std::string& field) {
  if (n.empty() || n.isNone()) fail(source, field, "missing");
  if (!n.isReal() && !n.isInt()) fail(source, field, "must be a number");
  return static_cast<double>(n);
}

Trapezoid read_trapezoid(const cv::FileNode& n, const std::string& source, const std::string& field) {
  if (n.empty() || n.isNone()) fail(source, field, "missing");
  if (!n.isSeq() || n.size() != 4) fail(source, field, "must be an array of four numbers [a, b, c, d]");
  std::array<double, 4> v{};
  for (int i = 0; i < 4; ++i) v[i] = read_number(n[i], source, field + "[" + std::to_string(i) + "]");
  return {v[0], v[1], v[2], v[3]};
}

std::array<Trapezoid, kFuzzyTerms> read_terms(const cv::FileNode& n, const std::string& source,
                                              const std::string& field) {
  if (n.empty() || n.isNone()) fail(source, field, "missing");
  if (!n.isMap()) fail(source, field, "must be an object {\"VL\": [...], \"L\": ..., \"H\": ..., \"VH\": ...}");
  std::array<Trapezoid, kFuzzyTerms> t{};
  for (int i = 0; i < kFuzzyTerms; ++i) {
    const std::string name = fuzzy_term_name(static_cast<FuzzyTerm>(i));
    t[i] = read_trapezoid(n[name], source, field + "." + name);
  }
  for (auto it = n.begin(); it != n.end(); ++it) {
    const std::string key = (*it).name();
    if (key != "VL" && key != "L" && key != "H" && key != "VH") fail(source, field + "." + key, "unknown term");
  }
  return t;
}

std::optional<FuzzyTerm> term_of(const std::string& s) {
  for (int i = 0; i < kFuzzyTerms; ++i)
    if (s == fuzzy_term_name(static_cast<FuzzyTerm>(i))) return static_cast<FuzzyTerm>(i);
  return std::nullopt;
}

}  // namespace

FuzzyConfig parse_fuzzy_config(const cv::FileNode& node, const std::string& source) {
  if (node.empty() || !node.isMap()) throw ConfigError(source + ": must be an object");
  FuzzyConfig c = FuzzyConfig::defaults();
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string key = (*it).name();
    if (key != "speed_max_cm_per_s" && key != "speed_terms" && key != "range_max_cm" && key != "range_terms" &&
        key != "rules" && key != "resolution_cm" && key != "snap_ranges_cm")
      fail(source, key, "unknown key");
  }
  c.speed_max_cm_per_s = read_number(node["speed_max_cm_per_s"], source, "speed_max_cm_per_s");
  c.speed_terms = read_terms(node["speed_terms"], source, "speed_terms");
  c.range_max_cm = read_number(node["range_max_cm"], source, "range_max_cm");
  c.range_terms = read_terms(node["range_terms"], source, "range_terms");
  const cv::FileNode rules = node["rules"];
  if (rules.empty() || !rules.isMap()) fail(source, "rules", "missing or not an object {\"VL\": \"VL\", ...}");
  for (auto it = rules.begin(); it != rules.end(); ++it) {
    const std::string key = (*it).name();
    if (!term_of(key)) fail(source, "rules." + key, "unknown input term");
  }
  for (int i = 0; i < kFuzzyTerms; ++i) {
    const std::string name = fuzzy_term_name(static_cast<FuzzyTerm>(i));
    const cv::FileNode r = rules[name];
    if (r.empty() || !r.isString()) fail(source, "rules." + name, "missing or not a term name (VL, L, H, VH)");
    const auto t = term_of(static_cast<std::string>(r));
    if (!t) fail(source, "rules." + name, "unknown output term '" + static_cast<std::string>(r) + "'");
    c.rules[i] = *t;
  }
  c.resolution_cm = read_number(node["resolution_cm"], source, "resolution_cm");
  const cv::FileNode snaps = node["snap_ranges_cm"];
  if (snaps.empty() || !snaps.isSeq()) fail(source, "snap_ranges_cm", "missing or not an array");
  c.snap_ranges_cm.clear();
  for (int i = 0; i < static_cast<int>(snaps.size()); ++i)
    c.snap_ranges_cm.push_back(read_number(snaps[i], source, "snap_ranges_cm[" + std::to_string(i) + "]"));
  validate_fuzzy_config(c, source);
  return c;
}

}  // namespace omniloc
