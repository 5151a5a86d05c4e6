// Mamdani min-max inference with centroid defuzzification (paper section 2.5).
#include "omniloc/fuzzy.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "omniloc/detail/config_reader.hpp"

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
    case FuzzyTerm::kVeryLow:
      return "VL";
    case FuzzyTerm::kLow:
      return "L";
    case FuzzyTerm::kHigh:
      return "H";
    case FuzzyTerm::kVeryHigh:
      return "VH";
  }
  return "?";
}

FuzzyConfig FuzzyConfig::defaults() {
  return FuzzyConfig{};
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
  // Rule i: IF speed is term i THEN range is rules[i]; several rules may share an output term
  // (max).
  for (int i = 0; i < kFuzzyTerms; ++i) {
    const int out = static_cast<int>(config.rules[i]);
    r.output_clip[out] = std::max(r.output_clip[out], r.speed_degrees[i]);
  }
  // validate() bounds the step count by kFuzzyMaxSteps; the clamp keeps an unvalidated config
  // from overflowing the int (undefined behaviour) or looping for minutes.
  const double steps = std::ceil(config.range_max_cm / config.resolution_cm);
  const int n = std::isfinite(steps)
                    ? static_cast<int>(std::clamp(steps, 1.0, double{kFuzzyMaxSteps}))
                    : kFuzzyMaxSteps;
  const double h = config.range_max_cm / n;
  double area = 0.0, moment = 0.0;
  for (int k = 0; k < n; ++k) {
    const double x = (k + 0.5) * h;  // midpoint rule
    double mu = 0.0;
    for (int t = 0; t < kFuzzyTerms; ++t)
      mu = std::max(mu, std::min(r.output_clip[t], config.range_terms[t].degree(x)));
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

using config::Origin;

std::string show_term(const Trapezoid& t) {
  return config::show({t.a, t.b, t.c, t.d});
}

void check_terms(const std::array<Trapezoid, kFuzzyTerms>& terms, double max, const Origin& at,
                 bool must_cover) {
  for (int i = 0; i < kFuzzyTerms; ++i) {
    const Trapezoid& t = terms[i];
    const Origin f = at / fuzzy_term_name(static_cast<FuzzyTerm>(i));
    const bool finite =
        std::isfinite(t.a) && std::isfinite(t.b) && std::isfinite(t.c) && std::isfinite(t.d);
    config::require(finite, f, "breakpoints must be finite", show_term(t));
    config::require(t.a <= t.b && t.b <= t.c && t.c <= t.d, f,
                    "breakpoints must satisfy a <= b <= c <= d", show_term(t));
    config::require(t.a >= 0.0 && t.d <= max, f,
                    "breakpoints must lie in [0, " + config::show(max) + "]", show_term(t));
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
    config::require(mu > 0.0, at,
                    "the terms leave an input uncovered (no rule would fire) at speed", x);
  }
}

}  // namespace

void FuzzyConfig::validate(const Origin& at) const {
  config::require(speed_max_cm_per_s > 0.0 && std::isfinite(speed_max_cm_per_s),
                  at / "speed_max_cm_per_s", "must be a positive number", speed_max_cm_per_s);
  config::require(range_max_cm > 0.0 && std::isfinite(range_max_cm), at / "range_max_cm",
                  "must be a positive number", range_max_cm);
  check_terms(speed_terms, speed_max_cm_per_s, at / "speed_terms", true);
  check_terms(range_terms, range_max_cm, at / "range_terms", false);
  for (int i = 0; i < kFuzzyTerms; ++i) {
    const int o = static_cast<int>(rules[i]);
    config::require(o >= 0 && o < kFuzzyTerms,
                    at / "rules" / fuzzy_term_name(static_cast<FuzzyTerm>(i)),
                    "output term out of range", o);
  }
  for (int i = 0; i < kFuzzyTerms; ++i) {
    const Trapezoid& t = range_terms[i];
    config::require(t.d > t.a, at / "range_terms" / fuzzy_term_name(static_cast<FuzzyTerm>(i)),
                    "has zero width (its centroid would be undefined)", show_term(t));
  }
  config::require(resolution_cm > 0.0 && resolution_cm <= range_max_cm / 10.0, at / "resolution_cm",
                  "must be > 0 and at most a tenth of range_max_cm", resolution_cm);
  // The lower bound comes from the loop it sizes: fuzzy_search_range takes
  // ceil(range_max_cm / resolution_cm) steps on every frame.
  const double finest = range_max_cm / kFuzzyMaxSteps;
  config::require(resolution_cm >= finest, at / "resolution_cm",
                  "must be at least range_max_cm / " + std::to_string(kFuzzyMaxSteps) + " = " +
                      config::show(finest) +
                      " cm: the centroid integrates range_max_cm / resolution_cm steps on every "
                      "frame",
                  resolution_cm);
  if (snap_ranges_cm.empty()) (at / "snap_ranges_cm").fail("must list at least one range", "[]");
  // The list is walked on every frame (snap_to_ranges) and each range checked against the grid.
  config::require(snap_ranges_cm.size() <= static_cast<std::size_t>(kFuzzyMaxSnapRanges),
                  at / "snap_ranges_cm",
                  "must list at most " + std::to_string(kFuzzyMaxSnapRanges) +
                      " ranges (the database search offers a handful; the list is walked on "
                      "every frame), got this many",
                  static_cast<double>(snap_ranges_cm.size()));
  for (std::size_t i = 0; i < snap_ranges_cm.size(); ++i) {
    const double r = snap_ranges_cm[i];
    config::require(std::isfinite(r) && r >= 0.0, (at / "snap_ranges_cm")[i],
                    "ranges must be finite and >= 0", r);
    if (i > 0)
      config::require(
          r > snap_ranges_cm[i - 1], (at / "snap_ranges_cm")[i],
          "must be strictly increasing (after " + config::show(snap_ranges_cm[i - 1]) + ")", r);
  }
}

namespace {

const config::Choices<FuzzyTerm>& term_choices() {
  static const config::Choices<FuzzyTerm> choices = {{"VL", FuzzyTerm::kVeryLow},
                                                     {"L", FuzzyTerm::kLow},
                                                     {"H", FuzzyTerm::kHigh},
                                                     {"VH", FuzzyTerm::kVeryHigh}};
  return choices;
}

// {"VL": v, "L": v, "H": v, "VH": v}, every term once, into an array indexed by term.
template <class V, class ReadOne>
std::array<V, kFuzzyTerms> read_per_term(const config::Node& n, ReadOne read_one) {
  n.expect_object();
  for (auto it = n.json().begin(); it != n.json().end(); ++it) {
    bool known = false;
    for (const auto& [name, term] : term_choices()) known = known || name == it.key();
    if (!known) (n / it.key()).fail("unknown term (the terms are VL, L, H, VH)");
  }
  std::array<V, kFuzzyTerms> out{};
  for (const auto& [name, term] : term_choices()) out[static_cast<int>(term)] = read_one(n / name);
  return out;
}

template <class V, class WriteOne>
config::Json write_per_term(const std::array<V, kFuzzyTerms>& values, WriteOne write_one) {
  config::Json out = config::Json::object();
  for (const auto& [name, term] : term_choices())
    out[name] = write_one(values[static_cast<int>(term)]);
  return out;
}

Trapezoid read_trapezoid(const config::Node& n) {
  const auto v = config::Codec<std::array<double, 4>>::read(n);
  return {v[0], v[1], v[2], v[3]};
}

config::Json write_trapezoid(const Trapezoid& t) {
  return config::Json::array({t.a, t.b, t.c, t.d});
}

config::Key<FuzzyConfig> terms_key(std::string name,
                                   std::array<Trapezoid, kFuzzyTerms> FuzzyConfig::*member) {
  return config::custom<FuzzyConfig>(
      std::move(name), config::Need::kRequired,
      [member](const config::Node& n, FuzzyConfig& c) {
        c.*member = read_per_term<Trapezoid>(n, read_trapezoid);
      },
      [member](const FuzzyConfig& c) { return write_per_term(c.*member, write_trapezoid); });
}

}  // namespace

const config::KeyTable<FuzzyConfig>& fuzzy_config_keys() {
  using config::key;
  using config::Need;
  static const config::KeyTable<FuzzyConfig> table = {
      key("speed_max_cm_per_s", &FuzzyConfig::speed_max_cm_per_s, Need::kRequired),
      terms_key("speed_terms", &FuzzyConfig::speed_terms),
      key("range_max_cm", &FuzzyConfig::range_max_cm, Need::kRequired),
      terms_key("range_terms", &FuzzyConfig::range_terms),
      config::custom<FuzzyConfig>(
          "rules", Need::kRequired,
          [](const config::Node& n, FuzzyConfig& c) {
            c.rules = read_per_term<FuzzyTerm>(
                n, [](const config::Node& r) { return read_choice(r, term_choices()); });
          },
          [](const FuzzyConfig& c) {
            return write_per_term(c.rules,
                                  [](FuzzyTerm t) { return config::Json(fuzzy_term_name(t)); });
          }),
      key("resolution_cm", &FuzzyConfig::resolution_cm, Need::kRequired),
      key("snap_ranges_cm", &FuzzyConfig::snap_ranges_cm, Need::kRequired),
  };
  return table;
}

FuzzyConfig parse_fuzzy_config(const config::Node& node) {
  FuzzyConfig c;
  config::read_keys(node, fuzzy_config_keys(), c);
  c.validate(node.origin());
  return c;
}

}  // namespace omniloc
