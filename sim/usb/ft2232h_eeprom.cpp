#include "omniloc_sim/ft2232h_eeprom.hpp"

#include <fstream>
#include <map>
#include <stdexcept>

namespace omniloc::sim {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

/// The line without its comment: a '#' outside a quoted string starts one.
std::string strip_comment(const std::string& line) {
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    if (line[i] == '"') quoted = !quoted;
    if (line[i] == '#' && !quoted) return line.substr(0, i);
  }
  return line;
}

}  // namespace

EepromIdentity read_eeprom_identity(const std::filesystem::path& conf) {
  std::ifstream in(conf);
  if (!in) throw std::runtime_error(conf.string() + ": cannot open the EEPROM configuration");
  const std::string file = conf.string();
  std::map<std::string, std::pair<std::string, int>> values;  // key -> (value, line)
  std::string raw;
  for (int line_no = 1; std::getline(in, raw); ++line_no) {
    const std::string line = trim(strip_comment(raw));
    if (line.empty()) continue;
    const auto eq = line.find('=');
    const std::string where = file + ":" + std::to_string(line_no) + ": ";
    if (eq == std::string::npos || trim(line.substr(0, eq)).empty())
      throw std::runtime_error(where + "expected key=value, got '" + line + "'");
    std::string value = trim(line.substr(eq + 1));
    if (!value.empty() && value.front() == '"') {
      if (value.size() < 2 || value.back() != '"')
        throw std::runtime_error(where + "unterminated string in '" + line + "'");
      value = value.substr(1, value.size() - 2);
    }
    const std::string key = trim(line.substr(0, eq));
    if (const auto seen = values.find(key); seen != values.end())
      throw std::runtime_error(where + "'" + key + "' given again (first on line " +
                               std::to_string(seen->second.second) + ")");
    values[key] = {value, line_no};
  }
  auto get = [&](const std::string& key) -> const std::pair<std::string, int>& {
    const auto it = values.find(key);
    if (it == values.end()) throw std::runtime_error(file + ": no '" + key + "' key");
    return it->second;
  };
  auto id16 = [&](const std::string& key) {
    const auto& [text, line_no] = get(key);
    std::size_t used = 0;
    unsigned long v = 0;
    try {
      v = std::stoul(text, &used, 0);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != text.size() || v > 0xFFFF)
      throw std::runtime_error(file + ":" + std::to_string(line_no) + ": " + key + " '" + text +
                               "' is not a 16-bit number");
    return static_cast<std::uint16_t>(v);
  };
  EepromIdentity id;
  id.vendor_id = id16("vendor_id");
  id.product_id = id16("product_id");
  id.manufacturer = get("manufacturer").first;
  id.product = get("product").first;
  id.serial = get("serial").first;
  id.channel_b_type = get("chb_type").first;
  return id;
}

}  // namespace omniloc::sim
