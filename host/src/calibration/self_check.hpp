// The calibration's check of its own camera against the frame (internal to the calibration).
#pragma once

#include <opencv2/core/mat.hpp>

#include "omniloc/calibration.hpp"
#include "omniloc/conventions.hpp"

namespace omniloc::detail {

/// How much of the field's lines the camera puts on the frame's carpet is seen there as line.
struct LineRecall {
  int expected = 0;  // line points the camera puts on the carpet, inside its table, off the masts
  int seen = 0;      // of those, with a line pixel within 3 px
  [[nodiscard]] double fraction() const {
    return expected > 0 ? static_cast<double>(seen) / expected : 0.0;
  }
};

/// The field's lines sampled every 2 cm, projected through `camera` from `pose`, against the
/// analysis's carpet and line masks.
[[nodiscard]] LineRecall model_line_recall(const CameraModel& camera, const FrameAnalysis& analysis,
                                           const Pose2& pose, const FieldGeometry& field);

}  // namespace omniloc::detail
