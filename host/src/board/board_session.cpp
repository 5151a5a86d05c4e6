// The board conversation of one session: identify, configure, stream (board_session.hpp).
#include "omniloc/board_session.hpp"

#include <cstdio>
#include <utility>

#include "omniloc/regmap.hpp"

namespace omniloc {

std::string BoardIdentity::version_text() const {
  return std::to_string(regmap::kVersionMajor.get(version)) + "." +
         std::to_string(regmap::kVersionMinor.get(version)) + "." +
         std::to_string(regmap::kVersionPatch.get(version));
}

namespace {
std::string hex32(std::uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%08X", v);
  return buf;
}
}  // namespace

bool version_differs(const BoardIdentity& identity) {
  return identity.version != regmap::kVersionValue;
}

bool version_compatible(std::uint32_t board, std::uint32_t host) {
  // Semantic versioning: the major version, and below 1.0 the minor one too, changes the layout.
  const auto major = [](std::uint32_t v) { return regmap::kVersionMajor.get(v); };
  const auto minor = [](std::uint32_t v) { return regmap::kVersionMinor.get(v); };
  return major(board) == major(host) && (major(host) != 0 || minor(board) == minor(host));
}

std::uint32_t control_decode_for(int decoding) {
  switch (decoding) {
    case 1:
      return regmap::kControlDecodeX1;
    case 2:
      return regmap::kControlDecodeX2;
    case 4:
      return regmap::kControlDecodeX4;
    default:
      throw std::invalid_argument("quadrature decoding must be 1, 2 or 4 (got " +
                                  std::to_string(decoding) + ")");
  }
}

BoardIdentity identify_board(BoardClient& client, const std::string& where) {
  BoardIdentity b;
  b.id = client.read_register(regmap::kRegId);
  if (b.id != regmap::kIdValue) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s: register ID reads 0x%08X, not 0x%08X: not an omniloc board",
                  where.c_str(), b.id, regmap::kIdValue);
    throw BoardIdentityError(buf);
  }
  b.version = client.read_register(regmap::kRegVersion);
  if (!version_compatible(b.version, regmap::kVersionValue)) {
    BoardIdentity host;
    host.version = regmap::kVersionValue;
    throw BoardIdentityError(where + ": the board's register map is version " + b.version_text() +
                             ", this host speaks " + host.version_text() +
                             " (the window layout differs): load the bitstream of this host's "
                             "version, or the host of the board's");
  }
  // CONFIG.CHANNELS: the wheels the bitstream was built for (rtl/encoder_core.v CHANNELS).
  const std::uint32_t config = client.read_register(regmap::kRegConfig);
  b.channels = static_cast<int>(regmap::kConfigChannels.get(config));
  if (b.channels < 3 || b.channels > regmap::kChannels) {
    throw BoardIdentityError(where + ": register CONFIG reads 0x" + hex32(config) + ": CHANNELS " +
                             std::to_string(b.channels) + " is not 3 or " +
                             std::to_string(regmap::kChannels) +
                             " (a damaged or foreign bitstream)");
  }
  b.control = client.read_register(regmap::kRegControl);
  // PERIOD counts board cycles per window; nothing on the host writes it, so it holds its reset
  // value clock / TICK_HZ, which gives the board's clock (what the timestamps count).
  b.period_cycles = client.read_register(regmap::kRegPeriod);
  b.clock_hz = static_cast<double>(b.period_cycles) * regmap::kTickHz;
  return b;
}

EncoderWindow SessionWindow::to_encoder_window(double offset_ms) const {
  EncoderWindow w;
  w.seq = raw.seq;
  w.t_end_ms = offset_ms + board_ms;
  for (std::size_t i = 0; i < w.counts.size() && i < raw.count.size(); ++i)
    w.counts[i] = raw.count[i];
  // The gyro's window, latched at the same capture as the counts (a v0.2 board always has the
  // fields).
  w.gyro.present = true;
  w.gyro.sum_lsb = raw.gyro_sum;
  w.gyro.samples = raw.gyro_count;
  w.gyro.flags = raw.gyro_flags;
  return w;
}

BoardSession::BoardSession(std::unique_ptr<Transport> transport, const BoardSessionOptions& options)
    : transport_(std::move(transport)) {
  if (!transport_) throw std::invalid_argument("BoardSession: no transport");
  client_ = std::make_unique<BoardClient>(*transport_, options.client);
  identity_ = identify_board(*client_, describe());
  // A robot's wheels must match the board's encoder channels (robot_config.hpp).
  if (options.wheels != 0)
    if (auto why = board_channel_mismatch(identity_.channels, options.wheels))
      throw BoardIdentityError(describe() + ": " + *why);
  if (options.configure) {
    std::uint32_t control = 0;
    control = regmap::kControlEnable.put(control, 1);
    control = regmap::kControlDecode.put(control, control_decode_for(options.decoding));
    control = regmap::kControlStream.put(control, 1);
    client_->write_register(regmap::kRegControl, control);
  }
}

BoardSession::~BoardSession() = default;

std::optional<SessionWindow> BoardSession::next_window(std::chrono::milliseconds timeout) {
  const auto w = client_->poll_telemetry(timeout);
  if (!w) return std::nullopt;
  if (!unwrap_) unwrap_.emplace(identity_.clock_hz);
  unwrap_->update(w->timestamp_cycles);
  return SessionWindow{*w, unwrap_->elapsed_ms()};
}

std::optional<std::string> BoardSession::stop_streaming() noexcept {
  try {
    client_->set_streaming(false);
    return std::nullopt;
  } catch (const std::exception& e) {
    return std::string(e.what());
  }
}

}  // namespace omniloc
