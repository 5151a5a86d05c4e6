// The live view in a build without cpp-httplib (host/src/live_view/live_view_absent.cpp, compiled
// into this test whatever the build has): the server refuses to start, saying what to install and
// naming the port, while the state (and its JSON) works as in any build.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "omniloc/camera.hpp"
#include "omniloc/field.hpp"
#include "omniloc/live_view.hpp"
#include "omniloc/localizer.hpp"

namespace {

using namespace omniloc;

TEST(LiveViewWithoutHttplib, TheServerRefusesToStartSayingWhy) {
  daemon::DaemonModels m;
  m.field = load_field("fira-robosot");
  m.camera = load_camera("default");
  m.localizer = load_localizer_config("default");
  live::LiveState state(m);
  EXPECT_FALSE(live::LiveViewServer::available());
  live::LiveViewOptions o;
  o.port = 8080;
  try {
    live::LiveViewServer server(state, o);
    ADD_FAILURE() << "a server started in a build without cpp-httplib";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    std::printf("%s\n", what.c_str());
    EXPECT_NE(what.find("http_port 8080"), std::string::npos) << what;
    EXPECT_NE(what.find("libcpp-httplib-dev"), std::string::npos) << what;
  }
  EXPECT_EQ(nlohmann::json::parse(state.field_json())["total_x_cm"], 750.0);
}

}  // namespace
