// The control channel's requests and replies (control.hpp), each error case by name.
#include <gtest/gtest.h>

#include <string>

#include <nlohmann/json.hpp>

#include "omniloc/control.hpp"

namespace omniloc::control {
namespace {

TEST(ControlRequest, EveryCommandReadsItsFields) {
  EXPECT_TRUE(
      std::holds_alternative<Status>(parse_request(R"({"id": 1, "cmd": "status"})").command));
  const Request p =
      parse_request(R"({"id": 2, "cmd": "set_pose", "x_cm": 375, "y_cm": -20.5, "yaw_deg": -90})");
  ASSERT_EQ(p.id, 2);
  const auto& sp = std::get<SetPose>(p.command);
  EXPECT_EQ(sp.x_cm, 375.0);
  EXPECT_EQ(sp.y_cm, -20.5);
  EXPECT_EQ(sp.yaw_deg, -90.0);
  EXPECT_EQ(
      std::get<SetSide>(parse_request(R"({"cmd": "set_side", "side": "yellow"})").command).side,
      "yellow");
  EXPECT_TRUE(std::holds_alternative<Relocalize>(
      parse_request(R"({"id": 3, "cmd": "relocalize"})").command));
  EXPECT_EQ(std::get<RecordStart>(
                parse_request(R"({"cmd": "record", "action": "start", "dir": "/d"})").command)
                .dir,
            "/d");
  EXPECT_TRUE(std::holds_alternative<RecordStop>(
      parse_request(R"({"cmd": "record", "action": "stop"})").command));
  EXPECT_FALSE(parse_request(R"({"cmd": "status"})").id.has_value());
  EXPECT_FALSE(parse_request(R"({"id": null, "cmd": "status"})").id.has_value());
}

struct Bad {
  std::string request;
  std::optional<std::int64_t> id;  // the id the error reply must carry
  std::string says;
};

// Each request refused by parse_request with an error that says `says` and carries `id`.
void expect_refused(const std::vector<Bad>& cases) {
  for (const Bad& c : cases) {
    try {
      (void)parse_request(c.request);
      ADD_FAILURE() << "accepted: " << c.request;
    } catch (const ControlError& e) {
      EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos)
          << c.request << " -> " << e.what();
      EXPECT_EQ(e.id(), c.id) << c.request;
    }
  }
}

TEST(ControlRequest, BadRequestsSayWhatIsWrong) {
  const std::vector<Bad> cases = {
      {"", std::nullopt, "not valid JSON"},
      {"{\"cmd\": \"status\"", std::nullopt, "not valid JSON"},
      {"[1]", std::nullopt, "must be a JSON object (got array)"},
      {R"({"id": 1.5, "cmd": "status"})", std::nullopt, "field 'id' must be an integer (got 1.5)"},
      {R"({"id": "7", "cmd": "status"})", std::nullopt,
       "field 'id' must be an integer (got \"7\")"},
      {R"({"id": 18446744073709551615, "cmd": "status"})", std::nullopt,
       "field 'id' is out of range"},
      {R"({"id": 4})", 4, "missing field 'cmd'"},
      {R"({"id": 4, "cmd": 9})", 4, "field 'cmd' must be a string (got 9)"},
      {R"({"id": 4, "cmd": "fly"})", 4,
       "unknown cmd 'fly' (record, relocalize, set_pose, set_side, status)"},
      {R"({"id": 5, "cmd": "status", "verbose": true})", 5, "status: unknown field 'verbose'"},
      {R"({"id": 6, "cmd": "set_pose", "x_cm": 1, "y_cm": 2})", 6,
       "set_pose: missing field 'yaw_deg'"},
      {R"({"id": 6, "cmd": "set_pose", "x_cm": "1", "y_cm": 2, "yaw_deg": 0})", 6,
       "set_pose: field 'x_cm' must be a number (got \"1\")"},
      {R"({"id": 6, "cmd": "set_pose", "x_cm": 1e9, "y_cm": 2, "yaw_deg": 0})", 6,
       "field 'x_cm' must be within +-10000"},
      {R"({"id": 6, "cmd": "set_pose", "x_cm": 1, "y_cm": 2, "yaw_deg": 400})", 6,
       "field 'yaw_deg' must be within +-360"},
      {R"({"id": 6, "cmd": "set_pose", "x_cm": 1e999, "y_cm": 2, "yaw_deg": 0})", std::nullopt,
       "not valid JSON"},
      {R"({"id": 7, "cmd": "set_side", "side": "red"})", 7,
       "set_side: field 'side' must be \"blue\" or \"yellow\" (got \"red\")"},
      {R"({"id": 8, "cmd": "record"})", 8, "record: missing field 'action'"},
      {R"({"id": 8, "cmd": "record", "action": "pause"})", 8,
       "record: field 'action' must be \"start\" or \"stop\""},
      {R"({"id": 8, "cmd": "record", "action": "start"})", 8, "record: missing field 'dir'"},
      {R"({"id": 8, "cmd": "record", "action": "start", "dir": ""})", 8,
       "field 'dir' must not be empty"},
      {R"({"id": 8, "cmd": "record", "action": "stop", "dir": "/d"})", 8,
       "'dir' is for action \"start\" only"},
      {std::string(kMaxRequestBytes + 1, ' '), std::nullopt, "bytes is larger than 4096"},
  };
  expect_refused(cases);
}

// Issue (hostile input): a key given twice was accepted, the last value winning, while every file
// reader refuses it (config::parse_json_text). The channel refuses it with the readers' message,
// naming the key and where it is; the id is echoed unless it is the key given twice.
TEST(ControlRequest, DuplicateKeysAreRefusedLikeTheFileReaders) {
  const std::vector<Bad> cases = {
      {R"({"id": 6, "cmd": "set_pose", "x_cm": 1, "x_cm": 900, "y_cm": 2, "yaw_deg": 0})", 6,
       "request:x_cm: duplicate key: an object may give a key only once (got \"x_cm\" a second "
       "time)"},
      {R"({"id": 6, "cmd": "set_pose", "x_cm": 1, "y_cm": 2, "yaw_deg": 0, "yaw_deg": 90})", 6,
       "request:yaw_deg: duplicate key"},
      {R"({"id": 6, "cmd": "status", "cmd": "set_pose", "x_cm": 1, "y_cm": 2, "yaw_deg": 0})", 6,
       "request:cmd: duplicate key"},
      {R"({"id": 6, "id": 7, "cmd": "status"})", std::nullopt, "request:id: duplicate key"},
      {R"({"id": 9, "cmd": "set_side", "side": "blue", "side": "yellow"})", 9,
       "request:side: duplicate key"},
  };
  expect_refused(cases);
  // The same keys once each are still fine.
  EXPECT_NO_THROW((void)parse_request(R"({"id": 6, "cmd": "set_pose", "x_cm": 1, "y_cm": 2,
                                          "yaw_deg": 0})"));
}

TEST(ControlReply, OneLineJsonWithTheIdEchoed) {
  const auto ok = nlohmann::json::parse(ok_reply(12, {{"x_cm", 1.5}}));
  EXPECT_EQ(ok, nlohmann::json::parse(R"({"id": 12, "ok": true, "x_cm": 1.5})"));
  const std::string err = error_reply(std::nullopt, "set_pose: \"quoted\"\nand a newline");
  EXPECT_EQ(err.find('\n'), std::string::npos) << "one datagram, one line";
  EXPECT_EQ(nlohmann::json::parse(err),
            nlohmann::json::parse(
                R"({"id": null, "ok": false, "error": "set_pose: \"quoted\"\nand a newline"})"));
  // A file name that is not UTF-8 does not make the reply unwritable.
  const auto bad_utf8 = nlohmann::json::parse(error_reply(1, std::string("record: /tmp/\xff")));
  EXPECT_EQ(bad_utf8["ok"], false);
}

}  // namespace
}  // namespace omniloc::control
