// The emulated FT2232H: usbfs ioctls answered on umockdev's worker thread. See ft2232h_model.hpp.
#include "omniloc_sim/ft2232h_model.hpp"

#include <umockdev.h>
// umockdev.h pulls in glib; the usbfs structures and request codes come from the kernel headers.
#include <linux/ioctl.h>
#include <linux/usbdevice_fs.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <mutex>
#include <stdexcept>

namespace omniloc::sim {

namespace {

constexpr std::size_t kPacketBytes = 512;  // high-speed bulk packet of the FT2232H
constexpr std::uint8_t kEpIn = 0x83;
constexpr std::uint8_t kEpOut = 0x04;
constexpr std::uint16_t kPortB = 2;

/// Device and configuration descriptors of an FT2232H (bcdDevice 7.00): two vendor-class
/// interfaces, A with bulk 0x81/0x02 and B with bulk 0x83/0x04, 512-byte packets.
constexpr const char* kDescriptorsHex =
    "1201000200000040030410600007010203010902370002010080320904000002"
    "ffffff0207058102000200070502020002000904010002ffffff020705830200"
    "020007050402000200";

struct Urb {
  UMockdevIoctlClient* client = nullptr;  // not owned: identity only
  UMockdevIoctlData* data = nullptr;      // owned ref: the client's struct usbdevfs_urb
  UMockdevIoctlData* buffer = nullptr;    // owned ref: its buffer (may be null for 0-length)
  std::uintptr_t client_addr = 0;
  usbdevfs_urb* urb() const { return reinterpret_cast<usbdevfs_urb*>(data->data); }
};

void release(Urb& u) {
  if (u.buffer) g_object_unref(u.buffer);
  if (u.data) g_object_unref(u.data);
  u.buffer = nullptr;
  u.data = nullptr;
}

std::vector<std::uint8_t> string_descriptor(const std::string& s) {
  std::vector<std::uint8_t> d{static_cast<std::uint8_t>(2 + 2 * s.size()), 3};
  for (const char c : s) {
    d.push_back(static_cast<std::uint8_t>(c));
    d.push_back(0);
  }
  return d;
}

}  // namespace

struct EmulatedUsb::Impl {
  UMockdevTestbed* testbed = nullptr;
};

EmulatedUsb::EmulatedUsb() : impl_(std::make_unique<Impl>()) {
  impl_->testbed = umockdev_testbed_new();
  // Only meaningful after the testbed exists (the answer is cached).
  if (!umockdev_in_mock_environment()) {
    g_object_unref(impl_->testbed);
    throw std::runtime_error(
        "the emulated USB bus needs libumockdev-preload: run this program under "
        "`umockdev-wrapper`");
  }
}

EmulatedUsb::~EmulatedUsb() {
  g_object_unref(impl_->testbed);
}

struct Ft2232hModel::Impl {
  EmulatedUsb& usb;
  UartSide& uart;
  Ft2232hConfig cfg;
  std::string devnode;
  std::string syspath;
  UMockdevIoctlBase* handler = nullptr;

  mutable std::mutex mu;
  Ft2232hState st;
  std::deque<Urb> done;  // completed, waiting to be reaped
  std::deque<Urb> pending_in;
  std::uint8_t line_bits = 0;
  int line_count = 0;
  std::chrono::steady_clock::time_point last_in = std::chrono::steady_clock::now();

  Impl(EmulatedUsb& u, UartSide& s, Ft2232hConfig c) : usb(u), uart(s), cfg(std::move(c)) {}

  static gboolean on_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self) {
    return static_cast<Impl*>(self)->ioctl(client) ? TRUE : FALSE;
  }

  // USBDEVFS_GET_CAPABILITIES: what a current kernel's usbfs offers.
  bool get_capabilities(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
    UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(guint32), nullptr);
    const guint32 caps = USBDEVFS_CAP_BULK_SCATTER_GATHER | USBDEVFS_CAP_BULK_CONTINUATION |
                         USBDEVFS_CAP_NO_PACKET_SIZE_LIM | USBDEVFS_CAP_REAP_AFTER_DISCONNECT |
                         USBDEVFS_CAP_ZERO_PACKET;
    std::memcpy(d->data, &caps, sizeof caps);
    g_object_unref(d);
    umockdev_ioctl_client_complete(client, 0, 0);
    return true;
  }

  // USBDEVFS_GETDRIVER: ftdi_sio on interface 1 while bound and not detached.
  bool get_driver(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
    UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_getdriver), nullptr);
    auto* g = reinterpret_cast<usbdevfs_getdriver*>(d->data);
    const bool bound = cfg.kernel_driver_bound && !st.driver_detached && g->interface == 1;
    if (bound) std::snprintf(g->driver, sizeof g->driver, "ftdi_sio");
    g_object_unref(d);
    umockdev_ioctl_client_complete(client, bound ? 0 : -1, bound ? 0 : ENODATA);
    return true;
  }

  // USBDEVFS_IOCTL: the kernel driver detached (DISCONNECT) or attached again (CONNECT).
  bool driver_ioctl(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
    UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_ioctl), nullptr);
    const auto* io = reinterpret_cast<const usbdevfs_ioctl*>(d->data);
    int err = 0;
    if (st.unplugged) {
      err = ENODEV;
    } else if (io->ioctl_code == static_cast<int>(USBDEVFS_DISCONNECT) && io->ifno == 1) {
      if (!cfg.kernel_driver_bound || st.driver_detached) err = ENODATA;
      st.driver_detached = true;
    } else if (io->ioctl_code == static_cast<int>(USBDEVFS_CONNECT) && io->ifno == 1) {
      st.driver_detached = false;
    } else {
      err = EINVAL;
    }
    g_object_unref(d);
    umockdev_ioctl_client_complete(client, err ? -1 : 0, err);
    return true;
  }

  // USBDEVFS_CLAIMINTERFACE / RELEASEINTERFACE of interface 1.
  bool claim_or_release(UMockdevIoctlClient* client, UMockdevIoctlData* arg,
                        unsigned long request) {
    UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(unsigned int), nullptr);
    unsigned int ifno = 0;
    std::memcpy(&ifno, d->data, sizeof ifno);
    g_object_unref(d);
    int err = 0;
    if (st.unplugged) {
      err = ENODEV;
    } else if (request == USBDEVFS_CLAIMINTERFACE) {
      // The kernel refuses a claim while ftdi_sio still owns the interface.
      if (ifno == 1 && cfg.kernel_driver_bound && !st.driver_detached) {
        err = EBUSY;
      } else if (ifno == 1) {
        st.interface_claimed = true;
      }
    } else if (ifno == 1) {
      st.interface_claimed = false;
    }
    umockdev_ioctl_client_complete(client, err ? -1 : 0, err);
    return true;
  }

  bool ioctl(UMockdevIoctlClient* client) {
    const unsigned long request = umockdev_ioctl_client_get_request(client);
    UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
    std::lock_guard lock(mu);
    switch (request) {
      case USBDEVFS_GET_CAPABILITIES:
        return get_capabilities(client, arg);
      case USBDEVFS_GETDRIVER:
        return get_driver(client, arg);
      case USBDEVFS_IOCTL:
        return driver_ioctl(client, arg);
      case USBDEVFS_CLAIMINTERFACE:
      case USBDEVFS_RELEASEINTERFACE:
        return claim_or_release(client, arg, request);
      case USBDEVFS_SUBMITURB:
        return submit(client, arg);
      case USBDEVFS_REAPURB:
      case USBDEVFS_REAPURBNDELAY:
        return reap(client, arg);
      case USBDEVFS_DISCARDURB:
        return discard(client, arg);
      default:
        st.unhandled_ioctls.push_back(request);
        return false;
    }
  }

  bool submit(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
    if (st.unplugged) {
      umockdev_ioctl_client_complete(client, -1, ENODEV);
      return true;
    }
    Urb u;
    u.client = client;
    u.data = umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_urb), nullptr);
    u.client_addr = u.data->client_addr;
    usbdevfs_urb* urb = u.urb();
    if (urb->buffer_length > 0) {
      u.buffer = umockdev_ioctl_data_resolve(u.data, offsetof(usbdevfs_urb, buffer),
                                             static_cast<gsize>(urb->buffer_length), nullptr);
    }
    urb->status = 0;
    urb->actual_length = 0;
    if (urb->type == USBDEVFS_URB_TYPE_CONTROL && u.buffer && urb->buffer_length >= 8) {
      control(u);
      done.push_back(u);
    } else if (urb->type == USBDEVFS_URB_TYPE_BULK && urb->endpoint == kEpOut) {
      const auto* bytes =
          u.buffer ? reinterpret_cast<const std::uint8_t*>(u.buffer->data) : nullptr;
      const auto n = static_cast<std::size_t>(std::max(urb->buffer_length, 0));
      if (bytes && n > 0) uart.to_board(std::span<const std::uint8_t>(bytes, n));
      st.bulk_out_bytes += n;
      urb->actual_length = urb->buffer_length;
      done.push_back(u);
    } else if (urb->type == USBDEVFS_URB_TYPE_BULK && urb->endpoint == kEpIn) {
      pending_in.push_back(u);
    } else {
      release(u);
      umockdev_ioctl_client_complete(client, -1, EINVAL);
      return true;
    }
    umockdev_ioctl_client_complete(client, 0, 0);
    return true;
  }

  /// Answers a control URB in place (setup packet first, data stage after it).
  void control(Urb& u) {
    usbdevfs_urb* urb = u.urb();
    auto* buf = reinterpret_cast<std::uint8_t*>(u.buffer->data);
    ControlRequest c;
    c.request_type = buf[0];
    c.request = buf[1];
    c.value = static_cast<std::uint16_t>(buf[2] | (buf[3] << 8));
    c.index = static_cast<std::uint16_t>(buf[4] | (buf[5] << 8));
    c.length = static_cast<std::uint16_t>(buf[6] | (buf[7] << 8));
    const std::size_t room = static_cast<std::size_t>(urb->buffer_length) - 8;
    std::vector<std::uint8_t> reply;
    bool ok = true;
    if (c.request_type == 0x80 && c.request == 6 &&
        (c.value >> 8) == 3) {  // GET_DESCRIPTOR(STRING)
      switch (c.value & 0xFF) {
        case 0:
          reply = {4, 3, 0x09, 0x04};
          break;  // LANGID en-US
        case 1:
          reply = string_descriptor(cfg.manufacturer);
          break;
        case 2:
          reply = string_descriptor(cfg.product);
          break;
        case 3:
          reply = string_descriptor(cfg.serial);
          break;
        default:
          ok = false;
      }
    } else if (c.request_type == 0x40) {
      ok = vendor_out(c);
    } else if (c.request_type == 0xC0 && c.request == 5 &&
               (c.index & 0xFF) == kPortB) {  // poll modem status
      reply = {cfg.modem_status, 0x60};
    } else if (c.request_type == 0xC0 && c.request == 10 &&
               (c.index & 0xFF) == kPortB) {  // get latency timer
      reply = {static_cast<std::uint8_t>(st.latency_ms)};
    } else {
      ok = false;
    }
    c.accepted = ok;
    st.control.push_back(c);
    if (!ok) {
      urb->status = -EPIPE;  // a stall, as the chip answers a request it does not know
      return;
    }
    const std::size_t n = std::min({reply.size(), room, static_cast<std::size_t>(c.length)});
    std::copy_n(reply.begin(), n, buf + 8);
    urb->actual_length = static_cast<int>(n);
  }

  bool vendor_out(const ControlRequest& c) {
    if (c.length != 0) return false;
    // Every SIO request names the channel in the low byte of wIndex; this model is channel B only.
    if ((c.index & 0xFF) != kPortB) return false;
    switch (c.request) {
      case 0:  // reset / purge
        if (c.value == 0) {
          ++st.resets;
        } else if (c.value == 1) {
          ++st.purges_rx;
        } else if (c.value == 2) {
          ++st.purges_tx;
        } else {
          return false;
        }
        return true;
      case 1:
        return true;  // modem control
      case 2:
        st.flow_control = static_cast<std::uint16_t>(c.index & 0xFF00);
        return true;
      case 3:
        st.baud_value = c.value;
        st.baud_index = c.index;
        return true;
      case 4:
        st.data_characteristics = c.value;
        return true;
      case 9:
        if (c.value < 1 || c.value > 255) return false;
        st.latency_ms = c.value;
        return true;
      case 11:
        st.bitmode = c.value;
        return true;
      default:
        return false;
    }
  }

  /// Fills a pending IN URB from the UART side: packets of 2 status bytes + up to 510 data bytes.
  /// Returns false when there is nothing to send yet and the latency timer has not expired.
  bool fill_in(Urb& u) {
    usbdevfs_urb* urb = u.urb();
    auto* buf = reinterpret_cast<std::uint8_t*>(u.buffer->data);
    const auto cap = static_cast<std::size_t>(urb->buffer_length);
    std::size_t len = 0;
    std::size_t payload = 0;
    while (len + 2 < cap) {
      const std::size_t room = std::min(kPacketBytes, cap - len) - 2;
      const std::size_t n = uart.from_board(std::span<std::uint8_t>(buf + len + 2, room));
      if (n == 0 && len > 0) break;
      const auto now = std::chrono::steady_clock::now();
      if (n == 0 && now - last_in < std::chrono::milliseconds(st.latency_ms)) return false;
      buf[len] = cfg.modem_status;
      buf[len + 1] = 0x60;  // THRE | TEMT
      if (line_count > 0) {
        buf[len + 1] = static_cast<std::uint8_t>(buf[len + 1] | line_bits);
        --line_count;
      }
      ++st.bulk_in_packets;
      if (n == 0) ++st.status_only_packets;
      len += 2 + n;
      payload += n;
      if (n < room) break;  // a short packet ends the transfer
    }
    st.bulk_in_bytes += payload;
    urb->actual_length = static_cast<int>(len);
    last_in = std::chrono::steady_clock::now();
    return true;
  }

  bool reap(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
    auto mine = [client](const Urb& u) { return u.client == client; };
    auto it = std::find_if(done.begin(), done.end(), mine);
    Urb u;
    if (it != done.end()) {
      u = *it;
      done.erase(it);
    } else {
      auto in = std::find_if(pending_in.begin(), pending_in.end(), mine);
      if (in != pending_in.end() && st.unplugged) {
        u = *in;
        pending_in.erase(in);
        u.urb()->status = -ESHUTDOWN;  // how usbfs completes URBs of a device that went away
        u.urb()->actual_length = 0;
      } else if (in != pending_in.end() && fill_in(*in)) {
        u = *in;
        pending_in.erase(in);
      } else {
        umockdev_ioctl_client_complete(client, -1, st.unplugged ? ENODEV : EAGAIN);
        return true;
      }
    }
    UMockdevIoctlData* ptr = umockdev_ioctl_data_resolve(arg, 0, sizeof(gpointer), nullptr);
    umockdev_ioctl_data_set_ptr(ptr, 0, u.data);  // the reap arg now owns a ref: syncs the URB back
    g_object_unref(ptr);
    release(u);
    umockdev_ioctl_client_complete(client, 0, 0);
    return true;
  }

  bool discard(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
    const auto addr = reinterpret_cast<std::uintptr_t>(*reinterpret_cast<void**>(arg->data));
    auto in = std::find_if(pending_in.begin(), pending_in.end(), [&](const Urb& u) {
      return u.client == client && u.client_addr == addr;
    });
    if (in == pending_in.end()) {
      umockdev_ioctl_client_complete(client, -1, EINVAL);
      return true;
    }
    Urb u = *in;
    pending_in.erase(in);
    u.urb()->status = -ENOENT;  // cancelled
    u.urb()->actual_length = 0;
    done.push_back(u);
    umockdev_ioctl_client_complete(client, 0, 0);
    return true;
  }
};

Ft2232hModel::Ft2232hModel(EmulatedUsb& usb, UartSide& uart, Ft2232hConfig config)
    : impl_(std::make_unique<Impl>(usb, uart, std::move(config))) {
  auto& d = *impl_;
  char node[64];
  std::snprintf(node, sizeof node, "bus/usb/%03d/%03d", d.cfg.bus, d.cfg.address);
  d.devnode = std::string("/dev/") + node;
  d.syspath = "/devices/usb" + std::to_string(d.cfg.bus) + "/" + std::to_string(d.cfg.bus) + "-" +
              std::to_string(d.cfg.address);
  d.handler = umockdev_ioctl_base_new();
  g_signal_connect_after(d.handler, "handle-ioctl", G_CALLBACK(&Impl::on_ioctl), impl_.get());
  UMockdevTestbed* tb = usb.impl().testbed;
  GError* err = nullptr;
  // Attach the handler first so that the device is served from the moment it appears.
  if (!umockdev_testbed_attach_ioctl(tb, d.devnode.c_str(), d.handler, &err)) {
    const std::string msg = err ? err->message : "unknown error";
    if (err) g_error_free(err);
    g_object_unref(d.handler);
    throw std::runtime_error("umockdev_testbed_attach_ioctl(" + d.devnode + "): " + msg);
  }
  char busnum[8];
  char devnum[8];
  std::snprintf(busnum, sizeof busnum, "%03d", d.cfg.bus);
  std::snprintf(devnum, sizeof devnum, "%03d", d.cfg.address);
  const std::string record =
      "P: " + d.syspath + "\nN: " + node + "\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\n" +
      "E: DRIVER=usb\nE: BUSNUM=" + busnum + "\nE: DEVNUM=" + devnum + "\nE: DEVNAME=" + d.devnode +
      "\nE: PRODUCT=403/6010/700\nA: busnum=" + std::to_string(d.cfg.bus) +
      "\\n\nA: devnum=" + std::to_string(d.cfg.address) +
      "\\n\nA: bConfigurationValue=1\\n\nA: speed=480\\n\nA: idVendor=0403\\n\n" +
      "A: idProduct=6010\\n\nA: manufacturer=" + d.cfg.manufacturer +
      "\\n\nA: product=" + d.cfg.product + "\\n\nA: serial=" + d.cfg.serial +
      "\\n\nH: descriptors=" + kDescriptorsHex + "\n";
  if (!umockdev_testbed_add_from_string(tb, record.c_str(), &err)) {
    const std::string msg = err ? err->message : "unknown error";
    if (err) g_error_free(err);
    throw std::runtime_error("umockdev_testbed_add_from_string(" + d.syspath + "): " + msg);
  }
}

Ft2232hModel::~Ft2232hModel() {
  auto& d = *impl_;
  umockdev_testbed_detach_ioctl(d.usb.impl().testbed, d.devnode.c_str(), nullptr);
  {
    std::lock_guard lock(d.mu);
    for (auto& u : d.done) release(u);
    for (auto& u : d.pending_in) release(u);
  }
  g_object_unref(d.handler);
}

void Ft2232hModel::unplug() {
  std::lock_guard lock(impl_->mu);
  impl_->st.unplugged = true;
}

void Ft2232hModel::inject_line_status(std::uint8_t bits, int count) {
  std::lock_guard lock(impl_->mu);
  impl_->line_bits = bits;
  impl_->line_count = count;
}

Ft2232hState Ft2232hModel::state() const {
  std::lock_guard lock(impl_->mu);
  return impl_->st;
}

std::string Ft2232hModel::devnode() const {
  return impl_->devnode;
}

}  // namespace omniloc::sim
