#include "json_read.hpp"

#include <cmath>
#include <filesystem>
#include <stdexcept>

namespace omniloc::detail {

cv::FileStorage open_json(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) {
    throw std::runtime_error(path + ": file does not exist");
  }
  cv::FileStorage fs;
  try {
    if (!fs.open(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_JSON)) {
      throw std::runtime_error(path + ": cannot be opened as JSON");
    }
  } catch (const cv::Exception& e) {
    throw std::runtime_error(path + ": malformed JSON (" + e.msg + ")");
  }
  return fs;
}

double read_number(const cv::FileNode& node, const std::string& key, const std::string& context) {
  const cv::FileNode v = node[key];
  if (v.empty() || v.isNone()) throw std::runtime_error(context + ": missing field '" + key + "'");
  if (!v.isReal() && !v.isInt()) throw std::runtime_error(context + ": field '" + key + "' is not a number");
  const double x = v.real();
  if (!std::isfinite(x)) throw std::runtime_error(context + ": field '" + key + "' is not finite");
  return x;
}

double read_positive(const cv::FileNode& node, const std::string& key, const std::string& context,
                     bool allow_zero) {
  const double x = read_number(node, key, context);
  if (allow_zero ? x < 0.0 : x <= 0.0) {
    throw std::runtime_error(context + ": field '" + key + "' must be " + (allow_zero ? ">= 0" : "> 0") +
                             " (got " + std::to_string(x) + ")");
  }
  return x;
}

void read_pair(const cv::FileNode& node, const std::string& context, double& a, double& b) {
  if (!node.isSeq() || node.size() != 2 || !(node[0].isReal() || node[0].isInt()) ||
      !(node[1].isReal() || node[1].isInt())) {
    throw std::runtime_error(context + ": expected a pair of numbers [a, b]");
  }
  a = node[0].real();
  b = node[1].real();
  if (!std::isfinite(a) || !std::isfinite(b)) throw std::runtime_error(context + ": values must be finite");
}

}  // namespace omniloc::detail
