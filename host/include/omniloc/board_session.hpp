// One session with the omniloc encoder board over any Transport: identify it (ID and register-map
// version), configure it for the robot (CONTROL: enable, the robot's quadrature decoding,
// streaming), learn its clock from PERIOD, and hand out streamed windows with unwrapped timestamps.
// The daemon, the simulated robot and `omniloc probe` all talk to the board through this one class,
// so there is one place that knows the order of that conversation.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "omniloc/board_client.hpp"
#include "omniloc/odometry.hpp"
#include "omniloc/protocol.hpp"
#include "omniloc/regmap.hpp"
#include "omniloc/transport.hpp"

namespace omniloc {

/// The board answered, but it is not a board this host can use: the ID register does not read
/// "OMNL", or its register map has another major version. Retrying does not help.
class BoardIdentityError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What the board says about itself, read once at the start of a session.
struct BoardIdentity {
  std::uint32_t id = 0;
  std::uint32_t version = 0;        ///< register-map version, regmap::kVersion* fields
  std::uint32_t control = 0;        ///< CONTROL as found (before the session configured it)
  std::uint32_t period_cycles = 0;  ///< PERIOD: board cycles per window
  double clock_hz = 0.0;  ///< board clock derived from PERIOD and the robot's window period
  /// CONFIG.CHANNELS: encoder channels the board counts (3 or 4)
  int channels = regmap::kChannels;

  [[nodiscard]] std::string version_text() const;  ///< "1.0.0"
};

/// Reads ID, VERSION, CONFIG, CONTROL and PERIOD; throws BoardIdentityError naming the transport
/// and both versions when the ID is wrong or the register map is not version_compatible with the
/// host's (a patch difference, or a minor one from 1.0 on, is accepted: the host checks
/// `version_differs()` to warn), or when CONFIG.CHANNELS is not 3 or 4.
/// The clock is PERIOD's reset value times the register map's tick rate (PERIOD = clock / TICK_HZ).
[[nodiscard]] BoardIdentity identify_board(BoardClient& client, const std::string& where);

/// True if a board of register-map version `board` can serve a host of version `host`: the same
/// major version and, before 1.0 (where every minor version may change the layout), the same minor.
[[nodiscard]] bool version_compatible(std::uint32_t board, std::uint32_t host);

/// True if the board's register-map version is not exactly the host's (any field).
[[nodiscard]] bool version_differs(const BoardIdentity& identity);

/// regmap CONTROL.DECODE value for a decoding multiplier 1, 2 or 4; throws std::invalid_argument
/// otherwise.
[[nodiscard]] std::uint32_t control_decode_for(int decoding);

struct BoardSessionOptions {
  int decoding = 4;       ///< the robot's quadrature decoding (robot config)
  bool configure = true;  ///< write CONTROL (enable, decoding, streaming) at open
  int wheels = 0;         ///< the robot's wheel count (wheel_count); 0 = not checked
  BoardClientOptions client;
};

/// A streamed window with its board time: milliseconds since the first window of this session,
/// from the unwrapped 32-bit cycle counter.
struct SessionWindow {
  protocol::Window raw;
  double board_ms = 0.0;

  /// The window as the odometry takes it: counts in the robot's decoding, the gyro's raw window,
  /// t_end_ms = board_ms + offset_ms, gyro_yaw_deg left 0 (the caller adds the heading).
  [[nodiscard]] EncoderWindow to_encoder_window(double offset_ms) const;
};

class BoardSession {
 public:
  /// Opens a session on `transport` (the session owns it): identify, then, if options.configure,
  /// CONTROL = enable | decode | stream. Throws BoardIdentityError, BoardError or TransportError.
  BoardSession(std::unique_ptr<Transport> transport, const BoardSessionOptions& options);
  ~BoardSession();
  BoardSession(const BoardSession&) = delete;
  BoardSession& operator=(const BoardSession&) = delete;

  [[nodiscard]] const BoardIdentity& identity() const { return identity_; }
  /// The next streamed window, waiting up to `timeout`; nullopt on timeout. Throws TransportError
  /// when the device is gone.
  [[nodiscard]] std::optional<SessionWindow> next_window(std::chrono::milliseconds timeout);
  /// Clears CONTROL.STREAM (best effort on the way out: errors are reported, not thrown).
  [[nodiscard]] std::optional<std::string> stop_streaming() noexcept;

  [[nodiscard]] BoardClient& client() { return *client_; }
  [[nodiscard]] Transport& transport() { return *transport_; }
  [[nodiscard]] std::string describe() const { return transport_->status().description; }

 private:
  std::unique_ptr<Transport> transport_;
  std::unique_ptr<BoardClient> client_;
  BoardIdentity identity_;
  std::optional<protocol::TimestampUnwrapper> unwrap_;
};

}  // namespace omniloc
