#include "omniloc/field.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "fnv.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/detail/config_reader.hpp"

namespace omniloc {

namespace {
constexpr double kMaxFieldSideCm = 5000.0;
constexpr double kMaxBorderCm = 1000.0;
constexpr double kMaxLineWidthCm = 50.0;
}  // namespace

namespace {

void positive(double v, const config::Origin& f) {
  config::require(v > 0.0, f, "must be > 0", v);
}
void non_negative(double v, const config::Origin& f) {
  config::require(v >= 0.0, f, "must be >= 0", v);
}

// The field's size and line width: positive, and bounded so that a typo cannot ask for an
// impossible database.
void validate_size(const FieldSpec& s, const config::Origin& at) {
  using config::require;
  require(!s.name.empty(), at / "name", "must not be empty", config::show(s.name));
  positive(s.field_length_cm, at / "field_length_cm");
  positive(s.field_width_cm, at / "field_width_cm");
  non_negative(s.border_cm, at / "border_cm");
  positive(s.line_width_cm, at / "line_width_cm");
  // Bounds far beyond any robot-soccer field (MSL is 22 x 14 m), so that a typo cannot ask for a
  // database of 10^6 x 10^6 points (a length of 1e7 cm ended in std::bad_alloc).
  require(s.field_length_cm <= kMaxFieldSideCm, at / "field_length_cm",
          "must be at most 5000 cm (50 m)", s.field_length_cm);
  require(s.field_width_cm <= kMaxFieldSideCm, at / "field_width_cm",
          "must be at most 5000 cm (50 m)", s.field_width_cm);
  require(s.border_cm <= kMaxBorderCm, at / "border_cm", "must be at most 1000 cm", s.border_cm);
  // A line is a few cm wide; 1000 cm would paint the whole field white.
  require(s.line_width_cm <= kMaxLineWidthCm, at / "line_width_cm", "must be at most 50 cm",
          s.line_width_cm);
}

// The circles, the goal and the areas in front of it: each fits its half of the field.
void validate_markings(const FieldSpec& s, const config::Origin& at) {
  using config::require;
  const double L = s.field_length_cm, W = s.field_width_cm;
  non_negative(s.centre_circle_radius_cm, at / "centre_circle_radius_cm");
  require(s.centre_circle_radius_cm < W / 2.0, at / "centre_circle_radius_cm",
          "must be < field_width_cm / 2", s.centre_circle_radius_cm);
  non_negative(s.corner_arc_radius_cm, at / "corner_arc_radius_cm");
  require(s.corner_arc_radius_cm < W / 2.0, at / "corner_arc_radius_cm",
          "must be < field_width_cm / 2", s.corner_arc_radius_cm);
  positive(s.goal.width_cm, at / "goal" / "width_cm");
  require(s.goal.width_cm < W, at / "goal" / "width_cm", "must be < field_width_cm",
          s.goal.width_cm);
  positive(s.goal.depth_cm, at / "goal" / "depth_cm");
  // The goal box stands on the carpet's border behind the goal line, inside the field frame.
  require(s.goal.depth_cm <= s.border_cm, at / "goal" / "depth_cm", "must be <= border_cm",
          s.goal.depth_cm);
  for (const auto& [key, area] :
       {std::pair{"goal_area", &s.goal_area}, std::pair{"penalty_area", &s.penalty_area}}) {
    non_negative(area->depth_cm, at / key / "depth_cm");
    require(area->depth_cm < L / 2.0, at / key / "depth_cm", "must be < field_length_cm / 2",
            area->depth_cm);
    non_negative(area->width_cm, at / key / "width_cm");
    require(area->width_cm < W, at / key / "width_cm", "must be < field_width_cm", area->width_cm);
  }
  non_negative(s.penalty_arc.radius_cm, at / "penalty_arc" / "radius_cm");
  non_negative(s.penalty_arc.centre_from_goal_line_cm,
               at / "penalty_arc" / "centre_from_goal_line_cm");
  require(s.penalty_arc.centre_from_goal_line_cm + s.penalty_arc.radius_cm < L / 2.0,
          at / "penalty_arc",
          "arc must stay within its half of the field (centre_from_goal_line_cm + radius_cm < "
          "field_length_cm / 2)",
          s.penalty_arc.centre_from_goal_line_cm + s.penalty_arc.radius_cm);
}

}  // namespace

void FieldSpec::validate(const config::Origin& at) const {
  validate_size(*this, at);
  validate_markings(*this, at);
  if (marks_from_centre_cm.empty()) return;
  const double L = field_length_cm, W = field_width_cm;
  positive(mark_radius_cm, at / "marks" / "radius_cm");
  for (std::size_t i = 0; i < marks_from_centre_cm.size(); ++i) {
    const Eigen::Vector2d& d = marks_from_centre_cm[i];
    config::require(std::abs(d.x()) + mark_radius_cm < L / 2.0 + 1e-9 &&
                        std::abs(d.y()) + mark_radius_cm < W / 2.0,
                    (at / "marks" / "from_centre_cm")[i], "lies outside the playing area",
                    config::show({d.x(), d.y()}));
  }
}

const char* goal_colour_name(GoalColour c) {
  switch (c) {
    case GoalColour::kBlue:
      return "blue";
    case GoalColour::kYellow:
      return "yellow";
    case GoalColour::kUnknown:
      break;
  }
  return "unknown";
}

namespace {
// Optional "colour_at_x_max": "blue" | "yellow"; absent (unknown) is not written back.
config::Key<FieldGoal> goal_colour_key() {
  const config::Choices<GoalColour> names = {{"blue", GoalColour::kBlue},
                                             {"yellow", GoalColour::kYellow}};
  return config::Key<FieldGoal>{"colour_at_x_max",
                                config::Need::kOptional,
                                config::Kind::kText,
                                [names](const config::Node& n, FieldGoal& g) {
                                  g.colour_at_x_max = config::read_choice(n, names);
                                },
                                [](const FieldGoal& g) -> std::optional<config::Json> {
                                  if (g.colour_at_x_max == GoalColour::kUnknown)
                                    return std::nullopt;
                                  return config::Json(goal_colour_name(g.colour_at_x_max));
                                },
                                "which goal colour is at the x = max end; absent = unknown"};
}
}  // namespace

const config::KeyTable<FieldSpec>& field_spec_keys() {
  using config::key;
  using config::Need;
  using F = FieldSpec;
  const config::KeyTable<FieldArea> area = {
      key("depth_cm", &FieldArea::depth_cm, Need::kRequired),
      key("width_cm", &FieldArea::width_cm, Need::kRequired),
  };
  static const config::KeyTable<FieldSpec> table = {
      key("name", &F::name, Need::kRequired),
      config::note<F>("description"),
      config::custom<F>(
          "units", Need::kOptional,
          [](const config::Node& n, F&) {
            if (n.text() != "cm") n.fail("the only unit is \"cm\"");
          },
          [](const F&) { return config::Json("cm"); }),
      key("field_length_cm", &F::field_length_cm, Need::kRequired),
      key("field_width_cm", &F::field_width_cm, Need::kRequired),
      key("border_cm", &F::border_cm, Need::kRequired),
      key("line_width_cm", &F::line_width_cm, Need::kRequired),
      key("centre_circle_radius_cm", &F::centre_circle_radius_cm, Need::kRequired),
      config::nested("goal", &F::goal,
                     config::KeyTable<FieldGoal>{
                         key("width_cm", &FieldGoal::width_cm, Need::kRequired),
                         key("depth_cm", &FieldGoal::depth_cm, Need::kRequired),
                         goal_colour_key(),
                     },
                     Need::kRequired),
      config::nested("goal_area", &F::goal_area, area, Need::kRequired),
      config::nested("penalty_area", &F::penalty_area, area, Need::kRequired),
      config::nested("penalty_arc", &F::penalty_arc,
                     config::KeyTable<PenaltyArc>{
                         key("radius_cm", &PenaltyArc::radius_cm, Need::kRequired),
                         key("centre_from_goal_line_cm", &PenaltyArc::centre_from_goal_line_cm,
                             Need::kRequired),
                     },
                     Need::kRequired),
      key("corner_arc_radius_cm", &F::corner_arc_radius_cm, Need::kRequired),
      config::group<F>("marks",
                       {
                           key("radius_cm", &F::mark_radius_cm, Need::kRequired),
                           key("from_centre_cm", &F::marks_from_centre_cm, Need::kRequired),
                       }),
  };
  return table;
}

FieldSpec parse_field_spec(const config::Node& node) {
  FieldSpec spec;
  config::read_keys(node, field_spec_keys(), spec);
  spec.validate(node.origin());
  return spec;
}

FieldGeometry build_field(const FieldSpec& spec, const std::string& source) {
  FieldGeometry f;
  f.source = source;
  f.spec = spec;
  f.name = spec.name;
  f.field_length_cm = spec.field_length_cm;
  f.field_width_cm = spec.field_width_cm;
  f.border_cm = spec.border_cm;
  f.line_width_cm = spec.line_width_cm;
  f.goal = spec.goal;
  const double cc_r = spec.centre_circle_radius_cm;
  const double corner_r = spec.corner_arc_radius_cm;
  const double goal_d = spec.goal_area.depth_cm, goal_w = spec.goal_area.width_cm;
  const double pen_d = spec.penalty_area.depth_cm, pen_w = spec.penalty_area.width_cm;
  const double pa_r = spec.penalty_arc.radius_cm;
  const double pa_c = spec.penalty_arc.centre_from_goal_line_cm;
  const double L = f.field_length_cm;
  const double W = f.field_width_cm;

  const double x0 = f.border_cm, x1 = f.border_cm + L;
  const double y0 = f.border_cm, y1 = f.border_cm + W;
  const Eigen::Vector2d c = f.centre_cm();
  auto seg = [&](double ax, double ay, double bx, double by) {
    f.segments.push_back({Eigen::Vector2d(ax, ay), Eigen::Vector2d(bx, by)});
  };
  seg(x0, y0, x1, y0);
  seg(x1, y0, x1, y1);
  seg(x1, y1, x0, y1);
  seg(x0, y1, x0, y0);
  seg(c.x(), y0, c.x(), y1);
  for (const double side : {1.0, -1.0}) {
    const double xg = side > 0 ? x0 : x1;  // this end's goal line
    for (const auto& [d, w] : {std::pair{goal_d, goal_w}, std::pair{pen_d, pen_w}}) {
      if (d <= 0.0 || w <= 0.0) continue;
      const double xf = xg + side * d;
      seg(xg, c.y() - w / 2, xf, c.y() - w / 2);
      seg(xf, c.y() - w / 2, xf, c.y() + w / 2);
      seg(xf, c.y() + w / 2, xg, c.y() + w / 2);
    }
    if (pa_r > 0.0) {
      // Only the part of the arc in front of the penalty area is drawn.
      const double cosine = std::clamp((pen_d - pa_c) / pa_r, -1.0, 1.0);
      const double half = rad_to_deg(std::acos(cosine));
      if (half > 0.0) {
        const double mid = side > 0 ? 0.0 : 180.0;
        f.arcs.push_back({Eigen::Vector2d(xg + side * pa_c, c.y()), pa_r, mid - half, mid + half});
      }
    }
  }
  if (cc_r > 0.0) f.arcs.push_back({c, cc_r, 0.0, 360.0});
  if (corner_r > 0.0) {
    f.arcs.push_back({Eigen::Vector2d(x0, y0), corner_r, 0.0, 90.0});
    f.arcs.push_back({Eigen::Vector2d(x1, y0), corner_r, 90.0, 180.0});
    f.arcs.push_back({Eigen::Vector2d(x1, y1), corner_r, 180.0, 270.0});
    f.arcs.push_back({Eigen::Vector2d(x0, y1), corner_r, 270.0, 360.0});
  }
  for (const Eigen::Vector2d& d : spec.marks_from_centre_cm)
    f.discs.push_back({c + d, spec.mark_radius_cm});
  return f;
}

namespace {

bool angle_in_sweep(double angle_deg, const FieldArc& a) {
  if (a.end_deg - a.start_deg >= 360.0) return true;
  double rel = std::fmod(angle_deg - a.start_deg, 360.0);
  if (rel < 0.0) rel += 360.0;
  return rel <= a.end_deg - a.start_deg;
}

bool in_arc(const FieldArc& a, double half_w, const Eigen::Vector2d& p) {
  const Eigen::Vector2d d = p - a.centre_cm;
  const double r = d.norm();
  if (std::abs(r - a.radius_cm) > half_w) return false;
  return angle_in_sweep(rad_to_deg(std::atan2(d.y(), d.x())), a);
}

bool in_segment(const FieldSegment& s, double half_w, const Eigen::Vector2d& p) {
  const Eigen::Vector2d ab = s.b_cm - s.a_cm;
  const double len = ab.norm();
  const Eigen::Vector2d ex = ab / len;
  const Eigen::Vector2d ap = p - s.a_cm;
  const double along = ap.dot(ex);
  const double across = ex.x() * ap.y() - ex.y() * ap.x();
  return along >= -half_w && along <= len + half_w && std::abs(across) <= half_w;
}

// Quick reject: does the ray segment [t_lo, t_hi] pass within `radius` of `centre`?
bool ray_near(const Eigen::Vector2d& o, const Eigen::Vector2d& u, double t_lo, double t_hi,
              const Eigen::Vector2d& centre, double radius) {
  const Eigen::Vector2d f = centre - o;
  const double along = f.dot(u);
  const double perp2 = f.squaredNorm() - along * along;
  if (perp2 > radius * radius) return false;
  return along + radius >= t_lo && along - radius <= t_hi;
}

// Roots of |o + t u - c| = r (u unit); returns the count (0 or 2).
int circle_hits(const Eigen::Vector2d& o, const Eigen::Vector2d& u, const Eigen::Vector2d& c,
                double r, double& t0, double& t1) {
  const Eigen::Vector2d f = o - c;
  const double b = f.dot(u);
  const double disc = b * b - (f.squaredNorm() - r * r);
  if (disc <= 0.0) return 0;
  const double s = std::sqrt(disc);
  t0 = -b - s;
  t1 = -b + s;
  return 2;
}

void push_clipped(double a, double b, double t_lo, double t_hi, std::vector<WhiteInterval>& out) {
  a = std::max(a, t_lo);
  b = std::min(b, t_hi);
  if (b > a) out.push_back({a, b});
}

}  // namespace

std::uint64_t FieldGeometry::fingerprint() const {
  using detail::fnv1a_double;
  std::uint64_t h = detail::kFnvOffset;
  for (double v : {field_length_cm, field_width_cm, border_cm, line_width_cm})
    h = fnv1a_double(v, h);
  for (const auto& s : segments) {
    for (double v : {s.a_cm.x(), s.a_cm.y(), s.b_cm.x(), s.b_cm.y()}) h = fnv1a_double(v, h);
  }
  for (const auto& a : arcs) {
    for (double v : {a.centre_cm.x(), a.centre_cm.y(), a.radius_cm, a.start_deg, a.end_deg})
      h = fnv1a_double(v, h);
  }
  for (const auto& d : discs) {
    for (double v : {d.centre_cm.x(), d.centre_cm.y(), d.radius_cm}) h = fnv1a_double(v, h);
  }
  return h;
}

FieldGeometry load_field(const std::string& name_or_path) {
  const std::string file = resolve_data_file("fields", name_or_path).string();
  return build_field(parse_field_spec(config::parse_json_file(file).root()), file);
}

bool on_carpet(const FieldGeometry& field, const Eigen::Vector2d& p) {
  return p.x() >= 0.0 && p.y() >= 0.0 && p.x() <= field.total_x_cm() && p.y() <= field.total_y_cm();
}

bool placeable(const FieldGeometry& field, const Eigen::Vector2d& p) {
  const double m = kPlacementMarginCm;
  return p.x() >= -m && p.y() >= -m && p.x() <= field.total_x_cm() + m &&
         p.y() <= field.total_y_cm() + m;
}

void for_each_line_point(const FieldGeometry& field, double step_cm,
                         const std::function<void(const Eigen::Vector2d&)>& f) {
  for (const auto& s : field.segments) {
    const int n = std::max(1, static_cast<int>(std::ceil((s.b_cm - s.a_cm).norm() / step_cm)));
    for (int i = 0; i <= n; ++i) f(s.a_cm + (s.b_cm - s.a_cm) * (static_cast<double>(i) / n));
  }
  for (const auto& a : field.arcs) {
    const double span_deg = a.end_deg - a.start_deg;
    const int n =
        std::max(1, static_cast<int>(std::ceil(deg_to_rad(span_deg) * a.radius_cm / step_cm)));
    for (int i = 0; i <= n; ++i) {
      const double t = deg_to_rad(a.start_deg + span_deg * i / n);
      f(a.centre_cm + a.radius_cm * Eigen::Vector2d(std::cos(t), std::sin(t)));
    }
  }
}

bool is_white(const FieldGeometry& field, const Eigen::Vector2d& p) {
  const double h = field.line_width_cm / 2.0;
  // Bounding-box rejects first: most points are far from most lines (the renderer calls this per
  // pixel).
  for (const auto& s : field.segments) {
    if (p.x() < std::min(s.a_cm.x(), s.b_cm.x()) - h ||
        p.x() > std::max(s.a_cm.x(), s.b_cm.x()) + h ||
        p.y() < std::min(s.a_cm.y(), s.b_cm.y()) - h ||
        p.y() > std::max(s.a_cm.y(), s.b_cm.y()) + h) {
      continue;
    }
    if (in_segment(s, h, p)) return true;
  }
  for (const auto& a : field.arcs) {
    const double reach = a.radius_cm + h;
    if (std::abs(p.x() - a.centre_cm.x()) > reach || std::abs(p.y() - a.centre_cm.y()) > reach)
      continue;
    if (in_arc(a, h, p)) return true;
  }
  for (const auto& d : field.discs) {
    if ((p - d.centre_cm).squaredNorm() <= d.radius_cm * d.radius_cm) return true;
  }
  return false;
}

WhiteLineIndex::WhiteLineIndex(const FieldGeometry& field) : field_(field) {
  const double h = field_.line_width_cm / 2.0;
  nx_ = static_cast<int>(std::ceil(field_.total_x_cm() / cell_cm_)) + 1;
  ny_ = static_cast<int>(std::ceil(field_.total_y_cm() / cell_cm_)) + 1;
  struct Box {
    double x0, y0, x1, y1;
  };
  std::vector<Box> boxes;
  for (const auto& sg : field_.segments) {
    boxes.push_back({std::min(sg.a_cm.x(), sg.b_cm.x()) - h, std::min(sg.a_cm.y(), sg.b_cm.y()) - h,
                     std::max(sg.a_cm.x(), sg.b_cm.x()) + h,
                     std::max(sg.a_cm.y(), sg.b_cm.y()) + h});
  }
  for (const auto& a : field_.arcs) {
    const double r = a.radius_cm + h;
    boxes.push_back(
        {a.centre_cm.x() - r, a.centre_cm.y() - r, a.centre_cm.x() + r, a.centre_cm.y() + r});
  }
  for (const auto& d : field_.discs) {
    boxes.push_back({d.centre_cm.x() - d.radius_cm, d.centre_cm.y() - d.radius_cm,
                     d.centre_cm.x() + d.radius_cm, d.centre_cm.y() + d.radius_cm});
  }
  if (boxes.size() > 65535) throw std::invalid_argument("WhiteLineIndex: too many lines");
  std::vector<std::vector<std::uint16_t>> buckets(static_cast<std::size_t>(nx_ * ny_));
  for (std::size_t b = 0; b < boxes.size(); ++b) {
    const int i0 = std::max(0, static_cast<int>(std::floor(boxes[b].x0 / cell_cm_)));
    const int i1 = std::min(nx_ - 1, static_cast<int>(std::floor(boxes[b].x1 / cell_cm_)));
    const int j0 = std::max(0, static_cast<int>(std::floor(boxes[b].y0 / cell_cm_)));
    const int j1 = std::min(ny_ - 1, static_cast<int>(std::floor(boxes[b].y1 / cell_cm_)));
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i)
        buckets[static_cast<std::size_t>(j * nx_ + i)].push_back(static_cast<std::uint16_t>(b));
    }
  }
  offsets_.push_back(0);
  for (const auto& bucket : buckets) {
    items_.insert(items_.end(), bucket.begin(), bucket.end());
    offsets_.push_back(static_cast<std::uint32_t>(items_.size()));
  }
}

bool WhiteLineIndex::is_white(const Eigen::Vector2d& p) const {
  // Lines lie on the carpet; buckets cover it (boxes reaching past it are clipped to the edge
  // buckets, so points just outside the carpet fall back to the full test).
  if (p.x() < 0.0 || p.y() < 0.0) return omniloc::is_white(field_, p);
  const int i = static_cast<int>(p.x() / cell_cm_), j = static_cast<int>(p.y() / cell_cm_);
  if (i >= nx_ || j >= ny_) return omniloc::is_white(field_, p);
  const double h = field_.line_width_cm / 2.0;
  const std::size_t nseg = field_.segments.size(), narc = field_.arcs.size();
  const auto b = static_cast<std::size_t>(j * nx_ + i);
  for (std::uint32_t k = offsets_[b]; k < offsets_[b + 1]; ++k) {
    const std::size_t id = items_[k];
    if (id < nseg) {
      if (in_segment(field_.segments[id], h, p)) return true;
    } else if (id < nseg + narc) {
      if (in_arc(field_.arcs[id - nseg], h, p)) return true;
    } else {
      const FieldDisc& d = field_.discs[id - nseg - narc];
      if ((p - d.centre_cm).squaredNorm() <= d.radius_cm * d.radius_cm) return true;
    }
  }
  return false;
}

RayCaster::RayCaster(const FieldGeometry& field) : half_width_cm_(field.line_width_cm / 2.0) {
  const double h = half_width_cm_;
  for (const auto& sg : field.segments) {
    const Eigen::Vector2d ab = sg.b_cm - sg.a_cm;
    const double len = ab.norm();
    segs_.push_back({sg.a_cm, ab / len, (sg.a_cm + sg.b_cm) / 2.0, len, len / 2.0 + h * 1.5});
  }
  for (const auto& a : field.arcs) {
    const double span = a.end_deg - a.start_deg;
    arcs_.push_back(
        {a, Eigen::Vector2d(std::cos(deg_to_rad(a.start_deg)), std::sin(deg_to_rad(a.start_deg))),
         Eigen::Vector2d(std::cos(deg_to_rad(a.end_deg)), std::sin(deg_to_rad(a.end_deg))),
         span >= 360.0, span <= 180.0});
  }
  discs_ = field.discs;
}

namespace {

// A segment's white band as a ray interval: the slab test in the segment's frame, along in
// [-h, len + h], across in [-h, h]. (RayCaster::Seg, private: deduced.)
void segment_interval(const auto& sg, const Eigen::Vector2d& o, const Eigen::Vector2d& u,
                      double t_lo, double t_hi, double h, std::vector<WhiteInterval>& out) {
  const Eigen::Vector2d ao = o - sg.a;
  double enter = t_lo, exit = t_hi;
  const double p_along = ao.dot(sg.ex), d_along = u.dot(sg.ex);
  const double p_across = sg.ex.x() * ao.y() - sg.ex.y() * ao.x(),
               d_across = sg.ex.x() * u.y() - sg.ex.y() * u.x();
  bool hit = true;
  for (const auto& [p, d, lo, hi] :
       {std::tuple{p_along, d_along, -h, sg.len + h}, std::tuple{p_across, d_across, -h, h}}) {
    if (std::abs(d) < 1e-12) {
      if (p < lo || p > hi) hit = false;
      continue;
    }
    double ta = (lo - p) / d, tb = (hi - p) / d;
    if (ta > tb) std::swap(ta, tb);
    enter = std::max(enter, ta);
    exit = std::min(exit, tb);
  }
  if (hit) push_clipped(enter, exit, t_lo, t_hi, out);
}

// Inside the arc's annulus sector? Sweeps up to 180 deg by two cross products, longer ones by
// angle. (RayCaster::Arc, private: deduced.)
bool in_arc_band(const auto& pa, double h, const Eigen::Vector2d& p) {
  const FieldArc& a = pa.arc;
  const Eigen::Vector2d d = p - a.centre_cm;
  const double r2 = d.squaredNorm();
  const double r_in = std::max(0.0, a.radius_cm - h), r_out = a.radius_cm + h;
  if (r2 < r_in * r_in || r2 > r_out * r_out) return false;
  if (pa.full) return true;
  if (pa.half_or_less) {
    return pa.e_start.x() * d.y() - pa.e_start.y() * d.x() >= 0.0 &&
           d.x() * pa.e_end.y() - d.y() * pa.e_end.x() >= 0.0;
  }
  return angle_in_sweep(rad_to_deg(std::atan2(d.y(), d.x())), a);
}

// Candidate boundaries of the arc's band along the ray: both circles of the annulus and the two
// radial end cuts, sorted after cand[0] = t_lo. Returns the count (at most 7).
int arc_candidates(const auto& pa, const Eigen::Vector2d& o, const Eigen::Vector2d& u, double t_lo,
                   double h, double (&cand)[8]) {
  const FieldArc& a = pa.arc;
  int n = 0;
  cand[n++] = t_lo;
  double t0 = 0, t1 = 0;
  if (circle_hits(o, u, a.centre_cm, a.radius_cm + h, t0, t1) == 2) {
    cand[n++] = t0;
    cand[n++] = t1;
  }
  if (a.radius_cm > h && circle_hits(o, u, a.centre_cm, a.radius_cm - h, t0, t1) == 2) {
    cand[n++] = t0;
    cand[n++] = t1;
  }
  if (!pa.full) {
    for (const Eigen::Vector2d* e : {&pa.e_start, &pa.e_end}) {
      const double den = u.x() * e->y() - u.y() * e->x();
      if (std::abs(den) < 1e-12) continue;
      const Eigen::Vector2d f = a.centre_cm - o;
      cand[n++] = (f.x() * e->y() - f.y() * e->x()) / den;
    }
  }
  for (int i = 2; i < n; ++i) {  // insertion sort of at most 6 values (cand[0] = t_lo stays first)
    for (int k = i; k > 1 && cand[k - 1] > cand[k]; --k) std::swap(cand[k - 1], cand[k]);
  }
  return n;
}

// An arc's white band as ray intervals: every piece between consecutive candidate boundaries is
// wholly in or out, decided at its midpoint.
void arc_intervals(const auto& pa, const Eigen::Vector2d& o, const Eigen::Vector2d& u, double t_lo,
                   double t_hi, double h, std::vector<WhiteInterval>& out) {
  double cand[8];
  const int n = arc_candidates(pa, o, u, t_lo, h, cand);
  double prev = t_lo;
  double run_start = -1.0;
  bool in_run = false;
  for (int i = 1; i <= n; ++i) {
    const double next = i < n ? std::clamp(cand[i], t_lo, t_hi) : t_hi;
    if (next <= prev) continue;
    const bool in = in_arc_band(pa, h, o + u * (0.5 * (prev + next)));
    if (in && !in_run) run_start = prev;
    if (!in && in_run) push_clipped(run_start, prev, t_lo, t_hi, out);
    in_run = in;
    prev = next;
  }
  if (in_run) push_clipped(run_start, t_hi, t_lo, t_hi, out);
}

// The intervals sorted by entry, overlapping ones merged.
void merge_intervals(std::vector<WhiteInterval>& out) {
  std::sort(out.begin(), out.end(),
            [](const WhiteInterval& x, const WhiteInterval& y) { return x.enter_cm < y.enter_cm; });
  std::size_t w = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (w > 0 && out[i].enter_cm <= out[w - 1].exit_cm) {
      out[w - 1].exit_cm = std::max(out[w - 1].exit_cm, out[i].exit_cm);
    } else {
      out[w++] = out[i];
    }
  }
  out.resize(w);
}

}  // namespace

void RayCaster::intervals(const Eigen::Vector2d& o, const Eigen::Vector2d& u, double t_lo,
                          double t_hi, std::vector<WhiteInterval>& out) const {
  out.clear();
  const double h = half_width_cm_;
  for (const auto& sg : segs_) {
    if (!ray_near(o, u, t_lo, t_hi, sg.mid, sg.bound)) continue;
    segment_interval(sg, o, u, t_lo, t_hi, h, out);
  }
  for (const auto& d : discs_) {
    if (!ray_near(o, u, t_lo, t_hi, d.centre_cm, d.radius_cm)) continue;
    double t0 = 0, t1 = 0;
    if (circle_hits(o, u, d.centre_cm, d.radius_cm, t0, t1) == 2)
      push_clipped(t0, t1, t_lo, t_hi, out);
  }
  for (const auto& pa : arcs_) {
    if (!ray_near(o, u, t_lo, t_hi, pa.arc.centre_cm, pa.arc.radius_cm + h)) continue;
    arc_intervals(pa, o, u, t_lo, t_hi, h, out);
  }
  merge_intervals(out);
}

void white_intervals(const FieldGeometry& field, const Eigen::Vector2d& o, const Eigen::Vector2d& u,
                     double t_lo, double t_hi, std::vector<WhiteInterval>& out) {
  RayCaster(field).intervals(o, u, t_lo, t_hi, out);
}

}  // namespace omniloc
