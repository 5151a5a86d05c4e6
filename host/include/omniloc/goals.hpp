// Goal colours as the cue that tells a pose from its twin (issue 13 item 4). On a point-symmetric
// field the pose p and its twin (centre * 2 - p, yaw + 180) see exactly the same lines; only the
// goals' colours differ. With the camera's goal colour models (learnt at calibration, camera
// "vision" block) and which colour stands at x = max, the goal-coloured pixels of the image are
// collected once per frame (observe_goals: their bearing and floor distance, robot frame), and each
// candidate pose is scored by how many of them lie where that pose expects their colour: beyond a
// goal line, inside the goal mouth's wedge as seen from the pose (goal_evidence). choose_by_goals
// picks one of two candidates only when the evidence is strong and one-sided; otherwise the result
// stays ambiguous.
//
// The colour models and the cue's thresholds come from the camera's "vision" block
// (CameraModel::vision, omniloc/vision.hpp); goal_colour_models() is the view of it this cue uses.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "omniloc/camera.hpp"
#include "omniloc/config.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/field.hpp"
#include "omniloc/vision.hpp"

namespace omniloc {

/// The goal colour models a camera carries: either colour may be unknown (not learnt).
struct GoalColourModels {
  std::optional<GoalHsv> blue;
  std::optional<GoalHsv> yellow;
  GoalColour colour_at_x_max = GoalColour::kUnknown;  ///< camera's learnt "goal_colour_at_x_max"
  GoalCueConfig cue;
  bool operator==(const GoalColourModels&) const = default;
};

/// The camera's goal colour models and cue thresholds (its "vision" block, learnt at calibration).
[[nodiscard]] GoalColourModels goal_colour_models(const VisionModel& vision);

/// Which colour stands at x = max: the field file's if it says, else the camera's learnt one.
[[nodiscard]] GoalColour goal_colour_at_x_max(const FieldGeometry& field,
                                              const GoalColourModels& models);

/// A goal-coloured pixel: robot-frame bearing and floor distance (infinity beyond the radius
/// table: a goal wall seen above the floor's last calibrated ring is "far").
struct GoalPixel {
  float bearing_deg = 0.0f;
  float ground_cm = 0.0f;
  float radius_px = 0.0f;  ///< in the image (for overlays)
  GoalColour colour = GoalColour::kUnknown;
};

/// One frame's goal-coloured pixels and what is needed to judge them.
struct GoalObservation {
  /// False when there is nothing to compare: no colour model, or which colour is at x = max
  /// unknown.
  bool colours_known = false;
  GoalColour colour_at_x_max = GoalColour::kUnknown;
  GoalCueConfig cue;
  std::vector<GoalPixel> pixels;
};

/// Collects the goal-coloured pixels of a BGR frame (outside the body, not in a mast sector).
/// Throws std::invalid_argument when the image does not have the camera's size.
[[nodiscard]] GoalObservation observe_goals(const cv::Mat& bgr, const CameraModel& camera,
                                            const FieldGeometry& field,
                                            const GoalColourModels& models);

/// Pixels beyond a goal line inside its mouth's wedge as seen from `pose`: of the colour the pose
/// expects there (agreeing), of the other colour (contrary).
struct GoalEvidence {
  int agreeing = 0;
  int contrary = 0;
  [[nodiscard]] int considered() const { return agreeing + contrary; }
  [[nodiscard]] int score() const { return agreeing - contrary; }
};
[[nodiscard]] GoalEvidence goal_evidence(const FieldGeometry& field, const Pose2& pose,
                                         const GoalObservation& obs);

enum class TwinDecision { kFirst, kSecond, kUndecided };
struct TwinChoice {
  TwinDecision decision = TwinDecision::kUndecided;
  GoalEvidence first;
  GoalEvidence second;
  double margin = 0.0;  ///< (first.score - second.score) / (2 * considered), see GoalCueConfig
  std::string reason;   ///< why (for the command's output and logs)
};
/// Picks between two candidate poses by the goal colours, or says why it cannot.
[[nodiscard]] TwinChoice choose_by_goals(const FieldGeometry& field, const Pose2& first,
                                         const Pose2& second, const GoalObservation& obs);

}  // namespace omniloc
