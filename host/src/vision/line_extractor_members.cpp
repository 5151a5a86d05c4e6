// LineExtractor's copy, move and destruction, here where its RayTable (an internal type, not in the
// installed vision.hpp) is complete.
#include "omniloc/detail/line_extractor.hpp"
#include "omniloc/vision.hpp"

namespace omniloc {

LineExtractor::~LineExtractor() = default;
LineExtractor::LineExtractor(const LineExtractor&) = default;
LineExtractor& LineExtractor::operator=(const LineExtractor&) = default;
LineExtractor::LineExtractor(LineExtractor&&) noexcept = default;
LineExtractor& LineExtractor::operator=(LineExtractor&&) noexcept = default;

}  // namespace omniloc
