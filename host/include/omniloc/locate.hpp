// Single-frame localisation: one scan to a pose by the localizer's global search and acceptance
// rule, shared by Localizer (its global searches: at start, when lost, the cross-check) and
// `omniloc locate`, so that the command says exactly what the localizer would do with the frame.
//
//   heading known   global_search over the grid at that heading, refinement by the config;
//   heading unknown global_search_any_yaw (every heading in 2 deg steps, then finer);
//   then            the error judged as the localizer judges it (refined error with ray-cast
//                   refinement), and when the lines alone are ambiguous (a second distinct minimum
//                   as good, e.g. the twin on the symmetric field) the goal colours choose between
//                   the two candidates (goals.hpp) if they can; accepted = error < E_TH and not
//                   (refuse_ambiguous and still ambiguous).
#pragma once

#include <optional>

#include <opencv2/core/mat.hpp>

#include "omniloc/camera.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/feature_db.hpp"
#include "omniloc/field.hpp"
#include "omniloc/goals.hpp"
#include "omniloc/line_scan.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/matcher.hpp"

namespace omniloc {

/// The matcher options a localizer config implies (one place for Localizer and locate_frame).
[[nodiscard]] MatchOptions match_options_of(const LocalizerConfig& config);

/// The error E_TH is judged on: at the refined position with ray-cast refinement (the error
/// surface is so steep that a grid point 5 cm from the robot often scores above E_TH), else at
/// the grid point.
[[nodiscard]] double judged_error(const LocalizerConfig& config, const MatchResult& m);

/// The yaw step of the global search without a heading.
inline constexpr double kAnyYawStepDeg = 2.0;

struct SingleFrameResult {
  Pose2 pose;             ///< the chosen candidate (yaw: the given heading, or the one found)
  MatchResult match;      ///< at pose; error is the judged error (see locate.hpp)
  bool accepted = false;  ///< error < E_TH and not refused as ambiguous
  /// the position is still ambiguous after the goal cue (the twin stands elsewhere)
  bool ambiguous = false;
  /// The twin stands at (nearly) the same position, at the opposite heading: the robot is near the
  /// centre of the point-symmetric field and the goal cue did not decide. The position is known,
  /// the heading only up to 180 deg (a Localizer without a heading refuses it; `locate` accepts
  /// the position and says so).
  bool heading_ambiguous = false;
  bool lines_ambiguous = false;  ///< the lines alone could not tell pose from twin
  std::optional<Pose2> twin;     ///< the other candidate when the lines were ambiguous
  double twin_error = kNoError;  ///< its judged error
  TwinChoice goal_choice;  ///< the goal cue's verdict (undecided with a reason when not needed or
                           ///< not possible)
  bool yaw_searched = false;  ///< the heading was unknown and searched
};

/// The localizer's global search and acceptance on one robot-frame scan. `yaw_deg` is the heading
/// when known; `at_yaw` may pass the scan already rotated to it (the localizer rotates once per
/// frame), else it is made here. `goals` (may be null) is the frame's goal observation.
[[nodiscard]] SingleFrameResult locate_frame(const LocalizerConfig& config,
                                             const FieldGeometry& field, const CameraModel& camera,
                                             const FeatureDb& db, const BearingScan& bearings,
                                             std::optional<double> yaw_deg,
                                             const GoalObservation* goals,
                                             const FieldScan* at_yaw = nullptr);

/// What the overlay draws besides the frame.
struct LocateOverlayInput {
  const BearingScan* bearings = nullptr;  ///< robot-frame rays, crossings and ray ends
  const SingleFrameResult* result = nullptr;
  const GoalObservation* goals = nullptr;  ///< goal-coloured samples (may be null)
};
/// The frame with: the rays' seen stretch (grey) and ends (the carpet boundary / view end, red),
/// the crossings (magenta), the goal-coloured samples (their colour), and the field model
/// projected through the camera at the found pose (yellow; the twin, if any, in cyan).
[[nodiscard]] cv::Mat locate_overlay(const cv::Mat& bgr, const CameraModel& camera,
                                     const FieldGeometry& field, const LocateOverlayInput& input);

}  // namespace omniloc
