#include "plant/firmware/inprocess_dut.hpp"

namespace rig::link {

InProcessDutLink::InProcessDutLink(plant::DutSource& source, Clock& clock, InProcessDutOptions opts) {
  InProcessBus::Options bo;
  bo.name = "dut-bus";
  bo.now = [&clock] { return clock.now_s(); };  // frame timestamps in the rig's (simulated) time
  bus_ = InProcessBus::create(std::move(bo));
  dut_port_ = bus_->open("dut");
  firmware_ = std::make_unique<plant::FirmwareEmulator>(source, *dut_port_, opts.firmware);
  opts.link.frame_time_is_clock_time = true;
  client_ = std::make_unique<CanDutLink>(bus_->open("rig"), clock, opts.link);
}

InProcessDutLink::~InProcessDutLink() {
  client_.reset();  // its stop frame reaches the firmware's queue, harmlessly
  firmware_.reset();
}

std::string InProcessDutLink::describe() const { return "emulated DUT firmware, " + client_->describe(); }

std::unique_ptr<InProcessDutLink> make_inprocess_dut(plant::DutSource& source, Clock& clock, InProcessDutOptions opts) {
  return std::make_unique<InProcessDutLink>(source, clock, std::move(opts));
}

}  // namespace rig::link
