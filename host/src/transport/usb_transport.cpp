// UsbTransport: libusb-1.0 straight onto the FT2232H's channel B.
//
// Threads: one event thread per transport runs libusb's event loop; it completes the bulk-IN
// transfers, strips the status bytes and appends the payload to rx_ under mu_. read() waits on cv_.
// write() is a synchronous bulk transfer on the caller's thread (libusb lets a synchronous transfer
// share the event loop with another thread).
#include "omniloc/usb_transport.hpp"

#include <libusb.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <mutex>
#include <thread>

namespace omniloc {

namespace {

std::string usb_error(int rc) {
  return std::string(libusb_error_name(rc));
}

[[noreturn]] void fail(int rc, const std::string& what) {
  const auto kind =
      rc == LIBUSB_ERROR_NO_DEVICE ? TransportErrorKind::kDeviceGone : TransportErrorKind::kConfig;
  throw TransportError(kind, what + ": " + usb_error(rc));
}

std::string string_descriptor(libusb_device_handle* h, std::uint8_t index, std::string& error) {
  if (index == 0) return {};
  unsigned char buf[256];
  const int n = libusb_get_string_descriptor_ascii(h, index, buf, sizeof buf);
  if (n < 0) {
    error = "string descriptor " + std::to_string(index) + ": " + usb_error(n);
    return {};
  }
  return std::string(reinterpret_cast<const char*>(buf), static_cast<std::size_t>(n));
}

/// Owns a libusb context: no process-wide state, each transport (and each search) has its own.
struct Context {
  Context() {
    const int rc = libusb_init(&ctx);
    if (rc < 0) fail(rc, "libusb_init");
  }
  ~Context() { libusb_exit(ctx); }
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  libusb_context* ctx = nullptr;
};

struct DeviceList {
  explicit DeviceList(libusb_context* ctx) {
    n = libusb_get_device_list(ctx, &list);
    if (n < 0) fail(static_cast<int>(n), "libusb_get_device_list");
  }
  ~DeviceList() { libusb_free_device_list(list, 1); }
  DeviceList(const DeviceList&) = delete;
  DeviceList& operator=(const DeviceList&) = delete;
  libusb_device** list = nullptr;
  ssize_t n = 0;
};

bool is_ft2232h(libusb_device* dev) {
  libusb_device_descriptor d{};
  return libusb_get_device_descriptor(dev, &d) == 0 && d.idVendor == ftdi::kVid &&
         d.idProduct == ftdi::kPidFt2232h;
}

/// Reads a device's strings; returns the open handle when keep is set and opening worked.
UsbBoardInfo describe(libusb_device* dev, const std::string& product, libusb_device_handle** keep) {
  UsbBoardInfo info;
  info.bus = libusb_get_bus_number(dev);
  info.address = libusb_get_device_address(dev);
  libusb_device_descriptor d{};
  libusb_get_device_descriptor(dev, &d);
  libusb_device_handle* h = nullptr;
  const int rc = libusb_open(dev, &h);
  if (rc < 0) {
    info.error = "libusb_open: " + usb_error(rc);
    return info;
  }
  info.manufacturer = string_descriptor(h, d.iManufacturer, info.error);
  info.product = string_descriptor(h, d.iProduct, info.error);
  info.serial = string_descriptor(h, d.iSerialNumber, info.error);
  info.is_omniloc = info.product == product;
  if (keep) {
    *keep = h;
  } else {
    libusb_close(h);
  }
  return info;
}

}  // namespace

std::vector<UsbBoardInfo> find_usb_boards(const std::string& product) {
  Context c;
  DeviceList devs(c.ctx);
  std::vector<UsbBoardInfo> out;
  for (ssize_t i = 0; i < devs.n; ++i) {
    if (is_ft2232h(devs.list[i])) out.push_back(describe(devs.list[i], product, nullptr));
  }
  return out;
}

struct UsbTransport::Impl {
  UsbTransportOptions opt;
  Context context;
  libusb_device_handle* handle = nullptr;
  bool claimed = false;
  bool detached_driver = false;
  UsbBoardInfo info;
  ftdi::BaudSetting baud;
  int packet_bytes = 512;

  mutable std::mutex mu;
  std::condition_variable cv;
  std::deque<std::uint8_t> rx;
  TransportCounters counters;
  bool gone = false;
  std::string io_error;  ///< a bulk-IN failure other than unplug, reported by the next read
  int in_flight = 0;
  bool stopping = false;

  std::vector<libusb_transfer*> transfers;
  std::vector<std::vector<unsigned char>> buffers;
  std::atomic<bool> run_events{true};
  std::thread events;

  std::string where() const {
    char buf[96];
    std::snprintf(buf, sizeof buf, "FT2232H %03d/%03d serial '%s' channel B", info.bus,
                  info.address, info.serial.c_str());
    return buf;
  }

  void open() {
    DeviceList devs(context.ctx);
    std::vector<std::string> seen;
    for (ssize_t i = 0; i < devs.n && !handle; ++i) {
      if (!is_ft2232h(devs.list[i])) continue;
      libusb_device_handle* h = nullptr;
      auto d = describe(devs.list[i], opt.product, &h);
      const bool match = d.is_omniloc && (opt.serial.empty() || d.serial == opt.serial);
      if (match && h) {
        handle = h;
        info = d;
        packet_bytes = libusb_get_max_packet_size(devs.list[i], ftdi::kEpInB);
        if (packet_bytes <= 2) packet_bytes = 512;
      } else {
        if (h) libusb_close(h);
        seen.push_back("'" + d.product + "' serial '" + d.serial + "'" +
                       (d.error.empty() ? "" : " (" + d.error + ")"));
      }
    }
    if (!handle) {
      std::string msg = "no FT2232H 0403:6010 with product '" + opt.product + "'" +
                        (opt.serial.empty() ? "" : " and serial '" + opt.serial + "'") + " found";
      if (!seen.empty()) {
        msg += "; FT2232H devices seen:";
        for (const auto& s : seen) msg += " " + s;
      }
      throw TransportError(TransportErrorKind::kNotFound, msg);
    }
  }

  void control(std::uint8_t request, std::uint16_t value, std::uint16_t index, const char* what) {
    const int rc =
        libusb_control_transfer(handle, ftdi::kRequestTypeOut, request, value, index, nullptr, 0,
                                static_cast<unsigned>(opt.io_timeout.count()));
    if (rc < 0) fail(rc, where() + ": " + what);
  }

  void configure() {
    // The kernel's ftdi_sio binds channel B as /dev/ttyUSBn: take the interface from it.
    const int active = libusb_kernel_driver_active(handle, ftdi::kInterfaceB);
    if (active == 1) {
      const int rc = libusb_detach_kernel_driver(handle, ftdi::kInterfaceB);
      if (rc < 0) fail(rc, where() + ": detach kernel driver");
      detached_driver = true;
    } else if (active < 0 && active != LIBUSB_ERROR_NOT_SUPPORTED) {
      fail(active, where() + ": query kernel driver");
    }
    int rc = libusb_claim_interface(handle, ftdi::kInterfaceB);
    if (rc < 0) fail(rc, where() + ": claim interface 1");
    claimed = true;
    baud = ftdi::h_series_baud(opt.baud, ftdi::kPortB);
    control(ftdi::kReqReset, ftdi::kResetSio, ftdi::kPortB, "reset");
    control(ftdi::kReqSetBitmode, 0x0000, ftdi::kPortB, "set bitmode reset (UART)");
    control(ftdi::kReqSetBaudRate, baud.value, baud.index, "set baud rate");
    control(ftdi::kReqSetData, ftdi::kData8N1, ftdi::kPortB, "set 8N1");
    control(ftdi::kReqSetFlowCtrl, 0, ftdi::kPortB, "disable flow control");
    control(ftdi::kReqSetLatencyTimer, opt.latency_ms, ftdi::kPortB, "set latency timer");
    control(ftdi::kReqReset, ftdi::kResetPurgeRx, ftdi::kPortB, "purge RX");
    control(ftdi::kReqReset, ftdi::kResetPurgeTx, ftdi::kPortB, "purge TX");
  }

  static void LIBUSB_CALL on_in(libusb_transfer* t) {
    static_cast<Impl*>(t->user_data)->completed(t);
  }

  void completed(libusb_transfer* t) {
    std::unique_lock lock(mu);
    if (t->status == LIBUSB_TRANSFER_COMPLETED) {
      // Each packet starts with [modem status, line status]; a transfer carries several packets.
      for (int off = 0; off < t->actual_length; off += packet_bytes) {
        const int end = std::min(off + packet_bytes, t->actual_length);
        ++counters.packets_in;
        if (end - off < 2) continue;
        const std::uint8_t line = t->buffer[off + 1];
        counters.line_overrun += (line & ftdi::kLineOverrun) ? 1 : 0;
        counters.line_parity += (line & ftdi::kLineParity) ? 1 : 0;
        counters.line_framing += (line & ftdi::kLineFraming) ? 1 : 0;
        counters.line_break += (line & ftdi::kLineBreak) ? 1 : 0;
        for (int i = off + 2; i < end; ++i) {
          if (rx.size() >= opt.rx_buffer_bytes) {
            ++counters.rx_dropped_bytes;
          } else {
            rx.push_back(t->buffer[i]);
          }
        }
        counters.bytes_read += static_cast<std::uint64_t>(end - off - 2);
      }
    } else if (t->status == LIBUSB_TRANSFER_NO_DEVICE) {
      gone = true;
    } else if (t->status != LIBUSB_TRANSFER_CANCELLED) {
      io_error =
          where() + ": bulk IN transfer status " + std::to_string(static_cast<int>(t->status));
    }
    const bool resubmit = !stopping && !gone && t->status != LIBUSB_TRANSFER_CANCELLED;
    if (resubmit) {
      const int rc = libusb_submit_transfer(t);
      if (rc == 0) {
        cv.notify_all();
        return;
      }
      if (rc == LIBUSB_ERROR_NO_DEVICE) {
        gone = true;
      } else {
        io_error = where() + ": resubmit bulk IN: " + usb_error(rc);
      }
    }
    --in_flight;
    cv.notify_all();
  }

  void start_streaming() {
    for (int i = 0; i < opt.in_transfers; ++i) {
      buffers.emplace_back(static_cast<std::size_t>(opt.in_transfer_bytes));
      libusb_transfer* t = libusb_alloc_transfer(0);
      if (!t)
        throw TransportError(TransportErrorKind::kConfig,
                             where() + ": libusb_alloc_transfer failed");
      transfers.push_back(t);
      libusb_fill_bulk_transfer(t, handle, ftdi::kEpInB, buffers.back().data(),
                                opt.in_transfer_bytes, &Impl::on_in, this, 0);
    }
    events = std::thread([this] {
      while (run_events.load()) {
        timeval tv{0, 100'000};
        libusb_handle_events_timeout_completed(context.ctx, &tv, nullptr);
      }
    });
    for (auto* t : transfers) {
      std::lock_guard lock(mu);
      const int rc = libusb_submit_transfer(t);
      if (rc < 0) fail(rc, where() + ": submit bulk IN");
      ++in_flight;
    }
  }

  void shutdown() {
    {
      std::unique_lock lock(mu);
      stopping = true;
      for (auto* t : transfers) libusb_cancel_transfer(t);  // errors: already completing, fine
      // The event thread delivers the cancellations; never free a transfer it may still touch.
      cv.wait_for(lock, std::chrono::seconds(2), [this] { return in_flight == 0; });
    }
    run_events = false;
    if (events.joinable()) {
      libusb_interrupt_event_handler(context.ctx);
      events.join();
    }
    if (in_flight == 0) {
      for (auto* t : transfers) libusb_free_transfer(t);
    }  // else leak rather than free memory libusb still references
    if (handle) {
      if (claimed) libusb_release_interface(handle, ftdi::kInterfaceB);
      if (detached_driver && !gone) libusb_attach_kernel_driver(handle, ftdi::kInterfaceB);
      libusb_close(handle);
    }
  }
};

UsbTransport::UsbTransport(UsbTransportOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->opt = std::move(options);
  try {
    impl_->open();
    impl_->configure();
    impl_->start_streaming();
  } catch (...) {
    impl_->shutdown();
    throw;
  }
}

UsbTransport::~UsbTransport() {
  impl_->shutdown();
}

void UsbTransport::write(std::span<const std::uint8_t> bytes) {
  auto& d = *impl_;
  std::size_t done = 0;
  while (done < bytes.size()) {
    int sent = 0;
    const int rc = libusb_bulk_transfer(d.handle, ftdi::kEpOutB,
                                        const_cast<unsigned char*>(bytes.data() + done),
                                        static_cast<int>(bytes.size() - done), &sent,
                                        static_cast<unsigned>(d.opt.io_timeout.count()));
    done += static_cast<std::size_t>(std::max(sent, 0));
    std::lock_guard lock(d.mu);
    d.counters.bytes_written += static_cast<std::uint64_t>(std::max(sent, 0));
    if (rc == LIBUSB_ERROR_NO_DEVICE) {
      d.gone = true;
      d.cv.notify_all();
      throw TransportError(TransportErrorKind::kDeviceGone,
                           d.where() + ": unplugged (LIBUSB_ERROR_NO_DEVICE on bulk OUT)");
    }
    if (rc == LIBUSB_ERROR_TIMEOUT) ++d.counters.write_timeouts;
    if (rc < 0) {
      throw TransportError(TransportErrorKind::kIo,
                           d.where() + ": bulk OUT after " + std::to_string(done) + " of " +
                               std::to_string(bytes.size()) + " bytes: " + usb_error(rc));
    }
  }
}

std::size_t UsbTransport::read(std::span<std::uint8_t> out, std::chrono::milliseconds timeout) {
  auto& d = *impl_;
  std::unique_lock lock(d.mu);
  d.cv.wait_for(lock, timeout, [&] { return !d.rx.empty() || d.gone || !d.io_error.empty(); });
  const std::size_t n = std::min(out.size(), d.rx.size());
  std::copy_n(d.rx.begin(), n, out.begin());
  d.rx.erase(d.rx.begin(), d.rx.begin() + static_cast<std::ptrdiff_t>(n));
  if (n > 0) return n;  // deliver what arrived before reporting a failure
  if (d.gone) {
    throw TransportError(TransportErrorKind::kDeviceGone,
                         d.where() + ": unplugged (LIBUSB_ERROR_NO_DEVICE)");
  }
  if (!d.io_error.empty()) {
    std::string e;
    std::swap(e, d.io_error);
    throw TransportError(TransportErrorKind::kIo, e);
  }
  return 0;
}

TransportStatus UsbTransport::status() const {
  const auto& d = *impl_;
  std::lock_guard lock(d.mu);
  TransportStatus s;
  s.open = d.handle != nullptr && !d.gone;
  s.device_gone = d.gone;
  s.description = d.where() + " at " + std::to_string(d.baud.actual_baud) + " baud";
  s.counters = d.counters;
  return s;
}

const UsbBoardInfo& UsbTransport::board() const {
  return impl_->info;
}

std::uint32_t UsbTransport::actual_baud() const {
  return impl_->baud.actual_baud;
}

}  // namespace omniloc
