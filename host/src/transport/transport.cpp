// Names for transport error kinds (used in messages and by `omniloc probe`).
#include "omniloc/transport.hpp"

namespace omniloc {

const char* to_string(TransportErrorKind kind) {
  switch (kind) {
    case TransportErrorKind::kDeviceGone:
      return "device gone";
    case TransportErrorKind::kIo:
      return "I/O error";
    case TransportErrorKind::kConfig:
      return "configuration failed";
    case TransportErrorKind::kNotFound:
      return "not found";
  }
  return "?";
}

}  // namespace omniloc
