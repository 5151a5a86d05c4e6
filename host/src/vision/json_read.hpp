// Reading validated values from cv::FileStorage (JSON) nodes with errors that name the file and
// the field. Internal to the vision sources.
#pragma once

#include <string>

#include <opencv2/core.hpp>
#include <opencv2/core/persistence.hpp>

namespace omniloc::detail {

/// Opens a JSON file, throwing std::runtime_error naming it when missing or malformed.
cv::FileStorage open_json(const std::string& path);

/// A number at node[key]; throws "<context>: field '<key>' ..." if missing or not numeric.
double read_number(const cv::FileNode& node, const std::string& key, const std::string& context);

/// Like read_number but the value must be finite and > 0 (or >= 0 when allow_zero).
double read_positive(const cv::FileNode& node, const std::string& key, const std::string& context,
                     bool allow_zero = false);

/// A 2-element numeric sequence [a, b].
void read_pair(const cv::FileNode& node, const std::string& context, double& a, double& b);

}  // namespace omniloc::detail
