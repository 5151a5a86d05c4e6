// The daemon's live view (docs/DAEMON.md "Live view"), shared by omnilocd and omnilocd-sim: with
// `http_port` > 0 a LiveState fed by the daemon's own observer callbacks and a LiveViewServer on
// http_address:http_port serving it (live_view.hpp).
#pragma once

#include <memory>
#include <string>

#include "omniloc/daemon.hpp"
#include "omniloc/daemon_config.hpp"
#include "omniloc/live_view.hpp"
#include "omniloc/log.hpp"

namespace omniloc::cli {

class LiveViewAttachment {
 public:
  /// Nothing when config.http_port is 0; else the server, listening, or std::runtime_error saying
  /// why not (port in use, a build without cpp-httplib). `models` must outlive the attachment.
  LiveViewAttachment(const daemon::DaemonConfig& config, const daemon::DaemonModels& models,
                     const Logger& log) {
    if (config.http_port == 0) return;
    live::LiveViewOptions o;
    o.address = config.http_address;
    o.port = config.http_port;
    state_ = std::make_unique<live::LiveState>(models, o);
    server_ = std::make_unique<live::LiveViewServer>(*state_, o);
    log.info("live view on http://" + o.address + ":" + std::to_string(server_->port()) + "/");
  }

  /// Chains the live view onto `observer`'s on_pose, on_frame and on_status (any callbacks there
  /// still run first).
  void attach(daemon::DaemonObserver& observer) {
    if (state_) state_->attach(observer);
  }

 private:
  std::unique_ptr<live::LiveState> state_;
  std::unique_ptr<live::LiveViewServer> server_;
};

}  // namespace omniloc::cli
