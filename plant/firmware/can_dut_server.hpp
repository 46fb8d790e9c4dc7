// `rig plant serve --can IFACE`: the emulated DUT's firmware on a real CAN
// interface (vcan in the guest kernel, or a USB-CAN adapter), paced by the
// wall clock at 1 kHz.
#pragma once
#include <memory>
#include <string>

#include "firmware_link/socketcan.hpp"
#include "plant/firmware/firmware_emulator.hpp"

namespace rig::plant {

class CanDutServer {
 public:
  // Opens the interface now (HardwareError naming it when it cannot).
  CanDutServer(DutSource& source, const std::string& iface, FirmwareOptions opts = {});
  ~CanDutServer();
  void start();  // returns at once; the firmware runs on its own thread
  void stop();
  FirmwareEmulator& firmware() { return *firmware_; }
  std::string describe() const;

 private:
  std::string iface_;
  std::unique_ptr<link::SocketCanTransport> transport_;
  std::unique_ptr<FirmwareEmulator> firmware_;
};

}  // namespace rig::plant
