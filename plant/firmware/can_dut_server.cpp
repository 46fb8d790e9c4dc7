#include "plant/firmware/can_dut_server.hpp"

namespace rig::plant {

CanDutServer::CanDutServer(DutSource& source, const std::string& iface, FirmwareOptions opts)
    : iface_(iface), transport_(std::make_unique<link::SocketCanTransport>(iface)),
      firmware_(std::make_unique<FirmwareEmulator>(source, *transport_, opts)) {}

CanDutServer::~CanDutServer() { stop(); }

void CanDutServer::start() { firmware_->start_realtime(); }
void CanDutServer::stop() {
  if (firmware_) firmware_->stop();
}

std::string CanDutServer::describe() const {
  return "emulated DUT firmware on " + transport_->name() + " (1 kHz" +
         (firmware_->options().commands ? "" : ", no command channel: streaming from power-on") + ")";
}

}  // namespace rig::plant
