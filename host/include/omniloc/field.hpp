// Field model: the white lines of a soccer field, loaded from a geometry file (common/fields/),
// as the one description shared by the renderer, the database builder and the matcher.
//
// Every line is stored by its centre line; a point is white when it lies within line_width_cm / 2
// of a segment or an arc (segment ends are extended by the half width so that corners close).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "omniloc/config.hpp"

namespace omniloc {

/// A rectangle in front of a goal line (goal area, penalty area), cm.
struct FieldArea {
  double depth_cm = 0.0;  ///< along field x, from the goal line
  double width_cm = 0.0;  ///< along field y, centred
  bool operator==(const FieldArea&) const = default;
};

/// The arc in front of a penalty area: its centre lies centre_from_goal_line_cm from the goal line.
struct PenaltyArc {
  double radius_cm = 0.0;  ///< 0: no arc
  double centre_from_goal_line_cm = 0.0;
  bool operator==(const PenaltyArc&) const = default;
};

/// Which colour a goal is painted (FIRA and RoboCup Junior: one blue, one yellow goal).
enum class GoalColour : std::uint8_t { kUnknown, kBlue, kYellow };

/// The goals: a box behind each goal line, centred on it, standing in the border (cm). Its colour
/// at the x = max end is optional: absent = unknown (learnt at calibration, camera "vision" block).
struct FieldGoal {
  double width_cm = 0.0;  ///< along field y, between the posts
  double depth_cm = 0.0;  ///< along field x, behind the goal line (at most border_cm)
  GoalColour colour_at_x_max = GoalColour::kUnknown;
  bool operator==(const FieldGoal&) const = default;
};

/// A geometry file (common/fields/<name>.json) as written: every key is required but "marks" (and
/// the notes "description", "units" = "cm"), so the files are the only source of these values.
struct FieldSpec {
  std::string name;
  double field_length_cm = 0.0;
  double field_width_cm = 0.0;
  double border_cm = 0.0;
  double line_width_cm = 0.0;
  double centre_circle_radius_cm = 0.0;  ///< 0: none
  FieldGoal goal;
  FieldArea goal_area;
  FieldArea penalty_area;
  PenaltyArc penalty_arc;
  double corner_arc_radius_cm = 0.0;  ///< 0: none
  double mark_radius_cm = 0.0;        ///< "marks": {"radius_cm", "from_centre_cm": [[dx, dy], ...]}
  std::vector<Eigen::Vector2d> marks_from_centre_cm;

  /// Throws ConfigError "<at>.<field>: <why> (got <value>)": non-positive sizes, circles or areas
  /// that do not fit the field, marks outside the playing area.
  void validate(const config::Origin& at) const;
  bool operator==(const FieldSpec&) const = default;
};

/// Reads and validates a geometry file's object.
[[nodiscard]] FieldSpec parse_field_spec(const config::Node& node);
/// The key table (config_reader.hpp) of a geometry file.
[[nodiscard]] const std::vector<config::Key<FieldSpec>>& field_spec_keys();

/// A straight white line between two points (its centre line), field frame cm.
struct FieldSegment {
  Eigen::Vector2d a_cm;
  Eigen::Vector2d b_cm;
};

/// A white arc: centre, radius of its centre line, and the counter-clockwise sweep start..end.
struct FieldArc {
  Eigen::Vector2d centre_cm;
  double radius_cm = 0.0;
  double start_deg = 0.0;
  double end_deg = 360.0;  // end_deg > start_deg; a span of 360 is a full circle
};

/// A filled white disc (penalty or free-ball mark).
struct FieldDisc {
  Eigen::Vector2d centre_cm;
  double radius_cm = 0.0;
};

struct FieldGeometry {
  std::string name;
  std::string source;            // file it was read from, for error messages
  double field_length_cm = 0.0;  // playing area, along field x
  double field_width_cm = 0.0;   // playing area, along field y
  double border_cm = 0.0;        // carpet around the playing area
  double line_width_cm = 0.0;
  FieldGoal goal;  // not lines: not in the fingerprint (the database does not depend on it)
  std::vector<FieldSegment> segments;
  std::vector<FieldArc> arcs;
  std::vector<FieldDisc> discs;
  /// The spec the lines were built from (a recording's meta.json embeds it, so that it replays
  /// without the geometry file).
  FieldSpec spec;

  /// Extent of the carpet (playing area plus border): the field frame spans [0, total].
  [[nodiscard]] double total_x_cm() const { return field_length_cm + 2.0 * border_cm; }
  [[nodiscard]] double total_y_cm() const { return field_width_cm + 2.0 * border_cm; }
  [[nodiscard]] Eigen::Vector2d centre_cm() const {
    return {total_x_cm() / 2.0, total_y_cm() / 2.0};
  }
  /// Hash of everything that changes the lines (not the name or source), for database headers.
  [[nodiscard]] std::uint64_t fingerprint() const;
};

/// "blue", "yellow" or "unknown".
[[nodiscard]] const char* goal_colour_name(GoalColour c);

/// The lines of a (valid) spec; `source` is kept for error messages.
[[nodiscard]] FieldGeometry build_field(const FieldSpec& spec, const std::string& source);

/// Loads a geometry file by name ("fira-robosot", "robocup-msl") or path. Throws ConfigError
/// naming the file and the field for a missing, malformed or invalid entry.
[[nodiscard]] FieldGeometry load_field(const std::string& name_or_path);

/// Calls `f` with points along the centre line of every segment and arc of the field, `step_cm`
/// apart along each (both ends included); the discs (marks) are the caller's.
void for_each_line_point(const FieldGeometry& field, double step_cm,
                         const std::function<void(const Eigen::Vector2d&)>& f);

/// True when the floor point p (field frame, cm) is on a white line.
[[nodiscard]] bool is_white(const FieldGeometry& field, const Eigen::Vector2d& p_cm);

/// is_white() for many points (the renderer calls it per pixel): a 10 cm bucket grid over the
/// carpet lists the few lines near each bucket. Same answers as is_white() on and off the carpet.
class WhiteLineIndex {
 public:
  explicit WhiteLineIndex(const FieldGeometry& field);
  [[nodiscard]] bool is_white(const Eigen::Vector2d& p_cm) const;

 private:
  FieldGeometry field_;
  double cell_cm_ = 10.0;
  int nx_ = 0, ny_ = 0;
  std::vector<std::uint32_t>
      offsets_;                       // bucket b's lines are items_[offsets_[b] .. offsets_[b + 1])
  std::vector<std::uint16_t> items_;  // segment i, then arc nseg + i, then disc nseg + narc + i
};

/// True when p lies on the carpet (playing area or border).
[[nodiscard]] bool on_carpet(const FieldGeometry& field, const Eigen::Vector2d& p_cm);

/// How far off the carpet a robot may be put down (a start pose, an operator's set_pose).
inline constexpr double kPlacementMarginCm = 100.0;
/// True when p lies on the carpet or within kPlacementMarginCm of it.
[[nodiscard]] bool placeable(const FieldGeometry& field, const Eigen::Vector2d& p_cm);

/// A stretch [enter, exit] of a ray p + t * dir (t in cm, dir a unit vector) that is white.
struct WhiteInterval {
  double enter_cm;
  double exit_cm;
};

/// Casts rays through the lines: the white stretches along origin + t dir for t in
/// [t_min, t_max], merged and sorted (an interval already white at t_min starts at t_min).
/// Holds per-line data (frames, bounding circles, arc end directions) computed once, because the
/// database builder and the refinement cast hundreds of thousands of rays.
class RayCaster {
 public:
  explicit RayCaster(const FieldGeometry& field);
  void intervals(const Eigen::Vector2d& origin_cm, const Eigen::Vector2d& dir, double t_min_cm,
                 double t_max_cm, std::vector<WhiteInterval>& out) const;

 private:
  struct Seg {
    Eigen::Vector2d a, ex, mid;
    double len, bound;
  };
  struct Arc {
    FieldArc arc;
    Eigen::Vector2d e_start, e_end;
    bool full, half_or_less;
  };
  double half_width_cm_;
  std::vector<Seg> segs_;
  std::vector<Arc> arcs_;
  std::vector<FieldDisc> discs_;
};

/// One-off form of RayCaster::intervals.
void white_intervals(const FieldGeometry& field, const Eigen::Vector2d& origin_cm,
                     const Eigen::Vector2d& dir, double t_min_cm, double t_max_cm,
                     std::vector<WhiteInterval>& out);

}  // namespace omniloc
