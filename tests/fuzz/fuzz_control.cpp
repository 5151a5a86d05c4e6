// Harness: omnilocd's control-channel request parser (control.hpp parse_request) on any datagram.
// A request it accepts must hold what the header promises (finite numbers within their limits, a
// known side, a non-empty record dir); a ControlError is the only error, and its reply, like an
// ok reply, must be one JSON object that echoes the id.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>

#include <nlohmann/json.hpp>

#include "fuzz_common.hpp"
#include "omniloc/control.hpp"

namespace {

using omniloc::fuzz::fuzz_check;
namespace control = omniloc::control;

void check_reply(const std::string& reply, std::optional<std::int64_t> id, bool ok) {
  const auto j = nlohmann::json::parse(reply, nullptr, /*allow_exceptions=*/false);
  fuzz_check(j.is_object(), "a reply is not a JSON object");
  fuzz_check(j.contains("id") && j.contains("ok") && j["ok"] == ok, "a reply lacks id or ok");
  if (id) {
    fuzz_check(j["id"].is_number_integer() && j["id"].get<std::int64_t>() == *id,
               "a reply does not echo the id");
  } else {
    fuzz_check(j["id"].is_null(), "a reply to a request without a readable id has an id");
  }
  if (!ok)
    fuzz_check(j.contains("error") && j["error"].is_string(), "an error reply has no error text");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view datagram(reinterpret_cast<const char*>(data), size);
  try {
    const control::Request q = control::parse_request(datagram);
    fuzz_check(size <= control::kMaxRequestBytes,
               "a request larger than kMaxRequestBytes was accepted");
    if (const auto* p = std::get_if<control::SetPose>(&q.command)) {
      fuzz_check(std::isfinite(p->x_cm) && std::fabs(p->x_cm) <= 10000.0,
                 "set_pose x_cm out of its limits");
      fuzz_check(std::isfinite(p->y_cm) && std::fabs(p->y_cm) <= 10000.0,
                 "set_pose y_cm out of its limits");
      fuzz_check(std::isfinite(p->yaw_deg) && std::fabs(p->yaw_deg) <= 360.0,
                 "set_pose yaw_deg out of its limits");
    } else if (const auto* s = std::get_if<control::SetSide>(&q.command)) {
      fuzz_check(s->side == "blue" || s->side == "yellow", "set_side accepted another side");
    } else if (const auto* r = std::get_if<control::RecordStart>(&q.command)) {
      fuzz_check(!r->dir.empty(), "record start accepted an empty dir");
    }
    fuzz_check(!control::command_name(q.command).empty(), "a command without a name");
    check_reply(control::ok_reply(q.id, {{"cmd", std::string(control::command_name(q.command))}}),
                q.id, true);
  } catch (const control::ControlError& e) {
    fuzz_check(e.what()[0] != '\0', "a ControlError without a message");
    check_reply(control::error_reply(e.id(), e.what()), e.id(), false);
  }
  return 0;
}
