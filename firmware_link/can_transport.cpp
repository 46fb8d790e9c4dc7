#include "firmware_link/can_transport.hpp"

#include <algorithm>
#include <cstdio>

#include "rig/core/errors.hpp"

#include <linux/can/error.h>

namespace rig::link {

void CanTransport::send_fd(const CanFdFrame& f) {
  throw HardwareError(name() + ": cannot send a CAN FD frame (id 0x" + [&] {
    char b[12];
    std::snprintf(b, sizeof b, "%X", f.id);
    return std::string(b);
  }() + ", " + std::to_string(f.len) + " bytes): this transport carries classic CAN only");
}

ErrorFrameInfo classify_error_frame(const CanFrame& f) {
  ErrorFrameInfo info;
  if (f.id & CAN_ERR_BUSOFF) {
    info.fatal = true;
    info.text = "bus-off";
    return info;
  }
  if (f.id & CAN_ERR_CRTL) {
    const uint8_t st = f.len > 1 ? f.data[1] : 0;
    if (st & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) {
      info.fatal = true;
      info.text = std::string("controller error passive (") + ((st & CAN_ERR_CRTL_RX_PASSIVE) ? "rx" : "") +
                  ((st & CAN_ERR_CRTL_RX_PASSIVE) && (st & CAN_ERR_CRTL_TX_PASSIVE) ? "+" : "") +
                  ((st & CAN_ERR_CRTL_TX_PASSIVE) ? "tx" : "") + ")";
      return info;
    }
    info.text = (st & (CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW)) ? "controller buffer overflow"
                : (st & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) ? "controller error warning"
                                                                             : "controller state change";
    return info;
  }
  if (f.id & CAN_ERR_RESTARTED) info.text = "controller restarted";
  else if (f.id & CAN_ERR_ACK) info.text = "no acknowledgement on transmission";
  else if (f.id & CAN_ERR_PROT) info.text = "protocol violation";
  else if (f.id & CAN_ERR_BUSERROR) info.text = "bus error";
  else if (f.id & CAN_ERR_LOSTARB) info.text = "lost arbitration";
  else if (f.id & CAN_ERR_TX_TIMEOUT) info.text = "tx timeout";
  else if (f.id & CAN_ERR_TRX) info.text = "transceiver error";
  else info.text = "error frame";
  return info;
}

bool filter_accepts(std::span<const CanFilter> filters, const CanFrame& f) {
  if (filters.empty() || f.error) return true;  // error frames are not subject to id filters
  return std::any_of(filters.begin(), filters.end(),
                     [&](const CanFilter& k) {
                       return f.extended == k.extended && (f.id & k.mask) == (k.id & k.mask);
                     });
}

}  // namespace rig::link
